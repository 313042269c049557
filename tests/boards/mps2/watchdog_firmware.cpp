// The CMSDK watchdog end to end in QEMU (ctest watchdog_reset_qemu, run without -no-reboot, so the
// watchdog's reset reboots the image). The control task runs in the 1 kHz TIMER0 interrupt over a
// HAL with the encoders held at the start pose and feeds the watchdog at the end of every healthy
// tick, as timer_firmware does. Each boot runs one scenario that must end in a watchdog reset; a
// record in .noinit RAM carries the scenario, and what the NMI of the first expiry saw, across it:
//   boot 1 (power-on): 50 healthy ticks (50 ms, far beyond the 8 ms to the reset: the watchdog
//          must not fire), then the 51st tick hangs in the interrupt;
//   boot 2: 30 healthy ticks, then an encoder jump latches a fault: the ticks go on with zero
//          torque but no longer feed;
//   boot 3: 30 healthy ticks, then the control interrupt is disabled: the main loop runs, no tick;
//   boot 4: checks the three resets and passes.
// Each boot checks the previous scenario (reset cause, ticks and feeds before the expiry, the first
// expiry 4 ms and the reset 8 ms after the last feed, the latched faults) and that the image came up
// with zero DAC codes and the supervisor in kInit. A scenario not ended by a reset within 100 ms of
// virtual time fails. Prints "watchdog_firmware: pass" and exits 0 on success.
#include <cstdint>

#include "board.hpp"
#include "still_hal.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/control_task.hpp"
#include "text.hpp"

namespace {

using cortex_m::text::Line;

enum Scenario : std::uint32_t { kHungTick = 0, kFaultLatched = 1, kIrqDisabled = 2, kDone = 3 };
constexpr const char* kScenarioName[] = {"hung tick", "latched fault", "control interrupt disabled"};
constexpr std::uint32_t kHealthyTicks[] = {50, 30, 30};
constexpr std::uint32_t kPeriodNs = 1000000000u / board::kControlHz;
constexpr std::uint32_t kResetLimitNs = 100000000u;  // the reset must come within this
constexpr std::uint32_t kToleranceNs = 10000u;       // on the expiry instants (10 us)

/// What the NMI of the first expiry saw; survives the reset.
struct Record {
  std::uint32_t magic;
  std::uint32_t scenario;    // the scenario that ran before the reset
  std::uint32_t ticks;       // ticks completed at the first expiry
  std::uint32_t feeds;       // watchdog feeds by then
  std::uint32_t expiry_ns;   // from the last feed to the first expiry (NMI)
  std::uint32_t alive_ns;    // from the last feed to the last instant before the reset
  std::uint32_t faults;      // the supervisor's latched bits at the first expiry
  std::uint32_t codes_zero;  // every DAC code was 0 at the first expiry
};
constexpr std::uint32_t kRecordMagic = 0x57444F47u;
__attribute__((section(".noinit"))) volatile Record g_rec;

using board::StillHal;

osc::ControlTask<board::Scalar> g_task;
StillHal g_hal;
volatile std::uint32_t g_scenario = kDone;
volatile std::uint32_t g_ticks = 0, g_feeds = 0, g_last_feed = 0;

bool near(std::uint32_t v, std::uint32_t want) { return v + kToleranceNs >= want && v <= want + kToleranceNs; }

/// Checks what the previous boot's scenario left in the record.
bool check_previous(std::uint32_t s) {
  const std::uint32_t n = kHealthyTicks[s];
  Line()
      .str("scenario ")
      .u32(s + 1)
      .str(" (")
      .str(kScenarioName[s])
      .str("): ")
      .u32(g_rec.ticks)
      .str(" ticks, ")
      .u32(g_rec.feeds)
      .str(" feeds; latched faults ")
      .u32(g_rec.faults)
      .str(", DAC codes ")
      .str(g_rec.codes_zero ? "zero" : "held")
      .str(" at the first expiry")
      .emit();
  Line()
      .str("  after the last feed: first expiry (NMI) at ")
      .u32(g_rec.expiry_ns)
      .str(" ns, reset at ")
      .u32(g_rec.alive_ns)
      .str(" ns")
      .emit();
  bool ok = g_rec.feeds == n && near(g_rec.expiry_ns, board::kWatchdogExpiryNs) &&
            near(g_rec.alive_ns, 2 * board::kWatchdogExpiryNs) && cortex_m::watchdog_faults() == g_rec.faults;
  switch (s) {
    case kHungTick:  // the tick after the last healthy one never completed
    case kIrqDisabled:
      ok = ok && g_rec.ticks == n && g_rec.faults == 0;
      break;
    case kFaultLatched:  // the ticks went on after the fault, with zero torque, unfed
      ok = ok && g_rec.ticks > n + 1 && (g_rec.faults & osc::kFaultEncoderJump) != 0 && g_rec.codes_zero != 0;
      break;
    default:
      ok = false;
  }
  return ok;
}

}  // namespace

extern "C" void TIMER0_Handler() {
  board::control_timer_ack();
  const std::uint32_t k = g_ticks;
  const std::uint32_t s = g_scenario;
  if (s >= kDone) return;
  if (s == kHungTick && k == kHealthyTicks[s]) {
    // A control step that never returns (bounded here, so that a missing reset fails the test).
    const std::uint32_t t0 = board::cycles();
    while (board::cycles() - t0 < kResetLimitNs) {
    }
    board::control_irq_disable();
    return;
  }
  if (s == kFaultLatched && k == kHealthyTicks[s]) g_hal.jump = 4 * g_task.jump.max_step[0];
  osc::control_tick(g_task, g_hal);
  g_ticks = k + 1;
  if (osc::supervisor_healthy(g_task.sup)) {  // the feeding rule
    board::watchdog_feed();
    g_feeds = g_feeds + 1;
    g_last_feed = board::cycles();
  }
}

// The first expiry: note what happened, drop the fault line, then follow virtual time until the
// watchdog's reset.
extern "C" void NMI_Handler() {
  const std::uint32_t last_feed = g_last_feed;
  g_rec.expiry_ns = board::cycles() - last_feed;
  g_rec.scenario = g_scenario;
  g_rec.ticks = g_ticks;
  g_rec.feeds = g_feeds;
  g_rec.faults = g_task.sup.latched;
  g_rec.codes_zero = g_hal.codes_zero() ? 1u : 0u;
  g_rec.magic = kRecordMagic;
  board::watchdog_expired(g_task.sup.latched);
  for (;;) g_rec.alive_ns = board::cycles() - last_feed;
}

int main() {
  board::cycle_counter_init();
  const cortex_m::ResetCause cause = board::reset_cause();
  Line()
      .str("boot: reset cause ")
      .str(board::reset_cause_name(cause))
      .str(", watchdog resets ")
      .u32(cortex_m::watchdog_resets())
      .emit();
  g_task.init(osc::Model<board::Scalar>::of(osc::robot::kArm), osc::Gains<board::Scalar>::paper(),
              osc::FrictionMode::kAdaptive, osc::joint_vector<board::Scalar>(osc::robot::kQStart), kPeriodNs);
  // Up with zero torque: every DAC code 0, the supervisor starting, the fault line released.
  const bool outputs_ok = g_hal.codes_zero() && g_task.sup.state == osc::SupervisorState::kInit &&
                          g_task.sup.latched == 0 && !board::g_fault_line;
  Line()
      .str("outputs at start: DAC codes ")
      .str(g_hal.codes_zero() ? "zero" : "NOT ZERO")
      .str(", supervisor ")
      .str(g_task.sup.state == osc::SupervisorState::kInit ? "init" : "NOT INIT")
      .emit();

  std::uint32_t scenario = kDone;
  bool ok = outputs_ok;
  if (cause == cortex_m::ResetCause::kPowerOn) {
    scenario = kHungTick;
  } else if (cause == cortex_m::ResetCause::kWatchdog && g_rec.magic == kRecordMagic && g_rec.scenario < kDone) {
    ok = check_previous(g_rec.scenario) && ok;
    scenario = g_rec.scenario + 1;
  } else {
    Line().str("unexpected reset").emit();
    ok = false;
  }
  g_rec.magic = 0;  // consumed
  if (!ok) {
    Line().str("watchdog_firmware: FAIL").emit();
    return 1;
  }
  if (scenario == kDone) {
    const bool all = cortex_m::watchdog_resets() == kDone;
    Line()
        .str(all ? "watchdog_firmware: pass (" : "watchdog_firmware: FAIL (")
        .u32(cortex_m::watchdog_resets())
        .str(" watchdog resets)")
        .emit();
    return all ? 0 : 1;
  }

  const std::uint32_t n = kHealthyTicks[scenario];
  Line()
      .str("scenario ")
      .u32(scenario + 1)
      .str(": ")
      .u32(n)
      .str(" healthy ticks, then ")
      .str(kScenarioName[scenario])
      .emit();
  g_scenario = scenario;
  board::watchdog_start();
  g_last_feed = board::cycles();
  board::control_timer_start(board::kControlHz);
  const std::uint32_t t0 = board::cycles();
  bool irq_off = false;
  while (board::cycles() - t0 < n * kPeriodNs + kResetLimitNs) {
    if (scenario == kIrqDisabled && !irq_off && g_ticks >= n) {
      board::control_irq_disable();  // the control interrupt stops: the main loop goes on
      irq_off = true;
    }
  }
  Line().str("no watchdog reset within ").u32(kResetLimitNs / 1000000u).str(" ms: watchdog_firmware: FAIL").emit();
  return 1;
}
