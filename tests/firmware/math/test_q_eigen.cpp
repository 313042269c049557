// Eigen in fixed point (osc/math/q_eigen.hpp): NumTraits, PartialPivLU and LLT on 3x3 and 6x6 against
// double, and a singular matrix's flag instead of an infinity.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cstdio>

#include "exact_reference.hpp"
#include "osc/math/q_eigen.hpp"
#include "test_util.hpp"

using namespace osc;
using namespace osc::test;

namespace {

// ---------------------------------------------------------------- Eigen
static_assert(Eigen::NumTraits<Fixed>::IsInteger == 0 && Eigen::NumTraits<Fixed>::IsSigned == 1);
static_assert(Eigen::NumTraits<Fixed>::epsilon() == Fixed::lsb());

TEST(FixedEigen, PartialPivLuAndLltSolveLikeDouble) {
  test::RandomStates rs;
  double worst_lu = 0, worst_llt = 0, worst_rcond = 0;
  for (int k = 0; k < 2000; ++k) {
    // 3x3 with entries in [-1, 1] and a condition number bounded by the diagonal shift.
    Mat3<double> A3 = Mat3<double>::Identity() * 1.5;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) A3(i, j) += 0.5 * rs.u(rs.rng);
    const Vec3<double> b3(rs.u(rs.rng), rs.u(rs.rng), rs.u(rs.rng));
    // 6x6 symmetric positive definite, eigenvalues in [0.1, 10] (like A(q) and Lambda).
    Mat6<double> M = Mat6<double>::Zero();
    for (int i = 0; i < 6; ++i) M.col(i) = rs.vec(1.0);
    const Mat6<double> A6 = 0.15 * M * M.transpose() + 0.1 * Mat6<double>::Identity();
    const Vec6<double> b6 = rs.vec(1.0);
    {
      test::NoMalloc guard;
      const Eigen::PartialPivLU<Mat3<Fixed>> lu(A3.cast<Fixed>());
      const Vec3<Fixed> x3 = lu.solve(b3.cast<Fixed>());
      const Vec3<Fixed> y3 = lu.transpose().solve(b3.cast<Fixed>());
      const Eigen::LLT<Mat6<Fixed>> llt(A6.cast<Fixed>());
      ASSERT_EQ(llt.info(), Eigen::Success);
      const Vec6<Fixed> x6 = llt.solve(b6.cast<Fixed>());
      const Eigen::PartialPivLU<Mat3<double>> lud(A3);
      worst_lu = std::max(worst_lu, (x3.cast<double>() - lud.solve(b3)).cwiseAbs().maxCoeff());
      worst_lu =
          std::max(worst_lu, (y3.cast<double>() - Vec3<double>(lud.transpose().solve(b3))).cwiseAbs().maxCoeff());
      worst_llt = std::max(worst_llt, (x6.cast<double>() - A6.llt().solve(b6)).cwiseAbs().maxCoeff());
      worst_rcond = std::max(worst_rcond, std::abs(static_cast<double>(lu.rcond()) - lud.rcond()));
    }
  }
  std::printf("Eigen in Q12.19: worst |x - x_double|: PartialPivLU 3x3 %.2e, LLT 6x6 %.2e; rcond %.2e\n", worst_lu,
              worst_llt, worst_rcond);
  EXPECT_LT(worst_lu, 1e-4);
  EXPECT_LT(worst_llt, 1e-3);
  EXPECT_LT(worst_rcond, 1e-4);
  EXPECT_EQ(fixed::take_flags(), 0u);
}

TEST(FixedEigen, ASingularMatrixRaisesTheFlagInsteadOfAnInfinity) {
  Mat3<Fixed> S = Mat3<Fixed>::Zero();
  S(0, 0) = Fixed(1);
  S(1, 1) = Fixed(1);
  fixed::take_flags();
  const Eigen::PartialPivLU<Mat3<Fixed>> lu(S);
  const Vec3<Fixed> x = lu.solve(Vec3<Fixed>(Fixed(1), Fixed(1), Fixed(1)));
  EXPECT_EQ(x(2).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kDivision);
  Mat6<Fixed> N = Mat6<Fixed>::Identity();
  N(3, 3) = Fixed(-1);
  EXPECT_EQ(Eigen::LLT<Mat6<Fixed>>(N).info(), Eigen::NumericalIssue);
}

}  // namespace
