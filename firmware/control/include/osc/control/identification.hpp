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
//
// Learning is gated by direction where the motion does not excite. At the speeds most motions
// reach (0.1-0.2 rad/s on the paper's trajectory), the Coulomb and Stribeck columns are collinear:
// exp(-tau_dec qd^2) is within a few percent of 1. There the data tell their sum, not their split,
// and a small misfit elsewhere (an observer lag, an inertia error) moves the split without bound
// through P's correlations (issue 26: an hour of one repeated move took J2's Coulomb level from 7.2
// to 0 and its Stribeck level from 1.9 to 9.1). So the identifier keeps, per joint, the windowed
// moments of the columns (viscous, Coulomb, Stribeck decay = Stribeck - Coulomb), and the decay's
// excitation: its mean square not explained by the other two (a Schur complement). Below
// params::kIdentifySplitExcitation the split is a consider state: the Stribeck level is held, the
// sum gets its optimal gain (Schmidt's filter), and P keeps the split's variance. For that, and for
// P's conditioning in float and fixed point, the filter's coordinates are (vis, cou + sti, sti,
// delta): the well known sum is a coordinate of its own, not the difference of two large, nearly
// opposite variances.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "osc/control/friction_fit.hpp"
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

/// Upper bounds on each joint's friction [N m s/rad, N m]: its viscous coefficient and its breakaway
/// torque (Coulomb + Stribeck, the friction at the onset of motion).
template <class S>
struct FrictionBounds {
  Vec6<S> vis, breakaway;
};

/// What one joint's identification step did (for its counters and the tests).
/// kFolded: the sample's turn went to the excitation monitor's block of moments (fold), one in
/// params::kIdentifyExciteBlock + 1 counted turns, so that no tick does both (the budget is the worst
/// tick's).
enum class IdentifyOutcome : std::uint8_t { kUpdated, kNotSettled, kResidualHigh, kOutlier, kFolded };

/// The excitation monitor's verdict on one coefficient (or a sum of them) and its standard
/// deviation sd: identified when sd is at most params::kIdentifiedFraction of its value, so that a
/// band of four standard deviations lies within 10 % of it; otherwise not excited (enough).
constexpr bool friction_identified(double value, double sd) {
  return sd <= params::kIdentifiedFraction * (value < 0 ? -value : value);
}

/// The excitation monitor's verdict on a joint's Coulomb / Stribeck split, from its decay excitation
/// (FrictionIdentifier::decay_excitation): learned at params::kIdentifySplitExcitation and above,
/// otherwise held.
constexpr bool split_excited(double decay_excitation) { return decay_excitation >= params::kIdentifySplitExcitation; }

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
  using Mat3 = Eigen::Matrix<S, 3, 3>;
  Mat4 P[kDof];                  // each joint's covariance [its units squared]
  Vec4 z[kDof];                  // each joint's estimate (vis, cou + sti, sti, delta), unbounded [its units]
  Vec6<S> innovation2;           // each joint's mean squared innovation, recent samples [its units squared]
  std::uint32_t updates[kDof];   // samples taken per joint
  std::uint32_t outliers[kDof];  // samples refused by the innovation gate
  Mat3 moments[kDof];            // the motion's windowed moments of (vis, cou, decay) columns (excite)
  Mat3 block[kDof];              // the current block's sums of them
  Vec6<S> split_excitation;      // the decay column's mean square unexplained by the others, times kDecayScale^2
  std::uint8_t block_count[kDof];
  std::uint8_t turn;  // the joint of the next update
  /// The friction as far as the identification proves it (prove), for the residual monitor's travel
  /// check: the band's tops (robot::kModelErrorBounds) until a coefficient is identified.
  FrictionBounds<S> proven;
  /// The fit check of the friction set last (seed: a saved record at power-on, an identify run's applied).
  FrictionFit<S> fit;
  static constexpr double kPerHour = 3600.0 * params::kControlHz / params::kIdentifyEvery;  // updates per hour

  /// The prior: theta^ anywhere from 0 to the band's top (robot::kModelErrorBounds), no counters.
  void reset() {
    for (int i = 0; i < kDof; ++i) {
      P[i] = prior(i);
      z[i].setZero();
      innovation2(i) = S(-1);  // none yet (update)
      updates[i] = 0;
      outliers[i] = 0;
      moments[i].setZero();
      block[i].setZero();
      block_count[i] = 0;
    }
    split_excitation.setZero();
    fit.reset();
    turn = 0;
    for (int i = 0; i < kDof; ++i) proven.vis(i) = top(0, i), proven.breakaway(i) = top(1, i);
  }
  /// The joint whose update is due this tick; advances the turn.
  int take_turn() {
    const int i = turn;
    turn = static_cast<std::uint8_t>(turn + 1 < kDof ? turn + 1 : 0);
    return i;
  }

  /// The least innovation variance an update counts in fixed point (update()) [filter's units].
  static constexpr S kFixedVarFloor = lit<S>(1.0 / 4096);

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
    prove(i);
    if (!s.settled && !params::kTickWorstCase) return IdentifyOutcome::kNotSettled;
    if (!residual_low && !params::kTickWorstCase) return IdentifyOutcome::kResidualHigh;
    if (block_count[i] >= params::kIdentifyExciteBlock) {
      fold(i);
      return IdentifyOutcome::kFolded;
    }
    static constexpr std::array<S, kDof> kInverseTorque =
        per_joint([](int j) { return 1 / robot::kDrives.torque_limit[j]; });
    const S sc = scale(i);
    Vec4& th = z[i];
    // The regressor in the filter's coordinates: phi^T (vis, cou, sti) = (phi_vis, phi_cou, phi_sti -
    // phi_cou)^T (vis, cou + sti, sti).
    const Vec4 phi(s.phi(0), s.phi(1), s.phi(2) - s.phi(1), s.gravity * kInverseTorque[i]);
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
    if (e2 * kGateSquaredInverse > explained + noise && !params::kTickWorstCase) {
      ++outliers[i];
      return IdentifyOutcome::kOutlier;
    }
    static constexpr S kAverage = lit<S>(1.0 / params::kIdentifyNoiseSamples);
    mean2 += kAverage * (e2 - mean2);
    S var = explained + correlation * noise;  // the innovation's variance, as the update counts it
    // In fixed point at least kFixedVarFloor (128 LSB: var's rounding within 0.4 %, as the noise's
    // floor), so that the gain P phi / var stays in range where the arm's quantisation noise is
    // below Q12.19's resolution in N^2 m^2 (the UR5e's wrist: 0.5 mN m); float and double as they are.
    if constexpr (fixed::is_q_v<S>) var = var < kFixedVarFloor ? kFixedVarFloor : var;
    th += correct(i, Pphi, var, excite(i, phi)) * innovation;
    const Vec4 bounded = project(i, th, theta_max);
    for (int c = 0; c < 3; ++c) theta(c * kDof + i) = bounded(c) * unscale(i);
    ++updates[i];
    for (int c = 0; c < 2; ++c) fit.judge(i, c, z[i](c), P[i](c, c), updates[i]);
    return IdentifyOutcome::kUpdated;
  }

  /// Joint i's friction set to theta^'s (a friction parameter set: a saved record applied at power-on, an
  /// identify run's applied): the estimate starts from it, with the prior's covariance (where the law goes on
  /// from, not what it knows: the data move it where they tell otherwise, and the split, which the task's motion
  /// seldom tells, stays). It is the reference of the joint's fit check (fit), which starts again.
  void seed(int i, const Vec18<S>& theta) {
    const S sc = scale(i), sti = theta(2 * kDof + i) * sc, sum = theta(kDof + i) * sc + sti;
    z[i](0) = theta(i) * sc;
    z[i](1) = sum;
    z[i](2) = sti;
    P[i] = prior(i);
    fit.set(i, z[i](0), sum, updates[i]);
  }
  /// Joint i's proven friction (proven), from its estimate z and covariance P as they stand (the
  /// drift included: while a joint is not sampled, P grows back and the bound with it). Its viscous
  /// coefficient and its breakaway torque are each at most z plus params::kTravelIdentifiedSd
  /// standard deviations, taken without a root: the first of params::kTravelTiers tiers whose
  /// standard deviation f z (f = params::kIdentifiedFraction, doubled tier by tier) covers sqrt(P)
  /// gives (1 + kTravelIdentifiedSd f) z; beyond the last, or z <= 0, the band's top, and never
  /// more, nor less than the band's bottom. Measured with params::kIdentifyDrift: a joint identified within 2.5 %
  /// keeps 1.1 z for about 9 s of rest, 1.2 z for 36 s, 1.4 z for 2.4 min and 1.8 z for 10 min (J2).
  void prove(int i) {
    static constexpr S kFraction = lit<S>(params::kIdentifiedFraction);
    static constexpr S kStep = lit<S>(params::kTravelIdentifiedSd * params::kIdentifiedFraction);
    const auto bound = [&](int c) {
      const S v = z[i](c), hi = top(c, i), p = P[i](c, c);
      if (!(v > S(0))) return hi;
      S fv = kFraction * v, above = kStep;
      for (int k = 0; k < params::kTravelTiers; ++k, fv += fv, above += above)
        if (p <= fv * fv) {
          const S b = (S(1) + above) * v * unscale(i), lo = bottom(c, i);
          return b < hi ? (b > lo ? b : lo) : hi;
        }
      return hi;
    };
    proven.vis(i) = bound(0);
    proven.breakaway(i) = bound(1);
  }

  /// The Kalman correction of joint i for a sample of innovation variance var, given P phi: P less
  /// (P phi)(P phi)^T / var, kept symmetric; returns the gain P phi / var.
  /// Without split (the Coulomb / Stribeck split not excited: excite), the Stribeck level
  /// (coordinate 2) is a consider state (Schmidt): its gain is 0, the others' the Kalman gain, and P
  /// is Joseph's form for that gain, which is the same update with the Stribeck level's variance
  /// left as it was.
  Vec4 correct(int i, const Vec4& Pphi, S var, bool split = true) {
    Vec4 gain = Pphi / var;
    Mat4& p = P[i];
    for (int a = 0; a < 4; ++a)
      for (int b = a; b < 4; ++b) {
        if (a == 2 && b == 2 && !split) continue;
        const S v = p(a, b) - gain(a) * Pphi(b);
        p(a, b) = v;
        p(b, a) = v;
      }
    if (!split) gain(2) = S(0);
    return gain;
  }
  /// The excitation monitor's gate: joint i's counted sample phi (the filter's coordinates) goes
  /// into the block of moments of its (vis, cou, decay) columns, decay = sti - cou (fold takes the
  /// full block). Returns whether the Coulomb / Stribeck split is excited enough to be learned.
  bool excite(int i, const Vec4& phi) {
    static constexpr S kGate =
        lit<S>(kDecayScale * kDecayScale * params::kIdentifySplitExcitation * params::kIdentifySplitExcitation);
    const Vec3<S> w(phi(0), phi(1), phi(2) * lit<S>(kDecayScale));
    Mat3& b = block[i];
    for (int r = 0; r < 3; ++r)
      for (int c = r; c < 3; ++c) b(r, c) += w(r) * w(c);
    ++block_count[i];
    return split_excitation(i) >= kGate;
  }
  /// A full block of joint i: the moments take its mean (an average over
  /// params::kIdentifyExciteBlocks blocks), and split_excitation(i) becomes the decay's mean square
  /// not explained by the other two columns.
  void fold(int i) {
    static constexpr S kMean = lit<S>(1.0 / params::kIdentifyExciteBlock);
    static constexpr S kAverage = lit<S>(1.0 / params::kIdentifyExciteBlocks);
    Mat3& b = block[i];
    Mat3& m = moments[i];
    for (int r = 0; r < 3; ++r)
      for (int c = r; c < 3; ++c) {
        m(r, c) += kAverage * (b(r, c) * kMean - m(r, c));
        b(r, c) = S(0);
      }
    block_count[i] = 0;
    split_excitation(i) = decay_unexplained(m);
  }
  /// The Schur complement of the decay column in the moments m (upper triangle): its mean square
  /// less what the Coulomb and viscous columns explain of it, eliminated in that order (an LDL^T
  /// step each, ratios before products, for fixed point's sake); 0 where those two are themselves
  /// collinear (a motion at one speed), which tells neither the split nor the viscous term.
  static S decay_unexplained(const Mat3& m) {
    static constexpr S kCollinear = lit<S>(1.0 / 1024);
    const S ss = m(1, 1);
    if (!(ss > S(0))) return S(0);
    const S l_v = m(0, 1) / ss, l_d = m(1, 2) / ss;
    const S vv = m(0, 0) - l_v * m(0, 1);  // the viscous column given the Coulomb column
    if (!(vv > kCollinear * m(0, 0))) return S(0);
    const S vd = m(0, 2) - l_d * m(0, 1);  // their cross moment given it
    const S u = m(2, 2) - l_d * m(1, 2) - (vd / vv) * vd;
    return u > S(0) ? u : S(0);
  }
  /// The decay column's factor in the moments (it is at most a few hundredths at the usual speeds:
  /// scaled up, it keeps fixed point's resolution; the blocks' sums stay within Q12.19 up to 8 rad/s).
  static constexpr double kDecayScale = 4;
  /// th (joint i's units) within [0, theta_max], projected in the metric of P^-1 (the estimate's
  /// own): a coefficient beyond a bound is set to it and the others move as P correlates them, so
  /// that a well identified sum (Coulomb + Stribeck) keeps its value when one of its terms meets a
  /// bound; one pass over the three, then a clip for what the pass leaves. The gravity error is not
  /// bounded.
  /// x is in the filter's coordinates (vis, cou + sti, sti, delta); the result is the coefficients
  /// (vis, cou, sti, delta). Coefficient c is a^T x, a = e_0, e_1 - e_2, e_2; its excess moves x by
  /// P a excess / a^T P a.
  Vec4 project(int i, Vec4 x, const Vec18<S>& theta_max) const {
    const S sc = scale(i);
    const Mat4& p = P[i];
    for (int c = 0; c < 3; ++c) {
      const S hi = theta_max(c * kDof + i) * sc, v = c == 1 ? x(1) - x(2) : x(c);
      const S excess = v < S(0) ? v : (v > hi ? v - hi : S(0));
      if (excess == S(0)) continue;
      const Vec4 pa = c == 1 ? Vec4(p.col(1) - p.col(2)) : Vec4(p.col(c));
      const S apa = c == 1 ? pa(1) - pa(2) : pa(c);
      if (apa > S(0)) x -= pa * (excess / apa);
    }
    Vec4 th(x(0), x(1) - x(2), x(2), x(3));
    for (int c = 0; c < 3; ++c) {
      const S hi = theta_max(c * kDof + i) * sc;
      if (th(c) < S(0)) th(c) = S(0);
      if (th(c) > hi) th(c) = hi;
    }
    return th;
  }

  /// Joint i's variance of coefficient c (0 vis, 1 cou, 2 sti), in the coefficient's own units
  /// squared (N m s/rad, N m) [host, double].
  double variance(int i, int c) const {
    const Mat4& p = P[i];
    const double v =
        c == 1 ? static_cast<double>(p(1, 1)) + static_cast<double>(p(2, 2)) - 2 * static_cast<double>(p(1, 2))
               : static_cast<double>(p(c, c));
    return v / square(scale_of(i));
  }
  /// Joint i's variance of the Coulomb and Stribeck levels' sum (the breakaway torque's) [N^2 m^2].
  double breakaway_variance(int i) const { return static_cast<double>(P[i](1, 1)) / square(scale_of(i)); }
  /// Joint i's Stribeck decay excitation: the decay column's RMS that the viscous and Coulomb
  /// columns do not explain, over the recent motion (excite) [1, a fraction of the Stribeck level];
  /// the split is learned at params::kIdentifySplitExcitation and above [host, double].
  double decay_excitation(int i) const {
    const double u = static_cast<double>(split_excitation(i));
    return u > 0 ? std::sqrt(u) / kDecayScale : 0.0;
  }
  /// Joint i's relative gravity error delta [1].
  double gravity_error(int i) const {
    return static_cast<double>(z[i](3)) / (scale_of(i) * robot::kDrives.torque_limit[i]);
  }

  /// The prior covariance of joint i in its units and the filter's coordinates: the coefficients
  /// independent, each the band's top as its standard deviation, the gravity error's link_inertia T_i;
  /// so the sum's variance is the Coulomb's plus the Stribeck's, and it covaries with the Stribeck
  /// level by the latter's.
  static Mat4 prior(int i) {
    static constexpr std::array<S, 4 * kDof> kPrior = band_squared(1.0);
    Mat4 p = Mat4::Zero();
    for (int c = 0; c < 4; ++c) p(c, c) = kPrior[c * kDof + i];
    p(1, 1) += p(2, 2);
    p(1, 2) = p(2, 2);
    p(2, 1) = p(2, 2);
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
  /// scale_of(i) in the scalar S, and its inverse.
  static S scale(int i) {
    static constexpr std::array<S, kDof> kScale = per_joint([](int j) { return scale_of(j); });
    return kScale[i];
  }
  static S unscale(int i) {
    static constexpr std::array<S, kDof> kUnscale = per_joint([](int j) { return 1 / scale_of(j); });
    return kUnscale[i];
  }
  /// The band's top of joint i's viscous coefficient (c = 0) or breakaway torque (c = 1, Coulomb +
  /// Stribeck) [N m s/rad, N m]; bottom(): its bottom, what is proven is never less (the band is what
  /// the arm's friction is known to lie within).
  static S top(int c, int i) { return band_end<&ModelErrorBounds::friction_hi>(c, i); }
  static S bottom(int c, int i) { return band_end<&ModelErrorBounds::friction_lo>(c, i); }
  template <FrictionCoefficients ModelErrorBounds::*End>
  static S band_end(int c, int i) {
    static constexpr std::array<S, kDof> kVis = per_joint([](int j) { return (robot::kModelErrorBounds.*End).vis[j]; });
    static constexpr std::array<S, kDof> kBreakaway = per_joint(
        [](int j) { return (robot::kModelErrorBounds.*End).cou[j] + (robot::kModelErrorBounds.*End).sti[j]; });
    return c == 0 ? kVis[i] : kBreakaway[i];
  }
  template <class F>
  static constexpr std::array<S, kDof> per_joint(F f) {
    std::array<S, kDof> a{};
    for (int j = 0; j < kDof; ++j) a[j] = lit<S>(f(j));
    return a;
  }
  /// f times each coefficient's prior variance in joint i's units: the band's top squared
  /// (robot::kModelErrorBounds), the gravity error's (link_inertia T_i)^2; with `sum`, the second is
  /// the filter's coordinate's, cou + sti: the Coulomb's plus the Stribeck's.
  static constexpr std::array<S, 4 * kDof> band_squared(double f, bool sum = false) {
    const ModelErrorBounds& b = robot::kModelErrorBounds;
    std::array<S, 4 * kDof> q{};
    for (int i = 0; i < kDof; ++i) {
      const double s2 = f * square(scale_of(i));
      q[i] = lit<S>(s2 * square(b.friction_hi.vis[i]));
      q[kDof + i] = lit<S>(s2 * (square(b.friction_hi.cou[i]) + (sum ? square(b.friction_hi.sti[i]) : 0.0)));
      q[2 * kDof + i] = lit<S>(s2 * square(b.friction_hi.sti[i]));
      q[3 * kDof + i] = lit<S>(s2 * square(b.link_inertia * robot::kDrives.torque_limit[i]));
    }
    return q;
  }
  /// The random walk: (kIdentifyDrift times each prior standard deviation)^2 per hour, up to the
  /// prior, in the filter's coordinates (the sum and the Stribeck level drift independently: a
  /// diagonal, so P stays positive definite). A variance above its prior (a held Stribeck level
  /// keeps its own) is left as it is, never lowered.
  void drift(int i) {
    static constexpr std::array<S, 4 * kDof> kDrift =
        band_squared(params::kIdentifyDrift * params::kIdentifyDrift / kPerHour, true);
    static constexpr std::array<S, 4 * kDof> kPrior = band_squared(1.0, true);
    for (int c = 0; c < 4; ++c) {
      const S p = P[i](c, c), v = p + kDrift[c * kDof + i], top = kPrior[c * kDof + i];
      P[i](c, c) = v < top ? v : (p < top ? top : p);
    }
  }
};

}  // namespace osc
