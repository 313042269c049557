// The excitation motion's check and preparation (osc/control/excitation.hpp, which includes this header at its end;
// its file comment's "Fitting the design" and "The check"): check_excitation samples every tick of a period against
// the limits, the singularity test and the loop's, and prepare_excitation plans the motion and checks it at the
// largest scale that passes.
#pragma once

#include <cstdint>

#include "osc/control/excitation.hpp"

namespace osc {

/// What check_excitation found.
template <class S>
struct ExcitationCheck {
  ExcitationStatus status = ExcitationStatus::kOk;
  /// The first failing tick of the period (0 .. P), -1 when kOk or when the plan refused.
  std::int32_t tick = -1;
  /// The joint that failed (-1: none, or the singularity test).
  int joint = -1;
  /// The gains' scale the motion was checked at (prepare_excitation).
  S scale = S(1);
  /// How many whole or partial checks prepare_excitation made (1 for check_excitation alone).
  std::uint8_t checks = 1;
  /// Over the ticks checked: each joint's largest |qd| [rad/s] and |tau| + |tau_f| [N m], the smallest
  /// room of a joint to its nearer bound of [q_min, q_max] (the limits less the margin) [rad], the smallest
  /// reciprocal condition of the Jacobian.
  Vec6<S> speed = Vec6<S>::Zero(), torque = Vec6<S>::Zero();
  S clearance = lit<S>(path_check::kNoClearance);
  S rcond = S(1);
};

namespace excitation {
/// The joint-limit and speed tests of a sample; r's extremes updated.
template <class S>
ExcitationStatus kinematic_limits(const JointSample<S>& d, const ExcitationLimits<S>& lim, ExcitationCheck<S>& r) {
  for (int i = 0; i < kDof; ++i) {
    const S lo = d.q(i) - lim.q_min(i), hi = lim.q_max(i) - d.q(i), c = lo < hi ? lo : hi;
    if (c < r.clearance) r.clearance = c;
    if (math::abs(d.qd(i)) > r.speed(i)) r.speed(i) = math::abs(d.qd(i));
    if (!(lo >= S(0) && hi >= S(0))) {
      r.joint = i;
      return ExcitationStatus::kOutOfWorkspace;
    }
  }
  for (int i = 0; i < kDof; ++i)
    if (!(math::abs(d.qd(i)) <= lim.speed(i))) {
      r.joint = i;
      return ExcitationStatus::kOverLimit;
    }
  return ExcitationStatus::kOk;
}

/// The torque test of a sample (data: forward kinematics at d.q): the rigid-body torque of (1) by rnea
/// and the strongest friction's (the drives', model.drives), each joint's magnitudes summed; r's extremes updated.
template <class S>
ExcitationStatus torque_limits(const Model<S>& model, const Data<S>& data, const JointSample<S>& d,
                               const ExcitationLimits<S>& lim, ExcitationCheck<S>& r) {
  const Vec6<S> tau = rnea(model, data, d.qd, d.qdd, true).tau;
  // Each motor's friction at its rate, to the joints through C^-T (DriveCoupling: the identity on an uncoupled arm).
  const Vec6<S> tau_f =
      joint_torques_of_motors(model.drives, friction_torque(lim.friction, motor_rates(model.drives, d.qd)));
  int over = -1;
  for (int i = 0; i < kDof; ++i) {
    const S need = math::abs(tau(i)) + math::abs(tau_f(i));
    if (need > r.torque(i)) r.torque(i) = need;
    if (over < 0 && !(need <= lim.torque(i))) over = i;
  }
  if (over < 0) return ExcitationStatus::kOk;
  r.joint = over;
  return ExcitationStatus::kOverLimit;
}
}  // namespace excitation

/// Checks every tick of `motion` (the file comment's "The check"); R_ref is the controller's reference
/// orientation, data the kernels' workspace (overwritten). The first failure stops it.
/// loop: the gains' sampled-loop test at every tick (loop::path_loop, as a move's path check; none: not
/// judged): an axis whose loop is unstable there fails it (kUnstableLoop), unless it was so at q0 already
/// and is no lighter (path_check::unstable_loop).
template <class S>
ExcitationCheck<S> check_excitation(const Model<S>& model, Data<S>& data, const ExcitationMotion<S>& motion,
                                    const Mat3<S>& R_ref, const ExcitationLimits<S>& lim,
                                    const loop::PathLoop* loop = nullptr) {
  const std::uint32_t before = math::take_arithmetic_flags<S>();  // the caller's, put back on return
  ExcitationCheck<S> r;
  r.scale = motion.scale();
  path_check::SingularityTrace<S> trace;
  PathCheck<S> singular;  // near_singular's smallest rcond
  ArmJacobianFactor<S> Jf;
  path_check::LoopTrace loop_trace;
  for (std::uint32_t n = 0; n <= excitation::kPeriodTicks; ++n) {
    const JointSample<S> d = motion.at_tick(n);
    ExcitationStatus s = excitation::kinematic_limits(d, lim, r);
    if (s == ExcitationStatus::kOk) {
      path_check::evaluate(model, data, Jf, d.q);
      if (path_check::near_singular(data, Jf, R_ref, trace, singular)) s = ExcitationStatus::kNearSingular;
    }
    if (s == ExcitationStatus::kOk && loop && path_check::unstable_loop(model, data, R_ref, *loop, loop_trace))
      s = ExcitationStatus::kUnstableLoop;
    if (s == ExcitationStatus::kOk) s = excitation::torque_limits(model, data, d, lim, r);
    if (s != ExcitationStatus::kOk) {
      r.status = s;
      r.tick = static_cast<std::int32_t>(n);
      break;
    }
  }
  r.rcond = singular.rcond;
  math::restore_arithmetic_flags<S>(before);  // the check's own discarded
  return r;
}

/// Plans the motion about q0 (the arm at rest there) and checks it at the largest scale that passes (the file
/// comment's "Fitting the design"): kOk with the motion to run at it, or the plan's refusal, or the last check's.
template <class S>
ExcitationCheck<S> prepare_excitation(const Model<S>& model, Data<S>& data, const Vec6<S>& q0, const Mat3<S>& R_ref,
                                      const ExcitationLimits<S>& lim, ExcitationMotion<S>& motion,
                                      const loop::PathLoop* loop = nullptr) {
  ExcitationCheck<S> r;
  r.status = motion.plan(q0, lim);
  if (r.status != ExcitationStatus::kOk) {
    r.joint = motion.refused_joint();
    return r;
  }
  motion.set_scale(S(1));
  r = check_excitation(model, data, motion, R_ref, lim, loop);
  if (r.status == ExcitationStatus::kOk) return r;
  std::uint8_t checks = 1;
  int lo = 1, hi = excitation::kAttempts - 1, best = -1;
  ExcitationCheck<S> passed;
  while (lo <= hi) {  // the smallest try in [lo, hi] that passes: the largest scale
    const int mid = (lo + hi) / 2;
    motion.set_scale(excitation::scale_of<S>(mid));
    r = check_excitation(model, data, motion, R_ref, lim, loop);
    ++checks;
    if (r.status == ExcitationStatus::kOk) {
      best = mid, passed = r, hi = mid - 1;
    } else {
      lo = mid + 1;
    }
  }
  if (best >= 0) {
    motion.set_scale(excitation::scale_of<S>(best));
    r = passed;
  }
  r.checks = checks;
  return r;
}

}  // namespace osc
