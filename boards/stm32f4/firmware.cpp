// The STM32F407 controller firmware (image stm32f4_firmware): the control task in the 1 kHz TIM6
// interrupt over the board's encoders and DACs (board.hpp), the E-stop interrupt, the watchdog fed
// by healthy ticks, and the command protocol on USART2 (app.hpp): the board starts disabled and
// takes commands (enable, move_to, paper, stop, ...), answering them and sending state frames and a
// telemetry frame (the PIL's actuator frame, osc/link/telemetry.hpp) every 10th tick. The same
// source, compiled with OSC_STM32F4_QEMU (board.hpp: the tick from TIM2, a still robot), is image
// stm32f4_qemu_link on QEMU's netduinoplus2, which ctest stm32f4_qemu_commands drives over USART2;
// the QEMU smoke image is qemu_smoke.cpp.
#include "app.hpp"

namespace {
board::App g_app;
}  // namespace

extern "C" void OSC_CONTROL_TIMER_HANDLER() { g_app.control_interrupt(); }

// The USART's receive interrupt: a byte into the ring.
extern "C" void USART2_Handler() { g_app.uart_interrupt(); }

// The E-stop input's rising edge (EXTI1).
extern "C" void EXTI1_Handler() { g_app.estop_interrupt(); }

// Fault handlers (boards/common/cortex_m/startup.cpp) call this first.
extern "C" void osc_safe_state() { g_app.board.safe_state(); }

int main() {
  g_app.boot();
  for (;;) g_app.idle();
}
