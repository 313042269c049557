// The operational-space dynamics (osc/kernels/opspace.hpp) on random non-singular states
// (props_fixture.hpp): (7) Lambda_dot - 2 Psi(x, x_dot) skew-symmetric; (8) Psi(x, y) z = Psi(x, z) y,
// property 2 B(q, y) z = B(q, z) y and h(v) = Psi(x, v) v; the block factorisation of J against a dense
// 6x6 LU, rcond at the named poses; the L D L^T factor of A against an LU.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cstdio>

#include "osc/kernels/opspace.hpp"
#include "props_fixture.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST_F(Props, LambdaDotMinusTwoPsiIsSkewSymmetric) {
  // (7): z^T (Lambda_dot - 2 Psi(x, x_dot)) z = 0 for all z, i.e. the symmetric part vanishes.
  // Lambda_dot by central differences along q(t) = q + t qd with R_ref fixed; x_dot = Ja qd;
  // Psi(x, x_dot) column k = psi_bilinear(x_dot, e_k).
  double worst = 0, worst_ref = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(1.0);
    const Mat3<double> R_ref = reference_for(k, q);
    update(q + kH * qd, R_ref);
    const Mat6<double> Lp = operational_inertia(data, os);
    update(q - kH * qd, R_ref);
    const Mat6<double> Lm = operational_inertia(data, os);
    update(q, R_ref);
    const Mat6<double> Ldot = (Lp - Lm) / (2 * kH);
    const Vec6<double> xd = os.Ja * qd;
    Mat6<double> Psi;
    {
      NoMalloc guard;
      for (int j = 0; j < kDof; ++j) Psi.col(j) = psi_bilinear(model, data, os, xd, Vec6<double>::Unit(j));
    }
    const Mat6<double> N = Ldot - 2 * Psi;
    const double scale = Ldot.norm() + 2 * Psi.norm();
    worst = std::max(worst, (N + N.transpose()).norm() / scale);
    // The check is not vacuous: Psi itself is far from skew (its symmetric part is O(Lambda_dot)).
    worst_ref = std::max(worst_ref, (Psi + Psi.transpose()).norm() / scale);
  }
  std::printf("||sym(Lambda_dot - 2 Psi)|| / (||Lambda_dot|| + 2||Psi||): %.2e (same for Psi alone: %.2e)\n", worst,
              worst_ref);
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(worst_ref, 1e-2);
}

TEST_F(Props, PsiAndChristoffelFormsAreSymmetricBilinear) {
  double worst_psi = 0, worst_B = 0, worst_h = 0, worst_c = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular();
    const Mat3<double> R_ref = reference_for(k, q);
    update(q, R_ref);
    const Vec6<double> y = rs.vec(0.5), z = rs.vec(0.5), u = rs.vec(1.0), v = rs.vec(1.0);
    NoMalloc guard;
    // (8)
    const Vec6<double> a = psi_bilinear(model, data, os, y, z), b = psi_bilinear(model, data, os, z, y);
    worst_psi = std::max(worst_psi, (a - b).norm() / std::max(a.norm(), 1e-9));
    // Property 2
    const Vec6<double> c1 = coriolis_bilinear(model, data, u, v), c2 = coriolis_bilinear(model, data, v, u);
    worst_B = std::max(worst_B, (c1 - c2).norm() / std::max(c1.norm(), 1e-9));
    // Quadratic and bilinear forms agree: psi_quadratic(v) = psi_bilinear(v, v).
    const Vec6<double> hq = psi_quadratic(model, data, os, y), hb = psi_bilinear(model, data, os, y, y);
    worst_h = std::max(worst_h, (hq - hb).norm() / std::max(hq.norm(), 1e-9));
    // B(q, qd) qd = c(q, qd) (Christoffel matrix against the RNEA velocity products).
    const Vec6<double> cq = velocity_products(model, data, u).c;
    worst_c = std::max(worst_c, (coriolis_matrix(model, data, u) * u - cq).norm() / std::max(cq.norm(), 1e-9));
  }
  std::printf("relative: (8) %.1e, property 2 %.1e, psi_quadratic vs psi_bilinear %.1e, B qd vs c %.1e\n", worst_psi,
              worst_B, worst_h, worst_c);
  EXPECT_LT(worst_psi, 1e-10);
  EXPECT_LT(worst_B, 1e-12);
  EXPECT_LT(worst_h, 1e-12);
  EXPECT_LT(worst_c, 1e-12);
}

TEST_F(Props, BlockFactorisationOfTheJacobian) {
  double worst_s = 0, worst_t = 0, worst_block = 0, min_rcond = 1e300;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular();
    update(q, reference_for(k, q));
    // The wrist axes meet at the frame-6 origin: zero upper-right block (geometric and analytic J).
    worst_block = std::max({worst_block, data.J.topRightCorner<3, 3>().norm(), os.Ja.topRightCorner<3, 3>().norm()});
    const Vec6<double> b = rs.vec(1.0);
    Vec6<double> xs, xt;
    {
      NoMalloc guard;
      xs = os.Jf.solve(b);
      xt = os.Jf.solve_transpose(b);
    }
    const Vec6<double> rs_ = Eigen::PartialPivLU<Mat6<double>>(os.Ja).solve(b);
    const Vec6<double> rt = Eigen::PartialPivLU<Mat6<double>>(Mat6<double>(os.Ja.transpose())).solve(b);
    worst_s = std::max(worst_s, (xs - rs_).norm() / rs_.norm());
    worst_t = std::max(worst_t, (xt - rt).norm() / rt.norm());
    min_rcond = std::min(min_rcond, static_cast<double>(os.Jf.rcond));
  }
  std::printf(
      "J factor vs dense 6x6 LU, relative: solve %.1e, solve_transpose %.1e; |J12| max %.1e; "
      "min rcond on random states %.1e\n",
      worst_s, worst_t, worst_block, min_rcond);
  EXPECT_LT(worst_block, 1e-15);
  EXPECT_LT(worst_s, 1e-10);
  EXPECT_LT(worst_t, 1e-10);
  EXPECT_GT(min_rcond, 0.0);

  // Named poses: qz, qr and qs are wrist-singular (q5 = 0); qn is well conditioned.
  SphericalWristJacobianFactor<double> f;
  auto rcond_at = [&](const double(&pose)[kDof]) {
    NoMalloc guard;
    forward_kinematics(model, data, test::from_array(pose));
    geometric_jacobian(data);
    f.compute(data.J);
    return static_cast<double>(f.rcond);
  };
  const double rz = rcond_at(puma560::kQz), rr = rcond_at(puma560::kQr), rsg = rcond_at(puma560::kQs),
               rn = rcond_at(puma560::kQn);
  std::printf("rcond: qz %.1e, qr %.1e, qs %.1e, qn %.3f\n", rz, rr, rsg, rn);
  EXPECT_LT(rz, 1e-12);
  EXPECT_LT(rr, 1e-12);
  EXPECT_LT(rsg, 1e-12);
  EXPECT_GT(rn, 1e-3);
}

TEST_F(Props, LdltFactorSolvesLikeAnLuOfA) {
  // A = L D L^T of the joint-space inertia (the factor the observer's Lambda^{-1} w uses), against
  // Eigen's partial-pivoting LU of the same A, at random states: solves agree to round-off and the
  // factors rebuild A.
  double worst_solve = 0, worst_rebuild = 0;
  for (int k = 0; k < kStates; ++k) {
    update(rs.q_nonsingular(), Mat3<double>::Identity());
    ASSERT_TRUE(os.A_ldlt.positive);
    const Vec6<double> b = rs.vec(10.0);
    Vec6<double> x;
    {
      NoMalloc guard;
      x = os.A_ldlt.solve(b);
    }
    const Vec6<double> x_lu = data.A.partialPivLu().solve(b);
    worst_solve = std::max(worst_solve, (x - x_lu).norm() / x_lu.norm());
    Mat6<double> L = Mat6<double>::Identity();
    L.triangularView<Eigen::StrictlyLower>() = os.A_ldlt.L;
    const Mat6<double> rebuilt = L * os.A_ldlt.d.asDiagonal() * L.transpose();
    worst_rebuild = std::max(worst_rebuild, (rebuilt - data.A).norm() / data.A.norm());
    EXPECT_NEAR((os.A_ldlt.d.cwiseProduct(os.A_ldlt.d_inv) - Vec6<double>::Ones()).cwiseAbs().maxCoeff(), 0.0, 1e-15);
  }
  std::printf("L D L^T of A: worst relative solve difference to LU %.1e, rebuild %.1e\n", worst_solve, worst_rebuild);
  EXPECT_LT(worst_solve, 1e-12);
  EXPECT_LT(worst_rebuild, 1e-14);
  // A matrix that is not positive definite is reported.
  LdltFactor<double, 6> f;
  Mat6<double> M = data.A;
  M(3, 3) = -1.0;
  f.compute(M);
  EXPECT_FALSE(f.positive);
}

}  // namespace
