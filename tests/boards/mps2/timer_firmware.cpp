// The control task in the 1 kHz TIMER0 interrupt, standalone (still_hal.hpp: the encoders held at the
// start pose, no plant, and the DAC codes kept in memory). The CMSDK watchdog runs and is fed at the
// end of every healthy tick (osc::supervisor_healthy); its first expiry (the NMI) would drop the
// fault line and wait for the reset. Runs 200 ticks, then stops the watchdog and checks that the
// ticks came 1 ms apart in virtual time, that no tick overran or faulted, that every tick fed the
// watchdog and it never expired, and reports the step timing, the stack high-water mark and the
// cause of the last reset. Prints "timer_firmware: pass" and exits 0 on success.
#include <cstdint>

#include "board.hpp"
#include "still_hal.hpp"
#include "osc/runtime/control_task.hpp"
#include "osc/robot.hpp"
#include "text.hpp"

namespace {

using board::StillHal;

constexpr int kTicks = 200;
constexpr std::uint32_t kPeriodNs = 1000000000u / board::kControlHz;

osc::ControlTask<board::Scalar> g_task;
StillHal g_hal;
volatile int g_ticks = 0;
volatile int g_feeds = 0;
volatile std::uint32_t g_faults = 0;
std::uint32_t g_stamp[kTicks];

}  // namespace

extern "C" void TIMER0_Handler() {
  board::control_timer_ack();
  const int k = g_ticks;
  if (k >= kTicks) return;
  g_stamp[k] = board::cycles();
  g_faults = g_faults | osc::control_tick(g_task, g_hal);
  // The watchdog is fed only at the end of a healthy tick.
  if (osc::supervisor_healthy(g_task.sup)) {
    board::watchdog_feed();
    g_feeds = g_feeds + 1;
  }
  g_ticks = k + 1;
}

// The watchdog's first expiry: fault line active, the cause noted and said (the tick it came after
// and the latched faults, so that a failing run names its cause), then the reset (under the tests'
// -no-reboot QEMU ends without the pass line).
extern "C" void NMI_Handler() {
  board::watchdog_expired(g_task.sup.latched);
  cortex_m::text::Line()
      .str("timer_firmware: FAIL, the watchdog expired after tick ")
      .i32(g_ticks)
      .str(", faults ")
      .u32(g_task.sup.latched)
      .emit();
  board::await_reset();
}

/// Writes a stack frame deeper than anything before it (and keeps the compiler from removing it).
[[gnu::noinline]] std::uint32_t use_stack_deeply() {
  volatile std::uint32_t deep[1536];  // 6 KiB
  for (std::uint32_t i = 0; i < 1536; ++i) deep[i] = i;
  return deep[7];
}

/// The telemetry's bounded sweep (cortex_m::stack_used_sweep) against the full scan: never above
/// it, equal once a sweep is through, and a new, deeper use found by the next sweep.
bool stack_sweep_agrees() {
  constexpr int kCalls = 4096 / cortex_m::kStackSweepWords + 2;  // a 16 KiB stack's sweep, and one more call
  std::uint32_t swept = 0;
  bool never_above = true;
  for (int k = 0; k < kCalls; ++k) {
    swept = board::stack_used_sweep();
    never_above = never_above && swept <= board::stack_used();
  }
  const bool equal = swept == board::stack_used();
  const std::uint32_t before = swept;
  (void)use_stack_deeply();
  for (int k = 0; k < kCalls; ++k) swept = board::stack_used_sweep();
  const bool deeper_found = swept == board::stack_used() && swept > before && swept >= 6144;
  cortex_m::text::Line()
      .str("stack sweep: ")
      .u32(before)
      .str(" bytes, then ")
      .u32(swept)
      .str(" after a 6 KiB frame (")
      .str(never_above && equal && deeper_found ? "agrees with the full scan" : "DISAGREES with the full scan")
      .str(")")
      .emit();
  return never_above && equal && deeper_found;
}

/// Each stage of the tick (osc::TickStage): its worst and mean instructions, a line each (the eight
/// of them would not fit one line's buffer).
void report_stages() {
  for (int s = 0; s < osc::kTickStages; ++s) {
    const osc::StepTiming& t = g_task.stages.stage[s];
    cortex_m::text::Line()
        .str("tick stage ")
        .str(osc::kTickStageNames[s])
        .str(", max/mean: ")
        .u32(t.max)
        .str("/")
        .u32(t.mean())
        .str(" instructions")
        .emit();
  }
}

int main() {
  board::cycle_counter_init();
  const cortex_m::ResetCause cause = board::reset_cause();
  g_task.init(osc::Model<board::Scalar>::of(osc::robot::kArm), osc::Gains<board::Scalar>::paper(),
              osc::FrictionMode::kAdaptive, osc::joint_vector<board::Scalar>(osc::robot::kQStart), kPeriodNs);
#ifdef OSC_TICK_WORST_CASE
  // The arm's own encoders, as the STM32F4 board runs them (its app.hpp): on the PUMA the coupled wrist, whose
  // friction law is the drives' (C^-T W(C^-1 qd^) theta^) and whose monitors take the motors' rates.
  g_task.set_encoders(osc::robot::kDriveTrain.encoders);
#endif
  board::watchdog_start();
  board::control_timer_start(board::kControlHz);
  while (g_ticks < kTicks) {
  }
  const bool watchdog_ok = g_feeds == kTicks && !board::Watchdog::expired_once();
  board::watchdog_stop();  // the run is over: no more ticks feed it
  // Tick spacing in virtual time.
  std::uint32_t lo = 0xFFFFFFFFu, hi = 0;
  for (int k = 1; k < kTicks; ++k) {
    const std::uint32_t d = g_stamp[k] - g_stamp[k - 1];
    lo = d < lo ? d : lo;
    hi = d > hi ? d : hi;
  }
  cortex_m::text::Line().str("ticks: ").i32(g_ticks).str(", spacing ").u32(lo).str("..").u32(hi).str(" ns").emit();
  cortex_m::text::Line()
      .str("control step: max ")
      .u32(g_task.timing.max)
      .str(", mean ")
      .u32(g_task.timing.mean())
      .str(" instructions (-icount shift=0)")
      .emit();
  report_stages();
  cortex_m::text::Line()
      .str("supervisor state ")
      .u32(static_cast<std::uint32_t>(g_task.sup.state))
      .str(", faults ")
      .u32(g_faults)
      .str(", torque code joint 2: ")
      .i32(g_hal.codes[1])
      .emit();
  cortex_m::text::Line().str("stack used: ").u32(board::stack_used()).str(" bytes").emit();
  cortex_m::text::Line()
      .str("watchdog: fed by ")
      .i32(g_feeds)
      .str(" of ")
      .i32(kTicks)
      .str(" ticks, ")
      .str(watchdog_ok ? "never expired" : "EXPIRED or unfed")
      .str("; reset cause ")
      .str(board::reset_cause_name(cause))
      .emit();
  const bool spacing_ok = lo + 100 >= kPeriodNs && hi <= kPeriodNs + 100;
  const bool sweep_ok = stack_sweep_agrees();
  const bool ok = spacing_ok && watchdog_ok && sweep_ok && g_faults == 0 &&
                  g_task.sup.state == osc::SupervisorState::kRun && g_hal.codes[1] != 0;
  cortex_m::text::Line().str(ok ? "timer_firmware: pass" : "timer_firmware: FAIL").emit();
  return ok ? 0 : 1;
}
