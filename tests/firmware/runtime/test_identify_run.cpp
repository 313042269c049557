// The identification run's two sides (osc/runtime/identify_run.hpp): the tick's sampler (each tick's signals into
// the ring, the torque of the tick before) and the main loop's run (the filter over the ring's ticks, primed at the
// run's first, a sample every params::kRunSampleTicks; a gap in its reads lost and settled over, another run's
// ignored). The estimate it forms on the simulated arm: tests/host_sim/test_identify_sim.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "osc/robot.hpp"
#include "osc/runtime/identify_run.hpp"

namespace {

using namespace osc;

/// A run on the PUMA's model (friction only), its sampler reset.
struct RunFixture {
  Model<double> model = Model<double>::of(robot::kArm);
  IdentifySampler<double> s;
  IdentifyRun<double> run;
  Vec6<double> dec = Vec6<double>::Constant(params::kTauDec);
  explicit RunFixture(std::uint32_t id) {
    s.reset();
    run.start(id, payload_mask::kNone, model, model);
  }
};

TEST(IdentifySampler, EachTickGoesIntoTheRingWithTheTorqueOfTheTickBefore) {
  IdentifySampler<double> s;
  s.reset();
  const Vec6<double> q = joint_vector<double>(robot::kQStart), dec = Vec6<double>::Constant(1.0);
  for (int k = 0; k < 70; ++k) s.tick(7, q, Vec6<double>::Constant(k), Vec6<double>::Constant(0.01 * k), dec);
  EXPECT_EQ(s.ticks, 70u);
  EXPECT_EQ(s.run_id, 7u);
  // Tick 69 in entry 69 % 64 = 5, with tick 68's torque; the first tick's torque is its own (the motion at rest).
  const IdentifyTick<double>& e = s.ring[69 % params::kRunRingTicks];
  EXPECT_EQ(e.tau(0), 68.0);
  EXPECT_EQ(e.qd(0), 0.01 * 69);
  IdentifySampler<double> t;
  t.reset();
  t.tick(3, q, Vec6<double>::Constant(2.0), Vec6<double>::Zero(), dec);
  EXPECT_EQ(t.ring[0].tau(0), 2.0);
  // Another run starts over.
  s.tick(8, q, Vec6<double>::Zero(), Vec6<double>::Zero(), dec);
  EXPECT_EQ(s.run_id, 8u);
  EXPECT_EQ(s.ticks, 1u);
}

TEST(IdentifyRun, APrimedRunGivesASampleEveryFiveTicksAndTheFilterSeesTheTickBeforesTorque) {
  RunFixture f(7);
  const Vec6<double> q = joint_vector<double>(robot::kQStart), zero = Vec6<double>::Zero();
  // The same torque step through the run and through a filter fed by hand with the tick before's.
  IdentifyFilter<double> hand;
  hand.prime(q, zero, zero, f.dec);
  int taken = 0;
  for (int k = 1; k <= 23; ++k) {
    const Vec6<double> tau = k >= 3 ? Vec6<double>::Constant(1.0) : zero;
    const Vec6<double> before = k >= 4 ? Vec6<double>::Constant(1.0) : zero;
    f.s.tick(7, q, tau, zero, f.dec);
    hand.update(q, before, zero);
    taken += f.run.poll(f.s);
    EXPECT_EQ(taken, k / static_cast<int>(params::kRunSampleTicks)) << k;
    EXPECT_EQ(f.run.poll(f.s), 0);  // nothing new a second time
  }
  EXPECT_EQ(f.run.taken(), 4u);
  EXPECT_EQ(f.run.lost(), 0u);
  EXPECT_EQ((f.run.filter().signals().tau - hand.signals().tau).norm(), 0.0);
  EXPECT_LT((f.run.filter().signals().q - q).norm(), 1e-12);  // primed at rest: the angles held
}

TEST(IdentifyRun, PollsWithinTheRingLoseNothingAndAGapIsLostThenSettled) {
  const Vec6<double> q = joint_vector<double>(robot::kQStart), z = Vec6<double>::Zero();
  // Every 12 ticks: within the ring, the same samples as every tick, and so the same estimate to the bit (a motion
  // of each joint, its torque, and the rates).
  RunFixture a(3), b(3);
  constexpr int kTicks = 4000;
  for (int k = 1; k <= kTicks; ++k) {
    Vec6<double> qk, tau, qd;
    for (int i = 0; i < kDof; ++i) {
      const double w = 0.01 * (i + 1), t = 1e-3 * k;
      qk(i) = q(i) + 0.2 * std::sin(w * k);
      qd(i) = 0.2 * w * 1e3 * std::cos(w * k);
      tau(i) = 5.0 * std::cos(w * k) + 2.0 * std::tanh(qd(i)) + t;
    }
    a.s.tick(3, qk, tau, qd, a.dec), b.s.tick(3, qk, tau, qd, b.dec);
    a.run.poll(a.s);
    if (k % 12 == 0) b.run.poll(b.s);
  }
  b.run.poll(b.s);
  EXPECT_EQ(a.run.taken(), kTicks / params::kRunSampleTicks);
  EXPECT_EQ(b.run.taken(), kTicks / params::kRunSampleTicks);
  EXPECT_EQ(b.run.lost(), 0u);
  const IdentifyReport ra = a.run.finish(), rb = b.run.finish();
  EXPECT_EQ(ra.samples, kTicks / params::kRunSampleTicks);
  EXPECT_EQ(ra.status, rb.status);
  EXPECT_NE(ra.residual_rms.norm(), 0.0);  // the rows were not empty
  EXPECT_EQ((ra.residual_rms - rb.residual_rms).norm(), 0.0);
  EXPECT_EQ((ra.friction - rb.friction).norm(), 0.0);
  // A poll 300 ticks after the last: the ticks the ring no longer holds are lost, and the filter's first
  // kRunSettleTicks after them; taken + lost is every sample of the run.
  RunFixture c(4);
  for (int k = 1; k <= 1000; ++k) {
    c.s.tick(4, q, z, z, c.dec);
    if (k <= 100 || k > 400) c.run.poll(c.s);
  }
  const std::uint32_t gap = (400 - params::kRunRingTicks) / params::kRunSampleTicks - 100 / params::kRunSampleTicks;
  const std::uint32_t settling = params::kRunSettleTicks / params::kRunSampleTicks;
  EXPECT_EQ(c.run.lost(), gap + settling);
  EXPECT_EQ(c.run.taken() + c.run.lost(), 1000 / params::kRunSampleTicks);
  // Another run's ticks are not this one's.
  IdentifyRun<double> other;
  other.start(5, payload_mask::kNone, c.model, c.model);
  EXPECT_EQ(other.poll(c.s), 0);
}

}  // namespace
