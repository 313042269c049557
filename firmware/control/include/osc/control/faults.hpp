// The firmware's fault catalogue: one list, from which the bits, their names and the mask of all
// faults are generated. Every fault latches in the supervisor (osc/runtime/supervisor.hpp) and
// commands zero torque in the tick that detects it. The control step itself raises three of them
// (non_finite, singular, overflow); the runtime, the link and the boards' HALs raise the rest
// (dac_bus: the STM32F4 board). Every bit a board can latch is here, so that it has a name.
#pragma once

#include <cstdint>

namespace osc {

// X(Name, "name", description), in bit order.
#define OSC_FAULT_LIST(X)                                                                                          \
  X(NonFinite, "non_finite", "a non-finite value anywhere in the step")                                            \
  X(EncoderJump, "encoder_jump", "an encoder moved further in one tick than the joint can")                        \
  X(Saturation, "saturation", "a torque stayed clipped at the DAC range for too many ticks")                       \
  X(Singular, "singular", "Jacobian reciprocal condition below the threshold")                                     \
  X(Overrun, "overrun", "the next tick arrived before this one ended")                                             \
  X(LinkLost, "link_lost", "repeated link errors, the last a silence alone (no frame, no byte)")                   \
  X(LinkCorrupt, "link_corrupt", "repeated link errors, the last a bad, cut short or stray frame")                 \
  X(EncoderRange, "encoder_range", "an encoder reading outside the joint limits plus a margin")                    \
  X(EncoderStuck, "encoder_stuck",                                                                                 \
    "an encoder stood still while the reference moved its joint by more than the bound")                           \
  X(Tracking, "tracking", "the measured tracking error exceeded its bound")                                        \
  X(ThetaBounds, "theta_bounds",                                                                                   \
    "a friction estimate left its band [-b theta_max, (1 + b) theta_max], b = params::kThetaFaultBand")            \
  X(Estop, "estop", "the emergency-stop input is active")                                                          \
  X(Overflow, "overflow",                                                                                          \
    "a fixed-point result saturated: an overflow, a division by a near-zero or a function outside its domain")     \
  X(DacBus, "dac_bus",                                                                                             \
    "a board's DAC frame did not complete on its bus (the codes may not have reached the amplifiers)")             \
  X(DriveFault, "drive_fault",                                                                                     \
    "a drive did not deliver the torque commanded (zero, full scale, stuck): the drive check or the residual")     \
  X(Collision, "collision", "an external torque beyond the model's error bounds: the residual monitor")            \
  X(PositionMismatch, "position_mismatch",                                                                         \
    "a pot and its encoders disagree beyond their band: a stuck or slipping encoder; homing: a pot off its index") \
  X(IndexMissing, "index_missing", "homing: a motor turned a whole revolution and more without an index pulse")    \
  X(Unstable, "unstable",                                                                                          \
    "a torque (less its friction compensation) oscillated at half the tick rate beyond its bound: the loop lost")  \
  X(CurrentSense, "current_sense",                                                                                 \
    "an amplifier's current monitor read off its scale (beyond any current its amplifier gives): the drive check") \
  X(PayloadMismatch, "payload_mismatch",                                                                           \
    "after an enable, the residual is the weight of a payload set and not on the arm, or on it and not set")

// The name and the meaning of an entry of an X-macro list of the form X(Name, "name", meaning):
// `{LIST(OSC_X_NAME)}` is the array of its names, `{LIST(OSC_X_DOC)}` of its meanings.
#define OSC_X_NAME(Name, name, doc) name,
#define OSC_X_DOC(Name, name, doc) doc,
// Its enumerators, named with a prefix: with OSC_X_PREFIX defined as kStage,
// `LIST(OSC_X_ENUMERATOR)` is kStageRead, kStageChecks, ...
#define OSC_X_CAT_(a, b) a##b
#define OSC_X_CAT(a, b) OSC_X_CAT_(a, b)
#define OSC_X_ENUMERATOR(Name, name, doc) OSC_X_CAT(OSC_X_PREFIX, Name),

namespace detail {
#define OSC_X_PREFIX kBit
enum FaultBit : unsigned { OSC_FAULT_LIST(OSC_X_ENUMERATOR) kFaultCount };
#undef OSC_X_PREFIX
}  // namespace detail

/// Named fault bits (sticky once latched).
enum Fault : std::uint32_t {
  kFaultNone = 0,
#define OSC_FAULT_ENUM(Name, name, doc) kFault##Name = 1u << detail::kBit##Name,
  OSC_FAULT_LIST(OSC_FAULT_ENUM)
#undef OSC_FAULT_ENUM
};

constexpr int kFaultCount = detail::kFaultCount;
static_assert(kFaultCount <= 32, "the fault bits fit the 32-bit fault word of the link and the supervisor");
/// Every defined fault bit.
constexpr std::uint32_t kAllFaults = (1u << kFaultCount) - 1u;

/// Names of the fault bits, in bit order (for telemetry and logs).
constexpr const char* kFaultNames[kFaultCount] = {OSC_FAULT_LIST(OSC_X_NAME)};
/// What each fault means, in bit order.
constexpr const char* kFaultDocs[kFaultCount] = {OSC_FAULT_LIST(OSC_X_DOC)};

/// Name of the lowest fault bit set in bits ("none" for 0).
constexpr const char* fault_name(std::uint32_t bits) {
  for (int i = 0; i < kFaultCount; ++i)
    if (bits & (1u << i)) return kFaultNames[i];
  return "none";
}

}  // namespace osc
