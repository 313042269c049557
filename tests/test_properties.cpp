// Properties of the kernels on random states: A symmetric positive definite; analytic Jacobian and
// Jdot qd against finite differences; Lambda_dot - 2 Psi skew-symmetric (7); Psi symmetric (8) and
// the Christoffel form (property 2); friction regressor (18)-(19); block factorisation of J;
// float against double. Every kernel call runs with Eigen's malloc check armed.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "osc/friction.hpp"
#include "osc/opspace.hpp"
#include "osc/params.hpp"
#include "test_util.hpp"

using namespace osc;
using test::NoMalloc;

namespace {

constexpr int kStates = 200;

struct Props : ::testing::Test {
  Model<double> model = Model<double>::puma560();
  Data<double> data{};
  OpSpace<double> os{};
  test::RandomStates rs;

  /// x(q) with orientation relative to R_ref.
  Vec6<double> x_of(const Vec6<double>& q, const Mat3<double>& R_ref) {
    NoMalloc guard;
    forward_kinematics(model, data, q);
    return operational_coordinates(data, R_ref);
  }
  void update(const Vec6<double>& q, const Mat3<double>& R_ref) {
    NoMalloc guard;
    opspace_update(model, data, os, q, R_ref);
  }
  Mat3<double> orientation(const Vec6<double>& q) {
    forward_kinematics(model, data, q);
    return data.R[kDof];
  }
};

TEST_F(Props, InertiaIsSymmetricPositiveDefinite) {
  for (int k = 0; k < kStates; ++k) {
    update(rs.q_nonsingular(), Mat3<double>::Identity());
    EXPECT_LT((data.A - data.A.transpose()).norm(), 1e-14);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Mat6<double>>(data.A).eigenvalues().minCoeff(), 0.0);
  }
}

TEST_F(Props, AnalyticJacobianAndJdotMatchFiniteDifferences) {
  const double h = 1e-6;
  double worst_J = 0, worst_Jd = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(1.0);
    // Reference orientation: the state's own, then one 0.3 rad away.
    Vec6<double> q_ref = q;
    if (k % 2) q_ref += rs.vec(0.3);
    const Mat3<double> R_ref = orientation(q_ref);
    update(q, R_ref);
    const Mat6<double> Ja = os.Ja;
    Mat6<double> fd;
    for (int j = 0; j < kDof; ++j) {
      const Vec6<double> e = Vec6<double>::Unit(j) * h;
      fd.col(j) = (x_of(q + e, R_ref) - x_of(q - e, R_ref)) / (2 * h);
    }
    worst_J = std::max(worst_J, (fd - Ja).norm() / Ja.norm());
    // d/dt (Ja(q + t qd)) qd by central differences.
    update(q + h * qd, R_ref);
    const Mat6<double> Jp = os.Ja;
    update(q - h * qd, R_ref);
    const Mat6<double> Jm = os.Ja;
    const Vec6<double> jd_fd = (Jp - Jm) / (2 * h) * qd;
    update(q, R_ref);
    Vec6<double> jd;
    {
      NoMalloc guard;
      jd = analytic_jdot_qd(model, data, os, qd);
    }
    worst_Jd = std::max(worst_Jd, (jd_fd - jd).norm() / (1e-3 + jd.norm()));
  }
  std::printf("analytic Jacobian vs central differences: %.2e; analytic Jdot qd: %.2e\n", worst_J, worst_Jd);
  EXPECT_LT(worst_J, 1e-7);
  EXPECT_LT(worst_Jd, 1e-6);
}

TEST_F(Props, LambdaDotMinusTwoPsiIsSkewSymmetric) {
  // (7): z^T (Lambda_dot - 2 Psi(x, x_dot)) z = 0, i.e. the symmetric part vanishes.
  const double h = 1e-6;
  double worst = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(1.0);
    const Mat3<double> R_ref = orientation(q + rs.vec(0.2));
    update(q + h * qd, R_ref);
    const Mat6<double> Lp = os.Lambda;
    update(q - h * qd, R_ref);
    const Mat6<double> Lm = os.Lambda;
    update(q, R_ref);
    const Mat6<double> Ldot = (Lp - Lm) / (2 * h);
    const Vec6<double> xd = os.Ja * qd;
    Mat6<double> Psi;
    {
      NoMalloc guard;
      for (int j = 0; j < kDof; ++j) Psi.col(j) = psi_bilinear(model, data, os, xd, Vec6<double>::Unit(j));
    }
    const Mat6<double> N = Ldot - 2 * Psi;
    worst = std::max(worst, (N + N.transpose()).norm() / (Ldot.norm() + 2 * Psi.norm()));
  }
  std::printf("||sym(Lambda_dot - 2 Psi)|| / scale: %.2e\n", worst);
  EXPECT_LT(worst, 1e-6);
}

TEST_F(Props, PsiAndChristoffelFormsAreSymmetricBilinear) {
  double worst_psi = 0, worst_B = 0, worst_h = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular();
    update(q, orientation(q + rs.vec(0.2)));
    const Vec6<double> y = rs.vec(0.5), z = rs.vec(0.5), u = rs.vec(1.0), v = rs.vec(1.0);
    NoMalloc guard;
    const Vec6<double> a = psi_bilinear(model, data, os, y, z), b = psi_bilinear(model, data, os, z, y);
    worst_psi = std::max(worst_psi, (a - b).norm() / (1e-9 + a.norm()));  // (8)
    const Vec6<double> c1 = coriolis_bilinear(model, data, u, v), c2 = coriolis_bilinear(model, data, v, u);
    worst_B = std::max(worst_B, (c1 - c2).norm() / (1e-9 + c1.norm()));  // property 2
    // Quadratic and bilinear forms agree, and B(q, qd) qd = c(q, qd).
    const Vec6<double> hq = psi_quadratic(model, data, os, y), hb = psi_bilinear(model, data, os, y, y);
    worst_h = std::max(worst_h, (hq - hb).norm() / (1e-9 + hq.norm()));
    const Vec6<double> cq = velocity_products(model, data, u).c;
    worst_h = std::max(worst_h, (coriolis_matrix(model, data, u) * u - cq).norm() / (1e-9 + cq.norm()));
  }
  EXPECT_LT(worst_psi, 1e-10);
  EXPECT_LT(worst_B, 1e-12);
  EXPECT_LT(worst_h, 1e-10);
}

TEST_F(Props, FrictionRegressorReproducesModel2IncludingZeroVelocity) {
  FrictionParams<double> p;
  for (int i = 0; i < kDof; ++i) {
    p.vis(i) = params::kFrictionPaper.vis[i];
    p.cou(i) = params::kFrictionPaper.cou[i];
    p.sti(i) = params::kFrictionPaper.sti[i];
    p.dec(i) = 0.5 + i;
  }
  for (int k = 0; k < kStates; ++k) {
    Vec6<double> qd = rs.vec(2.0);
    qd(k % kDof) = 0.0;  // sgn(0) = 0: no friction on a joint at rest
    NoMalloc guard;
    const Vec6<double> tau = friction_torque(p, qd);
    const Vec6<double> tw = friction_regressor(qd, p.dec) * p.theta();
    EXPECT_LT((tau - tw).norm(), 1e-12);
    EXPECT_EQ(tau(k % kDof), 0.0);
    // Model (2) written out independently.
    for (int i = 0; i < kDof; ++i) {
      const double s = qd(i) > 0 ? 1 : (qd(i) < 0 ? -1 : 0);
      EXPECT_NEAR(tau(i), p.vis(i) * qd(i) + (p.cou(i) + p.sti(i) * std::exp(-p.dec(i) * qd(i) * qd(i))) * s, 1e-12);
    }
  }
}

TEST_F(Props, BlockFactorisationOfTheJacobian) {
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular();
    update(q, orientation(q));
    EXPECT_LT((data.J.topRightCorner<3, 3>().norm()), 1e-15);  // wrist centre at the frame-6 origin
    const Vec6<double> b = rs.vec(1.0);
    const Eigen::PartialPivLU<Mat6<double>> lu(os.Ja), lut(Mat6<double>(os.Ja.transpose()));
    EXPECT_LT((os.Jf.solve(b) - lu.solve(b)).norm(), 1e-9 * (1 + lu.solve(b).norm()));
    EXPECT_LT((os.Jf.solve_transpose(b) - lut.solve(b)).norm(), 1e-9 * (1 + lut.solve(b).norm()));
    EXPECT_GT(os.Jf.rcond, 0.0);
  }
  JacobianFactor<double> f;
  for (const Vec6<double>& pose : {test::from_array(puma560::kQz), test::from_array(puma560::kQr),
                                   test::from_array(puma560::kQs)}) {
    forward_kinematics(model, data, pose);
    geometric_jacobian(data);
    f.compute(data.J);
    EXPECT_LT(f.rcond, 1e-12);
  }
  forward_kinematics(model, data, test::from_array(puma560::kQn));
  geometric_jacobian(data);
  f.compute(data.J);
  EXPECT_GT(f.rcond, 1e-3);
}

TEST_F(Props, FloatKernelsAgreeWithDouble) {
  // Float has a 6e-8 unit round-off; through the recursions and two 3x3 solves the stated
  // tolerance is 1e-4 relative (2e-4 for Psi, which divides by J twice and differences h).
  const Model<float> mf = Model<float>::puma560();
  Data<float> df;
  OpSpace<float> of;
  double wA = 0, wL = 0, wc = 0, wg = 0, wJ = 0, wP = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(1.0), v = rs.vec(0.2);
    const Mat3<double> R_ref = orientation(q + rs.vec(0.2));
    update(q, R_ref);
    const Vec6<double> c = velocity_products(model, data, qd).c, h = psi_quadratic(model, data, os, v);
    {
      NoMalloc guard;
      opspace_update(mf, df, of, q.cast<float>(), Mat3<float>(R_ref.cast<float>()));
    }
    const Vec6<float> cf = velocity_products(mf, df, qd.cast<float>()).c;
    const Vec6<float> hf = psi_quadratic(mf, df, of, v.cast<float>());
    auto rel = [](const auto& a, const auto& b) { return (a.template cast<double>() - b).norm() / (1e-6 + b.norm()); };
    wA = std::max(wA, rel(df.A, data.A));
    wL = std::max(wL, rel(of.Lambda, os.Lambda));
    wJ = std::max(wJ, rel(of.Ja, os.Ja));
    wg = std::max(wg, rel(of.g, os.g));
    wc = std::max(wc, rel(cf, c));
    wP = std::max(wP, rel(hf, h));
  }
  std::printf("float vs double, max relative: A %.1e, Lambda %.1e, Ja %.1e, g %.1e, c %.1e, Psi %.1e\n", wA, wL,
              wJ, wg, wc, wP);
  EXPECT_LT(wA, 1e-4);
  EXPECT_LT(wL, 1e-4);
  EXPECT_LT(wJ, 1e-4);
  EXPECT_LT(wg, 1e-4);
  EXPECT_LT(wc, 1e-4);
  EXPECT_LT(wP, 2e-4);
}

}  // namespace
