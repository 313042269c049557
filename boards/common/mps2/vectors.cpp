// MPS2 external interrupts 0..31 (CMSDK peripherals; the same numbers on AN385 and AN386), placed
// right after the common system vectors (boards/common/cortex_m/startup.cpp). Only the timers are
// used, and UART0's receive interrupt (the PIL image sleeps until a byte comes); the rest trap.
extern "C" {
void Default_Handler();  // boards/common/cortex_m/startup.cpp: reports and exits
void Unused_Irq_Handler() { Default_Handler(); }
void UART0RX_Handler() __attribute__((weak, alias("Unused_Irq_Handler")));
void TIMER0_Handler() __attribute__((weak, alias("Unused_Irq_Handler")));
void TIMER1_Handler() __attribute__((weak, alias("Unused_Irq_Handler")));
}

namespace {
using Handler = void (*)();
constexpr Handler D = Unused_Irq_Handler;
}  // namespace

__attribute__((section(".isr_vector.irq"), used)) const Handler g_irq_vectors[32] = {
    UART0RX_Handler,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    TIMER0_Handler,
    TIMER1_Handler,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
};
