// STM32F405/407 external interrupts 0..81 (RM0090 table 61), placed right after the common system
// vectors (boards/common/cortex_m/startup.cpp). The board uses four (board.hpp, "Interrupts"):
// EXTI1 (the E-stop), USART2 (the command link's received bytes), TIM6_DAC (the control interrupt)
// and TIM2 (the control interrupt of the QEMU images: netduinoplus2 has no TIM6). Every other one is unexpected and
// traps (Default_Handler: the outputs to their safe state, then a report).
extern "C" {
void Default_Handler();  // boards/common/cortex_m/startup.cpp
void Unused_Irq_Handler() { Default_Handler(); }
void EXTI1_Handler() __attribute__((weak, alias("Unused_Irq_Handler")));
void TIM2_Handler() __attribute__((weak, alias("Unused_Irq_Handler")));
void TIM6_DAC_Handler() __attribute__((weak, alias("Unused_Irq_Handler")));
void USART2_Handler() __attribute__((weak, alias("Unused_Irq_Handler")));
}

namespace {
using Handler = void (*)();
constexpr Handler D = Unused_Irq_Handler;
constexpr int kIrqs = 82;
}  // namespace

__attribute__((section(".isr_vector.irq"), used)) const Handler g_irq_vectors[kIrqs] = {
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    EXTI1_Handler,
    D,
    D,  // 0..9: WWDG, PVD, TAMP_STAMP, RTC_WKUP, FLASH, RCC, EXTI0..3
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,  // 10..19: EXTI4, DMA1 streams 0..6, ADC, CAN1_TX
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    TIM2_Handler,
    D,  // 20..29: CAN1, EXTI9_5, TIM1, TIM2 (28), TIM3
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    USART2_Handler,
    D,  // 30..39: TIM4, I2C1/2, SPI1/2, USART1, USART2 (38), USART3
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,  // 40..49: EXTI15_10, RTC_Alarm, OTG_FS_WKUP, TIM8, DMA1_7, FSMC, SDIO
    D,
    D,
    D,
    D,
    TIM6_DAC_Handler,
    D,
    D,
    D,
    D,
    D,  // 50..59: TIM5, SPI3, UART4/5, TIM6_DAC (54), TIM7, DMA2
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,  // 60..69: DMA2, ETH, CAN2, OTG_FS, DMA2
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,
    D,  // 70..79: DMA2_7, USART6, I2C3, OTG_HS, DCMI, CRYP
    D,
    D,  // 80..81: HASH_RNG, FPU
};
