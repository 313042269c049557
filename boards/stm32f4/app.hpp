// The firmware every STM32F4 image runs: the board (board.hpp), the control task, the command
// protocol's port on the USART link, and what the interrupts and the main loop do with them. firmware.cpp (image
// stm32f4_firmware) is the board's firmware: these in its interrupts and main loop, nothing else. qemu_smoke.cpp (image
// stm32f4_qemu) is the boot smoke test for QEMU's netduinoplus2: the same boot and ticks, with its
// record and checks around them; image stm32f4_qemu_link is firmware.cpp on QEMU's
// machine, driven over its USART by the Python client (ctest stm32f4_qemu_commands).
//
// The command link (docs/protocol.md, "The command protocol"; docs/stm32f4.md, "Commands"): the
// board starts disabled; the USART's receive interrupt fills a ring; the main loop feeds its bytes to
// the link's parser, hands command and setpoint frames to the port (osc/link/command_port.hpp) and
// prepares the commands (a move's path check) outside the tick; the tick, in the control interrupt,
// takes the mailbox and queues its answer and state frames, and the telemetry frame every 10th tick.
// What the two contexts share, and how:
//   - the command mailbox (task.pending), the setpoint mailbox (task.sample) and what a preparation
//     reads: the main loop touches them only with the control interrupt masked (with_tick_masked:
//     BASEPRI, the E-stop and the receive interrupt still come), for a copy or a few stores, never
//     around a path check (CommandPort::poll_paced);
//   - the transmit queue: two producers (the tick, the main loop) and one consumer (the main loop's
//     pump): the main loop offers with the tick masked;
//   - the receive ring: the receive interrupt produces, the main loop consumes (lock-free);
//   - the link watch: the main loop notes each valid frame (a byte store), the tick counts the
//     silence; a motion that runs after params::kCommandLinkTimeout without a frame (once a host
//     has sent a command) is stopped, category 2, aborted link_silent.
#pragma once

#include <cstdint>

#include "board.hpp"
#include "flash.hpp"  // stm32f4::FlashSectors
#include "cortex_m.hpp"
#include "osc/link/command_port.hpp"
#include "osc/link/identify_port.hpp"
#include "osc/link/telemetry.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/control_task.hpp"
#include "param_store.hpp"
#include "text.hpp"

namespace board {

/// The firmware's state and work; one instance (g_app) in each image.
struct App {
  volatile std::uint32_t ticks = 0;   ///< ticks completed
  volatile std::uint32_t faults = 0;  ///< every fault bit any tick detected
  std::uint32_t frames = 0;           ///< telemetry frames handed to the USART
  std::uint32_t telemetry_held = 0;   ///< telemetry frames not offered: the queue kept room for answers
  std::uint32_t rx_frames = 0;        ///< valid frames received
  std::uint32_t rx_other = 0;         ///< valid frames of a type the board does not take
  std::uint32_t rx_errors = 0;        ///< bad frames and junk (the parser's errors)
  Board board;
  osc::ControlTask<float> task;
  osc::CommandPort<float> port;
  osc::CommandPort<float>::PacedInputs paced;  ///< the port's copy of a command's inputs
  osc::CommandLinkWatch watch;
  /// An identify run's estimate, followed from the main loop (osc/link/identify_port.hpp): the run's ticks from the
  /// task's ring, at least every kServeEveryTicks ticks (the ring holds osc::params::kRunRingTicks).
  osc::IdentifyPort<float> identify;
  std::uint32_t served_tick = 0;                 ///< the tick count at the main loop's last serve()
  float capture_ring[pil::kCaptureValues] = {};  ///< the capture's buffer (osc/link/capture.hpp), 16 KiB
  pil::Parser parser;
  std::uint32_t rx_tick = 0;  ///< the tick count when the last byte was read (the in-frame timeout)
  std::uint8_t frame[pil::kMaxFrame];
  /// The parameters' store: flash sectors 10 and 11 (param_store.hpp). QEMU models no flash
  /// controller: there the command port keeps them in RAM, and the boot says so.
  stm32f4::FlashSectors<> sectors{*board.chip.flash};
  stm32f4::Safety::Stretch stretch{board.safety};
  persist::FlashParamStore<stm32f4::FlashSectors<>, stm32f4::Safety::Stretch> params{sectors, stretch};

  /// The board's boot (Board::init, interrupts off), the control task at the start pose, disabled
  /// (an enable command starts the torque), the boot line on the USART, then the watchdog, and the
  /// E-stop, receive and control interrupts. Runs once: cold, compiled for size as GCC compiles
  /// main() (without it, inlining the task's set-up here costs 300 bytes of flash).
  [[gnu::cold]] void boot() {
    board.init();
    task.init(osc::Model<float>::of(osc::robot::kArm), osc::Gains<float>::paper(), osc::FrictionMode::kAdaptive,
              osc::joint_vector<float>(osc::robot::kQStart), board.cycle_hz() / kControlHz, osc::TaskStart::kDisabled);
    // The arm's own encoders: per-joint resolution and the wrist coupling (robot::kDriveTrain).
    task.set_encoders(osc::robot::kDriveTrain.encoders);
    port.state_period = kStateEvery;
    port.capture.attach(capture_ring, pil::kCaptureValues);
    cortex_m::text::Line banner;
    board.describe(banner.str("osc stm32f4: "));
    board.uart.write_blocking(banner.text());
    board.uart.write_blocking("\r\n");
    cortex_m::text::Line line;
    board.uart.write_blocking(load_params(line.str("osc stm32f4: params ")).text());
    board.uart.write_blocking("\r\n");
    board.start_watchdog();
    board.start_control();
  }

  /// The newest parameter record from flash into the task (before the interrupts start), and the
  /// port's store: "loaded, sequence N", "defaults (none)", "defaults (layout_mismatch)", or a record
  /// the task refused ("defaults (bad_record)"); on QEMU "in RAM (QEMU: no flash controller)".
  [[gnu::cold]] cortex_m::text::Line& load_params(cortex_m::text::Line& l) {
    if constexpr (kQemu) {
      return l.str("in RAM (QEMU: no flash controller), defaults");
    } else {
      port.set_param_storage(params.storage());
      const persist::BootLoad b = params.apply_to(task);
      if (const char* why = b.defaults_why()) return l.str("defaults (").str(why).str(")");
      return l.str("loaded, sequence ").u32(b.load.sequence);
    }
  }

  /// The 1 kHz control interrupt: its acknowledgement, the link watch, the tick (BoardHal::tick:
  /// encoders, control step, DACs, safety outputs, watchdog), the port's answer and state frames, and
  /// every kTelemetryEvery-th tick an actuator frame, while the queue keeps room for answers.
  void control_interrupt() {
    board.control_ack();
    const std::uint32_t k = ticks;
    watch.before_tick(task, port.commanded());
    faults = faults | board.hal.tick(task);
    port.after_tick(task, TickWrite{board.uart});
    if (k % kTelemetryEvery == 0) {
      if (board.uart.queued() > kTxFrames - kTxAnswerReserve) {
        ++telemetry_held;
      } else {
        const int n =
            pil::encode(osc::telemetry_frame(task, board.hal.written(), k, cortex_m::stack_used_sweep()), frame);
        if (board.uart.offer(frame, n)) ++frames;
      }
    }
    ticks = k + 1;
  }

  /// The USART's interrupt: a received byte into the ring.
  void uart_interrupt() { board.uart.on_rx_interrupt(); }

  /// The E-stop input's rising edge: amplifier off and DACs to 0 V now, the fault on the next tick.
  void estop_interrupt() {
    board.safety.on_estop_interrupt();
    board.dac.clear();
  }

  /// The main loop's work: the received bytes through the parser into the port, the waiting
  /// commands prepared into the mailbox, the queued frames out.
  void serve() {
    for (std::uint8_t b; board.uart.read(b);) {
      rx_tick = ticks;
      on_result(parser.feed(b));
    }
    // A frame begun and silent for the in-frame timeout: cut short, its bytes scanned again.
    if (parser.in_frame() && ticks - rx_tick >= osc::kFrameTimeoutTicks) on_result(parser.expire());
    if (port.waiting() > 0)
      port.poll_paced(
          task, paced, MainWrite{board.uart}, [](auto&& f) { with_tick_masked(f); }, [this] { board.uart.pump(); });
    identify.after_tick(task, MainWriteWaiting{*this});
    board.uart.pump();
  }

  /// The main loop: serve(), then sleep until an interrupt (a byte, a tick) unless bytes wait or kServeEveryTicks
  /// ticks have passed (an identify run's ring is read within them).
  void idle() {
    served_tick = ticks;
    serve();
    cortex_m::sleep_while(
        [this] { return board.uart.rx_empty() && !board.uart.busy() && ticks - served_tick < kServeEveryTicks; });
  }

  /// A command straight into the mailbox (a test image's compiled-in step, no link): false while
  /// the mailbox is taken.
  bool command(osc::MotionVerb verb, std::uint32_t id) {
    bool placed = false;
    with_tick_masked([&] {
      if (task.pending.verb != osc::MotionVerb::kNone) return;
      task.pending = osc::prepare_command<float>(verb, id);
      placed = true;
    });
    return placed;
  }

  /// The end of a bounded run (a test image): the control interrupt off, the last frames sent.
  void stop() {
    cortex_m::irq_disable(kControlIrq);
    while (board.uart.busy()) board.uart.pump();
  }

 private:
  /// The tick's writer: the frame into the transmit queue (the tick is the only producer then).
  struct TickWrite {
    Uart& uart;
    void operator()(const std::uint8_t* p, int n) const { uart.offer(p, n); }
  };
  /// The main loop's writer: the same, with the tick masked (the queue's other producer).
  struct MainWrite {
    Uart& uart;
    void operator()(const std::uint8_t* p, int n) const {
      with_tick_masked([&] { uart.offer(p, n); });
    }
  };

  /// The main loop's writer of a frame sent once and never again (an identify run's report): it pumps the
  /// transmitter until the queue has room, for at most kTxWaitTicks. The solve before it keeps the main loop
  /// from pumping for about 0.2 s (27 million instructions, table target_instructions), and the tick's state and
  /// telemetry frames may have filled the queue meanwhile.
  struct MainWriteWaiting {
    App& app;
    void operator()(const std::uint8_t* p, int n) const {
      Uart& uart = app.board.uart;
      const std::uint32_t t0 = app.ticks;
      for (bool taken = false; !taken; uart.pump()) {
        const bool last = app.ticks - t0 >= kTxWaitTicks;  // then offered once more, dropped and counted if full
        with_tick_masked([&] {
          if (last || uart.queued() < kTxFrames) taken = uart.offer(p, n) || last;
        });
      }
    }
  };

  /// A parser result and the further events of the bytes already received: a valid frame is heard
  /// by the link watch and, a command or a setpoint, taken by the port (with the tick masked: the
  /// FIFO, the setpoint mailbox); an error is counted.
  void on_result(pil::Parser::Result r) {
    for (; r != pil::Parser::kPending; r = parser.next()) {
      if (r != pil::Parser::kFrame) {
        ++rx_errors;
        continue;
      }
      ++rx_frames;
      watch.heard();
      bool taken = false;
      with_tick_masked([&] { taken = port.receive(task, parser, MainWrite{board.uart}); });
      if (!taken) ++rx_other;
    }
  }
};

}  // namespace board
