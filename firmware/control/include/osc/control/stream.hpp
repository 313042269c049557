// A jerk-limited follower of streamed setpoints: a client sends samples x_k of the 6 operational
// coordinates (wrist-centre position [m]; roll, pitch, yaw of R R_ref^T [rad]) at a fixed rate of
// 10 Hz to 1 kHz; every 1 ms tick the follower produces a reference (x, xd, xdd) within the move
// limits that follows the stream.
//
// Target. The linear interpolation between the last two samples, delayed by one sample period T
// (so the segment is known when it is used): from the arrival of s_k,
//   r(tau) = s_prev + (s_k - s_prev) tau / T,   v_r = (s_k - s_prev) / T,   tau in ticks since then,
// where s_prev is where the target stood when s_k arrived (s_{k-1} for a punctual stream; the start
// pose for the first sample), so the target never jumps, also for a sample that comes early or late.
// While the next sample is late (tau > T) the target is extrapolated along v_r until the stream is
// stale (below), for at most kStreamExtrapolation (max(2 T, 20 ms) - T is within it for T <= 100 ms),
// and then holds; after end() the target stops at the last sample instead.
//
// A sample with its velocity v_k (push(s, v)): no delay. The target joins the sample's own line
// s_k + v_k t (t since its arrival) within one period, by the cubic (Hermite) from where the target
// stands, with its velocity w, to the point s_k + v_k T with velocity v_k: with h = tau / T,
//   r = r0 + (3 h^2 - 2 h^3) D + (h^3 - 2 h^2 + h) T w + (h^3 - h^2) T v_k,   D = s_k + v_k T - r0,
// position and velocity continuous at every sample; beyond T it goes on along the line, as the
// extrapolation above. For a path sampled with its derivative the target is the path itself up to
// the prediction's error (a T^2 / 2 at acceleration a): on test_stream's path at 10 Hz the
// reference is within 1.4 mm of the path, against 8.2 mm (about v T) for samples without velocity.
// The end sample's velocity is taken as zero (the arm comes to rest at it). A sample's velocity is
// clamped to +-kStreamMaxSampleVelocity per axis (far above any speed limit).
//
// Follower, per axis, each tick: the velocity it aims at
//   v* = v_r + clamp(kp e, +-sqrt(2 a_b |e|)),  e = r - p,  clamped to +-vmax,
// (the square root, which is the lower beyond |e| = amax / kp^2, bounds the position term by a
// braking curve at a_b = amax / 2, so a large error is closed without overshoot: kp alone would ask
// for a deceleration kp |v| > amax near vmax). kp = kStreamGain = 4 /s: the measured lag behind the
// delayed path is 0.3 to 0.9 mm (1 kHz to 10 Hz, test_stream); 8 /s halves it, but Q12.19 then
// exceeded the jerk limit by 0.8 % (the rounding margin would need a look). Then,
// exactly over one tick dt, the time-optimal change from (v, a) to (v*, 0) under amax and jmax
// (jerk_profile::velocity_change, its pieces evaluated over [0, dt] by advance()): |j| <= jmax and
// |a| <= amax by construction. |v| <= vmax too: along such a change the coast velocity
// v + a |a| / (2 jmax) moves monotonically towards v* (within the tick and over ticks), and v lies
// between the coast velocity and a velocity it had before, so with every v* within +-vmax so is v.
//
// Limits per axis, which guarantee the Euclidean ones of CartesianLimits (after rounding_margin):
//   translation  v/sqrt(3), a/sqrt(3), j/sqrt(3) of linear:  |p_dot| <= v, |p_ddot| <= a, ...
//   orientation  those of angular divided by sqrt(3) * 1.42:  w = E(phi) phi_dot, and for the
//                roll-pitch-yaw rates ||E(phi)||_2 = sqrt(1 + |sin pitch|) <= sqrt(2) < 1.42, so
//                |w| <= 1.42 |phi_dot| <= the angular speed limit (at any pitch away from the
//                coordinates' singularity at +-pi/2). The assumption is in the derivatives:
//                w_dot = E phi_ddot + Edot phi_dot, the first term within the limit, the second of
//                the order |phi_dot|^2 (<= 0.04 rad/s^2 at the default 0.5 rad/s): moderate rates
//                and pitch (the tests measure |w_dot| from differences of w, within 5 %).
//
// Stale stream: no sample for more than max(2 T, 20 ms) makes stale() true (the target was
// extrapolated from T on, at most kStreamExtrapolation); the caller then calls stop(): a category-2
// stop, every axis braked to v = 0 (v* = 0, no position term) under its limits scaled by
// |v_i| / max_k |v_k| within its group (translation, orientation), at least kStopScaleFloor and at
// least |a_i| (so |a_i| <= the stop's amax): axes whose accelerations are in the proportions of
// their velocities follow proportional profiles and stop together, so the reference decelerates
// approximately along its current direction (within 2 degrees in the tests). stopped(): stopped and
// at rest (v = a = 0 exactly: the last change ends inside a tick at (0, 0); an axis within
// kStopRestSpeed is set to rest, as Q12.19's last changes are below its resolution).
//
// Time in integer ticks. Header-only, allocation-free, templated on the scalar.
#pragma once

#include <cstdint>

#include "osc/control/cartesian_move.hpp"  // CartesianLimits, rounding_margin
#include "osc/control/jerk_profile.hpp"
#include "osc/control/params.hpp"
#include "osc/control/trajectory.hpp"  // Desired

namespace osc {

/// The longest extrapolation of a late stream's target along its last velocity [s].
constexpr double kStreamExtrapolation = 0.1;
/// A stream is stale after max(2 periods, kStreamTimeoutMin) without a sample [s].
constexpr double kStreamTimeoutMin = 0.02;
/// The position gain of the follower [1/s].
constexpr double kStreamGain = 4.0;
/// The bound on |E(phi)|_2 the orientation axes' limits assume (sqrt(2) at any pitch).
constexpr double kStreamEBound = 1.42;
/// An ended stream is done within this distance of its last sample [m, rad] (settled()).
constexpr double kStreamSettle = 1e-5;
/// The least scale of an axis' limits in a stop (an axis at rest still brings a to 0).
constexpr double kStopScaleFloor = 0.1;
/// A stopping axis whose speed is at most this is at rest [m/s, rad/s]: its speed is set to 0 and
/// its acceleration ramped to 0 at the stop's jerk limit (stop_axis). Two resolutions of Q12.19: in
/// it a tick's change a dt of a small acceleration (below 1.9e-3 m/s^2) rounds to 0 or one unit, and
/// a stop ended in a cycle of +-1 unit of speed, never at rest. In double and float the stop ends at
/// (0, 0) exactly in the tick after it passes below this (a change of a few nanometres).
constexpr double kStopRestSpeed = 4e-6;
/// A sample's velocity is clamped to this per axis [m/s, rad/s] (the fixed-point range: the target
/// is a sum of velocities times at most T = 0.1 s).
constexpr double kStreamMaxSampleVelocity = 2.0;

namespace stream {
/// Advances s over one tick dt by the time-optimal change from (v, a) to (vt, 0) under amax, j; the
/// rest of the tick after the change has ended at (vt, 0) exactly.
///
/// The position: the tick's displacement is accumulated as its mean velocity (the pieces' mean
/// velocities weighted by their fractions of the tick, at the velocity's resolution) into the
/// residual lo [m/s of one tick], of which the whole steps of p (lo / kHz rounded) are moved to p.
/// Advancing p itself would round each tick's v dt to p's resolution: in Q12.19 (2e-6 m) a speed
/// below 1e-3 m/s would not move p at all, a dead band of 2e-4 m with xd != 0 at rest.
template <class S>
void step_axis(jerk_profile::Kin<S>& s, S& lo, S vt, S amax, S j, S dt) {
  using namespace jerk_profile;
  const S zero(0), half = lit<S>(0.5), sixth = lit<S>(1.0 / 6.0), hz(static_cast<int>(params::kControlHz));
  const VelocityChange<S> c = velocity_change(s.v, s.a, vt, amax, j);
  S left = dt, w = zero;
  auto piece = [&](S jerk, S t) {
    const S tt = t < left ? t : left;
    if (!(tt > zero)) return;
    w += (tt * hz) * (s.v + tt * (s.a * half + tt * (jerk * sixth)));
    s.v = s.v + tt * (s.a + tt * (jerk * half));
    s.a = s.a + tt * jerk;
    left -= tt;
  };
  piece(c.sign * j, c.t1);
  if (left > zero && c.t2 > zero) {
    s.a = c.sign * amax;  // the hold, at the limit exactly (the ramp ends there to rounding)
    piece(zero, c.t2);
  }
  piece(-(c.sign * j), c.t3);
  if (left > zero && math::abs(s.a) > j * left) {
    // The ramps' durations left more acceleration than the rest of the tick can take away at the
    // jerk limit: it is ramped towards 0 at the limit, and the next tick's change goes on from there.
    // (In Q12.19 the change between small accelerations is ill-conditioned: b^2 / 2 of
    // velocity_change at |a| ~ 1e-3 m/s^2 is a unit or two of the format, and the pieces end with
    // an acceleration that setting it to 0 would jump by more than j dt.) In double and float the
    // acceleration left is rounding-small, and this never happens.
    piece(s.a > zero ? -j : j, left);
  }
  if (left > zero) {
    s.v = vt, s.a = zero;  // the change ended inside the tick: cruise at vt for the rest of it
    w += (left * hz) * vt;
  }
  lo += w;
  // What p actually moved by leaves the residual (in float, a step below half of p's ulp does not
  // move it: it stays in lo until the steps add up to one).
  const S p = s.p + lo / hz;
  lo -= (p - s.p) * hz;
  s.p = p;
}

/// A time [s] as whole ticks, rounded to the nearest.
constexpr std::uint32_t ticks(double seconds) {
  const double t = seconds * params::kControlHz;
  const auto whole = static_cast<std::uint32_t>(t);
  return t - whole >= 0.5 ? whole + 1 : whole;
}

template <class S>
S clamp(S x, S lim) {
  return x > lim ? lim : (x < -lim ? -lim : x);
}
}  // namespace stream

/// A stream's stop lead (StreamFollower::stop_lead) as a fraction: the distance d its stop covers
/// over the velocity v it starts from, lead = d / v [s]. None (v = 0) while no axis moves.
template <class S>
struct StopLead {
  S d{0}, v{0};
};

template <class S>
class StreamFollower {
 public:
  static constexpr std::uint32_t kHz = params::kControlHz;
  /// 1 / sqrt(3), rounded down (3 axes at this fraction of a limit are within it, in double too).
  static constexpr double kInvSqrt3 = 0.577350269;
  static constexpr std::uint32_t kExtrapolationTicks = stream::ticks(kStreamExtrapolation);
  static constexpr std::uint32_t kTimeoutMinTicks = stream::ticks(kStreamTimeoutMin);

  explicit StreamFollower(const CartesianLimits<S>& lim = CartesianLimits<S>::defaults()) { set_limits(lim); }

  /// The limits the reference keeps (before start()).
  void set_limits(const CartesianLimits<S>& lim) {
    const JerkLimits<S> l = rounding_margin(lim.linear), w = rounding_margin(lim.angular);
    const S kl = lit<S>(kInvSqrt3), kw = lit<S>(kInvSqrt3 / kStreamEBound);
    for (int i = 0; i < 6; ++i) {
      const JerkLimits<S>& g = i < 3 ? l : w;
      const S k = i < 3 ? kl : kw;
      lim_[i] = {g.v * k, g.a * k, g.j * k};
    }
    for (int g = 0; g < 2; ++g) {
      const JerkLimits<S>& a = lim_[3 * g];
      inv_a_[g] = S(1) / a.a, inv_j_[g] = S(1) / a.j, ramp_[g] = a.a / a.j;
    }
  }

  /// Starts at x0 at rest (the held pose), the stream's period `period_ticks` (1 to 100 ticks: 1 kHz
  /// to 10 Hz); stale after max(2 periods, timeout_min ticks) without a sample.
  void start(const Vec6<S>& x0, std::uint32_t period_ticks, std::uint32_t timeout_min = kTimeoutMinTicks) {
    period_ = period_ticks > 0 ? period_ticks : 1;
    rate_ = math::ratio<S>(kHz, period_);
    const std::uint32_t twice = 2 * period_;
    timeout_ = twice > timeout_min ? twice : timeout_min;
    period_s_ = math::ratio<S>(period_, kHz);
    prev_ = cur_ = sample_ = x0;
    w0_ = v1_ = Vec6<S>::Zero();
    since_ = 0;
    ended_ = stopping_ = with_velocity_ = false;
    for (int i = 0; i < 6; ++i) s_[i] = {x0(i), S(0), S(0)}, lo_[i] = S(0);
  }

  /// A new sample arrived (call before tick() of the same tick). Ignored after stop().
  void push(const Vec6<S>& sample) {
    if (stopping_) return;
    Vec6<S> vr;
    prev_ = target(vr);
    cur_ = sample_ = sample;
    since_ = 0;
    ended_ = with_velocity_ = false;
  }
  /// A new sample with its velocity (the rates of the coordinates): the target joins its line
  /// sample + velocity t within one period (the file comment).
  void push(const Vec6<S>& sample, const Vec6<S>& velocity) {
    if (stopping_) return;
    prev_ = target(w0_);
    sample_ = sample;
    for (int i = 0; i < 6; ++i) {
      v1_(i) = stream::clamp(velocity(i), lit<S>(kStreamMaxSampleVelocity));
      cur_(i) = sample(i) + v1_(i) * period_s_;
    }
    since_ = 0;
    ended_ = false, with_velocity_ = true;
  }

  /// The stream has ended: the target stays at the last sample (no extrapolation, never stale),
  /// reached at rest (a velocity given with it is taken as zero).
  void end() {
    ended_ = true;
    if (with_velocity_) cur_ = sample_, v1_ = Vec6<S>::Zero();
  }

  /// The category-2 stop: every axis brakes to rest, the axes of a group together.
  void stop() {
    if (stopping_) return;
    stopping_ = true;
    for (int g = 0; g < 6; g += 3) {
      S vmax(0);
      for (int i = g; i < g + 3; ++i) vmax = math::abs(s_[i].v) > vmax ? math::abs(s_[i].v) : vmax;
      for (int i = g; i < g + 3; ++i) {
        S k = vmax > S(0) ? math::abs(s_[i].v) / vmax : S(1);
        if (k < lit<S>(kStopScaleFloor)) k = lit<S>(kStopScaleFloor);
        const S a = lim_[i].a * k;
        stop_[i] = {S(0), a > math::abs(s_[i].a) ? a : math::abs(s_[i].a), lim_[i].j * k};
      }
    }
  }

  /// The reference for this tick: the state one tick on.
  Desired<S> tick() {
    const S dt = lit<S>(params::kDt), kp = lit<S>(kStreamGain), kp2 = lit<S>(kStreamGain * kStreamGain);
    Vec6<S> vr;
    const Vec6<S> r = target(vr);
    Desired<S> d;
    for (int i = 0; i < 6; ++i) {
      if (stopping_) {
        stop_axis(i, dt);
      } else {
        const JerkLimits<S>& l = lim_[i];
        // kp e, bounded by the braking curve sqrt(2 a_b |e|) (a_b = amax / 2), which is the lower
        // beyond |e| = amax / kp^2 (only there: a |e| of a small error is below the resolution of
        // Q12.19, and the bound would be 0).
        const S e = r(i) - s_[i].p, ae = math::abs(e);
        const S vp = ae * kp2 > l.a ? (e > S(0) ? math::sqrt(l.a * ae) : -math::sqrt(l.a * ae)) : kp * e;
        stream::step_axis(s_[i], lo_[i], stream::clamp(vr(i) + vp, l.v), l.a, l.j, dt);
      }
      d.x(i) = s_[i].p, d.xd(i) = s_[i].v, d.xdd(i) = s_[i].a;
    }
    if (since_ <= timeout_) ++since_;  // saturates: stale stays stale
    return d;
  }

  /// No sample for more than max(2 T, 20 ms) (and end() not called).
  bool stale() const { return !ended_ && since_ > timeout_; }
  /// Stopped (stop()) and every axis at rest.
  bool stopped() const { return stopping_ && at_rest(); }
  /// Ended (end()), the target at the last sample, and every axis within kStreamSettle of it and
  /// near rest (|v| <= kStreamSettle / s, |a| <= 10 kStreamSettle / s^2): the stream is done, and
  /// the reference can hold its position with v = a = 0 (a step below the resolution of Q12.19's
  /// speed and acceleration limits' margins).
  bool settled() const {
    if (!ended_ || since_ < period_) return false;
    const S tol = lit<S>(kStreamSettle), atol = lit<S>(10 * kStreamSettle);
    for (int i = 0; i < 6; ++i)
      if (math::abs(cur_(i) - s_[i].p) > tol || math::abs(s_[i].v) > tol || math::abs(s_[i].a) > atol) return false;
    return true;
  }
  /// Every axis at rest (v = a = 0).
  bool at_rest() const {
    for (int i = 0; i < 6; ++i)
      if (s_[i].v != S(0) || s_[i].a != S(0)) return false;
    return true;
  }
  /// The per-axis limits in use.
  const JerkLimits<S>& limits(int axis) const { return lim_[axis]; }
  /// How far a stop() from now would carry the reference, as a time at its present velocity: the
  /// longer of the two groups' (translation, rotation). A group's fastest axis (by its coast velocity
  /// below) brakes at the group's full limits amax, j (the others at theirs scaled in proportion,
  /// stopping together). Its stop from (v, a) (v >= 0 taken along the motion, a along it too) is the
  /// stop from rest acceleration at the coast velocity v_c = v + a^2 / (2 j), which covers
  ///   v_c (v_c / amax + amax / j) / 2       (half its duration at v_c: the profile is point-symmetric),
  /// with, when the axis accelerates (a > 0), the ramp of a to 0 before it added, t (v + a t / 3) with
  /// t = a / j; when it slows (a < 0), the ramp from 0 to a that the stop from v_c would have begun
  /// with taken off, t (v_c - |a| t / 6). The distance D divided by v, v floored at a^2 / (2 j): no
  /// jerk-limited motion from rest is slower at that acceleration (it ramped a from 0 at most at j),
  /// so the floor only bounds the lead where a stream reverses through v = 0 (there the check is a few
  /// ticks late: 4 mm of the reference at the PUMA's 0.4 m/s^2 from rest). For a trapezoidal stop the
  /// distance is exact; for a triangular one (v_c < amax^2 / j) it is above. Returned as the fraction
  /// D / v (StopLead), the longer group's taken by cross-multiplying: the tick's joint-limit check
  /// (motion_limits_reached) multiplies through by v, so that no division is taken (64-bit on the M3).
  StopLead<S> stop_lead() const {
    const S half = lit<S>(0.5), third = lit<S>(1.0 / 3.0), sixth = lit<S>(1.0 / 6.0);
    StopLead<S> lead;
    for (int g = 0; g < 2; ++g) {
      int f = 3 * g;
      S vc(0);
      for (int i = 3 * g; i < 3 * g + 3; ++i) {
        const S c = math::abs(s_[i].v) + s_[i].a * s_[i].a * half * inv_j_[g];
        if (c > vc) vc = c, f = i;
      }
      const S v = math::abs(s_[f].v), a = s_[f].v < S(0) ? S(-s_[f].a) : s_[f].a;
      const S t = math::abs(a) * inv_j_[g];
      S d = half * vc * (vc * inv_a_[g] + ramp_[g]);
      d += a > S(0) ? S(t * (v + third * a * t)) : S(-(t * (vc - sixth * math::abs(a) * t)));
      const S floor = a * a * half * inv_j_[g], den = v > floor ? v : floor;
      if (d > S(0) && den > S(0) && (lead.v == S(0) || d * lead.v > lead.d * den)) lead = {d, den};
    }
    return lead;
  }
  /// The target r at this tick and its velocity v_r.
  Vec6<S> target(Vec6<S>& vr) const {
    // The target moves until tau = T (after end()), else until the stream is stale, extrapolating
    // for at most kStreamExtrapolation; then it holds.
    const std::uint32_t extrapolated = period_ + kExtrapolationTicks;
    const std::uint32_t cap = ended_ ? period_ : (timeout_ < extrapolated ? timeout_ : extrapolated);
    const std::uint32_t tau = since_ < cap ? since_ : cap;
    if (with_velocity_) return joined_target(tau, since_ < cap, vr);
    const S f = math::ratio<S>(tau, period_);
    Vec6<S> r;
    for (int i = 0; i < 6; ++i) {
      const S dx = cur_(i) - prev_(i);
      r(i) = prev_(i) + dx * f;
      // v_r is clamped to vmax by the follower anyway: the difference is bounded first so that a
      // far sample (2 pi rad at 1 kHz) stays within the fixed-point range.
      vr(i) = since_ < cap ? stream::clamp(dx, lit<S>(2.0)) * rate_ : S(0);
    }
    return r;
  }

 private:
  /// The target of a sample with velocity at tau ticks since it came (the file comment): the cubic
  /// to its line until T, then along it; `moving`: false once held (vr = 0).
  Vec6<S> joined_target(std::uint32_t tau, bool moving, Vec6<S>& vr) const {
    Vec6<S> r;
    if (tau >= period_) {
      const S t = math::ratio<S>(tau - period_, kHz);
      for (int i = 0; i < 6; ++i) r(i) = cur_(i) + v1_(i) * t, vr(i) = moving ? v1_(i) : S(0);
      return r;
    }
    const S h = math::ratio<S>(tau, period_), h2 = h * h, h3 = h2 * h;
    const S c = lit<S>(3.0) * h2 - lit<S>(2.0) * h3, c0 = h3 - lit<S>(2.0) * h2 + h, c1 = h3 - h2;
    const S d = lit<S>(6.0) * (h - h2), d0 = lit<S>(3.0) * h2 - lit<S>(4.0) * h + S(1),
            d1 = lit<S>(3.0) * h2 - lit<S>(2.0) * h;
    for (int i = 0; i < 6; ++i) {
      const S D = cur_(i) - prev_(i);
      r(i) = prev_(i) + c * D + period_s_ * (c0 * w0_(i) + c1 * v1_(i));
      // D / T bounded first, as target()'s (the fixed-point range).
      vr(i) = moving ? d * (stream::clamp(D, lit<S>(2.0)) * rate_) + d0 * w0_(i) + d1 * v1_(i) : S(0);
    }
    return r;
  }

  /// One tick of a stop of axis i: the jerk-limited change to rest (step_axis), or, once its speed is
  /// within kStopRestSpeed, the speed 0 and the acceleration ramped to 0 at the stop's jerk limit (the
  /// position no longer moves).
  void stop_axis(int i, S dt) {
    jerk_profile::Kin<S>& s = s_[i];
    if (math::abs(s.v) > lit<S>(kStopRestSpeed)) {
      stream::step_axis(s, lo_[i], S(0), stop_[i].a, stop_[i].j, dt);
      return;
    }
    const S step = stop_[i].j * dt;
    s.v = S(0);
    s.a = math::abs(s.a) <= step ? S(0) : (s.a > S(0) ? S(s.a - step) : S(s.a + step));
  }

  JerkLimits<S> lim_[6]{}, stop_[6]{};
  S inv_a_[2]{}, inv_j_[2]{}, ramp_[2]{};  ///< per group: 1 / a, 1 / j, a / j of its axes' limits (stop_lead)
  jerk_profile::Kin<S> s_[6]{};
  S lo_[6]{};  ///< the positions' residuals below their resolution (step_axis)
  Vec6<S> prev_ = Vec6<S>::Zero(), cur_ = Vec6<S>::Zero();
  // A sample with velocity: the sample itself, its velocity (cur_ = sample_ + v1_ T), the target's
  // velocity when it came.
  Vec6<S> sample_ = Vec6<S>::Zero(), v1_ = Vec6<S>::Zero(), w0_ = Vec6<S>::Zero();
  S rate_ = S(0);      ///< samples per second (start())
  S period_s_ = S(0);  ///< T [s]
  std::uint32_t period_ = 1, timeout_ = 20, since_ = 0;
  bool ended_ = false, stopping_ = false, with_velocity_ = false;
};

}  // namespace osc
