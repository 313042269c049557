// The supervisor: a pure function from (state, fault conditions) to the next state, with named,
// sticky fault bits. Any fault commands zero torque in the same tick and stays latched until a
// reset; no transition leaves kFault.
#pragma once

#include <cstdint>

namespace osc {

/// Named fault bits (sticky).
enum Fault : std::uint32_t {
  kFaultNone = 0,
  kFaultNonFinite = 1u << 0,      ///< a non-finite value anywhere in the step
  kFaultEncoderJump = 1u << 1,    ///< an encoder moved further in one tick than the joint can
  kFaultSaturation = 1u << 2,     ///< a torque stayed clipped at the DAC range for too many ticks
  kFaultSingular = 1u << 3,       ///< Jacobian reciprocal condition below the threshold
  kFaultOverrun = 1u << 4,        ///< the next tick arrived before this one ended
  kFaultLinkLost = 1u << 5,       ///< no sensor frame within the link timeout
  kFaultLinkCorrupt = 1u << 6,    ///< a frame with a bad checksum, length or sequence number
};
constexpr std::uint32_t kAllFaults = 0x7F;

/// Names of the fault bits, in bit order (for telemetry and logs).
constexpr const char* kFaultNames[] = {"non_finite", "encoder_jump", "saturation", "singular",
                                       "overrun",    "link_lost",    "link_corrupt"};

enum class SupervisorState : std::uint8_t { kInit = 0, kRun = 1, kFault = 2 };

struct SupervisorInput {
  std::uint32_t faults;  ///< fault conditions detected in this tick
  bool ready;            ///< the controller is initialised (first valid sample taken)
};

struct Supervisor {
  SupervisorState state;
  std::uint32_t latched;  ///< sticky fault bits
};

/// Transition table:
///   any state, faults != 0       -> kFault (faults latched)
///   kInit, ready                 -> kRun
///   kInit, !ready                -> kInit
///   kRun                         -> kRun
///   kFault                       -> kFault (sticky)
constexpr Supervisor supervisor_next(Supervisor s, SupervisorInput in) {
  const std::uint32_t latched = s.latched | (in.faults & kAllFaults);
  if (latched != 0 || s.state == SupervisorState::kFault) return {SupervisorState::kFault, latched};
  if (s.state == SupervisorState::kInit) return {in.ready ? SupervisorState::kRun : SupervisorState::kInit, 0};
  return {SupervisorState::kRun, 0};
}

/// Torque may be commanded only in kRun.
constexpr bool torque_enabled(const Supervisor& s) { return s.state == SupervisorState::kRun; }

}  // namespace osc
