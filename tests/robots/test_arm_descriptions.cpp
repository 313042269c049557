// Each arm's generated table (osc/robots/<arm>.hpp, tools/armgen) against its own URDF read by an
// independent path: urdfdom straight into a KDL chain (kdl_urdf.hpp), URDF frames as they are, no
// placement, no generator code. Over 1 000 random states within the joint limits: the operational
// frame, J, A(q), c(q, qd), g(q) and Jdot qd of the kernels on the table agree with KDL on the URDF.
//
// Error measure (kdl_compare.hpp): relative, floor 1e-3 for c, g, Jdot qd; tolerance rel <= 1e-9.
#include <gtest/gtest.h>

#include <kdl/chaindynparam.hpp>
#include <random>
#include <string>

#include "kdl_compare.hpp"
#include "kdl_urdf.hpp"
#include "osc/kernels/dynamics.hpp"
#include "osc/robots/puma560.hpp"
#include "osc/robots/ur5e.hpp"

using namespace osc;

namespace {

constexpr int kStates = 1000;
constexpr double kTol = 1e-9;
constexpr double kFloor = 1e-3;

struct ArmCase {
  const char* arm;  // the folder under firmware/robots
  const ArmDescription& table;
  const char* tip;  // the URDF link of the operational point (the sheet's operational_point)
};

class ArmDescriptions : public ::testing::TestWithParam<ArmCase> {};

TEST_P(ArmDescriptions, GeneratedTableAgreesWithKdlOnTheUrdf) {
  const ArmCase& arm = GetParam();
  const std::string urdf = std::string(OSC_SOURCE_DIR) + "/firmware/robots/" + arm.arm + "/" + arm.arm + ".urdf";
  const KDL::Chain chain = test::kdl_chain_from_urdf(urdf, arm.tip);
  ASSERT_EQ(chain.getNrOfJoints(), static_cast<unsigned>(kDof));
  // Our operational frame (frame 6) is KDL's at the chain's last segment, the operational point's link.
  test::KdlComparison cmp(chain, arm.table.gravity, kDof, static_cast<int>(chain.getNrOfSegments()) - kDof, false,
                          kFloor, std::string(arm.arm) + ": ");
  const Model<double> model = Model<double>::of(arm.table);
  Data<double> data;
  std::mt19937_64 rng(55);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < kStates; ++k) {
    Vec6<double> q, qd;
    for (int i = 0; i < kDof; ++i) {
      q(i) = arm.table.q_min[i] + (arm.table.q_max[i] - arm.table.q_min[i]) * u(rng);
      qd(i) = 4 * u(rng) - 2;
    }
    cmp.add(model, data, q, qd);
  }
  cmp.expect_within(kTol);
}

// A check that could fail: the reader and the comparison see a wrong table. The UR5e's table with
// one product of inertia changed by 1 % of its link's largest moment no longer agrees.
TEST(ArmDescriptionsCheck, AChangedProductOfInertiaIsSeen) {
  ArmDescription changed = ur5e::kArm;
  changed.links[2].inertia[4] += 0.01 * changed.links[2].inertia[1];
  const std::string urdf = std::string(OSC_SOURCE_DIR) + "/firmware/robots/ur5e/ur5e.urdf";
  const KDL::Chain chain = test::kdl_chain_from_urdf(urdf, "tool0");
  KDL::ChainDynParam dyn(chain, KDL::Vector(0, 0, -changed.gravity));
  const Model<double> model = Model<double>::of(changed);
  Data<double> data;
  const Vec6<double> q(0.3, -1.1, 1.4, -0.7, 0.9, 0.2);  // a generic pose (at the start pose this term is unseen)
  KDL::JntArray kq(kDof);
  for (int i = 0; i < kDof; ++i) kq(i) = q(i);
  forward_kinematics(model, data, q);
  joint_inertia(model, data);
  KDL::JntSpaceInertiaMatrix H(kDof);
  ASSERT_GE(dyn.JntToMass(kq, H), 0);
  const Mat6<double> A_ref = H.data + Mat6<double>(model.armature.asDiagonal());
  EXPECT_GT((A_ref - data.A).norm() / A_ref.norm(), 1e-5);
}

INSTANTIATE_TEST_SUITE_P(Arms, ArmDescriptions,
                         ::testing::Values(ArmCase{"puma560", puma560::kArm, "link6"},
                                           ArmCase{"ur5e", ur5e::kArm, "tool0"}),
                         [](const ::testing::TestParamInfo<ArmCase>& p) { return std::string(p.param.arm); });

}  // namespace
