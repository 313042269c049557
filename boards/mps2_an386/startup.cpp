// Reset and vector table for mps2-an386: FPU on, .data copied, .bss zeroed, the main stack painted
// for the high-water mark, static constructors, main(), semihosting exit with main's status.
#include <cstdint>
#include <cstring>

#include "board.hpp"

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
void TIMER0_Handler() __attribute__((weak, alias("Default_Handler")));
void TIMER1_Handler() __attribute__((weak, alias("Default_Handler")));
}

namespace {
constexpr std::uint32_t kPaint = 0xC0FFEE11u;
using Handler = void (*)();
}  // namespace

// 16 system exceptions + 32 interrupts.
__attribute__((section(".isr_vector"), used)) const Handler g_vectors[16 + 32] = {
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
    // IRQ 0..31
    Default_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, TIMER0_Handler, TIMER1_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler,
};

extern "C" void Default_Handler() {
  board::semihost::write("unexpected interrupt\n");
  board::semihost::exit(90);
}

extern "C" void HardFault_Handler() {
  board::semihost::write("hard fault\n");
  board::semihost::exit(91);
}

extern "C" [[noreturn]] void Reset_Handler() {
  // FPU: full access to CP10 and CP11 before any floating-point instruction.
  board::scb_cpacr() |= (0xFu << 20);
  __asm__ volatile("dsb\n isb" ::: "memory");
  for (std::uint32_t *s = &__data_load__, *d = &__data_start__; d < &__data_end__;) *d++ = *s++;
  for (std::uint32_t* d = &__bss_start__; d < &__bss_end__;) *d++ = 0;
  // Paint the stack below the current frame.
  std::uint32_t* sp;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  for (std::uint32_t* p = &__stack_limit__; p < sp - 16; ++p) *p = kPaint;
  for (void (**f)() = &__init_array_start; f < &__init_array_end; ++f) (*f)();
  board::semihost::exit(application_main());
}

std::uint32_t board::stack_used() {
  const std::uint32_t* p = &__stack_limit__;
  while (p < &__stack_top__ && *p == kPaint) ++p;
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(&__stack_top__) -
                                    reinterpret_cast<std::uintptr_t>(p));
}
