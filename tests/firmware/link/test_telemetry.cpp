// A tick's telemetry (osc/link/telemetry.hpp): the actuator frame of a task whose timing, latch and
// estimates are set by hand: the codes, sequence number and stack given; the supervisor's state and
// latch; the step's last, largest and mean cycles, and each stage's from its marks (the cycle counter
// wrapping between two), hand-computed; the estimates in f32; the frame as written through the encoder
// and the parser.
#include <gtest/gtest.h>

#include <cstdint>

#include "frame_bytes.hpp"
#include "osc/link/telemetry.hpp"
#include "task_util.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST(Telemetry, TheActuatorFrameIsTheTasksTick) {
  auto task = disabled_task<double>();
  for (std::uint32_t c : {9000u, 9600u, 9300u}) task->step_timing.add(c);  // last 9300, largest 9600, mean 9300
  task->timing.add(13640);
  task->timing.add(12000);
  const std::uint32_t marks[kTickStages + 1] = {0xFFFFFF00u, 0xFFFFFFF0u, 0x10u,   0x110u, 0x2110u,
                                                0x2410u,     0x2420u,     0x2430u, 0x2500u};
  const std::uint32_t stages[kTickStages] = {0xF0, 0x20, 0x100, 0x2000, 0x300, 0x10, 0x10, 0xD0};
  task->stages.add(marks);
  task->sup = {SupervisorState::kFault, kFaultEstop | kFaultTracking};
  for (int i = 0; i < 3 * kDof; ++i) task->state.adapt.theta_hat(i) = 0.1 * i + 1.0 / 3;
  task->last.tau_f_hat << -0.5, 0.25, 1.0 / 3, 0, 2, -1e-3;
  const std::int32_t codes[kDof] = {120, -9100, 2047, 0, -15, 3};
  const pil::ActuatorFrame a = telemetry_frame(*task, codes, 1234, 2960);
  EXPECT_EQ(a.seq, 1234u);
  for (int i = 0; i < kDof; ++i) EXPECT_EQ(a.codes[i], codes[i]) << i;
  EXPECT_EQ(a.faults, static_cast<std::uint32_t>(kFaultEstop | kFaultTracking));
  EXPECT_EQ(a.state, 2);  // fault
  EXPECT_EQ(a.step_cycles, 9300u);
  EXPECT_EQ(a.max_cycles, 9600u);
  EXPECT_EQ(a.mean_cycles, 9300u);
  EXPECT_EQ(a.tick_max_cycles, 13640u);  // the largest tick, not the last
  for (int s = 0; s < kTickStages; ++s) EXPECT_EQ(a.stage_cycles[s], stages[s]) << kTickStageNames[s];
  EXPECT_EQ(a.stack_used, 2960u);
  for (int i = 0; i < 3 * kDof; ++i) EXPECT_EQ(a.theta_hat[i], static_cast<float>(0.1 * i + 1.0 / 3)) << i;
  EXPECT_EQ(a.tau_f_hat[0], -0.5f);
  EXPECT_EQ(a.tau_f_hat[2], static_cast<float>(1.0 / 3));
  EXPECT_EQ(a.link.total(), 0u);  // the link node's counters: not the task's
  const pil::ActuatorFrame b = decoded<pil::ActuatorFrame>(parsed(bytes_of(a)));
  EXPECT_EQ(bytes_of(b), bytes_of(a));
  EXPECT_EQ(b.mean_cycles, 9300u);
  EXPECT_EQ(b.stage_cycles[1], 0x20u);
  EXPECT_EQ(b.faults, a.faults);
}

}  // namespace
