// The firmware both STM32F4 images run: the board (board.hpp), the control task, and what the
// interrupts and the main loop do with them. firmware.cpp (image stm32f4_firmware) is the board's
// firmware: these in its interrupts and main loop, nothing else. qemu_smoke.cpp (image
// stm32f4_qemu) is the boot smoke test for QEMU's netduinoplus2: the same boot and ticks, with its
// record and checks around them.
#pragma once

#include <cstdint>

#include "board.hpp"
#include "cortex_m.hpp"
#include "osc/link/telemetry.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/control_task.hpp"
#include "text.hpp"

namespace board {

/// The firmware's state and work; one instance (g_app) in each image.
struct App {
  volatile std::uint32_t ticks = 0;   ///< ticks completed
  volatile std::uint32_t faults = 0;  ///< every fault bit any tick detected
  std::uint32_t frames = 0;           ///< telemetry frames handed to the USART
  Board board;
  osc::ControlTask<float> task;
  std::uint8_t frame[pil::kMaxFrame];

  /// The board's boot (Board::init, interrupts off), the control task at the start pose, the boot
  /// line on the USART, then the watchdog, and the E-stop and control interrupts. Runs once: cold,
  /// compiled for size as GCC compiles main() (without it, inlining the task's set-up here costs
  /// 300 bytes of flash).
  [[gnu::cold]] void boot() {
    board.init();
    task.init(osc::Model<float>::of(osc::robot::kArm), osc::Gains<float>::paper(), osc::FrictionMode::kAdaptive,
              osc::joint_vector<float>(osc::robot::kQStart), board.cycle_hz() / kControlHz);
    cortex_m::text::Line banner;
    board.describe(banner.str("osc stm32f4: "));
    board.uart.write_blocking(banner.text());
    board.uart.write_blocking("\r\n");
    board.start_watchdog();
    board.start_control();
  }

  /// The 1 kHz control interrupt: its acknowledgement, the tick (BoardHal::tick: encoders, control
  /// step, DACs, safety outputs, watchdog), and every kTelemetryEvery-th tick an actuator frame
  /// handed to the USART.
  void control_interrupt() {
    board.control_ack();
    const std::uint32_t k = ticks;
    faults = faults | board.hal.tick(task);
    if (k % kTelemetryEvery == 0) {
      const int n =
          pil::encode(osc::telemetry_frame(task, board.hal.written(), k, cortex_m::stack_used_sweep()), frame);
      if (board.uart.offer(frame, n)) ++frames;
    }
    ticks = k + 1;
  }

  /// The E-stop input's rising edge: amplifier off and DACs to 0 V now, the fault on the next tick.
  void estop_interrupt() {
    board.safety.on_estop_interrupt();
    board.dac.clear();
  }

  /// The main loop's work: the telemetry bytes out.
  void idle() { board.uart.pump(); }

  /// The end of a bounded run (a test image): the control interrupt off, the last frame sent.
  void stop() {
    cortex_m::irq_disable(kControlIrq);
    while (board.uart.busy()) board.uart.pump();
  }
};

}  // namespace board
