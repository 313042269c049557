// The STM32F407 controller firmware (image stm32f4_firmware): the control task in the 1 kHz TIM6
// interrupt over the board's encoders and DACs (board.hpp), the E-stop interrupt, the watchdog fed
// by healthy ticks, and a telemetry frame (the PIL's actuator frame, osc/link/telemetry.hpp) every
// 10th tick over USART2, sent by the main loop.
//
// Built with OSC_STM32F4_QEMU it is the boot smoke test for QEMU's netduinoplus2 (image
// stm32f4_qemu, ctest stm32f4_qemu): the same boot and tick, ticking from TIM2 against a still robot
// (board.hpp); after kSmokeTicks it checks the run, prints it over semihosting and the USART, and
// exits with the verdict as its semihosting status. After tick kEstopTick it presses the E-stop (its
// interrupt, pended in the NVIC).
#include <cstdint>

#include "board.hpp"
#include "osc/link/telemetry.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/control_task.hpp"
#include "text.hpp"

namespace {

using cortex_m::text::Line;

board::Board g_board;
osc::ControlTask<float> g_task;
volatile std::uint32_t g_ticks = 0;   // ticks completed
volatile std::uint32_t g_faults = 0;  // every fault bit any tick detected
std::uint32_t g_frames = 0;           // telemetry frames handed to the USART
std::uint8_t g_frame[pil::kMaxFrame];

// The smoke test's record (QEMU image only).
constexpr std::uint32_t kSmokeTicks = 300, kEstopTick = 250;
std::uint32_t g_stamp[board::kQemu ? kEstopTick : 1];  // cycle counter at each tick's start
struct Snapshot {
  osc::SupervisorState state;
  std::uint32_t latched, feeds;
  std::int32_t task_code, written_max;
  bool amplifier;
};
Snapshot g_before_estop{}, g_after_estop{};
volatile std::uint32_t g_estop_seen_at = 0;     // ticks completed when the E-stop interrupt ran
volatile std::uint32_t g_estop_latched_in = 0;  // the tick that latched `estop`

Snapshot snapshot() {
  std::int32_t w = 0;
  for (int i = 0; i < hal::kJoints; ++i) {
    const std::int32_t c = g_board.hal.written()[i];
    w = c > w ? c : -c > w ? -c : w;
  }
  return {g_task.sup.state,
          g_task.sup.latched,
          g_board.hal.feeds(),
          g_task.codes[1],
          w,
          g_board.safety.amplifier_enabled()};
}

}  // namespace

extern "C" void OSC_CONTROL_TIMER_HANDLER() {
  g_board.control_ack();
  const std::uint32_t k = g_ticks;
  if constexpr (board::kQemu) {
    if (k < kEstopTick) g_stamp[k] = board::CycleCounter::cycles();
  }
  g_faults = g_faults | g_board.hal.tick(g_task);
  if (k % board::kTelemetryEvery == 0) {
    const int n =
        pil::encode(osc::telemetry_frame(g_task, g_board.hal.written(), k, cortex_m::stack_used_sweep()), g_frame);
    if (g_board.uart.offer(g_frame, n)) ++g_frames;
  }
  if constexpr (board::kQemu) {
    if (k + 1 == kEstopTick) g_before_estop = snapshot();
    if (g_estop_latched_in == 0 && (g_task.sup.latched & osc::kFaultEstop)) {
      g_estop_latched_in = k;
      g_after_estop = snapshot();
    }
  }
  g_ticks = k + 1;
}

// The E-stop input's rising edge: amplifier off and DACs to 0 V now, the fault on the next tick.
extern "C" void EXTI1_Handler() {
  g_board.safety.on_estop_interrupt();
  g_board.dac.clear();
  g_estop_seen_at = g_ticks;
}

// Fault handlers (boards/common/cortex_m/startup.cpp) call this first.
extern "C" void osc_safe_state() { g_board.safe_state(); }

namespace {

/// The QEMU smoke test's checks and report; returns the exit status.
int smoke_verdict() {
  const std::uint32_t period = g_board.cycle_hz() / board::kControlHz;
  std::uint32_t lo = 0xFFFFFFFFu, hi = 0;
  for (std::uint32_t k = 1; k < kEstopTick; ++k) {
    const std::uint32_t d = g_stamp[k] - g_stamp[k - 1];
    lo = d < lo ? d : lo;
    hi = d > hi ? d : hi;
  }
  // QEMU has no RCC: the clock set-up must have timed out on the crystal and fallen back.
  const bool boot_ok = g_board.boot == board::BootFault::kHseTimeout && g_board.clocks.sysclk == 16000000u;
  const bool spacing_ok = lo + period / 100 >= period && hi <= period + period / 100;
  const Snapshot& b = g_before_estop;
  const Snapshot& a = g_after_estop;
  // Before the E-stop: the control task ran healthy, commanding torque, but the boot fault kept the
  // DAC codes at zero and the amplifier off; every tick fed the watchdog.
  const bool run_ok = b.state == osc::SupervisorState::kRun && b.latched == 0 && b.task_code != 0 &&
                      b.written_max == 0 && !b.amplifier && b.feeds == kEstopTick;
  // The E-stop: latched by the first tick after its interrupt, zero codes, amplifier off, no feed.
  const bool estop_ok = g_estop_seen_at == kEstopTick && g_estop_latched_in == g_estop_seen_at &&
                        a.state == osc::SupervisorState::kFault && a.latched == osc::kFaultEstop &&
                        a.written_max == 0 && !a.amplifier && a.feeds == kEstopTick;
  const bool telemetry_ok = g_frames == kSmokeTicks / board::kTelemetryEvery && g_board.uart.dropped() == 0;
  const bool ok = boot_ok && spacing_ok && run_ok && estop_ok && telemetry_ok;

  Line l1;
  g_board.describe(l1).emit();
  Line()
      .str("ticks ")
      .u32(g_ticks)
      .str(", spacing ")
      .u32(lo)
      .str("..")
      .u32(hi)
      .str(" cycles (period ")
      .u32(period)
      .str(")")
      .emit();
  Line()
      .str("control step: max ")
      .u32(g_task.step_timing.max)
      .str(", mean ")
      .u32(g_task.step_timing.mean())
      .str(" cycles; whole tick max ")
      .u32(g_task.timing.max)
      .str(" cycles (")
      .u32(g_task.timing.max * 1000u / 168u)
      .str(" instructions at -icount shift=0)")
      .emit();
  Line()
      .str("before the E-stop: state ")
      .u32(static_cast<std::uint32_t>(b.state))
      .str(", faults ")
      .u32(b.latched)
      .str(", torque code joint 2 ")
      .i32(b.task_code)
      .str(", DAC codes written ")
      .str(b.written_max == 0 ? "zero" : "NONZERO")
      .str(" (boot fault), amplifier ")
      .str(b.amplifier ? "ON" : "off")
      .str(", watchdog feeds ")
      .u32(b.feeds)
      .emit();
  Line()
      .str("E-stop: interrupt after tick ")
      .u32(g_estop_seen_at)
      .str(", latched by tick ")
      .u32(g_estop_latched_in)
      .str(", faults ")
      .str(osc::fault_name(a.latched))
      .str(", DAC codes ")
      .str(a.written_max == 0 ? "zero" : "NONZERO")
      .str(", amplifier ")
      .str(a.amplifier ? "ON" : "off")
      .str(", watchdog feeds ")
      .u32(a.feeds)
      .emit();
  Line()
      .str("telemetry: ")
      .u32(g_frames)
      .str(" frames, ")
      .u32(g_board.uart.dropped())
      .str(" dropped; stack used ")
      .u32(cortex_m::stack_used())
      .str(" bytes")
      .emit();
  Line v;
  v.str(ok ? "stm32f4_qemu: pass" : "stm32f4_qemu: FAIL");
  if (!ok)
    v.str(" (boot ")
        .u32(boot_ok)
        .str(", spacing ")
        .u32(spacing_ok)
        .str(", run ")
        .u32(run_ok)
        .str(", estop ")
        .u32(estop_ok)
        .str(", telemetry ")
        .u32(telemetry_ok)
        .str(")");
  g_board.uart.write_blocking(v.text());
  g_board.uart.write_blocking("\r\n");
  v.emit();
  return ok ? 0 : 1;
}

}  // namespace

int main() {
  g_board.init();
  g_task.init(osc::Model<float>::of(osc::robot::kArm), osc::Gains<float>::paper(), osc::FrictionMode::kAdaptive,
              osc::joint_vector<float>(osc::robot::kQStart), g_board.cycle_hz() / board::kControlHz);
  Line banner;
  g_board.describe(banner.str("osc stm32f4: "));
  g_board.uart.write_blocking(banner.text());
  g_board.uart.write_blocking("\r\n");
  g_board.start_watchdog();
  g_board.start_control();
  for (;;) {
    g_board.uart.pump();
    if constexpr (board::kQemu) {
      // The E-stop: QEMU models no GPIO and its EXTI ignores the software trigger (SWIER), so the
      // test pends the E-stop's interrupt itself; the handler is the board's.
      if (g_ticks == kEstopTick && g_estop_seen_at == 0) cortex_m::irq_pend(board::kEstopIrq);
      if (g_ticks >= kSmokeTicks) break;
    }
  }
  cortex_m::irq_disable(board::kControlIrq);
  while (g_board.uart.busy()) g_board.uart.pump();
  return smoke_verdict();
}
