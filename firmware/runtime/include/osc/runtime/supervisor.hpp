// The supervisor: a pure function from (state, fault conditions) to the next state, with named,
// sticky fault bits. Any fault commands zero torque in the same tick and stays latched until a
// reset (the runtime re-initialises the supervisor on a clear the motion state machine accepts);
// no transition leaves kFault. Its latch is the task's one latch of fault bits: the motion state
// machine reads it (MotionInput::latched, osc/runtime/motion_states.hpp), the telemetry and state
// frames report it.
#pragma once

#include <cstdint>

#include "osc/control/faults.hpp"

namespace osc {

enum class SupervisorState : std::uint8_t { kInit = 0, kRun = 1, kFault = 2 };
/// Names of the states, by code (telemetry, logs, the protocol document).
constexpr const char* kSupervisorStateNames[] = {"init", "run", "fault"};
constexpr int kSupervisorStateCount = sizeof(kSupervisorStateNames) / sizeof(kSupervisorStateNames[0]);
static_assert(kSupervisorStateCount == static_cast<int>(SupervisorState::kFault) + 1, "a name for every state");
/// The name of a state code ("?" for a code that is no state).
constexpr const char* supervisor_state_name(std::uint8_t code) {
  return code < kSupervisorStateCount ? kSupervisorStateNames[code] : "?";
}

struct SupervisorInput {
  std::uint32_t faults;  ///< fault conditions detected in this tick
  bool ready;            ///< the controller is initialised (first valid sample taken)
};

struct Supervisor {
  SupervisorState state;
  std::uint32_t latched;  ///< sticky fault bits: the task's one latch
};

/// Transition table:
///   any state, faults != 0       -> kFault (faults latched; a bit outside the catalogue too: a
///                                   fault the firmware cannot name still stops the torque)
///   kInit, ready                 -> kRun
///   kInit, !ready                -> kInit
///   kRun                         -> kRun
///   kFault                       -> kFault (sticky)
constexpr Supervisor supervisor_next(Supervisor s, SupervisorInput in) {
  const std::uint32_t latched = s.latched | in.faults;
  if (latched != 0 || s.state == SupervisorState::kFault) return {SupervisorState::kFault, latched};
  if (s.state == SupervisorState::kInit) return {in.ready ? SupervisorState::kRun : SupervisorState::kInit, 0};
  return {SupervisorState::kRun, 0};
}

/// Torque may be commanded only in kRun.
constexpr bool torque_enabled(const Supervisor& s) { return s.state == SupervisorState::kRun; }

/// A tick that ends in this state may feed a hardware watchdog: kRun, or kInit, with no fault
/// latched. A tick that latched a fault (and every tick after it) is not healthy, so the watchdog
/// expires (docs/firmware.md, "Watchdog").
constexpr bool supervisor_healthy(const Supervisor& s) { return s.state != SupervisorState::kFault && s.latched == 0; }

}  // namespace osc
