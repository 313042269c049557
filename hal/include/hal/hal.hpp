// Hardware abstraction: compile-time interfaces, bound by template parameter (no virtual calls).
// ControlHal is what the control task (osc/runtime/control_task.hpp) needs from the hardware; every
// binding states that it satisfies it (static_assert), and control_tick() requires it:
//   host_sim/plant_hal.hpp (the simulated PUMA 560), the link node (osc/link/node.hpp, the PIL
//   firmware's encoders and DACs), boards/<board>/ (e.g. the still-robot stub of timer_firmware),
//   and the scripted HAL of tests/firmware/runtime/test_control_task.cpp.
// The periodic control timer is the board's (boards/<board>/board.hpp: control_timer_start()); its
// interrupt calls osc::control_tick(). Telemetry: the task's StepTiming, supervisor state and fault
// bits; over the PIL link every actuator frame carries them (osc/link/frames.hpp).
#pragma once

#include <concepts>
#include <cstdint>

#include "osc/robots/arm.hpp"

namespace hal {

/// One encoder and one DAC per joint of the robot.
constexpr int kJoints = osc::kDof;

/// The control task's view of the hardware.
template <class H>
concept ControlHal = requires(H& h, std::int32_t* counts, const std::int32_t* codes, bool active) {
  /// Accumulated signed counts per joint since start-up, wrap-around of the hardware counters
  /// already extended (see EncoderUnwrap). Returns false when there is no valid sample this tick
  /// (e.g. its link frame was lost or corrupt): the tick then commands zero torque and skips the
  /// control step, without a fault; io_faults() decides when such ticks become one.
  { h.read_encoders(counts) } -> std::same_as<bool>;
  /// Signed DAC codes in [-kDacMaxCode, kDacMaxCode] (osc/runtime/io.hpp).
  { h.write_dacs(codes) } -> std::same_as<void>;
  /// A free-running 32-bit counter for step timing (0 where there is none).
  { h.cycles() } -> std::same_as<std::uint32_t>;
  /// osc::Fault bits the I/O layer detected since the last tick (e.g. a lost or corrupt link).
  { h.io_faults() } -> std::same_as<std::uint32_t>;
  /// The hardware fault line (e.g. an amplifier-enable interlock or a LED), driven every tick.
  { h.fault_output(active) } -> std::same_as<void>;
};

/// What homing and the position cross-check (issue 27) need beyond ControlHal: each joint's
/// potentiometer and each encoder's index latch. A HAL without them (a still-robot stub, the PIL
/// link today) satisfies ControlHal alone, and the task then takes its start pose on trust.
template <class H>
concept PositionHal = requires(H& h, std::uint16_t* codes, int channel, std::int32_t& count) {
  /// The potentiometers' ADC codes, one per joint (0 to 2^pot_bits - 1, osc::robot::kDriveTrain),
  /// the latest complete conversion; false when there is none yet (or it failed).
  { h.read_pots(codes) } -> std::same_as<bool>;
  /// The index pulse latched on an encoder channel since the last call: true once per pulse, with
  /// the encoder's accumulated count (as read_encoders gives it) at the pulse's edge.
  { h.take_index(channel, count) } -> std::same_as<bool>;
};

/// What the drive check (issue 56, docs/safety.md "The drive check") needs beyond ControlHal: each
/// amplifier's current, read back from its current-monitor output through an ADC, and its fault line
/// where one is wired. A HAL without them satisfies ControlHal alone: the task then cannot tell a
/// drive fault from a contact on one joint, nor find a DAC frozen at its last value at rest.
template <class H>
concept CurrentHal = requires(H& h, std::int16_t* currents) {
  /// Each amplifier channel's current (the channels of write_dacs), the latest complete conversion:
  /// signed ADC codes, +-(2^(bits-1) - 1) at +-range times the DAC's full-scale current
  /// (osc::robot::kDriveTrain.current); positive where a positive DAC code drives it. False when
  /// there is none (no conversion yet, it failed, or the board has no readback wired).
  { h.read_currents(currents) } -> std::same_as<bool>;
  /// Bit c: amplifier c's fault line is active (over-current, over-temperature, a supply fault as the
  /// amplifier reports it); 0 where no fault line is wired.
  { h.amp_faults() } -> std::same_as<std::uint32_t>;
};

/// Extends a free-running N-bit hardware counter (e.g. a 16-bit timer in encoder mode) to a
/// 32-bit position. Correct as long as fewer than 2^(N-1) counts pass between two reads.
template <int Bits>
struct EncoderUnwrap {
  static_assert(Bits >= 2 && Bits <= 32, "counter width");
  std::uint32_t last = 0;
  std::int32_t position = 0;

  std::int32_t update(std::uint32_t raw) {
    constexpr std::uint32_t kMask = Bits == 32 ? 0xFFFFFFFFu : ((1u << Bits) - 1u);
    std::uint32_t delta = (raw - last) & kMask;
    last = raw & kMask;
    // Sign-extend the N-bit difference.
    std::int32_t d = static_cast<std::int32_t>(delta << (32 - Bits)) >> (32 - Bits);
    // Modular 32-bit position: a counter that runs past INT32_MAX wraps instead of overflowing a
    // signed integer (undefined behaviour); the control task checks the step between ticks.
    position = static_cast<std::int32_t>(static_cast<std::uint32_t>(position) + static_cast<std::uint32_t>(d));
    return position;
  }
};

}  // namespace hal
