// The boot smoke test for QEMU's netduinoplus2 (image stm32f4_qemu, ctest stm32f4_qemu; built with
// OSC_STM32F4_QEMU, board.hpp): the firmware's boot and ticks (app.hpp), ticking from TIM2 against a
// still robot. The board boots disabled; the test's compiled-in steps enable it (straight into the
// command mailbox, no link) and, once it holds, start the paper's motion, as the commands enable and
// paper over the USART would. It records each tick's start and the state around the E-stop; after tick kEstopTick
// it presses the E-stop (its interrupt, pended in the NVIC); after kSmokeTicks it checks the run,
// prints it over semihosting and the USART, and exits with the verdict as its semihosting status.
// What it checks: docs/stm32f4.md, "The QEMU boot smoke test".
#include <cstdint>

#include "app.hpp"
#include "cortex_m.hpp"
#include "text.hpp"

static_assert(board::kQemu, "the QEMU image (OSC_STM32F4_QEMU)");

namespace {

using cortex_m::text::Line;

board::App g_app;

constexpr std::uint32_t kSmokeTicks = 300, kEstopTick = 250;
std::uint32_t g_stamp[kEstopTick];  // cycle counter at each tick's start
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
    const std::int32_t c = g_app.board.hal.written()[i];
    w = c > w ? c : -c > w ? -c : w;
  }
  return {g_app.task.sup.state,
          g_app.task.sup.latched,
          g_app.board.hal.feeds(),
          g_app.task.codes[1],
          w,
          g_app.board.safety.amplifier_enabled()};
}

}  // namespace

extern "C" void OSC_CONTROL_TIMER_HANDLER() {
  const std::uint32_t k = g_app.ticks;
  if (k < kEstopTick) g_stamp[k] = board::CycleCounter::cycles();
  g_app.control_interrupt();
  if (k + 1 == kEstopTick) g_before_estop = snapshot();
  if (g_estop_latched_in == 0 && (g_app.task.sup.latched & osc::kFaultEstop)) {
    g_estop_latched_in = k;
    g_after_estop = snapshot();
  }
}

// The USART's receive interrupt (nothing arrives here: USART2 goes to a file).
extern "C" void USART2_Handler() { g_app.uart_interrupt(); }

// The E-stop input's rising edge (EXTI1), recorded.
extern "C" void EXTI1_Handler() {
  g_app.estop_interrupt();
  g_estop_seen_at = g_app.ticks;
}

// Fault handlers (boards/common/cortex_m/startup.cpp) call this first.
extern "C" void osc_safe_state() { g_app.board.safe_state(); }

namespace {

/// The spacing of the ticks before the E-stop, in cycles, against the control period.
struct Spacing {
  std::uint32_t lo = 0xFFFFFFFFu, hi = 0, period = 0;
  bool ok() const { return lo + period / 100 >= period && hi <= period + period / 100; }
};
Spacing spacing() {
  Spacing s;
  s.period = g_app.board.cycle_hz() / board::kControlHz;
  for (std::uint32_t k = 1; k < kEstopTick; ++k) {
    const std::uint32_t d = g_stamp[k] - g_stamp[k - 1];
    s.lo = d < s.lo ? d : s.lo;
    s.hi = d > s.hi ? d : s.hi;
  }
  return s;
}

/// The test's checks, each true when it passed.
struct Checks {
  bool boot, spacing, run, estop, telemetry;
  bool ok() const { return boot && spacing && run && estop && telemetry; }
};
Checks check(const Spacing& s) {
  const Snapshot& b = g_before_estop;
  const Snapshot& a = g_after_estop;
  Checks c{};
  // QEMU has no RCC: the clock set-up must have timed out on the crystal and fallen back.
  c.boot = g_app.board.boot == board::BootFault::kHseTimeout && g_app.board.clocks.sysclk == 16000000u;
  c.spacing = s.ok();
  // Before the E-stop: the control task ran healthy, commanding torque, but the boot fault kept the
  // DAC codes at zero and the amplifier off; every tick fed the watchdog.
  c.run = b.state == osc::SupervisorState::kRun && b.latched == 0 && b.task_code != 0 && b.written_max == 0 &&
          !b.amplifier && b.feeds == kEstopTick;
  // The E-stop: latched by the first tick after its interrupt, zero codes, amplifier off, no feed.
  c.estop = g_estop_seen_at == kEstopTick && g_estop_latched_in == g_estop_seen_at &&
            a.state == osc::SupervisorState::kFault && a.latched == osc::kFaultEstop && a.written_max == 0 &&
            !a.amplifier && a.feeds == kEstopTick;
  c.telemetry = g_app.frames == kSmokeTicks / board::kTelemetryEvery && g_app.board.uart.dropped() == 0;
  return c;
}

/// The report's lines on the boot, the tick spacing and the step's timing.
void report_timing(const Spacing& s) {
  Line l1;
  g_app.board.describe(l1).emit();
  Line()
      .str("ticks ")
      .u32(g_app.ticks)
      .str(", spacing ")
      .u32(s.lo)
      .str("..")
      .u32(s.hi)
      .str(" cycles (period ")
      .u32(s.period)
      .str(")")
      .emit();
  Line()
      .str("control step: max ")
      .u32(g_app.task.step_timing.max)
      .str(", mean ")
      .u32(g_app.task.step_timing.mean())
      .str(" cycles; whole tick max ")
      .u32(g_app.task.timing.max)
      .str(" cycles (")
      .u32(g_app.task.timing.max * 1000u / 168u)
      .str(" instructions at -icount shift=0)")
      .emit();
}

/// Ends a line with what a snapshot's outputs were: "<codes>zero|NONZERO<note>, amplifier ON|off,
/// watchdog feeds n".
void emit_outputs(Line& line, const Snapshot& s, const char* codes, const char* note) {
  line.str(codes).str(s.written_max == 0 ? "zero" : "NONZERO").str(note);
  line.str(", amplifier ").str(s.amplifier ? "ON" : "off").str(", watchdog feeds ").u32(s.feeds).emit();
}

/// The report's lines on the state before and after the E-stop, and the telemetry.
void report_estop() {
  const Snapshot& b = g_before_estop;
  const Snapshot& a = g_after_estop;
  Line before;
  before.str("before the E-stop: state ").u32(static_cast<std::uint32_t>(b.state)).str(", faults ").u32(b.latched);
  before.str(", torque code joint 2 ").i32(b.task_code);
  emit_outputs(before, b, ", DAC codes written ", " (boot fault)");
  Line after;
  after.str("E-stop: interrupt after tick ").u32(g_estop_seen_at).str(", latched by tick ").u32(g_estop_latched_in);
  after.str(", faults ").str(osc::fault_name(a.latched));
  emit_outputs(after, a, ", DAC codes ", "");
  Line()
      .str("telemetry: ")
      .u32(g_app.frames)
      .str(" frames, ")
      .u32(g_app.board.uart.dropped())
      .str(" dropped; stack used ")
      .u32(cortex_m::stack_used())
      .str(" bytes")
      .emit();
}

/// The verdict's line, over semihosting and the USART; returns the exit status.
int verdict(const Checks& c) {
  Line v;
  v.str(c.ok() ? "stm32f4_qemu: pass" : "stm32f4_qemu: FAIL");
  if (!c.ok())
    v.str(" (boot ")
        .u32(c.boot)
        .str(", spacing ")
        .u32(c.spacing)
        .str(", run ")
        .u32(c.run)
        .str(", estop ")
        .u32(c.estop)
        .str(", telemetry ")
        .u32(c.telemetry)
        .str(")");
  g_app.board.uart.write_blocking(v.text());
  g_app.board.uart.write_blocking("\r\n");
  v.emit();
  return c.ok() ? 0 : 1;
}

}  // namespace

int main() {
  g_app.boot();
  g_app.port.state_period = 0;  // no host here: the USART carries the telemetry alone (osc_telemetry reads it)
  bool declared = false, enabled = false, paper = false;  // the compiled-in commands, each placed once
  for (;;) {
    g_app.serve();  // never asleep (idle() sleeps): the run stays deterministic under -icount
    // Not homed at boot: the still robot stands at the start pose, declared (pose code 0, a
    // TaskCommand's default; no pots here, so on trust).
    if (!declared) declared = g_app.command(osc::MotionVerb::kDeclarePose, 3);
    if (declared && !enabled) enabled = g_app.command(osc::MotionVerb::kEnable, 1);
    if (enabled && !paper && g_app.task.machine.state == osc::MotionState::kHolding)
      paper = g_app.command(osc::MotionVerb::kPaper, 2);
    // The E-stop: QEMU models no GPIO and its EXTI ignores the software trigger (SWIER), so the
    // test pends the E-stop's interrupt itself; the handler is the board's.
    if (g_app.ticks == kEstopTick && g_estop_seen_at == 0) cortex_m::irq_pend(board::kEstopIrq);
    if (g_app.ticks >= kSmokeTicks) break;
  }
  g_app.stop();
  const Spacing s = spacing();
  report_timing(s);
  report_estop();
  return verdict(check(s));
}
