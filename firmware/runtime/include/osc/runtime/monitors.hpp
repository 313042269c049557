// The tick's monitors (docs/safety.md): small types, each with `check(...) -> fault bits` and the
// state it keeps between ticks, run by control_tick() (osc/runtime/control_task.hpp) in two
// stages: the encoder checks before the control step, the step's checks after it.
//
//   before the step  EncoderRangeMonitor   every reading within the joint limits plus a margin
//                    EncoderJumpMonitor    no change beyond the joint's speed limit since the last sample
//   after the step   StuckEncoderMonitor   an encoder that stands still while its joint is driven
//                    TrackingMonitor       the tracking error e (36) within params::kTrackingLimit*
//                    ThetaBandMonitor      the friction estimates within their band
//                    SaturationMonitor     a DAC clipped for params::kSaturationTicks ticks in a row
// The thresholds are params:: constants (osc/control/params.hpp), converted to the scalar at compile time.
#pragma once

#include <cstdint>

#include "osc/control/controller.hpp"
#include "osc/runtime/io.hpp"

namespace osc {

/// Every encoder reading, the first included, lies within the joint limits plus
/// params::kJointLimitMargin (relative to the start pose, in counts, rounded outwards).
struct EncoderRangeMonitor {
  std::int64_t min_counts[kDof], max_counts[kDof];

  /// Joint i's plausible readings for `counts_per_rad` counts per radian, q0 the start pose's angle.
  void set(int i, double q0, double counts_per_rad) {
    min_counts[i] =
        static_cast<std::int64_t>((robot::kArm.q_min[i] - params::kJointLimitMargin - q0) * counts_per_rad) - 1;
    max_counts[i] =
        static_cast<std::int64_t>((robot::kArm.q_max[i] + params::kJointLimitMargin - q0) * counts_per_rad) + 1;
  }
  /// Channel i of a coupled drive train (inverse = C^-1, q0 the start pose): its motor angle
  /// e_i = sum_j C^-1_ij (q_j - q0_j) over the joints' box of limits plus the margin.
  void set(int i, const double (&q0)[kDof], double counts_per_rad, const double (&inverse)[kDof][kDof]) {
    double lo = 0, hi = 0;
    for (int j = 0; j < kDof; ++j) {
      const double a = inverse[i][j] * (robot::kArm.q_min[j] - params::kJointLimitMargin - q0[j]);
      const double b = inverse[i][j] * (robot::kArm.q_max[j] + params::kJointLimitMargin - q0[j]);
      lo += a < b ? a : b;
      hi += a < b ? b : a;
    }
    min_counts[i] = static_cast<std::int64_t>(lo * counts_per_rad) - 1;
    max_counts[i] = static_cast<std::int64_t>(hi * counts_per_rad) + 1;
  }
  std::uint32_t check(const std::int32_t counts[kDof]) const {
    std::uint32_t faults = 0;
    for (int i = 0; i < kDof; ++i)
      if (counts[i] < min_counts[i] || counts[i] > max_counts[i]) faults |= kFaultEncoderRange;
    return faults;
  }
};

/// No encoder changes by more than its joint's speed limit allows over the ticks since the last
/// sample (64-bit difference: the comparison cannot wrap). Also tells which encoders moved, for
/// the stuck-encoder monitor (on the first sample, all of them: the monitors start there).
struct EncoderJumpMonitor {
  std::int32_t max_step[kDof];  // largest plausible change per tick [counts]
  std::int32_t prev_counts[kDof];
  std::uint32_t age;  // ticks since prev_counts were sampled
  bool have_counts;   // a first sample has been taken

  void reset() {
    for (int i = 0; i < kDof; ++i) prev_counts[i] = 0;
    age = 0;
    have_counts = false;
  }
  /// Joint i's largest plausible step: the speed limit over one sample, plus one count of quantisation.
  void set(int i, double counts_per_rad) {
    max_step[i] = static_cast<std::int32_t>(counts_per_tick_at_max_speed(i, counts_per_rad)) + 1;
  }
  /// Channel i of a coupled drive train (inverse = C^-1).
  void set(int i, double counts_per_rad, const double (&inverse)[kDof][kDof]) {
    max_step[i] = static_cast<std::int32_t>(counts_per_tick_at_max_speed(i, counts_per_rad, inverse)) + 1;
  }
  /// A tick went by (with or without a sample).
  void tick() { ++age; }
  std::uint32_t check(const std::int32_t counts[kDof], bool moved[kDof]) {
    std::uint32_t faults = 0;
    if (have_counts) {
      for (int i = 0; i < kDof; ++i) {
        const std::int64_t d = static_cast<std::int64_t>(counts[i]) - prev_counts[i];
        const std::int64_t lim = static_cast<std::int64_t>(max_step[i]) * age;
        if (d > lim || d < -lim) faults |= kFaultEncoderJump;
        moved[i] = d != 0;
        prev_counts[i] = counts[i];
      }
    } else {
      for (int i = 0; i < kDof; ++i) prev_counts[i] = counts[i], moved[i] = true;
      have_counts = true;
    }
    age = 0;
    return faults;
  }
};

/// Longest interval between encoder changes the stuck-encoder monitor keeps [ticks].
constexpr std::uint32_t kStuckIntervalCap = 1u << 20;
/// The stuck-encoder monitor's accumulated reference motion is held at this bound [counts]: ten
/// times its threshold, so no decision changes, and within the range of every scalar.
constexpr double kStuckMotionBound = 10 * params::kStuckMotionCounts;

/// encoder_stuck: an encoder that stands still while its joint is driven.
///  - The torque commanded changed by more than params::kStuckTorque since the encoder's last
///    change (beyond the largest breakaway torque of static friction).
///  - The encoder has been silent for params::kStuckIntervals of its recent intervals between
///    counts (a joint that was moving should have counted), and the reference moved the joint by
///    more than params::kStuckMotionCounts since, or, for a joint that was counting fast, the
///    torque changed by more than params::kStuckTorqueSilent.
/// The peaks are the monitor's headroom, reported by the runner (docs/safety.md).
template <class S>
struct StuckEncoderMonitor {
  Vec6<S> motion;                      // reference motion since each encoder's last change [counts]
  std::uint64_t last_move_tick[kDof];  // tick of each encoder's last change
  std::uint32_t move_interval[kDof];   // ticks between its last two changes (its recent count rate)
  Vec6<S> tau_at_move;                 // the torque commanded at each encoder's last change
  Vec6<S> dtau_peak;                   // the largest torque change seen while an encoder stood still
  Vec6<S> dtau_gated_peak;             // ... while it was silent for kStuckIntervals of its intervals
  Vec6<S> peak;                        // the largest motion seen
  bool restart = false;                // the next check takes every encoder as just changed

  /// Clears the monitor. restart: the next check starts afresh from that tick's torques (an enable:
  /// the torque jumps from zero to what holds the arm, and no encoder needs to count for that).
  void reset(bool restart_next = false) {
    restart = restart_next;
    motion.setZero();
    peak.setZero();
    tau_at_move.setZero();
    dtau_peak.setZero();
    dtau_gated_peak.setZero();
    for (int i = 0; i < kDof; ++i) {
      last_move_tick[i] = 0;
      move_interval[i] = kStuckIntervalCap;
    }
  }
  /// After the step of tick `tick` that commanded the motor torques `tau` and reference motor rates
  /// `qd_ref` (both per encoder channel: the joints' own where each encoder reads its joint);
  /// `moved` from EncoderJumpMonitor.
  std::uint32_t check(const Vec6<S>& tau, const Vec6<S>& qd_ref, const bool moved[kDof], std::uint64_t tick, S dt,
                      const Vec6<math::io_scalar_t<S>>& counts_per_rad) {
    static constexpr std::array<S, kDof> kTorque = lit_array<S>(params::kStuckTorque);
    static constexpr std::array<S, kDof> kTorqueSilent = lit_array<S>(params::kStuckTorqueSilent);
    static constexpr S kMotionBound = lit<S>(kStuckMotionBound), kMotionCounts = lit<S>(params::kStuckMotionCounts);
    std::uint32_t faults = 0;
    const bool fresh = restart;
    restart = false;
    for (int i = 0; i < kDof; ++i) {
      S& m = motion(i);
      if (moved[i] || fresh) {
        const std::uint64_t gap = tick - last_move_tick[i];
        move_interval[i] = gap < kStuckIntervalCap ? static_cast<std::uint32_t>(gap) : kStuckIntervalCap;
        last_move_tick[i] = tick;
        m = S(0);
        tau_at_move(i) = tau(i);
        continue;
      }
      const S dtau = math::abs(tau(i) - tau_at_move(i));
      if (dtau > dtau_peak(i)) dtau_peak(i) = dtau;
      if (dtau > kTorque[i]) faults |= kFaultEncoderStuck;
      m += math::abs(qd_ref(i)) * dt * counts_per_rad(i);
      if (m > kMotionBound) m = kMotionBound;
      // Silent for many times its recent interval: a joint that was slowing down, as at a reversal
      // held by static friction, had long intervals already.
      const std::uint64_t silent = tick - last_move_tick[i];
      if (silent <= static_cast<std::uint64_t>(params::kStuckIntervals) * move_interval[i]) continue;
      if (m > peak(i)) peak(i) = m;
      if (m > kMotionCounts) faults |= kFaultEncoderStuck;
      if (move_interval[i] > static_cast<std::uint32_t>(params::kStuckFastInterval)) continue;
      if (dtau > dtau_gated_peak(i)) dtau_gated_peak(i) = dtau;
      if (dtau > kTorqueSilent[i]) faults |= kFaultEncoderStuck;
    }
    return faults;
  }
};

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
/// params::kThetaFaultBand (a NaN is outside too).
template <class S>
struct ThetaBandMonitor {
  template <class Theta>
  static std::uint32_t check(const Theta& theta_hat, const Theta& theta_max) {
    static constexpr S kBand = lit<S>(params::kThetaFaultBand);
    const S band = kBand;
    std::uint32_t faults = 0;
    for (int i = 0; i < 3 * kDof; ++i) {
      const S th = theta_hat(i), mx = theta_max(i);
      if (!(th >= -band * mx && th <= (S(1) + band) * mx)) faults |= kFaultThetaBounds;
    }
    return faults;
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

}  // namespace osc
