// What every QEMU MPS2 board built from Arm's CMSDK parts shares (mps2-an385: Cortex-M3;
// mps2-an386: Cortex-M4F): the 25 MHz system clock, the memory map (linker/mps2.ld), the CMSDK APB
// UARTs, timers and watchdog at the same addresses, the same interrupt numbers (vectors.cpp). One
// header of wiring over the shared Cortex-M code (boards/common/cortex_m): clock, register blocks,
// drivers as static functions; no virtual calls, no heap. A board's board.hpp includes it and adds
// what differs: its core and the scalar its images compute in (board::Scalar).
//
// Under QEMU with -icount shift=0 one instruction takes 1 ns of virtual time and the 25 MHz
// peripherals tick every 40 instructions; Board::cycles() therefore counts instructions, with a
// resolution of 40.
//
// UARTs: the n-th -serial option of QEMU is UART n (UART0 at 0x40004000 is the first).
#pragma once

#include <cstdint>

#include "cmsdk_watchdog.hpp"
#include "cortex_m.hpp"
#include "osc/control/params.hpp"

namespace board {

constexpr std::uint32_t kSysClockHz = 25000000;
/// The control rate is the controller's (one source: osc::params::kControlHz).
constexpr std::uint32_t kControlHz = osc::params::kControlHz;
static_assert(kSysClockHz % kControlHz == 0, "the control timer divides the clock exactly");
/// Virtual-time nanoseconds (= instructions under -icount shift=0) per processor clock cycle.
constexpr std::uint32_t kNsPerTick = 1000000000u / kSysClockHz;

namespace semihost = cortex_m::semihost;

struct CmsdkUart {
  volatile std::uint32_t DATA, STATE, CTRL, INTSTATUS, BAUDDIV;
  static constexpr std::uint32_t kTxFull = 1u << 0, kRxFull = 1u << 1;
  static constexpr std::uint32_t kTxEnable = 1u << 0, kRxEnable = 1u << 1, kRxIrqEnable = 1u << 3;
  static constexpr std::uint32_t kRxIrq = 1u << 1;  // INTSTATUS (write 1 to clear)
};
struct CmsdkTimer {
  volatile std::uint32_t CTRL, VALUE, RELOAD, INTSTATUS;
  static constexpr std::uint32_t kEnable = 1u << 0, kIrqEnable = 1u << 3;
};

inline CmsdkUart& uart0() { return *reinterpret_cast<CmsdkUart*>(0x40004000u); }
inline CmsdkTimer& timer0() { return *reinterpret_cast<CmsdkTimer*>(0x40000000u); }
inline CmsdkTimer& timer1() { return *reinterpret_cast<CmsdkTimer*>(0x40001000u); }

constexpr int kUart0RxIrq = 0;
constexpr int kTimer0Irq = 8;
constexpr int kTimer1Irq = 9;

// ---------------------------------------------------------------- UART0 (polling)
inline void uart_init() {
  uart0().BAUDDIV = 16;  // QEMU does not model the baud rate but wants a valid divider
  uart0().CTRL = CmsdkUart::kTxEnable | CmsdkUart::kRxEnable;
}
inline void uart_write(const std::uint8_t* p, int n) {
  for (int i = 0; i < n; ++i) {
    while (uart0().STATE & CmsdkUart::kTxFull) {
    }
    uart0().DATA = p[i];
  }
}
inline bool uart_rx_ready() { return (uart0().STATE & CmsdkUart::kRxFull) != 0; }
inline std::uint8_t uart_read() { return static_cast<std::uint8_t>(uart0().DATA); }
/// UART0's receive interrupt (UART0RX_Handler), raised by every received byte: it only wakes the
/// core from WFI (sleep_until_rx_or_irq); the handler acknowledges it, the byte stays for uart_read().
inline void uart_rx_irq_enable() {
  uart0().INTSTATUS = CmsdkUart::kRxIrq;
  uart0().CTRL = uart0().CTRL | CmsdkUart::kRxIrqEnable;
  cortex_m::irq_enable(kUart0RxIrq);
}
inline void uart_rx_irq_ack() { uart0().INTSTATUS = CmsdkUart::kRxIrq; }

// ---------------------------------------------------------------- timing
/// The CMSDK APB dual timer (0x40002000, Arm DDI 0479 "APB dual-input timers"): its first timer free-running
/// in 32 bits at the 25 MHz clock (no prescale, no interrupt) is the cycle counter, counting down from
/// 0xFFFFFFFF and wrapping there. The guest starts it, as it starts the control timer: the two keep one phase
/// (the tick's marks read it at the same instructions run after run).
struct CmsdkDualTimer {
  volatile std::uint32_t LOAD, VALUE, CONTROL, INTCLR, RIS, MIS, BGLOAD;
  static constexpr std::uint32_t kEnable = 1u << 7, kSize32 = 1u << 1;  // free-running (bit 6 clear), no prescale
};
inline CmsdkDualTimer& dual_timer1() { return *reinterpret_cast<CmsdkDualTimer*>(0x40002000u); }
/// Starts the cycle counter (the dual timer's first timer, free-running).
inline void cycle_counter_init() {
  dual_timer1().CONTROL = 0;
  dual_timer1().LOAD = 0xFFFFFFFFu;
  dual_timer1().CONTROL = CmsdkDualTimer::kEnable | CmsdkDualTimer::kSize32;
}
/// Monotonic virtual nanoseconds (instructions under -icount shift=0), modulo 2^32: differences hold for
/// spans under 4.29 s. One load (no wrap to extend): the tick reads it at each of its stages' marks
/// (osc::control_tick).
inline std::uint32_t cycles() { return ~dual_timer1().VALUE * kNsPerTick; }
inline void busy_wait(std::uint32_t ns) {
  const std::uint32_t t0 = cycles();
  while (cycles() - t0 < ns) {
  }
}

/// A CMSDK timer interrupting periodically at hz on irq.
inline void periodic_timer_start(CmsdkTimer& t, int irq, std::uint32_t hz) {
  t.CTRL = 0;
  t.RELOAD = kSysClockHz / hz - 1;
  t.VALUE = kSysClockHz / hz - 1;
  t.INTSTATUS = 1;
  t.CTRL = CmsdkTimer::kEnable | CmsdkTimer::kIrqEnable;
  cortex_m::irq_enable(irq);
}

// ---------------------------------------------------------------- control timer (TIMER0, IRQ 8)
/// Periodic TIMER0 interrupt at hz.
inline void control_timer_start(std::uint32_t hz) { periodic_timer_start(timer0(), kTimer0Irq, hz); }
/// Enables the control interrupt without the hardware timer: software pends it (PIL mode).
inline void control_irq_enable() { cortex_m::irq_enable(kTimer0Irq); }
/// Pends the control interrupt: it is taken right after this call.
inline void control_irq_pend() { cortex_m::irq_pend(kTimer0Irq); }
inline void control_timer_ack() { timer0().INTSTATUS = 1; }
inline bool control_timer_pending() { return (timer0().INTSTATUS & 1u) != 0; }
/// Stops the control interrupt (NVIC): no tick is taken after this call.
inline void control_irq_disable() { cortex_m::irq_disable(kTimer0Irq); }

// ---------------------------------------------------------------- wake-up timer (TIMER1, IRQ 9)
/// Periodic TIMER1 interrupt at hz, whose only job is to end a WFI (TIMER1_Handler acknowledges
/// it): a main loop that sleeps until the next byte still runs its time-based checks.
inline void wake_timer_start(std::uint32_t hz) { periodic_timer_start(timer1(), kTimer1Irq, hz); }
inline void wake_timer_ack() { timer1().INTSTATUS = 1; }
/// Sleeps (WFI) unless a byte is waiting in UART0; returns after any interrupt (a received byte
/// with uart_rx_irq_enable(), the wake-up timer), its handler run.
inline void sleep_until_rx_or_irq() {
  cortex_m::sleep_while([] { return !uart_rx_ready(); });
}

// ---------------------------------------------------------------- fault line
/// QEMU's MPS2 boards model no free output pin for an interlock; the binding keeps the level here
/// (a real board drives its amplifier-enable line). The link frames carry the state to the host.
inline volatile bool g_fault_line = false;
inline void fault_output(bool active) { g_fault_line = active; }

// ---------------------------------------------------------------- watchdog (CMSDK APB watchdog)
// At 0x40008000 on WDOGCLK = the 25 MHz system clock; its interrupt is the NMI (AN385 and AN386;
// QEMU's hw/arm/mps2.c wires it the same way on every MPS2 machine). The reset output resets the whole board.
using Watchdog = cmsdk::Watchdog<0x40008000u>;
/// The first expiry (the NMI) comes kWatchdogPeriods control periods after the last feed, the
/// reset as many again after it: a healthy tick feeds every period, so three late or missing feeds
/// are tolerated, a stale torque command is held for at most 4 ms before the NMI drops the fault
/// line, and the board resets 8 ms after the last healthy tick (docs/firmware.md, "Watchdog").
constexpr std::uint32_t kWatchdogPeriods = 4;
constexpr std::uint32_t kWatchdogExpiryNs = kWatchdogPeriods * (1000000000u / kControlHz);
constexpr std::uint32_t kWatchdogLoad = cmsdk::watchdog_load(kSysClockHz, kWatchdogExpiryNs / 1000u);
static_assert(kWatchdogLoad == 100000u, "4 ms at 25 MHz");

/// Starts the watchdog (counting from a full timeout).
inline void watchdog_start() { Watchdog::start(kWatchdogLoad); }
/// Restarts the count. Call only at the end of a healthy tick (osc::supervisor_healthy), or
/// where an image documents another rule (pil_firmware.cpp).
inline void watchdog_feed() { Watchdog::feed(); }
/// Stops the watchdog (test images, once their run is over).
inline void watchdog_stop() { Watchdog::stop(); }
/// Pauses it for a wait of any length up to minutes, as QEMU's model too allows
/// (cmsdk::Watchdog::pause); watchdog_start() resumes it from a full count.
inline void watchdog_pause() { Watchdog::pause(); }
/// The board's reaction to the first expiry, for the image's NMI_Handler: the fault line goes
/// active (on a real board: amplifier enable off, so no stale torque stays applied) and the reset
/// record notes that the reset to come is the watchdog's, with `faults` (the supervisor's latched
/// bits). The image then waits for the reset (await_reset()).
inline void watchdog_expired(std::uint32_t faults) {
  fault_output(true);
  cortex_m::note_watchdog_expiry(faults);
}
/// Waits for the watchdog's reset (one timeout after its first expiry).
[[noreturn]] inline void await_reset() {
  for (;;) {
  }
}

// ---------------------------------------------------------------- reset cause
/// The board has no reset-cause register (nor does QEMU's model); the cause comes from the reset
/// record in .noinit RAM (cortex_m.hpp).
inline cortex_m::ResetCause reset_cause() { return cortex_m::reset_cause(); }
inline const char* reset_cause_name(cortex_m::ResetCause c) {
  switch (c) {
    case cortex_m::ResetCause::kPowerOn:
      return "power-on";
    case cortex_m::ResetCause::kWatchdog:
      return "watchdog";
    case cortex_m::ResetCause::kOther:
      return "other";
  }
  return "?";
}

// ---------------------------------------------------------------- stack
inline std::uint32_t stack_used() { return cortex_m::stack_used(); }
inline std::uint32_t stack_used_sweep() { return cortex_m::stack_used_sweep(); }

}  // namespace board
