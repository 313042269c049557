// The saturating integer arithmetic under the fixed-point scalar (osc/math/saturating_int.hpp): the
// targets' 64-by-32-bit division routine against the host's exact division.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "osc/math/saturating_int.hpp"

using namespace osc;

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

}  // namespace
