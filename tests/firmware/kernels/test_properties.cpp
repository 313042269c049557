// Properties of the kernels on random non-singular states (deterministic seed):
//   A(q) symmetric positive definite;
//   analytic Jacobian and analytic Jdot qd against central finite differences of x(q) and Ja(q);
//   (7)  Lambda_dot - 2 Psi(x, x_dot) skew-symmetric;
//   (8)  Psi(x, y) z = Psi(x, z) y;  property 2: B(q, y) z = B(q, z) y;  h(v) = Psi(x, v) v;
//   (18)-(19) W_j(qd) theta = friction torque (2), including joints at rest (sgn 0 = 0);
//   block factorisation of J against a dense 6x6 LU; rcond at the named poses;
//   float kernels against double.
// Every kernel call runs with Eigen's malloc check armed (test::NoMalloc). Guards are never nested:
// the inner guard's destructor would re-enable allocation.
//
// Finite differences: central, step h = 1e-6 (rad, or s along q(t) = q + t qd with |qd_i| <= 1).
// Truncation error ~ h^2 |f'''| ~ 1e-12 and round-off ~ eps |f| / h ~ 1e-10 relative, amplified
// by the conditioning of Lambda (two solves with Ja); the tolerances below leave >= 10x margin
// over the worst value seen (printed).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cstdio>
#include <limits>
#include <random>

#include "osc/kernels/friction.hpp"
#include "osc/kernels/opspace.hpp"
#include "osc/control/params.hpp"
#include "test_util.hpp"

using namespace osc;
using test::NoMalloc;

namespace {

constexpr int kStates = 300;
constexpr double kH = 1e-6;

struct Props : ::testing::Test {
  Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data{};
  OpSpace<double> os{};
  test::RandomStates rs;

  /// x(q) = [p; phi] with orientation relative to R_ref.
  Vec6<double> x_of(const Vec6<double>& q, const Mat3<double>& R_ref) {
    NoMalloc guard;
    forward_kinematics(model, data, q);
    return operational_coordinates(data, R_ref);
  }
  /// opspace_update at q: fills data (frames, J, A) and os (x, Ja, Jf, A_ldlt, Lambda, g).
  void update(const Vec6<double>& q, const Mat3<double>& R_ref) {
    NoMalloc guard;
    opspace_update(model, data, os, q, R_ref);
  }
  /// End-effector orientation R_6(q).
  Mat3<double> orientation(const Vec6<double>& q) {
    NoMalloc guard;
    forward_kinematics(model, data, q);
    return data.R[kDof];
  }
  /// Reference orientation for state k: even k its own orientation (phi = 0 at q), odd k the
  /// orientation at a nearby perturbed configuration (|dq_i| <= 0.2 rad, phi != 0).
  Mat3<double> reference_for(int k, const Vec6<double>& q) {
    return orientation(k % 2 == 0 ? q : Vec6<double>(q + rs.vec(0.2)));
  }
};

TEST_F(Props, InertiaIsSymmetricPositiveDefinite) {
  double worst_sym = 0, min_eig = 1e300;
  for (int k = 0; k < kStates; ++k) {
    update(rs.q_nonsingular(), Mat3<double>::Identity());
    worst_sym = std::max(worst_sym, (data.A - data.A.transpose()).norm() / data.A.norm());
    min_eig = std::min(min_eig, Eigen::SelfAdjointEigenSolver<Mat6<double>>(data.A).eigenvalues().minCoeff());
    EXPECT_TRUE(os.A_ldlt.positive);
  }
  std::printf("A: max ||A - A^T|| / ||A|| %.1e, min eigenvalue %.3f kg m^2\n", worst_sym, min_eig);
  EXPECT_LT(worst_sym, 1e-15);
  EXPECT_GT(min_eig, 0.0);
}

TEST_F(Props, AnalyticJacobianAndJdotMatchFiniteDifferences) {
  double worst_J = 0, worst_Jd = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(1.0);
    const Mat3<double> R_ref = reference_for(k, q);
    update(q, R_ref);
    const Mat6<double> Ja = os.Ja;
    // dx/dq by central differences of operational_coordinates.
    Mat6<double> fd;
    for (int j = 0; j < kDof; ++j) {
      const Vec6<double> e = Vec6<double>::Unit(j) * kH;
      fd.col(j) = (x_of(q + e, R_ref) - x_of(q - e, R_ref)) / (2 * kH);
    }
    worst_J = std::max(worst_J, (fd - Ja).norm() / Ja.norm());
    // d/dt (Ja(q + t qd)) qd at t = 0, R_ref fixed.
    update(q + kH * qd, R_ref);
    const Mat6<double> Jp = os.Ja;
    update(q - kH * qd, R_ref);
    const Mat6<double> Jm = os.Ja;
    const Vec6<double> jd_fd = (Jp - Jm) / (2 * kH) * qd;
    update(q, R_ref);
    Vec6<double> jd;
    {
      NoMalloc guard;
      jd = analytic_jdot_qd(model, data, os, qd);
    }
    worst_Jd = std::max(worst_Jd, (jd_fd - jd).norm() / std::max(jd.norm(), 1e-3));
  }
  std::printf("analytic Jacobian vs central differences: %.2e; analytic Jdot qd: %.2e (relative)\n", worst_J, worst_Jd);
  EXPECT_LT(worst_J, 1e-7);
  EXPECT_LT(worst_Jd, 1e-6);
}

// E(phi) (phi_rate_to_angular) against the angular velocity of R(phi(t)) = Rz Ry Rx by central
// differences, w^ = R_dot R^T; and E^{-1} (angular_to_phi_rate) its inverse.
TEST(OrientationRates, EMapsRollPitchYawRatesToTheAngularVelocity) {
  const auto R = [](const Vec3<double>& p) {
    return Mat3<double>(Eigen::AngleAxisd(p(2), Vec3<double>::UnitZ()) *
                        Eigen::AngleAxisd(p(1), Vec3<double>::UnitY()) *
                        Eigen::AngleAxisd(p(0), Vec3<double>::UnitX()));
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.4, 1.4);
  for (int k = 0; k < 50; ++k) {
    const Vec3<double> phi(u(rng), u(rng), u(rng)), rate(u(rng), u(rng), u(rng));
    const double h = 1e-6;
    const Mat3<double> W = (R(phi + h * rate) - R(phi - h * rate)) / (2 * h) * R(phi).transpose();
    const Vec3<double> w(W(2, 1), W(0, 2), W(1, 0));
    EXPECT_LE((phi_rate_to_angular<double>(phi) * rate - w).norm(), 1e-8) << k;
    EXPECT_LE((angular_to_phi_rate<double>(phi) * phi_rate_to_angular<double>(phi) - Mat3<double>::Identity()).norm(),
              1e-12)
        << k;
  }
}

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

TEST_F(Props, FrictionRegressorReproducesModel2IncludingZeroVelocity) {
  FrictionParams<double> p;
  for (int i = 0; i < kDof; ++i) {
    p.vis(i) = robot::kFrictionPaper.vis[i];
    p.cou(i) = robot::kFrictionPaper.cou[i];
    p.sti(i) = robot::kFrictionPaper.sti[i];
    p.dec(i) = 0.5 + i;
  }
  const Vec18<double> theta = p.theta();
  for (int k = 0; k < kStates; ++k) {
    Vec6<double> qd = rs.vec(2.0);
    const int rest = k % kDof;
    qd(rest) = 0.0;                                // sgn(0) = 0: no friction on a joint at rest
    if (k % 3 == 0) qd((rest + 3) % kDof) = -0.0;  // negative zero too
    Vec6<double> tau, tw;
    Regressor<double> W;
    {
      NoMalloc guard;
      tau = friction_torque(p, qd);
      W = friction_regressor(qd, p.dec);
      tw = W * theta;
    }
    EXPECT_LT((tau - tw).norm(), 1e-12 * std::max(tau.norm(), 1.0));
    // Model (2) written out independently.
    for (int i = 0; i < kDof; ++i) {
      const double s = qd(i) > 0 ? 1 : (qd(i) < 0 ? -1 : 0);
      EXPECT_NEAR(tau(i), p.vis(i) * qd(i) + (p.cou(i) + p.sti(i) * std::exp(-p.dec(i) * qd(i) * qd(i))) * s, 1e-12);
      if (qd(i) == 0.0) {
        EXPECT_EQ(tau(i), 0.0);
        EXPECT_EQ(tw(i), 0.0);
        EXPECT_EQ(W.row(i).cwiseAbs().maxCoeff(), 0.0);
      }
    }
  }
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

TEST_F(Props, FloatKernelsAgreeWithDouble) {
  // Tolerance, relative (Frobenius / Euclidean): 1e-4 for A, J, Ja, g, c, tau_f, Lambda; 2e-4 for
  // Psi. Justification: float round-off is u = 6e-8. A, J, g, c come from short recursions (~6
  // levels of 3x3 products and cross products, sums of same-size terms): a few hundred u at most,
  // ~3e-5, before counting the rounding of q itself (u |q| |dF/dq| / |F| ~ a few u). Lambda =
  // J^-T A J^-1 and Psi (two solves with Ja and a difference of h(y+z), h(y-z)) multiply that by
  // the condition number of the 3x3 blocks, which q_nonsingular bounds (|sin q5|, |cos(q3+0.047)|
  // >= 0.2): observed worst (printed) is 10-100x below these bounds.
  const Model<float> mf = Model<float>::of(robot::kArm);
  Data<float> df;
  OpSpace<float> of;
  FrictionParams<double> pd;
  for (int i = 0; i < kDof; ++i) {
    pd.vis(i) = robot::kFrictionPaper.vis[i];
    pd.cou(i) = robot::kFrictionPaper.cou[i];
    pd.sti(i) = robot::kFrictionPaper.sti[i];
    pd.dec(i) = params::kTauDec;
  }
  const FrictionParams<float> pf{pd.vis.cast<float>(), pd.cou.cast<float>(), pd.sti.cast<float>(),
                                 pd.dec.cast<float>()};
  auto rel = [](const auto& f, const auto& d) {
    return (f.template cast<double>() - d).norm() / std::max(d.norm(), 1e-6);
  };
  double wA = 0, wL = 0, wc = 0, wg = 0, wJ = 0, wJa = 0, wP = 0, wF = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(1.0), v = rs.vec(0.2);
    const Mat3<double> R_ref = reference_for(k, q);
    const Vec6<float> qf = q.cast<float>(), qdf = qd.cast<float>(), vf = v.cast<float>();
    const Mat3<float> R_ref_f = R_ref.cast<float>();
    Vec6<double> c, h, tf;
    Vec6<float> cf, hf, tff;
    update(q, R_ref);
    {
      NoMalloc guard;
      c = velocity_products(model, data, qd).c;
      h = psi_quadratic(model, data, os, v);
      tf = friction_torque(pd, qd);
      opspace_update(mf, df, of, qf, R_ref_f);
      cf = velocity_products(mf, df, qdf).c;
      hf = psi_quadratic(mf, df, of, vf);
      tff = friction_torque(pf, qdf);
    }
    wA = std::max(wA, rel(df.A, data.A));
    wJ = std::max(wJ, rel(df.J, data.J));
    wJa = std::max(wJa, rel(of.Ja, os.Ja));
    wL = std::max(wL, rel(operational_inertia(df, of), operational_inertia(data, os)));
    wg = std::max(wg, rel(of.g, os.g));
    wc = std::max(wc, rel(cf, c));
    wP = std::max(wP, rel(hf, h));
    wF = std::max(wF, rel(tff, tf));
  }
  std::printf(
      "float vs double, max relative: A %.1e, J %.1e, Ja %.1e, Lambda %.1e, g %.1e, c %.1e, Psi %.1e, "
      "tau_f %.1e\n",
      wA, wJ, wJa, wL, wg, wc, wP, wF);
  EXPECT_LT(wA, 1e-4);
  EXPECT_LT(wJ, 1e-4);
  EXPECT_LT(wJa, 1e-4);
  EXPECT_LT(wL, 1e-4);
  EXPECT_LT(wg, 1e-4);
  EXPECT_LT(wc, 1e-4);
  EXPECT_LT(wF, 1e-4);
  EXPECT_LT(wP, 2e-4);
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

TEST(FloatFunctions, SinCosAndExpWithinTheirStatedErrors) {
  // math::sincos / sin / cos / exp for float (scalar.hpp, detail::sincos_float and exp_float)
  // against double at every argument of a dense grid over their stated ranges.
  double ws = 0, wc = 0, we = 0, ws_at = 0, we_at = 0;
  for (int i = -2000000; i <= 2000000; ++i) {
    const float v = static_cast<float>(i * 0.0032);  // |v| <= 6400
    float s, c;
    math::sincos(v, s, c);
    const double es = std::abs(s - std::sin(static_cast<double>(v)));
    const double ec = std::abs(c - std::cos(static_cast<double>(v)));
    if (es > ws) ws = es, ws_at = v;
    wc = std::max(wc, ec);
    EXPECT_EQ(math::sin(v), s);
    EXPECT_EQ(math::cos(v), c);
  }
  for (int i = -873000; i <= 885000; ++i) {
    const float v = static_cast<float>(i * 1e-4);  // e^v a normal float
    const double exact = std::exp(static_cast<double>(v));
    const double e = std::abs(math::exp(v) - exact) / exact;
    if (e > we) we = e, we_at = v;
  }
  std::printf(
      "float sin: worst |error| %.2e at %.4f, cos %.2e (stated 6e-8); exp: worst relative %.2e at %.4f "
      "(stated 2.4e-7)\n",
      ws, ws_at, wc, we, we_at);
  EXPECT_LE(ws, 6e-8);
  EXPECT_LE(wc, 6e-8);
  EXPECT_LE(we, 2.4e-7);
  EXPECT_EQ(math::exp(-100.0f), 0.0f);
  EXPECT_EQ(math::exp(100.0f), HUGE_VALF);
  EXPECT_TRUE(std::isnan(math::exp(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_EQ(math::exp(0.0f), 1.0f);
}

TEST(FloatFunctions, Atan2AndAsinWithinTheirStatedErrors) {
  // math::atan2 / asin for float (scalar.hpp, detail::atan2_float) against double: every direction
  // of a dense fan in all four quadrants, at radii from 1e-30 to 1e30, and asin over [-1, 1].
  double wa = 0, wa_at = 0, ws = 0;
  for (int i = 0; i < 400000; ++i) {
    const double angle = -3.14159265358979 + i * (2 * 3.14159265358979 / 400000);
    const double radius = std::pow(10.0, (i % 61) - 30);
    const float y = static_cast<float>(radius * std::sin(angle)), x = static_cast<float>(radius * std::cos(angle));
    const double e = std::abs(math::atan2(y, x) - std::atan2(static_cast<double>(y), static_cast<double>(x)));
    if (e > wa) wa = e, wa_at = angle;
  }
  for (int i = -1000000; i <= 1000000; ++i) {
    const float v = static_cast<float>(i * 1e-6);
    ws = std::max(ws, std::abs(math::asin(v) - std::asin(static_cast<double>(v))));
  }
  std::printf("float atan2: worst |error| %.2e at angle %.4f; asin %.2e (stated 2.4e-7)\n", wa, wa_at, ws);
  EXPECT_LE(wa, 2.4e-7);
  EXPECT_LE(ws, 2.4e-7);
  // IEEE's signed zeros and the axes, exactly; NaN in, NaN out.
  const float pi = 3.14159265358979f, half_pi = 1.57079632679490f;
  EXPECT_EQ(math::atan2(0.0f, 1.0f), 0.0f);
  EXPECT_TRUE(std::signbit(math::atan2(-0.0f, 1.0f)));
  EXPECT_EQ(math::atan2(0.0f, -0.0f), pi);
  EXPECT_EQ(math::atan2(-0.0f, -1.0f), -pi);
  EXPECT_EQ(math::atan2(2.0f, 0.0f), half_pi);
  EXPECT_EQ(math::atan2(-2.0f, 0.0f), -half_pi);
  EXPECT_NEAR(math::atan2(1.0f, 1.0f), pi / 4, 6e-8);
  EXPECT_NEAR(math::atan2(-1.0f, -1.0f), -3 * pi / 4, 2.4e-7);
  EXPECT_EQ(math::asin(1.0f), half_pi);
  EXPECT_EQ(math::asin(-1.0f), -half_pi);
  EXPECT_TRUE(std::isnan(math::atan2(std::numeric_limits<float>::quiet_NaN(), 1.0f)));
  EXPECT_TRUE(std::isnan(math::asin(1.0001f)));
}

}  // namespace
