// The drive check (DriveMonitor; docs/safety.md, "The drive check"): each amplifier's current, read
// back through its current monitor (hal::CurrentHal), against the DAC code it was given; a test dither
// on the codes that a frozen DAC or amplifier cannot follow; the amplifiers' fault lines. Run by
// control_tick() (osc/runtime/control_task.hpp) on a HAL with current readback, before the residual
// monitor, which then names what is left a collision (ResidualMonitor::classify). In integers: the
// codes' scale, whatever the scalar.
#pragma once

#include <cstdint>

#include "osc/control/faults.hpp"
#include "osc/control/params.hpp"
#include "osc/runtime/encoder_monitors.hpp"
#include "osc/runtime/io.hpp"

namespace osc {

/// The check's constants in DAC codes (the amplifiers' command scale), from the arm's stated bounds
/// (robot::kModelErrorBounds: the amplifiers; robot::kDriveTrain.current: the monitors).
struct DriveCheckConstants {
  std::int32_t adc_q8;       // one ADC code in DAC codes, times 256
  std::int32_t adc_max;      // the ADC's largest code magnitude, 2^(bits-1) - 1 (a reading there is off its scale)
  std::int32_t floor;        // the threshold's constant part [DAC codes]
  std::int32_t share;        // its share of the command's size, times 2^16
  std::int32_t limit[kDof];  // each amplifier's current limit (kDriveTrain.motor_torque_limit) [DAC codes]
};

/// x >= 0 to the nearest whole number (set-up arithmetic, compile time).
constexpr std::int32_t nearest(double x) {
  const auto n = static_cast<std::int32_t>(x);
  return x - n >= 0.5 ? n + 1 : n;
}

/// floor = kDriveMargin (amplifier offset + monitor offset + 3 sigma of the monitor's noise + half its
/// code); share = kDriveMargin (amplifier gain + monitor gain): 1.6 % of full scale and 8 % of the command
/// with the PUMA's and the UR5e's bounds (2 % and 2 %; 0.2 % and 0.2 %; 2 codes of 12 bits over 1.25 full scale).
constexpr DriveCheckConstants drive_check_constants() {
  const CurrentMonitor& m = robot::kDriveTrain.current;
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  DriveCheckConstants k{};
  if (m.bits <= 0) return k;
  const auto adc_max = static_cast<double>(current_max_code(m));
  const double lsb = m.range / adc_max;  // one ADC code, relative to the DAC's full scale
  const double floor = params::kDriveMargin * (b.amp_offset + m.offset + 3 * m.noise * lsb + 0.5 * lsb);
  const double share = params::kDriveMargin * (b.amp_gain + m.gain);
  const auto dac = static_cast<double>(kDacMaxCode);
  k.adc_q8 = nearest(lsb * dac * 256);
  k.adc_max = static_cast<std::int32_t>(adc_max);
  k.floor = nearest(floor * dac);
  k.share = nearest(share * 65536);
  for (int c = 0; c < kDof; ++c) {
    const double amp = robot::kDriveTrain.motor_torque_limit[c] * abs_of(robot::kArm.links[c].gear_ratio);
    const double fs = robot::kDrives.torque_limit[c];
    k.limit[c] = static_cast<std::int32_t>((amp < fs ? amp / fs : 1.0) * dac);
  }
  return k;
}
inline constexpr DriveCheckConstants kDriveCheck = drive_check_constants();

/// drive_fault, current_sense: per amplifier channel, every tick with a current sample.
///  - The tracking check: the current read at this tick's start, in DAC codes, lies between the last two
///    codes written (the amplifier's current loop, at most robot::kModelErrorBounds.amp_lag, moves from the
///    one before toward the last; it settles within a period) within floor + share |code|. Beyond, for
///    params::kDriveQualifyTicks readings in a row: drive_fault (a DAC at zero or full scale, an amplifier
///    off, a DAC frozen once the command has left its value).
///  - The dither check: the codes carry a square wave of +-dither codes (params::kDitherAmplitude of full
///    scale, params::kDitherHalfPeriod ticks a sign; ControlTask::dither_sign); the reading's distance outside
///    its codes' range less its mean, times their sign, filtered over 2^params::kDitherWindowShift readings
///    (those not right after a change of sign), is about 0 on a drive that follows and -dither on one that does
///    not, whether its command stands or drifts away from a frozen code.
///    Below -dither / 2: drive_fault, at rest as in motion (a DAC or an amplifier frozen at any value).
///  - The fault lines: an amplifier that reports a fault: drive_fault at once.
///  - The monitor itself: a reading at the end of the ADC's span (beyond the largest current an amplifier
///    can give, 1 / range of it): current_sense.
/// A channel whose reading is off by more than half its threshold, or whose dither fades below three
/// quarters, is a suspect: the residual monitor names a residual on its joint drive_fault, not collision.
struct DriveMonitor {
  // Per channel, from the codes the last two ticks wrote (written()), each within its amplifier's current limit:
  std::int32_t last[kDof];          // the last code (the amplifier has had it since)
  std::int32_t lo[kDof], hi[kDof];  // the two codes' range, where the current must lie
  std::int32_t threshold[kDof];     // floor + share max(|lo|, |hi|)
  std::int32_t distance[kDof];      // the last checked reading's distance outside [lo, hi] [DAC codes]
  std::int32_t dither[kDof];        // 2^kDitherShift times the filtered sign-weighted difference [DAC codes]
  std::int32_t base[kDof];          // 2^kDitherShift times the filtered distance outside the range [DAC codes]
  std::int8_t sign_last;            // the dither's sign in the last codes (0: none)
  std::uint8_t dithered;            // bit c: the next reading of channel c takes part in the dither check
  std::uint8_t writes;              // ticks whose codes are on record (2: the check runs)
  std::uint8_t over[kDof];          // consecutive readings beyond the threshold
  std::uint8_t suspect;             // bit c: channel c is a suspect (see the type's comment)
  std::uint32_t detected;           // the first fault's bit (0: none)
  std::int8_t channel;              // its channel, -1 none
  std::uint64_t detected_tick;
  std::int32_t amplitude;           // the dither's amplitude in use [DAC codes] (0: off)
  std::uint16_t peak[kDof];         // the largest |error| / threshold seen, times 1000 (the false-alarm margin)
  std::uint16_t dither_peak[kDof];  // the largest fade of a dither in use, -filtered / amplitude, times 1000

  static constexpr int kDitherShift = params::kDitherWindowShift;

  void reset() {
    for (int c = 0; c < kDof; ++c) {
      last[c] = lo[c] = hi[c] = dither[c] = base[c] = distance[c] = 0;
      threshold[c] = kDriveCheck.floor;
      over[c] = 0, peak[c] = dither_peak[c] = 0;
    }
    sign_last = 0;
    dithered = 0;
    writes = 0;
    suspect = 0;
    detected = 0;
    channel = -1;
    detected_tick = 0;
    amplitude = 0;
  }
  /// The codes this tick wrote, and the dither's sign in them (0: none): after the DAC write. The next reading
  /// lies between them and the last ones (the amplifier's current loop moves from one toward the other and
  /// settles within a period); it takes part in the dither check where both had the same sign and both codes
  /// with their dither lie within the amplifier's current limit (the reading after a change of sign carries
  /// the loop's lag behind its step of two amplitudes, up to 45 % of it: docs/safety.md; the others only a
  /// period's decay of that, e^-2 of it).
  void written(const std::int32_t codes[kDof], std::int8_t sign) {
    const DriveCheckConstants& k = kDriveCheck;
    const bool same = sign != 0 && sign == sign_last && amplitude > 0;
    dithered = 0;
    for (int c = 0; c < kDof; ++c) {
      const std::int32_t l = k.limit[c], u = codes[c], b = last[c];
      const std::int32_t a = within(u, l);
      const std::int32_t x = a < b ? a : b, y = a < b ? b : a;
      lo[c] = x, hi[c] = y, last[c] = a;
      threshold[c] = k.floor + static_cast<std::int32_t>((static_cast<std::uint32_t>(y > -x ? y : -x) * k.share) >> 16);
      const std::int32_t room = l - amplitude;
      if (same && y < room && x > -room) dithered |= static_cast<std::uint8_t>(1u << c);
    }
    sign_last = sign;
    if (writes < 2) ++writes;
  }
  /// This tick's reading (valid: the HAL gave one) and fault lines (bit c: amplifier c): the fault bits.
  std::uint32_t check(const std::int16_t adc[kDof], bool valid, std::uint32_t lines, std::uint64_t tick) {
    std::uint32_t faults = 0;
    int at = -1;
    if (lines != 0)
      for (int c = kDof - 1; c >= 0; --c)
        if (lines >> c & 1u) faults = kFaultDriveFault, at = c;
    suspect = 0;
    if (valid && writes >= 2)
      for (int c = 0; c < kDof; ++c) {
        const std::uint32_t f = check_channel(c, adc[c]);
        if (f != 0 && faults == 0) faults = f, at = c;
      }
    if (faults != 0 && detected == 0) detected = faults, channel = static_cast<std::int8_t>(at), detected_tick = tick;
    return faults;
  }
  /// Channel c's reading against its codes (check()).
  std::uint32_t check_channel(int c, std::int32_t reading) {
    const DriveCheckConstants& k = kDriveCheck;
    if (reading >= k.adc_max || reading <= -k.adc_max) {
      suspect |= static_cast<std::uint8_t>(1u << c);
      return kFaultCurrentSense;
    }
    const std::int32_t m = (reading * k.adc_q8) >> 8;  // in DAC codes
    const std::int32_t above = m - hi[c], below = lo[c] - m;
    const std::int32_t error = above > 0 ? above : (below > 0 ? below : 0);
    const std::int32_t th = threshold[c];
    distance[c] = error;
    track_peak(peak[c], error, th);
    if (2 * error > th) suspect |= static_cast<std::uint8_t>(1u << c);
    over[c] = qualify(over[c], error > th);
    std::uint32_t f = over[c] >= params::kDriveQualifyTicks ? static_cast<std::uint32_t>(kFaultDriveFault) : 0u;
    if (dithered >> c & 1u) {
      // The reading's distance outside its codes' range, signed (outside the range, not from the last code: a
      // drive's lag behind the controller's own steps, which answer the dither on a light joint, stays inside
      // it), less its mean over the window (base: 2^s times it, of the distance within the tracking threshold,
      // beyond which the tracking check has it): a DAC frozen while the command drifts away from its code reads
      // a distance that grows, and what the dither adds to it alternates about that growth.
      const std::int32_t d = above > 0 ? above : (below > 0 ? -below : 0);
      std::int32_t& b = base[c];
      b += within(d, th) - (b >> kDitherShift);
      // 2^s y += s e - y: the filter of the sign-weighted difference e, its level 2^s times the mean; e within +-2
      // amplitudes (a glitch adds at most that).
      const std::int32_t ec = within(d - (b >> kDitherShift), 2 * amplitude);
      std::int32_t& y = dither[c];
      y += (sign_last > 0 ? ec : -ec) - (y >> kDitherShift);
      const std::int32_t fade = -y, level = amplitude << kDitherShift;  // 2^s times the missing share
      track_peak(dither_peak[c], fade, level);
      if (4 * fade > 3 * level) suspect |= static_cast<std::uint8_t>(1u << c);
      if (2 * fade > level) f = kFaultDriveFault;
    }
    return f;
  }
  /// The dither runs: its filters start from a drive that follows (a torque-on, a change of amplitude).
  void start_dither(std::int32_t codes) {
    amplitude = codes;
    for (int c = 0; c < kDof; ++c) dither[c] = base[c] = 0;
  }

 private:
  /// x limited to [-t, t] (t >= 0).
  static constexpr std::int32_t within(std::int32_t x, std::int32_t t) { return x > t ? t : (x < -t ? -t : x); }
  /// peak = max(peak, 1000 value / limit): compared in 32 bits (value < 2^16, limit < 2^15), divided only for a
  /// new peak.
  static void track_peak(std::uint16_t& peak, std::int32_t value, std::int32_t limit) {
    if (value <= 0 ||
        static_cast<std::uint32_t>(value) * 1000u <= std::uint32_t{peak} * static_cast<std::uint32_t>(limit))
      return;
    const std::uint32_t r = static_cast<std::uint32_t>(value) * 1000u / static_cast<std::uint32_t>(limit);
    peak = r > 65535u ? std::uint16_t{65535} : static_cast<std::uint16_t>(r);
  }
};

/// Whether a suspect channel (bit c of `suspect`) drives joint i: its own, or one whose torque the wrist
/// coupling adds to it (C^-T: motor c reaches joint i where q_c = ... + C_ci e_i). The residual monitor's
/// isolation by order (ResidualMonitor::classify): a residual on a suspect's joint is a drive_fault.
template <class IoMapT>
bool drive_suspected(std::uint8_t suspect, int i, const IoMapT& io) {
  bool s = (suspect >> i & 1u) != 0;
  for (int k = 0; k < io.terms; ++k)
    if (io.col[k] == i && (suspect >> io.row[k] & 1u) != 0) s = true;
  return s;
}

}  // namespace osc
