// Commands to the task from outside the tick (a board's main loop, the host's driver): a move_to or a
// home prepared in full, planned and path-checked (prepare_checked_move, prepare_checked_home), a
// stream's setpoint into the task's mailbox (offer_setpoint) and a category-2 stop asked of the next
// tick (request_stop), each left where the next tick takes it (task.pending, task.sample,
// task.stop_request).
#pragma once

#include <cstdint>

#include "osc/control/excitation.hpp"
#include "osc/control/identify_estimate.hpp"  // payload_mask
#include "osc/control/path_check.hpp"
#include "osc/runtime/homing.hpp"
#include "osc/runtime/motion_commands.hpp"

namespace osc {

/// The task (osc/runtime/control_task.hpp, which includes this header before it defines the type):
/// the functions below take it by reference.
template <class S>
struct ControlTask;

/// Asks the next tick for a category-2 stop of the running motion, for `why` (a reason of the
/// runtime's, e.g. kLinkSilent): the tick takes it after its own (a reached limit, a stale stream)
/// and only while moving (motion_next ignores a stop request in any other state). Call it where the
/// tick runs (the control interrupt), before the tick; each tick takes the request it finds and
/// clears it.
template <class S>
void request_stop(ControlTask<S>& task, MotionReason why) {
  task.stop_request = why;
}

/// A path check's result as a refusal (none: the path is clear). A target beyond the arm's reach
/// (kUnreachable) is out of its workspace.
constexpr MotionReason path_refusal(PathStatus s) {
  switch (s) {
    case PathStatus::kOk:
      return MotionReason::kNone;
    case PathStatus::kNearSingular:
      return MotionReason::kNearSingular;
    case PathStatus::kUnstableLoop:
      return MotionReason::kUnstableLoop;
    case PathStatus::kOutOfWorkspace:
    case PathStatus::kUnreachable:
      break;
  }
  return MotionReason::kOutOfWorkspace;
}

/// The path check of a move_to prepare_move planned, or of a home's move (nothing if it refused it already), with the
/// sampled loop judged at the task's gains.
template <class S>
void check_prepared_move(ControlTask<S>& task, TaskCommand<S>& c) {
  if ((c.verb != MotionVerb::kMoveTo && c.verb != MotionVerb::kHome) || c.refusal != MotionReason::kNone) return;
  const Vec6<S> seed = c.brake ? task.state.adapt.q_prev : task.q_queue_end;
  const loop::PathLoop gains = loop::path_loop(task.gains.template cast<double>(), params::kPathLoopMargin);
  const PathCheck<S> pc =
      check_path(task.model, task.check_data, c.move, task.gen.reference_orientation(), seed, &gains);
  c.refusal = path_refusal(pc.status);
  c.q_end = pc.q_end;
}

/// Prepares a move_to in full, outside the tick (a board's main loop, the host's driver): the
/// limits, the queue and the plan (prepare_move), then the path check (check_path) from the joint
/// angles where the queue ends, or, for a move that starts where a braked motion comes to rest,
/// from the last measured ones. Put the result in task.pending for the next tick.
template <class S>
TaskCommand<S> prepare_checked_move(ControlTask<S>& task, const MoveRequest<S>& req, std::uint32_t id) {
  TaskCommand<S> c = prepare_move(task.gen, task.limits, task.tick, params::kControlHz, req, id);
  check_prepared_move(task, c);
  return c;
}

/// Prepares a home in full, outside the tick (like prepare_checked_move): the homing move from the
/// last measured angles, path-checked.
template <class S>
TaskCommand<S> prepare_checked_home(ControlTask<S>& task, std::uint32_t id) {
  TaskCommand<S> c =
      prepare_home(task.gen, home_limits(task), task.model, task.check_data, task.io, task.state.adapt.q_prev, id);
  check_prepared_move(task, c);
  return c;
}

/// An excitation's check as a refusal (none: it fits): the names a move's path check uses.
constexpr MotionReason excitation_refusal(ExcitationStatus s) {
  switch (s) {
    case ExcitationStatus::kOk:
      return MotionReason::kNone;
    case ExcitationStatus::kNearSingular:
      return MotionReason::kNearSingular;
    case ExcitationStatus::kOverLimit:
      return MotionReason::kOverLimit;
    case ExcitationStatus::kUnstableLoop:
      return MotionReason::kUnstableLoop;
    case ExcitationStatus::kOutOfWorkspace:
      break;
  }
  return MotionReason::kOutOfWorkspace;
}

/// The same about the joint angles q (a paced board's copy of the last measured ones), in the orientation
/// coordinates of the orientation at q (the run's own: the tick re-references the controller there as the run
/// starts, controller_rereference, wherever the enable was) and with the controller's gains (the sampled loop's
/// test, as a move's path check: unstable_loop), in the workspace `data`. payload: the payload's entries the run
/// estimates too (payload_mask).
template <class S>
TaskCommand<S> prepare_identify_at(const Model<S>& model, const Gains<S>& gains, Data<S>& data, const Vec6<S>& q,
                                   std::uint32_t id, ExcitationCheck<S>* check,
                                   std::uint16_t payload = payload_mask::kNone) {
  TaskCommand<S> c;
  c.verb = MotionVerb::kIdentify;
  c.id = id;
  c.payload = payload;
  const loop::PathLoop loop = loop::path_loop(gains.template cast<double>(), params::kPathLoopMargin);
  forward_kinematics(model, data, q);
  const Mat3<S> R_start = data.R[kDof];
  const ExcitationCheck<S> r =
      prepare_excitation(model, data, q, R_start, ExcitationLimits<S>::defaults(), c.excitation, &loop);
  c.refusal = excitation_refusal(r.status);
  c.checked = true;
  if (check) *check = r;
  return c;
}

/// Prepares an identification run outside the tick (like prepare_checked_move): its excitation motion
/// planned about the last measured joint angles and checked in full (prepare_excitation: limits, speeds,
/// torques with the model as it is, the payload included, and the Jacobian's condition), refused by
/// name rather than stopped halfway. Whether the arm holds there (else not_enabled, busy) is the tick's to
/// decide. `check`, when given, receives the check's report (which joint, which tick, the peaks).
template <class S>
TaskCommand<S> prepare_identify(ControlTask<S>& task, std::uint32_t id, ExcitationCheck<S>* check = nullptr,
                                std::uint16_t payload = payload_mask::kNone) {
  return prepare_identify_at(task.model, task.gains, task.check_data, task.state.adapt.q_prev, id, check, payload);
}

/// Puts a setpoint of stream `id` (with its velocity, or none) into the task's mailbox for the next
/// tick (prepare_setpoint):
/// false, counted in task.dropped, when no stream of that id runs; a setpoint not yet taken is
/// replaced (and counted).
template <class S>
bool offer_setpoint(ControlTask<S>& task, std::uint32_t id, const Vec3<S>& position, const Vec3<S>& rpy, bool has_rpy,
                    bool end, const Vec6<S>* velocity = nullptr) {
  StreamSample<S> s;
  if (!prepare_setpoint(task.gen, id, position, rpy, has_rpy, end, s, velocity)) {
    ++task.dropped;
    return false;
  }
  if (task.sample.valid) ++task.dropped;
  task.sample = s;
  return true;
}

}  // namespace osc
