// The saturating integer arithmetic under the fixed-point scalar (osc/math/saturating_int.hpp): the
// targets' 64-by-32-bit division routine against the host's exact division, and their square root against
// the digit-by-digit one and its definition.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "exact_reference.hpp"
#include "osc/math/saturating_int.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST(FixedArithmetic, TargetDivisionRoutineIsExact) {
  std::mt19937_64 rng(7);
  auto check = [](std::uint64_t n, std::uint32_t d) {
    ASSERT_EQ(fixed::detail::udiv64_32_digits(n, d), static_cast<std::uint32_t>(n / d)) << n << " / " << d;
  };
  for (std::uint32_t d : {1u, 2u, 3u, 0xFFFFu, 0x10000u, 0x10001u, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFFu}) {
    check(0, d);
    check((static_cast<std::uint64_t>(d) << 32) - 1, d);  // the largest quotient
    check(static_cast<std::uint64_t>(d) << 31, d);
    check(d, d);
  }
  for (int k = 0; k < 2000000; ++k) {
    std::uint32_t d = static_cast<std::uint32_t>(rng()) >> (rng() % 32);
    if (d == 0) d = 1;
    const std::uint64_t n = rng() % (static_cast<std::uint64_t>(d) << 32);
    check(n, d);
  }
}

/// floor(sqrt(n)) digit by digit, two bits of n a step: the root the targets used before isqrt64.
std::uint64_t isqrt64_digits(std::uint64_t n) {
  std::uint64_t res = 0, bit = std::uint64_t{1} << 62;
  while (bit > n) bit >>= 2;
  while (bit != 0) {
    if (n >= res + bit) {
      n -= res + bit;
      res = (res >> 1) + bit;
    } else {
      res >>= 1;
    }
    bit >>= 2;
  }
  return res;
}

TEST(FixedArithmetic, TargetSquareRootIsExact) {
  // Against the digit-by-digit root and the definition r^2 <= n < (r + 1)^2 (in 128 bits).
  auto check = [](std::uint64_t n) {
    const std::uint64_t r = fixed::detail::isqrt64(n);
    ASSERT_EQ(r, isqrt64_digits(n)) << n;
    const I128 r2 = static_cast<I128>(r) * static_cast<I128>(r), next = r2 + 2 * static_cast<I128>(r) + 1;
    ASSERT_TRUE(r2 <= static_cast<I128>(n) && static_cast<I128>(n) < next) << n;
  };
  // The 32-bit path: around every square (the root's steps) and every table cell, and a sweep.
  for (std::uint64_t s = 0; s <= 0x10000u; ++s)
    for (std::uint64_t n : {s * s - 1, s * s, s * s + 1})
      if (n <= 0xFFFFFFFFu) check(n);
  for (std::uint64_t cell = 16; cell <= 64; ++cell)
    for (int d = -2; d <= 2; ++d) check((cell << 26) + d);
  for (std::uint64_t n = 0; n <= 0xFFFFFFFFu; n += 997) check(n);
  // The 64-bit path: squares and their neighbours up to the top, powers of two, the words whose root
  // is 2^32 - 1, and random words of every length.
  for (std::uint64_t s = 0xFFFFFFFFu; s > 0xFFFFu; s -= 1 + s / 4096)
    for (std::uint64_t n : {s * s - 1, s * s, s * s + 1}) check(n);
  for (int e = 32; e < 64; ++e)
    for (int d = -2; d <= 2; ++d) check((std::uint64_t{1} << e) + static_cast<std::uint64_t>(d));
  for (std::uint64_t j = 0; j < 1000; ++j) check(~std::uint64_t{0} - j), check(0xFFFFFFFE00000001u - j);
  std::mt19937_64 rng(11);
  for (int k = 0; k < 1000000; ++k) check(rng() >> (rng() % 64));
}

}  // namespace
