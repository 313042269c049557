// Hardware abstraction: compile-time interfaces, bound by template parameter (no virtual calls).
//
// A HAL binding is a type H with these members (all may be static):
//   void read_encoders(std::int32_t counts[hal::kJoints]);
//       Accumulated signed counts per joint since start-up, wrap-around of the hardware counters
//       already extended (see EncoderUnwrap).
//   void write_dacs(const std::int32_t codes[hal::kJoints]);
//       Signed DAC codes in [-kDacMaxCode, kDacMaxCode] (osc/params.hpp).
//   std::uint32_t cycles();
//       A free-running 32-bit counter for step timing (0 where there is none).
//   std::uint32_t io_faults();
//       osc::Fault bits the I/O layer detected since the last tick (lost or corrupt link).
//   void fault_output(bool active);
//       The hardware fault line (e.g. an amplifier-enable interlock or a LED), driven every tick.
// The periodic control timer is the board's (boards/<board>/board.hpp: control_timer_start()); its
// interrupt calls osc::control_tick(). Telemetry: the task's StepTiming, supervisor state and fault
// bits; over the PIL link every actuator frame carries them (osc/pil.hpp).
// Bindings: host_sim/plant_hal.hpp (the simulated PUMA 560); boards/<board>/ for targets.
#pragma once

#include <cstdint>

namespace hal {

constexpr int kJoints = 6;

/// Extends a free-running N-bit hardware counter (e.g. a 16-bit timer in encoder mode) to a
/// 32-bit position. Correct as long as fewer than 2^(N-1) counts pass between two reads.
template <int Bits>
struct EncoderUnwrap {
  static_assert(Bits >= 2 && Bits <= 32, "counter width");
  std::uint32_t last = 0;
  std::int32_t position = 0;

  std::int32_t update(std::uint32_t raw) {
    constexpr std::uint32_t mask = Bits == 32 ? 0xFFFFFFFFu : ((1u << Bits) - 1u);
    std::uint32_t delta = (raw - last) & mask;
    last = raw & mask;
    // Sign-extend the N-bit difference.
    std::int32_t d = static_cast<std::int32_t>(delta << (32 - Bits)) >> (32 - Bits);
    position += d;
    return position;
  }
};

}  // namespace hal
