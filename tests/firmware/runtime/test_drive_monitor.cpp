// The drive check (osc/runtime/drive_monitor.hpp) alone, against an amplifier and a current monitor written
// out here from the stated bounds: a first-order current loop (robot::kModelErrorBounds.amp_lag at most), the
// DAC update some time after the sample, gain errors, offsets, the ADC's noise and rounding. Its constants
// against their derivation, a healthy drive within half its thresholds, each fault it must find (and when),
// what it must not take for one (a glitch, an amplifier at its current limit).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "osc/runtime/drive_monitor.hpp"

using namespace osc;

namespace {

constexpr double kFullScale = static_cast<double>(kDacMaxCode);

TEST(DriveCheck, ConstantsFollowTheStatedBounds) {
  const CurrentMonitor& m = robot::kDriveTrain.current;
  ASSERT_GT(m.bits, 0) << "the arm declares its current monitors";
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  const double top = std::ldexp(1.0, m.bits - 1) - 1, lsb = m.range / top;
  const double floor = params::kDriveMargin * (b.amp_offset + m.offset + 3 * m.noise * lsb + 0.5 * lsb);
  EXPECT_NEAR(kDriveCheck.floor, floor * kFullScale, 1.0);
  EXPECT_NEAR(kDriveCheck.share / 65536.0, params::kDriveMargin * (b.amp_gain + m.gain), 1e-4);
  EXPECT_NEAR(kDriveCheck.adc_q8 / 256.0, lsb * kFullScale, 1.0 / 256);
  EXPECT_EQ(kDriveCheck.adc_max, static_cast<std::int32_t>(top));
  // The estimate (drives-and-identification.md section 3): about 2 % of full scale and 6 % of the command.
  EXPECT_GT(kDriveCheck.floor, 0.01 * kFullScale);
  EXPECT_LT(kDriveCheck.floor, 0.025 * kFullScale);
  for (int c = 0; c < kDof; ++c) {
    const double amp = robot::kDriveTrain.motor_torque_limit[c] * std::abs(robot::kArm.links[c].gear_ratio);
    EXPECT_NEAR(kDriveCheck.limit[c], std::min(1.0, amp / robot::kDrives.torque_limit[c]) * kFullScale, 1.0) << c;
  }
}

/// An amplifier and its current monitor, per channel: the current follows the DAC code through a first-order
/// loop of time constant lag; the code of a tick arrives `delay` after its sample; the monitor reads the current
/// with a gain error, an offset and noise on the ADC's scale.
struct Drive {
  double lag = 0.5e-3, delay = 0.6e-3, gain = 0.02, offset = 0.002, noise = 2;
  double current[kDof] = {};  // [DAC codes]
  std::int32_t code[kDof] = {};
  double limit[kDof];
  bool frozen[kDof] = {}, zero[kDof] = {};
  std::mt19937 rng{7};
  std::normal_distribution<double> gauss{0.0, 1.0};
  Drive() {
    for (int c = 0; c < kDof; ++c) limit[c] = kDriveCheck.limit[c];
  }
  /// The current of each channel over one period: the old code for `delay`, then the new one.
  void period(const std::int32_t codes[kDof]) {
    const double dt = params::kDt;
    for (int c = 0; c < kDof; ++c) {
      const auto target = [&](std::int32_t k) {
        const double u = zero[c] ? 0.0 : static_cast<double>(k);
        return std::max(-limit[c], std::min(limit[c], u));
      };
      const double a = lag > 0 ? std::exp(-delay / lag) : 0, b = lag > 0 ? std::exp(-(dt - delay) / lag) : 0;
      current[c] = target(code[c]) + (current[c] - target(code[c])) * a;
      if (!frozen[c]) code[c] = codes[c];
      current[c] = target(code[c]) + (current[c] - target(code[c])) * b;
    }
  }
  void read(std::int16_t adc[kDof]) {
    const CurrentMonitor& m = robot::kDriveTrain.current;
    const double top = std::ldexp(1.0, m.bits - 1) - 1;
    for (int c = 0; c < kDof; ++c) {
      const double x = ((1 + gain) * current[c] / kFullScale + offset) / m.range * top + noise * gauss(rng);
      adc[c] = static_cast<std::int16_t>(std::max(-top, std::min(top, std::round(x))));
    }
  }
};

/// A task's side of the check: the codes (a command plus the dither) written each tick, the readings checked.
struct Loop {
  DriveMonitor m;
  Drive drive;
  std::uint64_t tick = 0;
  bool dither = true;
  Loop() {
    m.reset();
    m.start_dither(static_cast<std::int32_t>(params::kDitherAmplitude * kFullScale + 0.5));
  }
  /// One tick: check the reading, then write command(k) plus the dither; the fault bits.
  template <class Command>
  std::uint32_t step(Command command, std::uint32_t lines = 0) {
    std::int16_t adc[kDof];
    drive.read(adc);
    const std::uint32_t f = m.check(adc, true, lines, tick);
    const std::int8_t s = dither ? ((tick / params::kDitherHalfPeriod) % 2 == 0 ? 1 : -1) : 0;
    std::int32_t codes[kDof];
    for (int c = 0; c < kDof; ++c)
      codes[c] = static_cast<std::int32_t>(std::lround(command(c, tick) + s * m.amplitude));
    m.written(codes, s);
    drive.period(codes);
    ++tick;
    return f;
  }
};

/// A smooth command on every channel: a slow sine of 40 % of full scale and a faster one of 10 %, ramped in
/// over 0.1 s as an enable ramps the torque in (params::kEnableRamp).
double smooth(int c, std::uint64_t k) {
  const double t = static_cast<double>(k) * params::kDt, ramp = t < 0.1 ? t / 0.1 : 1.0;
  return ramp * kFullScale * (0.4 * std::sin(0.7 * t + c) + 0.1 * std::sin(9.0 * t + 2 * c));
}

TEST(DriveCheck, AHealthyDriveStaysWithinHalfItsThresholds) {
  // The bounds' corners: the slowest loop with the latest update, none; gains and offsets of either sign.
  for (const double lag : {0.0, 0.25e-3, 0.5e-3})
    for (const double gain : {-0.02, 0.02})
      for (const double offset : {-0.002, 0.002}) {
        Loop l;
        l.drive.lag = lag, l.drive.gain = gain, l.drive.offset = offset;
        for (int k = 0; k < 20000; ++k)
          ASSERT_EQ(l.step(smooth), 0u) << lag << " " << gain << " " << offset << " " << k;
        for (int c = 0; c < kDof; ++c) {
          EXPECT_LT(l.m.peak[c], 500) << "error / threshold x 1000, channel " << c << " lag " << lag;
          EXPECT_LT(l.m.dither_peak[c], 300) << "the dither's fade x 1000, channel " << c << " lag " << lag;
        }
        EXPECT_EQ(l.m.detected, 0u);
      }
}

/// The ticks from `at` until the check faults (-1: not within `ticks`), with channel 1's drive broken by `fault`.
template <class Fault, class Command>
int ticks_to_fault(Loop& l, int at, int ticks, Fault fault, Command command, std::uint32_t expect = kFaultDriveFault) {
  for (int k = 0; k < at; ++k)
    if (l.step(command) != 0) return -2;
  fault(l);
  for (int k = 0; k < ticks; ++k) {
    const std::uint32_t f = l.step(command);
    if (f != 0) {
      EXPECT_EQ(f, expect);
      EXPECT_EQ(l.m.channel, 1);
      return k;
    }
  }
  return -1;
}

TEST(DriveCheck, ADacAtZeroIsFoundWithin5MsOfACommandOf3PercentOfFullScale) {
  // The reading of the tick the fault comes in still holds the current before it; the next ones are off. At 10 %
  // of full scale every one is beyond the threshold: the third faults (k counts from the tick after the fault's
  // first period). At 3 %, with the dither's -1 % in its codes, the current loop's lag keeps the first within it.
  const auto at = [](double share) {
    return [share](int c, std::uint64_t) { return c == 1 ? share * kFullScale : 0.0; };
  };
  const auto zero = [](Loop& x) { x.drive.zero[1] = true; };
  Loop ten;
  EXPECT_EQ(ticks_to_fault(ten, 200, 50, zero, at(0.10)), params::kDriveQualifyTicks);
  for (const double lag : {0.0, 0.5e-3}) {
    Loop three;
    three.drive.lag = lag;
    const int k = ticks_to_fault(three, 200, 50, zero, at(0.03));
    EXPECT_GE(k, params::kDriveQualifyTicks) << lag;
    EXPECT_LE(k, 4) << "the fault's tick within 5 ms, lag " << lag;
  }
}

TEST(DriveCheck, ADacFrozenAtRestIsFoundByTheDitherWithin30Ms) {
  const auto rest = [](int c, std::uint64_t) { return c == 1 ? 0.2 * kFullScale : 0.0; };
  for (int phase = 0; phase < 2 * params::kDitherHalfPeriod; ++phase) {
    Loop l;
    const int k = ticks_to_fault(
        l, 500 + phase, 100, [](Loop& x) { x.drive.frozen[1] = true; }, rest);
    EXPECT_GE(k, 0) << phase;
    EXPECT_LE(k, 30) << phase;
  }
  // Without the dither a DAC frozen at rest reads as a healthy one: nothing to find.
  Loop off;
  off.dither = false;
  off.m.start_dither(0);
  EXPECT_EQ(ticks_to_fault(
                off, 500, 2000, [](Loop& x) { x.drive.frozen[1] = true; }, rest),
            -1);
}

TEST(DriveCheck, ADacFrozenUnderAMovingCommandIsFoundWithin30Ms) {
  // The command leaves the frozen code slowly: a few dither amplitudes off within the window, below the tracking
  // check's threshold (floor + share of a large code) for tens of ms. The dither check alone must find it: its
  // demodulation does not depend on how far the reading has drifted from the codes. Rates from 0.5 to 2 % of
  // full scale per 10 ms, either way, from a code of 35 % (the threshold there 4.4 amplitudes).
  for (const double rate : {-0.002, -0.001, -0.0005, 0.0005, 0.001, 0.002})
    for (int phase = 0; phase < 2 * params::kDitherHalfPeriod; phase += 3) {
      const int at = 500 + phase;
      const auto ramp = [rate, at](int c, std::uint64_t k) {
        const double moved = k > static_cast<std::uint64_t>(at) ? rate * static_cast<double>(k - at) : 0.0;
        return c == 1 ? (0.35 + moved) * kFullScale : 0.0;
      };
      Loop l;
      const int k = ticks_to_fault(
          l, at, 100, [](Loop& x) { x.drive.frozen[1] = true; }, ramp);
      EXPECT_GE(k, 0) << rate << " " << phase;
      EXPECT_LE(k, 30) << rate << " " << phase;
    }
}

TEST(DriveCheck, AFaultLineIsADriveFaultAtOnce) {
  Loop l;
  for (int k = 0; k < 100; ++k) ASSERT_EQ(l.step(smooth), 0u);
  EXPECT_EQ(l.step(smooth, 1u << 1), kFaultDriveFault);
  EXPECT_EQ(l.m.channel, 1);
}

TEST(DriveCheck, AReadingAtTheEndOfItsScaleIsTheMonitorsFault) {
  Loop l;
  for (int k = 0; k < 100; ++k) ASSERT_EQ(l.step(smooth), 0u);
  std::int16_t adc[kDof];
  l.drive.read(adc);
  adc[1] = static_cast<std::int16_t>(-kDriveCheck.adc_max);
  EXPECT_EQ(l.m.check(adc, true, 0, l.tick), kFaultCurrentSense);
  EXPECT_NE(l.m.suspect & 2u, 0u);
}

TEST(DriveCheck, OneBadConversionIsNoFault) {
  Loop l;
  for (int k = 0; k < 100; ++k) ASSERT_EQ(l.step(smooth), 0u);
  std::int16_t adc[kDof];
  l.drive.read(adc);
  adc[1] = static_cast<std::int16_t>(adc[1] > 0 ? adc[1] - 1000 : adc[1] + 1000);  // half of full scale off
  EXPECT_EQ(l.m.check(adc, true, 0, l.tick), 0u);
  EXPECT_NE(l.m.suspect & 2u, 0u) << "a suspect for the residual monitor's isolation";
  for (int k = 0; k < 2000; ++k) ASSERT_EQ(l.step(smooth), 0u) << k;
}

TEST(DriveCheck, AnAmplifierAtItsCurrentLimitIsNoFault) {
  // A command past channel 1's current limit (where the limit is below the DAC's full scale): the current stays at
  // the limit, the dither does not pass, and neither is a fault.
  int limited = -1;
  for (int c = 0; c < kDof; ++c)
    if (kDriveCheck.limit[c] < 0.9 * kFullScale) limited = c;
  if (limited < 0) GTEST_SKIP() << "every amplifier gives its DAC's full scale";
  Loop l;
  const auto over = [limited](int c, std::uint64_t k) {
    return c == limited ? (k < 500 ? 0.0 : 0.95 * kFullScale) : 0.0;
  };
  for (int k = 0; k < 3000; ++k) ASSERT_EQ(l.step(over), 0u) << k;
}

TEST(DriveCheck, NoReadingNoCheck) {
  DriveMonitor m;
  m.reset();
  std::int16_t adc[kDof] = {};
  const std::int32_t codes[kDof] = {20000, 20000, 20000, 20000, 20000, 20000};
  m.written(codes, 0);
  m.written(codes, 0);
  for (int k = 0; k < 10; ++k) EXPECT_EQ(m.check(adc, false, 0, k), 0u);  // not valid
  EXPECT_EQ(m.check(adc, true, 0, 10), 0u);                               // valid: one reading off
  EXPECT_EQ(m.check(adc, true, 0, 11), 0u);
  EXPECT_EQ(m.check(adc, true, 0, 12), kFaultDriveFault);  // the third in a row
}

}  // namespace
