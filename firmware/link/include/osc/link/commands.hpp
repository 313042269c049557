// The command protocol's frames (osc/link/command_frames.hpp) and the control task's commands and
// reports (osc/runtime/motion_commands.hpp), both ways:
//
//   controller: command_from_frame (a command frame checked and decoded into a verb and a
//               MoveRequest; a bad frame is refused: bad_command), prepare_frame_command (the same,
//               prepared for the task's mailbox), answer_due / answer_frame (a tick's report as an
//               answer frame), dropped_answer_frame (a move the tick dropped from the queue),
//               state_frame_from_task, trace_frame_from_task;
//   host:       frame_from_command / encode_command (a command as a frame), setpoint_frame,
//               report_from_frame (an answer frame as the tick's report), answer_ends (whether an
//               answer frame ends a command's motion).
//
// The controller's end on a link: osc/link/command_port.hpp (in the PIL node, osc/link/node.hpp).
#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>

#include "osc/link/frames.hpp"
#include "osc/runtime/control_task.hpp"

namespace osc {

/// The stop in effect in a motion state: category 0 in fault, 2 while stopping (MotionStep::stop of
/// the tick that left the machine in it).
constexpr StopCategory stop_category_of(MotionState s) {
  return s == MotionState::kFault      ? StopCategory::kCategory0
         : s == MotionState::kStopping ? StopCategory::kCategory2
                                       : StopCategory::kNone;
}

namespace detail {
inline bool command_within(float v, double bound) { return std::fabs(static_cast<double>(v)) <= bound; }

/// Every number finite, the position and the angles within their bounds, and with has_limits every
/// limit above 0.
inline bool command_numbers_valid(const pil::CommandFrame& f) {
  for (int i = 0; i < 3; ++i)
    if (!command_within(f.position[i], pil::kCommandMaxPosition) || !command_within(f.rpy[i], pil::kCommandMaxAngle))
      return false;
  for (float l : f.limits) {
    if (!std::isfinite(l)) return false;
    if ((f.flags & pil::kFlagHasLimits) && !(l > 0.0f)) return false;
  }
  if (f.verb == static_cast<std::uint8_t>(MotionVerb::kStream) && (f.period < 1 || f.period > pil::kStreamMaxPeriod))
    return false;
  return true;  // a NaN fails command_within(): !(NaN <= bound)
}

/// The position and the angles of a setpoint (either frame) within their bounds, its flags in their
/// list.
template <class Frame>
bool setpoint_pose_valid(const Frame& f) {
  if ((f.flags & ~pil::kSetpointFlagsKnown) != 0) return false;
  for (int i = 0; i < 3; ++i)
    if (!command_within(f.position[i], pil::kCommandMaxPosition) || !command_within(f.rpy[i], pil::kCommandMaxAngle))
      return false;
  return true;
}
inline bool setpoint_valid(const pil::SetpointFrame& f) { return setpoint_pose_valid(f); }
/// ... and of a setpoint with velocity, its velocities within +-kCommandMaxVelocity too.
inline bool setpoint_valid(const pil::SetpointVelocityFrame& f) {
  if (!setpoint_pose_valid(f)) return false;
  for (float v : f.velocity)
    if (!command_within(v, pil::kCommandMaxVelocity)) return false;
  return true;
}
}  // namespace detail

/// Checks a command frame and decodes it: the verb, and for move_to the request (filled for every
/// verb, so that frame_from_command gives the frame back). A verb or flag bit outside its list, a
/// non-finite number, a position coordinate beyond +-kCommandMaxPosition, an angle beyond
/// +-kCommandMaxAngle, with has_limits a limit not above 0, or a stream's period outside 1 to
/// kStreamMaxPeriod: bad_command, with `verb` the frame's
/// when its code is in the list (none otherwise) and `req` cleared. The limits against the configured
/// maxima, the queue and the path are prepare_move's.
template <class S>
MotionReason command_from_frame(const pil::CommandFrame& f, MoveRequest<S>& req, MotionVerb& verb) {
  req = MoveRequest<S>{};
  const bool known_verb = f.verb < MotionNames<MotionVerb>::kCount;
  verb = known_verb ? static_cast<MotionVerb>(f.verb) : MotionVerb::kNone;
  if (!known_verb || (f.flags & ~pil::kCommandFlagsKnown) != 0 || !detail::command_numbers_valid(f))
    return MotionReason::kBadCommand;
  for (int i = 0; i < 3; ++i) {
    req.position(i) = lit<S>(static_cast<double>(f.position[i]));
    req.rpy(i) = lit<S>(static_cast<double>(f.rpy[i]));
  }
  req.relative = (f.flags & pil::kFlagRelative) != 0;
  req.has_rpy = (f.flags & pil::kFlagHasRpy) != 0;
  req.replace = (f.flags & pil::kFlagReplace) != 0;
  req.has_limits = (f.flags & pil::kFlagHasLimits) != 0;
  req.period = f.period;
  JerkLimits<S>* const lim[2] = {&req.limits.linear, &req.limits.angular};
  for (int k = 0; k < 2; ++k) {
    lim[k]->v = lit<S>(static_cast<double>(f.limits[3 * k]));
    lim[k]->a = lit<S>(static_cast<double>(f.limits[3 * k + 1]));
    lim[k]->j = lit<S>(static_cast<double>(f.limits[3 * k + 2]));
  }
  return MotionReason::kNone;
}

/// The payload's entries an identify command's run estimates too (payload_mask): all ten with the flag payload.
inline std::uint16_t identify_payload_mask(const pil::CommandFrame& f) {
  return (f.flags & pil::kFlagPayload) != 0 ? payload_mask::kAll : payload_mask::kNone;
}

/// A command frame, ready for the task's mailbox (ControlTask::pending) at tick `next_tick`: decoded
/// (command_from_frame), then prepared (prepare_move for move_to, prepare_command otherwise; `max`:
/// the configured limits). A bad frame gives a command refused with bad_command.
template <class S>
TaskCommand<S> prepare_frame_command(const MotionGenerator<S>& gen, const CartesianLimits<S>& max,
                                     std::uint64_t next_tick, std::uint32_t rate_hz, const pil::CommandFrame& f) {
  MoveRequest<S> req;
  MotionVerb verb;
  const MotionReason why = command_from_frame(f, req, verb);
  if (why != MotionReason::kNone) {
    TaskCommand<S> c = prepare_command<S>(verb, f.id);
    c.refusal = why;
    return c;
  }
  if (verb == MotionVerb::kMoveTo) return prepare_move(gen, max, next_tick, rate_hz, req, f.id);
  if (verb == MotionVerb::kStream) return prepare_stream(max, req, f.id);
  if (verb == MotionVerb::kDeclarePose) return prepare_declare_pose<S>(f.period, f.id);
  return prepare_command<S>(verb, f.id);
}

/// A setpoint frame, or a setpoint_velocity frame, into the task's mailbox (offer_setpoint): false
/// (counted in task.dropped) for a bad one (a flag outside its list, a number beyond its bound or
/// not finite) or one of no running stream.
template <class S, class Frame>
bool offer_setpoint_frame(ControlTask<S>& task, const Frame& f) {
  if (!detail::setpoint_valid(f)) {
    ++task.dropped;
    return false;
  }
  Vec3<S> p, rpy;
  for (int i = 0; i < 3; ++i) {
    p(i) = lit<S>(static_cast<double>(f.position[i]));
    rpy(i) = lit<S>(static_cast<double>(f.rpy[i]));
  }
  const bool has_rpy = (f.flags & pil::kSetpointHasRpy) != 0, end = (f.flags & pil::kSetpointEnd) != 0;
  if constexpr (std::is_same_v<Frame, pil::SetpointVelocityFrame>) {
    Vec6<S> v;
    for (int i = 0; i < 6; ++i) v(i) = lit<S>(static_cast<double>(f.velocity[i]));
    return offer_setpoint(task, f.id, p, rpy, has_rpy, end, &v);
  } else {
    return offer_setpoint(task, f.id, p, rpy, has_rpy, end);
  }
}

/// Host side: a setpoint as a frame.
template <class S>
pil::SetpointFrame setpoint_frame(std::uint32_t id, const Vec3<S>& position, const Vec3<S>* rpy, bool end) {
  pil::SetpointFrame f;
  f.id = id;
  f.flags = static_cast<std::uint8_t>((end ? pil::kSetpointEnd : 0) | (rpy ? pil::kSetpointHasRpy : 0));
  for (int i = 0; i < 3; ++i) {
    f.position[i] = static_cast<float>(position(i));
    f.rpy[i] = rpy ? static_cast<float>((*rpy)(i)) : 0.0f;
  }
  return f;
}
/// Host side: a setpoint with its velocity (the wrist centre's, then the angular velocity, base
/// frame) as a frame.
template <class S>
pil::SetpointVelocityFrame setpoint_velocity_frame(std::uint32_t id, const Vec3<S>& position, const Vec3<S>* rpy,
                                                   const Vec6<S>& velocity, bool end) {
  const pil::SetpointFrame s = setpoint_frame(id, position, rpy, end);
  pil::SetpointVelocityFrame f;
  f.id = s.id, f.flags = s.flags;
  for (int i = 0; i < 3; ++i) f.position[i] = s.position[i], f.rpy[i] = s.rpy[i];
  for (int i = 0; i < 6; ++i) f.velocity[i] = static_cast<float>(velocity(i));
  return f;
}

namespace detail {
/// The largest f32 not above v: a limit sent as f32 never asks for more than the client's (a limit
/// at a configured maximum that f32 cannot hold, e.g. 0.1 m/s, stays within it in every scalar).
template <class S>
float f32_at_most(const S& v) {
  const double x = static_cast<double>(v);
  const float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -HUGE_VALF) : f;
}
}  // namespace detail

/// Host side: a command as a frame (the request's position and angles rounded to the nearest f32,
/// its limits to the f32 at most them; for verbs other than move_to a default request gives zeros).
template <class S>
pil::CommandFrame frame_from_command(std::uint32_t id, MotionVerb verb, const MoveRequest<S>& req = {}) {
  pil::CommandFrame f;
  f.id = id;
  f.verb = static_cast<std::uint8_t>(verb);
  f.flags =
      static_cast<std::uint8_t>((req.relative ? pil::kFlagRelative : 0) | (req.has_rpy ? pil::kFlagHasRpy : 0) |
                                (req.replace ? pil::kFlagReplace : 0) | (req.has_limits ? pil::kFlagHasLimits : 0));
  for (int i = 0; i < 3; ++i) {
    f.position[i] = static_cast<float>(req.position(i));
    f.rpy[i] = static_cast<float>(req.rpy(i));
  }
  const JerkLimits<S> lim[2] = {req.limits.linear, req.limits.angular};
  for (int k = 0; k < 2; ++k) {
    f.limits[3 * k] = detail::f32_at_most(lim[k].v);
    f.limits[3 * k + 1] = detail::f32_at_most(lim[k].a);
    f.limits[3 * k + 2] = detail::f32_at_most(lim[k].j);
  }
  f.period = static_cast<std::uint8_t>(req.period > 255 ? 255 : req.period);  // other verbs ignore it
  return f;
}

/// Host side: encodes a command frame into buf (at least pil::kMaxFrame bytes); returns its length.
template <class S>
int encode_command(std::uint32_t id, MotionVerb verb, const MoveRequest<S>& req, std::uint8_t* buf) {
  return pil::encode(frame_from_command(id, verb, req), buf);
}

/// Whether a tick's report has something to send: a command answered, a motion done or aborted, a
/// completion, moves dropped.
constexpr bool answer_due(const MotionReport& r) {
  return r.outcome != CommandOutcome::kNone || r.done_id != 0 || r.aborted_id != 0 || r.abort != MotionReason::kNone ||
         r.completion != MotionCompletion::kNone || r.dropped_moves != 0;
}

/// A tick's report as an answer frame, with the machine's state after the tick, the moves queued
/// then and the tick's number.
inline pil::AnswerFrame frame_from_report(const MotionReport& r, MotionState state, int queued, std::uint64_t tick) {
  pil::AnswerFrame a;
  a.id = r.id;
  a.verb = static_cast<std::uint8_t>(r.verb);
  a.outcome = static_cast<std::uint8_t>(r.outcome);
  a.refusal = static_cast<std::uint8_t>(r.refusal);
  a.cause = r.cause;
  a.done_id = r.done_id;
  a.aborted_id = r.aborted_id;
  a.abort = static_cast<std::uint8_t>(r.abort);
  a.completion = static_cast<std::uint8_t>(r.completion);
  a.state = static_cast<std::uint8_t>(state);
  a.stop = static_cast<std::uint8_t>(stop_category_of(state));
  a.queued = static_cast<std::uint8_t>(queued < 0 ? 0 : queued > 255 ? 255 : queued);
  a.tick = static_cast<std::uint32_t>(tick);
  return a;
}

/// The answer of the tick control_tick() just ran (its report; task.tick has moved on to the next).
template <class S>
pil::AnswerFrame answer_frame(const ControlTask<S>& task) {
  return frame_from_report(task.report, task.machine.state, task.gen.queued(), task.tick - 1);
}

/// The answer frame that names the k-th move the tick control_tick() just ran dropped from the queue
/// (k < task.report.dropped_moves): aborted_id its id, abort `dropped`, no command answered, the
/// tick's state, queue and number (sent after the tick's own answer frame, one per move).
template <class S>
pil::AnswerFrame dropped_answer_frame(const ControlTask<S>& task, int k) {
  MotionReport r;
  r.aborted_id = task.dropped_move_ids[k];
  r.abort = MotionReason::kDropped;
  return frame_from_report(r, task.machine.state, task.gen.queued(), task.tick - 1);
}

/// Host side: whether an answer frame ends command `id`: its motion done (done_id), or aborted with
/// a reason (aborted_id; dropped too). Every motion command accepted ends in exactly one such frame.
constexpr bool answer_ends(const pil::AnswerFrame& a, std::uint32_t id) {
  return id != 0 &&
         (a.done_id == id || (a.aborted_id == id && a.abort != static_cast<std::uint8_t>(MotionReason::kNone)));
}

/// Host side: an answer frame as the report of the tick that sent it (frame_from_report's inverse;
/// codes outside their lists are none).
inline MotionReport report_from_frame(const pil::AnswerFrame& a) {
  auto code = [](std::uint8_t c, auto none) {
    return c < MotionNames<decltype(none)>::kCount ? static_cast<decltype(none)>(c) : none;
  };
  MotionReport r;
  r.id = a.id;
  r.verb = code(a.verb, MotionVerb::kNone);
  r.outcome = code(a.outcome, CommandOutcome::kNone);
  r.refusal = code(a.refusal, MotionReason::kNone);
  r.cause = a.cause;
  r.done_id = a.done_id;
  r.aborted_id = a.aborted_id;
  r.abort = code(a.abort, MotionReason::kNone);
  r.completion = code(a.completion, MotionCompletion::kNone);
  return r;
}

namespace detail {
/// A pose as six f32: the position, then roll, pitch, yaw as a move_to's absolute rpy.
template <class S>
void pose_floats(const Vec3<S>& p, const Mat3<S>& R, float out[6]) {
  const Vec3<S> rpy = orientation_coordinates<S>(R, Mat3<S>::Identity());
  for (int i = 0; i < 3; ++i) {
    out[i] = static_cast<float>(p(i));
    out[3 + i] = static_cast<float>(rpy(i));
  }
}
}  // namespace detail

/// The task's state after a tick: the motion state, the stop in effect, the latched faults, the
/// moves queued, and the reference and measured poses of the last control step (ControlTask::desired; before
/// the first step, or after a step that failed, the pose the generator holds).
template <class S>
pil::StateFrame state_frame_from_task(const ControlTask<S>& task) {
  pil::StateFrame f;
  f.state = static_cast<std::uint8_t>(task.machine.state);
  f.stop = static_cast<std::uint8_t>(stop_category_of(task.machine.state));
  f.faults = task.sup.latched;  // the one latch (the machine reads it: MotionInput::latched)
  const int queued = task.gen.queued();
  f.queued = static_cast<std::uint8_t>(queued > 255 ? 255 : queued);
  f.running_id = task.gen.running_id();
  f.dropped = task.dropped;
  const StepOutput<S>& out = task.last;
  if (task.step_timing.count == 0 || out.status != kFaultNone) {
    detail::pose_floats<S>(task.gen.hold_pose().p, task.gen.hold_pose().R, f.x_d);
  } else {
    const Vec6<S>& x_d = task.desired.x;
    detail::pose_floats<S>(x_d.template head<3>(), Mat3<S>(rpy_rotation<S>(x_d.template tail<3>()) * task.state.R_ref),
                           f.x_d);
  }
  detail::pose_floats<S>(task.state.data.o[kDof], task.state.data.R[kDof], f.x);
  f.tick = static_cast<std::uint32_t>(task.tick - 1);
  f.friction_checked = task.state.adapt.identifier.fit.checked();
  f.friction_stale = task.state.adapt.identifier.fit.stale;
  return f;
}

/// The trace of the tick control_tick() just ran: `seq`, the sequence number of its sensor frame,
/// `faults`, the bits it detected (control_tick's result), the motion state after it, the desired
/// state of the last control step (ControlTask::desired) and the reference orientation, as they are
/// (f32 holds float exactly, and Q12.19 below 32 in magnitude: Q::operator float, no FPU needed).
template <class S>
pil::TraceFrame trace_frame_from_task(const ControlTask<S>& task, std::uint32_t seq, std::uint32_t faults) {
  pil::TraceFrame f;
  f.seq = seq;
  f.faults = faults;
  f.state = static_cast<std::uint8_t>(task.machine.state);
  for (int i = 0; i < 6; ++i) {
    f.x_d[i] = static_cast<float>(task.desired.x(i));
    f.xd_d[i] = static_cast<float>(task.desired.xd(i));
    f.xdd_d[i] = static_cast<float>(task.desired.xdd(i));
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) f.R_ref[3 * r + c] = static_cast<float>(task.state.R_ref(r, c));
  return f;
}

}  // namespace osc
