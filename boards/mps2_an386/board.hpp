// Board support for QEMU's mps2-an386 (Arm MPS2 with the AN386 FPGA image: Cortex-M4F, 25 MHz
// system clock, CMSDK APB UARTs and timers). One header: constants, register blocks, drivers as
// static functions; no virtual calls, no heap.
//
// Under QEMU with -icount shift=0 one instruction takes 1 ns of virtual time and the 25 MHz
// peripherals tick every 40 instructions; Board::cycles() therefore counts instructions, with a
// resolution of 40.
//
// UARTs: the n-th -serial option of QEMU is UART n (UART0 at 0x40004000 is the first).
#pragma once

#include <cstdint>

namespace board {

constexpr std::uint32_t kSysClockHz = 25000000;
constexpr std::uint32_t kControlHz = 1000;
/// Virtual-time nanoseconds (= instructions under -icount shift=0) per SysTick count.
constexpr std::uint32_t kNsPerTick = 1000000000u / kSysClockHz;

struct CmsdkUart {
  volatile std::uint32_t DATA, STATE, CTRL, INTSTATUS, BAUDDIV;
  static constexpr std::uint32_t kTxFull = 1u << 0, kRxFull = 1u << 1;
  static constexpr std::uint32_t kTxEnable = 1u << 0, kRxEnable = 1u << 1;
};
struct CmsdkTimer {
  volatile std::uint32_t CTRL, VALUE, RELOAD, INTSTATUS;
  static constexpr std::uint32_t kEnable = 1u << 0, kIrqEnable = 1u << 3;
};
struct SysTickRegs {
  volatile std::uint32_t CSR, RVR, CVR, CALIB;
};

inline CmsdkUart& uart0() { return *reinterpret_cast<CmsdkUart*>(0x40004000u); }
inline CmsdkTimer& timer0() { return *reinterpret_cast<CmsdkTimer*>(0x40000000u); }
inline SysTickRegs& systick() { return *reinterpret_cast<SysTickRegs*>(0xE000E010u); }
inline volatile std::uint32_t& nvic_iser0() { return *reinterpret_cast<volatile std::uint32_t*>(0xE000E100u); }
inline volatile std::uint32_t& nvic_ispr0() { return *reinterpret_cast<volatile std::uint32_t*>(0xE000E200u); }
inline volatile std::uint32_t& scb_cpacr() { return *reinterpret_cast<volatile std::uint32_t*>(0xE000ED88u); }

constexpr int kTimer0Irq = 8;

// ---------------------------------------------------------------- semihosting
namespace semihost {
inline int call(int op, const void* arg) {
  register int r0 __asm__("r0") = op;
  register const void* r1 __asm__("r1") = arg;
  __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}
inline void write(const char* s) { call(0x04, s); }  // SYS_WRITE0
[[noreturn]] inline void exit(int code) {
  const std::uint32_t block[2] = {0x20026u, static_cast<std::uint32_t>(code)};  // ApplicationExit
  call(0x20, block);  // SYS_EXIT_EXTENDED
  for (;;) {
  }
}
}  // namespace semihost

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
/// Starts SysTick free-running on the processor clock (24-bit down counter).
inline void cycle_counter_init() {
  systick().RVR = 0x00FFFFFF;
  systick().CVR = 0;
  systick().CSR = (1u << 2) | 1u;  // processor clock, enabled, no interrupt
}
/// Monotonic virtual nanoseconds (instructions under -icount shift=0), extended from SysTick.
/// Must be called at least every 0.67 s to follow the 24-bit wrap.
inline std::uint32_t cycles() {
  static std::uint32_t high = 0, last = 0;
  const std::uint32_t v = 0x00FFFFFFu - (systick().CVR & 0x00FFFFFFu);
  if (v < last) high += 1u << 24;
  last = v;
  return (high + v) * kNsPerTick;
}
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
  nvic_iser0() = 1u << kTimer0Irq;
}
/// Enables the control interrupt without the hardware timer: software pends it (PIL mode).
inline void control_irq_enable() { nvic_iser0() = 1u << kTimer0Irq; }
/// Pends the control interrupt. The barriers make every store made before the call (e.g. fault
/// flags the interrupt reads) visible to it: the interrupt is taken right after the write.
inline void control_irq_pend() {
  __asm__ volatile("dsb" ::: "memory");
  nvic_ispr0() = 1u << kTimer0Irq;
  __asm__ volatile("dsb\n isb" ::: "memory");
}
inline void control_timer_ack() { timer0().INTSTATUS = 1; }
inline bool control_timer_pending() { return (timer0().INTSTATUS & 1u) != 0; }

// ---------------------------------------------------------------- fault line
/// QEMU's mps2-an386 models no free output pin for an interlock; the binding keeps the level here
/// (a real board drives its amplifier-enable line). The link frames carry the state to the host.
inline volatile bool g_fault_line = false;
inline void fault_output(bool active) { g_fault_line = active; }

// ---------------------------------------------------------------- stack
/// Bytes of the main stack ever used (painted at reset).
std::uint32_t stack_used();

}  // namespace board
