// Homing (docs/safety.md "Homing"): the home command's move, planned outside the tick
// (prepare_home), and its ticks (homing_faults: each motor's index pulse latched, its revolution
// picked by the pots' coarse angle), ending with the encoders' zero corrected (finish_homing); the
// other ways to a known pose, declare_pose and an enable's coarse angles from the pots
// (coarse_from_pots); and the encoder-zero arithmetic they share, in integer ticks of 1/65536 count
// (detail::to_ticks, shift_encoder_zero, move_encoder_zero). The tick's motion stage
// (osc/runtime/motion_stage.hpp) and the commands' preparation (osc/runtime/command_prep.hpp) call them.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "osc/control/controller.hpp"
#include "osc/runtime/io.hpp"
#include "osc/runtime/motion_commands.hpp"
#include "osc/runtime/step_monitors.hpp"

namespace osc {

namespace detail {
/// Each motor's revolution referred to its joint, 2 pi / |G| [rad], and its index pulse's phase in
/// it: the shaft angle G e passes the index at index_angle + 2 pi k, so motor c's index positions are
/// e = (phase_c + k) rev_c, k integer, phase_c = sign(G_c) index_angle_c / 2 pi.
struct IndexTable {
  double rev[kDof], phase[kDof];
};
constexpr IndexTable index_table() {
  IndexTable t{};
  for (int c = 0; c < kDof; ++c) {
    const double G = robot::kArm.links[c].gear_ratio;
    t.rev[c] = 2 * kPi / abs_of(G);
    t.phase[c] = (G < 0 ? -1 : 1) * robot::kDriveTrain.index_angle[c] / (2 * kPi);
  }
  return t;
}
inline constexpr IndexTable kIndexTable = index_table();
static_assert(params::kHomeBand > 0 && params::kHomeBand < 0.5,
              "a pot within the band of the index position picks the right revolution (band < half a turn)");

/// Homing's arithmetic is in integer ticks of 1/65536 count (int64), on every scalar: an absolute
/// count reaches 10^5 (a joint's travel), which needs more than Q12.19 and float's 24 bits give to a
/// hundredth of a count, and the control path of the M4F calls no double routine, the M3's neither
/// double nor float (control_path_calls).
constexpr int kTickBits = 16;
/// x [rad] times counts per radian, in ticks.
template <class S>
std::int64_t to_ticks(S x, math::io_scalar_t<S> cpr) {
  if constexpr (fixed::is_q_v<S>) {
    constexpr int kShift = S::kFractionBits + math::io_scalar_t<S>::kFractionBits - kTickBits;
    return (static_cast<std::int64_t>(x.raw()) * cpr.raw()) >> kShift;
  } else {
    const S v = x * static_cast<S>(cpr);
    const auto whole = static_cast<std::int32_t>(v);  // |v| < 2^31 counts; float to int32: one instruction
    const auto frac = static_cast<std::int32_t>((v - static_cast<S>(whole)) * S(1 << kTickBits));
    return static_cast<std::int64_t>(whole) * (1 << kTickBits) + frac;
  }
}
/// Ticks over counts per radian [rad].
template <class S>
S from_ticks(std::int64_t t, math::io_scalar_t<S> cpr) {
  if constexpr (fixed::is_q_v<S>) {
    constexpr int kShift = S::kFractionBits + math::io_scalar_t<S>::kFractionBits - kTickBits;
    return S::from_raw(static_cast<typename S::Raw>(t * (std::int64_t{1} << kShift) / cpr.raw()));
  } else {
    const auto whole = static_cast<std::int32_t>(t >> kTickBits);
    const auto frac = static_cast<std::int32_t>(t & ((1 << kTickBits) - 1));
    return (static_cast<S>(whole) + static_cast<S>(frac) * S(1.0 / (1 << kTickBits))) / static_cast<S>(cpr);
  }
}
/// a / b rounded toward minus infinity (b > 0).
constexpr std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}
/// The named poses in the scalar S, built at compile time (no conversion from double in the tick).
template <class S>
inline constexpr auto kPoseTable = [] {
  std::array<std::array<S, kDof>, robot::kNamedPoseCount> t{};
  for (int p = 0; p < robot::kNamedPoseCount; ++p)
    for (int i = 0; i < kDof; ++i) t[p][i] = lit<S>(robot::kNamedPoses[p].q[i]);
  return t;
}();
}  // namespace detail

/// Each motor's index positions in ticks of its encoder (homing's, set with the encoders): at
/// phase + k rev from the motor's angle 0, and the band of a pot's coarse angle around one.
struct IndexTicks {
  std::int64_t rev[kDof], phase[kDof], band[kDof];
  [[gnu::cold]] static IndexTicks of(const EncoderMap& map) {  // set-up, in double
    IndexTicks t{};
    for (int c = 0; c < kDof; ++c) {
      const double n = map.counts_per_rad[c] * detail::kIndexTable.rev[c] * (1 << detail::kTickBits);
      t.rev[c] = std::llround(n);
      const double ph = detail::kIndexTable.phase[c] * n;
      t.phase[c] = std::llround(ph);
      t.band[c] = std::llround(params::kHomeBand * n);
    }
    return t;
  }
};

/// A homing in progress (the state homing; docs/safety.md "Homing").
template <class S>
struct Homing {
  std::uint32_t id = 0;                         ///< the home command's (the done_id of its completion)
  bool started = false;                         ///< its first tick took the start counts
  std::uint8_t found = 0;                       ///< bit c: channel c's index pulse found
  std::int32_t start_counts[kDof]{};            ///< the counts at its first tick
  FrictionMode mode = FrictionMode::kAdaptive;  ///< the task's friction mode, restored when homing ends
  Vec6<S> pot_offset = Vec6<S>::Zero();         ///< per motor: the pots' angle minus the encoders', at rest before it
  Vec6<S> correction = Vec6<S>::Zero();         ///< per motor: the exact angle minus the encoders' belief [rad]
};

/// The task (osc/runtime/control_task.hpp, which includes this header before it defines the type):
/// the functions below take it by reference.
template <class S>
struct ControlTask;

/// The encoders' zero moves: the joint angles at count 0 by dq (motor angles by de = C^-1 dq), and
/// the plausible counts (EncoderRangeMonitor) with them, to the count.
template <class S>
void shift_encoder_zero(ControlTask<S>& task, const Vec6<S>& dq, const Vec6<S>& de) {
  task.q_start += dq;
  for (int c = 0; c < kDof; ++c) {
    const std::int64_t t = detail::to_ticks<S>(de(c), task.io.counts_per_rad(c));
    const std::int64_t shift = (t + (1 << (detail::kTickBits - 1))) >> detail::kTickBits;  // to the nearest count
    task.range.min_counts[c] -= shift;
    task.range.max_counts[c] -= shift;
  }
}

/// The encoders' zero moved by dq at rest, with the position cross-check's pot-minus-encoder
/// difference moving with it (its learnt reference stays valid).
template <class S>
void move_encoder_zero(ControlTask<S>& task, const Vec6<S>& dq) {
  shift_encoder_zero(task, dq, motor_rates(task.io, dq));
  task.position.filtered -= dq;
  task.position.reference -= dq;
}

/// The limits of the homing move: the move limits, their speeds at most home_speed.
template <class S>
CartesianLimits<S> home_limits(const ControlTask<S>& task) {
  CartesianLimits<S> l = task.limits;
  if (task.home_speed[0] < l.linear.v) l.linear.v = task.home_speed[0];
  if (task.home_speed[1] < l.angular.v) l.angular.v = task.home_speed[1];
  return l;
}

/// Whether a home may start: potentiometers wired (parameter pots) and their cross-check's filter
/// settled on every joint (its difference is the coarse angle's offset). While it settles a home
/// waits (pots_settling); a HAL that has read no pot refuses it (no_pots).
template <class S>
bool homing_possible(const ControlTask<S>& task) {
  if (!task.pots) return false;
  for (int i = 0; i < kDof; ++i)
    if (task.position.updates[i] < PositionCrossCheck<S>::kSettleUpdates) return false;
  return true;
}

/// Whether the pots' filter is settling: a pot read, some joint not yet settled (a home and a
/// declare_pose wait for it: at most params::kPositionSettle filter time constants, 250 ms). A HAL
/// that reads no pot is never settling.
template <class S>
bool pots_settling(const ControlTask<S>& task) {
  bool read = false, settled = true;
  for (int i = 0; i < kDof; ++i) {
    read = read || task.position.updates[i] != 0;
    settled = settled && task.position.updates[i] >= PositionCrossCheck<S>::kSettleUpdates;
  }
  return read && !settled;
}

/// Plans the homing move, outside the tick (like a move_to: path-checked by check_prepared_move):
/// from the held pose, every motor (1 + kHomeMargin) revolutions toward the middle of its joint's
/// travel, at the homing limits `lim`. q: the measured angles; data: the planning workspace.
/// Refused not_needed on an arm with absolute encoders, busy unless the generator holds, over_limit when
/// the plan fails.
template <class S>
TaskCommand<S> prepare_home(const MotionGenerator<S>& gen, const CartesianLimits<S>& lim, const Model<S>& model,
                            Data<S>& data, const IoMap<S>& io, const Vec6<S>& q, std::uint32_t id) {
  static constexpr std::array<S, kDof> kTurn = [] {
    std::array<S, kDof> t{};
    for (int c = 0; c < kDof; ++c) t[c] = lit<S>(detail::kIndexTable.rev[c] * (1 + params::kHomeMargin));
    return t;
  }();
  static constexpr std::array<S, kDof> kMid = [] {
    std::array<S, kDof> m{};
    for (int c = 0; c < kDof; ++c) m[c] = lit<S>((robot::kArm.q_min[c] + robot::kArm.q_max[c]) / 2);
    return m;
  }();
  TaskCommand<S> c = prepare_command<S>(MotionVerb::kHome, id);
  c.epoch = gen.epoch();
  if (has_absolute_encoders(robot::kDriveTrain)) {
    c.refusal = MotionReason::kNotNeeded;
    return c;
  }
  if (gen.source() != MotionSource::kHold) {
    c.refusal = MotionReason::kBusy;
    return c;
  }
  Vec6<S> de;
  for (int k = 0; k < kDof; ++k) de(k) = q(k) < kMid[k] ? kTurn[k] : S(-kTurn[k]);
  const Vec6<S> q_end = q + joint_from_motor(io, de);
  const std::uint32_t saved = math::take_arithmetic_flags<S>();
  forward_kinematics(model, data, q_end);
  const Pose<S> to{data.o[kDof], data.R[kDof]};
  const ProfileStatus st = c.move.plan(gen.queue_end(), to, lim, gen.reference_orientation());
  if (math::take_arithmetic_fault<S>() || st != ProfileStatus::kOk) c.refusal = MotionReason::kOverLimit;
  math::restore_arithmetic_flags<S>(saved);
  return c;
}

/// A home accepted: the move starts in the next tick; the pots' offset from the encoders (the
/// cross-check's filtered difference, at rest) is taken per motor.
template <class S>
[[gnu::noinline]] void start_homing(ControlTask<S>& task, std::uint32_t id) {
  task.homing = {};
  task.homing.id = id;
  task.homing.pot_offset = motor_rates(task.io, task.position.filtered);
  // No friction compensation nor learning while homing (restored by end_homing): its slow move is
  // no excitation to learn from (the robust law tripled J5's estimates in 2.5 s), and the estimate's
  // sign flipping with the velocity at a slow reversal stepped the torque by twice it.
  task.homing.mode = task.mode;
  task.mode = FrictionMode::kNone;
}

/// Homing ended (done, stopped, aborted or faulted): the friction mode back.
template <class S>
void end_homing(ControlTask<S>& task) {
  task.mode = task.homing.mode;
}

/// Motor c's index pulse at count n: its coarse angle (the encoders' belief plus the pots' offset)
/// picks the revolution, the index phase gives the exact angle, and their difference is the
/// correction. A coarse angle further than kHomeBand of a turn from the index position: position_mismatch.
template <class S>
[[gnu::noinline]] std::uint32_t homing_latch(ControlTask<S>& task, int c, std::int32_t n) {
  const IndexTicks& x = task.index_ticks;
  const math::io_scalar_t<S> cpr = task.io.counts_per_rad(c);
  const Vec6<S> e0 = motor_rates(task.io, task.q_start);  // the motors' angles at count 0, believed
  // The motor's angle at the latch from its 0, in ticks: as the encoders believe it, as the pots do.
  const std::int64_t believed =
      detail::to_ticks<S>(e0(c), cpr) + static_cast<std::int64_t>(n) * (1 << detail::kTickBits);
  const std::int64_t coarse = believed + detail::to_ticks<S>(task.homing.pot_offset(c), cpr);
  const std::int64_t k = detail::floor_div(coarse - x.phase[c] + x.rev[c] / 2, x.rev[c]);  // the nearest index
  const std::int64_t exact = x.phase[c] + k * x.rev[c];
  const std::int64_t off = coarse - exact;  // the coarse angle minus the index position
  task.homing.correction(c) = detail::from_ticks<S>(exact - believed, cpr);
  task.homing.found = static_cast<std::uint8_t>(task.homing.found | (1u << c));
  return off > x.band[c] || -off > x.band[c] ? static_cast<std::uint32_t>(kFaultPositionMismatch) : 0u;
}

/// A tick of the homing, with the step's generator events: each motor's index pulse latched in the
/// last sample interval (a latch further from the count than a tick's plausible step is an old one,
/// or its encoder stopped counting: not taken), the move braked once all are found, and at the move's
/// end a motor without its index pulse named: encoder_stuck when it turned less than half a
/// revolution, index_missing otherwise.
template <class S, class Hal>
[[gnu::noinline]] std::uint32_t homing_faults(
    ControlTask<S>& task, Hal& hal, const std::int32_t counts[kDof],
    const MotionEvents& ev) {  // out of line: the running tick's code stays as it was
  constexpr std::uint8_t kAll = (1u << kDof) - 1u;
  Homing<S>& h = task.homing;
  if (!h.started) {
    for (int c = 0; c < kDof; ++c) h.start_counts[c] = counts[c];
    h.started = true;
  }
  std::uint32_t faults = 0;
  for (int c = 0; c < kDof; ++c) {
    std::int32_t n;
    if (!hal.take_index(c, n) || (h.found >> c & 1u) != 0) continue;
    const std::int64_t d = static_cast<std::int64_t>(n) - counts[c];
    if (d > task.jump.max_step[c] || -d > task.jump.max_step[c]) continue;
    faults |= homing_latch(task, c, n);
  }
  if (h.found == kAll && !task.gen.braking()) task.gen.brake(task.tick + 1, params::kControlHz, home_limits(task));
  if (!ev.finished || h.found == kAll) return faults;
  for (int c = 0; c < kDof; ++c) {
    if ((h.found >> c & 1u) != 0) continue;
    const std::int64_t d = static_cast<std::int64_t>(counts[c]) - h.start_counts[c];
    const std::int64_t turned2 = (d < 0 ? -d : d) * (2 << detail::kTickBits);  // twice the turn, in ticks
    faults |= turned2 < task.index_ticks.rev[c] ? kFaultEncoderStuck : kFaultIndexMissing;
  }
  return faults;
}

/// Homing complete (every index found, at rest): the encoders' zero corrected, the observer
/// restarted and the pose held where the arm now is known to be, the torque beyond gravity ramped
/// in again, the cross-check learnt anew; the home command done.
template <class S>
[[gnu::noinline]] void finish_homing(ControlTask<S>& task, const Vec6<S>& q) {
  const Vec6<S> dq = joint_from_motor(task.io, task.homing.correction);
  shift_encoder_zero(task, dq, task.homing.correction);
  const Vec6<S> q_now = q + dq;
  controller_restart(task.model, task.state, q_now);
  task.gen.hold({task.state.data.o[kDof], task.state.data.R[kDof]}, task.state.R_ref);
  task.q_queue_end = q_now;
  task.stuck.reset(true);
  task.residual.reset();
  task.position.reset();
  task.ramping = true;
  task.ramp_start = task.tick + 1;
  task.homed = true;
  task.report.done_id = task.homing.id;
}

/// An enable of an arm not homed: where the pots have settled, the encoders' zero moves to the pots'
/// coarse angles (the cross-check's filtered difference, which moves with it), so that the model,
/// the limits and the hold are computed within the pots' accuracy of the true pose rather than at an
/// assumed one. Returns the angles now measured.
template <class S>
[[gnu::noinline]] Vec6<S> coarse_from_pots(ControlTask<S>& task, const Vec6<S>& q) {
  if (!homing_possible(task)) return q;
  const Vec6<S> dq = task.position.filtered;
  move_encoder_zero(task, dq);
  return q + dq;
}

/// declare_pose accepted (disabled, measured, the pots agreeing): the encoders' zero set so that
/// the angles now read are the pose's.
template <class S>
[[gnu::noinline]] void declare_pose(ControlTask<S>& task, const Vec6<S>& q, int pose) {
  Vec6<S> dq;
  for (int i = 0; i < kDof; ++i) dq(i) = detail::kPoseTable<S>[pose][i] - q(i);
  move_encoder_zero(task, dq);
  task.homed = true;
}

/// Whether the pots contradict a declared pose: a joint whose pot angle (the encoders' plus the
/// cross-check's filtered difference) is further than kDeclareBand from it. Joints whose pots have
/// not been read yet, and an arm without pots, contradict nothing.
template <class S>
[[gnu::noinline]] bool pots_disagree(const ControlTask<S>& task, const Vec6<S>& q, int pose) {
  static constexpr S kBand = lit<S>(params::kDeclareBand);
  if (!task.pots) return false;
  for (int i = 0; i < kDof; ++i) {
    if (task.position.updates[i] == 0) continue;
    const S d = q(i) + task.position.filtered(i) - detail::kPoseTable<S>[pose][i];
    if (d > kBand || -d > kBand) return true;
  }
  return false;
}

}  // namespace osc
