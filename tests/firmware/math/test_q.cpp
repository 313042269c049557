// The fixed-point scalar Q<F> (osc/math/q.hpp): rounding and saturation of every operation against exact
// integer arithmetic, the sticky flags, the edges of the range, the conversions to float and double, the
// mixed-format product and the integer quotient.
#include <gtest/gtest.h>

#include <cmath>

#include "exact_reference.hpp"
#include "osc/math/q.hpp"
#include "osc/math/scalar.hpp"

using namespace osc;
using namespace osc::test;
using fixed::Q;

namespace {

std::int32_t clamp32(I128 v) { return v > kMax ? kMax : (v < kMin ? kMin : static_cast<std::int32_t>(v)); }
/// floor(v / 2^s + 1/2): round half up, as the product rounds.
I128 round_shift(I128 v, int s) {
  const I128 d = I128(1) << s;
  I128 q = v / d;
  if (v - q * d < 0) --q;  // floor
  return (v - q * d) * 2 >= d ? q + 1 : q;
}
/// round(n / d) half away from zero.
I128 round_div(I128 n, I128 d) {
  const bool neg = (n < 0) != (d < 0);
  const I128 an = n < 0 ? -n : n, ad = d < 0 ? -d : d;
  const I128 q = (an + ad / 2) / ad;
  return neg ? -q : q;
}

TEST(FixedArithmetic, EveryOperationRoundsAsExactArithmeticAndSaturatesWithTheFlag) {
  Raws r;
  for (int k = 0; k < 200000; ++k) {
    const std::int32_t a = k % 2 ? r.any() : r.uniform(), b = k % 3 ? r.any() : r.uniform();
    const Fixed x = Fixed::from_raw(a), y = Fixed::from_raw(b);
    auto check = [&](const char* op, Fixed got, I128 exact) {
      ASSERT_EQ(got.raw(), clamp32(exact)) << op << " a=" << a << " b=" << b;
    };
    fixed::take_flags();
    const Fixed s = x + y;
    const bool sat_s = (I128(a) + b) != s.raw();
    EXPECT_EQ(fixed::take_flags() != 0, sat_s);
    check("+", s, I128(a) + b);
    const Fixed d = x - y;
    EXPECT_EQ(fixed::take_flags() != 0, (I128(a) - b) != d.raw());
    check("-", d, I128(a) - b);
    const Fixed p = x * y;
    const I128 pe = round_shift(I128(a) * b, 19);
    EXPECT_EQ(fixed::take_flags() != 0, pe != p.raw());
    check("*", p, pe);
    if (b != 0) {
      const Fixed qt = x / y;
      const I128 qe = round_div(I128(a) << 19, b);
      EXPECT_EQ(fixed::take_flags() == fixed::kDivision, qe != qt.raw()) << a << " / " << b;
      check("/", qt, qe);
    }
  }
}

TEST(FixedArithmetic, EdgesOfTheRange) {
  fixed::take_flags();
  EXPECT_EQ((Fixed::max() + Fixed::lsb()).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ((-Fixed::min()).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ(fixed::abs(Fixed::min()).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ((Fixed(3000) * Fixed(2)).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  // Division by zero and by a near-zero.
  EXPECT_EQ((Fixed(1) / Fixed(0)).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kDivision);
  EXPECT_EQ((Fixed(-1) / Fixed(0)).raw(), kMin);
  EXPECT_EQ((Fixed(0) / Fixed(0)).raw(), 0);
  EXPECT_EQ(fixed::take_flags(), fixed::kDivision);
  EXPECT_EQ((Fixed(1) / Fixed::lsb()).raw(), kMax);  // 2^19 > 4096
  EXPECT_EQ(fixed::take_flags(), fixed::kDivision);
  EXPECT_EQ((Fixed(-4096) / Fixed(1)).raw(), kMin);  // exactly the bottom of the range: no flag
  EXPECT_EQ(fixed::take_flags(), 0u);
  // Conversions.
  EXPECT_EQ(Fixed(5000.0).raw(), kMax);
  EXPECT_EQ(Fixed(-1e9).raw(), kMin);
  EXPECT_EQ(Fixed(std::nan("")).raw(), 0);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow | fixed::kDomain);
  EXPECT_EQ(Fixed(5000).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ(Fixed(std::uint64_t{1} << 40).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ(FixedIo(Fixed::max()).raw(), 1 << 24);  // 4096 in Q19.12, rounded up from 4096 - 2^-19
  EXPECT_EQ(Fixed(FixedIo(5000)).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ(static_cast<std::int32_t>(Fixed(-2.75)), -2);  // truncation, as a float converts
  EXPECT_EQ(static_cast<std::int32_t>(Fixed(2.75)), 2);
  EXPECT_EQ(Fixed(0.5).raw(), 1 << 18);
  EXPECT_EQ(Fixed(-1.5 * kLsb).raw(), -2);  // half away from zero
  // The flag is sticky until taken.
  (void)(Fixed::max() * Fixed(2));
  (void)(Fixed(1) + Fixed(1));
  EXPECT_EQ(fixed::flags(), fixed::kOverflow);
  EXPECT_EQ(fixed::flags(), fixed::kOverflow);
  EXPECT_TRUE(math::take_arithmetic_fault<Fixed>());
  EXPECT_FALSE(math::take_arithmetic_fault<Fixed>());
  EXPECT_FALSE(math::take_arithmetic_fault<float>());
}

TEST(FixedArithmetic, ConversionsToFloatAndDoubleAreExactOrCorrectlyRounded) {
  Raws r;
  for (int k = 0; k < 100000; ++k) {
    const Fixed x = Fixed::from_raw(r.uniform());
    const double d = static_cast<double>(x);
    EXPECT_EQ(d * (1 << 19), static_cast<double>(x.raw()));
    EXPECT_EQ(static_cast<float>(x), static_cast<float>(d));
  }
  // The edges, and the ties of the rounding to 24 bits (even down, odd up), in three formats.
  for (std::int32_t raw :
       {1, -1, 2, INT32_MAX, INT32_MIN, INT32_MIN + 1, (1 << 24) - 1, 1 << 24, (1 << 24) + 1, (1 << 24) + 3,
        -((1 << 24) + 1), -((1 << 24) + 3), (1 << 30) + 64, (1 << 30) + 192, 0x7FFFFFC0, 0x7FFFFF40}) {
    EXPECT_EQ(static_cast<float>(Fixed::from_raw(raw)), static_cast<float>(static_cast<double>(Fixed::from_raw(raw))))
        << raw;
    EXPECT_EQ(static_cast<float>(FixedIo::from_raw(raw)),
              static_cast<float>(static_cast<double>(FixedIo::from_raw(raw))))
        << raw;
    EXPECT_EQ(static_cast<float>(fixed::Q<30>::from_raw(raw)),
              static_cast<float>(static_cast<double>(fixed::Q<30>::from_raw(raw))))
        << raw;
  }
  EXPECT_EQ(static_cast<float>(Fixed::from_raw(0)), 0.0f);
}

TEST(FixedArithmetic, MixedFormatProductAndIntegerQuotient) {
  Raws r;
  for (int k = 0; k < 100000; ++k) {
    const std::int32_t a = r.any(), b = r.any();
    fixed::take_flags();
    EXPECT_EQ((Fixed::from_raw(a) * FixedIo::from_raw(b)).raw(), clamp32(round_shift(I128(a) * b, 12)));
    const std::int32_t counts = static_cast<std::int32_t>(r.rng() % 400001) - 200000;
    if (b != 0) {
      const Fixed q = math::quotient<Fixed>(counts, FixedIo::from_raw(b));
      EXPECT_EQ(q.raw(), clamp32(round_div(I128(counts) << 31, b)));
    }
  }
  fixed::take_flags();
  // Sample counts to seconds: exact to the rounding, uptime-independent within the period.
  EXPECT_EQ(math::ratio<Fixed>(25000, 1000).raw(), 25 << 19);
  EXPECT_EQ(math::ratio<Fixed>(1, 1000).raw(), 524);  // 0.001 * 2^19 = 524.288
  EXPECT_EQ(math::ratio<Fixed>(2999, 1000).raw(), static_cast<std::int32_t>(std::lround(2.999 * (1 << 19))));
  EXPECT_EQ(fixed::take_flags(), 0u);
  EXPECT_EQ(math::ratio<float>(2999, 1000), 2999.0f * 1e-3f);  // as n dt for float
  EXPECT_EQ(math::ratio<double>(2999, 1000), 2999.0 * 1e-3);
}

}  // namespace
