// The control task (osc/runtime/control_task.hpp) with a scripted HAL: healthy ticks, each fault latched
// with zero torque in the tick that detects it, ticks without a sample, hold ticks; and the HAL concept
// it binds to.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <utility>

#include "osc/runtime/control_task.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

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
    EXPECT_FALSE(supervisor_healthy(task->sup));  // the faulting tick does not feed the watchdog
    // Stays latched with healthy inputs afterwards.
    run(3);
    EXPECT_EQ(task->sup.state, SupervisorState::kFault);
    EXPECT_TRUE(hal.all_zero());
    EXPECT_FALSE(supervisor_healthy(task->sup));
  }
};

TEST_F(TaskFixture, HealthyTicksRunAndCommandTorque) {
  EXPECT_EQ(run(5), 0u);
  EXPECT_EQ(task->sup.state, SupervisorState::kRun);
  EXPECT_FALSE(hal.all_zero());  // holds gravity
  EXPECT_EQ(hal.writes, 5);
  EXPECT_FALSE(hal.fault_line);
  EXPECT_TRUE(supervisor_healthy(task->sup));  // healthy ticks feed the watchdog
  EXPECT_EQ(task->timing.count, 5u);
  EXPECT_GT(task->timing.max, 0u);
}

TEST_F(TaskFixture, EncoderJumpFaultsInTheSameTick) {
  run(3);
  hal.counts[1] += task->jump.max_step[1];    // the largest plausible step is no jump (the torque it
  EXPECT_EQ(run(1) & kFaultEncoderJump, 0u);  // asks for while the other joints stand still is another matter)
  hal.counts[1] += task->jump.max_step[1] + 1;
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
  const auto edge =
      static_cast<std::int32_t>((robot::kArm.q_max[0] + params::kJointLimitMargin - robot::kQStart[0]) * c);
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

TEST_F(TaskFixture, FrozenEncodersWhileTheReferenceMovesFaultAsStuck) {
  // The robot's encoders do not move while the trajectory runs away. The residual monitor a trial:
  // the stuck-encoder monitor's criteria (reference motion or torque change while an encoder stands
  // still) latch long before the torques clip (this used to take the saturation check hundreds of
  // ticks at full scale).
  task->residual.armed = false;
  int k = 0;
  std::uint32_t f = 0;
  for (; k < 20000 && f == 0; ++k) f = run(1);
  EXPECT_EQ(f, static_cast<std::uint32_t>(kFaultEncoderStuck)) << "after " << k << " ticks";
  EXPECT_EQ(task->sup.latched & kFaultSaturation, 0u);
  expect_latched(kFaultEncoderStuck);
}

TEST_F(TaskFixture, FrozenEncodersFaultTheArmedResidualMonitor) {
  // The same, the residual monitor armed (the default): every joint still from rest under a rising
  // torque is an arm held where it stands, which the sensors cannot tell from a contact on every
  // joint or from drives that do not deliver (collision, drive_fault or encoder_stuck, as the
  // torques' pattern says); the residual monitor latches its fault once the torques leave the joints' static bands,
  // before any torque clips (the saturation check) or the tracking bound.
  ASSERT_TRUE(task->residual.armed);
  int k = 0;
  std::uint32_t f = 0;
  for (; k < 20000 && f == 0; ++k) f = run(1);
  EXPECT_TRUE(f == kFaultCollision || f == kFaultEncoderStuck || f == kFaultDriveFault)
      << f << " after " << k << " ticks";
  EXPECT_LT(k, 1000);
  EXPECT_EQ(task->sup.latched & (kFaultSaturation | kFaultTracking), 0u);
  expect_latched(f);
}

TEST_F(TaskFixture, PersistentSaturationFaults) {
  OSC_PUMA_TUNED("the torque that clips the PUMA's DAC does not clip the UR5e's");
  // Joint 1 creeps away from the reference by one count per tick (0.06 mm at the tip) and the other
  // encoders dither by a count (so that none stands still): the torque on joint 1 clips within a
  // millimetre of error, long before the 10 mm tracking bound, and after kSaturationTicks clipped
  // ticks the fault latches. (The residual monitor is a trial here: armed, it names this joint
  // running off at full torque a collision after 73 ticks, before the saturation check.)
  task->residual.armed = false;
  std::uint32_t f = 0;
  int k = 0, first_clip = -1;
  for (; k < 1000 && f == 0; ++k) {
    hal.counts[0] = k;
    for (int i = 1; i < kDof; ++i) hal.counts[i] = k % 2;
    f = run(1);
    if (first_clip < 0 && task->saturation.ticks[0] > 0) first_clip = k;
  }
  EXPECT_EQ(f, static_cast<std::uint32_t>(kFaultSaturation)) << "after " << k << " ticks";
  ASSERT_GE(first_clip, 0);
  int longest = 0;  // the joint that tripped it has been clipped exactly kSaturationTicks ticks
  for (int i = 0; i < kDof; ++i) longest = std::max<int>(longest, task->saturation.ticks[i]);
  EXPECT_EQ(longest, params::kSaturationTicks);
  expect_latched(kFaultSaturation);
}

TEST_F(TaskFixture, TrackingErrorBeyondItsBoundFaults) {
  // Joint 2 reads 0.01 rad off the start pose (about 6 mm at the tip): within the bound; 0.03 rad
  // (about 18 mm): a fault in that tick.
  hal.counts[1] = static_cast<std::int32_t>(0.01 * task->counts_per_rad(1));
  EXPECT_EQ(run(1), 0u);
  start(robot::kQStart);
  hal.counts[1] = static_cast<std::int32_t>(0.03 * task->counts_per_rad(1));
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultTracking));
  expect_latched(kFaultTracking);
}

TEST_F(TaskFixture, FrictionEstimateOutOfItsBoundsFaults) {
  // (67) has no bounds of its own: an estimate beyond [-theta_max, 2 theta_max] latches theta_bounds.
  // (The encoders dither by a count, so that the torque step the estimate causes is not taken for
  // a stuck encoder.)
  auto dither = [&](int n) {
    std::uint32_t f = 0;
    for (int k = 0; k < n; ++k) {
      for (int i = 0; i < kDof; ++i) hal.counts[i] ^= 1;
      f = run(1);
    }
    return f;
  };
  task->gains.adaptation = AdaptationLaw::kPaper;
  EXPECT_EQ(dither(2), 0u);
  task->state.adapt.theta_hat(7) = 2.1f * task->gains.theta_max(7);
  // The monitor checks three of the 18 a tick: within six ticks, and not before its part's turn.
  std::uint32_t f = 0;
  int ticks = 0;
  while (f == 0 && ticks < ThetaBandMonitor<float>::kParts) f = dither(1), ++ticks;
  EXPECT_EQ(f, static_cast<std::uint32_t>(kFaultThetaBounds));
  EXPECT_GE(ticks, 1);
  EXPECT_LE(ticks, ThetaBandMonitor<float>::kParts);
  expect_latched(kFaultThetaBounds);
  // The robust law projects a stray estimate back into [0, theta_max] in the step: no fault.
  start(robot::kQStart);
  task->gains.adaptation = AdaptationLaw::kRobust;
  EXPECT_EQ(dither(2), 0u);
  task->state.adapt.theta_hat(7) = 2.1f * task->gains.theta_max(7);
  EXPECT_EQ(dither(ThetaBandMonitor<float>::kParts), 0u);
  EXPECT_LE(task->state.adapt.theta_hat(7), task->gains.theta_max(7));
}

TEST_F(TaskFixture, EstopInputFaultsInTheSameTick) {
  run(2);
  hal.faults = kFaultEstop;
  EXPECT_EQ(run(1), static_cast<std::uint32_t>(kFaultEstop));
  expect_latched(kFaultEstop);
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
  EXPECT_TRUE(hal.all_zero());                        // zero codes in this tick
  EXPECT_EQ(task->step_timing.count, steps);          // no control step
  EXPECT_EQ(task->sup.state, SupervisorState::kRun);  // and no latch
  EXPECT_FALSE(hal.fault_line);
  EXPECT_EQ(task->tick, tick + 1);  // the sample clock runs on
  hal.sample = true;
  EXPECT_EQ(run(1), 0u);
  EXPECT_FALSE(hal.all_zero());  // torque again with the next sample
}

TEST_F(TaskFixture, TheEncoderJumpLimitSpansTheTicksWithoutASample) {
  run(3);
  hal.sample = false;
  run(2);  // two ticks without a sample: the next one is three ticks after the last
  hal.sample = true;
  hal.counts[1] += 3 * task->jump.max_step[1];
  EXPECT_EQ(run(1) & kFaultEncoderJump, 0u);  // no jump (the stuck and tracking monitors see it, though)
  hal.sample = false;
  run(1);
  hal.sample = true;
  hal.counts[1] += 2 * task->jump.max_step[1] + 1;  // beyond two ticks' worth
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
  EXPECT_EQ(task->jump.age, 1u);
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
