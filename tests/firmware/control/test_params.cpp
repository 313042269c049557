// The parameters (osc/control/params.hpp) whose values are derived, not fitted: each recomputed from
// its derivation in the header's comment.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "osc/control/params.hpp"
#include "osc/kernels/dynamics.hpp"
#include "osc/robot.hpp"

using namespace osc;

namespace {

/// The band of each joint is its derivation (params.hpp): 6 codes of its pot, twice the elastic
/// deflection at full-scale torque for a 15 Hz locked-motor resonance at the start pose on J1-J3, and
/// 1 mrad of backlash, rounded up to 0.1 mrad.
TEST(PositionCrossCheck, TheBandIsItsDerivation) {
  const auto model = Model<double>::of(robot::kArm);
  auto data = std::make_unique<Data<double>>();
  forward_kinematics(model, *data, joint_vector<double>(robot::kQStart));
  joint_inertia(model, *data);
  const auto& d = robot::kDriveTrain;
  for (int i = 0; i < kDof; ++i) {
    const double code = (d.pot_max[i] - d.pot_min[i]) / ((1 << d.pot_bits) - 1);
    const double k = std::pow(2 * kPi * params::kPositionElasticHz, 2) * data->A(i, i);
    const double elastic = i < 3 ? 2 * robot::kDrives.torque_limit[i] / k : 0;
    const double band = params::kPositionBandCodes * code + elastic + params::kPositionBacklash;
    EXPECT_GE(params::kPositionBand[i], band) << "joint " << i + 1;
    EXPECT_LT(params::kPositionBand[i], band + 1e-4) << "joint " << i + 1;
  }
}

}  // namespace
