// The identification run's two sides (osc/runtime/identify_run.hpp): the tick's sampler (a run primes the
// filter, a sample every params::kRunSampleTicks, the torque of the tick before) and the main loop's
// (each new sample taken once, a missed one counted lost, another run's ignored). The estimate it forms
// on the simulated arm: tests/host_sim/test_identify_sim.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "osc/robot.hpp"
#include "osc/runtime/identify_run.hpp"

namespace {

using namespace osc;

TEST(IdentifySampler, APrimedRunGivesASampleEveryFiveTicks) {
  IdentifySampler<double> s;
  s.reset();
  const Vec6<double> q = joint_vector<double>(robot::kQStart), tau = Vec6<double>::Constant(2.0);
  const Vec6<double> dec = Vec6<double>::Constant(params::kTauDec);
  for (int k = 1; k <= 23; ++k) {
    s.tick(7, q, tau, Vec6<double>::Zero(), dec);
    EXPECT_EQ(s.count, static_cast<std::uint32_t>(k / params::kRunSampleTicks)) << k;
  }
  // Primed at rest: the filtered angles are the angles, their rates 0, the torque the torque.
  EXPECT_LT((s.sample.q - q).norm(), 1e-12);
  EXPECT_LT(s.sample.qd.norm(), 1e-12);
  EXPECT_LT((s.sample.tau - tau).norm(), 1e-12);
  // Another run starts over.
  s.tick(8, q, tau, Vec6<double>::Zero(), dec);
  EXPECT_EQ(s.run_id, 8u);
  EXPECT_EQ(s.count, 0u);
}

TEST(IdentifySampler, TheTorqueIsTheTickBefores) {
  IdentifySampler<double> a, b;
  a.reset(), b.reset();
  const Vec6<double> q = Vec6<double>::Zero(), dec = Vec6<double>::Constant(1.0), zero = Vec6<double>::Zero();
  // a: a torque step at tick 3; b: the same step fed one tick later by hand, with the tick before's own.
  IdentifyFilter<double> f;
  f.prime(q, zero, zero, dec);
  for (int k = 0; k < 10; ++k) {
    const Vec6<double> tau = k >= 3 ? Vec6<double>::Constant(1.0) : zero;
    const Vec6<double> before = k >= 4 ? Vec6<double>::Constant(1.0) : zero;
    a.tick(1, q, tau, zero, dec);
    f.update(q, before, zero);
  }
  EXPECT_EQ((a.filter.signals().tau - f.signals().tau).norm(), 0.0);
}

TEST(IdentifyRun, EachSampleIsTakenOnceAndAMissedOneCounted) {
  IdentifySampler<double> s;
  s.reset();
  const Model<double> model = Model<double>::of(robot::kArm);
  IdentifyRun<double> run;
  run.start(3, payload_mask::kNone, model, model);
  const Vec6<double> q = joint_vector<double>(robot::kQStart), z = Vec6<double>::Zero();
  const Vec6<double> dec = Vec6<double>::Constant(1.0);
  int taken = 0;
  for (int k = 0; k < 100; ++k) {
    s.tick(3, q, z, z, dec);
    // The main loop polls every tick for the first 50, then every 12 ticks (two samples or three apart).
    if (k >= 50 && k % 12 != 0) continue;
    taken += run.poll(s);
    EXPECT_FALSE(run.poll(s));  // nothing new a second time
  }
  taken += run.poll(s);  // the last one
  EXPECT_EQ(run.taken(), static_cast<std::uint32_t>(taken));
  EXPECT_EQ(run.taken() + run.lost(), s.count);
  EXPECT_GT(run.lost(), 0u);
  // Another run's samples are not this one's.
  IdentifyRun<double> other;
  other.start(4, payload_mask::kNone, model, model);
  EXPECT_FALSE(other.poll(s));
}

}  // namespace
