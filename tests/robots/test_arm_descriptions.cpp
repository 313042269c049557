// Each arm's generated table (osc/robots/<arm>.hpp, tools/armgen) against its own URDF read by an
// independent path: urdfdom straight into a KDL chain (kdl_urdf.hpp), URDF frames as they are, no
// placement, no generator code. Over 1 000 random states within the joint limits: the operational
// frame, J, A(q), c(q, qd), g(q) and Jdot qd of the kernels on the table agree with KDL on the URDF.
//
// Error measure, per state and quantity (as test_kdl.cpp): rel = ||ours - KDL|| / max(||KDL||, floor),
// Frobenius / Euclidean norms, SI units. Floors: none for the frame [R p] and J (their norms are >=
// sqrt 3), none for A (>= the armature); 1e-3 for c, g, Jdot qd (N m, m/s^2: a state where the
// reference nearly vanishes is measured absolutely). Tolerance: rel <= 1e-9.
#include <gtest/gtest.h>

#include <cstdio>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacdotsolver.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <random>
#include <string>

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

struct Worst {
  std::string name;
  double value = 0;
  void add(double err, double ref_norm, double floor) { value = std::max(value, err / std::max(ref_norm, floor)); }
};

class ArmDescriptions : public ::testing::TestWithParam<ArmCase> {};

TEST_P(ArmDescriptions, GeneratedTableAgreesWithKdlOnTheUrdf) {
  const ArmCase& arm = GetParam();
  const std::string urdf = std::string(OSC_SOURCE_DIR) + "/firmware/robots/" + arm.arm + "/" + arm.arm + ".urdf";
  const KDL::Chain chain = test::kdl_chain_from_urdf(urdf, arm.tip);
  ASSERT_EQ(chain.getNrOfJoints(), static_cast<unsigned>(kDof));
  const KDL::Vector gravity(0, 0, -arm.table.gravity);
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainJntToJacSolver jac(chain);
  KDL::ChainDynParam dyn(chain, gravity);
  KDL::ChainJntToJacDotSolver jacdot(chain);
  jacdot.setRepresentation(KDL::ChainJntToJacDotSolver::HYBRID);  // frame-6 origin, base axes

  const Model<double> model = Model<double>::of(arm.table);
  Data<double> data;
  std::mt19937_64 rng(55);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Worst w_fk{"operational frame [R p]"}, w_jac{"geometric Jacobian"}, w_A{"A(q) with armature"}, w_c{"c(q, qd)"},
      w_g{"g(q)"}, w_jd{"Jdot qd"};
  KDL::Jacobian J(kDof);
  KDL::JntSpaceInertiaMatrix H(kDof);
  KDL::JntArray kq(kDof), kqd(kDof), C(kDof), G(kDof);
  for (int k = 0; k < kStates; ++k) {
    Vec6<double> q, qd;
    for (int i = 0; i < kDof; ++i) {
      q(i) = arm.table.q_min[i] + (arm.table.q_max[i] - arm.table.q_min[i]) * u(rng);
      qd(i) = 4 * u(rng) - 2;
      kq(i) = q(i), kqd(i) = qd(i);
    }
    forward_kinematics(model, data, q);
    geometric_jacobian(data);
    joint_inertia(model, data);
    const VelocityProducts<double> vp = velocity_products(model, data, qd);
    const Vec6<double> g = gravity_torques(model, data);

    KDL::Frame F;
    ASSERT_GE(fk.JntToCart(kq, F), 0);
    Eigen::Matrix<double, 3, 4> ours, ref;
    ours << data.R[kDof], data.o[kDof];
    for (int r = 0; r < 3; ++r) {
      for (int s = 0; s < 3; ++s) ref(r, s) = F.M(r, s);
      ref(r, 3) = F.p(r);
    }
    w_fk.add((ours - ref).norm(), ref.norm(), 0.0);
    ASSERT_GE(jac.JntToJac(kq, J), 0);
    w_jac.add((J.data - data.J).norm(), J.data.norm(), 0.0);
    ASSERT_GE(dyn.JntToMass(kq, H), 0);
    ASSERT_GE(dyn.JntToCoriolis(kq, kqd, C), 0);
    ASSERT_GE(dyn.JntToGravity(kq, G), 0);
    // A URDF has no motors: the table's armature G^2 Jm is added to KDL's link inertia.
    const Mat6<double> A_ref = H.data + Mat6<double>(model.armature.asDiagonal());
    w_A.add((A_ref - data.A).norm(), A_ref.norm(), 0.0);
    w_c.add((C.data - vp.c).norm(), C.data.norm(), kFloor);
    w_g.add((G.data - g).norm(), G.data.norm(), kFloor);
    KDL::Twist t;
    ASSERT_GE(jacdot.JntToJacDot(KDL::JntArrayVel(kq, kqd), t), 0);
    Vec6<double> jd;
    jd << t.vel.x(), t.vel.y(), t.vel.z(), t.rot.x(), t.rot.y(), t.rot.z();
    w_jd.add((jd - vp.jdot_qd).norm(), jd.norm(), kFloor);
  }
  for (const Worst* w : {&w_fk, &w_jac, &w_A, &w_c, &w_g, &w_jd}) {
    std::printf("%s: max relative error vs KDL from the URDF, %-26s %.2e\n", arm.arm, w->name.c_str(), w->value);
    EXPECT_LE(w->value, kTol) << arm.arm << ": " << w->name;
  }
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
  const Vec6<double> q = joint_vector<double>(ur5e::kQStart);
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
                         [](const ::testing::TestParamInfo<ArmCase>& info) { return std::string(info.param.arm); });

}  // namespace
