// The fixed-point elementary functions (osc/math/q_functions.hpp): each one's stated maximum error
// against double (docs/fixed_point.md) over its whole input range, and its domain's flag.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "exact_reference.hpp"
#include "osc/math/q_functions.hpp"
#include "osc/math/scalar.hpp"

using namespace osc;
using namespace osc::test;

namespace {

// ---------------------------------------------------------------- elementary functions
/// Worst error in LSB of Fixed of f against g over the given raw arguments.
template <class F, class G>
double worst_lsb(const std::vector<std::int32_t>& args, F f, G g, double* where = nullptr) {
  double worst = 0;
  for (std::int32_t a : args) {
    const Fixed x = Fixed::from_raw(a);
    const double e = std::abs(static_cast<double>(f(x)) - g(static_cast<double>(x))) / kLsb;
    if (e > worst) {
      worst = e;
      if (where) *where = static_cast<double>(x);
    }
  }
  return worst;
}

/// Arguments over the whole range: uniform raws, every magnitude, and a dense sweep of [lo, hi].
std::vector<std::int32_t> arguments(double lo, double hi, int n = 400000) {
  Raws r;
  std::vector<std::int32_t> v;
  for (int k = 0; k < n; ++k) v.push_back(k % 2 ? r.uniform() : r.any());
  const std::int32_t a = Fixed(lo).raw(), b = Fixed(hi).raw();
  const std::int64_t step = std::max<std::int64_t>(1, (static_cast<std::int64_t>(b) - a) / n);
  for (std::int64_t x = a; x <= b; x += step) v.push_back(static_cast<std::int32_t>(x));
  v.push_back(kMax);
  v.push_back(kMin);
  v.push_back(0);
  return v;
}

// The stated maximum errors (docs/fixed_point.md), in LSB of Q12.19 (1.9e-6).
constexpr double kSinCosMaxLsb = 0.51;
constexpr double kSqrtMaxLsb = 0.5;
constexpr double kAtan2MaxLsb = 0.51;
constexpr double kAsinMaxLsb = 0.51;
constexpr double kExpMaxLsb = 0.51;  // plus kExpMaxRelative of the result
constexpr double kExpMaxRelative = 4e-9;

TEST(FixedFunctions, SinAndCosWithinTheirStatedErrorEverywhere) {
  const auto args = arguments(-40, 40);
  double at_s = 0, at_c = 0;
  const double es = worst_lsb(
      args, [](Fixed x) { return math::sin(x); }, [](double x) { return std::sin(x); }, &at_s);
  const double ec = worst_lsb(
      args, [](Fixed x) { return math::cos(x); }, [](double x) { return std::cos(x); }, &at_c);
  std::printf("sin: worst %.4f LSB at %.6f; cos: worst %.4f LSB at %.6f\n", es, at_s, ec, at_c);
  EXPECT_LE(es, kSinCosMaxLsb);
  EXPECT_LE(ec, kSinCosMaxLsb);
}

TEST(FixedFunctions, SqrtIsCorrectlyRounded) {
  const auto args = arguments(0, 10);
  double worst = 0;
  for (std::int32_t a : args) {
    if (a < 0) continue;
    const Fixed x = Fixed::from_raw(a);
    worst = std::max(worst, std::abs(static_cast<double>(math::sqrt(x)) - std::sqrt(static_cast<double>(x))) / kLsb);
  }
  std::printf("sqrt: worst %.4f LSB\n", worst);
  EXPECT_LE(worst, kSqrtMaxLsb);
  fixed::take_flags();
  EXPECT_EQ(math::sqrt(Fixed(-1)).raw(), 0);
  EXPECT_EQ(fixed::take_flags(), fixed::kDomain);
}

TEST(FixedFunctions, ExpWithinItsStatedErrorEverywhere) {
  const auto args = arguments(-20, 8.3);
  double worst = 0, at = 0;
  fixed::take_flags();
  for (std::int32_t a : args) {
    const Fixed x = Fixed::from_raw(a);
    const double want = std::exp(static_cast<double>(x));
    const Fixed got = math::exp(x);
    if (want >= 4096) {
      EXPECT_EQ(got.raw(), kMax) << static_cast<double>(x);
      EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
      continue;
    }
    const double e = (std::abs(static_cast<double>(got) - want) - kExpMaxRelative * want) / kLsb;
    if (e > worst) worst = e, at = static_cast<double>(x);
  }
  // e^x just below the top of the range.
  fixed::take_flags();
  EXPECT_NEAR(static_cast<double>(math::exp(Fixed(8.3))), std::exp(static_cast<double>(Fixed(8.3))),
              4e-9 * 4096 + kLsb);
  EXPECT_EQ(fixed::take_flags(), 0u);
  std::printf("exp: worst |error| - %.0e e^x = %.4f LSB at %.6f\n", kExpMaxRelative, worst, at);
  EXPECT_LE(worst, kExpMaxLsb);
}

TEST(FixedFunctions, Atan2WithinItsStatedErrorEverywhere) {
  Raws r;
  double worst = 0;
  for (int k = 0; k < 1000000; ++k) {
    const std::int32_t a = k % 3 ? r.any() : r.uniform(), b = k % 5 ? r.any() : r.uniform();
    const Fixed y = Fixed::from_raw(a), x = Fixed::from_raw(b);
    const double want = std::atan2(static_cast<double>(y), static_cast<double>(x));
    worst = std::max(worst, std::abs(static_cast<double>(math::atan2(y, x)) - want) / kLsb);
  }
  for (std::int32_t a : {0, 1, -1, kMax, kMin})
    for (std::int32_t b : {0, 1, -1, kMax, kMin}) {
      const double want = std::atan2(a * kLsb, b * kLsb);
      worst = std::max(
          worst, std::abs(static_cast<double>(math::atan2(Fixed::from_raw(a), Fixed::from_raw(b))) - want) / kLsb);
    }
  std::printf("atan2: worst %.4f LSB\n", worst);
  EXPECT_LE(worst, kAtan2MaxLsb);
  for (int i = 0; i <= 8; ++i) EXPECT_NEAR(fixed::detail::kAtanEighthsQ30[i], std::atan(i / 8.0) * (1 << 30), 0.5) << i;
}

TEST(FixedFunctions, AsinWithinItsStatedErrorOnItsWholeDomain) {
  double worst = 0, at = 0;
  for (std::int32_t a = -(1 << 19); a <= (1 << 19); ++a) {  // every argument in [-1, 1]
    const Fixed x = Fixed::from_raw(a);
    const double e = std::abs(static_cast<double>(math::asin(x)) - std::asin(static_cast<double>(x))) / kLsb;
    if (e > worst) worst = e, at = static_cast<double>(x);
  }
  std::printf("asin: worst %.4f LSB at %.7f\n", worst, at);
  EXPECT_LE(worst, kAsinMaxLsb);
  fixed::take_flags();
  EXPECT_EQ(math::asin(Fixed(1.5)), math::asin(Fixed(1)));
  EXPECT_EQ(fixed::take_flags(), fixed::kDomain);
}

}  // namespace
