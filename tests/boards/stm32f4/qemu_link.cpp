// The board's firmware on QEMU's netduinoplus2 (image stm32f4_qemu_link; built with OSC_STM32F4_QEMU,
// board.hpp: the tick from TIM2, a still robot): the same App as stm32f4_firmware (app.hpp), the
// command protocol on USART2, running until QEMU ends. ctest stm32f4_qemu_commands drives it with
// the Python client over a pseudo-terminal (qemu_commands.py).
#include "app.hpp"

static_assert(board::kQemu, "the QEMU image (OSC_STM32F4_QEMU)");

namespace {
board::App g_app;
}  // namespace

extern "C" void OSC_CONTROL_TIMER_HANDLER() { g_app.control_interrupt(); }
extern "C" void USART2_Handler() { g_app.uart_interrupt(); }
extern "C" void EXTI1_Handler() { g_app.estop_interrupt(); }
extern "C" void osc_safe_state() { g_app.board.safe_state(); }

int main() {
  g_app.boot();
  for (;;) g_app.idle();
}
