// The excitation's preparation (osc/control/excitation_check.hpp): it runs the motion at the largest of its scales
// 1, 0.9, 0.81, ... (params::kExcitationScaleStep, down to kExcitationMinScale) that passes, full scale first and
// then by halving, in at most four checks. The check itself is test_excitation.cpp's.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "osc/control/excitation.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

const Model<double>& arm_model() {
  static const Model<double> m = Model<double>::of(robot::kArm);
  return m;
}
Data<double>& kernels_data() {
  static const std::unique_ptr<Data<double>> d = std::make_unique<Data<double>>();
  return *d;
}

Vec6<double> q_start() { return joint_vector<double>(robot::kQStart); }

/// The orientation of frame 6 at q (the controller's reference there).
Mat3<double> orientation_of(const Vec6<double>& q) {
  Data<double> d;
  forward_kinematics(arm_model(), d, q);
  return d.R[kDof];
}

/// J1's torque the motion needs at scale s from the start pose (no loop test: the torque alone decides).
double j1_torque_at(double s) {
  ExcitationMotion<double> m;
  const ExcitationLimits<double> lim = ExcitationLimits<double>::defaults();
  EXPECT_EQ(m.plan(q_start(), lim), ExcitationStatus::kOk);
  m.set_scale(s);
  const ExcitationCheck<double> c = check_excitation(arm_model(), kernels_data(), m, orientation_of(q_start()), lim);
  EXPECT_EQ(c.status, ExcitationStatus::kOk) << s;
  return c.torque(0);
}

}  // namespace

TEST(ExcitationCheck, TheScalesAreTheStepsPowersDownToTheLeastCut) {
  EXPECT_EQ(excitation::kAttempts, 7);  // 0.9^6 = 0.531 >= kExcitationMinScale = 0.5 > 0.9^7 = 0.478
  for (int k = 0; k < excitation::kAttempts; ++k)
    EXPECT_NEAR(excitation::scale_of<double>(k), std::pow(0.9, k), 1e-15) << k;
  EXPECT_GE(excitation::scale_of<double>(excitation::kAttempts - 1), params::kExcitationMinScale);
  EXPECT_LT(excitation::scale_of<double>(excitation::kAttempts), params::kExcitationMinScale);
}

// For each scale k, J1's torque limit just above what the motion needs there (and below what it needs at the scale
// before): the preparation runs it at exactly that scale, the largest that passes, after at most four checks (a
// linear search would take k + 1, up to seven).
TEST(ExcitationCheck, ItRunsAtTheLargestScaleThatPassesInAtMostFourChecks) {
  for (int k = 0; k < excitation::kAttempts; ++k) {
    const double s = excitation::scale_of<double>(k);
    ExcitationLimits<double> lim = ExcitationLimits<double>::defaults();
    lim.torque(0) = j1_torque_at(s) * (1 + 1e-9);
    if (k > 0) {
      ASSERT_GT(j1_torque_at(excitation::scale_of<double>(k - 1)), lim.torque(0)) << k;
    }
    ExcitationMotion<double> m;
    const ExcitationCheck<double> c =
        prepare_excitation(arm_model(), kernels_data(), q_start(), orientation_of(q_start()), lim, m);
    ASSERT_EQ(c.status, ExcitationStatus::kOk) << k;
    EXPECT_NEAR(c.scale, s, 1e-12) << k;
    EXPECT_NEAR(m.scale(), s, 1e-12) << k;  // the motion to run is set at it, not at the last scale checked
    EXPECT_LE(c.torque(0), lim.torque(0)) << k;
    // Full scale, then [1, 6] halved: 3 first (passes for k <= 3), then 1 or 5, then 2, 4 or 6 where needed.
    constexpr int kChecks[] = {1, 3, 4, 4, 4, 4, 4};
    EXPECT_EQ(c.checks, kChecks[k]) << k;
  }
}

// None passes: refused with the smallest scale's reason, after four checks.
TEST(ExcitationCheck, WhereNoScalePassesItIsRefusedWithTheSmallestScalesReason) {
  ExcitationLimits<double> lim = ExcitationLimits<double>::defaults();
  lim.torque(0) = 0.9 * j1_torque_at(excitation::scale_of<double>(excitation::kAttempts - 1));
  ExcitationMotion<double> m;
  const ExcitationCheck<double> c =
      prepare_excitation(arm_model(), kernels_data(), q_start(), orientation_of(q_start()), lim, m);
  EXPECT_EQ(c.status, ExcitationStatus::kOverLimit);
  EXPECT_EQ(c.joint, 0);
  EXPECT_NEAR(c.scale, excitation::scale_of<double>(excitation::kAttempts - 1), 1e-15);
  EXPECT_EQ(c.checks, 4);
}
