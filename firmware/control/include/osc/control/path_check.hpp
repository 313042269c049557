// The path check of a point-to-point move (cartesian_move.hpp): before a move is accepted, whether
// the arm can follow it from where it is (or from where the move queued before it ends) on the same
// inverse-kinematics branch, with every joint inside its limits and the Jacobian well-conditioned.
//
// The path is sampled at params::kPathCheckPoints evenly spaced times t_i = i T / N, i = 0 .. N - 1
// (T the move's duration, N = kPathCheckPoints), and at its end (i = N). At each sample the joint
// angles q_i solving the pose (p_d, R_d) = move.pose_at(t_i) come from a few Newton steps that start
// from the previous sample's solution (the first from the seed q, the arm's current angles):
//   e = [p_d - p(q); 1/2 sum_c r_c(q) x r_d,c]       (r_c, r_d,c: the columns of R(q), R_d)
//   q <- q + J(q)^{-1} e                               (J the geometric Jacobian of the wrist centre)
// For R_d = Rot(k, theta) R(q) the orientation error is sin(theta) k, the rotation that J's angular
// rows map the joint rates to, so the step is Newton's for the pose (quadratic convergence, no
// orientation coordinates). J^{-1} is the arm's factor's (ArmJacobianFactor, osc/control/arm_opspace.hpp):
// two 3x3 inverses for an arm with a spherical wrist, a pivoted LU for any other; no 6x6 inverse. Each step is scaled
// down, if need be, so that no joint moves more than kMaxStep: a damped Newton where J is nearly singular. Starting
// every sample from the one before keeps the solution on the seed's branch (elbow up or down, wrist flipped or not, the
// seed's turn of each joint): there is no closed-form solution and no switch between branches, and the joint limits are
// those of the path the arm would actually follow.
//
// A sample fails, and the check stops there, in the order tested:
//   kUnreachable     the Newton steps left a residual above kPositionTolerance or
//                    kOrientationTolerance (or R more than 90 degrees from R_d): no solution on the
//                    seed's branch near the previous sample's. A pose beyond the arm's reach, or one
//                    past a fold of the branch, where the path touches a singular pose without
//                    crossing it and only another branch goes on (the shoulder singularity, the
//                    wrist centre passing next to joint 1's axis, is the usual one). Newton cannot
//                    tell the two apart without a global solution; the caller reports both as
//                    out_of_workspace.
//   kOutOfWorkspace  a joint closer than params::kWorkspaceMargin to one of its limits
//                    (robot::kArm.q_min, q_max), or beyond it; where the path starts so (an arm a
//                    stream's stop brought to rest at a limit), only where the joint comes closer to
//                    the limit than at the start: a path may leave a limit, not go towards it;
//   kNearSingular    the reciprocal condition that the controller tests (that of the analytic
//                    Jacobian in the orientation coordinates relative to R_ref, controller.hpp)
//                    below params::kPathMinRcond, or a singularity crossed since the sample before
//                    (below), or in fixed point a saturated result in the sample's arithmetic (a
//                    division by a near-zero determinant).
//   kUnstableLoop    (when the caller passes the gains' loop::PathLoop) the sampled closed loop of the
//                    observer and the controller at the task's gains (sampled_loop.hpp) is not stable
//                    at the sample's Lambda^-1 = J_a A^-1 J_a^T, its bounds times
//                    params::kPathLoopMargin: an axis so light there (J4's axis along J1's on a
//                    PUMA, q2 + q3 near -pi/2) that the damping's step, lambda (k_s + k_nd) dt,
//                    passes about 2 and the arm would oscillate from tick to tick. The same test
//                    that refuses a gain (param set: unstable_loop), at the path's poses. A path
//                    that starts where an axis's loop is judged unstable already (the arm stands
//                    there, held by its friction) may leave that region, not go deeper: that axis
//                    fails only where its bounds exceed the first sample's.
// Between two samples the joints move continuously along the branch. A singularity the path
// crosses there, with both samples' rcond above the threshold (joint 5 passing through 0 between
// two samples), changes the sign of the determinant of one of the Jacobian's blocks, J11 (arm) or
// J22 (wrist), or of det J for an arm without a spherical wrist, or turns the roll and yaw
// coordinates by pi (pitch passing +-90 degrees relative to R_ref): both are compared with the
// sample before. What a joint does between two samples the margin
// kWorkspaceMargin covers, and kPathMinRcond is ten times the controller's threshold.
//
// Cost, bounded: the iteration counts are fixed (kFirstIterations at the first sample,
// kIterations at each other), one forward kinematics, geometric Jacobian and factorisation each:
// kEvaluations = 1 + 6 + 16 x 4 = 71 of them per check, plus per sample (17) one pose on the path
// (pose_at), the orientation coordinates and the analytic Jacobian's factorisation, and with the loop's
// test one joint inertia, Lambda^-1 (an L D L^T of A and six solves) and loop::stable(). It runs when a
// move is accepted, not every tick.
//
// Allocation-free, templated on the scalar (double, float, osc::Fixed); the kernels' workspace Data
// is the caller's. In fixed point the check raises the sticky arithmetic flags of its thread of
// execution like any kernel (near a singularity a determinant's reciprocal saturates): it takes the
// flags raised before it on entry and gives them back on return, its own discarded, so that a
// control step after it sees only its own. (On a target where the control interrupt computes in
// fixed point too, the check must not run where that interrupt can preempt it: they share the flags.)
#pragma once

#include <array>
#include <cstdint>
#include <utility>

#include "osc/control/cartesian_move.hpp"
#include "osc/control/arm_opspace.hpp"
#include "osc/control/params.hpp"
#include "osc/control/sampled_loop.hpp"
#include "osc/robot.hpp"

namespace osc {

/// The outcome of a path check (the first failure met along the path).
enum class PathStatus : std::uint8_t {
  kOk = 0,
  kOutOfWorkspace,  ///< a joint within kWorkspaceMargin of a limit (or beyond)
  kNearSingular,    ///< the Jacobian's reciprocal condition below kPathMinRcond
  kUnreachable,     ///< Newton did not converge: no joint angles on the seed's branch reach the pose
  kUnstableLoop     ///< the gains would make the sampled closed loop unstable there (Lambda^-1's light axes)
};

namespace path_check {
/// The clearance reported when no sample reached the joint limit test: beyond any joint's range.
constexpr double kNoClearance = 2 * kPi;
}  // namespace path_check

/// What check_path found.
template <class S>
struct PathCheck {
  PathStatus status = PathStatus::kOk;
  /// The first failing sample: 0 the start, params::kPathCheckPoints the end; -1 when kOk.
  int sample = -1;
  /// The smallest distance of a joint to its nearer limit over the samples that reached the joint
  /// limit test [rad] (the margin not subtracted: kOutOfWorkspace when below kWorkspaceMargin).
  S clearance = lit<S>(path_check::kNoClearance);
  /// The smallest reciprocal condition over the samples that reached the Jacobian test (a
  /// singularity crossed between two samples fails the check whatever it is).
  S rcond = S(1);
  /// The largest residual left by the Newton steps over the samples: position [m] and orientation
  /// (|sin| of the angle) [rad], each the largest coordinate.
  S position_error = S(0), orientation_error = S(0);
  /// The joint angles at the end of the path (when not kOk: at the failing sample): the seed of the
  /// check of the move queued after this one.
  Vec6<S> q_end = Vec6<S>::Zero();
};

namespace path_check {

/// Newton steps at the first sample (from the seed, which may lie a tracking error away from the
/// move's start) and at every other (from the previous sample's solution).
constexpr int kFirstIterations = 6;
constexpr int kIterations = 4;
/// Forward kinematics with Jacobian per check.
constexpr int kEvaluations = 1 + kFirstIterations + params::kPathCheckPoints * kIterations;
/// The largest change of any joint in one Newton step [rad]; a longer step is scaled down to it.
constexpr double kMaxStep = 0.5;
/// The residual above which a sample is unreachable: position [m] and orientation [rad], each
/// coordinate, the same for every scalar. Far above what converged Newton steps leave (measured over
/// the tests' moves: double 1e-15, float 2.5e-7, Q12.19 7.6e-6, four of its resolutions), far below
/// what a pose out of reach leaves (its distance beyond the reach: centimetres at the first sample
/// past it, at 16 samples a path).
constexpr double kPositionTolerance = 1e-4;
constexpr double kOrientationTolerance = 1e-3;
/// How much closer to its limit than at the path's start a joint that starts within kWorkspaceMargin of it
/// may come [rad]: the Newton steps' residual (far below it) on a path that does not move the joint.
constexpr double kClearanceSlack = 1e-4;
/// The joint limits in the scalar (converted at compile time).
template <class S>
constexpr std::array<S, kDof> kQMin = lit_array<S>(robot::kArm.q_min);
template <class S>
constexpr std::array<S, kDof> kQMax = lit_array<S>(robot::kArm.q_max);

/// Fixed point: a saturated result since the check began (the check stops at the sample that
/// raised it); false for float and double.
template <class S>
bool saturated() {
  if constexpr (fixed::is_q_v<S>)
    return fixed::flags() != 0;
  else
    return false;
}

/// Forward kinematics and the geometric Jacobian at q, and the Jacobian's factors.
template <class S>
void evaluate(const Model<S>& model, Data<S>& data, ArmJacobianFactor<S>& Jf, const Vec6<S>& q) {
  forward_kinematics(model, data, q);
  geometric_jacobian(data);
  Jf.compute(data.J);
}

/// The error of the pose in data (forward_kinematics run) against the target:
/// [p_d - p; 1/2 sum_c r_c x r_d,c], the second sin(theta) k for R_d = Rot(k, theta) R. aligned:
/// trace(R^T R_d) = 1 + 2 cos(theta) > 1, so that a small sine is a small angle, not one near pi.
template <class S>
Vec6<S> pose_error(const Data<S>& data, const Pose<S>& target, bool& aligned) {
  const Mat3<S>& R = data.R[kDof];
  const Mat3<S>& Rd = target.R;
  Vec6<S> e;
  e.template head<3>() = target.p - data.o[kDof];
  e.template tail<3>() =
      lit<S>(0.5) * (cross(R.col(0), Rd.col(0)) + cross(R.col(1), Rd.col(1)) + cross(R.col(2), Rd.col(2)));
  const S trace = dot_sum<S>(R.col(0), Rd.col(0), R.col(1), Rd.col(1)) + R.col(2).dot(Rd.col(2));
  aligned = trace > S(1);
  return e;
}

/// q <- q + J^{-1} e, the step scaled down to kMaxStep in its largest joint.
template <class S>
void newton_step(const ArmJacobianFactor<S>& Jf, const Vec6<S>& e, Vec6<S>& q) {
  Vec6<S> dq = Jf.solve(e);
  const S longest = dq.cwiseAbs().maxCoeff();
  const S max_step = lit<S>(kMaxStep);
  if (longest > max_step) dq *= max_step / longest;
  q += dq;
}

/// What the joint-limit test of the first sample leaves for the others': each joint's clearance there.
template <class S>
struct ClearanceTrace {
  bool valid = false;  // the first sample was judged
  S start[kDof] = {};
};

/// The joint-limit test of a sample at its solution q: a joint closer than kWorkspaceMargin to one of its
/// limits (or beyond it) fails it, unless the path began there already (an arm a stream's category-2 stop
/// brought to rest at a limit, motion_limits_reached) and the joint is no closer than it was there, less
/// kClearanceSlack: a path may leave a limit, not go towards it. r.clearance updated.
template <class S>
bool out_of_workspace(const Vec6<S>& q, ClearanceTrace<S>& trace, PathCheck<S>& r) {
  const S margin = lit<S>(params::kWorkspaceMargin), slack = lit<S>(kClearanceSlack);
  bool fails = false;
  for (int i = 0; i < kDof; ++i) {
    const S lo = q(i) - kQMin<S>[i], hi = kQMax<S>[i] - q(i), c = lo < hi ? lo : hi;
    if (c < r.clearance) r.clearance = c;
    if (!trace.valid) {
      trace.start[i] = c;
    } else if (!(c >= margin) && !(trace.start[i] < margin && c >= trace.start[i] - slack)) {
      fails = true;
    }
  }
  trace.valid = true;
  return fails;
}

/// What the singularity test of a sample leaves for the next one's: the signs of the geometric
/// Jacobian's determinants (det_signs: each changes sign where the path crosses a singularity) and the
/// orientation coordinates (roll and yaw turn by pi where the path crosses their own singularity,
/// pitch = +-90 degrees).
template <class S>
struct SingularityTrace {
  bool valid = false;  // a sample came before
  bool arm_positive = false, wrist_positive = false;
  Vec3<S> phi = Vec3<S>::Zero();
};

/// det M, by a triple product.
template <class S>
S det3(const Mat3<S>& M) {
  return M.col(0).dot(cross(M.col(1), M.col(2)));
}

/// The signs of the geometric Jacobian's determinants at the sample (data and its factor Jf evaluated
/// there): with a spherical wrist, those of its two blocks, J11 (a singularity of the arm) and J22 (of
/// the wrist), each of which a crossing turns; without one, that of det J (from its factors) and true.
template <class S>
std::pair<bool, bool> det_signs(const Data<S>& data, const ArmJacobianFactor<S>& Jf) {
  if constexpr (kArmSphericalWrist) {
    return {det3<S>(data.J.template topLeftCorner<3, 3>()) > S(0),
            det3<S>(data.J.template bottomRightCorner<3, 3>()) > S(0)};
  } else {
    return {Jf.det_positive(), true};
  }
}

/// a - b turned into [-pi, pi] (a, b in [-pi, pi]).
template <class S>
S angle_difference(S a, S b) {
  const S d = a - b, pi = lit<S>(kPi), two_pi = lit<S>(2 * kPi);
  return d > pi ? S(d - two_pi) : (d < -pi ? S(d + two_pi) : d);
}

/// The analytic Jacobian of a sample (data evaluated there), in the orientation coordinates relative to R_ref
/// (controller.hpp).
template <class S>
Mat6<S> sample_analytic_jacobian(const Data<S>& data, const Mat3<S>& R_ref) {
  return analytic_jacobian(data.J, orientation_coordinates<S>(data.R[kDof], R_ref));
}

/// The singularity test of a sample (data and Jg, the geometric Jacobian's factor, evaluated at its solution): the
/// reciprocal condition that the controller tests, that of the analytic Jacobian in the orientation coordinates
/// relative to R_ref (controller.hpp), and a singularity crossed since the sample before (trace); in fixed point also a
/// saturated result in the sample's arithmetic. r.rcond updated.
template <class S>
bool near_singular(const Data<S>& data, const ArmJacobianFactor<S>& Jg, const Mat3<S>& R_ref,
                   SingularityTrace<S>& trace, PathCheck<S>& r) {
  const Vec3<S> phi = orientation_coordinates<S>(data.R[kDof], R_ref);
  ArmJacobianFactor<S> Jf;
  Jf.compute(analytic_jacobian(data.J, phi));
  if (!(Jf.rcond >= r.rcond)) r.rcond = Jf.rcond;
  const auto [arm, wrist] = det_signs(data, Jg);
  const S half_pi = lit<S>(kPi / 2);
  const bool crossed = trace.valid && (arm != trace.arm_positive || wrist != trace.wrist_positive ||
                                       math::abs(angle_difference(phi(0), trace.phi(0))) > half_pi ||
                                       math::abs(angle_difference(phi(2), trace.phi(2))) > half_pi);
  trace = {true, arm, wrist, phi};
  return !(Jf.rcond >= lit<S>(params::kPathMinRcond)) || crossed || saturated<S>();
}

/// What the loop's test of the first sample leaves for the others': each axis's bounds there (loop::path_bounds) and
/// whether its loop was judged stable there.
struct LoopTrace {
  bool valid = false;  // the first sample was judged
  loop::LoopBounds start{};
  bool stable[kDof] = {};
};

/// The sampled loop's test of a sample (data evaluated there; its joint inertia computed here): an axis whose loop is
/// not stable at Lambda^-1's bounds there times the margin (loop::path_bounds, loop::axis_stable) fails it, unless
/// the path began where that axis's loop was judged unstable already (the arm stands there, held by its friction:
/// on the PUMA's power-on poses with q2 + q3 near -pi/2) and the axis is no lighter than it was there: a path may
/// leave such a region, not go deeper into it. In fixed point a saturated Lambda^-1 fails it too.
template <class S>
bool unstable_loop(const Model<S>& model, Data<S>& data, const Mat3<S>& R_ref, const loop::PathLoop& loop,
                   LoopTrace& trace) {
  joint_inertia(model, data);
  const loop::LoopBounds b = loop::path_bounds(loop, lambda_inverse<S>(data.A, sample_analytic_jacobian(data, R_ref)));
  if (saturated<S>()) return true;
  bool fails = false;
  for (int i = 0; i < kDof; ++i) {
    const bool ok = loop::axis_stable(b, i);
    if (!trace.valid) {
      trace.stable[i] = ok;
      continue;
    }
    if (!ok && (trace.stable[i] || b.a[i] > trace.start.a[i] || b.b[i] > trace.start.b[i])) fails = true;
  }
  if (!trace.valid) trace.valid = true, trace.start = b;
  return fails;
}

/// The tests of one sample at its solution q (data and Jg evaluated there), in order; r's extremes updated. loop:
/// the sampled loop's test (none: not judged).
template <class S>
PathStatus classify(const Model<S>& model, Data<S>& data, const ArmJacobianFactor<S>& Jg, const Pose<S>& target,
                    const Mat3<S>& R_ref, const Vec6<S>& q, ClearanceTrace<S>& clearance, SingularityTrace<S>& trace,
                    PathCheck<S>& r, const loop::PathLoop* loop, LoopTrace& loop_trace) {
  bool aligned;
  const Vec6<S> e = pose_error(data, target, aligned);
  const S ep = e.template head<3>().cwiseAbs().maxCoeff(), eo = e.template tail<3>().cwiseAbs().maxCoeff();
  if (!(ep <= r.position_error)) r.position_error = ep;
  if (!(eo <= r.orientation_error)) r.orientation_error = eo;
  if (!(ep <= lit<S>(kPositionTolerance)) || !(eo <= lit<S>(kOrientationTolerance)) || !aligned)
    return PathStatus::kUnreachable;
  if (out_of_workspace(q, clearance, r)) return PathStatus::kOutOfWorkspace;
  if (near_singular(data, Jg, R_ref, trace, r)) return PathStatus::kNearSingular;
  if (loop && unstable_loop(model, data, R_ref, *loop, loop_trace)) return PathStatus::kUnstableLoop;
  return PathStatus::kOk;
}

}  // namespace path_check

/// Checks the path of `move` from the joint angles q_seed (the arm's, or the q_end of the check of
/// the move queued before it); R_ref is the controller's reference orientation. data is the kernels'
/// workspace (overwritten). loop: the gains' sampled-loop test at every sample (loop::path_loop; none: not
/// judged). See the file comment.
template <class S>
PathCheck<S> check_path(const Model<S>& model, Data<S>& data, const CartesianMove<S>& move, const Mat3<S>& R_ref,
                        const Vec6<S>& q_seed, const loop::PathLoop* loop = nullptr) {
  using namespace path_check;
  constexpr int N = params::kPathCheckPoints;
  const std::uint32_t before = math::take_arithmetic_flags<S>();  // the caller's, put back on return
  PathCheck<S> r;
  Vec6<S> q = q_seed;
  ArmJacobianFactor<S> Jf;
  ClearanceTrace<S> clearance;
  SingularityTrace<S> trace;
  path_check::LoopTrace loop_trace;
  evaluate(model, data, Jf, q);
  for (int i = 0; i <= N; ++i) {
    const Pose<S> target = i == N ? move.end() : move.pose_at(move.duration() * math::ratio<S>(i, N));
    for (int k = 0; k < (i == 0 ? kFirstIterations : kIterations); ++k) {
      bool aligned;
      newton_step(Jf, pose_error(data, target, aligned), q);
      evaluate(model, data, Jf, q);
    }
    const PathStatus s = classify(model, data, Jf, target, R_ref, q, clearance, trace, r, loop, loop_trace);
    if (s != PathStatus::kOk) {
      r.status = s;
      r.sample = i;
      break;
    }
  }
  r.q_end = q;
  math::restore_arithmetic_flags<S>(before);  // the check's own discarded
  return r;
}

}  // namespace osc
