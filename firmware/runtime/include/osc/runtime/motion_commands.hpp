// The commands a client gives the control task (issue 23), how each is prepared outside the
// interrupt, and what the task reports back.
//
// A command is prepared where there is time (the main loop of a board, the host's driver): a move
// is checked against the configured limits, planned from where the queue will end
// (MotionGenerator::queue_end, or where the running motion would come to rest for a re-target or
// after the paper's motion) and checked along its path. What the geometry and the limits decide is
// a refusal already (over_limit, queue_full, busy, out_of_workspace, near_singular). The prepared
// command then waits in the task's mailbox (ControlTask::pending) for the next tick, which passes
// it to the motion state machine (motion_states.hpp: not_enabled, stopping, faulted) and, once
// accepted, to the generator: its effect starts with the tick after (one tick from arrival to the
// first changed setpoint).
#pragma once

#include <cstdint>

#include "osc/control/motion.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/motion_states.hpp"

namespace osc {

// X(Name, "name", meaning): the verbs of the command frame, in code order.
#define OSC_MOTION_VERB_LIST(X)                                                                               \
  X(None, "none", "no command")                                                                               \
  X(Enable, "enable", "torque on, holding the measured pose; the observer starts there")                      \
  X(Disable, "disable", "torque off; from a motion, after a category-2 stop to rest")                         \
  X(MoveTo, "move_to", "a jerk-limited move to a pose: queued, or re-targeting the running motion")           \
  X(Paper, "paper", "the paper's motion (68) about the held position, until a stop")                          \
  X(Stop, "stop", "category-2 stop: decelerate along the path within the limits, then hold")                  \
  X(Clear, "clear", "leave fault for disabled, once no fault cause is present")                               \
  X(Stream, "stream", "follow the setpoint frames that follow, jerk-limited; stale: category-2 stop")         \
  X(Home, "home", "homing: each motor up to one revolution to its index pulse, from the pots' coarse angles") \
  X(DeclarePose, "declare_pose", "the arm stands at the named pose `pose` (torque off; the pots must agree)") \
  X(Identify, "identify", "an identification run: the excitation about the held angles, checked first")

#define OSC_X_PREFIX k
OSC_MOTION_ENUM(MotionVerb, OSC_MOTION_VERB_LIST);
#undef OSC_X_PREFIX

/// The state machine's command for a verb (a code outside the list: none).
constexpr MotionCommand verb_command(MotionVerb v) {
  switch (v) {
    case MotionVerb::kEnable:
      return MotionCommand::kEnable;
    case MotionVerb::kDisable:
      return MotionCommand::kDisable;
    case MotionVerb::kMoveTo:
    case MotionVerb::kPaper:
    case MotionVerb::kStream:
    case MotionVerb::kIdentify:
      return MotionCommand::kMove;
    case MotionVerb::kStop:
      return MotionCommand::kStop;
    case MotionVerb::kClear:
      return MotionCommand::kClear;
    case MotionVerb::kHome:
      return MotionCommand::kHome;
    case MotionVerb::kDeclarePose:
      return MotionCommand::kDeclarePose;
    case MotionVerb::kNone:
      break;
  }
  return MotionCommand::kNone;
}

/// A move_to: the target of the wrist centre and, optionally, of the orientation; relative to
/// where the queue ends (position offset in the base frame, rotation applied in the base frame)
/// or absolute (the base-frame position; R = Rz(yaw) Ry(pitch) Rx(roll)); optional limits, each at
/// most the configured maximum.
template <class S>
struct MoveRequest {
  Vec3<S> position = Vec3<S>::Zero();  ///< [m]
  Vec3<S> rpy = Vec3<S>::Zero();       ///< [rad], with has_rpy
  bool relative = false;
  bool has_rpy = false;
  bool replace = false;  ///< re-target: brake the running motion along its path, drop the queue, go
  bool has_limits = false;
  CartesianLimits<S> limits{};
  std::uint32_t period = 1;  ///< stream: the setpoints' period [ticks] (relative, has_limits apply too)
};

/// A command ready for the next tick.
template <class S>
struct TaskCommand {
  MotionVerb verb = MotionVerb::kNone;
  std::uint32_t id = 0;                        ///< the client's, echoed in the reports
  MotionReason refusal = MotionReason::kNone;  ///< decided while preparing
  bool brake = false;                          ///< move_to: brake the running motion first
  std::uint8_t pose = 0;                       ///< declare_pose: the pose's code (robot::kNamedPoses)
  std::uint32_t epoch = 0;                     ///< the generator's, when the move was planned
  CartesianMove<S> move{};                     ///< move_to: the planned move
  Vec6<S> q_end = Vec6<S>::Zero();             ///< move_to: the joint angles at its end (path check)
  std::uint32_t period = 1;                    ///< stream: the setpoints' period [ticks]
  bool relative = false;                       ///< stream: setpoints relative to where it starts
  CartesianLimits<S> limits{};                 ///< stream: its limits
  ExcitationMotion<S> excitation{};            ///< identify: the motion, planned and checked
  std::uint16_t payload = 0;  ///< identify: the payload's entries estimated too (payload_mask; 0: none)
  bool checked = false;       ///< identify: planned and checked by prepare_identify (else the tick refuses it)
};

/// One setpoint of a stream, ready for the next tick (prepare_setpoint): the follower's target in
/// the controller's coordinates (position; roll, pitch, yaw of R R_ref^T).
template <class S>
struct StreamSample {
  bool valid = false;         ///< waiting for the tick (taken there)
  bool end = false;           ///< the stream's last
  bool has_velocity = false;  ///< v is the sample's velocity (else none was given)
  Vec6<S> x = Vec6<S>::Zero();
  Vec6<S> v = Vec6<S>::Zero();  ///< the rates of x (position; roll, pitch, yaw)
};

/// What one tick reports: the answer to its command, and the motions that ended. Every motion
/// command accepted (move_to, paper, stream, home) ends in exactly one report: done (done_id),
/// aborted (aborted_id, why), or, a move taken from the queue before it started, dropped (one of
/// the tick's dropped_moves).
struct MotionReport {
  std::uint32_t id = 0;  ///< the command answered in this tick (0 with outcome none)
  MotionVerb verb = MotionVerb::kNone;
  CommandOutcome outcome = CommandOutcome::kNone;
  MotionReason refusal = MotionReason::kNone;
  std::uint32_t cause = 0;  ///< with refusal faulted: the fault bits behind it
  /// A motion command that ended in this tick: done (its move reached its target at rest, a stream
  /// its last setpoint, a home every index pulse) or aborted (why); 0: none, or a motion whose end
  /// was reported already (the motion a re-target brakes).
  std::uint32_t done_id = 0, aborted_id = 0;
  MotionReason abort = MotionReason::kNone;
  MotionCompletion completion = MotionCompletion::kNone;
  /// Moves dropped from the queue in this tick, never started (their motion ahead stopped,
  /// re-targeted or faulted): their ids are the task's dropped_move_ids[0, dropped_moves), each
  /// aborted `dropped` (kept out of the report, which every tick clears).
  std::uint8_t dropped_moves = 0;
};

/// The pose a move_to asks for, from where its move starts.
template <class S>
Pose<S> move_target(const Pose<S>& from, const MoveRequest<S>& req) {
  Pose<S> to = from;
  to.p = req.relative ? Vec3<S>(from.p + req.position) : req.position;
  if (req.has_rpy) to.R = req.relative ? Mat3<S>(rpy_rotation<S>(req.rpy) * from.R) : rpy_rotation<S>(req.rpy);
  return to;
}

/// Prepares a move_to for the tick `next_tick`: limits, queue, plan (the path check is the
/// caller's, on the planned move). `max`: the configured limits.
template <class S>
TaskCommand<S> prepare_move(const MotionGenerator<S>& gen, const CartesianLimits<S>& max, std::uint64_t next_tick,
                            std::uint32_t rate_hz, const MoveRequest<S>& req, std::uint32_t id) {
  TaskCommand<S> c;
  c.verb = MotionVerb::kMoveTo;
  c.id = id;
  c.epoch = gen.epoch();
  const CartesianLimits<S> lim = req.has_limits ? req.limits : max;
  if (!lim.within(max)) {
    c.refusal = MotionReason::kOverLimit;
    return c;
  }
  // A move while a stream or an identification run runs: its end is not known until it ends (stop it,
  // or wait).
  if (gen.source() == MotionSource::kStream || gen.source() == MotionSource::kExcitation) {
    c.refusal = MotionReason::kBusy;
    return c;
  }
  // A re-target, or a move after the paper's motion, starts where the running motion comes to rest
  // when braked in the tick after the command's (or where its brake ends: the moves waiting are
  // dropped). A move while the paper's motion slows down for one is queued behind it.
  c.brake = req.replace || (gen.source() == MotionSource::kPaper && !gen.braking());
  if (!c.brake && gen.queue_full()) {
    c.refusal = MotionReason::kQueueFull;
    return c;
  }
  // The plan's fixed-point saturations are its own (a refusal), not the next tick's fault.
  const std::uint32_t saved = math::take_arithmetic_flags<S>();
  const Pose<S> from = c.brake ? gen.brake_end(next_tick + 1, rate_hz, max) : gen.queue_end();
  const ProfileStatus st = c.move.plan(from, move_target(from, req), lim, gen.reference_orientation());
  // A rotation beyond kMaxMoveRotation, a non-finite target, a plan that left the scalar's range.
  if (math::take_arithmetic_fault<S>() || st != ProfileStatus::kOk) c.refusal = MotionReason::kOverLimit;
  math::restore_arithmetic_flags<S>(saved);
  return c;
}

/// Prepares a stream command: its limits against the configured maxima `max` (over_limit). Whether
/// the generator holds (else busy) is the tick's to decide.
template <class S>
TaskCommand<S> prepare_stream(const CartesianLimits<S>& max, const MoveRequest<S>& req, std::uint32_t id) {
  TaskCommand<S> c;
  c.verb = MotionVerb::kStream;
  c.id = id;
  c.period = req.period;
  c.relative = req.relative;
  c.limits = req.has_limits ? req.limits : max;
  if (!c.limits.within(max)) c.refusal = MotionReason::kOverLimit;
  return c;
}

/// Prepares a setpoint of the running stream `id`: false (dropped) when no stream of that id runs.
/// position, rpy: absolute (base frame), or relative to the pose the stream started at; without
/// has_rpy the orientation stays as it started. `velocity` (or none): the wrist centre's velocity
/// and the angular velocity w, base frame (relative: of the offset and of the rotation applied, the
/// same), as the rates of the follower's coordinates: phi_dot = E^{-1}(phi) w (0 without has_rpy;
/// all 0 with end).
template <class S>
bool prepare_setpoint(const MotionGenerator<S>& gen, std::uint32_t id, const Vec3<S>& position, const Vec3<S>& rpy,
                      bool has_rpy, bool end, StreamSample<S>& out, const Vec6<S>* velocity = nullptr) {
  if (gen.source() != MotionSource::kStream || gen.braking() || gen.running_id() != id) return false;
  const std::uint32_t saved = math::take_arithmetic_flags<S>();
  MoveRequest<S> req;
  req.position = position, req.rpy = rpy, req.relative = gen.stream_relative(), req.has_rpy = has_rpy;
  const Pose<S> to = move_target(gen.hold_pose(), req);
  out.x << to.p, orientation_coordinates<S>(to.R, gen.reference_orientation());
  out.end = end;
  out.has_velocity = velocity != nullptr;
  out.v.setZero();
  if (velocity && !end) {
    out.v.template head<3>() = velocity->template head<3>();
    // The orientation's coordinates are those of R R_ref^T, R_ref fixed: its angular velocity is R's.
    if (has_rpy)
      out.v.template tail<3>() = angular_to_phi_rate<S>(out.x.template tail<3>()) * velocity->template tail<3>();
  }
  out.valid = !math::take_arithmetic_fault<S>();
  math::restore_arithmetic_flags<S>(saved);
  return out.valid;
}

/// A command without a plan (every verb but move_to): nothing to prepare, the tick decides it (a
/// paper command while a motion runs, busy, where the state is current).
template <class S>
TaskCommand<S> prepare_command(MotionVerb verb, std::uint32_t id) {
  TaskCommand<S> c;
  c.verb = verb;
  c.id = id;
  return c;
}

/// Prepares a declare_pose of the pose of code `pose` (robot::kNamedPoses): unknown_pose for a code
/// outside the list, not_needed on an arm with absolute encoders. The pots check and the state are the tick's.
template <class S>
TaskCommand<S> prepare_declare_pose(unsigned pose, std::uint32_t id) {
  TaskCommand<S> c = prepare_command<S>(MotionVerb::kDeclarePose, id);
  if (pose >= static_cast<unsigned>(robot::kNamedPoseCount)) {
    c.refusal = MotionReason::kUnknownPose;
    return c;
  }
  c.pose = static_cast<std::uint8_t>(pose);
  if (has_absolute_encoders(robot::kDriveTrain)) c.refusal = MotionReason::kNotNeeded;  // as prepare_home
  return c;
}

}  // namespace osc
