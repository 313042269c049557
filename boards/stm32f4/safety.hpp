// Safety I/O (pins.hpp): the amplifier-enable output, the E-stop input on EXTI, the fault LED, the
// amplifiers' fault lines, and the independent watchdog (IWDG).
//
//   - Amplifier enable: low (disabled, also by its external pull-down while the MCU is in reset)
//     from boot; high only while the supervisor runs healthy with torque allowed, the boot found no
//     fault and no E-stop was seen; low at once on any fault (Safety::force_safe(), from the tick,
//     the E-stop interrupt and the fault handlers).
//   - E-stop: a rising edge on the input (EXTI line 1; RM0090 12.2: SYSCFG_EXTICR routes port D to
//     the line, RTSR selects the rising edge, IMR unmasks it, PR is cleared by writing 1) runs
//     on_estop_interrupt(): amplifier off and LED on within the interrupt, and a latch the next tick
//     reports as osc::kFaultEstop (io_faults()), so the supervisor latches `estop` within one tick.
//     The input level is also read every tick: a stop pressed before boot has no edge.
//   - Amplifier fault lines: one input with a pull-up per amplifier, low while it is healthy; read
//     each tick as the HAL's amp_faults() bits (high: the amplifier's fault, or a broken wire).
//   - IWDG (RM0090 21.3): clocked by the 32 kHz LSI (17 to 47 kHz, data sheet DS8626), /4, reload
//     kWatchdogReload: expires 5 ms after the last feed (3.4 to 9.4 ms over the LSI's range). Started
//     once, it cannot be stopped; the MCU resets when it expires, and the amplifier enable falls
//     with the reset. It is fed only at the end of a healthy tick (board_hal.hpp).
#pragma once

#include <cstdint>

#include "clock.hpp"
#include "gpio.hpp"
#include "osc/control/faults.hpp"
#include "pins.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

constexpr std::uint32_t kWatchdogPrescaler = 0;  // LSI / 4
constexpr std::uint32_t kWatchdogReload = 40;    // 40 / (32 kHz / 4) = 5 ms
constexpr std::uint32_t kLsiHz = 32000, kLsiMinHz = 17000, kLsiMaxHz = 47000;
constexpr std::uint32_t kWatchdogLongPrescaler = 6, kWatchdogLongReload = 4095;  // LSI / 256, the longest
static_assert(std::uint64_t{kWatchdogLongReload} * (4u << kWatchdogLongPrescaler) * 1000u / kLsiMaxHz > 2 * 2000,
              "the stretched watchdog outlasts a sector erase (2 s at most, DS8626) twice at the fastest LSI");
/// The watchdog's timeout [us] for an LSI frequency.
constexpr std::uint32_t watchdog_timeout_us(std::uint32_t lsi_hz) {
  return static_cast<std::uint32_t>(std::uint64_t{kWatchdogReload} * (4u << kWatchdogPrescaler) * 1000000u / lsi_hz);
}
static_assert(watchdog_timeout_us(kLsiHz) == 5000 && watchdog_timeout_us(kLsiMaxHz) > 3 * 1000,
              "5 ms nominal, more than three control periods at the fastest LSI");

class Safety {
 public:
  /// Polls of IWDG_SR: a prescaler or reload update takes up to 5 LSI periods (about 300 us).
  static constexpr std::uint32_t kWatchdogPolls = 100000;

  /// Pins (amplifier disabled, LED off) and the E-stop interrupt line; SYSCFG's clock goes on here.
  void init(const Chip& chip) {
    chip_ = chip;
    pin_configure(chip, pins::kAmpEnable);
    pin_configure(chip, pins::kFaultLed);
    pin_configure(chip, pins::kEstop);
    for (const PinConfig& p : pins::kAmpFaults) pin_configure(chip, p);
    chip.rcc->APB2ENR = chip.rcc->APB2ENR | RccRegs::kSyscfgEn;
    read_back(chip.rcc->APB2ENR);
    constexpr int kEstopLine = pins::kEstopExtiLine;
    Reg& cr = chip.syscfg->EXTICR[kEstopLine / 4];
    const std::uint32_t shift = 4u * (kEstopLine % 4);
    cr = (cr & ~(0xFu << shift)) | (static_cast<std::uint32_t>(pins::kEstop.pin.port) << shift);
    chip.exti->RTSR = chip.exti->RTSR | kLine;
    chip.exti->FTSR = chip.exti->FTSR & ~kLine;
    chip.exti->PR = kLine;
    chip.exti->IMR = chip.exti->IMR | kLine;
  }

  /// The E-stop interrupt (EXTI line 1).
  void on_estop_interrupt() {
    chip_.exti->PR = kLine;
    estop_latched_ = true;
    force_safe();
  }
  /// The E-stop was seen (edge since boot, or the input is high now).
  bool estop() {
    if (pin_read(chip_.port(pins::kEstop.pin.port), pins::kEstop.pin.n)) estop_latched_ = true;
    return estop_latched_;
  }
  /// The E-stop as the control task's fault bit.
  std::uint32_t io_faults() { return estop() ? static_cast<std::uint32_t>(osc::kFaultEstop) : 0u; }
  /// Bit c: amplifier c's fault line reads high (the amplifier reports a fault, or its wire is open).
  std::uint32_t amp_faults() const {
    std::uint32_t bits = 0;
    for (int c = 0; c < hal::kJoints; ++c) {
      const Pin p = pins::kAmpFaults[c].pin;
      if (pin_read(chip_.port(p.port), p.n)) bits |= 1u << c;
    }
    return bits;
  }

  /// Amplifier off, fault LED on. Register writes only: callable from any interrupt or fault handler
  /// (before init() there is nothing to switch off: the pin is still an input, held low externally).
  void force_safe() {
    amplifier_ = false;
    if (chip_.exti == nullptr) return;
    write(pins::kAmpEnable, false);
    write(pins::kFaultLed, true);
  }
  /// The outputs after a tick: the amplifier enabled only if `torque_allowed` and no E-stop; the
  /// LED lit on `fault`.
  void set_outputs(bool torque_allowed, bool fault) {
    write(pins::kFaultLed, fault);
    amplifier_ = torque_allowed && !estop();
    write(pins::kAmpEnable, amplifier_);
  }
  bool amplifier_enabled() const { return amplifier_; }

  /// Starts the IWDG (kWatchdogReload). kWatchdogSetup if the prescaler and reload were not taken.
  BootFault watchdog_start() {
    chip_.dbgmcu->APB1_FZ = chip_.dbgmcu->APB1_FZ | DbgmcuRegs::kIwdgStop;  // halted by a debugger: paused
    chip_.iwdg->KR = IwdgRegs::kStart;                                      // starts the LSI too
    return watchdog_set(kWatchdogPrescaler, kWatchdogReload) ? BootFault::kNone : BootFault::kWatchdogSetup;
  }
  void watchdog_feed() { chip_.iwdg->KR = IwdgRegs::kReload; }
  /// The watchdog at its longest (LSI / 256, reload 4095: 22 s at the fastest LSI, 33 s nominal), fed:
  /// around a flash save, which stalls the core for up to 2 s (boards/common/param_store/param_store.hpp).
  bool watchdog_stretch() { return watchdog_set(kWatchdogLongPrescaler, kWatchdogLongReload); }
  /// Back to kWatchdogReload, fed.
  bool watchdog_restore() { return watchdog_set(kWatchdogPrescaler, kWatchdogReload); }
  /// The stretch and its undoing as a store's watchdog (FlashParamStore).
  struct Stretch {
    Safety& s;
    void stretch() { s.watchdog_stretch(); }
    void restore() { s.watchdog_restore(); }
  };

 private:
  static constexpr std::uint32_t kLine = 1u << pins::kEstopExtiLine;
  /// Prescaler and reload, waited for (RM0090 21.3.2: PVU, RVU), then fed; false if not taken.
  bool watchdog_set(std::uint32_t prescaler, std::uint32_t reload) {
    IwdgRegs& w = *chip_.iwdg;
    w.KR = IwdgRegs::kUnlock;
    w.PR = prescaler;
    w.RLR = reload;
    const bool taken = poll_until([&] { return (w.SR & (IwdgRegs::kPvu | IwdgRegs::kRvu)) == 0; }, kWatchdogPolls);
    w.KR = IwdgRegs::kReload;
    return taken;
  }
  void write(const PinConfig& p, bool high) { pin_write(chip_.port(p.pin.port), p.pin.n, high); }

  Chip chip_{};
  volatile bool estop_latched_ = false;
  volatile bool amplifier_ = false;
};

}  // namespace stm32f4
