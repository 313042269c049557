// Friction identified from the generalised-momentum residual: the `momentum` adaptation law (issue 26;
// docs/adaptation.md, "Identification from the residual").
//
// The residual monitor (osc/runtime/monitors.hpp) filters, per joint, the torque the model does not
// explain: r = H(tau_f^ - tau_f), H a first-order filter of bandwidth K = params::kResidualGain, and it
// filters the friction model's regressor columns and the estimate tau_f^ = W theta^ through the same H.
// So, per joint i, with phi_i = H(W_i) one sample older (the residual's friction is that of the last
// period, n_{k-1}):
//     y_i = H(tau_f^)_i - r_i = H(tau_f)_i = phi_i^T theta_i + noise,      theta_i = (vis, cou, sti)_i,
// a linear regression in three coefficients per joint (friction is uncoupled: Property 4), with a
// measurement that is the torque itself, not (67)'s one-sample position increment (a signal of about
// 1e-6 rad against a 1e-4 rad encoder quantum). Its noise is the velocity estimate's quantisation
// through A and H: the derivative of H(eta) against H(eta) itself in the viscous column, so it is
// uncorrelated with the regressor (E[x dx/dt] = 0 for a stationary x) and the estimate has no
// errors-in-variables bias to speak of.
//
// Each joint's three coefficients are estimated by a Kalman filter: theta a random walk (the
// coefficients drift with temperature, params::kIdentifyDrift of the band's top per hour), the prior
// theta^ = 0 with the band's top as its standard deviation (robot::kModelErrorBounds). Its covariance
// P is the excitation monitor: a coefficient, or a sum of them, is identified when its standard
// deviation is small against its value; a motion that does not excite a direction leaves P there
// as it was (plus the drift) and the estimate with it. A sample counts only where the friction
// model holds and the residual is friction: the joint moving, its encoder counting, for
// params::kIdentifySettle filter time constants, its residual within params::kIdentifyMaxRatio of its
// threshold, its innovation within params::kIdentifyGate standard deviations.
// The joints take turns, one update every params::kIdentifyEvery ticks each: a few hundred
// instructions per tick. The update is + * and one division per joint.
#pragma once

#include <array>
#include <cstdint>

#include "osc/control/params.hpp"
#include "osc/kernels/model.hpp"
#include "osc/robot.hpp"

namespace osc {

/// One joint's sample for the identification, taken by the residual monitor: y = H(tau_f), the
/// regressor columns (vis, cou, sti) and the model's gravity torque through H, and whether the joint has moved long
/// enough for them to hold no standstill.
template <class S>
struct FrictionSample {
  S y;
  Vec3<S> phi;
  S gravity;  // the model's gravity torque through H (the model error's regressor)
  bool settled;
};

/// What one joint's identification step did (for its counters and the tests).
enum class IdentifyOutcome : std::uint8_t { kUpdated, kNotSettled, kResidualHigh, kOutlier };

/// The excitation monitor's verdict on one coefficient (or a sum of them) and its standard
/// deviation sd: identified when sd is at most params::kIdentifiedFraction of its value, so that a
/// band of four standard deviations lies within 10 % of it; otherwise not excited (enough).
constexpr bool friction_identified(double value, double sd) {
  return sd <= params::kIdentifiedFraction * (value < 0 ? -value : value);
}

template <class S>
struct FrictionIdentifier {
  using Vec4 = Eigen::Matrix<S, 4, 1>;
  using Mat4 = Eigen::Matrix<S, 4, 4>;
  /// Each joint's regression runs in its own torque unit, 1 / kScale[i] N m, a power of two chosen
  /// so that the prior's largest standard deviation is at most 64 units (its variance fits Q12.19's
  /// range, and a wrist's converged one keeps thousands of its LSBs): exact in every scalar.
  /// Its coefficients, in those units: (vis, cou, sti) scaled, and the model's gravity error as a
  /// torque at the joint's full scale, delta T_i, with the regressor g / T_i.
  /// The gravity error is the model's: the link inertias are known within robot::kModelErrorBounds'
  /// link_inertia (10 %), so the residual holds delta g(q). It is estimated beside the friction so
  /// that it does not leak into it (on J2, 10 % of its gravity torque is several times its
  /// friction), and not compensated: the paper's controller compensates friction only.
  Mat4 P[kDof];                  // each joint's covariance [its units squared]
  Vec4 z[kDof];                  // each joint's estimate, unbounded [its units] (theta^ is it projected)
  Vec6<S> innovation2;           // each joint's mean squared innovation, recent samples [its units squared]
  std::uint32_t updates[kDof];   // samples taken per joint
  std::uint32_t outliers[kDof];  // samples refused by the innovation gate
  std::uint8_t turn;             // the joint of the next update
  static constexpr double kPerHour = 3600.0 * params::kControlHz / params::kIdentifyEvery;  // updates per hour

  /// The prior: theta^ anywhere from 0 to the band's top (robot::kModelErrorBounds), no counters.
  void reset() {
    for (int i = 0; i < kDof; ++i) {
      P[i] = prior(i);
      z[i].setZero();
      innovation2(i) = S(-1);  // none yet (update)
      updates[i] = 0;
      outliers[i] = 0;
    }
    turn = 0;
  }
  /// The joint whose update is due this tick; advances the turn.
  int take_turn() {
    const int i = turn;
    turn = static_cast<std::uint8_t>(turn + 1 < kDof ? turn + 1 : 0);
    return i;
  }

  /// Joint i's Kalman update from sample s: its estimate z moves by the gain times the innovation,
  /// and theta^'s coefficients (i, 6 + i, 12 + i) are z projected within [0, theta_max] (project).
  /// z itself is not bounded: a bound fed back into a linear estimator ratchets (on a frictionless
  /// plant, estimates near 0 walk to their upper bounds over an hour). P grows by the drift whether
  /// or not the sample counts, up to the prior.
  /// The sample's noise variance is measured: the recent mean squared innovation less what P
  /// explains of it, within [bound_var / 256, bound_var], bound_var the variance the residual
  /// monitor's quantisation bound implies [N^2 m^2]. The update counts it `correlation` times: the
  /// samples' correlation through the residual's filter, fewer independent samples than updates.
  IdentifyOutcome update(int i, const FrictionSample<S>& s, bool residual_low, S bound_var, S correlation,
                         Vec18<S>& theta, const Vec18<S>& theta_max) {
    drift(i);
    if (!s.settled) return IdentifyOutcome::kNotSettled;
    if (!residual_low) return IdentifyOutcome::kResidualHigh;
    static constexpr std::array<S, kDof> kUnscale = per_joint([](int j) { return 1 / scale_of(j); });
    static constexpr std::array<S, kDof> kInverseTorque =
        per_joint([](int j) { return 1 / robot::kDrives.torque_limit[j]; });
    const S sc = scale(i);
    Vec4& th = z[i];
    const Vec4 phi(s.phi(0), s.phi(1), s.phi(2), s.gravity * kInverseTorque[i]);
    const Vec4 Pphi = P[i] * phi;
    const S explained = phi.dot(Pphi);
    const S innovation = s.y * sc - phi.dot(th), e2 = innovation * innovation;
    const S bound = bound_var * (sc * sc);
    S& mean2 = innovation2(i);
    if (mean2 < S(0)) mean2 = bound + explained;  // none yet: start from the bound
    S noise = mean2 - explained;
    const S floor = bound * lit<S>(1.0 / 256);
    noise = noise < floor ? floor : (noise > bound ? bound : noise);
    static constexpr S kGateSquaredInverse = lit<S>(1.0 / (params::kIdentifyGate * params::kIdentifyGate));
    if (e2 * kGateSquaredInverse > explained + noise) {
      ++outliers[i];
      return IdentifyOutcome::kOutlier;
    }
    static constexpr S kAverage = lit<S>(1.0 / params::kIdentifyNoiseSamples);
    mean2 += kAverage * (e2 - mean2);
    const S var = explained + correlation * noise;  // the innovation's variance, as the update counts it
    th += correct(i, Pphi, var) * innovation;
    const Vec4 bounded = project(i, th, theta_max);
    for (int c = 0; c < 3; ++c) theta(c * kDof + i) = bounded(c) * kUnscale[i];
    ++updates[i];
    return IdentifyOutcome::kUpdated;
  }

  /// The Kalman correction of joint i for a sample of innovation variance var, given P phi: P less
  /// (P phi)(P phi)^T / var, kept symmetric; returns the gain P phi / var.
  Vec4 correct(int i, const Vec4& Pphi, S var) {
    const Vec4 gain = Pphi / var;
    for (int a = 0; a < 4; ++a)
      for (int b = a; b < 4; ++b) {
        const S v = P[i](a, b) - gain(a) * Pphi(b);
        P[i](a, b) = v;
        P[i](b, a) = v;
      }
    return gain;
  }
  /// th (joint i's units) within [0, theta_max], projected in the metric of P^-1 (the estimate's
  /// own): a coefficient beyond a bound is set to it and the others move as P correlates them, so
  /// that a well identified sum (Coulomb + Stribeck) keeps its value when one of its terms meets a
  /// bound; one pass over the three, then a clip for what the pass leaves. The gravity error is not
  /// bounded.
  Vec4 project(int i, Vec4 th, const Vec18<S>& theta_max) const {
    const S sc = scale(i);
    for (int c = 0; c < 3; ++c) {
      const S hi = theta_max(c * kDof + i) * sc, v = th(c);
      const S excess = v < S(0) ? v : (v > hi ? v - hi : S(0));
      if (excess != S(0) && P[i](c, c) > S(0)) th -= P[i].col(c) * (excess / P[i](c, c));
    }
    for (int c = 0; c < 3; ++c) {
      const S hi = theta_max(c * kDof + i) * sc;
      if (th(c) < S(0)) th(c) = S(0);
      if (th(c) > hi) th(c) = hi;
    }
    return th;
  }

  /// Joint i's variance of coefficient c (0 vis, 1 cou, 2 sti), in the coefficient's own units
  /// squared (N m s/rad, N m) [host, double].
  double variance(int i, int c) const { return static_cast<double>(P[i](c, c)) / square(scale_of(i)); }
  /// Joint i's variance of the Coulomb and Stribeck levels' sum (the breakaway torque's) [N^2 m^2].
  double breakaway_variance(int i) const {
    const double v =
        static_cast<double>(P[i](1, 1)) + static_cast<double>(P[i](2, 2)) + 2 * static_cast<double>(P[i](1, 2));
    return v / square(scale_of(i));
  }
  /// Joint i's relative gravity error delta [1].
  double gravity_error(int i) const {
    return static_cast<double>(z[i](3)) / (scale_of(i) * robot::kDrives.torque_limit[i]);
  }

  /// The prior covariance of joint i in its units: the band's top squared on the diagonal, and the
  /// gravity error's (link_inertia T_i)^2.
  static Mat4 prior(int i) {
    static constexpr std::array<S, 4 * kDof> kPrior = band_squared(1.0);
    Mat4 p = Mat4::Zero();
    for (int c = 0; c < 4; ++c) p(c, c) = kPrior[c * kDof + i];
    return p;
  }
  /// Joint i's unit: the power of two that brings its largest prior standard deviation within
  /// [32, 64) units (robot::kModelErrorBounds: the band's tops, link_inertia times full scale).
  static constexpr double scale_of(int i) {
    const ModelErrorBounds& b = robot::kModelErrorBounds;
    double top = b.link_inertia * robot::kDrives.torque_limit[i];
    for (double v : {b.friction_hi.vis[i], b.friction_hi.cou[i], b.friction_hi.sti[i]}) top = v > top ? v : top;
    double s = 1.0 / 64;
    while (s * 2 * top < 64) s *= 2;
    return s;
  }

 private:
  static constexpr double square(double v) { return v * v; }
  /// scale_of(i) in the scalar S.
  static S scale(int i) {
    static constexpr std::array<S, kDof> kScale = per_joint([](int j) { return scale_of(j); });
    return kScale[i];
  }
  template <class F>
  static constexpr std::array<S, kDof> per_joint(F f) {
    std::array<S, kDof> a{};
    for (int j = 0; j < kDof; ++j) a[j] = lit<S>(f(j));
    return a;
  }
  /// f times each coefficient's prior variance in joint i's units: the band's top squared
  /// (robot::kModelErrorBounds), the gravity error's (link_inertia T_i)^2.
  static constexpr std::array<S, 4 * kDof> band_squared(double f) {
    const ModelErrorBounds& b = robot::kModelErrorBounds;
    std::array<S, 4 * kDof> q{};
    for (int i = 0; i < kDof; ++i) {
      const double s2 = f * square(scale_of(i));
      q[i] = lit<S>(s2 * square(b.friction_hi.vis[i]));
      q[kDof + i] = lit<S>(s2 * square(b.friction_hi.cou[i]));
      q[2 * kDof + i] = lit<S>(s2 * square(b.friction_hi.sti[i]));
      q[3 * kDof + i] = lit<S>(s2 * square(b.link_inertia * robot::kDrives.torque_limit[i]));
    }
    return q;
  }
  /// The random walk: (kIdentifyDrift times each prior standard deviation)^2 per hour, up to the prior.
  void drift(int i) {
    static constexpr std::array<S, 4 * kDof> kDrift =
        band_squared(params::kIdentifyDrift * params::kIdentifyDrift / kPerHour);
    static constexpr std::array<S, 4 * kDof> kPrior = band_squared(1.0);
    for (int c = 0; c < 4; ++c) {
      const S v = P[i](c, c) + kDrift[c * kDof + i];
      P[i](c, c) = v < kPrior[c * kDof + i] ? v : kPrior[c * kDof + i];
    }
  }
};

}  // namespace osc
