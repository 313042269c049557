// The on-board capture's frames and lists (issue 58; docs/protocol.md, "Capture"): the board's
// oscilloscope. Up to kCaptureChannels signals, each an element of a declared signal, sampled every
// tick (or every `divider` ticks) into a buffer of kCaptureValues numbers with a pre-trigger, triggered
// by a fault, a command, a channel crossing a level, or by hand, and read out over the link:
//
//   capture       host -> controller   arm (the channels, trigger, pre-trigger, divider), trigger,
//                                      abort, status, read (a chunk of the samples)
//   capture_data  controller -> host   the answer to each capture frame, at once: the capture's
//                                      state and set-up, the trigger's tick, and with read, values
//
// The signals are declared here once (OSC_CAPTURE_SIGNAL_LIST): their names, sizes, units and
// meanings for the document and the clients, and what each element reads from the control task
// (osc/link/capture.hpp expands that part). Macros and constants only, like command_frames.hpp, which
// frames.hpp includes with this file.
#pragma once

#include <cstdint>

#include "osc/control/faults.hpp"  // OSC_X_NAME, OSC_X_DOC, OSC_X_ENUMERATOR
#include "osc/robots/arm.hpp"
#include "osc/runtime/timing.hpp"

namespace pil {

/// Channels a capture records at once, the numbers its buffer holds (the samples per channel are
/// kCaptureValues / channels: 4096 samples of one channel, 512 of eight), and the values a
/// capture_data frame carries.
constexpr int kCaptureChannels = 8;
constexpr int kCaptureValues = 4096;
constexpr int kCaptureChunk = 40;

// X(Name, "name", elements, "unit", meaning, value): a signal a channel can record, its elements
// 0 to elements - 1. `value` is what element k reads from the control task `t` after the tick (the
// control step's outputs are the last step's in a tick without one).
#define OSC_CAPTURE_SIGNAL_LIST(X)                                                                                     \
  X(Error, "error", 6, "m, rad",                                                                                       \
    "the tracking error e = x_d - x (36): the wrist centre's position, then the orientation coordinates", t.last.e(k)) \
  X(ObserverError, "observer_error", 6, "m, rad", "the observer's position error x~ (23), as error's",                 \
    t.last.x_tilde(k))                                                                                                 \
  X(Velocity, "velocity", 6, "m/s, rad/s", "the observed velocity x^dot (21)", t.last.xd_hat(k))                       \
  X(Torque, "tau", osc::kDof, "N m", "the control step's joint torques of joints 1 to 6", t.last.tau(k))               \
  X(FrictionTorque, "tau_f_hat", osc::kDof, "N m", "the estimated friction torque (30) of joints 1 to 6",              \
    t.last.tau_f_hat(k))                                                                                               \
  X(ThetaHat, "theta_hat", 3 * osc::kDof, "N m s/rad, N m, N m",                                                       \
    "the friction estimates: viscous of joints 1-6, then Coulomb 1-6, then Stribeck 1-6", t.state.adapt.theta_hat(k))  \
  X(Residual, "residual", osc::kDof, "N m", "the residual monitor's momentum residual r of joints 1 to 6",             \
    t.residual.r(k))                                                                                                   \
  X(ResidualThreshold, "residual_threshold", osc::kDof, "N m", "its threshold this tick, joint by joint",              \
    t.residual.threshold(k))                                                                                           \
  X(Codes, "codes", osc::kDof, "code", "the DAC codes this tick wrote, joints 1 to 6", t.codes[k])                     \
  X(DriveMargin, "drive_margin", osc::kDof, "code",                                                                    \
    "the drive check's margin: its threshold less the last checked current reading's distance outside its codes' "     \
    "range (below 0: beyond it)",                                                                                      \
    t.drive.threshold[k] - t.drive.distance[k])                                                                        \
  X(StageCycles, "stage_cycles", osc::kTickStages, "cycles", "this tick's stages, in Tick stages order",               \
    t.stages.stage[k].last)

#define OSC_CAPTURE_SIGNAL_ENUMERATOR(Name, name, n, unit, doc, value) kCaptureSignal##Name,
enum CaptureSignal : std::uint8_t { OSC_CAPTURE_SIGNAL_LIST(OSC_CAPTURE_SIGNAL_ENUMERATOR) kCaptureSignalCount };
#undef OSC_CAPTURE_SIGNAL_ENUMERATOR
#define OSC_CAPTURE_SIGNAL_FIELD(Name, name, n, unit, doc, value) {name, n, unit, doc},
/// A signal as the document and the clients list it.
struct CaptureSignalInfo {
  const char* name;
  int elements;
  const char* unit;
  const char* doc;
};
constexpr CaptureSignalInfo kCaptureSignals[kCaptureSignalCount] = {OSC_CAPTURE_SIGNAL_LIST(OSC_CAPTURE_SIGNAL_FIELD)};
#undef OSC_CAPTURE_SIGNAL_FIELD

// X(Name, "name", meaning): what a capture frame asks; each is answered at once by a capture_data frame.
#define OSC_CAPTURE_OP_LIST(X)                                                                            \
  X(Arm, "arm", "start recording the channels until the trigger and after it (drops any capture before)") \
  X(Trigger, "trigger", "trigger an armed capture now, whatever its trigger")                             \
  X(Abort, "abort", "stop and drop the capture: idle")                                                    \
  X(Status, "status", "the capture's state and set-up, nothing changed")                                  \
  X(Read, "read", "a done capture's values from offset: up to kCaptureChunk, sample by sample")

// X(Name, "name", meaning): what ends an armed capture's pre-trigger. The trigger's sample is the first sample at
// or after the event: with divider 1 the event's tick itself.
#define OSC_CAPTURE_TRIGGER_LIST(X)                                                                      \
  X(Manual, "manual", "a capture frame's trigger op")                                                    \
  X(Fault, "fault", "a tick that latches a fault bit not latched before it (the trigger's tick is its)") \
  X(Command, "command", "a tick that accepts a command (a move, a stop, an enable, ...)")                \
  X(Rising, "rising", "channel level_channel from below level to at or above it between two samples")    \
  X(Falling, "falling", "channel level_channel from above level to at or below it between two samples")

// X(Name, "name", meaning): where a capture is.
#define OSC_CAPTURE_STATE_LIST(X)                                                 \
  X(Idle, "idle", "no capture: never armed, aborted, or refused")                 \
  X(Armed, "armed", "recording, waiting for the trigger")                         \
  X(Triggered, "triggered", "triggered, recording the samples after the trigger") \
  X(Done, "done", "the buffer holds the capture, pre samples before the trigger's tick")

// X(Name, "name", meaning): a capture frame's answer.
#define OSC_CAPTURE_STATUS_LIST(X)                                                                            \
  X(Ok, "ok", "done as asked")                                                                                \
  X(BadOp, "bad_op", "an op outside the list")                                                                \
  X(NoBuffer, "no_buffer", "arm: the board keeps no capture buffer")                                          \
  X(BadChannel, "bad_channel",                                                                                \
    "arm: channels outside 1 to kCaptureChannels, or a signal or element outside the list (Capture signals)") \
  X(BadTrigger, "bad_trigger",                                                                                \
    "arm: a trigger outside the list, a level channel beyond the channels, or a non-finite level")            \
  X(BadSpan, "bad_span", "arm: pre not below the samples per channel, or divider 0")                          \
  X(NotArmed, "not_armed", "trigger: no capture is armed")                                                    \
  X(NotDone, "not_done", "read: the capture is not done")                                                     \
  X(BadOffset, "bad_offset", "read: offset beyond the capture's values")

#define OSC_X_PREFIX kCaptureOp
enum CaptureOp : std::uint8_t { OSC_CAPTURE_OP_LIST(OSC_X_ENUMERATOR) kCaptureOpCount };
#undef OSC_X_PREFIX
#define OSC_X_PREFIX kCaptureTrigger
enum CaptureTrigger : std::uint8_t { OSC_CAPTURE_TRIGGER_LIST(OSC_X_ENUMERATOR) kCaptureTriggerCount };
#undef OSC_X_PREFIX
#define OSC_X_PREFIX kCaptureState
enum CaptureState : std::uint8_t { OSC_CAPTURE_STATE_LIST(OSC_X_ENUMERATOR) kCaptureStateCount };
#undef OSC_X_PREFIX
#define OSC_X_PREFIX kCaptureStatus
enum CaptureStatus : std::uint8_t { OSC_CAPTURE_STATUS_LIST(OSC_X_ENUMERATOR) kCaptureStatusCount };
#undef OSC_X_PREFIX
constexpr const char* kCaptureOpNames[kCaptureOpCount] = {OSC_CAPTURE_OP_LIST(OSC_X_NAME)};
constexpr const char* kCaptureOpDocs[kCaptureOpCount] = {OSC_CAPTURE_OP_LIST(OSC_X_DOC)};
constexpr const char* kCaptureTriggerNames[kCaptureTriggerCount] = {OSC_CAPTURE_TRIGGER_LIST(OSC_X_NAME)};
constexpr const char* kCaptureTriggerDocs[kCaptureTriggerCount] = {OSC_CAPTURE_TRIGGER_LIST(OSC_X_DOC)};
constexpr const char* kCaptureStateNames[kCaptureStateCount] = {OSC_CAPTURE_STATE_LIST(OSC_X_NAME)};
constexpr const char* kCaptureStateDocs[kCaptureStateCount] = {OSC_CAPTURE_STATE_LIST(OSC_X_DOC)};
constexpr const char* kCaptureStatusNames[kCaptureStatusCount] = {OSC_CAPTURE_STATUS_LIST(OSC_X_NAME)};
constexpr const char* kCaptureStatusDocs[kCaptureStatusCount] = {OSC_CAPTURE_STATUS_LIST(OSC_X_DOC)};

// The field lists, X(type, name, extent, unit, meaning) as in frames.hpp.
#define OSC_CAPTURE_FIELDS(X)                                                                                   \
  X(std::uint32_t, id, , "", "the client's number for the request, echoed in its answer")                       \
  X(std::uint8_t, op, , "", "what to do (Capture operations)")                                                  \
  X(std::uint8_t, channels, , "", "arm: how many channels, 1 to kCaptureChannels")                              \
  X(std::uint8_t, signal, [kCaptureChannels], "", "arm: each channel's signal (Capture signals)")               \
  X(std::uint8_t, element, [kCaptureChannels], "", "arm: each channel's element of its signal (0 first)")       \
  X(std::uint8_t, trigger, , "", "arm: what triggers it (Capture triggers)")                                    \
  X(std::uint8_t, level_channel, , "", "arm, rising or falling: the channel compared with level")               \
  X(float, level, , "the channel's", "arm, rising or falling: the level")                                       \
  X(std::uint32_t, pre, , "samples", "arm: the samples kept before the trigger, below the samples per channel") \
  X(std::uint8_t, divider, , "ticks", "arm: a sample every divider ticks (1: every tick, 1 kHz)")               \
  X(std::uint32_t, offset, , "", "read: the first value's index, sample x channels + channel")

#define OSC_CAPTURE_DATA_FIELDS(X)                                                                            \
  X(std::uint32_t, id, , "", "the request's id")                                                              \
  X(std::uint8_t, op, , "", "its operation")                                                                  \
  X(std::uint8_t, status, , "", "ok, or why it was refused (Capture statuses)")                               \
  X(std::uint8_t, state, , "", "the capture's state after it (Capture states)")                               \
  X(std::uint8_t, channels, , "", "the capture's channels (0: idle)")                                         \
  X(std::uint8_t, signal, [kCaptureChannels], "", "each channel's signal")                                    \
  X(std::uint8_t, element, [kCaptureChannels], "", "each channel's element")                                  \
  X(std::uint8_t, trigger, , "", "its trigger")                                                               \
  X(std::uint8_t, divider, , "ticks", "its divider")                                                          \
  X(std::uint32_t, depth, , "samples", "samples per channel the capture holds when done")                     \
  X(std::uint32_t, pre, , "samples",                                                                          \
    "the samples before the trigger's: as armed, or fewer when it came before that many were recorded")       \
  X(std::uint32_t, trigger_tick, , "tick", "the tick of the trigger's sample (triggered, done), low 32 bits") \
  X(std::uint32_t, first_tick, , "tick", "the tick of the first sample held (done), low 32 bits")             \
  X(std::uint32_t, offset, , "", "read: the first value's index")                                             \
  X(std::uint8_t, count, , "", "read: the values in this frame (0 to kCaptureChunk)")                         \
  X(float, values, [kCaptureChunk], "the signals'", "read: the values from offset, sample by sample")

}  // namespace pil
