// The STM32F407 controller firmware (image stm32f4_firmware): the control task in the 1 kHz TIM6
// interrupt over the board's encoders and DACs (board.hpp), the E-stop interrupt, the watchdog fed
// by healthy ticks, and a telemetry frame (the PIL's actuator frame, osc/link/telemetry.hpp) every
// 10th tick over USART2, sent by the main loop (app.hpp). The QEMU image is qemu_smoke.cpp.
#include "app.hpp"

static_assert(!board::kQemu, "the board's image; the QEMU image is qemu_smoke.cpp");

namespace {
board::App g_app;
}  // namespace

extern "C" void OSC_CONTROL_TIMER_HANDLER() { g_app.control_interrupt(); }

// The E-stop input's rising edge (EXTI1).
extern "C" void EXTI1_Handler() { g_app.estop_interrupt(); }

// Fault handlers (boards/common/cortex_m/startup.cpp) call this first.
extern "C" void osc_safe_state() { g_app.board.safe_state(); }

int main() {
  g_app.boot();
  for (;;) g_app.idle();
}
