// Board support for QEMU's mps2-an386 (Arm MPS2 with the AN386 FPGA image: Cortex-M4F, 25 MHz
// system clock, CMSDK APB UARTs and timers). One header of wiring over the shared Cortex-M code
// (boards/common/cortex_m): clock, register blocks, drivers as static functions; no virtual calls,
// no heap. Its interrupt table is vectors.cpp.
//
// Under QEMU with -icount shift=0 one instruction takes 1 ns of virtual time and the 25 MHz
// peripherals tick every 40 instructions; Board::cycles() therefore counts instructions, with a
// resolution of 40.
//
// UARTs: the n-th -serial option of QEMU is UART n (UART0 at 0x40004000 is the first).
#pragma once

#include <cstdint>

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
  static constexpr std::uint32_t kTxEnable = 1u << 0, kRxEnable = 1u << 1;
};
struct CmsdkTimer {
  volatile std::uint32_t CTRL, VALUE, RELOAD, INTSTATUS;
  static constexpr std::uint32_t kEnable = 1u << 0, kIrqEnable = 1u << 3;
};

inline CmsdkUart& uart0() { return *reinterpret_cast<CmsdkUart*>(0x40004000u); }
inline CmsdkTimer& timer0() { return *reinterpret_cast<CmsdkTimer*>(0x40000000u); }

constexpr int kTimer0Irq = 8;

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

// ---------------------------------------------------------------- timing
/// Starts the cycle counter (SysTick, free-running).
inline void cycle_counter_init() { cortex_m::systick_free_run(); }
/// Monotonic virtual nanoseconds (instructions under -icount shift=0).
/// Must be called at least every 0.67 s to follow the 24-bit SysTick wrap.
inline std::uint32_t cycles() { return cortex_m::systick_cycles() * kNsPerTick; }
inline void busy_wait(std::uint32_t ns) {
  const std::uint32_t t0 = cycles();
  while (cycles() - t0 < ns) {
  }
}

// ---------------------------------------------------------------- control timer (TIMER0, IRQ 8)
/// Periodic TIMER0 interrupt at hz.
inline void control_timer_start(std::uint32_t hz) {
  timer0().CTRL = 0;
  timer0().RELOAD = kSysClockHz / hz - 1;
  timer0().VALUE = kSysClockHz / hz - 1;
  timer0().INTSTATUS = 1;
  timer0().CTRL = CmsdkTimer::kEnable | CmsdkTimer::kIrqEnable;
  cortex_m::irq_enable(kTimer0Irq);
}
/// Enables the control interrupt without the hardware timer: software pends it (PIL mode).
inline void control_irq_enable() { cortex_m::irq_enable(kTimer0Irq); }
/// Pends the control interrupt: it is taken right after this call.
inline void control_irq_pend() { cortex_m::irq_pend(kTimer0Irq); }
inline void control_timer_ack() { timer0().INTSTATUS = 1; }
inline bool control_timer_pending() { return (timer0().INTSTATUS & 1u) != 0; }

// ---------------------------------------------------------------- fault line
/// QEMU's mps2-an386 models no free output pin for an interlock; the binding keeps the level here
/// (a real board drives its amplifier-enable line). The link frames carry the state to the host.
inline volatile bool g_fault_line = false;
inline void fault_output(bool active) { g_fault_line = active; }

// ---------------------------------------------------------------- stack
inline std::uint32_t stack_used() { return cortex_m::stack_used(); }

}  // namespace board
