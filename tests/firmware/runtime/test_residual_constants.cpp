// The residual monitor's constants of the arm (osc/runtime/residual_constants.hpp), built at compile time:
// each friction band as its middle and half-width gives back the band's ends (so |theta^ - mid| + half,
// theta^'s farthest distance from the band, is the band's width at either end); the least breakaway
// below the band's top; each filter a stable first-order one at the tick and over a turn, the turn's
// step that of params::kResidualTurnEvery ticks to first order; in float and Q12.19 the constants of
// double to their scalar's resolution.
#include <gtest/gtest.h>

#include <cmath>

#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/residual_constants.hpp"

using namespace osc;

namespace {

TEST(ResidualConstants, EachBandAsItsMiddleAndHalfWidthIsTheBandsEnds) {
  const ResidualConstants<double>& k = kResidualConstants<double>;
  const FrictionCoefficients &lo = robot::kModelErrorBounds.friction_lo, &hi = robot::kModelErrorBounds.friction_hi;
  for (int i = 0; i < kDof; ++i) {
    EXPECT_GE(k.vis_half[i], 0.0) << i;
    EXPECT_GE(k.sti_half[i], 0.0) << i;
    EXPECT_NEAR(k.vis_mid[i] - k.vis_half[i], lo.vis[i], 1e-12) << i;
    EXPECT_NEAR(k.vis_mid[i] + k.vis_half[i], hi.vis[i], 1e-12) << i;
    EXPECT_NEAR(k.sti_mid[i] - k.sti_half[i], lo.sti[i], 1e-12) << i;
    EXPECT_NEAR(k.sti_mid[i] + k.sti_half[i], hi.sti[i], 1e-12) << i;
    EXPECT_NEAR(std::abs(lo.vis[i] - k.vis_mid[i]) + k.vis_half[i], hi.vis[i] - lo.vis[i], 1e-12) << i;
    EXPECT_NEAR(std::abs(hi.sti[i] - k.sti_mid[i]) + k.sti_half[i], hi.sti[i] - lo.sti[i], 1e-12) << i;
    EXPECT_LE(k.cou_lo[i], k.cou_hi[i]) << i;
    EXPECT_NEAR(k.static_band[i], hi.cou[i] + hi.sti[i], 1e-12) << i;
    EXPECT_LT(k.static_lo[i], k.static_band[i]) << i;  // the least breakaway, over the margin, below the top
  }
}

TEST(ResidualConstants, EachFilterIsAStableFirstOrderOneAtTheTickAndOverATurn) {
  const ResidualConstants<double>& k = kResidualConstants<double>;
  const int n = params::kResidualTurnEvery;
  for (int i = 0; i < kDof; ++i) {
    EXPECT_GT(k.keep[i], 0.0) << i;
    EXPECT_LT(k.keep[i], 1.0) << i;
    EXPECT_GT(k.turn_keep[i], 0.0) << i;
    EXPECT_LT(k.turn_keep[i], k.keep[i]) << i;
    EXPECT_NEAR(k.turn_gain_dt[i] + k.turn_keep[i], 1.0, 1e-15) << i;  // what a turn takes and keeps
    // (1 - K dt)^n = 1 - n K dt + n (n - 1) / 2 (K dt)^2 - ...: a turn's step is n ticks' to first order.
    const double x = k.gain[i] * params::kDt;
    EXPECT_NEAR(std::pow(k.keep[i], n), k.turn_keep[i], n * (n - 1) / 2.0 * x * x * (1 + 1e-9)) << i;
    EXPECT_GT(std::pow(k.keep[i], n), k.turn_keep[i]) << i;
    EXPECT_LT(k.slow_dt, k.turn_gain_dt[i]) << i;  // the slow filter: slower than the residual's
  }
  EXPECT_GT(k.slow_dt, 0.0);
}

template <class S>
void expect_constants_of_double(double resolution, double relative) {
  const ResidualConstants<S>& k = kResidualConstants<S>;
  const ResidualConstants<double>& d = kResidualConstants<double>;
  const auto near = [&](S v, double want) {
    return std::abs(static_cast<double>(v) - want) <= resolution + relative * std::abs(want);
  };
  for (int i = 0; i < kDof; ++i) {
    EXPECT_TRUE(near(k.keep[i], d.keep[i])) << i;
    EXPECT_TRUE(near(k.turn_keep[i], d.turn_keep[i])) << i;
    EXPECT_TRUE(near(k.gain[i], d.gain[i])) << i;
    EXPECT_TRUE(near(k.static_band[i], d.static_band[i])) << i;
    EXPECT_TRUE(near(k.offset[i], d.offset[i])) << i;
    EXPECT_TRUE(near(k.armature_delta[i], d.armature_delta[i])) << i;
    EXPECT_TRUE(near(k.peak_margin[i], d.peak_margin[i])) << i;
  }
  EXPECT_TRUE(near(k.margin, d.margin));
  EXPECT_TRUE(near(k.slow_dt, d.slow_dt));
}

TEST(ResidualConstants, InFloatAndFixedPointTheyAreTheDoublesToTheirResolution) {
  expect_constants_of_double<float>(0, 6e-8);
  expect_constants_of_double<Fixed>(0.5 / (1 << 19), 0);  // half an LSB of Q12.19
}

}  // namespace
