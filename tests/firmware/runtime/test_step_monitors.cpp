// The step's checks (osc/runtime/step_monitors.hpp), each alone against its rule written out from
// docs/safety.md and params::, in double, float and fixed point: the saturation count, the oscillation
// monitor's half-rate amplitude, the tracking limits, the friction estimates' band, and the position cross-check of the
// pots against the encoders.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "monitor_fixtures.hpp"
#include "osc/runtime/step_monitors.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST(Saturation, ConsecutiveClippedTicks) {
  SaturationMonitor m;
  m.reset();
  for (int k = 1; k < params::kSaturationTicks; ++k) ASSERT_EQ(m.check(3, true), 0u) << k;
  EXPECT_EQ(m.check(3, false), 0u);  // one unclipped tick starts the count again
  for (int k = 1; k < params::kSaturationTicks; ++k) ASSERT_EQ(m.check(3, true), 0u) << k;
  EXPECT_EQ(m.check(3, true), kFaultSaturation);
  EXPECT_EQ(m.check(2, true), 0u);  // per joint
}

/// The oscillation monitor fed a joint's codes c(k) (every other joint 0); the first step that faults (-1: none).
template <class Codes>
int first_unstable(OscillationMonitor& m, int joint, int steps, Codes c) {
  std::int32_t codes[kDof] = {};
  for (int k = 0; k < steps; ++k) {
    codes[joint] = static_cast<std::int32_t>(c(k));
    const std::uint32_t f = m.check(codes);
    if (f != 0) {
      EXPECT_EQ(f, kFaultUnstable);
      return k;
    }
  }
  return -1;
}

/// Its rule, from step_monitors.hpp and params::: a half-rate oscillation of amplitude a is found when a exceeds
/// kOscillationLimit of the DAC's full scale (its filter settled: the level after n steps is 1 - (1 - 2^-shift)^n of
/// the amplitude's); smooth commands and white noise of that amplitude are not.
TEST(Oscillation, AHalfRateAmplitudeBeyondItsLimit) {
  const double limit = params::kOscillationLimit * kDacMaxCode;
  const double step = 1.0 / (1 << params::kOscillationShift);
  OscillationMonitor m;
  // Held just under the limit for 10 000 steps: none; just over: found once the filter reaches the limit.
  m.reset();
  EXPECT_EQ(first_unstable(m, 2, 10000, [&](int k) { return 1000 + (k % 2 ? -0.97 : 0.97) * limit; }), -1);
  EXPECT_NEAR(m.ratio(2), 0.97, 0.01);
  m.reset();
  const int found = first_unstable(m, 2, 10000, [&](int k) { return -500 + (k % 2 ? -1.5 : 1.5) * limit; });
  // The level reaches 1/1.5 of its final value after n steps: (1 - step)^n = 1/3 (the first step only primes).
  const double expected = std::log(1.0 / 3) / std::log(1 - step) + 1;
  EXPECT_NEAR(found, expected, 1.5);
  // Per joint: the others' zero codes are no oscillation; one tick without a step (reset) restarts it.
  for (int j = 0; j < kDof; ++j) EXPECT_LT(m.ratio(j), j == 2 ? 2.0 : 1e-9) << j;
  m.reset();
  EXPECT_EQ(m.ratio(2), 0);
  // A smooth command: a torque ramp over 50 ms to full scale, then a sine at 20 Hz of the full scale.
  m.reset();
  EXPECT_EQ(first_unstable(m, 0, 5000,
                           [&](int k) {
                             return k < 50 ? k / 50.0 * kDacMaxCode
                                           : kDacMaxCode * std::cos(2 * M_PI * 20 * (k - 50) / 1000.0);
                           }),
            -1);
  EXPECT_LT(m.ratio(0), 0.2);
  // White noise over the limit's whole amplitude, for 100 000 steps: its half-rate share averages out.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-limit, limit);
  m.reset();
  double peak = 0;
  std::int32_t codes[kDof] = {};
  for (int k = 0; k < 100000; ++k) {
    codes[5] = static_cast<std::int32_t>(std::lround(u(rng)));
    ASSERT_EQ(m.check(codes), 0u) << k;
    peak = std::max(peak, m.ratio(5));
  }
  EXPECT_LT(peak, 0.5);
  // A loop lost: an oscillation from one code growing 2 % a step is found where its amplitude passes the limit
  // (the filter lags a growing one by about 2^shift steps' growth).
  m.reset();
  const int grown = first_unstable(m, 4, 20000, [](int k) { return (k % 2 ? -1 : 1) * std::pow(1.02, k); });
  const int at_limit = static_cast<int>(std::ceil(std::log(limit) / std::log(1.02)));
  EXPECT_GE(grown, at_limit);
  EXPECT_LE(grown, at_limit + 40);
}

TYPED_TEST(Monitors, TrackingLimits) {
  using S = TypeParam;
  const double lp = params::kTrackingLimitPosition, lo = params::kTrackingLimitOrientation;
  auto check = [](double x, double y, double z, double a, double b, double c) {
    Vec6<S> e;
    e << lit<S>(x), lit<S>(y), lit<S>(z), lit<S>(a), lit<S>(b), lit<S>(c);
    return TrackingMonitor<S>::check(e);
  };
  EXPECT_EQ(check(0, 0, 0, 0, 0, 0), 0u);
  // The translation's norm: 0.99 lp along a diagonal is in, 1.01 lp out.
  const double d = 1 / std::sqrt(3.0);
  EXPECT_EQ(check(0.99 * lp * d, -0.99 * lp * d, 0.99 * lp * d, 0, 0, 0), 0u);
  EXPECT_EQ(check(1.01 * lp * d, -1.01 * lp * d, 1.01 * lp * d, 0, 0, 0), kFaultTracking);
  // Each orientation component alone.
  for (int i = 3; i < 6; ++i) {
    double v[6] = {0, 0, 0, 0, 0, 0};
    v[i] = -0.99 * lo;
    EXPECT_EQ(check(v[0], v[1], v[2], v[3], v[4], v[5]), 0u) << i;
    v[i] = -1.01 * lo;
    EXPECT_EQ(check(v[0], v[1], v[2], v[3], v[4], v[5]), kFaultTracking) << i;
  }
}

TYPED_TEST(Monitors, ThetaBand) {
  using S = TypeParam;
  using Theta = decltype(Gains<S>::paper().theta_max);
  const Theta mx = Gains<S>::paper().theta_max;
  const double band = params::kThetaFaultBand;
  Theta th = mx;
  EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), 0u);
  for (int i : {0, 7, 17}) {
    th = mx;
    th(i) = lit<S>((1 + band) * params::kThetaMax[i] * 0.99);
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), 0u) << i;
    th(i) = lit<S>((1 + band) * params::kThetaMax[i] * 1.01);
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), kFaultThetaBounds) << i;
    th(i) = lit<S>(-band * params::kThetaMax[i] * 0.99);
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), 0u) << i;
    th(i) = lit<S>(-band * params::kThetaMax[i] * 1.01);
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), kFaultThetaBounds) << i;
    // The control task's check a part at a time: the coefficient's own part finds it, no other.
    for (int p = 0; p < ThetaBandMonitor<S>::kParts; ++p)
      EXPECT_EQ(ThetaBandMonitor<S>::check_part(th, mx, p),
                p == i / ThetaBandMonitor<S>::kPart ? static_cast<std::uint32_t>(kFaultThetaBounds) : 0u)
          << i << " part " << p;
  }
  if constexpr (std::numeric_limits<S>::has_quiet_NaN) {
    th = mx;
    th(4) = std::numeric_limits<S>::quiet_NaN();
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), kFaultThetaBounds);
  }
}

// ------------------------------------------------------------------ the position cross-check

/// A potentiometer code of joint i at angle q (the plant's pot_scale, rounded and clamped).
std::uint16_t pot_code(int i, double q, double offset_codes = 0) {
  const auto& d = robot::kDriveTrain;
  const double full = (1 << d.pot_bits) - 1;
  const double x = std::round((q - d.pot_min[i]) / (d.pot_max[i] - d.pot_min[i]) * full + offset_codes);
  return static_cast<std::uint16_t>(x < 0 ? 0 : x > full ? full : x);
}

TYPED_TEST(Monitors, PotentiometerAngleIsTheSpanOverTheCodes) {
  using S = TypeParam;
  const auto& d = robot::kDriveTrain;
  for (int i = 0; i < kDof; ++i)
    for (int code : {0, 1, 1000, 2048, 4094, 4095}) {
      const double want = d.pot_min[i] + code * (d.pot_max[i] - d.pot_min[i]) / 4095.0;
      const double got = static_cast<double>(PositionCrossCheck<S>::pot_angle(i, static_cast<std::uint16_t>(code)));
      EXPECT_NEAR(got, want, 4e-6) << "joint " << i + 1 << " code " << code;  // a few Q12.19 resolutions
    }
}

/// Healthy: the pots follow the joints (with an offset and a noise of 4 codes rms, the band's design
/// value) while every joint sweeps its range back and forth: no fault, and the filtered difference
/// stays within three quarters of its band (measured 0.62 on J5, the narrowest: the noise term is
/// about 6 sigma of the filtered difference, the worst of 1 300 correlated updates about 3.5 sigma). Stuck: joint j's
/// encoder freezes mid-sweep at 0.2 rad/s: the fault comes once the joint has moved about its band past the filter's
/// lag, and only joint j's ratio grows.
TYPED_TEST(Monitors, PositionCrossCheckIgnoresNoiseAndCatchesAStuckEncoder) {
  using S = TypeParam;
  constexpr double kOffset[kDof] = {12, -8, 15, -20, 6, -10};
  const Vec6<double> q0 = joint_vector<double>(robot::kQStart);
  const double speed = 0.2;  // rad/s
  for (int stuck = -1; stuck < kDof; ++stuck) {
    PositionCrossCheck<S> m;
    m.reset();
    std::mt19937 rng(7 + stuck);
    std::normal_distribution<double> noise(0, 4);
    double worst = 0;
    int fault_tick = -1;
    const int t_stuck = 1000;
    Vec6<double> q_stuck = q0;
    for (int t = 0; t < 4000 && fault_tick < 0; ++t) {
      Vec6<double> q;
      for (int i = 0; i < kDof; ++i) q(i) = q0(i) + 0.3 * std::sin(speed / 0.3 * t * 1e-3 + i);  // peak 0.2 rad/s
      if (t == t_stuck) q_stuck = q;
      Vec6<double> q_enc = q;
      if (stuck >= 0 && t >= t_stuck) q_enc(stuck) = q_stuck(stuck);
      std::uint16_t codes[kDof];
      for (int i = 0; i < kDof; ++i) codes[i] = pot_code(i, q(i), kOffset[i] + noise(rng));
      if (m.check(codes, true, q_enc.cast<S>()) & kFaultPositionMismatch) fault_tick = t;
      for (int i = 0; i < kDof; ++i)
        if (i != stuck) worst = std::max(worst, static_cast<double>(m.ratio(i)));
    }
    EXPECT_LT(worst, 0.75) << "healthy joints' filtered difference, a fraction of the band (stuck " << stuck << ")";
    if (stuck < 0) {
      EXPECT_EQ(fault_tick, -1);
      continue;
    }
    ASSERT_GE(fault_tick, t_stuck) << "joint " << stuck + 1 << " not detected";
    // Detected once the joint moved its band (through the filter's lag and the qualifying updates).
    double moved = 0;
    for (int t = t_stuck; t <= fault_tick; ++t)
      moved = std::max(moved, std::fabs(0.3 * std::sin(speed / 0.3 * t * 1e-3 + stuck) - (q_stuck(stuck) - q0(stuck))));
    EXPECT_GT(moved, params::kPositionBand[stuck]) << "joint " << stuck + 1;
    EXPECT_LT(moved, params::kPositionBand[stuck] + 0.2 * 0.12) << "joint " << stuck + 1 << ": within 120 ms of lag";
  }
}

/// A pot sample that is not valid (no complete conversion) is skipped, and a reset learns the
/// reference again (a cleared fault).
TYPED_TEST(Monitors, PositionCrossCheckSkipsInvalidSamplesAndRelearnsAfterAReset) {
  using S = TypeParam;
  const Vec6<double> q0 = joint_vector<double>(robot::kQStart);
  PositionCrossCheck<S> m;
  m.reset();
  std::uint16_t codes[kDof];
  for (int i = 0; i < kDof; ++i) codes[i] = pot_code(i, q0(i));
  for (int t = 0; t < 3000; ++t) EXPECT_EQ(m.check(codes, true, q0.cast<S>()), 0u);
  // The encoders now 0.1 rad off on every joint: a fault, unless the samples are invalid.
  Vec6<double> off = q0;
  off.array() += 0.1;
  for (int t = 0; t < 3000; ++t) EXPECT_EQ(m.check(codes, false, off.cast<S>()), 0u);
  std::uint32_t f = 0;
  for (int t = 0; t < 300; ++t) f |= m.check(codes, true, off.cast<S>());
  EXPECT_NE(f & kFaultPositionMismatch, 0u);
  m.reset();
  f = 0;
  for (int t = 0; t < 3000; ++t) f |= m.check(codes, true, off.cast<S>());
  EXPECT_EQ(f, 0u) << "after a reset the new difference is the reference";
}

}  // namespace
