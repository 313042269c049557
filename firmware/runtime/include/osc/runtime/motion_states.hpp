// The motion state machine (issue 23): a pure function from (machine, one tick's command and events)
// to the next machine and what the tick must do: accept or refuse the command with a named reason,
// the stop category in effect, torque on or off, capture the pose to hold, report an aborted or a
// completed motion. The tick's motion stage runs it (osc/runtime/motion_stage.hpp).
//
// How it combines with the Supervisor (osc/runtime/supervisor.hpp): the supervisor is the
// category-0 latch below this machine, and the one latch of fault bits (Supervisor::latched): the
// machine keeps none, it reads the supervisor's (MotionInput::latched) for its fault rows and a
// refusal's cause. A tick's fault bits go to both, and both are in fault in that tick; torque
// reaches the DACs only when both allow it (torque_enabled(sup) && step.torque).
// The runtime passes an enable only once the supervisor runs (kRun: a measured pose exists to hold).
// supervisor_next never leaves kFault, so a clear that this machine accepts (causes gone) is the one
// event on which the runtime re-initialises the supervisor ({kInit, 0}, with the task's init at the
// measured pose); the next enable starts the observer there (MotionStep::enabling).
//
// Stop categories (IEC 60204-1): a fault is category 0 (zero torque, amplifiers off, at once); a stop
// command, a stale stream or a reached limit is category 2 (decelerate along the path within the
// limits, then hold with power on). A disable while moving is the same deceleration, then the torque
// off at rest: category 1 in the standard's terms, reported tick by tick as category 2 while it
// decelerates. Disabling cuts the torque of every joint: the brakes (joints 1 to 3 of a PUMA) and a
// supported wrist are the integration's concern.
#pragma once

#include <cstdint>

#include "osc/control/faults.hpp"  // OSC_X_NAME, OSC_X_DOC, OSC_X_ENUMERATOR

namespace osc {

// X(Name, "name", meaning), in code order (each list below is declared once, by OSC_MOTION_ENUM).
#define OSC_MOTION_STATE_LIST(X)                                                                                    \
  X(Disabled, "disabled", "no torque, no fault: an enable holds the measured pose")                                 \
  X(Holding, "holding", "torque on, holding the pose captured on entry, the observer running")                      \
  X(Moving, "moving", "following the motion generator (move_to, stream, paper, queued moves)")                      \
  X(Stopping, "stopping", "category-2 stop: decelerating along the path to rest, torque on")                        \
  X(Fault, "fault", "category-0 stop: zero torque, amplifiers off; sticky until a clear")                           \
  X(Yielding, "yielding", "a collision's reaction yield: gravity, Coriolis and friction compensated, no stiffness") \
  X(Homing, "homing", "torque on, each motor turning up to one revolution to its index pulse (a home command)")

#define OSC_MOTION_COMMAND_LIST(X)                                                           \
  X(None, "none", "no command this tick (a code outside this list counts as none)")          \
  X(Enable, "enable", "torque on, holding the measured pose (observer started there)")       \
  X(Disable, "disable", "torque off; from a motion, after a category-2 stop to rest")        \
  X(Move, "move", "any motion: move_to, stream, the paper's trajectory, a queued move")      \
  X(Stop, "stop", "category-2 stop of the motion, then hold")                                \
  X(Clear, "clear", "leave fault for disabled, once no fault cause is present")              \
  X(Home, "home", "find each encoder's index pulse from the pots' coarse angles, then hold") \
  X(DeclarePose, "declare_pose", "the operator asserts the arm stands at a named pose (torque off)")

/// Why a command was refused or a running motion aborted. The geometric ones are decided by the
/// motion generator, which refuses with them after this machine accepted; `dropped` by the runtime,
/// for each move taken from the queue before it started (the tick that stopped, re-targeted or
/// faulted the motion ahead of it names each: MotionReport::dropped_moves); motion_next() decides
/// the rest.
#define OSC_MOTION_REASON_LIST(X)                                                                                   \
  X(None, "none", "not refused, not aborted")                                                                       \
  X(OutOfWorkspace, "out_of_workspace", "the target is outside the workspace (motion generator)")                   \
  X(NearSingular, "near_singular", "the path passes too near a singular pose (motion generator)")                   \
  X(OverLimit, "over_limit", "a joint, speed or acceleration limit would be exceeded (motion generator)")           \
  X(QueueFull, "queue_full", "no room in the motion queue (motion generator)")                                      \
  X(NotEnabled, "not_enabled", "a move or a stop while disabled: enable first")                                     \
  X(Faulted, "faulted", "in fault, or a fault aborted the motion; the cause is in MotionStep::cause")               \
  X(Stopping, "stopping", "a move during a category-2 stop: sent again once at rest (completion stopped)")          \
  X(StopCommand, "stop_command", "a stop command aborted the motion")                                               \
  X(DisableCommand, "disable_command", "a disable command aborted the motion (stop, then disabled)")                \
  X(StaleStream, "stale_stream", "the runtime stopped the motion: its stream of setpoints went stale")              \
  X(LimitReached, "limit_reached", "the runtime stopped the motion: a limit was reached")                           \
  X(Busy, "busy", "a paper or stream command while a motion runs, a move_to while a stream runs: stop it, or wait") \
  X(Superseded, "superseded", "a re-target replaced the motion; or the queue changed before the command's tick")    \
  X(BadCommand, "bad_command",                                                                                      \
    "a bad command frame: a verb or flag outside its list, a non-finite number, a bound exceeded, a limit <= 0")    \
  X(LinkSilent, "link_silent", "the board's command link went silent while a motion ran: category-2 stop")          \
  X(Collision, "collision", "the runtime stopped the motion: a collision, its reaction category_2 or yield")        \
  X(Yielding, "yielding", "a move while yielding to a collision: a stop or an enable holds the pose first")         \
  X(NotHomed, "not_homed", "a motion before the encoders' offsets are known: home, or declare_pose, first")         \
  X(NoPots, "no_pots", "a home on an arm without potentiometers (parameter pots 0, or none read): declare_pose")    \
  X(PotsDisagree, "pots_disagree",                                                                                  \
    "a declare_pose whose pose a potentiometer contradicts by more than params::kDeclareBand (2 degrees)")          \
  X(TorqueOn, "torque_on", "a declare_pose while the torque is on: disable first")                                  \
  X(UnknownPose, "unknown_pose", "a declare_pose of a pose code outside the robot's list of named poses")           \
  X(Dropped, "dropped",                                                                                             \
    "a queued move that never started: the motion ahead of it was stopped, re-targeted or faulted")                 \
  X(NotNeeded, "not_needed",                                                                                        \
    "a home or a declare_pose on an arm with absolute encoders: its angles are known from power-on")                \
  X(UnstableLoop, "unstable_loop",                                                                                  \
    "the path passes a pose where the gains would make the sampled closed loop unstable (motion generator)")

#define OSC_COMMAND_OUTCOME_LIST(X)                   \
  X(None, "none", "no command this tick")             \
  X(Accepted, "accepted", "the command was accepted") \
  X(Refused, "refused", "the command was refused, for the reason named")

#define OSC_STOP_CATEGORY_LIST(X)                                                              \
  X(None, "none", "no stop in effect")                                                         \
  X(Category0, "category_0", "uncontrolled stop: zero torque and amplifiers off in this tick") \
  X(Category2, "category_2", "controlled stop: decelerate along the path within the limits, then hold")

#define OSC_MOTION_COMPLETION_LIST(X)                                                              \
  X(None, "none", "nothing completed this tick")                                                   \
  X(Finished, "finished", "the motion finished: the generator's queue ran empty at rest; holding") \
  X(Stopped, "stopped", "a category-2 stop reached rest; holding, or disabled after a disable")    \
  X(Homed, "homed", "homing found every index pulse: the encoders' offsets are set; holding")

/// What a detected collision does (the residual monitor's collision, osc/runtime/monitors.hpp); an
/// encoder or a drive fault is always category 0.
#define OSC_COLLISION_REACTION_LIST(X)                                                                \
  X(Category0, "category_0", "a fault: zero torque and amplifiers off in this tick (the default)")    \
  X(Category2, "category_2", "a moving arm decelerates along its path within the limits, then holds") \
  X(Yield, "yield", "gravity, Coriolis and friction compensation only, so that a person can push the arm away")

/// The names, meanings and count of an enumeration declared by OSC_MOTION_ENUM, in code order.
template <class E>
struct MotionNames;

// enum class Type { kName, ... } from an X-macro list, and MotionNames<Type>.
#define OSC_X_PREFIX k
#define OSC_MOTION_ENUM(Type, LIST)                                 \
  enum class Type : std::uint8_t { LIST(OSC_X_ENUMERATOR) };        \
  template <>                                                       \
  struct MotionNames<Type> {                                        \
    static constexpr const char* kNames[] = {LIST(OSC_X_NAME)};     \
    static constexpr const char* kDocs[] = {LIST(OSC_X_DOC)};       \
    static constexpr int kCount = sizeof(kNames) / sizeof(*kNames); \
  }
OSC_MOTION_ENUM(MotionState, OSC_MOTION_STATE_LIST);
OSC_MOTION_ENUM(MotionCommand, OSC_MOTION_COMMAND_LIST);
OSC_MOTION_ENUM(MotionReason, OSC_MOTION_REASON_LIST);
OSC_MOTION_ENUM(CommandOutcome, OSC_COMMAND_OUTCOME_LIST);
OSC_MOTION_ENUM(StopCategory, OSC_STOP_CATEGORY_LIST);
OSC_MOTION_ENUM(MotionCompletion, OSC_MOTION_COMPLETION_LIST);
OSC_MOTION_ENUM(CollisionReaction, OSC_COLLISION_REACTION_LIST);
#undef OSC_X_PREFIX  // OSC_MOTION_ENUM stays defined: motion_commands.hpp declares its verbs with it

// A list that grows fails here: motion_next() and its table must say what the new entry does.
static_assert(MotionNames<MotionState>::kCount == static_cast<int>(MotionState::kHoming) + 1);
static_assert(MotionNames<MotionCommand>::kCount == static_cast<int>(MotionCommand::kDeclarePose) + 1);
static_assert(MotionNames<MotionReason>::kCount == static_cast<int>(MotionReason::kUnstableLoop) + 1);
static_assert(MotionNames<CommandOutcome>::kCount == static_cast<int>(CommandOutcome::kRefused) + 1);
static_assert(MotionNames<StopCategory>::kCount == static_cast<int>(StopCategory::kCategory2) + 1);
static_assert(MotionNames<MotionCompletion>::kCount == static_cast<int>(MotionCompletion::kHomed) + 1);
static_assert(MotionNames<CollisionReaction>::kCount == static_cast<int>(CollisionReaction::kYield) + 1);

/// The name of a code of one of these enumerations ("?" for a code outside its list).
template <class E>
constexpr const char* motion_name(E e) {
  const auto i = static_cast<unsigned>(e);
  return i < MotionNames<E>::kCount ? MotionNames<E>::kNames[i] : "?";
}

struct MotionMachine {
  MotionState state = MotionState::kDisabled;
  bool disable_at_rest = false;  ///< kStopping only: the stop ends in kDisabled, not kHolding
};

/// One tick's command and events.
struct MotionInput {
  MotionCommand command = MotionCommand::kNone;
  std::uint32_t faults = 0;  ///< fault bits detected in this tick (category 0), in the catalogue or not
  /// The fault bits latched since the last accepted clear: the supervisor's (Supervisor::latched, the
  /// one latch), this tick's faults among them or not (the machine adds them).
  std::uint32_t latched = 0;
  std::uint32_t causes = 0;  ///< fault conditions still present (e.g. the E-stop held): a clear needs none
  /// The runtime's category-2 stop of a motion (kStaleStream, kLimitReached, kLinkSilent); kNone: no request.
  MotionReason stop_request = MotionReason::kNone;
  bool motion_finished = false;  ///< the generator's queue ran empty at rest
  bool stopped = false;          ///< the category-2 deceleration reached rest
  bool yield = false;            ///< a collision whose reaction is yield (CollisionReaction::kYield)
  bool homed = true;             ///< the encoders' offsets are known (homing, declare_pose): motion allowed
};

/// The next machine and what the tick does.
struct MotionStep {
  MotionMachine machine;
  CommandOutcome outcome = CommandOutcome::kNone;  ///< of this tick's command
  MotionReason refusal = MotionReason::kNone;      ///< why it was refused (kNone unless refused)
  /// With a refusal `faulted`: the bits behind it (a clear's: those present now; else the latched,
  /// this tick's included).
  std::uint32_t cause = 0;
  MotionReason abort = MotionReason::kNone;  ///< a running motion was aborted in this tick, and why
  MotionCompletion completion = MotionCompletion::kNone;
  StopCategory stop = StopCategory::kNone;  ///< the stop in effect after this tick
  bool torque = false;                      ///< torque on in this tick's output (off in a fault's tick)
  bool capture_pose = false;                ///< entered kHolding: hold the measured pose from now on
  bool enabling = false;                    ///< enabled: start the observer at the measured pose, ramp torque in
};

/// A motion runs: a client's (moving) or homing's. Both end in holding, or stop like a motion.
constexpr bool motion_running(MotionState s) { return s == MotionState::kMoving || s == MotionState::kHoming; }

/// The states with the torque on: the control step runs and torque reaches the DACs (the supervisor
/// allowing). The one list of them: motion_next's torque, the tick's step, the enable's ramp, the
/// parameters written only with the torque off (param_torque_off), the simulated arm's brakes.
constexpr bool motion_powered(MotionState s) {
  return s == MotionState::kHolding || motion_running(s) || s == MotionState::kStopping || s == MotionState::kYielding;
}
/// The torque known to be off: a state of the list not powered (disabled, fault); a state code
/// outside the list is not known to be off.
constexpr bool motion_torque_off(MotionState s) {
  return static_cast<int>(s) < MotionNames<MotionState>::kCount && !motion_powered(s);
}

namespace detail {

constexpr bool motion_state_known(MotionState s) { return static_cast<int>(s) < MotionNames<MotionState>::kCount; }

/// A machine in fault (or faulting now, or unreadable): only a clear with no cause present leaves it.
constexpr MotionStep motion_fault_tick(const MotionMachine& m, const MotionInput& in, MotionCommand c) {
  MotionStep r{};
  if (motion_running(m.state)) r.abort = MotionReason::kFaulted;
  const std::uint32_t present = in.faults | in.causes;
  if (c == MotionCommand::kClear && present == 0) {
    r.machine = {MotionState::kDisabled, false};
    r.outcome = CommandOutcome::kAccepted;
    return r;
  }
  r.machine = {MotionState::kFault, false};
  r.stop = StopCategory::kCategory0;
  if (c == MotionCommand::kNone) return r;
  r.outcome = CommandOutcome::kRefused;
  r.refusal = MotionReason::kFaulted;
  r.cause = c == MotionCommand::kClear ? present : in.latched | in.faults;
  return r;
}

/// The events of the tick, in order: the generator's reports (finished, stopped), then the
/// runtime's stop request. A state they do not name ignores them.
constexpr MotionStep motion_events(const MotionMachine& m, const MotionInput& in) {
  MotionStep r{};
  r.machine = {m.state, m.state == MotionState::kStopping && m.disable_at_rest};
  if (in.yield && m.state != MotionState::kDisabled) {
    // A collision to yield to: whatever the arm did (a motion, its stop), it now gives way.
    r.machine = {MotionState::kYielding, false};
    if (motion_running(m.state)) r.abort = MotionReason::kCollision;
  } else if (motion_running(m.state) && in.motion_finished) {
    r.machine.state = MotionState::kHolding;
    r.completion = m.state == MotionState::kHoming ? MotionCompletion::kHomed : MotionCompletion::kFinished;
  } else if (motion_running(m.state) && in.stop_request != MotionReason::kNone) {
    r.machine.state = MotionState::kStopping;
    r.abort = in.stop_request;
  } else if (m.state == MotionState::kStopping && in.stopped) {
    r.machine = {m.disable_at_rest ? MotionState::kDisabled : MotionState::kHolding, false};
    r.completion = MotionCompletion::kStopped;
  }
  return r;
}

constexpr void motion_refuse(MotionStep& r, MotionReason why) {
  r.outcome = CommandOutcome::kRefused;
  r.refusal = why;
}

/// Starts a category-2 stop of a motion in progress (the first abort of a tick names it).
constexpr void motion_stop(MotionStep& r, MotionReason why) {
  r.machine.state = MotionState::kStopping;
  if (r.abort == MotionReason::kNone) r.abort = why;
}

/// A move's or a home's refusal in a state with the torque on (none: it may start).
constexpr MotionReason motion_start_refusal(MotionState s) {
  if (s == MotionState::kStopping) return MotionReason::kStopping;
  if (s == MotionState::kYielding) return MotionReason::kYielding;
  return MotionReason::kNone;
}

/// The command, on the state the events left (the table of motion_next()).
constexpr void motion_command(MotionStep& r, MotionCommand c, bool homed) {
  MotionMachine& m = r.machine;
  r.outcome = c == MotionCommand::kNone ? CommandOutcome::kNone : CommandOutcome::kAccepted;
  const bool disabled = m.state == MotionState::kDisabled;
  const MotionReason blocked = disabled ? MotionReason::kNotEnabled : motion_start_refusal(m.state);
  switch (c) {
    case MotionCommand::kEnable:
      r.enabling = disabled;
      if (disabled || m.state == MotionState::kYielding) m.state = MotionState::kHolding;
      m.disable_at_rest = false;
      return;
    case MotionCommand::kDisable:
      if (m.state == MotionState::kHolding || m.state == MotionState::kYielding) m.state = MotionState::kDisabled;
      if (motion_running(m.state)) motion_stop(r, MotionReason::kDisableCommand);
      m.disable_at_rest = m.state == MotionState::kStopping;
      return;
    case MotionCommand::kMove:
      if (blocked != MotionReason::kNone) return motion_refuse(r, blocked);
      if (m.state == MotionState::kHoming) return motion_refuse(r, MotionReason::kBusy);
      if (!homed) return motion_refuse(r, MotionReason::kNotHomed);
      m.state = MotionState::kMoving;
      return;
    case MotionCommand::kStop:
      if (disabled) return motion_refuse(r, MotionReason::kNotEnabled);
      if (motion_running(m.state)) motion_stop(r, MotionReason::kStopCommand);
      if (m.state == MotionState::kYielding) m.state = MotionState::kHolding;
      return;
    case MotionCommand::kHome:
      if (blocked != MotionReason::kNone) return motion_refuse(r, blocked);
      if (m.state == MotionState::kMoving) return motion_refuse(r, MotionReason::kBusy);
      m.state = MotionState::kHoming;
      return;
    case MotionCommand::kDeclarePose:
      if (!disabled) return motion_refuse(r, MotionReason::kTorqueOn);
      return;
    case MotionCommand::kNone:
    case MotionCommand::kClear:
      return;
  }
}

}  // namespace detail

/// Transition table. One tick: the fault rows first; otherwise the events, then the command on the
/// state they left.
///   any state, faults != 0, or latched != 0 (the supervisor's), or a state code outside the list:
///                                -> fault (a bit outside the catalogue too);
///                                   category 0, torque off in this tick; a motion in progress is
///                                   aborted: faulted; a command is refused: faulted (cause: latched | faults)
///   fault, clear, faults | causes == 0   -> disabled, accepted (the runtime clears the supervisor's latch)
///   fault, clear, a cause present        -> fault, refused: faulted (cause: faults | causes)
///   events (states not named ignore them):
///   moving, motion finished              -> holding, completion finished, pose captured
///   homing, motion finished              -> holding, completion homed, pose captured
///   moving, homing, stop requested (r)   -> stopping, category 2, motion aborted: r
///   stopping, stopped                    -> holding (pose captured), or disabled if a disable is
///                                           pending; completion stopped
///   holding, moving, homing, stopping, yielding, yield (a collision, reaction yield; before the events above)
///                                        -> yielding, a pending disable dropped; moving, homing: aborted collision
///   commands (= : stays, accepted; a command code outside the list is none):
///              enable            disable                  move                 stop
///   disabled   holding, enabling =                        refused not_enabled  refused not_enabled
///   holding    =                 disabled                 moving [3]           =
///   moving     =                 stopping, pending [1]    = (re-target/queue)  stopping [2]
///   homing     =                 stopping, pending [1]    refused busy         stopping [2]
///   stopping   =, not pending    =, pending               refused stopping     =
///   yielding   holding           disabled                 refused yielding     holding
///              home                  declare_pose
///   disabled   refused not_enabled   = [4]
///   holding    homing                refused torque_on
///   moving     refused busy          refused torque_on
///   homing     =                     refused torque_on
///   stopping   refused stopping      refused torque_on
///   yielding   refused yielding      refused torque_on
///   clear: = in every state but fault.
///   [1] aborted: disable_command; at rest, disabled.  [2] aborted: stop_command.
///   [3] refused not_homed until the encoders' offsets are known (MotionInput::homed).
///   [4] the runtime sets the offsets from the named pose (declare_pose, after its pots check).
/// The states with the torque on are motion_powered's.
/// Torque is on in holding, moving, homing, stopping, yielding; the stop in effect is category 0 in fault, 2 in
/// stopping (yielding is a reaction, not a stop: none). The pose is captured whenever holding is entered (enable,
/// finished, stopped). Decisions: a command whose end state already holds is accepted and does nothing (enable when
/// enabled, disable when disabled, stop when holding or stopping, clear outside fault): repeating
/// one is harmless. A move or a stop while disabled is refused (not_enabled): nothing holds the arm,
/// and the client must know. A move while stopping is refused (stopping): the stop must reach rest first, or a
/// stale stream's or a reached limit's stop would be overridden by the next setpoint, and the move
/// would be planned from a state still decelerating; it is sent again after the completion
/// `stopped`. An enable while stopping to disable cancels the disable (the last command wins; the
/// stop still ends at rest, holding). In fault, every command but clear is refused (faulted): the
/// client learns that the arm is in a category-0 stop, and a disable is no way around a clear.
/// A motion is aborted once, with the reason of the tick that ended it: a fault during a stop
/// aborts nothing more (the stop's completion never comes; the fault is the report), and a stop
/// request in the tick a motion finished at rest is ignored (holding, nothing to stop).
constexpr MotionStep motion_next(const MotionMachine& m, const MotionInput& in) {
  const bool known_command = static_cast<int>(in.command) < MotionNames<MotionCommand>::kCount;
  const MotionCommand c = known_command ? in.command : MotionCommand::kNone;
  if ((in.faults | in.latched) != 0 || m.state == MotionState::kFault || !detail::motion_state_known(m.state))
    return detail::motion_fault_tick(m, in, c);
  MotionStep r = detail::motion_events(m, in);
  detail::motion_command(r, c, in.homed);
  const MotionState s = r.machine.state;
  r.stop = s == MotionState::kStopping ? StopCategory::kCategory2 : StopCategory::kNone;
  r.torque = motion_powered(s);
  r.capture_pose = s == MotionState::kHolding && m.state != MotionState::kHolding;
  return r;
}

}  // namespace osc
