// The step's checks of the tick's monitors (osc/runtime/monitors.hpp; docs/safety.md), run after the
// control step besides the stuck-encoder and residual monitors, and the output's.
//
//   TrackingMonitor     the tracking error e (36) within params::kTrackingLimit*
//   ThetaBandMonitor    the friction estimates within their band
//   PositionCrossCheck  each joint's potentiometer against its encoders (a HAL with pots)
//   SaturationMonitor   a DAC clipped for params::kSaturationTicks ticks in a row
//   OscillationMonitor  a torque (less its friction compensation) oscillating at half the tick rate
#pragma once

#include <array>
#include <cstdint>

#include "osc/control/controller.hpp"
#include "osc/runtime/encoder_monitors.hpp"
#include "osc/runtime/io.hpp"

namespace osc {

/// tracking: the measured tracking error e (36) beyond params::kTrackingLimitPosition (its
/// translation's norm) or params::kTrackingLimitOrientation (each orientation component).
template <class S>
struct TrackingMonitor {
  static std::uint32_t check(const Vec6<S>& e) {
    static constexpr S kLimitPosition = lit<S>(params::kTrackingLimitPosition);
    static constexpr S kLimitOrientation = lit<S>(params::kTrackingLimitOrientation);
    std::uint32_t faults = 0;
    const S lp = kLimitPosition, lo = kLimitOrientation;
    if (e.template head<3>().squaredNorm() > lp * lp) faults |= kFaultTracking;
    for (int i = 3; i < 6; ++i)
      if (math::abs(e(i)) > lo) faults |= kFaultTracking;
    return faults;
  }
};

/// theta_bounds: a friction estimate outside [-band theta_max, (1 + band) theta_max], band
/// params::kThetaFaultBand (a NaN is outside too). The control task checks a sixth of them a tick
/// (check_part: kPart coefficients, each every 6 ms): the estimates move by a small share
/// of their bound a second, a drift through the band takes minutes (docs/adaptation.md), and a NaN
/// is the step's own non_finite fault at once (the whole check took 240 instructions a tick on the M4F).
template <class S>
struct ThetaBandMonitor {
  static constexpr int kPart = 3;
  static constexpr int kParts = 3 * kDof / kPart;
  template <class Theta>
  static std::uint32_t check(const Theta& theta_hat, const Theta& theta_max) {
    std::uint32_t faults = 0;
    for (int p = 0; p < kParts; ++p) faults |= check_part(theta_hat, theta_max, p);
    return faults;
  }
  /// Coefficients kPart p to kPart (p + 1) - 1.
  template <class Theta>
  static std::uint32_t check_part(const Theta& theta_hat, const Theta& theta_max, int p) {
    static constexpr S kBand = lit<S>(params::kThetaFaultBand);
    const S band = kBand;
    std::uint32_t faults = 0;
    for (int i = kPart * p; i < kPart * (p + 1); ++i) {
      const S th = theta_hat(i), mx = theta_max(i);
      if (!(th >= -band * mx && th <= (S(1) + band) * mx)) faults |= kFaultThetaBounds;
    }
    return faults;
  }
};

/// position_mismatch: each joint's potentiometer against its encoders (docs/safety.md, "The position
/// cross-check"), an independent detector of a stuck or slipping encoder. The difference
/// d = q_pot - q_enc is the potentiometer's offset plus its noise and quantisation, the joint's elastic
/// deflection and backlash: it does not change with the motion. It is low-pass filtered (time
/// constant params::kPositionFilter; params::kPositionJointsPerTick joints a tick, in turn), its
/// settled value kept as the reference (after params::kPositionSettle time constants), and a joint
/// whose filtered difference is further than params::kPositionBand from it for kPositionQualify of its
/// updates in a row is a fault. reset() (a cleared fault, a new start pose) learns it again. A HAL
/// without potentiometers (hal::PositionHal) never runs it.
template <class S>
struct PositionCrossCheck {
  static constexpr int kPerTick = params::kPositionJointsPerTick;
  static constexpr int kUpdateTicks = (kDof + kPerTick - 1) / kPerTick;  // a joint's update period [ticks]
  static constexpr double kAlpha = kUpdateTicks * params::kDt / params::kPositionFilter;
  static constexpr std::uint16_t kSettleUpdates =
      static_cast<std::uint16_t>(params::kPositionSettle * params::kPositionFilter / (kUpdateTicks * params::kDt));
  static_assert(kAlpha > 0 && kAlpha < 0.5, "a joint's update period well inside the filter's time constant");

  Vec6<S> filtered;             // the filtered difference q_pot - q_enc per joint [rad]
  Vec6<S> reference;            // its settled value
  std::uint16_t updates[kDof];  // updates since the reset (saturating at kSettleUpdates)
  std::uint8_t over[kDof];      // consecutive updates beyond the band
  int next;                     // the first joint of the next tick's turn

  void reset() {
    filtered.setZero();
    reference.setZero();
    for (int i = 0; i < kDof; ++i) updates[i] = 0, over[i] = 0;
    next = 0;
  }

  /// One tick: the potentiometer codes (valid: a complete conversion) and the encoder angles q.
  std::uint32_t check(const std::uint16_t codes[kDof], bool valid, const Vec6<S>& q) {
    static constexpr std::array<S, kDof> kBand = lit_array<S>(params::kPositionBand);
    static constexpr S kA = lit<S>(kAlpha);
    const int first = next;
    next = (next + kPerTick) % kDof;
    if (!valid) return 0;
    std::uint32_t faults = 0;
    for (int k = 0; k < kPerTick; ++k) {
      const int i = first + k;
      if (i >= kDof) break;
      const S d = pot_angle(i, codes[i]) - q(i);
      if (updates[i] == 0) {
        filtered(i) = d;
      } else {
        filtered(i) += kA * (d - filtered(i));
      }
      if (updates[i] < kSettleUpdates) {
        if (++updates[i] == kSettleUpdates) reference(i) = filtered(i);
        continue;
      }
      const S e = filtered(i) - reference(i);
      over[i] = qualify(over[i], e > kBand[i] || -e > kBand[i]);
      if (over[i] >= params::kPositionQualify) faults |= kFaultPositionMismatch;
    }
    return faults;
  }
  /// Joint i's angle at a potentiometer code: pot_min + code (pot_max - pot_min) / full scale. In fixed
  /// point from the span's raw value in 64 bits: a Q12.19 scale of about 1.5 mrad a code would be off
  /// by up to half its resolution, 4 mrad over the 4095 codes.
  static S pot_angle(int i, std::uint16_t code) {
    static constexpr std::array<S, kDof> kMin = lit_array<S>(robot::kDriveTrain.pot_min);
    // An arm without potentiometers (pot_bits 0) never reads one; a full scale of 1 keeps this defined.
    static constexpr double kFull =
        robot::kDriveTrain.pot_bits > 0 ? static_cast<double>((1 << robot::kDriveTrain.pot_bits) - 1) : 1.0;
    if constexpr (fixed::is_q_v<S>) {
      static constexpr std::array<std::int64_t, kDof> kSpanRaw = [] {
        std::array<std::int64_t, kDof> a{};
        for (int j = 0; j < kDof; ++j)
          a[j] = lit<S>(robot::kDriveTrain.pot_max[j] - robot::kDriveTrain.pot_min[j]).raw();
        return a;
      }();
      const std::int64_t full = static_cast<std::int64_t>(kFull);
      return kMin[i] + S::from_raw(static_cast<typename S::Raw>((kSpanRaw[i] * code + full / 2) / full));
    } else {
      static constexpr std::array<S, kDof> kScale = [] {
        std::array<S, kDof> a{};
        for (int j = 0; j < kDof; ++j)
          a[j] = lit<S>((robot::kDriveTrain.pot_max[j] - robot::kDriveTrain.pot_min[j]) / kFull);
        return a;
      }();
      return kMin[i] + static_cast<S>(code) * kScale[i];
    }
  }

  /// How far joint i's filtered difference is from its reference, as a fraction of its band (0 until
  /// settled): the healthy runs' margin.
  S ratio(int i) const {
    static constexpr std::array<S, kDof> kInvBand = [] {
      std::array<S, kDof> a{};
      for (int j = 0; j < kDof; ++j) a[j] = lit<S>(1.0 / params::kPositionBand[j]);
      return a;
    }();
    if (updates[i] < kSettleUpdates) return S(0);
    const S e = filtered(i) - reference(i);
    return (e < S(0) ? -e : e) * kInvBand[i];
  }
};

/// saturation: a joint's DAC code clipped for params::kSaturationTicks consecutive ticks.
struct SaturationMonitor {
  std::uint16_t ticks[kDof];  // consecutive clipped ticks per joint

  void reset() {
    for (auto& t : ticks) t = 0;
  }
  std::uint32_t check(int joint, bool clipped) {
    ticks[joint] = clipped ? static_cast<std::uint16_t>(ticks[joint] + 1) : 0;
    return ticks[joint] >= params::kSaturationTicks ? static_cast<std::uint32_t>(kFaultSaturation) : 0u;
  }
};

/// unstable: a joint's torque oscillating at half the tick rate, every other tick up then down, with an amplitude
/// beyond params::kOscillationLimit of its range (the DAC's full scale). That is how a sampled loop is lost: where
/// an axis of Lambda^-1 is so light that the damping's step passes about 2, the torques alternate sign from tick to
/// tick and grow (the path check refuses such paths, `unstable_loop`; a stream or an unchecked motion can still
/// reach one). Without this check the arm shakes at 500 Hz until the residual monitor misreads it as a collision
/// or a DAC clips for 50 ticks (`saturation`), hundreds of milliseconds later. The torque is the step's less its
/// friction compensation, as DAC codes (control_task.hpp's stage_codes): the compensation's sign follows the
/// velocity estimate's and flips from tick to tick about rest (a healthy half-rate share of up to 7.8 % of the
/// range measured with it, 2.2 % without; the gains' tops 13.3 %: docs/safety.md, "The oscillation monitor"). The
/// component: each code's difference from the step before, its sign flipped every other step (a half-rate oscillation
/// of amplitude a gives 2a every tick; a smooth command's differences cancel), averaged by a first-order filter of
/// 2^kOscillationShift steps. Integers: the same in every scalar. A tick without a step restarts it (its zero codes are
/// no oscillation).
struct OscillationMonitor {
  static constexpr int kShift = params::kOscillationShift;
  /// The filter's level at the limit: 2^kShift times the differences' 2a.
  static constexpr std::int32_t kLevelLimit =
      static_cast<std::int32_t>((1 << kShift) * 2.0 * params::kOscillationLimit * kDacMaxCode);
  static_assert((std::int64_t{1} << kShift) * 4 * kDacMaxCode < (std::int64_t{1} << 31),
                "the filter's level fits 32 bits");
  std::int32_t last[kDof];   // the previous step's codes
  std::int32_t level[kDof];  // 2^kShift times the filtered half-rate component of the differences
  bool primed;               // last holds a step's codes
  bool odd;                  // this step's differences are negated

  void reset() {
    for (auto& l : level) l = 0;
    primed = false;
    odd = false;
  }
  std::uint32_t check(const std::int32_t* codes) {
    std::uint32_t faults = 0;
    for (int i = 0; i < kDof; ++i) {
      if (primed) {
        const std::int32_t d = codes[i] - last[i];
        level[i] += (odd ? -d : d) - (level[i] >> kShift);
        if (level[i] > kLevelLimit || level[i] < -kLevelLimit) faults = kFaultUnstable;
      }
      last[i] = codes[i];
    }
    primed = true;
    odd = !odd;
    return faults;
  }
  /// Joint i's half-rate amplitude as a share of its limit (the healthy runs' margin).
  double ratio(int i) const { return (level[i] < 0 ? -level[i] : level[i]) / static_cast<double>(kLevelLimit); }
};

}  // namespace osc
