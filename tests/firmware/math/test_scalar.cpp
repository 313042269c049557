// The scalar layer (osc/math/scalar.hpp): all_finite in float, double and fixed point, against
// std::isfinite coefficient by coefficient, for every placement of a non-finite value.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "osc/math/scalar.hpp"
#include "osc/kernels/model.hpp"

using namespace osc;

namespace {

template <class S>
void expect_all_finite_agrees() {
  using L = std::numeric_limits<S>;
  const S specials[] = {L::infinity(), -L::infinity(), L::quiet_NaN(), -L::quiet_NaN()};
  const S finite[] = {S(0), -S(0), L::max(), L::lowest(), L::min(), L::denorm_min(), S(1.5)};
  Vec6<S> v;
  for (const S f : finite) {
    v.setConstant(f);
    EXPECT_TRUE(math::all_finite(v)) << f;
  }
  for (int i = 0; i < 6; ++i)
    for (const S x : specials) {
      v.setConstant(L::max());  // the largest finite values: their differences are 0, not an overflow
      v(i) = x;
      EXPECT_FALSE(math::all_finite(v)) << "entry " << i << " = " << x;
      EXPECT_EQ(math::all_finite(v), std::isfinite(v(i)));
    }
  Eigen::Matrix<S, 3, 6> m = Eigen::Matrix<S, 3, 6>::Ones();
  EXPECT_TRUE(math::all_finite(m));
  m(2, 5) = L::quiet_NaN();
  EXPECT_FALSE(math::all_finite(m));
  EXPECT_FALSE(math::all_finite(m.col(5)));
  EXPECT_TRUE(math::all_finite(m.col(4)));
}

}  // namespace

TEST(Scalar, AllFiniteFindsEveryInfinityAndNaNInFloatAndDouble) {
  expect_all_finite_agrees<float>();
  expect_all_finite_agrees<double>();
}

TEST(Scalar, AllFiniteIsTrueForAnyFixedPointValue) {
  Vec6<fixed::Q<19>> v;
  v.setConstant(fixed::Q<19>(1e9));  // saturated: finite, the sticky flag tells
  EXPECT_TRUE(math::all_finite(v));
  (void)fixed::take_flags();
}
