// A one-dimensional, jerk-limited, time-optimal motion profile: from any start state (p0, v0, a0)
// within the limits to a target position reached at rest (v = a = 0), under |v| <= vmax,
// |a| <= amax, |j| <= jmax. Allocation-free, templated on the scalar (double, float, osc::Fixed).
//
// Planning (JerkProfile::plan, plan_with_duration) runs when a command is accepted: closed forms
// and bisections of a fixed iteration count, so its cost is bounded. Evaluation (JerkProfile::at)
// runs every tick: a search over at most 7 segments and one cubic in the segment's local time.
//
// The shape (the UDDU profile of Ruckig, Berscheid and Kroeger 2021; Haschke, Weitnauer and Ritter
// 2008 for a target at rest). By Pontryagin's principle a time-optimal jerk is bang-bang (+-jmax)
// except on arcs where a constraint holds (|a| = amax, or a = 0 at |v| = vmax), and between two such
// arcs it switches at most twice. Moving towards the target (direction d = +1; d = -1 is the mirror:
// every p, v, a, j negated), the profile is
//   1 jerk +j    a rises from a0 (the velocity change towards the peak, "accelerate")
//   2 jerk 0     a = +amax held       (only if amax is reached)
//   3 jerk -j    a falls to 0 at the peak velocity vp
//   4 jerk 0     cruise at vp = vmax  (only if vmax is reached)
//   5 jerk -j    a falls to -ap       (the velocity change from vp to 0, "brake")
//   6 jerk 0     a = -amax held       (only if amax is reached)
//   7 jerk +j    a rises to 0 as v reaches 0, at the target
// Segments 1-3 and 5-7 are each the time-optimal change of velocity to a state with a = 0
// (velocity_change below). With a moving start, a segment may be empty, 1 may have jerk -j (the
// peak below the velocity the start coasts to), and when the target lies so close that the profile
// brakes all the way (the velocity falls monotonically from v0 to 0) 3 and 5 merge and segment 1
// only relaxes a0 < 0 part of the way: "+j for t1, then the hardest stop", family F1 below.
//
// Which way (d): the hardest stop from the start (velocity_change to v = 0) ends at p_stop, the
// nearest place where the axis can be at rest. A target at or beyond p_stop is approached with
// d = sign(pT - p_stop) = +1; a target behind it (a re-targeted move, or a target that the stopping
// distance overshoots) gets d = -1: the profile brakes through v = 0 and comes back.
//
// A start whose acceleration would carry the velocity past vmax even when a0 is ramped to 0 at once
// (v0 + a0 |a0| / (2 jmax) > vmax: the limit cannot be kept) first ramps a at -j (holding -amax if
// it must) until a ramp back to a = 0 ends exactly at vmax: the least excess over vmax. These two
// segments come before the seven; the segments that follow then start at a = -amax or continue
// the same ramp and merge, so the profile still has at most 7 non-empty segments (the tests count).
#pragma once

#include <cstdint>
#include <type_traits>

#include "osc/math/scalar.hpp"

namespace osc {

/// Why a plan was refused (the caller refuses the command).
enum class ProfileStatus : std::uint8_t {
  kOk = 0,
  kBadLimits,           ///< a limit not positive (or NaN)
  kBadStart,            ///< |v0| > vmax or |a0| > amax (or NaN)
  kBadTarget,           ///< a NaN target or duration
  kDurationTooShort,    ///< plan_with_duration: T below the minimum time
  kDurationUnreachable  ///< plan_with_duration: T beyond the slowest profile of the method
};

/// The limits of one axis: |v| <= v, |a| <= a, |j| <= j, all > 0.
template <class S>
struct JerkLimits {
  S v, a, j;
};

/// A state on the profile: position, velocity, acceleration, and the jerk acting from there.
template <class S>
struct ProfileState {
  S p, v, a, j;
};

/// One constant-jerk segment: it starts at time t0 in state (p, v, a) and lasts duration.
template <class S>
struct JerkSegment {
  S t0, duration, jerk, p, v, a;
};

namespace jerk_profile {
/// Bisection steps: enough to narrow an interval to the scalar's resolution.
template <class S>
constexpr int kBisections = fixed::is_q_v<S> ? 32 : (std::is_same_v<S, float> ? 26 : 56);

template <class S>
struct Kin {
  S p, v, a;
};

/// The state after time t at constant jerk: the exact cubic, in Horner form from the segment's
/// own start (the rounding stays that of the local time, whatever the time since the start).
template <class S>
[[gnu::always_inline]] inline Kin<S> advance(const Kin<S>& s, S jerk, S t) {
  const S half = lit<S>(0.5);
  const S j6 = jerk * lit<S>(1.0 / 6.0);
  return {s.p + t * (s.v + t * (s.a * half + t * j6)), s.v + t * (s.a + t * (jerk * half)), s.a + t * jerk};
}

/// The velocity at which the axis coasts out when its acceleration a is ramped to 0 at full jerk
/// j: v + a |a| / (2 j).
template <class S>
S coast_velocity(S v, S a, S j) {
  return v + a * math::abs(a) / (lit<S>(2) * j);
}

/// The time-optimal change from (v, a) to (vt, 0): jerk sign j for t1, 0 for t2 (at a = sign amax),
/// -sign j for t3. sign = +1 when vt lies above the coast velocity (the acceleration must rise
/// first), else -1. In the frame of sign = +1 (dv = sign (vt - v), b = sign a), the peak ap of a
/// ramp up from b and down to 0 changes the velocity by (ap^2 - b^2)/(2j) + ap^2/(2j) = dv, so
///   ap = sqrt(j dv + b^2 / 2);
/// beyond amax the peak is held for t2 = (dv - (amax^2 - b^2/2) / j) / amax. t1 = (ap - b) / j,
/// t3 = ap / j (Haschke et al. 2008, eqs. 6-8).
template <class S>
struct VelocityChange {
  S sign, t1, t2, t3;
};
template <class S>
VelocityChange<S> velocity_change(S v, S a, S vt, S amax, S j) {
  const S zero(0);
  const S sign = vt >= coast_velocity(v, a, j) ? S(1) : S(-1);
  const S dv = sign * (vt - v), b = sign * a, half_b2 = lit<S>(0.5) * b * b;
  const S ap2 = j * dv + half_b2;
  const S ap = ap2 > amax * amax ? amax : (ap2 > zero ? math::sqrt(ap2) : zero);
  const S t1 = ap > b ? (ap - b) / j : zero;  // rounding may leave ap a hair below b
  const S t3 = ap / j;
  if (!(ap2 > amax * amax)) return {sign, t1, zero, t3};
  // The hold: what the two ramps of the rounded durations leave of dv (in exact arithmetic
  // (ap^2 - b^2)/(2j) and ap^2/(2j)), the hold and the ramp down at exactly amax (hold_acceleration).
  // So the velocity reached is right to the rounding of the hold (in fixed point the ramps'
  // durations round to 2^-19 s, which at 100 m/s^3 would otherwise leave a cruise 1e-5 m/s off).
  const S half = lit<S>(0.5);
  const S t2 = (dv - t1 * (b + j * t1 * half) - t3 * (amax - j * t3 * half)) / amax;
  return {sign, t1, t2 > zero ? t2 : zero, t3};
}

/// The acceleration of a zero-jerk segment: in exact arithmetic one of -amax (a hold), 0 (a cruise)
/// and +amax, so the nearest of them. The ramps before it end there only to the rounding of their
/// durations (in fixed point 2^-19 s, at 100 m/s^3 an acceleration 1e-4 m/s^2 off, which over a 1 s
/// cruise would become 5e-5 m); the jump this leaves in a is that rounding.
template <class S>
S hold_acceleration(S a, S amax) {
  const S half = lit<S>(0.5) * amax;
  return a > half ? amax : (a < -half ? -amax : S(0));
}

/// A profile under construction: (jerk, duration) pieces, at most pre-phase 2 + 7; amax, the
/// acceleration of its holds.
template <class S>
struct Pieces {
  static constexpr int kCapacity = 9;
  S amax;
  S jerk[kCapacity];
  S t[kCapacity];
  int n = 0;
  explicit Pieces(S amax_) : amax(amax_) {}
  void add(S jerk_, S t_) {
    jerk[n] = jerk_;
    t[n] = t_;
    ++n;
  }
  void add(const VelocityChange<S>& c, S j) {
    add(c.sign * j, c.t1);
    add(S(0), c.t2);
    add(-(c.sign * j), c.t3);
  }
  Kin<S> end(Kin<S> s) const {
    for (int i = 0; i < n; ++i) {
      if (jerk[i] == S(0) && t[i] > S(0)) s.a = hold_acceleration(s.a, amax);
      s = advance(s, jerk[i], t[i]);
    }
    return s;
  }
  S duration() const {
    S sum(0);
    for (int i = 0; i < n; ++i) sum += t[i];
    return sum;
  }
};

/// The largest x in [lo, hi] with too_far(x) false (too_far monotone; too_far(lo) is taken false),
/// by a fixed number of halvings.
template <class S, class F>
S bisect(S lo, S hi, F too_far) {
  for (int k = 0; k < kBisections<S>; ++k) {
    const S mid = lo + (hi - lo) * lit<S>(0.5);
    if (too_far(mid))
      hi = mid;
    else
      lo = mid;
  }
  return lo;
}

/// The main profile in the frame of d = +1 (x from the start, u = d v, b = d a), from a state
/// whose coast velocity is within vlim, to x_target at or beyond the hardest stop. Three families,
/// in order of the distance they cover (each continuous and increasing in its parameter, and each
/// ending where the next begins):
///   F1 (u_c > 0 and b < 0 only): +j for t1 in [0, -b/j], then the hardest stop: a0 < 0 is relaxed
///      part of the way. t1 = 0 is the hardest stop; t1 = -b/j reaches a = 0 at u_c and is F2(u_c).
///   F2: velocity_change to (vp, 0), then velocity_change to (0, 0), for vp in [max(u_c, 0), vlim];
///      vp = max(u_c, 0) is the hardest stop (u_c <= 0) or F1's end (u_c > 0).
///   F3: F2(vlim) with a cruise at vlim for tc = (x_target - F2(vlim)) / vlim inserted.
/// F1 and F2 are solved by bisection on t1 or vp (the distance of F2 is a quartic in vp without a
/// cruise, Haschke et al. sec. III; a bisection of fixed count is simpler and as exact).
/// at_limit: the pre-phase has left the coast velocity at vlim (u_c = vlim, b <= 0); then the only
/// peak is vlim, reached by the ramp of b to 0 (computed from the rounded state instead, a
/// difference of rounding between u_c and vlim would become a peak sqrt(j ulp): two needless ramps).
template <class S>
Pieces<S> main_profile(S u, S b, S x_target, S vlim, S amax, S j, bool at_limit) {
  const S zero(0);
  const Kin<S> s0{zero, u, b};
  auto f2 = [&](S vp, S tc) {
    Pieces<S> f(amax);
    f.add(at_limit ? VelocityChange<S>{S(1), -b / j, zero, zero} : velocity_change(u, b, vp, amax, j), j);
    f.add(zero, tc);
    f.add(velocity_change(vp, zero, zero, amax, j), j);
    return f;
  };
  auto f1 = [&](S t1) {
    Pieces<S> f(amax);
    f.add(j, t1);
    const Kin<S> s1 = advance(s0, j, t1);
    f.add(velocity_change(s1.v, s1.a, zero, amax, j), j);
    return f;
  };
  const S uc = coast_velocity(u, b, j);
  S vlow = uc > zero ? uc : zero;
  if (vlow > vlim || at_limit) vlow = vlim;
  const Pieces<S> top = f2(vlim, zero);
  const S x_top = top.end(s0).p;
  if (x_target >= x_top) return f2(vlim, (x_target - x_top) / vlim);  // F3: cruise at vlim
  if (uc > zero && b < zero && x_target < f2(vlow, zero).end(s0).p)   // F1
    return f1(bisect(zero, -b / j, [&](S t1) { return f1(t1).end(s0).p > x_target; }));
  return f2(bisect(vlow, vlim, [&](S vp) { return f2(vp, zero).end(s0).p > x_target; }), zero);  // F2
}

/// The whole time-optimal profile under the velocity limit vlim (the start's |v0| may exceed it:
/// plan_with_duration lowers vlim below |v0|), in the real frame.
template <class S>
Pieces<S> plan_pieces(const Kin<S>& start, S target, S vlim, S amax, S j) {
  const S zero(0);
  Pieces<S> out(amax);
  Kin<S> s = start;
  // The pre-phase: if a0 carries the velocity past vlim, ramp towards -sign(a) amax until the
  // coast velocity is +-vlim (the first two segments of velocity_change to (+-vlim, 0)).
  const S vc = coast_velocity(s.v, s.a, j);
  const bool pre = vc > vlim || vc < -vlim;
  if (pre) {
    const VelocityChange<S> c = velocity_change(s.v, s.a, vc > zero ? vlim : -vlim, amax, j);
    out.add(c.sign * j, c.t1);
    out.add(zero, c.t2);
    s = out.end(s);
    if (c.t2 > zero) s.a = c.sign * amax;  // exactly at the limit, so that the hold continues unbroken
  }
  // The direction: towards the target from the hardest stop's end.
  Pieces<S> stop(amax);
  stop.add(velocity_change(s.v, s.a, zero, amax, j), j);
  const S d = target >= stop.end(s).p ? S(1) : S(-1);
  const Pieces<S> m = main_profile(d * s.v, d * s.a, d * (target - s.p), vlim, amax, j, pre && d * vc > zero);
  for (int i = 0; i < m.n; ++i) out.add(d * m.jerk[i], m.t[i]);
  return out;
}
}  // namespace jerk_profile

/// A planned profile: at most 7 non-empty constant-jerk segments (storage for 9, see the header
/// comment), each with its start state, evaluated in its own local time.
template <class S>
class JerkProfile {
 public:
  static constexpr int kMaxSegments = jerk_profile::Pieces<S>::kCapacity;

  /// The time-optimal profile from (p0, v0, a0) to `target` at rest. On a status other than kOk the
  /// profile is left as it was.
  ProfileStatus plan(S p0, S v0, S a0, S target, const JerkLimits<S>& lim) {
    const ProfileStatus st = check(p0, v0, a0, target, lim);
    if (st != ProfileStatus::kOk) return st;
    assemble({p0, v0, a0}, target, jerk_profile::plan_pieces<S>({p0, v0, a0}, target, lim.v, lim.a, lim.j));
    return ProfileStatus::kOk;
  }

  /// The same move lasting exactly T >= the minimum time (translation and rotation of one move share
  /// one duration).
  /// - From rest (v0 = a0 = 0): the time-optimal profile scaled in time by k = T / Tmin: durations
  ///   times k, jerk / k^3 (v and a scale by 1/k and 1/k^2), so every limit holds and the path is
  ///   the same. Exact to the rounding of the durations.
  /// - Moving: the time-optimal profile under a lowered velocity limit c in [vmax / 2^s, vmax],
  ///   found by bisection: Tmin(c) is continuous, equal to Tmin at c = vmax and growing without
  ///   bound as c falls (a cruise at c). For c below the start's speed the profile first brakes to
  ///   c (the pre-phase). Exact to the bisection's resolution (the scalar's). T beyond Tmin(vmax /
  ///   2^s) (s = 8 in fixed point, where a slower crawl would leave the range of time; 20
  ///   otherwise), or any T > Tmin when the target is the hardest stop's end: kDurationUnreachable.
  ProfileStatus plan_with_duration(S p0, S v0, S a0, S target, const JerkLimits<S>& lim, S T) {
    using namespace jerk_profile;
    const ProfileStatus st = check(p0, v0, a0, target, lim);
    if (st != ProfileStatus::kOk) return st;
    if (!math::isfinite(T)) return ProfileStatus::kBadTarget;
    const Kin<S> start{p0, v0, a0};
    const Pieces<S> fastest = plan_pieces(start, target, lim.v, lim.a, lim.j);
    const S tmin = fastest.duration();
    if (T < tmin) return ProfileStatus::kDurationTooShort;
    if (v0 == S(0) && a0 == S(0)) {
      const S k = tmin > S(0) ? T / tmin : S(1);
      Pieces<S> scaled = fastest;
      // jerk / k^3 and amax / k^2 one division at a time: k^3 leaves a fixed-point range (Q12.19:
      // k > 16) where every quotient stays within it.
      for (int i = 0; i < scaled.n; ++i) scaled.t[i] = scaled.t[i] * k, scaled.jerk[i] = scaled.jerk[i] / k / k / k;
      scaled.amax = scaled.amax / k / k;
      assemble(start, target, scaled);
      return ProfileStatus::kOk;
    }
    auto duration_at = [&](S c) { return plan_pieces(start, target, c, lim.a, lim.j).duration(); };
    const S c_min = lim.v * lit<S>(fixed::is_q_v<S> ? 1.0 / 256 : 1.0 / (1 << 20));
    if (duration_at(c_min) < T) return ProfileStatus::kDurationUnreachable;
    // The largest c with Tmin(c) >= T, i.e. the fastest profile that is not shorter than T.
    const S c = bisect(c_min, lim.v, [&](S cv) { return duration_at(cv) < T; });
    assemble(start, target, plan_pieces(start, target, c, lim.a, lim.j));
    return ProfileStatus::kOk;
  }

  /// The hardest stop from (p0, v0, a0): the time-optimal change to v = a = 0 at full jerk, wherever
  /// it comes to rest (a category-2 stop along the axis). The target is where it ends. A stop is
  /// planned from any finite state: a speed beyond lim.v only slows (a profile evaluated at its cruise
  /// lies beyond its own limit by a rounding: float's 4e-9 m/s at 0.04 m/s), and an acceleration
  /// beyond lim.a is taken at lim.a. Only a non-finite start (kBadStart) or bad limits fail, leaving
  /// the profile as it was.
  ProfileStatus plan_stop(S p0, S v0, S a0, const JerkLimits<S>& lim) {
    const ProfileStatus st = check(p0, S(0), S(0), p0, lim);
    if (st != ProfileStatus::kOk) return st;
    if (!math::isfinite(v0) || !math::isfinite(a0)) return ProfileStatus::kBadStart;
    if (a0 > lim.a) a0 = lim.a;
    if (a0 < -lim.a) a0 = -lim.a;
    const jerk_profile::Kin<S> start{p0, v0, a0};
    jerk_profile::Pieces<S> stop(lim.a);
    stop.add(jerk_profile::velocity_change(v0, a0, S(0), lim.a, lim.j), lim.j);
    assemble(start, stop.end(start).p, stop);
    return ProfileStatus::kOk;
  }

  /// (p, v, a, j) at time t from the start: t < 0 the start, t beyond the end the target at rest.
  ProfileState<S> at(S t) const {
    if (!(t < duration_)) return {target_, S(0), S(0), S(0)};
    int i = 0;
    while (i + 1 < n_ && !(t < seg_[i + 1].t0)) ++i;
    const JerkSegment<S>& g = seg_[i];
    S tau = t - g.t0;
    if (tau < S(0)) tau = S(0);
    const jerk_profile::Kin<S> k = jerk_profile::advance<S>({g.p, g.v, g.a}, g.jerk, tau);
    return {k.p, k.v, k.a, g.jerk};
  }

  S duration() const { return duration_; }
  S target() const { return target_; }
  int segment_count() const { return n_; }
  const JerkSegment<S>& segment(int i) const { return seg_[i]; }

 private:
  static ProfileStatus check(S p0, S v0, S a0, S target, const JerkLimits<S>& lim) {
    const S zero(0);
    // Written so that a NaN fails each comparison.
    if (!(lim.v > zero) || !(lim.a > zero) || !(lim.j > zero) || !math::isfinite(lim.v) || !math::isfinite(lim.a) ||
        !math::isfinite(lim.j))
      return ProfileStatus::kBadLimits;
    if (!(math::abs(v0) <= lim.v) || !(math::abs(a0) <= lim.a) || !math::isfinite(p0)) return ProfileStatus::kBadStart;
    if (!math::isfinite(target)) return ProfileStatus::kBadTarget;
    return ProfileStatus::kOk;
  }

  /// The segments of `pieces` from `start`: empty pieces dropped, neighbours of equal jerk merged
  /// (one cubic), each segment's start state by the same cubic that at() evaluates.
  void assemble(const jerk_profile::Kin<S>& start, S target, const jerk_profile::Pieces<S>& pieces) {
    jerk_profile::Kin<S> s = start;
    S t(0);
    n_ = 0;
    for (int i = 0; i < pieces.n; ++i) {
      if (!(pieces.t[i] > S(0))) continue;
      if (n_ > 0 && seg_[n_ - 1].jerk == pieces.jerk[i]) {
        JerkSegment<S>& g = seg_[n_ - 1];
        g.duration += pieces.t[i];
      } else {
        if (n_ > 0)
          s = jerk_profile::advance<S>({seg_[n_ - 1].p, seg_[n_ - 1].v, seg_[n_ - 1].a}, seg_[n_ - 1].jerk,
                                       seg_[n_ - 1].duration);
        if (pieces.jerk[i] == S(0)) s.a = jerk_profile::hold_acceleration(s.a, pieces.amax);
        seg_[n_++] = {t, pieces.t[i], pieces.jerk[i], s.p, s.v, s.a};
      }
      t += pieces.t[i];
    }
    duration_ = t;
    target_ = target;
  }

  JerkSegment<S> seg_[kMaxSegments]{};
  int n_ = 0;
  S duration_{0};
  S target_{0};
};

}  // namespace osc
