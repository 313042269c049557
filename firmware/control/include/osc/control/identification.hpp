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
/// regressor columns (vis, cou, sti) and the model's gravity torque through H, and whether the joint has moved long enough for them
/// to hold no standstill.
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
  /// Each joint's covariance of (vis, cou, sti, gravity error) [their units squared]. The gravity
  /// error is the model's: the link inertias are known within robot::kModelErrorBounds' link_inertia
  /// (10 %), so the residual holds delta g(q), delta the joint's relative error. It is estimated
  /// beside the friction so that it does not leak into it (on J2, 10 % of its gravity torque is
  /// several times its friction), and not compensated: the paper's controller compensates friction
  /// only.
  Mat4 P[kDof];
  Vec6<S> gravity_error;             // each joint's delta [1]
  Vec6<S> innovation2;               // each joint's mean squared innovation, recent samples [N^2 m^2]
  std::uint32_t updates[kDof];       // samples taken per joint
  std::uint32_t outliers[kDof];      // samples refused by the innovation gate
  std::uint8_t turn;                 // the joint of the next update
  static constexpr double kPerHour = 3600.0 * params::kControlHz / params::kIdentifyEvery;  // updates per hour

  /// The prior: theta^ anywhere from 0 to the band's top (robot::kModelErrorBounds), no counters.
  void reset() {
    for (int i = 0; i < kDof; ++i) {
      P[i] = prior(i);
      gravity_error(i) = S(0);
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

  /// Joint i's Kalman update from sample s: theta^'s coefficients (i, 6 + i, 12 + i) move by the
  /// gain times the innovation, then are kept within [0, theta_max] as the robust law's are. P grows
  /// by the drift whether or not the sample counts, up to the prior.
  /// The sample's noise variance is measured: the recent mean squared innovation less what P
  /// explains of it, within [bound_var / 256, bound_var], bound_var the variance the residual
  /// monitor's quantisation bound implies [N^2 m^2]. The update counts it `correlation` times: the
  /// samples' correlation through the residual's filter, fewer independent samples than updates.
  IdentifyOutcome update(int i, const FrictionSample<S>& s, bool residual_low, S bound_var, S correlation,
                         Vec18<S>& theta, const Vec18<S>& theta_max) {
    drift(i);
    if (!s.settled) return IdentifyOutcome::kNotSettled;
    if (!residual_low) return IdentifyOutcome::kResidualHigh;
    const Vec4 th(theta(i), theta(kDof + i), theta(2 * kDof + i), gravity_error(i));
    const Vec4 phi(s.phi(0), s.phi(1), s.phi(2), s.gravity);
    const Vec4 Pphi = P[i] * phi;
    const S explained = phi.dot(Pphi);
    const S innovation = s.y - phi.dot(th), e2 = innovation * innovation;
    S& mean2 = innovation2(i);
    if (mean2 < S(0)) mean2 = bound_var + explained;  // none yet: start from the bound
    S noise = mean2 - explained;
    const S floor = bound_var * lit<S>(1.0 / 256);
    noise = noise < floor ? floor : (noise > bound_var ? bound_var : noise);
    static constexpr S kGate = lit<S>(params::kIdentifyGate);
    if (e2 > (kGate * kGate) * (explained + noise)) {
      ++outliers[i];
      return IdentifyOutcome::kOutlier;
    }
    static constexpr S kAverage = lit<S>(1.0 / params::kIdentifyNoiseSamples);
    mean2 += kAverage * (e2 - mean2);
    const S var = explained + correlation * noise;  // the innovation's variance, as the update counts it
    const Vec4 next = project(i, th + correct(i, Pphi, var) * innovation, theta_max);
    for (int c = 0; c < 3; ++c) theta(c * kDof + i) = next(c);
    gravity_error(i) = next(3);
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
  /// theta within [0, theta_max], projected in the metric of P^-1 (the estimate's own): a coefficient
  /// beyond a bound is set to it and the others move as P correlates them, so that a well
  /// identified sum (Coulomb + Stribeck) keeps its value when one of its terms meets a bound; one
  /// pass over the three, then a clip for what the pass leaves. The gravity error is not bounded.
  Vec4 project(int i, Vec4 th, const Vec18<S>& theta_max) const {
    for (int c = 0; c < 3; ++c) {
      const S hi = theta_max(c * kDof + i), v = th(c);
      const S excess = v < S(0) ? v : (v > hi ? v - hi : S(0));
      if (excess != S(0) && P[i](c, c) > S(0)) th -= P[i].col(c) * (excess / P[i](c, c));
    }
    for (int c = 0; c < 3; ++c) {
      const S hi = theta_max(c * kDof + i);
      if (th(c) < S(0)) th(c) = S(0);
      if (th(c) > hi) th(c) = hi;
    }
    return th;
  }

  /// Joint i's standard deviation of coefficient c (0 vis, 1 cou, 2 sti).
  S variance(int i, int c) const { return P[i](c, c); }
  /// Joint i's variance of the Coulomb and Stribeck levels' sum (the breakaway torque's).
  S breakaway_variance(int i) const { return P[i](1, 1) + P[i](2, 2) + S(2) * P[i](1, 2); }

  /// The prior covariance of joint i: the band's top squared on the diagonal, and the gravity
  /// error's, link_inertia squared.
  static Mat4 prior(int i) {
    static constexpr std::array<S, 4 * kDof> kPrior = band_squared(1.0);
    Mat4 p = Mat4::Zero();
    for (int c = 0; c < 4; ++c) p(c, c) = kPrior[c * kDof + i];
    return p;
  }

 private:
  /// f times each coefficient's prior variance: the band's top squared (robot::kModelErrorBounds),
  /// the gravity error's link_inertia squared.
  static constexpr std::array<S, 4 * kDof> band_squared(double f) {
    const ModelErrorBounds& b = robot::kModelErrorBounds;
    std::array<S, 4 * kDof> q{};
    for (int i = 0; i < kDof; ++i) {
      q[i] = lit<S>(f * b.friction_hi.vis[i] * b.friction_hi.vis[i]);
      q[kDof + i] = lit<S>(f * b.friction_hi.cou[i] * b.friction_hi.cou[i]);
      q[2 * kDof + i] = lit<S>(f * b.friction_hi.sti[i] * b.friction_hi.sti[i]);
      q[3 * kDof + i] = lit<S>(f * b.link_inertia * b.link_inertia);
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
