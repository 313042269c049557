// The command protocol's payloads (issue 23), declared once each as a field list like the sensor
// and actuator frames' (osc/link/frames.hpp, which includes this file and makes the structs, their
// encoding and decoding, the payload lengths and the protocol document's tables from them):
//
//   command  host -> controller   a client's command: a verb, move_to's target, options and limits
//   answer   controller -> host   a tick's report: the answer to a command, a motion done or aborted
//   state    controller -> host   the motion state, the latched faults, the reference and measured pose
//   setpoint host -> controller   one sample of a stream (the stream command started it)
//   trace    controller -> host   a tick's reference in the controller's own coordinates and its faults,
//                                 for a host that checks the run against its own (scripts under QEMU)
//
// The conversions between these frames and the control task's commands and reports are in
// osc/link/commands.hpp. Macros and constants only: no dependency beyond the fault catalogue's
// X-macro helpers.
#pragma once

#include <cstdint>

#include "osc/control/faults.hpp"  // OSC_X_NAME, OSC_X_DOC, OSC_X_ENUMERATOR

namespace pil {

// X(Name, "name", meaning): the command frame's flag bits, bit k for the k-th entry. They qualify a
// move_to (relative and has_limits a stream too; payload an identify); other verbs ignore them. A bit
// outside this list makes the command bad_command.
#define OSC_COMMAND_FLAG_LIST(X)                                                                                      \
  X(Relative, "relative",                                                                                             \
    "position is an offset from where the queue ends, rpy a rotation applied to its orientation (both in "            \
    "the base frame); otherwise both are absolute. stream: its setpoints are, from the pose it starts at")            \
  X(HasRpy, "has_rpy", "rpy gives the target orientation; otherwise the orientation stays as it is")                  \
  X(Replace, "replace",                                                                                               \
    "re-target: brake the running motion along its path, drop the queued moves, move from where it comes to "         \
    "rest; otherwise the move is queued")                                                                             \
  X(HasLimits, "has_limits", "limits apply to this move or stream; otherwise the configured maxima (Command checks)") \
  X(Payload, "payload",                                                                                               \
    "identify: estimate the payload at the flange too, all ten of its inertial parameters (an identify_payload "      \
    "frame follows the identify frame)")

// The masks of a list of flag bits: `LIST(OSC_X_FLAG_MASK)` with OSC_X_PREFIX the bits' prefix
// (the enumerators) and OSC_X_MASK the masks'.
#define OSC_X_FLAG_MASK(Name, name, doc) \
  constexpr std::uint8_t OSC_X_CAT(OSC_X_MASK, Name) = static_cast<std::uint8_t>(1u << OSC_X_CAT(OSC_X_PREFIX, Name));

#define OSC_X_PREFIX kFlagBit
#define OSC_X_MASK kFlag
enum CommandFlagBit : std::uint8_t { OSC_COMMAND_FLAG_LIST(OSC_X_ENUMERATOR) kCommandFlagCount };
OSC_COMMAND_FLAG_LIST(OSC_X_FLAG_MASK)
#undef OSC_X_MASK
#undef OSC_X_PREFIX
static_assert(kCommandFlagCount <= 8, "the flags fit their byte");
/// Every defined flag bit.
constexpr std::uint8_t kCommandFlagsKnown = static_cast<std::uint8_t>((1u << kCommandFlagCount) - 1u);
/// Names and meanings of the flags, in bit order.
constexpr const char* kCommandFlagNames[kCommandFlagCount] = {OSC_COMMAND_FLAG_LIST(OSC_X_NAME)};
constexpr const char* kCommandFlagDocs[kCommandFlagCount] = {OSC_COMMAND_FLAG_LIST(OSC_X_DOC)};

// X(Name, "name", meaning): the setpoint frame's flag bits, bit k for the k-th entry. A bit outside
// this list makes the setpoint bad (dropped and counted).
#define OSC_SETPOINT_FLAG_LIST(X)                                                                 \
  X(End, "end", "the stream's last setpoint: the arm comes to rest there and the stream is done") \
  X(HasRpy, "has_rpy", "rpy gives the orientation; otherwise it stays as the stream started")

#define OSC_X_PREFIX kSetpointBit
#define OSC_X_MASK kSetpoint
enum SetpointFlagBit : std::uint8_t { OSC_SETPOINT_FLAG_LIST(OSC_X_ENUMERATOR) kSetpointFlagCount };
OSC_SETPOINT_FLAG_LIST(OSC_X_FLAG_MASK)
#undef OSC_X_MASK
#undef OSC_X_PREFIX
constexpr std::uint8_t kSetpointFlagsKnown = static_cast<std::uint8_t>((1u << kSetpointFlagCount) - 1u);
constexpr const char* kSetpointFlagNames[kSetpointFlagCount] = {OSC_SETPOINT_FLAG_LIST(OSC_X_NAME)};
constexpr const char* kSetpointFlagDocs[kSetpointFlagCount] = {OSC_SETPOINT_FLAG_LIST(OSC_X_DOC)};

/// A stream's period in ticks (1 ms): 1 to kStreamMaxPeriod (1 kHz to 10 Hz), else bad_command.
constexpr int kStreamMaxPeriod = 100;

/// The bounds a command frame's numbers must be within (else bad_command): each coordinate of
/// `position` within +-kCommandMaxPosition [m], each angle of `rpy` within +-kCommandMaxAngle [rad]
/// (2 pi), every number finite, and with has_limits every limit above 0.
constexpr double kCommandMaxPosition = 10.0;
constexpr double kCommandMaxAngle = 6.283185307179586;
/// A setpoint_velocity frame's velocities within +-kCommandMaxVelocity [m/s, rad/s] (else the
/// setpoint is bad: dropped and counted).
constexpr double kCommandMaxVelocity = 10.0;

// The field lists, X(type, name, extent, unit, meaning) as in frames.hpp. The references in
// parentheses name the protocol document's tables.
#define OSC_COMMAND_FIELDS(X)                                                                                 \
  X(std::uint32_t, id, , "",                                                                                  \
    "the client's number for the command, echoed in its answer and, for a motion, in done_id or aborted_id; " \
    "use nonzero numbers (0 there means none)")                                                               \
  X(std::uint8_t, verb, , "", "what to do (Verbs)")                                                           \
  X(std::uint8_t, flags, , "", "move_to's options, one bit each (Command flags)")                             \
  X(float, position, [3], "m",                                                                                \
    "move_to: the target position of the wrist centre in the base frame (with relative: the offset)")         \
  X(float, rpy, [3], "rad",                                                                                   \
    "move_to with has_rpy: roll, pitch, yaw of the target orientation, R = Rz(yaw) Ry(pitch) Rx(roll) "       \
    "(with relative: of the rotation applied)")                                                               \
  X(float, limits, [6], "m/s, m/s^2, m/s^3, rad/s, rad/s^2, rad/s^3",                                         \
    "move_to or stream with has_limits: the linear speed, acceleration and jerk, then the angular speed, "    \
    "acceleration and jerk; each at most the configured maximum (Command checks)")                            \
  X(std::uint8_t, period, , "ms",                                                                             \
    "stream: the setpoints' period, 1 to 100 ms (1 kHz to 10 Hz); declare_pose: the pose's code (Poses); "    \
    "other verbs ignore it")

#define OSC_SETPOINT_FIELDS(X)                                                                                    \
  X(std::uint32_t, id, , "", "the id of the stream command whose stream this is (others' setpoints are dropped)") \
  X(std::uint8_t, flags, , "", "end, has_rpy (Setpoint flags)")                                                   \
  X(float, position, [3], "m",                                                                                    \
    "the wrist centre in the base frame (the stream's relative flag: the offset from where it started)")          \
  X(float, rpy, [3], "rad",                                                                                       \
    "with has_rpy: roll, pitch, yaw of the orientation, as move_to's (relative: of the rotation applied)")

// The setpoint with its velocity: the setpoint frame's fields, then the velocity.
#define OSC_SETPOINT_VELOCITY_FIELDS(X)                                                                          \
  OSC_SETPOINT_FIELDS(X)                                                                                         \
  X(float, velocity, [6], "m/s, rad/s",                                                                          \
    "the setpoint's velocity: the wrist centre's, then the angular velocity, both in the base frame (relative: " \
    "of the offset and of the rotation applied); each within +-kCommandMaxVelocity; without has_rpy the "        \
    "angular velocity is taken as 0, with end all of it")

#define OSC_ANSWER_FIELDS(X)                                                                                   \
  X(std::uint32_t, id, , "", "the id of the command answered in this tick; 0 when none was")                   \
  X(std::uint8_t, verb, , "", "its verb (Verbs); none when no command was answered")                           \
  X(std::uint8_t, outcome, , "", "accepted or refused; none when no command was answered (Command outcomes)")  \
  X(std::uint8_t, refusal, , "", "why the command was refused (Reasons); none unless refused")                 \
  X(std::uint32_t, cause, , "", "with refusal faulted: the fault bits behind it (Fault bits)")                 \
  X(std::uint32_t, done_id, , "",                                                                              \
    "the id of a motion done in this tick: a move_to at its target at rest, a stream at its last setpoint, a " \
    "home with every index pulse found; 0: none")                                                              \
  X(std::uint32_t, aborted_id, , "",                                                                           \
    "the id of a motion (move_to, paper, stream, home) aborted in this tick, or of a queued move dropped "     \
    "(abort dropped: a frame of its own); 0: none, a motion without an id, or one aborted already (the "       \
    "motion a re-target brakes)")                                                                              \
  X(std::uint8_t, abort, , "",                                                                                 \
    "why a running motion was aborted in this tick, or dropped for a queued move (Reasons); none: no abort")   \
  X(std::uint8_t, completion, , "", "a motion that came to rest in this tick (Completions)")                   \
  X(std::uint8_t, state, , "", "the motion state after this tick (Motion states)")                             \
  X(std::uint8_t, stop, , "", "the stop in effect after this tick (Stop categories)")                          \
  X(std::uint8_t, queued, , "",                                                                                \
    "moves in the motion queue after this tick, the running one included; 0 in fault and disabled")            \
  X(std::uint32_t, tick, , "tick", "the number of the tick that answered (0: the first), low 32 bits")

#define OSC_STATE_FIELDS(X)                                                                                     \
  X(std::uint8_t, state, , "", "the motion state (Motion states)")                                              \
  X(std::uint8_t, stop, , "", "the stop in effect (Stop categories)")                                           \
  X(std::uint32_t, faults, , "", "the fault bits latched since the last accepted clear (Fault bits)")           \
  X(std::uint8_t, queued, , "", "moves in the motion queue, the running one included; 0 in fault, disabled")    \
  X(std::uint32_t, running_id, , "",                                                                            \
    "the id of the running motion (move_to, stream, paper, home; braking after a stop or a re-target too); "    \
    "0: none, always in fault and disabled")                                                                    \
  X(std::uint32_t, dropped, , "", "setpoints dropped since start: no stream of their id running, or bad")       \
  X(float, x_d, [6], "m, rad",                                                                                  \
    "the reference pose of the last control step: the wrist centre's position in the base frame, then roll, "   \
    "pitch, yaw of the orientation as move_to's absolute rpy")                                                  \
  X(float, x, [6], "m, rad", "the measured pose of the last control step, the same way")                        \
  X(std::uint32_t, tick, , "tick",                                                                              \
    "the number of the last tick run (0: the first; 0xFFFFFFFF before it), low 32 bits")                        \
  X(LinkCounters, link, , "",                                                                                   \
    "the errors counted since start on the link this frame goes over, as its receiver at the controller's end " \
    "sees the client's bytes: one u32 per kind (Link error counters; seq_errors and timeouts stay 0)")          \
  X(std::uint8_t, friction_checked, , "",                                                                       \
    "joints (bit i: joint i + 1) whose friction as set (a saved record at power-on, an identify applied) the "  \
    "momentum law has checked: once per coefficient, when it first knew it within 2.5 % of the set value")      \
  X(std::uint8_t, friction_stale, , "",                                                                         \
    "of those, the joints whose set friction lay more than params::kSavedFitFraction (20 %) off what the law "  \
    "identified: it no longer fits the arm (the law goes on from the data; param save keeps what it learns)")

// X(Name, "name", meaning): what a param frame asks (the parameter table, osc/runtime/parameters.hpp).
// Each is answered at once by a param_answer frame, in the order they come.
#define OSC_PARAM_OP_LIST(X)                                                                                           \
  X(Get, "get", "the element's value, its range, the table's size and layout (a listing gets each index)")             \
  X(Set, "set", "value into the element, checked (Parameter statuses); the answer carries the value now")              \
  X(Save, "save", "every value into the board's store (STM32F4: flash; else RAM or osc_sim --param-file); torque off") \
  X(Load, "load", "the store's newest valid record applied, checked as a whole; torque off")                           \
  X(Reset, "reset", "the table's defaults applied; torque off; the store is unchanged")                                \
  X(Check, "check",                                                                                                    \
    "the gains' margins as they are: margins = observer, its b bound [1/s^2], condition (37), the sampled loop")

#define OSC_X_PREFIX kParamOp
enum ParamOp : std::uint8_t { OSC_PARAM_OP_LIST(OSC_X_ENUMERATOR) kParamOpCount };
#undef OSC_X_PREFIX
constexpr const char* kParamOpNames[kParamOpCount] = {OSC_PARAM_OP_LIST(OSC_X_NAME)};
constexpr const char* kParamOpDocs[kParamOpCount] = {OSC_PARAM_OP_LIST(OSC_X_DOC)};

// X(Name, "name", meaning): the param_answer frame's flag bits, bit k for the k-th entry.
#define OSC_PARAM_FLAG_LIST(X)                                                                        \
  X(Warn37, "warn_37", "the gains as they are now leave the paper's sufficient condition (37) unmet") \
  X(TorqueOff, "torque_off", "the parameter may be written only while the torque is off")             \
  X(Persists, "persists", "the parameter is kept by save")
#define OSC_X_PREFIX kParamFlagBit
#define OSC_X_MASK kParamFlag
enum ParamFlagBit : std::uint8_t { OSC_PARAM_FLAG_LIST(OSC_X_ENUMERATOR) kParamFlagCount };
OSC_PARAM_FLAG_LIST(OSC_X_FLAG_MASK)
#undef OSC_X_MASK
#undef OSC_X_PREFIX
constexpr const char* kParamFlagNames[kParamFlagCount] = {OSC_PARAM_FLAG_LIST(OSC_X_NAME)};
constexpr const char* kParamFlagDocs[kParamFlagCount] = {OSC_PARAM_FLAG_LIST(OSC_X_DOC)};

#define OSC_PARAM_FIELDS(X)                                                                      \
  X(std::uint32_t, id, , "", "the client's number for the request, echoed in its answer")        \
  X(std::uint8_t, op, , "", "what to do (Parameter operations)")                                 \
  X(std::uint8_t, index, , "", "get, set: the parameter's index in the table (Parameters)")      \
  X(std::uint8_t, element, , "", "get, set: the element of a vector parameter (0 for a number)") \
  X(float, value, , "the parameter's", "set: the new value")

#define OSC_PARAM_ANSWER_FIELDS(X)                                                                                \
  X(std::uint32_t, id, , "", "the request's id")                                                                  \
  X(std::uint8_t, op, , "", "its operation")                                                                      \
  X(std::uint8_t, index, , "", "its parameter's index (get, set)")                                                \
  X(std::uint8_t, element, , "", "its element (get, set)")                                                        \
  X(std::uint8_t, status, , "", "ok, or why it was refused (Parameter statuses)")                                 \
  X(std::uint8_t, flags, , "", "warn_37, torque_off, persists (Parameter flags)")                                 \
  X(std::uint8_t, count, , "", "the number of parameters in the table")                                           \
  X(std::uint32_t, layout, , "", "the table's layout version (a client with another table must not use it)")      \
  X(float, value, , "the parameter's",                                                                            \
    "get, set: the element's value now (after a set: the new one, or the old when refused)")                      \
  X(float, lo, , "the parameter's", "get, set: the element's least value")                                        \
  X(float, hi, , "the parameter's", "get, set: the element's greatest value")                                     \
  X(float, margins, [4], "1, 1/s^2, 1, 1",                                                                        \
    "set of a gain, check: the observer's stability margin (above 1: stable), its bound on b, condition (37)'s, " \
    "the sampled loop's gain margin (at least 1: stable)")

// The identify frame: an identify run's estimate (osc/control/identify_estimate.hpp, IdentifyReport), sent once
// after the run's motion ended by a board that estimates (osc/link/identify_port.hpp). The coefficients are the
// drives' (the joints' on an uncoupled arm): model (2)'s theta in its order, viscous 1-6, Coulomb 1-6, Stribeck
// 1-6, as the parameters friction_vis, friction_cou and friction_sti take them, and the armatures' corrections as
// armature_correction takes them.
#define OSC_IDENTIFY_FIELDS(X)                                                                                         \
  X(std::uint32_t, id, , "", "the identify command's id")                                                              \
  X(std::uint8_t, status, , "", "ok, or why there is no estimate (Identify statuses)")                                 \
  X(std::uint32_t, samples, , "", "the run's samples in the estimate")                                                 \
  X(std::uint32_t, lost, , "", "samples the board's main loop missed (0 on a healthy board)")                          \
  X(float, condition, , "", "the regressor's condition number (column-normalised information matrix)")                 \
  X(float, prediction_error, , "", "the worst joint's torque-prediction error (rms residual / rms torque)")            \
  X(float, friction, [3 * kJoints], "N m s/rad, N m", "theta: viscous 1-6, Coulomb 1-6, Stribeck 1-6 (0 when not ok)") \
  X(float, friction_sd, [3 * kJoints], "N m s/rad, N m", "each coefficient's standard deviation")                      \
  X(std::uint32_t, identified, , "",                                                                                   \
    "bit k set: friction[k] is identified (its standard deviation within params::kIdentifiedFraction of it)")          \
  X(float, armature, [kJoints], "kg m^2", "each drive's armature correction (what the model's armature lacks)")        \
  X(float, armature_sd, [kJoints], "kg m^2", "their standard deviations")

// The identify_payload frame: an identify run's estimate of the payload at the flange (the run asked with the
// command flag payload; osc/kernels/payload.hpp), sent right after its identify frame. The mass, centre of mass and
// inertia are in the form the parameters payload_mass, payload_com and payload_inertia take them (0 when the run is
// not ok); the standard deviations and the verdicts are the estimated parameters' pi: the mass, its first moment
// m c (frame 6) and its inertia about frame 6's origin (Ixx, Ixy, Ixz, Iyy, Iyz, Izz).
#define OSC_IDENTIFY_PAYLOAD_FIELDS(X)                                                                                 \
  X(std::uint32_t, id, , "", "the identify command's id")                                                              \
  X(std::uint8_t, status, , "", "the run's: ok, or why there is no estimate (Identify statuses)")                      \
  X(float, mass, , "kg", "the payload's mass")                                                                         \
  X(float, com, [3], "m", "its centre of mass in frame 6")                                                             \
  X(float, inertia, [6], "kg m^2", "its inertia about its centre of mass, frame-6 axes: Ixx, Iyy, Izz, Ixy, Ixz, Iyz") \
  X(float, pi_sd, [10], "kg, kg m, kg m^2",                                                                            \
    "the standard deviations of the estimated parameters: m; m c (x, y, z); the inertia about frame 6's origin "       \
    "(Ixx, Ixy, Ixz, Iyy, Iyz, Izz)")                                                                                  \
  X(std::uint32_t, identified, , "",                                                                                   \
    "bit k set: the k-th of those parameters is identified (its standard deviation within "                            \
    "params::kIdentifiedFraction of it)")

// The identify_offset frame: an identify run's estimate of each drive's torque offset b_i (osc/control/
// identify_estimate.hpp, IdentifyReport::offset), sent right after every identify frame. b_i is the constant torque
// the drive adds to the one commanded (an amplifier's or a current sensor's offset, a constant load the model lacks);
// the estimate keeps it out of the friction's Coulomb and Stribeck terms. It is reported, not compensated: no
// parameter takes it (docs/adaptation.md, "Each drive's torque offset").
#define OSC_IDENTIFY_OFFSET_FIELDS(X)                                                             \
  X(std::uint32_t, id, , "", "the identify command's id")                                         \
  X(std::uint8_t, status, , "", "the run's: ok, or why there is no estimate (Identify statuses)") \
  X(float, offset, [kJoints], "N m",                                                              \
    "each drive's torque offset, the torque it adds to the one commanded (0 when not ok)")        \
  X(float, offset_sd, [kJoints], "N m", "their standard deviations")

// The trace frame: what a host needs to follow a commanded run tick by tick as the controller saw it
// (puma_experiment --motion --qemu: the tracking error and the reference's own maxima, the same as
// the in-process controller's). A Q12.19 number below 32 in magnitude is exact in f32, and so is
// every value here.
#define OSC_TRACE_FIELDS(X)                                                                                          \
  X(std::uint32_t, seq, , "", "the sequence number of the tick's sensor frame (its actuator frame's)")               \
  X(std::uint32_t, faults, , "", "the fault bits this tick detected (Fault bits); the actuator frame's are latched") \
  X(std::uint8_t, state, , "", "the motion state after this tick (Motion states)")                                   \
  X(float, x_d, [6], "m, rad",                                                                                       \
    "the desired pose of the last control step in the controller's coordinates: the wrist centre's position in "     \
    "the base frame, then the orientation coordinates relative to R_ref")                                            \
  X(float, xd_d, [6], "m/s, rad/s", "its velocity, in the same coordinates")                                         \
  X(float, xdd_d, [6], "m/s^2, rad/s^2", "its acceleration, in the same coordinates")                                \
  X(float, R_ref, [9], "", "the controller's reference orientation, row by row (x_d's orientation is relative to it)")

}  // namespace pil
