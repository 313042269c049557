// The tick's monitors together (osc/runtime/monitors.hpp, which includes them all): each, tripped, returns
// the one fault bit its line of the header's table names. Each monitor's own rule is tested in the file of
// its header: test_encoder_monitors.cpp, test_step_monitors.cpp and test_residual_monitor.cpp (with
// test_residual_constants.cpp, test_residual_thresholds.cpp, test_residual_travel.cpp); the tick's stage
// timing in test_timing.cpp.
#include <gtest/gtest.h>

#include <bitset>
#include <cstdint>

#include "osc/runtime/monitors.hpp"

using namespace osc;

namespace {

// Each monitor the header's table names, driven once beyond its rule (in double), returns exactly one
// fault bit: the catalogue's entry (osc/control/faults.hpp) of the name the table gives it, no two the same.
TEST(MonitorSet, EachReturnsTheOneFaultBitItsTableNames) {
  struct Tripped {
    const char* name;
    std::uint32_t bits;
  };
  const double c = 1000;  // counts per radian
  EncoderRangeMonitor range;
  for (int i = 0; i < kDof; ++i) range.set(i, 0.0, c);
  std::int32_t far[kDof] = {};
  far[2] = static_cast<std::int32_t>(range.max_counts[2]) + 1;
  EncoderJumpMonitor jump;
  jump.reset();
  for (int i = 0; i < kDof; ++i) jump.set(i, c);
  std::int32_t counts[kDof] = {};
  bool moved[kDof] = {};
  jump.tick();
  ASSERT_EQ(jump.check(counts, moved), 0u);  // the first sample
  jump.tick();
  counts[4] = jump.max_step[4] + 1;
  Vec6<double> e = Vec6<double>::Zero();
  e(0) = 2 * params::kTrackingLimitPosition;
  const Vec18<double> theta_max = Gains<double>::paper().theta_max;
  Vec18<double> theta = theta_max;
  theta(5) = (2 + params::kThetaFaultBand) * theta_max(5);  // beyond (1 + band) theta_max
  SaturationMonitor saturation;
  saturation.reset();
  std::uint32_t clipped = 0;
  for (int k = 0; k < params::kSaturationTicks; ++k) clipped = saturation.check(1, true);
  const Tripped tripped[] = {
      {"encoder_range", range.check(far)},
      {"encoder_jump", jump.check(counts, moved)},
      {"tracking", TrackingMonitor<double>::check(e)},
      {"theta_bounds", ThetaBandMonitor<double>::check(theta, theta_max)},
      {"saturation", clipped},
  };
  std::uint32_t seen = 0;
  for (const Tripped& t : tripped) {
    EXPECT_EQ(std::bitset<32>(t.bits).count(), 1u) << t.name;
    EXPECT_STREQ(fault_name(t.bits), t.name);
    EXPECT_EQ(seen & t.bits, 0u) << t.name << " shares a bit";
    seen |= t.bits;
  }
}

}  // namespace
