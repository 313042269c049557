// The task's trajectory (68) (osc/control/trajectory.hpp): its spec from a period and an envelope, the
// paper's and others; at rest at its start, its derivatives against finite differences.
#include <gtest/gtest.h>

#include <cmath>

#include "controller_fixtures.hpp"
#include "osc/control/trajectory.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST(Trajectory, SpecFromPeriodAndEnvelopeReproducesThePapersAndScalesToOthers) {
  const TrajectorySpec<double> s = trajectory_spec(params::kAmplitude, 5000, params::kEnvelope, params::kDt);
  EXPECT_EQ(s.period_ticks, kTrajectoryPeriodTicks);
  EXPECT_EQ(s.settled_ticks, kEnvelopeSettledTicks);
  EXPECT_NEAR(s.omega, params::kOmega, 1e-15);
  // A 2 s period with a slower envelope: c t^3 >= 400 first at t = 20 s (c = 0.05) -> 10 periods;
  // c = 0.01: t >= 34.2 s -> 18 periods of 2 s = 36 s.
  const TrajectorySpec<double> f = trajectory_spec(0.02, 2000, 0.01, params::kDt);
  EXPECT_EQ(f.settled_ticks, 36000u);
  EXPECT_NEAR(f.omega, kPi, 1e-15);
  // The phase after settling repeats with the configured period.
  const Vec3<double> p0(0.5, 0, 0.3);
  for (std::uint64_t n : {36000ull, 36000ull + 777, 1000000ull + 3}) {
    const double t1 = trajectory_time(f, n, 1000), t2 = trajectory_time(f, n + 2000, 1000);
    EXPECT_EQ(t1, t2);
    EXPECT_NEAR(trajectory(f, p0, t1).x(0) - p0(0), 0.02 * std::sin(kPi * static_cast<double>(n) * 1e-3), 1e-9) << n;
  }
}

TEST(Trajectory, StartsAtRestAndDerivativesMatchFiniteDifferences) {
  const Vec3<double> p0(0.6, -0.15, 0.0);
  const Desired<double> d0 = trajectory(kPaperTrajectory, p0, 0.0);
  EXPECT_LT((d0.x.head<3>() - p0).norm(), 1e-15);
  EXPECT_LT(d0.xd.norm(), 1e-15);
  EXPECT_LT(d0.xdd.norm(), 1e-15);
  EXPECT_EQ(d0.x.tail<3>().norm(), 0.0);  // orientation held
  const double h = 1e-5;
  for (double t : {0.3, 1.7, 4.2, 9.9, 33.3, 119.0}) {
    const Desired<double> d = trajectory(kPaperTrajectory, p0, t), dp = trajectory(kPaperTrajectory, p0, t + h),
                          dm = trajectory(kPaperTrajectory, p0, t - h);
    EXPECT_LT(((dp.x - dm.x) / (2 * h) - d.xd).norm(), 1e-8) << t;
    EXPECT_LT(((dp.xd - dm.xd) / (2 * h) - d.xdd).norm(), 1e-7) << t;
  }
  // After the envelope: +-50 mm, y and z equal (f = 1).
  const Desired<double> d = trajectory(kPaperTrajectory, p0, 100.0 + 1.25);  // sin = 1 at a quarter period
  EXPECT_NEAR(d.x(0) - p0(0), params::kAmplitude, 1e-9);
  EXPECT_NEAR(d.x(1) - p0(1), d.x(2) - p0(2), 1e-15);
}

}  // namespace
