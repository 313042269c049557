// The encoder checks (osc/runtime/encoder_monitors.hpp), each alone against its rule written out from
// docs/safety.md and params::: the range of every reading, the jump since the last sample, and the
// stuck-encoder monitor fed a step output by hand (in double, float and fixed point).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "monitor_fixtures.hpp"
#include "osc/runtime/encoder_monitors.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST(EncoderRange, LimitsPlusTheMarginRoundedOutwards) {
  EncoderRangeMonitor m;
  const double c = 1000;  // counts per radian
  for (int i = 0; i < kDof; ++i) m.set(i, 0.25, c);
  for (int i = 0; i < kDof; ++i) {
    // The rule: (q_min - margin - q0) c, truncated, less one; likewise above.
    const double lo = (robot::kArm.q_min[i] - params::kJointLimitMargin - 0.25) * c;
    const double hi = (robot::kArm.q_max[i] + params::kJointLimitMargin - 0.25) * c;
    EXPECT_LE(m.min_counts[i], std::floor(lo));
    EXPECT_GE(m.min_counts[i], std::floor(lo) - 2);
    EXPECT_GE(m.max_counts[i], std::ceil(hi));
    EXPECT_LE(m.max_counts[i], std::ceil(hi) + 2);
  }
  std::int32_t counts[kDof] = {};
  EXPECT_EQ(m.check(counts), 0u);
  for (int i = 0; i < kDof; ++i) {
    std::int32_t at[kDof] = {};
    at[i] = static_cast<std::int32_t>(m.max_counts[i]);
    EXPECT_EQ(m.check(at), 0u) << i;
    at[i] += 1;
    EXPECT_EQ(m.check(at), kFaultEncoderRange) << i;
    at[i] = static_cast<std::int32_t>(m.min_counts[i]);
    EXPECT_EQ(m.check(at), 0u) << i;
    at[i] -= 1;
    EXPECT_EQ(m.check(at), kFaultEncoderRange) << i;
  }
}

TEST(EncoderJump, TheSpeedLimitOverTheTicksSinceTheLastSample) {
  EncoderJumpMonitor m;
  m.reset();
  for (int i = 0; i < kDof; ++i) m.set(i, counts_per_rad(i));
  for (int i = 0; i < kDof; ++i)  // speed limit x 1 ms x counts/rad, + 1
    EXPECT_EQ(m.max_step[i],
              static_cast<std::int32_t>(robot::kDrives.max_joint_speed[i] * 1e-3 * counts_per_rad(i)) + 1);
  std::int32_t c[kDof] = {100, -100, 5, 0, 7, 1 << 30};
  bool moved[kDof] = {};
  m.tick();
  EXPECT_EQ(m.check(c, moved), 0u);  // the first sample: anything within range is fine
  EXPECT_TRUE(m.have_counts);
  for (bool b : moved) EXPECT_TRUE(b);  // the monitors start here
  m.tick();
  c[1] += m.max_step[1];
  EXPECT_EQ(m.check(c, moved), 0u);
  EXPECT_TRUE(moved[1]);
  EXPECT_FALSE(moved[0]);
  // Two ticks, one of them without a sample: twice the step is plausible, one count more is not.
  m.tick();
  m.tick();
  EXPECT_EQ(m.age, 2u);
  c[2] -= 2 * m.max_step[2];
  EXPECT_EQ(m.check(c, moved), 0u);
  m.tick();
  c[2] -= m.max_step[2] + 1;
  EXPECT_EQ(m.check(c, moved), kFaultEncoderJump);
  EXPECT_EQ(m.age, 0u);
  // A wrap of the 32-bit count is a jump, not a small step.
  m.tick();
  c[5] = std::numeric_limits<std::int32_t>::min();
  std::int32_t before[kDof];
  std::copy(c, c + kDof, before);
  m.tick();
  before[5] = std::numeric_limits<std::int32_t>::max();
  EXPECT_EQ(m.check(before, moved), kFaultEncoderJump);
  EXPECT_EQ(m.check(c, moved), kFaultEncoderJump);
}

/// The stuck-encoder monitor fed a step output by hand: joint `j` driven at `qd` rad/s with torque
/// `tau` while its encoder stands still from tick 1 on.
template <class S>
struct StuckRig {
  StuckEncoderMonitor<S> m;
  Vec6<math::io_scalar_t<S>> cpr;
  StepOutput<S> out{};
  Vec6<S> qd_ref;  // the joint rates the reference commands
  std::int32_t counts[kDof] = {};
  std::uint64_t tick = 0;
  StuckRig() {
    m.reset();
    for (int i = 0; i < kDof; ++i) cpr(i) = lit<math::io_scalar_t<S>>(counts_per_rad(i));
    out.tau.setZero();
    qd_ref.setZero();
  }
  /// One tick; `moved_all`: every encoder counted, by `way` counts.
  std::uint32_t step(bool moved_all, std::int32_t way = 1) {
    bool moved[kDof];
    for (int i = 0; i < kDof; ++i) moved[i] = moved_all, counts[i] += moved_all ? way : 0;
    return m.check(out.tau, qd_ref, counts, moved, tick++, lit<S>(params::kDt), cpr);
  }
};

TYPED_TEST(Monitors, StuckEncoderTorqueChangeWhileStill) {
  using S = TypeParam;
  for (int j = 0; j < kDof; ++j) {
    StuckRig<S> r;
    r.tick = 1000;  // the first count 1000 ticks after the start: a slow joint
    r.out.tau(j) = lit<S>(5);
    EXPECT_EQ(r.step(true), 0u);  // counted at a torque of 5 N m
    // Still, but the torque within 5 +- 0.95 kStuckTorque: fine for a while (the silent checks
    // wait kStuckIntervals of its 1000-tick interval).
    r.out.tau(j) = lit<S>(5 - 0.95 * params::kStuckTorque[j]);
    for (int k = 0; k < 100; ++k) ASSERT_EQ(r.step(false), 0u) << j << " " << k;
    // Beyond it: a fault once it has held for kStuckQualifyTicks ticks in a row. A tick back
    // within it starts the count again.
    r.out.tau(j) = lit<S>(5 + 1.05 * params::kStuckTorque[j]);
    for (int k = 1; k < params::kStuckQualifyTicks; ++k) ASSERT_EQ(r.step(false), 0u) << j << " " << k;
    r.out.tau(j) = lit<S>(5);
    ASSERT_EQ(r.step(false), 0u) << j;
    r.out.tau(j) = lit<S>(5 + 1.05 * params::kStuckTorque[j]);
    for (int k = 1; k < params::kStuckQualifyTicks; ++k) ASSERT_EQ(r.step(false), 0u) << j << " " << k;
    EXPECT_EQ(r.step(false), kFaultEncoderStuck) << j;
    EXPECT_GE(static_cast<double>(r.m.dtau_peak(j)), 1.04 * params::kStuckTorque[j]);
  }
}

TYPED_TEST(Monitors, StuckEncoderSilentWhileTheReferenceMoves) {
  using S = TypeParam;
  const int j = 1;
  StuckRig<S> r;
  // Counting every tick: the recent interval is 1 tick.
  for (int k = 0; k < 5; ++k) ASSERT_EQ(r.step(true), 0u);
  // Then silent, with the reference moving the joint by v counts a tick: the monitor waits out
  // kStuckIntervals intervals, then faults once the motion passes kStuckMotionCounts.
  const double v = 2.0;  // counts per tick
  r.qd_ref(j) = lit<S>(v / (params::kDt * counts_per_rad(j)));
  const int expect = static_cast<int>(std::ceil(params::kStuckMotionCounts / v));
  int fault_tick = -1;
  for (int k = 1; k <= 2 * expect && fault_tick < 0; ++k)
    if (r.step(false) & kFaultEncoderStuck) fault_tick = k;
  EXPECT_NEAR(fault_tick, expect + 1, 2);
  // A joint that was counting fast also faults on the smaller silent torque change: at once when
  // the silence is long enough, the change having lasted since (qualified); ...
  StuckRig<S> t;
  for (int k = 0; k < 5; ++k) ASSERT_EQ(t.step(true), 0u);
  t.out.tau(j) = lit<S>(1.05 * params::kStuckTorqueSilent[j]);
  int first = -1;
  for (int k = 1; k <= 3 * params::kStuckIntervals && first < 0; ++k)
    if (t.step(false) & kFaultEncoderStuck) first = k;
  EXPECT_EQ(first, params::kStuckIntervals + 1);
  // ... or once it has lasted kStuckQualifyTicks ticks, a change that came after the silence did.
  StuckRig<S> u;
  for (int k = 0; k < 5; ++k) ASSERT_EQ(u.step(true), 0u);
  first = -1;
  for (int k = 1; k <= 3 * params::kStuckIntervals && first < 0; ++k) {
    u.out.tau(j) = lit<S>(k > params::kStuckIntervals ? 1.05 * params::kStuckTorqueSilent[j] : 0.0);
    if (u.step(false) & kFaultEncoderStuck) first = k;
  }
  EXPECT_EQ(first, params::kStuckIntervals + params::kStuckQualifyTicks);
}

TYPED_TEST(Monitors, StuckEncoderDitherIsNoMovingJoint) {
  using S = TypeParam;
  // An encoder dithering by a count every tick, both ways, as an edge under the sensor does at rest:
  // its interval is 1 tick, but it was not counting one way. Then silent, with a torque change above
  // the moving joint's silent threshold and below the still joint's: no fault (the compensation's
  // sign flips at rest by twice the Coulomb + Stribeck level, 18 N m on J2).
  for (int j = 0; j < kDof; ++j) {
    StuckRig<S> r;
    for (int k = 0; k < 6; ++k) ASSERT_EQ(r.step(true, k % 2 ? -1 : 1), 0u);
    const double between = (params::kStuckTorqueSilent[j] + params::kStuckTorque[j]) / 2;
    r.out.tau(j) = lit<S>(between);
    for (int k = 0; k < 4 * params::kStuckIntervals; ++k) ASSERT_EQ(r.step(false), 0u) << j << " " << k;
    EXPECT_EQ(static_cast<double>(r.m.dtau_gated_peak(j)), 0.0) << j;
    // The same torque after counting one way: the silent criterion trips.
    StuckRig<S> t;
    for (int k = 0; k < 6; ++k) ASSERT_EQ(t.step(true, -1), 0u);
    t.out.tau(j) = lit<S>(between);
    int first = -1;
    for (int k = 1; k <= 4 * params::kStuckIntervals && first < 0; ++k)
      if (t.step(false) & kFaultEncoderStuck) first = k;
    EXPECT_EQ(first, params::kStuckIntervals + 1) << j;
  }
}

// The activity's window (the residual monitor's slide test on a fine encoder): each channel's |change| over
// the last whole window of params::kResidualSlideInterval ticks, whichever way, and nothing from the
// restart's reading on until a window has passed.
TEST(EncoderActivity, TheWindowsTravelIsTheLastWholeWindowsChange) {
  EncoderActivity a;
  a.reset();
  std::int32_t counts[kDof] = {};
  bool moved[kDof] = {};
  a.restart(counts, 0);
  constexpr int kW = params::kResidualSlideInterval;
  const std::int32_t pace[kDof] = {3, -2, 0, 1, 7, -1};  // counts a tick
  for (int t = 1; t <= 3 * kW; ++t) {
    for (int i = 0; i < kDof; ++i) {
      moved[i] = pace[i] != 0;
      counts[i] += pace[i];
    }
    a.track(counts, moved, static_cast<std::uint64_t>(t));
    for (int i = 0; i < kDof; ++i) {
      const std::uint32_t expect = t < kW ? 0u : static_cast<std::uint32_t>(std::abs(pace[i]) * kW);
      EXPECT_EQ(a.window_travel[i], expect) << "tick " << t << " channel " << i;
    }
  }
  // A joint that stops: its next whole window reads 0.
  for (int t = 3 * kW + 1; t <= 5 * kW; ++t) {
    for (int i = 0; i < kDof; ++i) moved[i] = false;
    a.track(counts, moved, static_cast<std::uint64_t>(t));
  }
  for (int i = 0; i < kDof; ++i) EXPECT_EQ(a.window_travel[i], 0u) << i;
}

// Without windows (the stuck-encoder monitor's record, which no slide test reads): the same changes, intervals and
// directions as with them, and the windows' counts left as they were.
TEST(EncoderActivity, WithoutWindowsTheChangesAreTrackedAloneTheSame) {
  EncoderActivity with, without;
  with.reset();
  without.reset();
  std::int32_t counts[kDof] = {};
  bool moved[kDof] = {};
  with.restart(counts, 0);
  without.restart(counts, 0);
  const std::int32_t pace[kDof] = {3, -2, 0, 1, 7, -1};
  for (int t = 1; t <= 4 * params::kResidualSlideInterval; ++t) {
    for (int i = 0; i < kDof; ++i) {
      moved[i] = pace[i] != 0 && t % (i + 1) == 0;
      if (moved[i]) counts[i] += t % 3 == 0 ? -pace[i] : pace[i];
    }
    with.track(counts, moved, static_cast<std::uint64_t>(t));
    without.track(counts, moved, static_cast<std::uint64_t>(t), false);
    for (int i = 0; i < kDof; ++i) {
      EXPECT_EQ(without.last_move_tick[i], with.last_move_tick[i]) << t << " " << i;
      EXPECT_EQ(without.move_interval[i], with.move_interval[i]) << t << " " << i;
      EXPECT_EQ(without.direction[i], with.direction[i]) << t << " " << i;
      EXPECT_EQ(without.steady[i], with.steady[i]) << t << " " << i;
      EXPECT_EQ(without.reversed[i], with.reversed[i]) << t << " " << i;
      EXPECT_EQ(without.window_travel[i], 0u) << t << " " << i;
    }
  }
  for (int i = 0; i < kDof; ++i) {
    if (pace[i] != 0) {
      EXPECT_GT(with.window_travel[i], 0u) << i;
    }
  }
}

}  // namespace
