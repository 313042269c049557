// The tick's timing (osc/runtime/timing.hpp): every stage of control_tick() timed on every tick, the
// stages adding up to the tick, against a HAL whose cycle counter advances by a known amount at each call.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "osc/runtime/control_task.hpp"
#include "osc/runtime/timing.hpp"

using namespace osc;

namespace {

/// Cycles advance by a different amount at each call, so each stage has its own length.
struct StagedHal {
  std::uint32_t clock = 0, calls = 0;
  std::int32_t written[kDof] = {};
  bool fault_line = false;
  void fault_output(bool a) { fault_line = a; }
  bool read_encoders(std::int32_t c[kDof]) {
    for (int i = 0; i < kDof; ++i) c[i] = 0;
    return true;
  }
  void write_dacs(const std::int32_t c[kDof]) { std::copy(c, c + kDof, written); }
  std::uint32_t cycles() { return clock += ++calls; }
  std::uint32_t io_faults() { return 0; }
};
static_assert(hal::ControlHal<StagedHal>);

TEST(TickStages, EveryStageTimedAndTheyAddUpToTheTick) {
  auto task = std::make_unique<ControlTask<double>>();
  task->init(Model<double>::of(robot::kArm), Gains<double>::paper(), FrictionMode::kAdaptive,
             joint_vector<double>(robot::kQStart));
  StagedHal hal;
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t calls_before = hal.calls;
    ASSERT_EQ(control_tick(*task, hal), 0u);
    std::uint32_t sum = 0;
    for (const StepTiming& s : task->stages.stage) {
      EXPECT_EQ(s.count, static_cast<std::uint32_t>(k + 1));
      EXPECT_GT(s.last, 0u);
      sum += s.last;
    }
    EXPECT_EQ(sum, task->timing.last);
    // Marks at calls n+1 .. n+10 (and the overrun check's read in the codes stage): the clock advances by the
    // sum of the call numbers in between, the codes stage two; the step's own time is its stage's.
    const std::uint32_t n = calls_before;
    EXPECT_EQ(task->stages.stage[kStageRead].last, n + 2);
    EXPECT_EQ(task->stages.stage[kStageChecks].last, n + 3);
    EXPECT_EQ(task->stages.stage[kStageReference].last, n + 4);
    EXPECT_EQ(task->stages.stage[kStageStep].last, n + 5);
    EXPECT_EQ(task->stages.stage[kStageMonitors].last, n + 6);
    EXPECT_EQ(task->stages.stage[kStageCodes].last, (n + 7) + (n + 8));
    EXPECT_EQ(task->stages.stage[kStageDecide].last, n + 9);
    EXPECT_EQ(task->stages.stage[kStageOutput].last, n + 10);
    EXPECT_EQ(task->step_timing.last, task->stages.stage[kStageStep].last);
    EXPECT_EQ(task->step_timing.count, static_cast<std::uint32_t>(k + 1));
  }
  EXPECT_STREQ(kTickStageNames[kStageStep], "step");
  EXPECT_EQ(static_cast<int>(kTickStages), 8);
}

}  // namespace
