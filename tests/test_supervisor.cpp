// The supervisor (exhaustively) and the control task's fault handling with a scripted HAL.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "osc/runtime/control_task.hpp"

using namespace osc;

namespace {

// Independent oracle: the specification of supervisor_next written as plain rules.
Supervisor oracle(Supervisor s, SupervisorInput in) {
  Supervisor n = s;
  n.latched = s.latched | (in.faults & kAllFaults);
  if (s.state == SupervisorState::kFault) n.state = SupervisorState::kFault;
  else if (n.latched) n.state = SupervisorState::kFault;
  else if (s.state == SupervisorState::kInit) n.state = in.ready ? SupervisorState::kRun : SupervisorState::kInit;
  else n.state = SupervisorState::kRun;
  return n;
}

TEST(Supervisor, ExhaustiveAgainstTheSpecification) {
  int cases = 0;
  for (int st = 0; st < 3; ++st)
    for (std::uint32_t latched = 0; latched <= kAllFaults; ++latched)
      for (std::uint32_t f = 0; f <= 2 * kAllFaults + 1; ++f)  // includes an undefined bit
        for (int ready = 0; ready < 2; ++ready) {
          const Supervisor s{static_cast<SupervisorState>(st), st == 2 ? latched : 0u};
          if (st != 2 && latched != 0) continue;  // only kFault carries latched bits
          const SupervisorInput in{f, ready != 0};
          const Supervisor got = supervisor_next(s, in), want = oracle(s, in);
          ASSERT_EQ(got.state, want.state) << st << " " << f << " " << ready;
          ASSERT_EQ(got.latched, want.latched);
          // Properties: faults are sticky and always disable torque.
          if (f & kAllFaults) {
            ASSERT_FALSE(torque_enabled(got));
          }
          if (st == 2) {
            ASSERT_EQ(got.state, SupervisorState::kFault);
          }
          ASSERT_EQ(got.latched & s.latched, s.latched);
          ++cases;
        }
  EXPECT_GT(cases, 1000);
}

/// A HAL whose encoder counts, cycle counter and I/O faults the test scripts.
struct ScriptedHal {
  std::int32_t counts[kDof] = {0, 0, 0, 0, 0, 0};
  std::int32_t written[kDof] = {1, 1, 1, 1, 1, 1};
  std::uint32_t clock = 0, clock_step = 10, faults = 0;
  int writes = 0;
  bool fault_line = false;
  bool sample = true;  // the tick has a valid sample
  void fault_output(bool a) { fault_line = a; }
  bool read_encoders(std::int32_t c[kDof]) {
    for (int i = 0; i < kDof; ++i) c[i] = counts[i];
    return sample;
  }
  void write_dacs(const std::int32_t c[kDof]) {
    for (int i = 0; i < kDof; ++i) written[i] = c[i];
    ++writes;
  }
  std::uint32_t cycles() { return clock += clock_step; }
  std::uint32_t io_faults() {
    const std::uint32_t f = faults;
    faults = 0;
    return f;
  }
  bool all_zero() const {
    for (int c : written)
      if (c != 0) return false;
    return true;
  }
};
static_assert(hal::ControlHal<ScriptedHal>);
// The concept is a real check: a binding that lacks one function, or returns the wrong type, fails it.
struct HalWithoutFaultLine {
  bool read_encoders(std::int32_t*) { return true; }
  void write_dacs(const std::int32_t*) {}
  std::uint32_t cycles() { return 0; }
  std::uint32_t io_faults() { return 0; }
};
struct HalWithFloatCycles : HalWithoutFaultLine {
  float cycles() { return 0; }
  void fault_output(bool) {}
};
struct HalWithVoidEncoders : HalWithFloatCycles {
  std::uint32_t cycles() { return 0; }
  void read_encoders(std::int32_t*) {}  // cannot say that a tick has no sample
};
static_assert(hal::ControlHal<HalWithVoidEncoders> == false);
static_assert(!hal::ControlHal<HalWithoutFaultLine>);
static_assert(!hal::ControlHal<HalWithFloatCycles>);

struct TaskFixture : ::testing::Test {
  std::unique_ptr<ControlTask<float>> task = std::make_unique<ControlTask<float>>();
  ScriptedHal hal;
  void SetUp() override { start(robot::kQStart); }
  void start(const double (&q0)[kDof], std::uint32_t period = 0) {
    Vec6<float> q;
    for (int i = 0; i < kDof; ++i) q(i) = static_cast<float>(q0[i]);
    task->init(Model<float>::of(robot::kArm), Gains<float>::paper(), FrictionMode::kAdaptive, q, period);
  }
  /// Runs ticks; returns the faults of the last.
  std::uint32_t run(int n) {
    std::uint32_t f = 0;
    for (int k = 0; k < n; ++k) f = control_tick(*task, hal);
    return f;
  }
  void expect_latched(std::uint32_t bit) {
    EXPECT_EQ(task->sup.state, SupervisorState::kFault);
    EXPECT_TRUE(task->sup.latched & bit) << task->sup.latched;
    EXPECT_TRUE(hal.all_zero());
    EXPECT_TRUE(hal.fault_line);
    // Stays latched with healthy inputs afterwards.
    run(3);
    EXPECT_EQ(task->sup.state, SupervisorState::kFault);
    EXPECT_TRUE(hal.all_zero());
  }
};

TEST_F(TaskFixture, HealthyTicksRunAndCommandTorque) {
  EXPECT_EQ(run(5), 0u);
  EXPECT_EQ(task->sup.state, SupervisorState::kRun);
  EXPECT_FALSE(hal.all_zero());  // holds gravity
  EXPECT_EQ(hal.writes, 5);
  EXPECT_FALSE(hal.fault_line);
  EXPECT_EQ(task->timing.count, 5u);
  EXPECT_GT(task->timing.max, 0u);
}

TEST_F(TaskFixture, EncoderJumpFaultsInTheSameTick) {
  run(3);
  hal.counts[1] += task->max_count_step[1];  // the largest plausible step is fine
  EXPECT_EQ(run(1), 0u);
  hal.counts[1] += task->max_count_step[1] + 1;
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultEncoderJump));
  expect_latched(kFaultEncoderJump);
}

TEST_F(TaskFixture, GarbageFirstEncoderSampleFaultsWithZeroTorque) {
  // INT32_MAX counts at the very first sample used to drive full scale on every DAC.
  hal.counts[2] = 2147483647;
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultEncoderRange));
  EXPECT_EQ(hal.writes, 1);
  expect_latched(kFaultEncoderRange);
}

TEST_F(TaskFixture, ReadingsWithinTheLimitsPlusMarginAreAcceptedBeyondThemNot) {
  // The first sample at the edge of the plausible range of joint 1 (its limit plus the margin,
  // less one count): accepted; one count further: a fault.
  const double c = task->counts_per_rad(0);
  const auto edge = static_cast<std::int32_t>((robot::kArm.q_max[0] + params::kJointLimitMargin - robot::kQStart[0]) * c);
  hal.counts[0] = edge;
  run(1);
  EXPECT_EQ(task->sup.latched & kFaultEncoderRange, 0u);
  start(robot::kQStart);
  hal.counts[0] = edge + 3;
  EXPECT_TRUE(run(1) & kFaultEncoderRange);
}

TEST_F(TaskFixture, NonFiniteStateFaultsInTheSameTick) {
  run(3);
  task->inject_nonfinite();
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultNonFinite));
  expect_latched(kFaultNonFinite);
}

TEST_F(TaskFixture, SingularPoseFaults) {
  double q[kDof];
  for (int i = 0; i < kDof; ++i) q[i] = robot::kQStart[i];
  q[4] = 0.0;  // wrist singularity
  start(q);
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultSingular));
  expect_latched(kFaultSingular);
}

TEST_F(TaskFixture, PersistentSaturationFaults) {
  // The robot does not move (encoders frozen) while the trajectory runs away: the error grows until
  // the torques clip, and after kSaturationTicks clipped ticks the fault latches.
  int k = 0;
  std::uint32_t f = 0;
  for (; k < 20000 && f == 0; ++k) f = run(1);
  EXPECT_EQ(f, static_cast<std::uint32_t>(kFaultSaturation)) << "after " << k << " ticks";
  expect_latched(kFaultSaturation);
}

TEST_F(TaskFixture, OverrunFaults) {
  start(robot::kQStart, 1000);
  hal.clock_step = 100;
  EXPECT_EQ(run(2), 0u);
  hal.clock_step = 2000;  // the step now takes longer than the period
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultOverrun));
  expect_latched(kFaultOverrun);
}

TEST_F(TaskFixture, ATickWithoutASampleCommandsZeroTorqueWithoutAFault) {
  run(5);
  ASSERT_FALSE(hal.all_zero());
  const std::uint64_t tick = task->tick;
  const std::uint32_t steps = task->step_timing.count;
  hal.sample = false;
  EXPECT_EQ(run(1), 0u);
  EXPECT_TRUE(hal.all_zero());                      // zero codes in this tick
  EXPECT_EQ(task->step_timing.count, steps);        // no control step
  EXPECT_EQ(task->sup.state, SupervisorState::kRun);  // and no latch
  EXPECT_FALSE(hal.fault_line);
  EXPECT_EQ(task->tick, tick + 1);                  // the sample clock runs on
  hal.sample = true;
  EXPECT_EQ(run(1), 0u);
  EXPECT_FALSE(hal.all_zero());                     // torque again with the next sample
}

TEST_F(TaskFixture, TheEncoderJumpLimitSpansTheTicksWithoutASample) {
  run(3);
  hal.sample = false;
  run(2);  // two ticks without a sample: the next one is three ticks after the last
  hal.sample = true;
  hal.counts[1] += 3 * task->max_count_step[1];
  EXPECT_EQ(run(1), 0u);
  hal.sample = false;
  run(1);
  hal.sample = true;
  hal.counts[1] += 2 * task->max_count_step[1] + 1;  // beyond two ticks' worth
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultEncoderJump));
}

TEST_F(TaskFixture, HoldTickRepeatsTheCodesAndRunsTheClocks) {
  run(4);
  std::int32_t before[kDof];
  std::copy(hal.written, hal.written + kDof, before);
  const int writes = hal.writes;
  const std::uint64_t tick = task->tick;
  hold_tick(*task, hal);
  EXPECT_EQ(hal.writes, writes + 1);
  EXPECT_TRUE(std::equal(before, before + kDof, hal.written));
  EXPECT_EQ(task->tick, tick + 1);
  EXPECT_EQ(task->prev_counts_age, 1u);
}

TEST_F(TaskFixture, LinkFaultsFromTheIoLayer) {
  run(2);
  hal.faults = kFaultLinkLost;
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultLinkLost));
  expect_latched(kFaultLinkLost);
}

}  // namespace
