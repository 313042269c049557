// What the fixed-point scalar's tests share (test_q.cpp, test_q_functions.cpp, test_q_eigen.cpp,
// test_saturating_int.cpp): exact integers for the reference, the ends of the raw range, and raw values
// of every magnitude.
#pragma once

#include <cstdint>
#include <random>

namespace osc::test {

__extension__ using I128 = __int128;      // exact products and quotients for the reference
constexpr double kLsb = 1.0 / (1 << 19);  // of Fixed
constexpr std::int32_t kMax = INT32_MAX, kMin = INT32_MIN;

struct Raws {
  std::mt19937_64 rng{20261124};
  /// A raw value of every magnitude: a random sign, bit length and mantissa.
  std::int32_t any() {
    const int bits = static_cast<int>(rng() % 32);
    std::int64_t v = static_cast<std::int64_t>(rng() & ((std::uint64_t{1} << bits) - 1));
    if (rng() & 1) v = -v;
    return static_cast<std::int32_t>(v);
  }
  std::int32_t uniform() { return static_cast<std::int32_t>(static_cast<std::uint32_t>(rng())); }
};

}  // namespace osc::test
