// The tick's motion stage (docs/motion.md): after the supervisor, the tick's command, faults and the
// generator's events through the motion state machine (motion_next, osc/runtime/motion_states.hpp), and
// what it decided applied to the generator and the controller (motion_update, motion_apply); with what
// the tick hands it: a collision's reaction (take_collision), the category-2 stop of the tick
// (tick_stop_request, motion_limits_reached) and a yielding arm's reference (yield_reference).
// control_tick() (osc/runtime/control_task.hpp) calls them.
#pragma once

#include <cstdint>

#include "osc/control/controller.hpp"
#include "osc/control/path_check.hpp"
#include "osc/runtime/homing.hpp"
#include "osc/runtime/motion_commands.hpp"
#include "osc/runtime/supervisor.hpp"

namespace osc {

/// The task (osc/runtime/control_task.hpp, which includes this header before it defines the type):
/// the functions below take it by reference.
template <class S>
struct ControlTask;

/// The reference of a yielding arm (a collision's reaction yield): the arm's own pose and observed
/// velocity one sample old, no acceleration. Then e = x_{k-1} - x_k and eta = x^dot^_{k-1} - x^dot^_k +
/// k_s e are of the order of one sample's motion, and (32) reduces to the bias force of (35) (gravity,
/// Coriolis and the friction estimate) with the observer's correction and a damping of
/// (k_s + k_nd) k_s dt (about 21 N s/m on x, y, z): no stiffness holds the arm where it was, and the
/// observer (22) still integrates the force that is applied.
template <class S>
Desired<S> yield_reference(const ControlTask<S>& task) {
  Desired<S> d;
  d.x = task.last.x;
  d.xd = task.last.xd_hat;
  d.xdd.setZero();
  return d;
}

/// An identification run's reference (its joint reference, MotionGenerator::excitation_at) in the
/// controller's coordinates, to first order about the pose of the last step (q its angles, x its
/// coordinates, J_a its analytic Jacobian, the task's state.os):
///   x_d = x + J_a (q_r - q),   x_d' = J_a q_r',   x_d'' = J_a q_r'' + Jdot_a(q^')q^',
/// the last with the last step's velocity product at the observed joint rates (state.psi.jdot_yy). The
/// neglected terms are second order in q_r - q, one tick's motion and the tracking error (about 2e-3
/// rad: micrometres), and the controller's (36) error is then J_a (q_r - q), its joint error mapped. The
/// run's end at rest (its last period, or a stop's) holds there (excitation_end).
template <class S>
Desired<S> excitation_reference(ControlTask<S>& task, MotionEvents& ev) {
  const ExcitationStep<S> e = task.gen.excitation_at(task.tick, params::kControlHz);
  const Mat6<S>& Ja = task.state.os.Ja;
  Desired<S> d;
  d.x = task.state.os.x + Ja * Vec6<S>(e.ref.q - task.state.adapt.q_prev);
  d.xd = Ja * e.ref.qd;
  d.xdd = Ja * e.ref.qdd + task.state.psi.jdot_yy;
  return e.at_rest_end ? task.gen.excitation_end(d, ev) : d;
}

/// The limits checked every tick of a motion (a category-2 stop when one is reached): each joint
/// within its limits, the Jacobian's reciprocal condition at least params::kLimitMinRcond. A stream,
/// whose path no check has judged, is stopped where its stop would end at the limit: each joint
/// taken ahead by its rate estimate (one tick old) times the stream's stop lead (the distance its
/// stop covers, as a time d / v; StreamFollower::stop_lead, compared multiplied through by v, without
/// a division), since a joint stopped only at its limit
/// brakes past it (0.11 rad at 0.20 m/s on the PUMA: beyond the encoders' params::kJointLimitMargin).
/// A move's path and the paper's keep params::kWorkspaceMargin from the limits (the path check);
/// theirs is the joint itself, which a move passing near a limit and turning away does not reach.
/// The limits are the motion's (ControlTask::q_lo, q_hi: motion_limits_from): the robot's, widened
/// to params::kLimitStartSlack beyond where the motion found a joint near or past one, so that an
/// arm a stop left at a limit can be moved away from it (as the path check lets a move leave it).
template <class S>
MotionReason motion_limits_reached(const ControlTask<S>& task, const Vec6<S>& q) {
  static constexpr S kMinRcond = lit<S>(params::kLimitMinRcond);
  if (!motion_running(task.machine.state)) return MotionReason::kNone;
  for (int i = 0; i < kDof; ++i)
    if (q(i) < task.q_lo(i) || q(i) > task.q_hi(i)) return MotionReason::kLimitReached;
  const StopLead<S> lead = task.gen.stream_stop_lead();
  if (lead.v > S(0))
    for (int i = 0; i < kDof; ++i) {  // ahead by the stream's stop distance, all times lead.v
      const S ahead = task.state.adapt.qd_hat_prev(i) * lead.d;
      if (ahead < (task.q_lo(i) - q(i)) * lead.v || ahead > (task.q_hi(i) - q(i)) * lead.v)
        return MotionReason::kLimitReached;
    }
  if (task.last.rcond < kMinRcond) return MotionReason::kLimitReached;
  return MotionReason::kNone;
}

/// A collision whose reaction is not category 0 is no fault: taken out of `faults`, it is that
/// reaction's (a category-2 stop or a yield), and the contact is noted until the next motion. Else
/// category 0: the fault stays, or there was no collision.
template <class S>
CollisionReaction take_collision(ControlTask<S>& task, std::uint32_t& faults) {
  if ((faults & kFaultCollision) == 0 || task.collision_reaction == CollisionReaction::kCategory0)
    return CollisionReaction::kCategory0;
  faults &= ~static_cast<std::uint32_t>(kFaultCollision);
  task.contact = true;  // the contact may last
  return task.collision_reaction;
}

/// The tick's category-2 stop request, the first of: a collision (reaction category 2), a reached
/// limit, a stale stream, the board's (request_stop), which it takes.
template <class S>
MotionReason tick_stop_request(ControlTask<S>& task, bool stepped, const Vec6<S>& q, CollisionReaction collision) {
  MotionReason r = collision == CollisionReaction::kCategory2 ? MotionReason::kCollision : MotionReason::kNone;
  if (r == MotionReason::kNone && stepped) r = motion_limits_reached(task, q);
  if (r == MotionReason::kNone && task.gen.stream_stale()) r = MotionReason::kStaleStream;
  if (r == MotionReason::kNone) r = task.stop_request;
  task.stop_request = MotionReason::kNone;
  return r;
}

/// The faults after which the encoders' offsets are no longer trusted: the arm must be homed again.
constexpr std::uint32_t kFaultsUnhoming =
    kFaultEncoderJump | kFaultEncoderRange | kFaultEncoderStuck | kFaultPositionMismatch | kFaultIndexMissing;

/// The command of the tick as the state machine sees it: none while an enable from disabled waits
/// for a measured pose (the supervisor running and a checked sample in this tick: it stays
/// pending), or when preparing refused it (the
/// refusal goes into the report) or it is no longer valid (its plan's epoch passed: superseded; a
/// paper command when the generator does not hold: busy).
template <class S>
MotionCommand motion_command_of_tick(ControlTask<S>& task, bool measured, const Vec6<S>& q) {
  const TaskCommand<S>& cmd = task.pending;
  MotionReport& rep = task.report;
  if (cmd.verb == MotionVerb::kNone) return MotionCommand::kNone;
  if (cmd.verb == MotionVerb::kEnable && task.machine.state == MotionState::kDisabled &&
      (task.sup.state != SupervisorState::kRun || !measured))
    return MotionCommand::kNone;
  if (cmd.verb == MotionVerb::kDeclarePose && !measured) return MotionCommand::kNone;  // it needs the angles now
  // A home, a declare_pose and the enable of an arm not homed (it takes the pots' coarse angles) wait
  // for the pots.
  const bool coarse = cmd.verb == MotionVerb::kHome || cmd.verb == MotionVerb::kDeclarePose ||
                      (cmd.verb == MotionVerb::kEnable && !task.homed);
  if (coarse && task.pots && pots_settling(task)) return MotionCommand::kNone;
  rep.id = cmd.id;
  rep.verb = cmd.verb;
  // An identification run's own refusal (its check's) only where the arm holds: elsewhere the state's
  // (not_enabled, busy, ...), which say what to do first. One that skipped prepare_identify never moves.
  const bool identify = cmd.verb == MotionVerb::kIdentify;
  MotionReason pre = identify && task.machine.state != MotionState::kHolding ? MotionReason::kNone : cmd.refusal;
  if (identify && !cmd.checked) pre = MotionReason::kBadCommand;
  const bool planned = cmd.verb == MotionVerb::kMoveTo || cmd.verb == MotionVerb::kHome;
  if (pre == MotionReason::kNone && planned && cmd.epoch != task.gen.epoch()) pre = MotionReason::kSuperseded;
  if (pre == MotionReason::kNone && cmd.verb == MotionVerb::kHome && !homing_possible(task))
    pre = MotionReason::kNoPots;
  if (pre == MotionReason::kNone && cmd.verb == MotionVerb::kDeclarePose &&
      task.machine.state == MotionState::kDisabled && pots_disagree(task, q, cmd.pose))
    pre = MotionReason::kPotsDisagree;
  if (pre == MotionReason::kNone &&
      (cmd.verb == MotionVerb::kPaper || cmd.verb == MotionVerb::kStream || cmd.verb == MotionVerb::kIdentify) &&
      task.gen.source() != MotionSource::kHold)
    pre = MotionReason::kBusy;
  if (pre == MotionReason::kNone) return verb_command(cmd.verb);
  rep.outcome = CommandOutcome::kRefused;
  rep.refusal = pre;
  return MotionCommand::kNone;
}

/// The moves waiting in the generator's queue, which this tick drops (a re-target's or a stop's
/// brake, a hold, a fault's halt): their ids into the report, after any the tick dropped already
/// (CommandPort::after_tick answers each, aborted dropped). Called only in the ticks that drop.
template <class S>
[[gnu::noinline]] void report_dropped(ControlTask<S>& task) {
  constexpr int kMax = MotionGenerator<S>::kMaxWaiting;
  const int n = task.report.dropped_moves;
  task.report.dropped_moves = static_cast<std::uint8_t>(n + task.gen.waiting_ids(task.dropped_move_ids + n, kMax - n));
}

/// The generator holds the pose the last step measured (the next move's path starts at q); the
/// moves waiting are dropped.
template <class S>
void hold_measured_pose(ControlTask<S>& task, const Vec6<S>& q) {
  report_dropped(task);
  task.gen.hold({task.state.data.o[kDof], task.state.data.R[kDof]}, task.state.R_ref);
  task.q_queue_end = q;
}

/// The motion an abort of this tick ends, into the report: while homing, the home command (its
/// move's end, which the generator reports done in a fault's tick at the end of the move, is not the
/// home's: finish_homing reports that); otherwise the generator's running motion, unless a
/// re-target brakes it (its abort, superseded, was reported: none). A yield (a collision) that a
/// stop, an enable or a disable of the same tick left at once (holding, disabled) ends the motion
/// here, at the measured pose q: motion_apply sees no change into or out of yielding.
template <class S>
[[gnu::noinline]] void report_abort(ControlTask<S>& task, MotionState before, const Vec6<S>& q, bool yield) {
  MotionReport& rep = task.report;
  if (before == MotionState::kHoming) {
    rep.aborted_id = task.homing.id;
    rep.done_id = 0;
  } else {
    rep.aborted_id = task.gen.braking() ? 0 : task.gen.running_id();
  }
  const MotionState s = task.machine.state;
  if (yield && (s == MotionState::kHolding || s == MotionState::kDisabled)) hold_measured_pose(task, q);
}

/// A tick with faults (category 0): an encoder's fault unhomes the arm; the running motion (its
/// abort reported) and the moves waiting (named, dropped) end at once, so that from this tick on
/// nothing runs nor is queued (the state frame's queued and running_id 0) until an enable holds.
template <class S>
[[gnu::noinline]] void fault_motion(ControlTask<S>& task, std::uint32_t faults) {
  if (!has_absolute_encoders(robot::kDriveTrain) && (faults & kFaultsUnhoming) != 0) task.homed = false;
  report_dropped(task);
  task.gen.halt();
}

/// A re-target accepted: the running motion brakes from sample `next` on, aborted superseded (once:
/// not again when it brakes already, for a re-target before), and the moves waiting are dropped.
template <class S>
[[gnu::noinline]] void retarget(ControlTask<S>& task, std::uint64_t next) {
  if (task.gen.source() != MotionSource::kHold && !task.gen.braking()) {
    task.report.aborted_id = task.gen.running_id();
    task.report.abort = MotionReason::kSuperseded;
  }
  report_dropped(task);
  task.gen.brake(next, params::kControlHz, task.limits);
}

/// The joint limits of a motion that starts at q (motion_limits_reached): each joint's, widened to
/// params::kLimitStartSlack beyond q where q is that close to it or past it.
template <class S>
void motion_limits_from(ControlTask<S>& task, const Vec6<S>& q) {
  static constexpr S kSlack = lit<S>(params::kLimitStartSlack);
  for (int i = 0; i < kDof; ++i) {
    const S lo = q(i) - kSlack, hi = q(i) + kSlack;
    task.q_lo(i) = lo < path_check::kQMin<S>[i] ? lo : path_check::kQMin<S>[i];
    task.q_hi(i) = hi > path_check::kQMax<S>[i] ? hi : path_check::kQMax<S>[i];
  }
}

/// What an accepted command and the machine's step ask of the generator and the controller, from
/// the next tick on.
template <class S>
void motion_apply(ControlTask<S>& task, const MotionStep& st, MotionState before, const Vec6<S>& q) {
  const std::uint64_t next = task.tick + 1;
  const bool accepted = st.outcome == CommandOutcome::kAccepted;
  const TaskCommand<S>& cmd = task.pending;
  const bool motion = cmd.verb == MotionVerb::kMoveTo || cmd.verb == MotionVerb::kPaper ||
                      cmd.verb == MotionVerb::kStream || cmd.verb == MotionVerb::kIdentify;
  if (accepted && (motion || cmd.verb == MotionVerb::kClear)) task.contact = false;
  if (accepted && !motion_running(before) && (motion || cmd.verb == MotionVerb::kHome)) motion_limits_from(task, q);
  if (st.enabling) {
    const Vec6<S> q_now = task.homed ? q : coarse_from_pots(task, q);
    controller_restart(task.model, task.state, q_now);
    hold_measured_pose(task, q_now);
    task.stuck.reset(true);
    task.residual.reset();
    task.contact = false;
    task.ramping = true;
    task.ramp_start = next;
  }
  if (accepted && (cmd.verb == MotionVerb::kMoveTo || cmd.verb == MotionVerb::kHome)) {  // a planned move
    if (cmd.brake) retarget(task, next);  // a home starts from holding only
    task.gen.push(cmd.move, cmd.id);
    task.gen.start_moves(next);
    task.q_queue_end = cmd.q_end;
  }
  if (accepted && cmd.verb == MotionVerb::kHome) start_homing(task, cmd.id);
  if (accepted && cmd.verb == MotionVerb::kDeclarePose) declare_pose(task, q, cmd.pose);
  if (before == MotionState::kHoming && st.machine.state != MotionState::kHoming) end_homing(task);
  if (st.completion == MotionCompletion::kHomed) finish_homing(task, q);
  if (accepted && cmd.verb == MotionVerb::kPaper)
    task.gen.start_paper(task.gains.trajectory, next, cmd.id, task.gen.held_orientation());
  if (accepted && cmd.verb == MotionVerb::kStream)
    task.gen.start_stream(cmd.period, cmd.relative, cmd.limits, cmd.id, task.stream_timeout_ticks);
  if (accepted && cmd.verb == MotionVerb::kIdentify) {
    // The run's orientation coordinates are those of where it starts (its check's, prepare_identify_at), wherever
    // the enable was: the controller re-referenced here, at rest, and the pose held in them.
    controller_rereference(task.state, q);
    hold_measured_pose(task, q);
    task.gen.start_excitation(cmd.excitation, next, cmd.id);
    task.identify.accept(cmd.id, cmd.payload);  // its sampler starts again at the run's first tick, whatever the id
  }
  // Into yielding, the motion is dropped; out of it, the pose reached is held.
  if ((st.machine.state == MotionState::kYielding) != (before == MotionState::kYielding)) hold_measured_pose(task, q);
  if (st.machine.state == MotionState::kStopping && before != MotionState::kStopping) {
    report_dropped(task);
    task.gen.stop(next, params::kControlHz, task.limits);
    task.q_queue_end = q;  // near where the stop ends: the next check's Newton steps start the path there
  }
  if (accepted && cmd.verb == MotionVerb::kClear) {
    task.sup = {SupervisorState::kInit, 0};
    task.stuck.reset(true);  // from this tick's torques: a clear while holding is no torque change
    task.residual.reset();
    task.saturation.reset();
    task.oscillation.reset();
    task.position.reset();  // learnt again from the next samples (an encoder fault also unhomed the arm)
  }
  if (!motion_powered(st.machine.state)) task.ramping = false;
}

/// The motion stage at the end of a tick: the tick's command, faults and the generator's events
/// through the state machine (motion_next), then what it decided (motion_apply). Returns whether
/// torque may reach the DACs in this tick.
template <class S>
bool motion_update(ControlTask<S>& task, std::uint32_t faults, bool measured, const Vec6<S>& q, const MotionEvents& ev,
                   MotionReason stop_request, bool yield) {
  task.report = {};
  MotionInput in;
  in.command = motion_command_of_tick(task, measured, q);
  in.homed = task.homed;
  in.faults = faults;
  in.latched = task.sup.latched;  // the one latch: the supervisor's, this tick's faults in it (stage_decide)
  in.stop_request = stop_request;
  in.yield = yield;
  in.motion_finished = ev.finished;
  in.stopped = ev.stopped;
  const MotionState before = task.machine.state;
  const MotionStep st = motion_next(task.machine, in);
  task.machine = st.machine;
  MotionReport& rep = task.report;
  if (in.command != MotionCommand::kNone) {
    rep.outcome = st.outcome;
    rep.refusal = st.refusal;
    rep.cause = st.cause;
  }
  rep.abort = st.abort;
  rep.completion = st.completion;
  rep.done_id = ev.done_id;
  if (st.abort != MotionReason::kNone) report_abort(task, before, q, yield);
  if (faults != 0) fault_motion(task, faults);
  motion_apply(task, st, before, q);
  task.identify.note_end(rep.done_id, rep.aborted_id);                       // an identify run's end, for the main loop
  if (rep.verb != MotionVerb::kNone) task.pending.verb = MotionVerb::kNone;  // answered: taken
  return st.torque;
}

}  // namespace osc
