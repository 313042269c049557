// The residual monitor's turn and per-joint bound and thresholds (ResidualMonitor, osc/runtime/residual_monitor.hpp,
// which includes this header at its end; docs/safety.md derives each term): on each turn (params::kResidualTurnEvery
// steps), the motion over it, the friction's error against the band, the pointwise bound of the model's error
// filtered as r, the change channel's regressors and the two channels' thresholds.
#pragma once

#include <cstdint>

#include "osc/runtime/residual_monitor.hpp"

namespace osc {

/// A turn: the accelerations over it and A's rows against them first (each joint's thresholds read every
/// joint's), then one pass per joint: its friction, bound, change channel, thresholds and travel check.
/// Returns the joint that moved too far (the travel check), or -1.
template <class S>
inline int ResidualMonitor<S>::turn_pass(const ResidualInput<S>& in, const bool moved[kDof], bool prime,
                                         std::uint64_t tick) {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  if constexpr (kArmSphericalWrist) {
    if (in.J) wrist_noise(*in.J);
  } else if (in.os) {
    // The columns from kMixedNoiseBefore on (those before it on the step before: between_turns()); all when priming.
    mixed_noise(in.os->Ja, in.os->Jf, prime ? 0 : kMixedNoiseBefore, kDof);
  }
  const Motion m = motion(in);
  const StrongestFriction strongest(in);
  int moved_too_far = -1;
  for (int i = 0; i < kDof; ++i) {
    const Friction f = strongest(i);
    const FrictionError e = friction_error(in, f, i, tick, m.moving_speed[i]);
    const Torques t = torques(in, i);
    const S model = model_error(in, t, i);
    const S b = pointwise_bound(in, e, i, model);
    Changes ch{};
    if (prime) {
      bound(i) = b;
    } else {
      low_pass(bound(i), b, c.turn_gain_dt[i]);
      if (i == sample_joint) take_sample(i, e, in.io);
      ch = update_change(in, e, t, i);
    }
    const S loop = update_thresholds(e, ch, m, i);
    travel_error(i) = motion_error(in, m, i, model, loop);
    if (travel(in, f, i, moved[i], prime || contact, travel_turn(i, true))) moved_too_far = i;
  }
  return moved_too_far;
}

template <class S>
inline void ResidualMonitor<S>::mixed_noise(const Mat6<S>& J, const ArmJacobianFactor<S>& Jf, int first, int last) {
  if (first == 0) velocity_noise.setZero();
  // Scalar loops over the factor's own columns (no vector temporaries): the same operations, in the same order,
  // as m = k_min e_j + sum_a (k_a - k_min) J_aj J^-1 e_a; velocity_noise += quantum_j / 2 |m|.
  for (int j = first; j < last; ++j) {
    S m[kDof];
    for (int i = 0; i < kDof; ++i) m[i] = S(0);
    m[j] = k_min;
    for (int a = 0; a < kDof; ++a) {
      if (gain_excess(a) == S(0)) continue;
      const S s = gain_excess(a) * J(a, j);
      const auto col = Jf.inverse_column(a);
      for (int i = 0; i < kDof; ++i) m[i] += s * col(i);
    }
    const S h = half_quantum(j);
    for (int i = 0; i < kDof; ++i) velocity_noise(i) += h * math::abs(m[i]);
    // In fixed point x's own rounding too, which no J turns back: J^-1's column j times k_j and its bound.
    if constexpr (fixed::is_q_v<S>) velocity_noise += pose_noise(j) * Jf.inverse_column(j).cwiseAbs();
  }
}

/// A step between turns: the travel check's counts and drive, and the odd joints' step of its bounds (the even
/// joints' is on the turn: each joint's every kResidualTurnEvery steps, half of them in each step), with the
/// error bound of the last turn; without a spherical wrist, half the velocity noise the next turn reads.
template <class S>
inline int ResidualMonitor<S>::between_turns(const ResidualInput<S>& in, const bool moved[kDof]) {
  // Without a spherical wrist, the first columns of the next turn's velocity noise (mixed_noise()).
  if constexpr (!kArmSphericalWrist) {
    if (in.os) mixed_noise(in.os->Ja, in.os->Jf, 0, kMixedNoiseBefore);
  }
  const StrongestFriction strongest(in);
  int moved_too_far = -1;
  for (int i = 0; i < kDof; ++i)
    if (travel(in, strongest(i), i, moved[i], contact, travel_turn(i, false))) moved_too_far = i;
  return moved_too_far;
}

/// A turn's joint motion (Motion).
template <class S>
inline auto ResidualMonitor<S>::motion(const ResidualInput<S>& in) -> Motion {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  Motion m;
  for (int j = 0; j < kDof; ++j) {
    m.moving_speed[j] = math::mul_add(lag, math::abs(acc(j)), velocity_noise(j));
    acc(j) = math::mul_add(c.gain[j], in.qd(j) - qd_turn(j), c.turn_keep[j] * acc(j));
    low_pass(acc_slow(j), acc(j), c.slow_dt);
    m.a[j] = math::abs(acc(j));
    m.da[j] = math::abs(acc(j) - acc_slow(j));
    m.inertia[j] = m.inertia_change[j] = m.noise[j] = S(0);
  }
  qd_turn = in.qd;
  m.allowance = S(0);
  if (allowance_mass > S(0)) m.allowance = allowance_change(in, m);
  // Column by column: each of A's coefficients is read once.
  for (int j = 0; j < kDof; ++j)
    for (int i = 0; i < kDof; ++i) {
      const S mag = math::abs(in.A(i, j));
      m.inertia[i] = math::mul_add(mag, m.a[j], m.inertia[i]);
      m.inertia_change[i] = math::mul_add(mag, m.da[j], m.inertia_change[i]);
      m.noise[i] = math::mul_add(mag, velocity_noise(j), m.noise[i]);
    }
  return m;
}

/// The share of a payload's torque error that the change channel can see, this turn (Motion::allowance), at most 2
/// (its weight's torque from one side to the other). allowance(i), m g l_i with l_i = flange_lever(i), bounds:
/// - its weight's torque's rate by that times w = sum_j |q^dot_j| (joint j turns the weight about an axis, or moves
///   axis i with it, at most l_i from it), which the change channel sees as the rate over the slow filter's gain (a
///   ramp's r - r_slow);
/// - its inertial torques, m l_i times the flange's acceleration, by that times (sum_j l_j |q^dot^dot_j| + l_0 w^2)
///   / g: the accelerations' change (Motion::da) for the first, twice the whole for the second.
/// At rest 0: a hold's and a slow motion's collision sensitivity is the channel's own (docs/safety.md, "A payload not
/// yet identified").
template <class S>
inline S ResidualMonitor<S>::allowance_change(const ResidualInput<S>& in, const Motion& m) const {
  static constexpr S kSlowPeriod = lit<S>(1.0 / params::kResidualSlowGain);
  S w = S(0), inertial = S(0);
  for (int j = 0; j < kDof; ++j)
    w += math::abs(in.qd(j)), inertial = math::mul_add(allowance_reach(j), m.da[j], inertial);
  const S share = math::mul_add(w, kSlowPeriod, math::mul_add(S(2) * allowance_reach(0) * w, w, inertial));
  return share < S(2) ? share : S(2);
}

/// Joint i's friction against the band (FrictionError), `f` at its strongest; `moving` is the speed
/// beyond which the joint may count as moving (Motion::moving_speed).
template <class S>
inline auto ResidualMonitor<S>::friction_error(const ResidualInput<S>& in, const Friction& f, int i, std::uint64_t tick,
                                               S moving) const -> FrictionError {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  using math::abs;
  FrictionError e;
  if (in.theta) {
    const Vec18<S>& th = *in.theta;
    e.th_v = th(i), e.th_c = th(kDof + i), e.th_s = th(2 * kDof + i);
  } else {
    e.th_v = e.th_c = e.th_s = S(0);
  }
  e.dv = abs(e.th_v - c.vis_mid[i]) + c.vis_half[i];
  // Coulomb's level lies within its band and below the strongest breakaway less the least Stribeck
  // level (the identification's proven breakaway narrows it; the band's top leaves it as it is).
  const S cap = f.breakaway - c.sti_lo[i], cou_top = cap < c.cou_hi[i] ? cap : c.cou_hi[i];
  const S below = e.th_c - c.cou_lo[i], above = cou_top - e.th_c;
  e.dc = below > above ? below : above;
  e.ds = abs(e.th_s - c.sti_mid[i]) + c.sti_half[i];
  // Static friction anywhere within the band (its top, or what the identification proves), against
  // whatever the estimate says.
  e.still = math::mul_add(f.vis, moving, f.breakaway) + abs(in.tau_f(i));
  // The direction of motion is known when the encoder counts and q^dot is beyond its noise and lag;
  // the joint slides (its friction on the model's curve) when it counts fast enough besides. The
  // stillness envelope and the identification's samples go by the first (a joint that crawls
  // between counts resets neither).
  // On an encoder finer than the slide speed's count interval, its counts over the last window as
  // well (EncoderActivity::fast_enough): a joint held against static friction may creep and count, and
  // q^dot, the observer's, carries the friction the model lacks (tens of mrad/s while it stands).
  const bool up = in.qd(i) > S(0);
  e.moving = abs(in.qd(i)) > moving && activity.counting(i, up, tick) && activity.fast_enough(i);
  e.sliding = e.moving && activity.sliding(i);
  return e;
}

/// Joint i's bound on the unexplained torque that changes with the state (then filtered as r):
/// friction, amplifiers, and the link inertia's share of gravity and Coriolis torques.
template <class S>
inline S ResidualMonitor<S>::pointwise_bound(const ResidualInput<S>& in, const FrictionError& e, int i, S model) const {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  using math::mul_add;
  // Moving: the band's distance from the estimate, coefficient by coefficient, at the motor's rate (the joint's
  // where C = I: ResidualInput::io; the other motors' friction through a coupling is cross_friction's).
  const S rate = in.rate ? (*in.rate)(i) : in.qd(i);
  const S friction = e.sliding ? mul_add(math::abs(rate), e.dv,
                                         mul_add(in.decay(i), e.ds, mul_add(c.vis_hi[i], velocity_noise(i), e.dc)))
                               : e.still;
  return friction + model;
}

/// Joint i's bound on the unexplained torque besides friction and the inertias: the link
/// inertia's share of gravity and Coriolis torques, the amplifier's gain, ripple and offset, and
/// the coupled motors' friction (error_floor, with a contact's push while it lasts).
template <class S>
inline S ResidualMonitor<S>::model_error(const ResidualInput<S>& in, const Torques& t, int i) const {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  using math::mul_add;
  return mul_add(c.link_inertia, math::abs(in.g(i)) + math::abs(t.coriolis),
                 mul_add(c.gain_ripple, t.size, error_floor(i)));
}

/// Joint i's change channel, a turn at a time: each regressor of the model's error filtered as r, then slowly,
/// and r itself slowly (the torque and r as their means over the turn: their tick-by-tick alternation, a
/// compensation's sign term at a joint that hunts about rest, would alias into a turn's samples). A
/// model error sum_k delta_k phi_k with constant coefficients delta_k reaches r - r_slow as
/// sum_k delta_k (phi_k filtered - its slow part): bounded by the same sum of |delta_k| times
/// the regressors' changes. Static friction is no such sum: a joint that does not move may hold
/// anything within its static band, from one end to the other (twice the band), and keeps it in
/// the change threshold until the slow filter forgets it.
template <class S>
inline auto ResidualMonitor<S>::update_change(const ResidualInput<S>& in, const FrictionError& e, const Torques& t,
                                              int i) -> Changes {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  const S Ks = c.slow_dt, Kdt = c.turn_gain_dt[i], half = lit<S>(0.5);
  // The friction's regressors at the motor's rate (the joint's where C = I: ResidualInput::io).
  const S qd = in.rate ? (*in.rate)(i) : in.qd(i), sign = qd > S(0) ? S(1) : (qd < S(0) ? S(-1) : S(0));
  // Filtered as r, then slowly: the regressor's change.
  const auto band = [&](int k, S phi) {
    low_pass(reg[k](i), phi, Kdt);
    low_pass(reg_slow[k](i), reg[k](i), Ks);
    return reg[k](i) - reg_slow[k](i);
  };
  Changes ch;
  ch.vis = band(kVis, qd);
  ch.cou = band(kCou, sign);
  ch.sti = band(kSti, sign * in.decay(i));
  ch.estimate = band(kEstimate, in.tau_f(i));
  ch.gravity = band(kGravity, in.g(i));
  ch.coriolis = band(kCoriolis, t.coriolis);
  ch.torque = band(kTorque, half * (tau_prev(i) + tau_last(i)));
  low_pass(reg[kTorqueSize](i), t.size, Kdt);          // |tau|: its size alone
  low_pass(r_slow(i), half * (r(i) + r_last(i)), Ks);  // d = r - r_slow: check(), every step
  stillness(i) = e.moving ? stillness(i) - Ks * stillness(i) : S(1);
  return ch;
}

/// Joint i's friction sample, on a turn: r is this tick's, the filtered regressors still the last turn's, as
/// the friction in r is of the periods before (n_{k-1}). Settled: moving, its encoder counting, since
/// params::kIdentifySettle time constants of the filter (the stillness envelope has decayed that
/// far), and its filtered speed params::kIdentifyMinSpeed times its velocity noise (slower, the
/// noise is a share of the viscous column, and its errors in the variables a bias): its own row's,
/// noise_base, without the wrist's mixing (wrist_noise()), which would leave the paper's slow wrist
/// motion to its few fast samples: J4's Coulomb / Stribeck split learnt from them, J4's and J6's
/// residuals reached 0.42 and 0.53 of their thresholds on the paper's motion (0.29 with this).
/// On a coupled drive train (io) the sample is motor i's: its torque (C^T (tau_f^ - r))_i, the terms of the
/// joints after i (C is lower triangular) filtered with the same gain (the wrist's), and their filtered values
/// the last turn's as i's (this pass reaches them after i).
template <class S>
inline void ResidualMonitor<S>::take_sample(int i, const FrictionError& e, const IoMap<S>* io) {
  static constexpr std::array<S, kDof> kSettled = settled_stillness();
  sample.y = reg[kEstimate](i) - r(i);
  for (int k = 0; io && k < io->terms; ++k)
    if (io->col[k] == i) sample.y += io->c[k] * (reg[kEstimate](io->row[k]) - r(io->row[k]));
  sample.phi = Vec3<S>(reg[kVis](i), reg[kCou](i), reg[kSti](i));
  sample.gravity = reg[kGravity](i);
  static constexpr S kMinSpeed = lit<S>(params::kIdentifyMinSpeed);
  sample.settled = e.moving && stillness(i) <= kSettled[i] && math::abs(sample.phi(0)) > kMinSpeed * noise_base(i);
}

/// Joint i's thresholds: the filtered bound, the inertias' error on the filtered accelerations, and
/// the velocity estimate's noise through A and the filter. `ch`: the regressors' changes (zero
/// when priming). Returns the current loop's lag term (the travel check's too).
template <class S>
inline S ResidualMonitor<S>::update_thresholds(const FrictionError& e, const Changes& ch, const Motion& m, int i) {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  using math::abs;
  using math::mul_add;
  const S quantum = c.quantum_gain[i] * m.noise[i], margin_quantum = c.margin * quantum;
  noise_bound(i) = quantum;
  // The current loop's lag T: its error T d(tau)/dt, filtered as r, is T K (tau - tau filtered), the larger of
  // the turn's two periods.
  const S now = abs(tau_prev(i) - reg[kTorque](i)), before = abs(tau_last(i) - reg[kTorque](i));
  const S loop = c.lag_gain[i] * (now > before ? now : before);
  const S pointwise = mul_add(c.link_inertia, m.inertia[i], mul_add(c.armature_delta[i], m.a[i], bound(i) + loop));
  threshold(i) = mul_add(c.peak_margin[i], pointwise, margin_quantum);
  // The friction error (theta - theta^)^T w: the band's distances times the regressors'
  // changes at the estimate of now, plus what the estimate's own change added.
  const S learnt = ch.estimate - mul_add(e.th_v, ch.vis, mul_add(e.th_c, ch.cou, e.th_s * ch.sti));
  const S friction = mul_add(e.dv, abs(ch.vis), mul_add(e.dc, abs(ch.cou), mul_add(e.ds, abs(ch.sti), abs(learnt)))) +
                     mul_add(c.vis_hi[i], velocity_noise(i),
                             S(2) * mul_add(e.sliding ? stillness(i) : S(1), e.still, cross_friction(i)));
  // A payload not yet identified: the allowance's torque times its share that changes (Motion::allowance).
  const S model = mul_add(c.link_inertia, m.inertia_change[i] + abs(ch.gravity) + abs(ch.coriolis),
                          mul_add(c.armature_delta[i], m.da[i], m.allowance * allowance(i)));
  const S amplifier = mul_add(c.amp_gain, abs(ch.torque), mul_add(c.ripple, reg[kTorqueSize](i), loop));
  change_threshold(i) = mul_add(c.peak_margin[i], friction + model + amplifier, margin_quantum);
  return loop;
}

}  // namespace osc
