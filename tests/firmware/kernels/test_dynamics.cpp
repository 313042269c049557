// The joint-space dynamics (osc/kernels/dynamics.hpp) on random non-singular states (props_fixture.hpp):
// A(q) symmetric positive definite.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdio>

#include "osc/kernels/dynamics.hpp"
#include "props_fixture.hpp"

using namespace osc;
using namespace osc::test;

namespace {

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

}  // namespace
