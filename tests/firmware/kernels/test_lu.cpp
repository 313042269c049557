// The pivoted LU factor of the Jacobian (osc/kernels/lu.hpp), in double against Eigen's LU, the exact
// 1-norm condition number and the spherical-wrist block factor; in float and Q12.19 against double
// within the rounding bounds derived below.
//
// Exact reference: rcond = 1 / (||J||_1 ||J^{-1}||_1) with J^{-1} from Eigen's FullPivLU in double
// (a test may invert; the firmware does not).
//
// The rounding bounds (first order, Higham, "Accuracy and Stability of Numerical Algorithms", 2nd ed.,
// thm 9.4 and 8.5, for this factor's operation order), the double reference taken at the same
// rounded J and b so that only the factor's own rounding is measured:
//   float (unit roundoff u = 2^-24, gamma_k = k u / (1 - k u)): an entry of U is a dot product of at
//   most n - 1 terms and a difference, a multiplier that and two products (by the pivot's rounded
//   reciprocal), so P^T L^ U^ = J + P^T E with |E| <= gamma_{n+2} |L^||U^|; the forward substitution
//   solves (L^ + dL) y = P b with |dL| <= gamma_n |L^|, the back substitution (products by the rounded
//   reciprocals) (U^ + dU) x = y with |dU| <= gamma_{n+2} |U^|. To first order, with gamma_{3n+4}
//   rounded up to gamma_{3n+6},
//     |x^ - x| <= gamma_{3n+6} |J^{-1}| P^T |L^||U^| |x^|        (solve; J^{-T} and its transpose for
//   solve_transpose), componentwise.
//   fixed point (every rounding at most eta = half an LSB, absolute; dot products rounded once):
//   U's entries are off by eta; a multiplier l = v (1/p) is off by eta (1 + |p| + p^2) as an entry
//   of L U; a forward step by eta; a back step x_i = (s (1/u_ii)) by eta (1 + |u_ii| + u_ii^2 |x_i|)
//   as a residual. Hence
//     |x^ - x| <= eta |J^{-1}| P^T (|E|/eta |x^| + |L^| rho + 1),   rho_i = 1 + |u_ii| + u_ii^2 |x^_i|,
//   |E_ij|/eta = 1 (i <= j), 1 + |u_jj| + u_jj^2 (i > j), and for solve_transpose the same with J^T
//   (|J^{-T}| (rho + |U^|^T 1 + |E|^T P |x^|)). Asserted with a factor 1.5 for the second-order terms
//   (and the double reference's own error); the measured ratios are printed.
// rcond = 1 / (||J||_1 ||J^{-1}||_1) from the columns J^{-1} e_j, each a solve: relative error within
// gamma_{3n+6} kappa_1 (double and float: 24 kappa_1 u); in fixed point within about
// (n (1 + |u_kk| + u_kk^2) / ||J||_1 + 1) eta kappa_1 (the columns' error above, and rcond's own rounding,
// eta / rcond): asserted as 10 eta kappa_1 at the PUMA's J (|u_kk| <= 2, ||J||_1 >= 1).
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>

#include "osc/kernels/lu.hpp"
#include "osc/kernels/opspace.hpp"
#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

using M6 = Mat6<double>;
using V6 = Vec6<double>;

struct Exact {
  double rcond;
  M6 inv;
};
Exact exact_of(const M6& J) {
  const M6 inv = Eigen::FullPivLU<M6>(J).inverse();
  const double n = J.cwiseAbs().colwise().sum().maxCoeff(), ni = inv.cwiseAbs().colwise().sum().maxCoeff();
  return {1.0 / (n * ni), inv};
}

template <class S>
PivotedLuJacobianFactor<S> factor_of(const Mat6<S>& J) {
  PivotedLuJacobianFactor<S> f;
  test::NoMalloc guard;
  f.compute(J);
  return f;
}

/// L, U and P^T (P J = L U) of a factor, in double.
struct Factors {
  M6 L, U, Pt;
};
template <class S>
Factors factors(const PivotedLuJacobianFactor<S>& f) {
  const M6 lu = f.lu.template cast<double>();
  Factors r{M6::Identity(), M6::Zero(), M6::Zero()};
  r.L.triangularView<Eigen::StrictlyLower>() = lu;
  r.U.triangularView<Eigen::Upper>() = lu;
  for (int k = 0; k < kDof; ++k) r.Pt(f.perm[k], k) = 1;
  return r;
}

/// Random matrices: entries uniform in [-2, 2] (the scale of a Jacobian in m/rad), or U diag(sigma) V^T
/// with random orthogonal U, V and singular values log-uniform in [sigma_min, 2].
struct RandomMatrices {
  std::mt19937_64 rng{2024};
  std::uniform_real_distribution<double> u{-1.0, 1.0};
  std::normal_distribution<double> g{0.0, 1.0};
  M6 uniform() {
    M6 m;
    for (int j = 0; j < kDof; ++j)
      for (int i = 0; i < kDof; ++i) m(i, j) = 2 * u(rng);
    return m;
  }
  M6 orthogonal() {
    M6 m;
    for (int j = 0; j < kDof; ++j)
      for (int i = 0; i < kDof; ++i) m(i, j) = g(rng);
    return Eigen::HouseholderQR<M6>(m).householderQ();
  }
  M6 with_singular_values(double sigma_min) {
    V6 s;
    for (int i = 0; i < kDof; ++i) s(i) = 2 * std::pow(sigma_min / 2, 0.5 * (u(rng) + 1));
    s(0) = 2, s(1) = sigma_min;
    return orthogonal() * s.asDiagonal() * orthogonal().transpose();
  }
  V6 vec() {
    V6 v;
    for (int i = 0; i < kDof; ++i) v(i) = u(rng);
    return v;
  }
};

/// The PUMA 560's analytic Jacobian at random joint angles within its limits, with the block factor.
struct PumaJacobians {
  Model<double> model = Model<double>::of(robot::kArm);
  std::unique_ptr<Data<double>> data = std::make_unique<Data<double>>();
  std::unique_ptr<OpSpace<double, SphericalWristJacobianFactor<double>>> os =
      std::make_unique<OpSpace<double, SphericalWristJacobianFactor<double>>>();
  test::RandomStates rs;
  const M6& at_random() {
    V6 q;
    for (int i = 0; i < kDof; ++i) {
      const double lo = robot::kArm.q_min[i], hi = robot::kArm.q_max[i];
      q(i) = lo + (hi - lo) * 0.5 * (rs.u(rs.rng) + 1.0);
    }
    // The reference orientation near the pose's own: phi up to ~0.3 rad, as in the task.
    forward_kinematics(model, *data, V6(q + rs.vec(0.15)));
    const Mat3<double> R_ref = data->R[kDof];
    opspace_update(model, *data, *os, q, R_ref, false);
    return os->Ja;
  }
};

double rel(const V6& a, const V6& b) { return (a - b).norm() / b.norm(); }

TEST(PivotedLu, SolvesRandomMatricesLikeEigensLu) {
  RandomMatrices rm;
  double worst_s = 0, worst_t = 0, worst_full = 0, worst_rebuild = 0, worst_l = 0, min_rcond = 1;
  int same_pivots = 0, n = 0;
  for (int k = 0; k < 2000; ++k) {
    const M6 J = k % 2 ? rm.uniform() : rm.with_singular_values(2e-3);
    const Exact ex = exact_of(J);
    if (ex.rcond < 1e-4) continue;  // well conditioned: kappa_1 below 1e4
    ++n;
    min_rcond = std::min(min_rcond, ex.rcond);
    const PivotedLuJacobianFactor<double> f = factor_of(J);
    const V6 b = rm.vec();
    V6 xs, xt;
    {
      test::NoMalloc guard;
      xs = f.solve(b);
      xt = f.solve_transpose(b);
    }
    const Eigen::PartialPivLU<M6> ref(J);
    worst_s = std::max(worst_s, rel(xs, ref.solve(b)));
    worst_t = std::max(worst_t, rel(xt, ref.transpose().solve(b)));
    worst_full = std::max({worst_full, rel(xs, Eigen::FullPivLU<M6>(J).solve(b)),
                           rel(xt, Eigen::FullPivLU<M6>(M6(J.transpose())).solve(b))});
    const Factors F = factors(f);
    worst_rebuild = std::max(worst_rebuild, (F.Pt * F.L * F.U - J).cwiseAbs().maxCoeff() / J.cwiseAbs().maxCoeff());
    worst_l = std::max(worst_l, F.L.cwiseAbs().maxCoeff());
    // The pivots are Eigen's: the largest entry of each column (P J's rows are J's rows perm).
    const M6 PJ = ref.permutationP() * J;
    bool same = true;
    for (int i = 0; i < kDof; ++i) same = same && PJ.row(i) == J.row(f.perm[i]);
    same_pivots += same;
    EXPECT_NEAR((f.u_inv.cwiseProduct(F.U.diagonal()) - V6::Ones()).cwiseAbs().maxCoeff(), 0.0, 1e-15);
    // The side of the singularity (the path check's det_signs): the sign of Eigen's determinant.
    EXPECT_EQ(f.det_positive(), ref.determinant() > 0) << k;
    M6 swapped = J;  // two rows exchanged: the determinant's sign turns
    swapped.row(0).swap(swapped.row(3));
    EXPECT_EQ(factor_of(swapped).det_positive(), ref.determinant() < 0) << k;
  }
  std::printf(
      "%d random matrices (rcond >= %.1e): relative to PartialPivLU solve %.1e, solve_transpose %.1e; to FullPivLU "
      "%.1e; P^T L U - J %.1e of max|J|; max|L| %.3f; Eigen's pivots %d of %d\n",
      n, min_rcond, worst_s, worst_t, worst_full, worst_rebuild, worst_l, same_pivots, n);
  EXPECT_GT(n, 1500);
  EXPECT_LE(worst_s, 1e-12);
  EXPECT_LE(worst_t, 1e-12);
  EXPECT_LE(worst_full, 1e-12);
  EXPECT_LE(worst_rebuild, 1e-15);
  EXPECT_LE(worst_l, 1.0);
  EXPECT_EQ(same_pivots, n);
}

TEST(PivotedLu, PivotsAZeroLeadingEntry) {
  // Without pivoting this J fails at once (J(0, 0) = 0) and again at its second pivot; an
  // anti-diagonal and a cyclic permutation of a well-conditioned matrix have zero leading entries too.
  M6 J;
  J << 0, 1, 2, 0, 0, 1,   //
      1, 1, 0, 0.5, 0, 0,  //
      1, 1, 1, 0, 0.2, 0,  //
      0, 0, 0, 1, 1, 0,    //
      0.3, 0, 0, 0, 1, 1,  //
      0, 0, 0.5, 1, 0, 1;
  M6 anti = M6::Zero();
  for (int i = 0; i < kDof; ++i) anti(i, kDof - 1 - i) = i + 1.0;
  RandomMatrices rm;
  M6 cyclic = M6::Zero();
  for (int i = 0; i < kDof; ++i) cyclic.row(i) = rm.with_singular_values(0.1).row((i + 1) % kDof);
  cyclic(0, 0) = 0;
  for (const M6& m : {J, anti, cyclic}) {
    const PivotedLuJacobianFactor<double> f = factor_of(m);
    EXPECT_NE(f.perm[0], 0);
    const V6 b = rm.vec();
    EXPECT_LE((m * f.solve(b) - b).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_LE((m.transpose() * f.solve_transpose(b) - b).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_GT(f.rcond, 1e-3);
  }
  // The anti-diagonal's rcond is exact: ||J||_1 = 6, ||J^{-1}||_1 = 1.
  EXPECT_DOUBLE_EQ(factor_of(anti).rcond, 1.0 / 6.0);
}

/// rcond / exact over a family of matrices, and the error relative to kappa_1 u (u = 2^-53).
struct RcondQuality {
  double lowest = 1, highest = 1, worst_per_kappa = 0;
  int n = 0;
  void add(double r, double exact_value) {
    const double q = r / exact_value;
    lowest = std::min(lowest, q);
    highest = std::max(highest, q);
    worst_per_kappa = std::max(worst_per_kappa, std::abs(q - 1) * exact_value / std::ldexp(1.0, -53));
    ++n;
  }
  void print(const char* what) const {
    std::printf("%s, %d matrices: rcond / exact in [1 - %.1e, 1 + %.1e], |rcond / exact - 1| <= %.2f kappa_1 u\n", what,
                n, 1 - lowest, highest - 1, worst_per_kappa);
  }
};

TEST(PivotedLu, RcondIsTheExactOneNormValue) {
  // ||J^{-1}||_1 from the factors' columns: exact but for round-off, which grows as kappa_1 u.
  RandomMatrices rm;
  RcondQuality uniform, graded, puma;
  for (int k = 0; k < 3000; ++k) {
    const M6 J = rm.uniform();
    uniform.add(factor_of(J).rcond, exact_of(J).rcond);
  }
  for (int k = 0; k < 3000; ++k) {
    const M6 J = rm.with_singular_values(std::pow(10.0, -1 - 8 * 0.5 * (rm.u(rm.rng) + 1)));  // kappa 10 .. 1e9
    graded.add(factor_of(J).rcond, exact_of(J).rcond);
  }
  PumaJacobians pj;
  for (int k = 0; k < 1000; ++k) {
    const M6 J = pj.at_random();
    const Exact ex = exact_of(J);
    if (ex.rcond < 1e-9) continue;
    puma.add(factor_of(J).rcond, ex.rcond);
  }
  uniform.print("uniform entries in [-2, 2]");
  graded.print("singular values log-uniform in [sigma_min, 2], kappa 10..1e9");
  puma.print("PUMA 560 analytic J in its joint limits, rcond >= 1e-9");
  for (const RcondQuality* q : {&uniform, &graded, &puma}) EXPECT_LE(q->worst_per_kappa, 24.0);
}

// The control step's rcond by halves (compute(J, half)): three of J^{-1}'s columns from this J, three
// kept from the call before. The first call, and one after the pivots' order changed, are exact; two
// calls with the same J are exact; between two Js the value is 1 / (||J||_1 max(the halves' norms))
// from the columns each half saw. The columns kept are J^{-1}'s (inverse_column).
TEST(PivotedLu, RcondByHalvesIsExactOnceBothHalvesSawTheJacobian) {
  RandomMatrices rm;
  for (int k = 0; k < 500; ++k) {
    const M6 J = rm.uniform();
    const Exact ex = exact_of(J);
    if (ex.rcond < 1e-6) continue;
    PivotedLuJacobianFactor<double> f;
    f.compute(J, 1);  // nothing known yet: exact
    EXPECT_NEAR(f.rcond, ex.rcond, 1e-9 * ex.rcond) << k;
    for (int a = 0; a < kDof; ++a)
      EXPECT_LE((f.inverse_column(a) - ex.inv.col(a)).cwiseAbs().maxCoeff(), 1e-9 * ex.inv.cwiseAbs().maxCoeff());
    // A nearby J with the same pivots: half 0 from it, half 1 from J.
    const M6 J2 = J + 1e-3 * rm.uniform();
    const Exact ex2 = exact_of(J2);
    const std::array<std::uint8_t, kDof> perm = f.perm;
    f.compute(J2, 0);
    if (f.perm != perm) {
      EXPECT_NEAR(f.rcond, ex2.rcond, 1e-9 * ex2.rcond) << k;  // a new order: exact
      continue;
    }
    double half[2] = {0, 0};
    for (int K = 0; K < kDof; ++K) {
      const int a = perm[K];
      const double n = (K == 0 || K == 3 || K == 5 ? ex2.inv : ex.inv).col(a).cwiseAbs().sum();
      half[K == 0 || K == 3 || K == 5 ? 0 : 1] = std::max(half[K == 0 || K == 3 || K == 5 ? 0 : 1], n);
    }
    const double expected = 1 / (J2.cwiseAbs().colwise().sum().maxCoeff() * std::max(half[0], half[1]));
    EXPECT_NEAR(f.rcond, expected, 1e-9 * expected) << k;
    f.compute(J2, 1);  // both halves from J2: exact
    EXPECT_NEAR(f.rcond, ex2.rcond, 1e-9 * ex2.rcond) << k;
  }
  // A change of the pivots' order (another J, whose rcond is far from the first's): exact.
  const M6 J = rm.uniform();
  PivotedLuJacobianFactor<double> f;
  f.compute(J);
  const std::array<std::uint8_t, kDof> perm = f.perm;
  M6 other = rm.with_singular_values(1e-4);
  PivotedLuJacobianFactor<double> g;
  for (g.compute(other); g.perm == perm; g.compute(other)) other = rm.with_singular_values(1e-4);
  f.compute(other, 0);
  EXPECT_NEAR(f.rcond, exact_of(other).rcond, 1e-9 * exact_of(other).rcond);
  // A singular J forgets the halves: the next call is exact.
  f.compute(M6::Zero(), 1);
  EXPECT_EQ(f.rcond, 0.0);
  f.compute(J, 1);
  EXPECT_NEAR(f.rcond, exact_of(J).rcond, 1e-9 * exact_of(J).rcond);
}

/// Hager's estimate of ||A^{-1}||_1 as LAPACK's xLACN2 computes it (at most 5 iterations, then
/// Higham's extra vector), with the factor's solves; counts them.
double hager_estimate(const PivotedLuJacobianFactor<double>& f, int& solves) {
  auto signs = [](const V6& v) { return V6(v.unaryExpr([](double a) { return a >= 0 ? 1.0 : -1.0; })); };
  V6 y = f.solve(V6::Constant(1.0 / kDof));
  double est = y.cwiseAbs().sum();
  V6 xi = signs(y);
  solves = 1;
  int j = 0;
  (f.solve_transpose(xi)).cwiseAbs().maxCoeff(&j);
  ++solves;
  for (int iter = 2; iter <= 5; ++iter) {
    y = f.solve(V6::Unit(j));
    ++solves;
    const double old = est;
    est = y.cwiseAbs().sum();
    if (signs(y) == xi || est <= old) break;
    xi = signs(y);
    const V6 z = f.solve_transpose(xi);
    ++solves;
    const int last = j;
    z.cwiseAbs().maxCoeff(&j);
    if (z(last) == std::abs(z(j))) break;
  }
  V6 alt;
  for (int i = 0; i < kDof; ++i) alt(i) = (i % 2 ? -1.0 : 1.0) * (1.0 + i / (kDof - 1.0));
  ++solves;
  return std::max(est, 2 * f.solve(alt).cwiseAbs().sum() / (3 * kDof));
}

TEST(PivotedLu, HagersEstimateMissesByMoreThanAFactorOfThreeOnSomeMatrices) {
  // Why rcond is exact (lu.hpp): the estimator the exact norm replaces, at about its cost, on the
  // same random matrices: usually exact, but beyond a factor 3 now and then.
  RandomMatrices rm;
  int exact = 0, beyond3 = 0, most_solves = 0;
  double worst = 1, solves_sum = 0;
  constexpr int kN = 20000;
  for (int k = 0; k < kN; ++k) {
    const M6 J = rm.uniform();
    const PivotedLuJacobianFactor<double> f = factor_of(J);
    int solves = 0;
    const double ratio = exact_of(J).inv.cwiseAbs().colwise().sum().maxCoeff() / hager_estimate(f, solves);
    exact += ratio < 1 + 1e-9;
    beyond3 += ratio > 3;
    worst = std::max(worst, ratio);
    solves_sum += solves;
    most_solves = std::max(most_solves, solves);
  }
  std::printf(
      "Hager's estimate (xLACN2) on %d uniform random 6x6 matrices: exact on %.1f %%, short by more than 3x on %.2f "
      "%% (worst %.2fx); %.2f solves on average, at most %d\n",
      kN, 100.0 * exact / kN, 100.0 * beyond3 / kN, worst, solves_sum / kN, most_solves);
  EXPECT_GT(beyond3, 0);
  EXPECT_LT(beyond3, kN / 100);
}

TEST(PivotedLu, SingularAndNonFiniteJacobiansGiveZeroRcondAndFiniteSolves) {
  RandomMatrices rm;
  const M6 J = rm.with_singular_values(0.1);
  M6 zero_col = J, zero_row = J, same_cols = J, nan = J, inf = J;
  zero_col.col(3).setZero();
  zero_row.row(1).setZero();
  same_cols.col(4) = same_cols.col(1);
  nan(2, 3) = std::numeric_limits<double>::quiet_NaN();
  inf(5, 0) = std::numeric_limits<double>::infinity();
  const V6 b = rm.vec();
  for (const M6& m : {zero_col, zero_row, M6(M6::Zero()), nan, inf}) {
    const PivotedLuJacobianFactor<double> f = factor_of(m);
    EXPECT_EQ(f.rcond, 0.0);
    EXPECT_TRUE(f.solve(b).allFinite());
    EXPECT_TRUE(f.solve_transpose(b).allFinite());
  }
  // Two equal columns: the last pivot is the round-off of a cancellation, 0 or about 1e-16.
  const PivotedLuJacobianFactor<double> f = factor_of(same_cols);
  EXPECT_LE(f.rcond, 1e-14);
  EXPECT_TRUE(std::isfinite(f.rcond));
  // In float the same.
  for (const M6& m : {zero_col, zero_row, nan, inf, same_cols}) {
    const PivotedLuJacobianFactor<float> ff = factor_of(Mat6<float>(m.cast<float>()));
    EXPECT_LE(ff.rcond, 1e-6f);
    EXPECT_TRUE(ff.solve(b.cast<float>()).allFinite());
    EXPECT_TRUE(ff.solve_transpose(b.cast<float>()).allFinite());
  }
}

TEST(PivotedLu, NearlySingularJacobiansGiveATinyRcond) {
  RandomMatrices rm;
  RcondQuality quality;
  for (double s : {1e-7, 1e-9, 1e-11, 1e-13}) {
    for (int k = 0; k < 50; ++k) {
      const M6 J = rm.with_singular_values(s);
      const PivotedLuJacobianFactor<double> f = factor_of(J);
      EXPECT_LE(f.rcond, 1e-6);
      EXPECT_TRUE(std::isfinite(f.rcond));
      quality.add(f.rcond, exact_of(J).rcond);
    }
  }
  quality.print("nearly singular (sigma_min 1e-7 .. 1e-13 of 2)");
  EXPECT_LE(quality.highest, 1.01);
  EXPECT_GE(quality.lowest, 0.99);
  // The PUMA's wrist-singular poses (q5 = 0): qz, qr, qs.
  Model<double> model = Model<double>::of(robot::kArm);
  auto data = std::make_unique<Data<double>>();
  for (const double* pose : {puma560::kQz, puma560::kQr, puma560::kQs}) {
    V6 q;
    for (int i = 0; i < kDof; ++i) q(i) = pose[i];
    forward_kinematics(model, *data, q);
    geometric_jacobian(*data);
    const PivotedLuJacobianFactor<double> f = factor_of(data->J);
    EXPECT_LE(f.rcond, 1e-12);
    EXPECT_TRUE(f.solve(V6::Ones()).allFinite() || f.rcond == 0.0);
  }
}

TEST(PivotedLu, AgreesWithTheSphericalWristFactorOnThePuma) {
  PumaJacobians pj;
  double worst_s = 0, worst_t = 0, ratio_lo = 1e9, ratio_hi = 0;
  int n = 0;
  while (n < 500) {
    const M6 J = pj.at_random();
    if (pj.os->Jf.rcond < 1e-3) continue;
    ++n;
    const PivotedLuJacobianFactor<double> f = factor_of(J);
    const V6 b = pj.rs.vec(1.0);
    worst_s = std::max(worst_s, rel(f.solve(b), pj.os->Jf.solve(b)));
    worst_t = std::max(worst_t, rel(f.solve_transpose(b), pj.os->Jf.solve_transpose(b)));
    // The two factors' rcond are different numbers (the whole J's, the worse block's).
    ratio_lo = std::min(ratio_lo, f.rcond / pj.os->Jf.rcond);
    ratio_hi = std::max(ratio_hi, f.rcond / pj.os->Jf.rcond);
  }
  std::printf(
      "PUMA J (block rcond >= 1e-3), LU vs block factor, relative: solve %.1e, solve_transpose %.1e; rcond LU / "
      "rcond block in [%.3f, %.3f]\n",
      worst_s, worst_t, ratio_lo, ratio_hi);
  EXPECT_LE(worst_s, 1e-12);
  EXPECT_LE(worst_t, 1e-12);
}

/// The componentwise bounds of the file comment for the factor f of J (in S, cast to double), x^ its
/// solution of J x = b (transpose: J^T x = b); returns max_i |x^_i - x_i| / bound_i.
template <class S>
double bound_ratio(const PivotedLuJacobianFactor<S>& f, const M6& J, const V6& xs, const V6& x, bool transpose) {
  const Factors F = factors(f);
  const M6 Jinv = exact_of(J).inv;
  V6 bound;
  if constexpr (fixed::is_q_v<S>) {
    const double eta = 0.5 * std::ldexp(1.0, -S::kFractionBits);
    const V6 u = F.U.diagonal().cwiseAbs();
    M6 E = M6::Ones();  // |E| / eta
    for (int j = 0; j < kDof; ++j)
      for (int i = j + 1; i < kDof; ++i) E(i, j) = 1 + u(j) + u(j) * u(j);
    V6 r;  // the back substitution's (solve) or forward substitution's (transpose) residual / eta
    if (!transpose) {
      for (int i = 0; i < kDof; ++i) r(i) = 1 + u(i) + u(i) * u(i) * std::abs(xs(i));
      bound = eta * Jinv.cwiseAbs() * F.Pt * (E * xs.cwiseAbs() + F.L.cwiseAbs() * r + V6::Ones());
    } else {
      const V6 z = F.L.transpose() * F.Pt.transpose() * xs;  // U^T z = b, L^T P x = z
      for (int i = 0; i < kDof; ++i) r(i) = 1 + u(i) + u(i) * u(i) * std::abs(z(i));
      bound = eta * Jinv.transpose().cwiseAbs() *
              (r + F.U.cwiseAbs().transpose() * V6::Ones() + E.transpose() * F.Pt.transpose() * xs.cwiseAbs());
    }
  } else {
    const double uu = std::ldexp(1.0, -std::numeric_limits<S>::digits), k = 3 * kDof + 6;
    const double gamma = k * uu / (1 - k * uu);
    const M6 LU = F.Pt * F.L.cwiseAbs() * F.U.cwiseAbs();  // P^T |L^||U^|
    bound = transpose ? V6(gamma * Jinv.transpose().cwiseAbs() * LU.transpose() * xs.cwiseAbs())
                      : V6(gamma * Jinv.cwiseAbs() * LU * xs.cwiseAbs());
  }
  return ((xs - x).cwiseAbs().array() / bound.array()).maxCoeff();
}

/// The factor in S against double at the PUMA's J (rounded to S; double factors the rounded J) over
/// states with the exact rcond above the controller's threshold (1e-3): the solves within their bound
/// (the file comment), rcond within rcond_per_kappa kappa_1 of double's, relative.
template <class S, class Next>
void agrees_with_double(const char* name, const char* what, Next next_j, double rcond_per_kappa) {
  test::RandomStates rs;
  double worst_bound = 0, worst_rel = 0, worst_rcond = 0, worst_kappa = 0;
  int n = 0;
  fixed::take_flags();
  while (n < 500) {
    const Mat6<S> Js = next_j().template cast<S>();
    const M6 J = Js.template cast<double>();
    const Exact ex = exact_of(J);
    if (ex.rcond < 1e-3) continue;
    ++n;
    const Vec6<S> bs = rs.vec(1.0).cast<S>();
    const V6 b = bs.template cast<double>();
    const PivotedLuJacobianFactor<S> f = factor_of(Js);
    const PivotedLuJacobianFactor<double> fd = factor_of(J);
    Vec6<S> xs, xt;
    {
      test::NoMalloc guard;
      xs = f.solve(bs);
      xt = f.solve_transpose(bs);
    }
    const V6 xd = fd.solve(b), xtd = fd.solve_transpose(b);
    worst_bound = std::max({worst_bound, bound_ratio(f, J, xs.template cast<double>(), xd, false),
                            bound_ratio(f, J, xt.template cast<double>(), xtd, true)});
    worst_rel = std::max({worst_rel, (xs.template cast<double>() - xd).cwiseAbs().maxCoeff() / xd.cwiseAbs().maxCoeff(),
                          (xt.template cast<double>() - xtd).cwiseAbs().maxCoeff() / xtd.cwiseAbs().maxCoeff()});
    worst_kappa = std::max(worst_kappa, 1 / ex.rcond);
    // rcond: the rounded factors' (relative to double's at the same J, over kappa_1).
    const double r = static_cast<double>(f.rcond);
    worst_rcond = std::max(worst_rcond, std::abs(r - fd.rcond) / fd.rcond * ex.rcond);
  }
  EXPECT_EQ(fixed::take_flags(), 0u) << "a saturation in " << name;
  std::printf(
      "%s vs double, %d %s (kappa_1 <= %.0f): worst error / bound %.3f, worst relative (max norm) %.1e; "
      "rcond relative to double's <= %.2f of its bound times kappa_1\n",
      name, n, what, worst_kappa, worst_bound, worst_rel, worst_rcond / rcond_per_kappa);
  EXPECT_LE(worst_bound, 1.5);
  EXPECT_LE(worst_rcond, rcond_per_kappa);
}

/// The two families: the PUMA's analytic J at random joint angles within its limits, and random
/// matrices with entries up to about 2 and rcond down to the threshold (sigma_min 1e-3 .. 1e-2 of 2).
template <class S>
void agrees_with_double_on_both(const char* name, double rcond_per_kappa) {
  PumaJacobians pj;
  agrees_with_double<S>(
      name, "PUMA states", [&] { return pj.at_random(); }, rcond_per_kappa);
  RandomMatrices rm;
  agrees_with_double<S>(
      name, "random near-threshold matrices",
      [&] { return rm.with_singular_values(std::pow(10.0, -2.5 + 0.5 * rm.u(rm.rng))); }, rcond_per_kappa);
}

TEST(PivotedLu, FloatAgreesWithDoubleWithinTheRoundingBound) {
  agrees_with_double_on_both<float>("float", 24 * std::ldexp(1.0, -24));  // 24 u
}

TEST(PivotedLu, FixedPointAgreesWithDoubleWithinTheRoundingBound) {
  agrees_with_double_on_both<Fixed>("Q12.19", 10 * std::ldexp(0.5, -Fixed::kFractionBits));  // 10 eta
}

TEST(PivotedLu, FixedPointRcondBeyondTheRangeIsZeroAndLeavesTheFlagsAlone) {
  // A J whose inverse exceeds the Q12.19 range (sigma_min 1e-5): its norm saturates; rcond is 0
  // and the flags are those before compute (here one raised before, kept).
  RandomMatrices rm;
  for (int k = 0; k < 20; ++k) {
    const Mat6<Fixed> J = rm.with_singular_values(1e-5).cast<Fixed>();
    fixed::take_flags();
    fixed::restore_flags(fixed::kDomain);
    const PivotedLuJacobianFactor<Fixed> f = factor_of(J);
    EXPECT_EQ(fixed::take_flags(), static_cast<std::uint32_t>(fixed::kDomain));
    EXPECT_LE(static_cast<double>(f.rcond), 1e-4);
  }
  // A singular pivot: no division by it (no kDivision), rcond 0.
  M6 J = rm.with_singular_values(0.1);
  J.col(2) = J.col(0);
  fixed::take_flags();
  const PivotedLuJacobianFactor<Fixed> f = factor_of(Mat6<Fixed>(J.cast<Fixed>()));
  EXPECT_EQ(fixed::take_flags(), 0u);
  EXPECT_EQ(f.rcond, Fixed(0));
}

}  // namespace
