// The point-to-point move (osc/control/cartesian_move.hpp) run by the motion generator: the reference
// it produces, sampled every millisecond, against its limits (speed, acceleration and jerk of the
// translation and of the rotation, the rotation's from E(phi) phi_dot, not from the profile), the
// straight line and the single axis, its end; the orientation coordinates' rates against finite
// differences; the targets and limits it refuses.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "motion_fixtures.hpp"
#include "osc/control/cartesian_move.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST(CartesianMove, StraightLineAboutOneAxisWithinItsLimitsEndingAtTheTarget) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose<double> a =
        pose(0.4 + 0.1 * U(rng), 0.1 * U(rng), 0.3 + 0.1 * U(rng), {0.3 * U(rng), 0.3 * U(rng), U(rng)});
    const Pose<double> b =
        pose(0.4 + 0.2 * U(rng), 0.2 * U(rng), 0.3 + 0.2 * U(rng), {0.3 * U(rng), 0.3 * U(rng), U(rng)});
    const Mat3<double> R_ref = rpy_rotation<double>({0.1, -0.2, 0.3});
    CartesianMove<double> m;
    ASSERT_EQ(m.plan(a, b, kLim, R_ref), ProfileStatus::kOk);
    // Synchronised: both profiles last the move's duration (or are empty).
    for (double dur : {m.linear().duration(), m.angular().duration()}) {
      if (dur > 0) {
        EXPECT_NEAR(dur, m.duration(), 1e-9);
      }
    }
    MotionGenerator<double> g;
    g.hold(a, R_ref);
    ASSERT_TRUE(g.push(m));
    g.start_moves(100);
    const Vec3<double> line[2] = {a.p, b.p};
    const Trace tr = run(g, 100, 20000, true, line);
    expect_within_limits(tr);
    EXPECT_LE(tr.off_line, 1e-12);
    EXPECT_EQ(tr.finished, 1);
    EXPECT_NEAR(tr.ticks - 1, m.duration() * kHz, 1.0);
    // It ends holding the target: position and orientation coordinates of b.
    EXPECT_LE((tr.last.x.head<3>() - b.p).norm(), 1e-12);
    EXPECT_LE((tr.last.x.tail<3>() - orientation_coordinates<double>(b.R, R_ref)).norm(), 1e-9);
    EXPECT_EQ(tr.last.xd.norm(), 0.0);
  }
}

TEST(CartesianMove, OrientationRatesAreTheDerivativesOfItsCoordinates) {
  const Mat3<double> R_ref = rpy_rotation<double>({0.2, 0.1, -0.4});
  CartesianMove<double> m;
  ASSERT_EQ(m.plan(pose(0.5, 0, 0.3, {0, 0, 0}), pose(0.5, 0.05, 0.3, {0.5, -0.4, 0.9}), kLim, R_ref),
            ProfileStatus::kOk);
  const double h = 1e-6;
  double worst_v = 0, worst_a = 0;
  for (double t = 0.01; t < m.duration(); t += 0.037) {
    const Desired<double> d = m.at(t), dp = m.at(t + h), dm = m.at(t - h);
    worst_v = std::max(worst_v, ((dp.x - dm.x) / (2 * h) - d.xd).norm());
    worst_a = std::max(worst_a, ((dp.xd - dm.xd) / (2 * h) - d.xdd).norm());
    // The orientation is the rotation about the one axis: R(t) R0^T = Rot(k, psi(t)).
    const Mat3<double> R = rpy_rotation<double>(d.x.tail<3>()) * R_ref;
    const Mat3<double> Rd = R * rpy_rotation<double>({0, 0, 0}).transpose();
    Vec3<double> k;
    double angle;
    rotation_axis_angle<double>(Rd, k, angle);
    EXPECT_NEAR(std::abs(k.dot(m.axis())), 1.0, 1e-9) << t;
    EXPECT_NEAR(angle, m.angular().at(t).p, 1e-9) << t;
  }
  EXPECT_LE(worst_v, 1e-6);
  EXPECT_LE(worst_a, 1e-4);
}

TEST(CartesianMove, RefusesRotationsBeyondTheLimitAndNonFiniteTargets) {
  CartesianMove<double> m;
  const Pose<double> a = pose(0.5, 0, 0.3, {0, 0, 0});
  EXPECT_EQ(m.plan(a, pose(0.5, 0, 0.3, {0, 0, 3.0}), kLim, a.R), ProfileStatus::kBadTarget);
  EXPECT_EQ(m.plan(a, pose(NAN, 0, 0.3, {0, 0, 0}), kLim, a.R), ProfileStatus::kBadTarget);
  CartesianLimits<double> bad = kLim;
  bad.linear.v = 0;
  EXPECT_EQ(m.plan(a, pose(0.6, 0, 0.3, {0, 0, 0}), bad, a.R), ProfileStatus::kBadLimits);
  EXPECT_FALSE(bad.within(kLim));
  bad = kLim;
  bad.angular.j *= 1.01;
  EXPECT_FALSE(bad.within(kLim));
  EXPECT_TRUE(kLim.within(kLim));
}

}  // namespace
