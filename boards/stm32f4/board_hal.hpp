// The board's binding of the control task (hal::ControlHal): encoders from the timers, torque
// commands to the DAC pair, the E-stop and the control timer's overrun as I/O faults, and a tick
// (BoardHal::tick) that drives the safety outputs and feeds the watchdog after the control step.
// Also hal::PositionHal: the joints' potentiometers (the ADC scan each tick takes and restarts) and
// the encoders' index latches; and hal::CurrentHal: the amplifiers' currents (the same scan) and their
// fault lines.
// Templates over the drivers (the board's, or fakes in tests/boards/stm32f4/test_stm32f4.cpp), each constrained by
// the concept of what the binding needs from it: no virtual calls.
#pragma once

#include <concepts>
#include <cstdint>

#include "control_timer.hpp"
#include "hal/hal.hpp"
#include "osc/control/faults.hpp"
#include "osc/runtime/control_task.hpp"
#include "safety.hpp"

namespace stm32f4 {

/// The encoders: every joint's accumulated count, and each index pulse latched since it was last
/// taken, as such a count (e.g. EncoderBank, or a still robot's zeros and no pulse).
template <class E>
concept EncoderInput = requires(E& e, std::int32_t* counts, int channel, std::int32_t& count) {
  { e.read(counts) } -> std::same_as<void>;
  { e.take_index(channel, count) } -> std::same_as<bool>;
};
/// The potentiometers: a scan taken and the next started once a tick (update: whether the scan was
/// good), and that tick's codes (read: false without a good scan). E.g. AnalogInputs, or none (QEMU).
template <class P>
concept PotInput = requires(P& p, const P& cp, std::uint16_t* codes) {
  { p.update() } -> std::same_as<bool>;
  { cp.read(codes) } -> std::same_as<bool>;
};
/// The amplifiers' current monitors, converted in the potentiometers' scan: that tick's signed codes
/// (read_currents: the code less mid-scale; false without a good scan). E.g. AnalogInputs, or none.
template <class A>
concept CurrentInput = requires(const A& ca, std::int16_t* currents) {
  { ca.read_currents(currents) } -> std::same_as<bool>;
};
/// The torque outputs: one tick's codes (false: a bus fault), and every output to 0 V at once
/// (e.g. ad5754r::DacPair).
template <class D>
concept DacOutput = requires(D& d, const std::int32_t* codes) {
  { d.write(codes) } -> std::same_as<bool>;
  { d.clear() } -> std::same_as<void>;
};
/// The step timing's clock: a free-running 32-bit cycle count, read without an instance.
template <class C>
concept CycleClock = requires {
  { C::cycles() } -> std::same_as<std::uint32_t>;
};

/// Analog: one scan a tick of the potentiometers and the current monitors.
template <EncoderInput Encoders, DacOutput Dac, CycleClock Clock, PotInput Analog>
requires CurrentInput<Analog>
class BoardHal {
 public:
  BoardHal(Encoders& encoders, Dac& dac, Analog& analog, Safety& safety, TimRegs& control_timer)
      : enc_(encoders), dac_(dac), analog_(analog), safety_(safety), timer_(control_timer) {}

  /// Whether torque may be commanded at all: false after a boot fault (docs/stm32f4.md, "Boot
  /// faults"): zero codes and the amplifier disabled, whatever the supervisor says.
  void permit_torque(bool permitted) { permitted_ = permitted; }

  // hal::ControlHal
  bool read_encoders(std::int32_t counts[hal::kJoints]) {
    enc_.read(counts);
    return true;
  }
  void write_dacs(const std::int32_t codes[hal::kJoints]) {
    const bool zero = !permitted_ || safety_.estop();
    for (int i = 0; i < hal::kJoints; ++i) written_[i] = zero ? 0 : codes[i];
    if (!dac_.write(written_)) dac_fault_ = true;
    // An E-stop that came during the burst: its codes may already be latched; clear them now.
    if (!zero && safety_.estop()) dac_.clear();
  }
  std::uint32_t cycles() { return Clock::cycles(); }
  std::uint32_t io_faults() {
    std::uint32_t f = safety_.io_faults();
    // The next update already pending when this tick starts (acknowledged on entry): overrun.
    if (control_timer_pending(timer_)) f |= osc::kFaultOverrun;
    if (dac_fault_) f |= osc::kFaultDacBus;  // a DAC frame did not complete on the SPI bus
    return f;
  }
  void fault_output(bool active) {
    if (active) safety_.force_safe();
  }

  // hal::PositionHal
  /// The scan this tick took (the one the previous tick started); false when it failed or none ran.
  bool read_pots(std::uint16_t codes[hal::kJoints]) { return analog_.read(codes); }
  /// The index pulse latched on joint `channel`'s encoder, once, as the count read_encoders gives.
  bool take_index(int channel, std::int32_t& count) { return enc_.take_index(channel, count); }

  // hal::CurrentHal
  /// Each amplifier's current from the scan this tick took (signed codes, 0 at 0 A); false when it
  /// failed or none ran.
  bool read_currents(std::int16_t currents[hal::kJoints]) { return analog_.read_currents(currents); }
  /// Bit c: amplifier c's fault line is high (its fault, or a broken wire), read now.
  std::uint32_t amp_faults() { return safety_.amp_faults(); }

  /// One control tick: the analog scan (currents, potentiometers) taken and the next one started (no wait), the
  /// control task, then the amplifier enable (on only in kRun with torque permitted and no E-stop)
  /// and the fault LED (a latched fault or a boot fault), then the watchdog, fed only when the
  /// supervisor is healthy (osc::supervisor_healthy). Returns the faults detected in the tick.
  template <class S>
  std::uint32_t tick(osc::ControlTask<S>& task) {
    analog_.update();
    const std::uint32_t faults = osc::control_tick(task, *this);
    safety_.set_outputs(permitted_ && osc::torque_enabled(task.sup),
                        task.sup.state == osc::SupervisorState::kFault || !permitted_);
    if (osc::supervisor_healthy(task.sup)) {
      safety_.watchdog_feed();
      ++feeds_;
    }
    return faults;
  }

  /// The codes sent to the DACs in the last tick.
  const std::int32_t* written() const { return written_; }
  std::uint32_t feeds() const { return feeds_; }

 private:
  Encoders& enc_;
  Dac& dac_;
  Analog& analog_;
  Safety& safety_;
  TimRegs& timer_;
  bool permitted_ = true;
  bool dac_fault_ = false;
  std::int32_t written_[hal::kJoints] = {};
  std::uint32_t feeds_ = 0;
};

}  // namespace stm32f4
