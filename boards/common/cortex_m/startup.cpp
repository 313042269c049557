// Reset and system exceptions, shared by every Cortex-M board: FPU on (where there is one), .data
// copied, .bss zeroed, the main stack painted for the high-water mark, static constructors, main(),
// semihosting exit with main's status. The 16 system entries of the vector table are here, in
// section .isr_vector; each board's vectors.cpp places its external interrupts right after them,
// in .isr_vector.irq (the linker scripts keep the two in that order).
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
}

namespace {
constexpr std::uint32_t kPaint = 0xC0FFEE11u;
using Handler = void (*)();
}  // namespace

__attribute__((section(".isr_vector"), used)) const Handler g_system_vectors[16] = {
    reinterpret_cast<Handler>(&__stack_top__),
    Reset_Handler,
    NMI_Handler,
    HardFault_Handler,
    MemManage_Handler,
    BusFault_Handler,
    UsageFault_Handler,
    nullptr, nullptr, nullptr, nullptr,
    SVC_Handler,
    nullptr, nullptr,
    PendSV_Handler,
    SysTick_Handler,
};

extern "C" void Default_Handler() {
  cortex_m::semihost::write("unexpected interrupt\n");
  cortex_m::semihost::exit(90);
}

extern "C" void HardFault_Handler() {
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
  for (void (**f)() = &__init_array_start; f < &__init_array_end; ++f) (*f)();
  cortex_m::semihost::exit(application_main());
}

std::uint32_t cortex_m::stack_used() {
  const std::uint32_t* p = &__stack_limit__;
  while (p < &__stack_top__ && *p == kPaint) ++p;
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(&__stack_top__) -
                                    reinterpret_cast<std::uintptr_t>(p));
}
