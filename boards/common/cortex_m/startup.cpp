// Reset and system exceptions, shared by every Cortex-M board: FPU on (where there is one), .data
// copied, .bss zeroed, the main stack painted for the high-water mark, the reset record read (the
// cause of this reset), static constructors, main(), semihosting exit with main's status. The fault
// handlers first put the board's outputs in their safe state (osc_safe_state(), cortex_m.hpp). The
// 16 system entries of the vector table are here, in section .isr_vector; each board's vectors.cpp
// places its external interrupts right after them, in .isr_vector.irq (the linker scripts keep the
// two in that order).
#include <cstdint>

#include "cortex_m.hpp"

extern "C" {
extern std::uint32_t __stack_limit__, __stack_top__;
extern std::uint32_t __data_start__, __data_end__, __data_load__;
extern std::uint32_t __bss_start__, __bss_end__;
extern void (*__init_array_start)();
extern void (*__init_array_end)();
int application_main() __asm__("main");  // the image's main(), called once

[[noreturn]] void Reset_Handler();
void Default_Handler();
void HardFault_Handler();
void NMI_Handler() __attribute__((weak, alias("Default_Handler")));
void MemManage_Handler() __attribute__((weak, alias("HardFault_Handler")));
void BusFault_Handler() __attribute__((weak, alias("HardFault_Handler")));
void UsageFault_Handler() __attribute__((weak, alias("HardFault_Handler")));
void SVC_Handler() __attribute__((weak, alias("Default_Handler")));
void PendSV_Handler() __attribute__((weak, alias("Default_Handler")));
void SysTick_Handler() __attribute__((weak, alias("Default_Handler")));
void osc_safe_state() __attribute__((weak));
}

extern "C" void osc_safe_state() {}

namespace {
constexpr std::uint32_t kPaint = 0xC0FFEE11u;
using Handler = void (*)();

/// The reset record (cortex_m.hpp), in RAM that survives a reset.
struct ResetRecord {
  std::uint32_t magic;            // kRecordMagic: written by this firmware since the power-on
  std::uint32_t watchdog_noted;   // note_watchdog_expiry() ran: the next reset is the watchdog's
  std::uint32_t watchdog_resets;  // since the power-on
  std::uint32_t faults;           // as noted at the last watchdog expiry
  std::uint32_t check;            // seal(): tells a written record from undefined RAM
  std::uint32_t seal() const { return ~(magic ^ watchdog_noted ^ (watchdog_resets * 0x9E3779B9u) ^ faults); }
};
constexpr std::uint32_t kRecordMagic = 0x52535431u;
__attribute__((section(".noinit"))) volatile ResetRecord g_reset_record;
cortex_m::ResetCause g_reset_cause;
std::uint32_t g_watchdog_faults;

/// Reads the record left by the previous run (if any) and starts a new one.
void read_reset_record() {
  ResetRecord r;
  r.magic = g_reset_record.magic;
  r.watchdog_noted = g_reset_record.watchdog_noted;
  r.watchdog_resets = g_reset_record.watchdog_resets;
  r.faults = g_reset_record.faults;
  r.check = g_reset_record.check;
  if (r.magic != kRecordMagic || r.check != r.seal()) {
    g_reset_cause = cortex_m::ResetCause::kPowerOn;
    r.watchdog_resets = 0;
  } else if (r.watchdog_noted != 0) {
    g_reset_cause = cortex_m::ResetCause::kWatchdog;
    ++r.watchdog_resets;
    g_watchdog_faults = r.faults;
  } else {
    g_reset_cause = cortex_m::ResetCause::kOther;
  }
  r.magic = kRecordMagic;
  r.watchdog_noted = 0;
  r.faults = 0;
  g_reset_record.magic = r.magic;
  g_reset_record.watchdog_noted = r.watchdog_noted;
  g_reset_record.watchdog_resets = r.watchdog_resets;
  g_reset_record.faults = r.faults;
  g_reset_record.check = r.seal();
}
}  // namespace

__attribute__((section(".isr_vector"), used)) const Handler g_system_vectors[16] = {
    reinterpret_cast<Handler>(&__stack_top__),
    Reset_Handler,
    NMI_Handler,
    HardFault_Handler,
    MemManage_Handler,
    BusFault_Handler,
    UsageFault_Handler,
    nullptr,
    nullptr,
    nullptr,
    nullptr,
    SVC_Handler,
    nullptr,
    nullptr,
    PendSV_Handler,
    SysTick_Handler,
};

extern "C" void Default_Handler() {
  osc_safe_state();
  cortex_m::semihost::write("unexpected interrupt\n");
  cortex_m::semihost::exit(90);
}

extern "C" void HardFault_Handler() {
  osc_safe_state();
  cortex_m::semihost::write("hard fault\n");
  cortex_m::semihost::exit(91);
}

extern "C" [[noreturn]] void Reset_Handler() {
#if defined(__ARM_FP)
  // FPU: full access to CP10 and CP11 before any floating-point instruction.
  cortex_m::scb_cpacr() |= (0xFu << 20);
  __asm__ volatile("dsb\n isb" ::: "memory");
#endif
  for (std::uint32_t *s = &__data_load__, *d = &__data_start__; d < &__data_end__;) *d++ = *s++;
  for (std::uint32_t* d = &__bss_start__; d < &__bss_end__;) *d++ = 0;
  // Paint the stack below the current frame.
  std::uint32_t* sp;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  for (std::uint32_t* p = &__stack_limit__; p < sp - 16; ++p) *p = kPaint;
  read_reset_record();
  for (void (**f)() = &__init_array_start; f < &__init_array_end; ++f) (*f)();
  cortex_m::semihost::exit(application_main());
}

std::uint32_t cortex_m::stack_used() {
  const std::uint32_t* p = &__stack_limit__;
  while (p < &__stack_top__ && *p == kPaint) ++p;
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(&__stack_top__) -
                                    reinterpret_cast<std::uintptr_t>(p));
}

std::uint32_t cortex_m::stack_used_sweep() {
  // `mark`: the lowest word found written, so far; `next`: the sweep's next word, from the limit
  // up to the mark, then from the limit again. Any word below the mark that gets written is met
  // by the next sweep.
  static const std::uint32_t* mark = &__stack_top__;
  static const std::uint32_t* next = &__stack_limit__;
  for (int k = 0; k < kStackSweepWords && next < mark; ++k, ++next)
    if (*next != kPaint) mark = next;
  if (next >= mark) next = &__stack_limit__;
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(&__stack_top__) -
                                    reinterpret_cast<std::uintptr_t>(mark));
}

cortex_m::ResetCause cortex_m::reset_cause() { return g_reset_cause; }
std::uint32_t cortex_m::watchdog_resets() { return g_reset_record.watchdog_resets; }
std::uint32_t cortex_m::watchdog_faults() { return g_watchdog_faults; }

void cortex_m::note_watchdog_expiry(std::uint32_t faults) {
  ResetRecord r;
  r.magic = kRecordMagic;
  r.watchdog_noted = 1;
  r.watchdog_resets = g_reset_record.watchdog_resets;
  r.faults = faults;
  g_reset_record.watchdog_noted = r.watchdog_noted;
  g_reset_record.faults = r.faults;
  g_reset_record.check = r.seal();
  g_reset_record.magic = r.magic;
}
