// Board support for an STM32F407 controller board (Cortex-M4F, 168 MHz): the chip's drivers
// (boards/common/stm32f4) and the DAC's (boards/common/devices/ad5754r) wired to its pins (pins.hpp)
// and to the chip (stm32f4::Chip::hardware()), with this folder's safety I/O, DAC bus and HAL
// binding; the boot sequence, the interrupts and their priorities. Over the shared Cortex-M code
// (boards/common/cortex_m); no virtual calls, no heap. docs/stm32f4.md describes the board.
//
// Build-time switch OSC_STM32F4_QEMU (the image stm32f4_qemu, for QEMU's netduinoplus2, an
// STM32F405 with the same core and memory map): QEMU models TIM2..TIM5, the USARTs, SPI, SYSCFG and
// EXTI, but not TIM6/TIM7, the RCC, GPIO, the IWDG, encoder mode nor input capture; its ADCs are a
// stub (a read of DR after a start gives the last value + 7: no scan, no EOC), DMA2 a placeholder that
// reads 0, and the ADCs' common registers (ADC1 + 0x300) are not mapped. With the switch
//   - the control interrupt comes from TIM2 (IRQ 28) instead of TIM6 (IRQ 54), with QEMU's fixed
//     48 MHz timer clock;
//   - the encoders are a still robot (every count 0, and no index pulse ever: take_index is always
//     false): TIM2 is the tick, and QEMU would run TIM3..5 as free counters, not in encoder mode;
//   - there are no analog inputs: the ADC and DMA2 are never touched, and read_pots and
//     read_currents are always false (no sample);
//   - the cycle counter's rate is QEMU's fixed 168 MHz CPU clock, whatever the RCC set-up reports.
// Everything else is the board image's code: the bounded clock set-up (which falls back to HSI
// there, the RCC reading zero), the DAC frames on SPI2, the safety I/O registers, the watchdog's
// registers, the EXTI E-stop (driven by its software trigger in the smoke test) and the USART link
// (commands in, answers, state and telemetry frames out).
#pragma once

#include <cstdint>
#include <type_traits>

#include "ad5754r.hpp"
#include "adc.hpp"
#include "analog_inputs.hpp"
#include "board_hal.hpp"
#include "clock.hpp"
#include "control_timer.hpp"
#include "cortex_m.hpp"
#include "dac_bus.hpp"
#include "encoders.hpp"
#include "osc/control/params.hpp"
#include "osc/link/command_port.hpp"
#include "osc/link/frames.hpp"
#include "pins.hpp"
#include "safety.hpp"
#include "stm32f4_regs.hpp"
#include "text.hpp"
#include "usart.hpp"

#if defined(OSC_STM32F4_QEMU)
#define OSC_CONTROL_TIMER_HANDLER TIM2_Handler
#else
#define OSC_CONTROL_TIMER_HANDLER TIM6_DAC_Handler
#endif

namespace board {

using stm32f4::BootFault;

#if defined(OSC_STM32F4_QEMU)
constexpr bool kQemu = true;
#else
constexpr bool kQemu = false;
#endif

/// The control rate is the controller's (one source: osc::params::kControlHz).
constexpr std::uint32_t kControlHz = osc::params::kControlHz;

// ---------------------------------------------------------------- interrupts
// IRQ numbers: RM0090 table 61. Priorities: the STM32F4 implements 4 priority bits (16 levels, 0 the
// most urgent); with the reset priority grouping all 4 are pre-emption bits. The E-stop pre-empts
// everything, so that the amplifier falls within microseconds even in the middle of a step; the
// USART's receive interrupt pre-empts the control tick (a tick is longer than a byte time: the data
// register would overrun); the tick pre-empts the main loop (commands, transmission). The main loop
// masks the tick alone (BASEPRI at kControlPriority: App::masked) around the command mailbox's
// hand-over. The fault exceptions (HardFault, NMI) are above all of them by the architecture.
constexpr int kPriorityBits = 4;
constexpr int kEstopIrq = 7;  // EXTI1
constexpr int kTim2Irq = 28, kUsart2Irq = 38, kTim6DacIrq = 54;
constexpr unsigned kEstopPriority = 0, kUsartPriority = 1, kControlPriority = 2;
static_assert(kEstopPriority < kUsartPriority && kUsartPriority < kControlPriority);
constexpr stm32f4::Timer kControlTimer = kQemu ? stm32f4::Timer::kTim2 : stm32f4::Timer::kTim6;
constexpr int kControlIrq = kQemu ? kTim2Irq : kTim6DacIrq;

// ---------------------------------------------------------------- QEMU's timer and clock
/// netduinoplus2's CPU clock (hw/arm/netduinoplus2.c: 168 MHz, whatever the RCC says) and the
/// clock of its TIM2..TIM5 model: 1 GHz in QEMU 7.2, the version of Debian 12 (the property
/// clock-frequency of stm32f2xx-timer, `info qtree`; later QEMU versions model 48 MHz).
constexpr std::uint32_t kQemuTimerHz = 1000000000, kQemuCpuHz = 168000000;
/// QEMU 7.2's timer model re-bases its count on every write to PSC, CNT or EGR.UG and then fires
/// after ARR plus that base instead of ARR + 1 counts: the QEMU image runs TIM2 unprescaled with
/// its 32-bit reload (999 999 at 1 GHz: 1 ms) and writes none of the three (control_timer_start).
constexpr stm32f4::TimerDivider qemu_control_divider() {
  return stm32f4::control_divider_32bit(kQemuTimerHz, kControlHz);
}

// ---------------------------------------------------------------- the USART link
constexpr std::uint32_t kTelemetryBaud = 460800;
/// An actuator frame (pil::kMaxFrame bytes, 10 bits each on the line) every 10th tick: 100 frames a second.
constexpr std::uint32_t kTelemetryEvery = 10;
/// The main loop serves at least this often, in ticks (an identify run's ring holds osc::params::kRunRingTicks).
constexpr std::uint32_t kServeEveryTicks = 16;
/// A state frame every 20th tick (osc::kStatePeriod): 50 a second.
constexpr std::uint32_t kStateEvery = osc::kStatePeriod;
static_assert(10u * (pil::kMaxFrame * kControlHz / kTelemetryEvery +
                     (pil::kStatePayload + pil::kOverhead) * kControlHz / kStateEvery) <=
                  kTelemetryBaud * 6 / 10,
              "telemetry and state frames fill at most 60 % of the line: answers have room");
/// Answer frames a tick may give: its own, and one for each move it drops from the motion queue (a
/// stop behind a full queue: osc::MotionGenerator::kMaxWaiting).
constexpr int kTxAnswers = 1 + osc::params::kMoveQueueLength + 1;
/// Frames the transmitter queues (a power of two: the queue's indices wrap): a tick gives its
/// answers, a state frame and a telemetry frame, and the main loop sends none while it checks a
/// move's path (a tick or two).
constexpr int kTxFrames = 32;
/// Telemetry is offered only while this many slots stay free: an answer never waits behind it.
constexpr int kTxAnswerReserve = kTxAnswers + 2;
static_assert(kTxFrames >= kTxAnswerReserve + 3 && (kTxFrames & (kTxFrames - 1)) == 0,
              "room for a tick's answers, state and telemetry, and for telemetry behind the reserve");
/// Ticks the main loop waits at most for the transmit queue's room for a frame sent once (an identify report):
/// a frame of pil::kMaxFrame bytes goes out in under 5 ms at kTelemetryBaud, and frees a slot.
constexpr std::uint32_t kTxWaitTicks = 100;
/// Received bytes the ring holds. The main loop's longest busy stretch is an identify command's preparation: up to
/// four scales of its check, 140 million instructions each (table target_instructions), about 3 s at 168 MHz. A
/// client meanwhile resends the command every 0.5 s (61 B) and keeps the link alive every 0.1 s (35 B): about
/// 400 B/s, so 2 KiB hold 5 s of it. (A path check, 1 to 2 ms, is the longest stretch while a motion runs.)
constexpr unsigned kRxBytes = 2048;

/// Runs f with the control interrupt held off (BASEPRI at its priority), the E-stop and the USART's
/// receive interrupt still taken: the main loop's side of what it shares with the tick (the command
/// mailbox, the transmit queue). Keep f short (a copy, a few stores): the tick waits meanwhile.
template <class F>
void with_tick_masked(F&& f) {
  const std::uint32_t old = cortex_m::basepri_raise(kControlPriority, kPriorityBits);
  f();
  cortex_m::basepri_restore(old);
}

/// The QEMU image's encoders: a still robot, with no index pulse.
struct StillEncoders {
  void init(const stm32f4::Chip&) {}
  void read(std::int32_t counts[hal::kJoints]) {
    for (int i = 0; i < hal::kJoints; ++i) counts[i] = 0;
  }
  bool take_index(int, std::int32_t&) { return false; }
};
using Encoders = std::conditional_t<kQemu, StillEncoders, stm32f4::EncoderBank<stm32f4::pins::kEncoders>>;

/// The QEMU image's analog inputs: none (QEMU has no DMA2 and no scan): never a potentiometer's or a
/// current's sample.
struct NoAnalogInputs {
  void init(const stm32f4::Chip&, std::uint32_t) {}
  bool update() { return false; }
  bool read(std::uint16_t*) const { return false; }
  bool read_currents(std::int16_t*) const { return false; }
};
using Analog = std::conditional_t<kQemu, NoAnalogInputs, stm32f4::AnalogInputs>;
/// The first `n` conversions of the scan (all by default) [ns] at a PCLK2.
constexpr std::uint32_t scan_ns_at(std::uint32_t pclk2, int n = stm32f4::AnalogInputs::kCount) {
  return stm32f4::AnalogInputs::scan_ns(pclk2 / stm32f4::adc_divider(pclk2), n);
}
/// A scan fits a tick, on the PLL and on the HSI fallback alike (each tick takes the one before), with
/// room to spare; the currents, converted first, within the tick's first 20 us on the PLL.
static_assert(scan_ns_at(stm32f4::kPllClocks.pclk2) < 1000000000u / kControlHz / 4 &&
                  scan_ns_at(stm32f4::kHsiClocks.pclk2) < 1000000000u / kControlHz / 2,
              "the analog scan well within the tick");
static_assert(scan_ns_at(stm32f4::kPllClocks.pclk2, hal::kJoints) < 20000u, "the currents at the tick's start");

/// Step timing: the DWT cycle counter, or SysTick where the DWT does not count (start() finds out).
struct CycleCounter {
  static inline bool dwt = false;
  static void start() {
    dwt = cortex_m::dwt_start();
    if (!dwt) cortex_m::systick_free_run();
  }
  /// Processor clock cycles. With SysTick, call at least every 2^24 cycles (0.1 s): every tick does.
  static std::uint32_t cycles() { return dwt ? cortex_m::dwt_cycles() : cortex_m::systick_cycles(); }
};

/// Why the MCU last reset (RCC_CSR's flags, read at boot and cleared).
inline const char* reset_cause_name(std::uint32_t csr) {
  using R = stm32f4::RccRegs;
  if (csr & R::kIwdgRstf) return "watchdog";
  if (csr & R::kSftRstf) return "software";
  if (csr & R::kPorRstf) return "power-on";
  if (csr & R::kPinRstf) return "reset pin";
  return "unknown";
}

using Dac = ad5754r::DacPair<stm32f4::SpiDacBus>;
using Hal = stm32f4::BoardHal<Encoders, Dac, CycleCounter, Analog>;
static_assert(hal::ControlHal<Hal> && hal::PositionHal<Hal> && hal::CurrentHal<Hal>);
/// The USART link: commands in, answer, state and telemetry frames out.
using Uart = stm32f4::UsartLink<kTxFrames, pil::kMaxFrame, kRxBytes>;

/// The board: its drivers and what the boot found.
struct Board {
  stm32f4::Chip chip = stm32f4::Chip::hardware();
  stm32f4::Clocks clocks{};
  BootFault boot = BootFault::kNone;  ///< the first boot fault (docs/stm32f4.md, "Boot faults")
  std::uint32_t reset_flags = 0;
  Encoders encoders;
  Analog analog;
  stm32f4::SpiDacBus dac_bus;
  Dac dac{dac_bus};
  stm32f4::Safety safety;
  Uart uart;
  Hal hal{encoders, dac, analog, safety, chip.timer(kControlTimer)};

  /// Boot, with interrupts still off: clocks (bounded, HSI fallback), the reset cause, the cycle
  /// counter, the safety outputs first (amplifier disabled) and inputs, the DACs at 0 V, the encoders and
  /// their index captures, the analog inputs' ADC (the first tick starts its first scan), the USART link.
  /// A boot fault keeps the torque off for good (Hal::permit_torque).
  void init() {
    clocks = stm32f4::clock_init(*chip.rcc, *chip.flash);
    note(clocks.fault);
    reset_flags = chip.rcc->CSR;
    chip.rcc->CSR = chip.rcc->CSR | stm32f4::RccRegs::kRmvf;
    CycleCounter::start();
    chip.rcc->AHB1ENR = chip.rcc->AHB1ENR | 0x1Fu;  // GPIO ports A..E
    stm32f4::read_back(chip.rcc->AHB1ENR);
    safety.init(chip);
    dac_bus.init(chip, clocks.pclk1);
    if (!dac.init()) note(BootFault::kDacSetup);
    encoders.init(chip);
    analog.init(chip, clocks.pclk2);
    uart.init(chip, clocks.pclk1, kTelemetryBaud, stm32f4::pins::kUartTx, stm32f4::pins::kUartRx);
  }
  /// The independent watchdog: from here on only healthy ticks keep the MCU out of reset.
  void start_watchdog() { note(safety.watchdog_start()); }
  /// The E-stop interrupt, the USART's receive interrupt and the 1 kHz control interrupt, with
  /// their priorities.
  void start_control() {
    cortex_m::irq_priority(kEstopIrq, kEstopPriority, kPriorityBits);
    cortex_m::irq_priority(kUsart2Irq, kUsartPriority, kPriorityBits);
    cortex_m::irq_priority(kControlIrq, kControlPriority, kPriorityBits);
    cortex_m::irq_enable(kEstopIrq);
    cortex_m::irq_enable(kUsart2Irq);
    if constexpr (!kQemu) {
      chip.rcc->APB1ENR = chip.rcc->APB1ENR | stm32f4::RccRegs::kTim6En;
      stm32f4::read_back(chip.rcc->APB1ENR);
    }
    stm32f4::control_timer_start(chip.timer(kControlTimer),
                                 kQemu ? qemu_control_divider() : stm32f4::control_divider(timer_hz(), kControlHz));
    cortex_m::irq_enable(kControlIrq);
  }
  /// The control timer's acknowledgement, first thing in its interrupt.
  void control_ack() { stm32f4::control_timer_ack(chip.timer(kControlTimer)); }

  /// The control timer's kernel clock (TIM6 and TIM2 are both on APB1).
  std::uint32_t timer_hz() const { return kQemu ? kQemuTimerHz : clocks.tim_apb1; }
  /// The cycle counter's rate.
  std::uint32_t cycle_hz() const { return kQemu ? kQemuCpuHz : clocks.sysclk; }
  /// The outputs to their safe state (fault handlers, E-stop): amplifier off, LED on, DACs to 0 V.
  void safe_state() {
    safety.force_safe();
    dac.clear();
  }
  /// The boot report, one line: "<fault or ok>, sysclk, reset cause".
  cortex_m::text::Line& describe(cortex_m::text::Line& l) const {
    return l.str("boot ")
        .str(stm32f4::boot_fault_name(boot))
        .str(", sysclk ")
        .u32(clocks.sysclk)
        .str(clocks.on_pll() ? " Hz (HSE, PLL)" : " Hz (HSI fallback)")
        .str(", reset cause ")
        .str(reset_cause_name(reset_flags))
        .str(", cycle counter ")
        .str(CycleCounter::dwt ? "DWT" : "SysTick");
  }

 private:
  void note(BootFault f) {
    if (boot == BootFault::kNone) boot = f;
    hal.permit_torque(boot == BootFault::kNone);
  }
};

}  // namespace board
