// The supervisor (exhaustively) and the control task's fault handling with a scripted HAL.
#include <gtest/gtest.h>

#include <memory>

#include "osc/runtime/control_task.hpp"

using namespace osc;

namespace {

// Independent oracle: the specification of supervisor_next written as plain rules.
Supervisor oracle(Supervisor s, SupervisorInput in) {
  Supervisor n = s;
  n.latched = s.latched | in.faults;  // every bit, named in the catalogue or not
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
          if (f != 0) {
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
  void fault_output(bool a) { fault_line = a; }
  void read_encoders(std::int32_t c[kDof]) {
    for (int i = 0; i < kDof; ++i) c[i] = counts[i];
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
  void read_encoders(std::int32_t*) {}
  void write_dacs(const std::int32_t*) {}
  std::uint32_t cycles() { return 0; }
  std::uint32_t io_faults() { return 0; }
};
struct HalWithFloatCycles : HalWithoutFaultLine {
  float cycles() { return 0; }
  void fault_output(bool) {}
};
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

// Found by tests/fuzz/fuzz_supervisor: a fault bit outside the catalogue (here from a HAL's I/O
// layer) was masked off by supervisor_next, and the torque stayed on.
TEST(Supervisor, AFaultBitOutsideTheCatalogueFaultsAndIsLatched) {
  const std::uint32_t unknown = 1u << 31;
  ASSERT_EQ(unknown & kAllFaults, 0u);
  const Supervisor s = supervisor_next({SupervisorState::kRun, 0}, {unknown, true});
  EXPECT_EQ(s.state, SupervisorState::kFault);
  EXPECT_EQ(s.latched, unknown);
  EXPECT_FALSE(torque_enabled(s));
  EXPECT_EQ(supervisor_next({SupervisorState::kInit, 0}, {unknown, true}).state, SupervisorState::kFault);
}

TEST_F(TaskFixture, AnIoFaultBitOutsideTheCatalogueFaultsWithZeroTorque) {
  run(2);
  EXPECT_FALSE(hal.all_zero());
  hal.faults = 1u << 20;
  EXPECT_EQ(run(1), 1u << 20);
  expect_latched(1u << 20);
}

TEST_F(TaskFixture, LinkFaultsFromTheIoLayer) {
  run(2);
  hal.faults = kFaultLinkLost;
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultLinkLost));
  expect_latched(kFaultLinkLost);
}

}  // namespace
