// Code shared by every Cortex-M3/M4 board: core registers (SCB, NVIC, SysTick, DWT), semihosting,
// the SysTick- and DWT-based cycle counters, the main-stack high-water mark, the reset record and
// the safe-state hook of the fault handlers. A board adds
// its own clock, peripherals and interrupt table (boards/<board>/board.hpp, vectors.cpp).
#pragma once

#include <cstdint>

namespace cortex_m {

struct SysTickRegs {
  volatile std::uint32_t CSR, RVR, CVR, CALIB;
};
inline SysTickRegs& systick() { return *reinterpret_cast<SysTickRegs*>(0xE000E010u); }
/// NVIC set-enable, clear-enable and set-pending registers: word n covers interrupts 32n..32n+31.
inline volatile std::uint32_t& nvic_iser(int n) { return reinterpret_cast<volatile std::uint32_t*>(0xE000E100u)[n]; }
inline volatile std::uint32_t& nvic_icer(int n) { return reinterpret_cast<volatile std::uint32_t*>(0xE000E180u)[n]; }
inline volatile std::uint32_t& nvic_ispr(int n) { return reinterpret_cast<volatile std::uint32_t*>(0xE000E200u)[n]; }
/// NVIC interrupt priority registers: one byte per interrupt (ARMv7-M ARM, B3.4.9).
inline volatile std::uint8_t& nvic_ipr(int irq) { return reinterpret_cast<volatile std::uint8_t*>(0xE000E400u)[irq]; }
inline volatile std::uint32_t& scb_cpacr() { return *reinterpret_cast<volatile std::uint32_t*>(0xE000ED88u); }

/// Enables external interrupt irq.
inline void irq_enable(int irq) { nvic_iser(irq >> 5) = 1u << (irq & 31); }
/// Disables external interrupt irq; it is not taken after this call returns.
inline void irq_disable(int irq) {
  nvic_icer(irq >> 5) = 1u << (irq & 31);
  __asm__ volatile("dsb\n isb" ::: "memory");
}
/// Pends external interrupt irq. The barriers make every store made before the call (e.g. fault
/// flags the interrupt reads) visible to it: the interrupt is taken right after the write.
inline void irq_pend(int irq) {
  __asm__ volatile("dsb" ::: "memory");
  nvic_ispr(irq >> 5) = 1u << (irq & 31);
  __asm__ volatile("dsb\n isb" ::: "memory");
}
/// Sleeps until an interrupt is pending, without a window for a lost wake-up: interrupts are masked
/// (PRIMASK) while `idle()` is evaluated and during the WFI, which still returns on a pending one;
/// the pending interrupts are taken when the mask is cleared, before this function returns. Does
/// not sleep when idle() is false.
template <class Idle>
inline void sleep_while(Idle idle) {
  __asm__ volatile("cpsid i" ::: "memory");
  if (idle()) __asm__ volatile("dsb\n wfi" ::: "memory");
  __asm__ volatile("cpsie i\n isb" ::: "memory");
}
/// Masks every interrupt of priority `level` and below (numerically level and above: BASEPRI,
/// ARMv7-M B1.4.3; it only ever raises the mask: BASEPRI_MAX); the more urgent ones still come.
/// Returns the mask before, for basepri_restore(). `prio_bits` as irq_priority's.
inline std::uint32_t basepri_raise(unsigned level, int prio_bits) {
  std::uint32_t old;
  __asm__ volatile("mrs %0, basepri" : "=r"(old)::"memory");
  const std::uint32_t mask = level << (8 - prio_bits);
  __asm__ volatile("msr basepri_max, %0\n isb" ::"r"(mask) : "memory");
  return old;
}
/// Puts back the mask basepri_raise() returned.
inline void basepri_restore(std::uint32_t old) { __asm__ volatile("msr basepri, %0\n isb" ::"r"(old) : "memory"); }
/// Sets the priority of external interrupt irq: `level` 0 is the most urgent; the device implements
/// the top `prio_bits` bits of each priority byte (a board constant: 4 on the STM32F4).
inline void irq_priority(int irq, unsigned level, int prio_bits) {
  nvic_ipr(irq) = static_cast<std::uint8_t>(level << (8 - prio_bits));
}

// ---------------------------------------------------------------- DWT cycle counter
// ARMv7-M ARM C1.8: DWT_CTRL (0xE0001000) bit 0 CYCCNTENA, DWT_CYCCNT (0xE0001004) counts processor
// clock cycles; the DWT is enabled by DEMCR (0xE000EDFC) bit 24 TRCENA. Optional: DWT_CTRL bit 25
// NOCYCCNT reads 1 where there is no cycle counter (and an emulator may have no DWT at all).
inline volatile std::uint32_t& dwt_ctrl() { return *reinterpret_cast<volatile std::uint32_t*>(0xE0001000u); }
inline volatile std::uint32_t& dwt_cyccnt() { return *reinterpret_cast<volatile std::uint32_t*>(0xE0001004u); }
inline volatile std::uint32_t& demcr() { return *reinterpret_cast<volatile std::uint32_t*>(0xE000EDFCu); }
/// Starts the DWT cycle counter. Returns false when it does not count (no DWT, or no CYCCNT).
inline bool dwt_start() {
  demcr() = demcr() | (1u << 24);
  dwt_cyccnt() = 0;
  dwt_ctrl() = dwt_ctrl() | 1u;
  const std::uint32_t a = dwt_cyccnt();
  for (int i = 0; i < 8; ++i) __asm__ volatile("nop");
  return dwt_cyccnt() != a;
}
/// Processor clock cycles (32 bits, wraps every 2^32 cycles: 25.6 s at 168 MHz).
inline std::uint32_t dwt_cycles() { return dwt_cyccnt(); }

// ---------------------------------------------------------------- semihosting
namespace semihost {
inline int call(int op, const void* arg) {
  register int r0 __asm__("r0") = op;
  register const void* r1 __asm__("r1") = arg;
  __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}
inline void write(const char* s) { call(0x04, s); }  // SYS_WRITE0
/// SYS_OPEN: a handle for `path` (":tt" is the debugger's console) in `mode` (0 "r", 4 "w"), or -1.
inline int open(const char* path, std::uint32_t length, std::uint32_t mode) {
  const std::uint32_t block[3] = {reinterpret_cast<std::uint32_t>(path), mode, length};
  return call(0x01, block);
}
/// SYS_WRITE (op 0x05) or SYS_READ (op 0x06) of n bytes at p: the number NOT transferred.
inline int transfer(int op, int handle, const void* p, int n) {
  const std::uint32_t block[3] = {static_cast<std::uint32_t>(handle), reinterpret_cast<std::uint32_t>(p),
                                  static_cast<std::uint32_t>(n)};
  return call(op, block);
}
/// SYS_WRITE: writes n bytes; returns how many were NOT written (0 on success).
inline int write(int handle, const void* p, int n) { return transfer(0x05, handle, p, n); }
/// SYS_READ: reads up to n bytes, waiting for at least one; returns how many of the n were NOT read
/// (n at the end of the input).
inline int read(int handle, void* p, int n) { return transfer(0x06, handle, p, n); }
/// SYS_SEEK: the file position of `handle` to byte `pos` from its start; true on success.
inline bool seek(int handle, std::uint32_t pos) {
  const std::uint32_t block[2] = {static_cast<std::uint32_t>(handle), pos};
  return call(0x0A, block) == 0;
}
/// SYS_FLEN: the length in bytes of the file of `handle`, or -1.
inline int file_length(int handle) {
  const std::uint32_t block[1] = {static_cast<std::uint32_t>(handle)};
  return call(0x0C, block);
}
/// SYS_GET_CMDLINE: the command line the debugger passes (QEMU: the -semihosting-config arg=
/// values, else the -kernel file and the -append text), NUL-terminated, into buf[0..n); its length,
/// or -1 when it does not fit.
inline int command_line(char* buf, int n) {
  std::uint32_t block[2] = {reinterpret_cast<std::uint32_t>(buf), static_cast<std::uint32_t>(n)};
  return call(0x15, block) == 0 ? static_cast<int>(block[1]) : -1;
}
[[noreturn]] inline void exit(int code) {
  const std::uint32_t block[2] = {0x20026u, static_cast<std::uint32_t>(code)};  // ApplicationExit
  call(0x20, block);                                                            // SYS_EXIT_EXTENDED
  for (;;) {
  }
}
}  // namespace semihost

// ---------------------------------------------------------------- cycle counter
/// Starts SysTick free-running on the processor clock (24-bit down counter).
inline void systick_free_run() {
  systick().RVR = 0x00FFFFFF;
  systick().CVR = 0;
  systick().CSR = (1u << 2) | 1u;  // processor clock, enabled, no interrupt
}
/// Processor clock cycles since systick_free_run(), extended from the 24-bit SysTick to 32 bits.
/// Must be called at least every 2^24 cycles to follow the wrap.
inline std::uint32_t systick_cycles() {
  static std::uint32_t high = 0, last = 0;
  const std::uint32_t v = 0x00FFFFFFu - (systick().CVR & 0x00FFFFFFu);
  if (v < last) high += 1u << 24;
  last = v;
  return high + v;
}

// ---------------------------------------------------------------- fault handlers
// The common fault handlers (startup.cpp: HardFault and its escalations, any unexpected interrupt)
// first call osc_safe_state(), then report over semihosting and exit. The default does nothing; a
// board with outputs that move the robot defines it to put them in their safe state (amplifiers
// disabled, torque commands zero) with plain register writes: it runs in a fault handler.
extern "C" void osc_safe_state();

// ---------------------------------------------------------------- stack
/// Bytes of the main stack ever used (painted at reset by the common startup code): a scan of
/// the unused part, up to a few thousand words.
std::uint32_t stack_used();
/// The same high-water mark for a periodic caller (the control interrupt's telemetry): each call
/// examines at most kStackSweepWords words of an ongoing sweep and returns the deepest use found
/// so far, so a new depth shows within (stack size / 4 / kStackSweepWords) calls. Never more than
/// stack_used().
std::uint32_t stack_used_sweep();
constexpr int kStackSweepWords = 64;

// ---------------------------------------------------------------- reset record
// Neither the Cortex-M3/M4 core nor QEMU's MPS2 boards have a reset-cause register. The cause is
// kept in a record in .noinit RAM (the linker script places it; the startup code neither loads nor
// zeroes it): the watchdog's interrupt, one timeout before its reset, notes that the reset to come
// is the watchdog's (note_watchdog_expiry); the startup code reads and clears the note before
// main(). A check word tells a written record from the undefined RAM of a power-on.
enum class ResetCause : std::uint8_t {
  kPowerOn = 0,   ///< no valid record: RAM was not retained
  kWatchdog = 1,  ///< the watchdog expired (its interrupt ran) before this reset
  kOther = 2,     ///< RAM retained, the watchdog not involved (e.g. a debugger or software reset)
};
/// The cause of the last reset (set by the startup code before main()).
ResetCause reset_cause();
/// Watchdog resets since the last power-on.
std::uint32_t watchdog_resets();
/// The fault bits passed to note_watchdog_expiry() before the last watchdog reset (0 otherwise).
std::uint32_t watchdog_faults();
/// Called from the watchdog's interrupt: the next reset is the watchdog's; `faults` (e.g. the
/// supervisor's latched bits) are kept for the next boot.
void note_watchdog_expiry(std::uint32_t faults);

}  // namespace cortex_m
