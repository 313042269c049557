// The control task the 1 kHz timer interrupt runs: read encoders -> angles -> control step
// (observer, controller, adaptation) -> torques -> DAC codes -> write, under the supervisor.
// Bound to a HAL at compile time; the same code runs against the simulated plant on the host and
// on the targets.
// The HAL is the concept hal::ControlHal (hal/hal.hpp).
#pragma once

#include <cstdint>

#include "hal/hal.hpp"
#include "osc/control/controller.hpp"
#include "osc/runtime/io.hpp"
#include "osc/runtime/supervisor.hpp"

namespace osc {

static_assert(has_spherical_wrist(robot::kArm),
              "the kernels factor J block-triangularly (SphericalWristJacobianFactor): the robot needs a "
              "spherical wrist centred at the frame-6 origin");

/// Per-step timing, in the HAL's cycle-counter units.
struct StepTiming {
  std::uint32_t last = 0, max = 0;
  std::uint64_t sum = 0;
  std::uint32_t count = 0;
  std::uint32_t mean() const { return count ? static_cast<std::uint32_t>(sum / count) : 0; }
  void add(std::uint32_t c) {
    last = c;
    if (c > max) max = c;
    sum += c;
    ++count;
  }
};

/// Longest interval between encoder changes the stuck-encoder monitor keeps [ticks].
constexpr std::uint32_t kStuckIntervalCap = 1u << 20;
/// The stuck-encoder monitor's accumulated reference motion is held at this bound [counts]: ten
/// times its threshold, so no decision changes, and within the range of every scalar.
constexpr double kStuckMotionBound = 10 * params::kStuckMotionCounts;

template <class S>
struct ControlTask {
  Model<S> model;
  Gains<S> gains;
  FrictionMode mode;
  Vec6<S> q_start;                            // joint angles at which the encoders read zero
  Vec6<math::io_scalar_t<S>> counts_per_rad;  // encoder counts per joint radian (the robot's drives by default)
  std::uint64_t tick;                         // samples since start (64 bits: never wraps in service)
  bool have_counts;                           // a first encoder sample has been taken
  ControllerState<S> state;
  StepOutput<S> last;        // the most recent step, for telemetry
  std::int32_t codes[kDof];  // the most recent DAC codes
  std::int32_t prev_counts[kDof];
  std::uint32_t prev_counts_age;                    // ticks since prev_counts were sampled
  std::int32_t max_count_step[kDof];                // largest plausible encoder change per tick
  std::int64_t min_counts[kDof], max_counts[kDof];  // plausible readings: joint limits plus a margin
  std::uint16_t sat_ticks[kDof];                    // consecutive clipped ticks per joint
  Vec6<S> stuck_motion;                             // reference motion since each encoder's last change [counts]
  std::uint64_t last_move_tick[kDof];               // tick of each encoder's last change
  std::uint32_t move_interval[kDof];                // ticks between its last two changes (its recent count rate)
  Vec6<S> tau_at_move;                              // the torque commanded at each encoder's last change
  Vec6<S> stuck_dtau_peak;                          // the largest torque change seen while an encoder stood still
  Vec6<S> stuck_dtau_gated_peak;                    // ... while it was silent for kStuckIntervals of its intervals
  Vec6<S> stuck_peak;                               // the largest stuck_motion seen (the monitor's headroom)
  Supervisor sup;
  std::uint32_t period_cycles;  // overrun budget per step (0: not checked)
  StepTiming timing;            // the whole tick: I/O, step, supervision
  StepTiming step_timing;       // the control step alone: observer + controller + adaptation

  void init(const Model<S>& m, const Gains<S>& g, FrictionMode fm, const Vec6In<S>& q0, std::uint32_t period = 0) {
    model = m;
    gains = g;
    mode = fm;
    q_start = q0;
    tick = 0;
    have_counts = false;
    prev_counts_age = 0;
    controller_init(model, state, q0);
    for (int i = 0; i < kDof; ++i) {
      codes[i] = 0;
      prev_counts[i] = 0;
      sat_ticks[i] = 0;
    }
    stuck_motion.setZero();
    stuck_peak.setZero();
    tau_at_move.setZero();
    stuck_dtau_peak.setZero();
    stuck_dtau_gated_peak.setZero();
    for (int i = 0; i < kDof; ++i) {
      last_move_tick[i] = 0;
      move_interval[i] = kStuckIntervalCap;
    }
    set_encoder_resolution(robot::kDrives.encoder_counts_per_motor_rev);
    sup = {SupervisorState::kInit, 0};
    period_cycles = period;
    timing = {};
    step_timing = {};
  }
  /// Encoders of another resolution than the robot table's (counts per motor revolution, after
  /// quadrature decoding): the count scaling and the plausible step per tick follow it.
  void set_encoder_resolution(double counts_per_motor_rev) {
    for (int i = 0; i < kDof; ++i) {
      const double c = osc::counts_per_rad(i, counts_per_motor_rev);
      counts_per_rad(i) = lit<math::io_scalar_t<S>>(c);
      // Speed limit times the sample, in counts, plus one count of quantisation.
      max_count_step[i] = static_cast<std::int32_t>(counts_per_tick_at_max_speed(i, c)) + 1;
      // The joint limits plus the margin, relative to the start pose, in counts (rounded outwards).
      const double q0 = static_cast<double>(q_start(i));
      min_counts[i] = static_cast<std::int64_t>((robot::kArm.q_min[i] - params::kJointLimitMargin - q0) * c) - 1;
      max_counts[i] = static_cast<std::int64_t>((robot::kArm.q_max[i] + params::kJointLimitMargin - q0) * c) + 1;
    }
  }
  /// Test hook (fault injection): poisons the observer state with a NaN.
  void inject_nonfinite() { state.obs.y(0) = S(0) / S(0); }
};

/// Encoder counts to joint angles.
template <class S>
Vec6<S> angles_from_counts(const Vec6<S>& q_start, const Vec6<math::io_scalar_t<S>>& counts_per_rad,
                           const std::int32_t counts[kDof]) {
  Vec6<S> q;
  for (int i = 0; i < kDof; ++i) q(i) = counts_to_angle<S>(counts[i], counts_per_rad(i), q_start(i));
  return q;
}

/// The checks of a completed step against what the controller commanded (docs/safety.md):
///  - encoder_stuck: an encoder stood still while the reference moved its joint by more than
///    params::kStuckMotionCounts counts since its last change;
///  - tracking: the measured tracking error e (36) beyond params::kTrackingLimit*;
///  - theta_bounds: a friction estimate outside [-band theta_max, (1 + band) theta_max].
template <class S>
std::uint32_t plausibility_faults(ControlTask<S>& task, const bool moved[kDof]) {
  // The thresholds in S, converted at compile time.
  static constexpr std::array<S, kDof> kStuckTorque = lit_array<S>(params::kStuckTorque);
  static constexpr std::array<S, kDof> kStuckTorqueSilent = lit_array<S>(params::kStuckTorqueSilent);
  static constexpr S kMotionBound = lit<S>(kStuckMotionBound), kMotionCounts = lit<S>(params::kStuckMotionCounts);
  static constexpr S kLimitPosition = lit<S>(params::kTrackingLimitPosition);
  static constexpr S kLimitOrientation = lit<S>(params::kTrackingLimitOrientation);
  static constexpr S kBand = lit<S>(params::kThetaFaultBand);
  std::uint32_t faults = 0;
  const StepOutput<S>& out = task.last;
  for (int i = 0; i < kDof; ++i) {
    S& m = task.stuck_motion(i);
    if (moved[i]) {
      const std::uint64_t gap = task.tick - task.last_move_tick[i];
      task.move_interval[i] = gap < kStuckIntervalCap ? static_cast<std::uint32_t>(gap) : kStuckIntervalCap;
      task.last_move_tick[i] = task.tick;
      m = S(0);
      task.tau_at_move(i) = out.tau(i);
      continue;
    }
    // The torque change since the encoder's last count: beyond the largest breakaway torque of
    // static friction, stuck whatever the joint did before.
    const S dtau = math::abs(out.tau(i) - task.tau_at_move(i));
    if (dtau > task.stuck_dtau_peak(i)) task.stuck_dtau_peak(i) = dtau;
    if (dtau > kStuckTorque[i]) faults |= kFaultEncoderStuck;
    m += math::abs(out.qd_ref(i)) * task.gains.dt * task.counts_per_rad(i);
    if (m > kMotionBound) m = kMotionBound;
    // The encoder has been silent for many times its recent interval between counts: a joint that
    // was moving should have counted (one that was slowing down, as at a reversal held by static
    // friction, had long intervals already). Then a smaller torque change, or the reference having
    // moved the joint far, is a stuck encoder.
    const std::uint64_t silent = task.tick - task.last_move_tick[i];
    if (silent <= static_cast<std::uint64_t>(params::kStuckIntervals) * task.move_interval[i]) continue;
    if (m > task.stuck_peak(i)) task.stuck_peak(i) = m;
    if (m > kMotionCounts) faults |= kFaultEncoderStuck;
    if (task.move_interval[i] > static_cast<std::uint32_t>(params::kStuckFastInterval)) continue;
    if (dtau > task.stuck_dtau_gated_peak(i)) task.stuck_dtau_gated_peak(i) = dtau;
    if (dtau > kStuckTorqueSilent[i]) faults |= kFaultEncoderStuck;
  }
  const S lp = kLimitPosition, lo = kLimitOrientation;
  if (out.e.template head<3>().squaredNorm() > lp * lp) faults |= kFaultTracking;
  for (int i = 3; i < 6; ++i)
    if (math::abs(out.e(i)) > lo) faults |= kFaultTracking;
  if (task.mode == FrictionMode::kAdaptive) {
    const S band = kBand;
    for (int i = 0; i < 3 * kDof; ++i) {
      const S th = task.state.adapt.theta_hat(i), mx = task.gains.theta_max(i);
      if (!(th >= -band * mx && th <= (S(1) + band) * mx)) faults |= kFaultThetaBounds;
    }
  }
  return faults;
}

/// One tick. Returns the fault bits detected in this tick. On any fault, whenever the supervisor is
/// not in kRun, and in a tick without a valid sample (read_encoders() false: no control step), every
/// DAC gets code 0 in this same tick.
template <class S, hal::ControlHal Hal>
std::uint32_t control_tick(ControlTask<S>& task, Hal& hal) {
  const std::uint32_t c0 = hal.cycles();
  std::uint32_t faults = hal.io_faults();
  std::int32_t counts[kDof];
  const bool sampled = hal.read_encoders(counts);
  bool moved[kDof] = {};
  ++task.prev_counts_age;
  if (sampled) {
    // Every reading, the first included, must lie within the joint limits plus the margin.
    for (int i = 0; i < kDof; ++i)
      if (counts[i] < task.min_counts[i] || counts[i] > task.max_counts[i]) faults |= kFaultEncoderRange;
    // An encoder change beyond the physical joint speed over the ticks since the last sample
    // (comparison written so that it cannot wrap).
    if (task.have_counts) {
      for (int i = 0; i < kDof; ++i) {
        const std::int64_t d = static_cast<std::int64_t>(counts[i]) - task.prev_counts[i];
        const std::int64_t lim = static_cast<std::int64_t>(task.max_count_step[i]) * task.prev_counts_age;
        if (d > lim || d < -lim) faults |= kFaultEncoderJump;
        moved[i] = d != 0;
        task.prev_counts[i] = counts[i];
      }
    } else {
      for (int i = 0; i < kDof; ++i) task.prev_counts[i] = counts[i], moved[i] = true;  // the monitors start here
      task.have_counts = true;
    }
    task.prev_counts_age = 0;
  }

  for (int i = 0; i < kDof; ++i) task.codes[i] = 0;
  if (sampled && task.sup.state != SupervisorState::kFault && faults == 0) {
    const Vec6<S> q = angles_from_counts(task.q_start, task.counts_per_rad, counts);
    const S t = trajectory_time<S>(task.gains.trajectory, task.tick, params::kControlHz);
    const std::uint32_t s0 = hal.cycles();
    task.last = control_step(task.model, task.gains, task.mode, task.state, q, t);
    task.step_timing.add(hal.cycles() - s0);
    faults |= task.last.status;  // non_finite, singular
    if (task.last.status == kFaultNone) faults |= plausibility_faults(task, moved);
    for (int i = 0; i < kDof; ++i) {
      const bool clipped = torque_to_code(i, task.last.tau(i), task.codes[i]);
      task.sat_ticks[i] = clipped ? static_cast<std::uint16_t>(task.sat_ticks[i] + 1) : 0;
      if (task.sat_ticks[i] >= params::kSaturationTicks) faults |= kFaultSaturation;
    }
  }
  // A fixed-point saturation in the monitors or the torque conversion (the step reports its own).
  if (math::take_arithmetic_fault<S>()) faults |= kFaultOverflow;
  // The step's own duration against the period (the next tick would have arrived).
  const std::uint32_t elapsed = hal.cycles() - c0;
  if (task.period_cycles != 0 && elapsed > task.period_cycles) faults |= kFaultOverrun;

  task.sup = supervisor_next(task.sup, {faults, task.have_counts});
  if (!torque_enabled(task.sup))
    for (int i = 0; i < kDof; ++i) task.codes[i] = 0;
  hal.write_dacs(task.codes);
  hal.fault_output(task.sup.state == SupervisorState::kFault);
  task.timing.add(hal.cycles() - c0);
  ++task.tick;
  return faults;
}

/// A tick without a new sample in which the I/O layer keeps the outputs (a short, bounded gap, e.g.
/// a sensor frame not yet in on a timer-paced link): no control step, the DACs get the previous codes
/// again, the sample clock and the age of the last encoder sample run on.
template <class S, hal::ControlHal Hal>
void hold_tick(ControlTask<S>& task, Hal& hal) {
  ++task.prev_counts_age;
  hal.write_dacs(task.codes);
  ++task.tick;
}

}  // namespace osc
