// The encoder checks of the tick's monitors (osc/runtime/monitors.hpp; docs/safety.md): before the
// control step, each reading's range and its change since the last sample; after it, the
// stuck-encoder monitor, with the record of each encoder's changes (EncoderActivity) that it and
// the residual monitor (osc/runtime/residual_monitor.hpp) keep.
//
//   EncoderRangeMonitor  every reading within the joint limits plus a margin
//   EncoderJumpMonitor   no change beyond the joint's speed limit since the last sample
//   EncoderActivity      each encoder's last changes: when, how far apart, which way (qualify(): the
//                        monitors' time qualification)
//   StuckEncoderMonitor  an encoder that stands still while its joint is driven
#pragma once

#include <array>
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

/// Longest interval between encoder changes the monitors keep [ticks].
constexpr std::uint32_t kStuckIntervalCap = 1u << 20;

/// A run of consecutive ticks that a criterion has held, one tick on (saturating): the monitors'
/// time qualification.
constexpr std::uint8_t qualify(std::uint8_t run, bool holds) {
  return holds ? static_cast<std::uint8_t>(run < 255 ? run + 1 : 255) : std::uint8_t{0};
}

/// Each encoder channel's recent activity, from EncoderJumpMonitor's moved: when it last changed,
/// the interval between its last two changes, and their directions. A joint counts one way only if
/// its last two changes had the same sign: an encoder dithering by a count at rest (an edge under
/// the sensor, a joint held against static friction) changes every tick or two, both ways, and is
/// not a moving joint.
struct EncoderActivity {
  std::uint64_t last_move_tick[kDof];  // tick of each encoder's last change
  std::uint32_t move_interval[kDof];   // ticks between its last two changes (its recent count rate)
  std::int32_t last_counts[kDof];      // its reading at its last change
  std::int8_t direction[kDof];         // the sign of its last change
  bool steady[kDof];                   // its last two changes had the same sign
  bool reversed[kDof];                 // ... opposite signs
  // Each channel's counts over the last whole window of params::kResidualSlideInterval ticks, either way
  // (the residual monitor's slide test on a fine encoder: ResidualMonitor::slide_counts).
  std::int32_t window_start[kDof];    // its reading at the current window's start
  std::uint32_t window_travel[kDof];  // |its change| over the last whole window
  std::uint8_t window_left;           // ticks until the current window ends
  /// Set-up (set_slide): the counts channel c must make over a window for its joint to count as moving
  /// (the residual monitor's friction_error): params::kResidualSlideSpeed's, where its encoder counts
  /// kResidualSlideInterval ticks apart at a lower speed; else 0, no such test (the count interval
  /// decides, as on the PUMA).
  std::uint32_t slide_counts[kDof] = {};

  void reset() {
    for (int i = 0; i < kDof; ++i)
      last_move_tick[i] = 0, move_interval[i] = kStuckIntervalCap, last_counts[i] = 0, direction[i] = 0,
      steady[i] = false, reversed[i] = false, window_start[i] = 0, window_travel[i] = 0;
    window_left = 0;
  }
  /// Channel i changed (or is taken as changed) at `tick`.
  void mark(int i, std::uint64_t tick) {
    const std::uint64_t gap = tick - last_move_tick[i];
    move_interval[i] = gap < kStuckIntervalCap ? static_cast<std::uint32_t>(gap) : kStuckIntervalCap;
    last_move_tick[i] = tick;
  }
  /// A sample: the channels that moved, and (windows) the windows' counts, which only the slide test reads
  /// (fast_enough(): the residual monitor's record, not the stuck-encoder monitor's).
  void track(const std::int32_t counts[kDof], const bool moved[kDof], std::uint64_t tick, bool windows = true) {
    for (int i = 0; i < kDof; ++i) {
      if (!moved[i]) continue;
      const std::int8_t way = counts[i] > last_counts[i] ? 1 : -1;
      steady[i] = way == direction[i];
      reversed[i] = way == -direction[i];
      direction[i] = way;
      last_counts[i] = counts[i];
      mark(i, tick);
    }
    if (!windows) return;
    if (window_left > 0) {
      --window_left;
      return;
    }
    window_left = params::kResidualSlideInterval - 1;
    for (int i = 0; i < kDof; ++i) {
      const std::int32_t d = counts[i] - window_start[i];
      window_travel[i] = static_cast<std::uint32_t>(d < 0 ? -d : d);
      window_start[i] = counts[i];
    }
  }
  /// The clock moved on by n ticks (a host test's jump of the uptime): the changes keep their age.
  void shift(std::uint64_t n) {
    for (std::uint64_t& t : last_move_tick) t += n;
  }
  /// Every channel taken as just changed at `tick`, from `counts`; none counts one way yet.
  void restart(const std::int32_t counts[kDof], std::uint64_t tick) {
    for (int i = 0; i < kDof; ++i)
      last_counts[i] = window_start[i] = counts[i], window_travel[i] = 0, steady[i] = reversed[i] = false,
      mark(i, tick);
    window_left = params::kResidualSlideInterval - 1;
  }
  /// Channel c's slide test for an encoder of `quantum` [rad at its joint] (0: none, a coupled channel).
  void set_slide(int c, double quantum) {
    constexpr double kSlideTravel = params::kResidualSlideSpeed * params::kResidualSlideInterval * params::kDt;
    const double counts = quantum > 0 ? kSlideTravel / quantum : 0.0;
    slide_counts[c] = counts > 1 ? static_cast<std::uint32_t>(counts) : 0u;
  }
  /// Channel c made its slide test's counts over the last whole window (always, without one).
  bool fast_enough(int c) const { return window_travel[c] >= slide_counts[c]; }
  /// Channel c has been silent for more than params::kStuckIntervals of its recent intervals.
  bool silent(int c, std::uint64_t tick) const {
    const std::uint64_t quiet = tick - last_move_tick[c];
    return move_interval[c] < kStuckIntervalCap &&
           quiet > static_cast<std::uint64_t>(params::kStuckIntervals) * move_interval[c];
  }
  /// Channel c counts the way `up` says at its recent pace: its last two changes that way, the last
  /// within twice the interval between them.
  bool counting(int c, bool up, std::uint64_t tick) const {
    return steady[c] && (direction[c] > 0) == up && move_interval[c] < kStuckIntervalCap &&
           tick - last_move_tick[c] <= 2 * static_cast<std::uint64_t>(move_interval[c]) + 1;
  }
  /// Channel c's last two changes at most params::kResidualSlideInterval ticks apart: with counting
  /// (above), a sliding joint, not one creeping in stick-slip.
  bool sliding(int c) const { return move_interval[c] <= static_cast<std::uint32_t>(params::kResidualSlideInterval); }
  /// Channel c was counting one way, fast: its last two changes of one sign, at most
  /// params::kStuckFastInterval ticks apart.
  bool was_fast(int c) const {
    return steady[c] && move_interval[c] <= static_cast<std::uint32_t>(params::kStuckFastInterval);
  }
};
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
  Vec6<S> motion;                  // reference motion since each encoder's last change [counts]
  EncoderActivity activity;        // each encoder's changes (restarted with the monitor)
  Vec6<S> tau_at_move;             // the torque commanded at each encoder's last change
  Vec6<S> dtau_peak;               // the largest torque change seen while an encoder stood still
  Vec6<S> dtau_gated_peak;         // ... while it was silent for kStuckIntervals of its intervals
  Vec6<S> peak;                    // the largest motion seen
  std::uint8_t over[kDof];         // consecutive ticks the torque change has been beyond kStuckTorque
  std::uint8_t over_silent[kDof];  // ... beyond kStuckTorqueSilent
  bool restart = false;            // the next check takes every encoder as just changed

  /// Clears the monitor. restart: the next check starts afresh from that tick's torques (an enable:
  /// the torque jumps from zero to what holds the arm, and no encoder needs to count for that).
  void reset(bool restart_next = false) {
    restart = restart_next;
    motion.setZero();
    peak.setZero();
    tau_at_move.setZero();
    dtau_peak.setZero();
    dtau_gated_peak.setZero();
    activity.reset();
    for (int i = 0; i < kDof; ++i) over[i] = 0, over_silent[i] = 0;
  }
  /// After the step of tick `tick` that commanded the motor torques `tau` and reference motor rates
  /// `qd_ref` (both per encoder channel: the joints' own where each encoder reads its joint);
  /// `counts` and `moved` from EncoderJumpMonitor. torque_only: the torque criterion alone
  /// (kStuckTorque, beyond the torque that breaks any joint away from its static friction), as while
  /// homing: the criteria tuned on the paper's trajectory are off (the reference motion while silent
  /// trips on slow moves of a joint that static friction holds, Corke's J1).
  std::uint32_t check(const Vec6<S>& tau, const Vec6<S>& qd_ref, const std::int32_t counts[kDof],
                      const bool moved[kDof], std::uint64_t tick, S dt,
                      const Vec6<math::io_scalar_t<S>>& counts_per_rad, bool torque_only = false) {
    static constexpr std::array<S, kDof> kTorque = lit_array<S>(params::kStuckTorque);
    static constexpr std::array<S, kDof> kTorqueSilent = lit_array<S>(params::kStuckTorqueSilent);
    static constexpr S kMotionBound = lit<S>(kStuckMotionBound), kMotionCounts = lit<S>(params::kStuckMotionCounts);
    std::uint32_t faults = 0;
    const bool fresh = restart;
    restart = false;
    if (fresh)
      activity.restart(counts, tick);
    else
      activity.track(counts, moved, tick, false);  // silent() and was_fast() only: no windows
    for (int i = 0; i < kDof; ++i) {
      S& m = motion(i);
      if (moved[i] || fresh) {
        m = S(0);
        tau_at_move(i) = tau(i);
        over[i] = 0, over_silent[i] = 0;
        continue;
      }
      const S dtau = math::abs(tau(i) - tau_at_move(i));
      if (dtau > dtau_peak(i)) dtau_peak(i) = dtau;
      // A torque criterion counts once the change has lasted params::kStuckQualifyTicks ticks.
      over[i] = qualify(over[i], dtau > kTorque[i]);
      over_silent[i] = qualify(over_silent[i], dtau > kTorqueSilent[i]);
      if (over[i] >= params::kStuckQualifyTicks) faults |= kFaultEncoderStuck;
      m += math::abs(qd_ref(i)) * dt * counts_per_rad(i);
      if (m > kMotionBound) m = kMotionBound;
      // Silent for many times its recent interval: a joint that was slowing down, as at a reversal
      // held by static friction, had long intervals already.
      if (!activity.silent(i, tick)) continue;
      if (m > peak(i)) peak(i) = m;
      if (torque_only) continue;
      if (m > kMotionCounts) faults |= kFaultEncoderStuck;
      // A joint that was counting one way fast should have counted on.
      if (!activity.was_fast(i)) continue;
      if (dtau > dtau_gated_peak(i)) dtau_gated_peak(i) = dtau;
      if (over_silent[i] >= params::kStuckQualifyTicks) faults |= kFaultEncoderStuck;
    }
    return faults;
  }
};

}  // namespace osc
