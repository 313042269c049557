// Each arm's generated table (osc/robots/<arm>.hpp, tools/armgen) against its own URDF read by an
// independent path: urdfdom straight into a KDL chain (kdl_urdf.hpp), URDF frames as they are, no
// placement, no generator code. Over 1 000 random states within the joint limits: the operational
// frame, J, A(q), c(q, qd), g(q) and Jdot qd of the kernels on the table agree with KDL on the URDF.
//
// Error measure (kdl_compare.hpp): relative, floor 1e-3 for c, g, Jdot qd; tolerance rel <= 1e-9.
//
// At the same states, through the general factor of J (PivotedLuJacobianFactor, which any arm can take), the
// operational-space terms satisfy the paper's properties: (6) Lambda symmetric positive definite (m1, m2
// printed), and equal to (J A^-1 J^T)^-1 formed densely by Eigen; (7) Lambda_dot - 2 Psi(x, x_dot) skew-symmetric,
// Lambda_dot by central differences; (8) Psi(x, y) z = Psi(x, z) y; (9) Psi(x, x_dot) linear in x_dot (zeta_c
// printed); and p = J^-T g (J^T p = g, and against Eigen's LU of J).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cstdio>
#include <kdl/chaindynparam.hpp>
#include <cmath>
#include <random>
#include <string>

#include "kdl_compare.hpp"
#include "kdl_urdf.hpp"
#include "osc/kernels/dynamics.hpp"
#include "osc/kernels/opspace.hpp"
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

TEST_P(ArmDescriptions, OperationalSpacePropertiesHold) {
  const ArmCase& arm = GetParam();
  using M6 = Mat6<double>;
  using V6 = Vec6<double>;
  const Model<double> model = Model<double>::of(arm.table);
  Data<double> data;
  OpSpace<double, PivotedLuJacobianFactor<double>> os;
  constexpr double kH = 1e-6, kMinRcond = 1e-3;  // states nearer a singularity are counted, not tested
  auto update = [&](const V6& q, const Mat3<double>& R_ref) { opspace_update(model, data, os, q, R_ref); };
  auto psi_matrix = [&](const V6& y) {  // Psi(x, y), column j = Psi(x, y) e_j
    M6 P;
    for (int j = 0; j < kDof; ++j) P.col(j) = psi_bilinear(model, data, os, y, V6::Unit(j));
    return P;
  };
  std::mt19937_64 rng(55);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int tested = 0, skipped = 0;
  double m1 = 1e300, m2 = 0, zeta = 0;
  double w_sym = 0, w_dense = 0, w7 = 0, w7_ref = 0, w8 = 0, w9 = 0, w_p = 0, w_p_lu = 0;
  for (int k = 0; k < kStates; ++k) {
    V6 q, qd, dq;
    for (int i = 0; i < kDof; ++i) {
      q(i) = arm.table.q_min[i] + (arm.table.q_max[i] - arm.table.q_min[i]) * u(rng);
      qd(i) = 2 * u(rng) - 1;
      dq(i) = 0.4 * u(rng) - 0.2;
    }
    forward_kinematics(model, data, k % 2 == 0 ? q : V6(q + dq));  // phi = 0 at even k, not at odd
    const Mat3<double> R_ref = data.R[kDof];
    update(q, R_ref);
    if (!(os.Jf.rcond >= kMinRcond)) {
      ++skipped;
      continue;
    }
    ++tested;
    const M6 L = operational_inertia(data, os);
    const M6 Ja = os.Ja;
    // (6)
    const M6 L_dense = (Ja * data.A.inverse() * Ja.transpose()).inverse();
    w_dense = std::max(w_dense, (L - L_dense).norm() / L_dense.norm());
    Eigen::SelfAdjointEigenSolver<M6> eig(L);
    m1 = std::min(m1, eig.eigenvalues().minCoeff());
    m2 = std::max(m2, eig.eigenvalues().maxCoeff());
    w_sym = std::max(w_sym, (L - L.transpose()).norm() / L.norm());
    // p = J^-T g
    const V6 p = operational_gravity(os);
    w_p = std::max(w_p, (Ja.transpose() * p - os.g).norm() / std::max(os.g.norm(), 1e-3));
    const V6 p_lu = Ja.transpose().fullPivLu().solve(os.g);
    w_p_lu = std::max(w_p_lu, (p - p_lu).norm() / std::max(p_lu.norm(), 1e-3));
    // (8), (9) at x, with y = x_dot
    const V6 y = Ja * qd, z = Ja * V6(qd.reverse());
    const V6 a = psi_bilinear(model, data, os, y, z), b = psi_bilinear(model, data, os, z, y);
    w8 = std::max(w8, (a - b).norm() / std::max(a.norm(), 1e-9));
    const M6 P = psi_matrix(y), P2 = psi_matrix(V6(2 * y));
    w9 = std::max(w9, (P2 - 2 * P).norm() / P.norm());
    zeta = std::max(zeta, P.cwiseAbs().rowwise().sum().maxCoeff() / y.norm());
    // (7): Lambda_dot along q(t) = q + t qd, R_ref fixed
    update(q + kH * qd, R_ref);
    const M6 Lp = operational_inertia(data, os);
    update(q - kH * qd, R_ref);
    const M6 Lm = operational_inertia(data, os);
    const M6 Ldot = (Lp - Lm) / (2 * kH), N = Ldot - 2 * P;
    const double scale = Ldot.norm() + 2 * P.norm();
    w7 = std::max(w7, (N + N.transpose()).norm() / scale);
    w7_ref = std::max(w7_ref, (P + P.transpose()).norm() / scale);
  }
  std::printf("%s: %d states tested, %d nearer a singularity (rcond < %g)\n", arm.arm, tested, skipped, kMinRcond);
  std::printf("  (6) m1 %.3g, m2 %.3g; Lambda vs dense (J A^-1 J^T)^-1 %.1e; asymmetry %.1e\n", m1, m2, w_dense, w_sym);
  std::printf("  (7) sym(Lambda_dot - 2 Psi) %.1e (Psi alone %.1e); (8) %.1e; (9) linearity %.1e, zeta_c %.3g\n", w7,
              w7_ref, w8, w9, zeta);
  std::printf("  p: J^T p - g %.1e, against Eigen's LU %.1e\n", w_p, w_p_lu);
  EXPECT_GE(tested, kStates / 2);
  EXPECT_GT(m1, 0);
  EXPECT_LT(w_sym, 1e-12);
  EXPECT_LT(w_dense, 1e-8);
  EXPECT_LT(w7, 1e-5);
  EXPECT_GT(w7_ref, 1e-2);  // not vacuous: Psi alone is far from skew
  EXPECT_LT(w8, 1e-10);
  EXPECT_LT(w9, 1e-12);
  EXPECT_TRUE(std::isfinite(zeta));
  EXPECT_LT(w_p, 1e-10);
  EXPECT_LT(w_p_lu, 1e-9);
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
