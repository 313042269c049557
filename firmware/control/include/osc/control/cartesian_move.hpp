// A point-to-point move of the operational point (the wrist centre) and of the orientation: the
// position along the straight line from start to target, the orientation about the one axis that
// turns the start orientation into the target's, each a jerk-limited profile (jerk_profile.hpp) of
// one scalar (the distance s along the line, the angle psi about the axis), the two
// time-synchronised: the faster is stretched to the slower's duration (plan_with_duration), so both
// start and end together and each stays within its limits.
//
//   p(t) = p0 + u s(t),                  u = (p1 - p0) / |p1 - p0|
//   R(t) = Rot(k, psi(t)) R0,            Rot(k, Psi) = R1 R0^T
// and, in the controller's coordinates x = [p; phi] (phi: roll, pitch, yaw of R R_ref^T,
// kinematics.hpp), with the base angular velocity w = k psi_dot:
//   phi_dot = E^{-1}(phi) w,   phi_ddot = E^{-1}(phi) (k psi_ddot - Edot(phi, phi_dot) phi_dot).
// Linear speed |p_dot| = |s_dot| and angular speed |w| = |psi_dot|: the profile's limits are those of
// the Cartesian reference itself.
//
// A stop (stop()) replaces both profiles by their hardest stops from the state they have reached:
// the reference decelerates along the same line and about the same axis, within the same limits,
// and comes to rest where it can (IEC 60204-1 category 2).
//
// Allocation-free, templated on the scalar; planning (plan, stop) runs when a command is accepted,
// at() every tick.
#pragma once

#include <type_traits>

#include "osc/control/jerk_profile.hpp"
#include "osc/control/trajectory.hpp"  // Desired
#include "osc/kernels/kinematics.hpp"

namespace osc {

/// A pose of the operational point: position [m] and orientation, both in the base frame.
template <class S>
struct Pose {
  Vec3<S> p;
  Mat3<S> R;
};

/// The limits of a move: translation (|p_dot|, |p_ddot|, |p_dddot|) and rotation about its axis.
template <class S>
struct CartesianLimits {
  JerkLimits<S> linear, angular;

  /// The configured maxima (params::kMoveLinear, kMoveAngular).
  static CartesianLimits defaults() {
    return {{lit<S>(params::kMoveLinear[0]), lit<S>(params::kMoveLinear[1]), lit<S>(params::kMoveLinear[2])},
            {lit<S>(params::kMoveAngular[0]), lit<S>(params::kMoveAngular[1]), lit<S>(params::kMoveAngular[2])}};
  }
  /// Every limit positive and at most max's.
  bool within(const CartesianLimits& max) const {
    auto in = [](const JerkLimits<S>& l, const JerkLimits<S>& m) {
      return l.v > S(0) && l.a > S(0) && l.j > S(0) && !(l.v > m.v) && !(l.a > m.a) && !(l.j > m.j);
    };
    return in(linear, max.linear) && in(angular, max.angular);
  }
};

/// The limits a plan uses: the asked ones less a margin for the scalar's rounding of the reference
/// it produces, so that the reference, as evaluated and differenced tick by tick, stays within the
/// asked ones. Measured excess without it (tests/firmware/control/test_motion.cpp, the motion tour):
/// float 2e-4 of the jerk limit; Q12.19 3e-3 of the jerk, 2e-5 of v and a (a few resolution steps
/// of the acceleration over one tick).
template <class S>
JerkLimits<S> rounding_margin(const JerkLimits<S>& l) {
  if constexpr (fixed::is_q_v<S>)
    return {l.v * lit<S>(0.999), l.a * lit<S>(0.999), l.j * lit<S>(0.98)};
  else if constexpr (std::is_same_v<S, float>)
    return {l.v * lit<S>(0.9999), l.a * lit<S>(0.9999), l.j * lit<S>(0.998)};
  else
    return l;
}

/// Rot(k, angle): the rotation by `angle` about the unit axis k (Rodrigues).
template <class S>
Mat3<S> axis_rotation(const Vec3<S>& k, S angle) {
  S s, c;
  math::sincos(angle, s, c);
  Mat3<S> K;
  K << S(0), -k(2), k(1), k(2), S(0), -k(0), -k(1), k(0), S(0);
  return Mat3<S>::Identity() + s * K + (S(1) - c) * (K * K);
}

/// The rotation R = Rz(yaw) Ry(pitch) Rx(roll) (the convention of the orientation coordinates), its
/// nine entries in closed form (a third of the instructions of the three rotations' product).
template <class S>
Mat3<S> rpy_rotation(const Vec3<S>& rpy) {
  S sr, cr, sp, cp, sy, cy;
  math::sincos(rpy(0), sr, cr);
  math::sincos(rpy(1), sp, cp);
  math::sincos(rpy(2), sy, cy);
  const S spsr = sp * sr, spcr = sp * cr;
  Mat3<S> R;
  R << cy * cp, cy * spsr - sy * cr, cy * spcr + sy * sr,  //
      sy * cp, sy * spsr + cy * cr, sy * spcr - cy * sr,   //
      -sp, cp * sr, cp * cr;
  return R;
}

/// The axis k and angle in [0, pi) of the rotation Rd (Rd = Rot(k, angle)); k = x and angle 0 for
/// a rotation too small to name an axis (below 5e-7 rad, in fixed point 5e-5 rad). Angles near pi have no
/// well-conditioned axis from this formula: callers refuse rotations beyond kMaxMoveRotation.
template <class S>
void rotation_axis_angle(const Mat3<S>& Rd, Vec3<S>& k, S& angle) {
  const Vec3<S> v(Rd(2, 1) - Rd(1, 2), Rd(0, 2) - Rd(2, 0), Rd(1, 0) - Rd(0, 1));  // 2 sin(angle) k
  const S n = math::sqrt(v.dot(v));
  const S c = Rd(0, 0) + Rd(1, 1) + Rd(2, 2) - S(1);  // 2 cos(angle)
  // Below the scalar's rounding of R1 R0^T (Q12.19: a few 1e-6 per entry) there is no axis to name.
  if (!(n > lit<S>(fixed::is_q_v<S> ? 1e-4 : 1e-6))) {
    k = Vec3<S>::UnitX();
    angle = S(0);
    return;
  }
  k = v / n;
  angle = math::atan2(n, c);
}

/// The largest rotation a move may make [rad] (170 deg: the axis of a half turn is ill-conditioned).
constexpr double kMaxMoveRotation = 170.0 * kPi / 180.0;

template <class S>
class CartesianMove {
 public:
  /// Plans the move from `from` to `to`, both at rest, under `lim`; R_ref is the controller's
  /// reference orientation (its coordinates phi). kBadTarget for a rotation beyond
  /// kMaxMoveRotation or a non-finite pose.
  ProfileStatus plan(const Pose<S>& from, const Pose<S>& to, const CartesianLimits<S>& lim, const Mat3<S>& R_ref) {
    if (!math::all_finite(to.p) || !math::all_finite(to.R)) return ProfileStatus::kBadTarget;
    p0_ = from.p;
    R0_ = from.R;
    R_ref_ = R_ref;
    const Vec3<S> dp = to.p - from.p;
    const S length = math::sqrt(dp.dot(dp));
    u_ = length > S(0) ? Vec3<S>(dp / length) : Vec3<S>(Vec3<S>::UnitX());
    S angle;
    rotation_axis_angle<S>(Mat3<S>(to.R * from.R.transpose()), k_, angle);
    if (!(angle <= lit<S>(kMaxMoveRotation))) return ProfileStatus::kBadTarget;
    const JerkLimits<S> lin = rounding_margin(lim.linear), ang = rounding_margin(lim.angular);
    ProfileStatus st = s_.plan(S(0), S(0), S(0), length, lin);
    if (st == ProfileStatus::kOk) st = psi_.plan(S(0), S(0), S(0), angle, ang);
    if (st != ProfileStatus::kOk) return st;
    // Stretch the faster to the slower's duration (from rest: its time-scaled shape).
    if (s_.duration() < psi_.duration())
      st = s_.plan_with_duration(S(0), S(0), S(0), length, lin, psi_.duration());
    else if (psi_.duration() < s_.duration())
      st = psi_.plan_with_duration(S(0), S(0), S(0), angle, ang, s_.duration());
    rotates_ = angle > S(0);
    phi_rest_ = orientation_coordinates<S>(R0_, R_ref_);
    return st;
  }

  /// Replaces the move by its category-2 stop from the state at time t: each profile's hardest stop
  /// (JerkProfile::plan_stop, which plans one from any finite state: a state at the move's cruise
  /// speed may lie beyond the limit by a rounding), along the same line and about the same axis. Time
  /// restarts at 0.
  void stop(S t, const CartesianLimits<S>& lim) {
    const ProfileState<S> s = s_.at(t), a = psi_.at(t);
    s_.plan_stop(s.p, s.v, s.a, rounding_margin(lim.linear));
    psi_.plan_stop(a.p, a.v, a.a, rounding_margin(lim.angular));
  }

  /// The desired state at time t since the start (or since the stop): before 0 the start, after
  /// duration() the end at rest.
  Desired<S> at(S t) const {
    const ProfileState<S> s = s_.at(t);
    Desired<S> d;
    d.x.template head<3>() = p0_ + u_ * s.p;
    d.xd.template head<3>() = u_ * s.v;
    d.xdd.template head<3>() = u_ * s.a;
    if (!rotates_) {
      d.x.template tail<3>() = phi_rest_;
      d.xd.template tail<3>().setZero();
      d.xdd.template tail<3>().setZero();
      return d;
    }
    const ProfileState<S> a = psi_.at(t);
    const Vec3<S> phi = orientation_coordinates<S>(Mat3<S>(axis_rotation<S>(k_, a.p) * R0_), R_ref_);
    const PhiRate<S> E = phi_rate(phi);
    const Vec3<S> phid = E.Einv * (k_ * a.v);
    d.x.template tail<3>() = phi;
    d.xd.template tail<3>() = phid;
    d.xdd.template tail<3>() = E.Einv * (k_ * a.a - edot_rates(E, phid));
    return d;
  }

  /// The pose at time t (as at(t), before 0 the start, after duration() the end): the position and
  /// the rotation Rot(k, psi(t)) R0 themselves, without the orientation coordinates (the path check,
  /// path_check.hpp, follows these).
  Pose<S> pose_at(S t) const { return {p0_ + u_ * s_.at(t).p, axis_rotation<S>(k_, psi_.at(t).p) * R0_}; }
  /// The pose at rest at the end (after a stop: where the stop ends).
  Pose<S> end() const { return {p0_ + u_ * s_.target(), axis_rotation<S>(k_, psi_.target()) * R0_}; }
  S duration() const { return s_.duration() > psi_.duration() ? s_.duration() : psi_.duration(); }
  const JerkProfile<S>& linear() const { return s_; }
  const JerkProfile<S>& angular() const { return psi_; }
  const Vec3<S>& direction() const { return u_; }
  const Vec3<S>& axis() const { return k_; }

 private:
  Vec3<S> p0_ = Vec3<S>::Zero(), u_ = Vec3<S>::UnitX(), k_ = Vec3<S>::UnitX(), phi_rest_ = Vec3<S>::Zero();
  Mat3<S> R0_ = Mat3<S>::Identity(), R_ref_ = Mat3<S>::Identity();
  JerkProfile<S> s_, psi_;
  bool rotates_ = false;
};

}  // namespace osc
