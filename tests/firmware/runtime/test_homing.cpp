// Homing (osc/runtime/homing.hpp): the homing's fixed-point ticks of a count (a motor's angle in counts
// times 2^16) round trip in every scalar. Homing itself on the simulated arm: tests/host_sim/test_homing.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/homing.hpp"

namespace {

using namespace osc;

TEST(Homing, TicksRoundTripInEveryScalar) {
  const double cpr = robot::kDriveTrain.encoders.counts_per_rad[1];  // J2: 13 669 counts/rad
  for (double x : {-3.9, -0.123456, 0.0, 1e-4, 2.5}) {
    const std::int64_t want = std::llround(x * cpr * 65536);
    EXPECT_NEAR(static_cast<double>(detail::to_ticks<double>(x, cpr)), static_cast<double>(want), 1.0) << x;
    EXPECT_NEAR(static_cast<double>(detail::to_ticks<float>(static_cast<float>(x), static_cast<float>(cpr))),
                static_cast<double>(want), 0.02 * 65536)
        << x;  // float's 24 bits: 0.005 counts at 5e4
    // Q12.19's angle resolution, 1.9e-6 rad: 0.026 counts at J2's 13 669 counts/rad.
    EXPECT_NEAR(static_cast<double>(detail::to_ticks<Fixed>(Fixed(x), FixedIo(cpr))), static_cast<double>(want),
                0.03 * 65536)
        << x;
    EXPECT_NEAR(detail::from_ticks<double>(want, cpr), x, 1e-9);
    EXPECT_NEAR(static_cast<double>(detail::from_ticks<Fixed>(want, FixedIo(cpr))), x, 2e-5) << x;
  }
  EXPECT_EQ(detail::floor_div(-7, 2), -4);
  EXPECT_EQ(detail::floor_div(7, 2), 3);
  EXPECT_EQ(detail::floor_div(-8, 2), -4);
}

}  // namespace
