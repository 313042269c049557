// The built arm's operational-space state (osc/control/arm_opspace.hpp): the factor of J it takes is
// the one its description calls for, and the control law's operational terms do not depend on which
// factor computes them: on the built arm, the block factor (where it applies) and the pivoted LU give
// the same Lambda a + J^-T tau, p, Psi(x, y) y and Psi(x, y) z, and the same J^-1 x_dot.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <type_traits>

#include "osc/control/arm_opspace.hpp"
#include "osc/robots/puma560.hpp"
#include "osc/robots/ur5e.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

using Lu = PivotedLuJacobianFactor<double>;
using Block = SphericalWristJacobianFactor<double>;

TEST(ArmOpSpace, TheFactorIsTheOneTheArmCallsFor) {
  EXPECT_EQ(kArmSphericalWrist, has_spherical_wrist(robot::kArm));
  EXPECT_EQ((std::is_same_v<ArmJacobianFactor<double>, Block>), has_spherical_wrist(robot::kArm));
  EXPECT_EQ((std::is_same_v<ArmJacobianFactor<float>, PivotedLuJacobianFactor<float>>),
            !has_spherical_wrist(robot::kArm));
  // The description decides it: the UR5e's offset wrist (d5, d6 != 0) has none, the PUMA's has one.
  EXPECT_FALSE(has_spherical_wrist(ur5e::kArm));
  EXPECT_TRUE(has_spherical_wrist(puma560::kArm));
}

/// The operational terms of the built arm with the factor F, at q with reference orientation R_ref.
template <class F>
struct Terms {
  Vec6<double> force, p, psi_yy, psi_yz, qd;
};

template <class F>
Terms<F> terms(const Model<double>& model, const Vec6<double>& q, const Mat3<double>& R_ref, const Vec6<double>& y,
               const Vec6<double>& z, const Vec6<double>& a, const Vec6<double>& tau, double& rcond) {
  Data<double> data;
  OpSpace<double, F> os;
  opspace_update(model, data, os, q, R_ref);
  rcond = os.Jf.rcond;
  Terms<F> t;
  t.force = operational_force(data, os, a, tau);
  t.p = operational_gravity(os);
  const PsiPair<double> pp = psi_pair(model, data, os, y, z);
  t.psi_yy = pp.yy;
  t.psi_yz = pp.yz;
  t.qd = os.Jf.solve(y);
  return t;
}

double rel(const Vec6<double>& a, const Vec6<double>& b) { return (a - b).norm() / std::max(b.norm(), 1e-9); }

TEST(ArmOpSpace, TheControlLawsTermsDoNotDependOnTheFactor) {
  const Model<double> model = Model<double>::of(robot::kArm);
  test::RandomStates rs;
  double worst = 0;
  int n = 0;
  for (int k = 0; k < 300; ++k) {
    const Vec6<double> q = rs.q_nonsingular();
    Data<double> data;
    forward_kinematics(model, data, Vec6<double>(q + rs.vec(0.2)));
    const Mat3<double> R_ref = data.R[kDof];
    const Vec6<double> y = rs.vec(0.5), z = rs.vec(0.5), a = rs.vec(1.0), tau = rs.vec(10.0);
    double rc_arm = 0, rc_lu = 0;
    const auto ta = terms<ArmJacobianFactor<double>>(model, q, R_ref, y, z, a, tau, rc_arm);
    const auto tl = terms<Lu>(model, q, R_ref, y, z, a, tau, rc_lu);
    if (rc_lu < 1e-3) continue;
    ++n;
    worst = std::max({worst, rel(ta.force, tl.force), rel(ta.p, tl.p), rel(ta.psi_yy, tl.psi_yy),
                      rel(ta.psi_yz, tl.psi_yz), rel(ta.qd, tl.qd)});
  }
  std::printf("%d states: the arm's factor against the pivoted LU, relative: %.1e\n", n, worst);
  EXPECT_GT(n, 200);
  EXPECT_LE(worst, 1e-10);
}

// The fixed-point pose x(q) (forward kinematics and the orientation coordinates about a reference orientation
// up to 0.15 rad away) within params::kPoseRoundingLsb of double's at the same quantised q, per coordinate,
// over 1000 random states: the rounding the residual monitor's velocity noise takes (mixed_noise()).
// Measured: the UR5e 2.5-2.9 LSB per coordinate, the PUMA 560 2.3-3.4.
TEST(ArmOpSpace, TheFixedPointPoseIsWithinItsStatedRounding) {
  const Model<double> md = Model<double>::of(robot::kArm);
  const Model<Fixed> mf = Model<Fixed>::of(robot::kArm);
  test::RandomStates rs;
  const double lsb = std::ldexp(1.0, -Fixed::kFractionBits);
  double worst[kDof] = {};
  for (int k = 0; k < 1000; ++k) {
    const Vec6<Fixed> qf = rs.q_nonsingular().cast<Fixed>();
    const Vec6<double> q = qf.cast<double>();
    Data<double> dd;
    Data<Fixed> df;
    ArmOpSpace<double> od;
    ArmOpSpace<Fixed> of;
    forward_kinematics(md, dd, Vec6<double>(q + rs.vec(0.15)));
    const Mat3<double> R_ref = dd.R[kDof].cast<Fixed>().cast<double>();
    opspace_update(md, dd, od, q, R_ref);
    opspace_update(mf, df, of, qf, Mat3<Fixed>(R_ref.cast<Fixed>()));
    for (int a = 0; a < kDof; ++a)
      worst[a] = std::max(worst[a], std::abs(static_cast<double>(of.x(a)) - od.x(a)) / lsb);
  }
  std::printf("%s: the fixed-point pose's rounding, per coordinate [LSB]:", robot::kArm.name);
  for (double w : worst) std::printf(" %.2f", w);
  std::printf(" (stated: %d)\n", params::kPoseRoundingLsb);
  for (int a = 0; a < kDof; ++a) EXPECT_LE(worst[a], params::kPoseRoundingLsb) << "coordinate " << a;
}

}  // namespace
