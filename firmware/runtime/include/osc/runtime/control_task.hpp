// The control task the 1 kHz timer interrupt runs: read encoders -> angles -> control step
// (observer, controller, adaptation) -> torques -> DAC codes -> write, under the supervisor.
// Bound to a HAL at compile time; the same code runs against the simulated plant on the host and
// on the targets.
// The HAL is the concept hal::ControlHal (hal/hal.hpp).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "hal/hal.hpp"
#include "osc/control/controller.hpp"
#include "osc/control/path_check.hpp"
#include "osc/runtime/io.hpp"
#include "osc/runtime/monitors.hpp"
#include "osc/runtime/motion_commands.hpp"
#include "osc/runtime/supervisor.hpp"
#include "osc/runtime/timing.hpp"

namespace osc {

static_assert(has_spherical_wrist(robot::kArm),
              "the kernels factor J block-triangularly (SphericalWristJacobianFactor): the robot needs a "
              "spherical wrist centred at the frame-6 origin");

/// How a task starts: running the paper's experiment from the first sample (moving along (68)
/// about the start pose, the observer started at q_start; the firmware's default, and bit for bit
/// the paper's run: its procedure places the arm at q_start, a declared pose), or disabled, waiting
/// for an enable, not homed: motion is refused (not_homed) until a home or a declare_pose.
enum class TaskStart : std::uint8_t { kPaper, kDisabled };

/// Collision thresholds a user may set [N m]: each finite, from 0 (the derived threshold alone) to
/// the joint's full-scale torque (a residual beyond it could not be told from a saturated drive).
constexpr bool collision_thresholds_valid(const double threshold_nm[kDof]) {
  for (int i = 0; i < kDof; ++i)
    if (!(threshold_nm[i] >= 0 && threshold_nm[i] <= robot::kDrives.torque_limit[i])) return false;
  return true;
}

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

template <class S>
struct ControlTask {
  Model<S> model;
  Gains<S> gains;
  FrictionMode mode;
  Vec6<S> q_start;     // joint angles at which the encoders read zero
  IoMap<S> io;         // encoders and coupling (robot::kEncodersUniform by default)
  std::uint64_t tick;  // samples since start (64 bits: never wraps in service)
  ControllerState<S> state;
  MotionMachine machine;      // the motion state machine (osc/runtime/motion_states.hpp)
  MotionGenerator<S> gen;     // the desired state of each tick (osc/control/motion.hpp)
  CartesianLimits<S> limits;  // the configured maxima of a move
  TaskCommand<S> pending;     // the next tick's command (verb none: no command)
  StreamSample<S> sample;     // the next tick's stream setpoint (prepare_setpoint)
  std::uint32_t dropped;      // setpoints dropped (no stream of their id running, bad, or overwritten untaken)
  MotionReason stop_request;  // the next tick's category-2 stop asked from outside the tick (e.g. link_silent)
  Vec6<S> q_queue_end;        // the joint angles where the queued moves end (the next path check's seed)
  Data<S> check_data;         // the path check's workspace (command preparation, outside the tick)
  MotionReport report;        // this tick's answer and motion events
  std::uint64_t ramp_start;   // the tick the enable's torque ramp started
  bool ramping;               // the torque is being ramped in (enable)
  StepOutput<S> last;         // the most recent step, for telemetry
  Desired<S> desired;         // the most recent step's desired state (the generator's reference)
  std::int32_t codes[kDof];   // the most recent DAC codes
  EncoderRangeMonitor range;  // the encoder checks (osc/runtime/monitors.hpp)
  EncoderJumpMonitor jump;
  StuckEncoderMonitor<S> stuck;  // the step's checks
  ResidualMonitor<S> residual;
  FrictionIdentifier<S> identifier;      // the `momentum` law's (osc/control/identification.hpp)
  CollisionReaction collision_reaction;  // what the residual monitor's collision does (set_collision)
  std::uint32_t stream_timeout_ticks;    // a stream is stale after max(2 periods, this) without a setpoint
  bool contact;                          // a collision was reacted to (category 2, yield) since the last motion
  SaturationMonitor saturation;
  PositionCrossCheck<S> position;  // a HAL with potentiometers (hal::PositionHal)
  bool pots;                       // the arm's potentiometers are wired (parameter pots): the cross-check runs
  Supervisor sup;
  std::uint32_t period_cycles;  // overrun budget per step (0: not checked)
  StepTiming timing;            // the whole tick: I/O, step, supervision
  StepTiming step_timing;       // the control step alone: observer + controller + adaptation
  TickTiming stages;            // each stage of the tick (TickStage)
  // Last: the tick's hot members keep their offsets (the M4F's loads reach 4 kB from the task's base).
  bool homed;                   // the encoders' offsets are known (homing, declare_pose, a paper start)
  Homing<S> homing;             // the homing in progress (state homing)
  IndexTicks index_ticks;       // the index positions of the encoders (set_encoders)
  std::array<S, 2> home_speed;  // the homing move's speeds [m/s, rad/s] (parameter home_speed)
  // The ids of the moves the last tick dropped from the queue (report.dropped_moves of them).
  std::uint32_t dropped_move_ids[MotionGenerator<S>::kMaxWaiting];

  void init(const Model<S>& m, const Gains<S>& g, FrictionMode fm, const Vec6In<S>& q0, std::uint32_t period = 0,
            TaskStart start = TaskStart::kPaper) {
    model = m;
    gains = g;
    mode = fm;
    q_start = q0;
    tick = 0;
    controller_init(model, state, q0);
    machine = {};
    gen.hold({state.data.o[kDof], state.data.R[kDof]}, state.R_ref);
    if (start == TaskStart::kPaper) {
      machine.state = MotionState::kMoving;
      gen.start_paper(gains.trajectory, 0);
    }
    limits = CartesianLimits<S>::defaults();
    desired.x.setZero(), desired.xd.setZero(), desired.xdd.setZero();
    q_queue_end = q0;
    pending = {};
    sample = {};
    dropped = 0;
    stop_request = MotionReason::kNone;
    report = {};
    ramp_start = 0;
    ramping = false;
    for (int i = 0; i < kDof; ++i) codes[i] = 0;
    jump.reset();
    stuck.reset();
    residual.reset();
    residual.collision_floor.setZero();
    identifier.reset();
    collision_reaction = CollisionReaction::kCategory0;
    stream_timeout_ticks = stream::ticks(kStreamTimeoutMin);
    contact = false;
    saturation.reset();
    position.reset();
    pots = true;
    homed = start == TaskStart::kPaper;  // the paper's procedure: the arm placed at q_start
    homing = {};
    home_speed = lit_array<S>(params::kHomeSpeed);
    set_encoders(robot::kEncodersUniform);
    sup = {SupervisorState::kInit, 0};
    period_cycles = period;
    timing = {};
    step_timing = {};
    stages = {};
  }
  /// The encoders and coupling of the arm (osc/robots/arm.hpp, EncoderMap): the angles, the
  /// torques' DAC channels, the plausible readings and steps, the stuck-encoder monitor's channels.
  [[gnu::cold]] void set_encoders(const EncoderMap& map) {  // set-up, in double: compiled for size
    io = IoMap<S>::of(map);
    index_ticks = IndexTicks::of(map);
    double q0[kDof];
    for (int i = 0; i < kDof; ++i) q0[i] = static_cast<double>(q_start(i));
    double C[kDof][kDof], inverse[kDof][kDof];
    coupling_matrices(map, C, inverse);
    Vec6<S> quantum;  // each joint's angle quantum: sum_c |C_jc| / counts_per_rad_c
    for (int j = 0; j < kDof; ++j) {
      double d = 0;
      for (int c = 0; c < kDof; ++c) d += abs_of(C[j][c]) / map.counts_per_rad[c];
      quantum(j) = lit<S>(d);
    }
    residual.set(quantum, gains.k, io.inverse);
    for (int i = 0; i < kDof; ++i) {
      const double c = map.counts_per_rad[i];
      if (io.coupled()) {
        jump.set(i, c, io.inverse);
        range.set(i, q0, c, io.inverse);
      } else {
        jump.set(i, c);
        range.set(i, q0[i], c);
      }
    }
  }
  /// Encoders of another resolution than the robot table's on every joint (counts per motor
  /// revolution, after quadrature decoding), uncoupled.
  void set_encoder_resolution(double counts_per_motor_rev) {
    set_encoders(uniform_encoders("uniform", robot::kArm, counts_per_motor_rev));
  }
  /// A collision's reaction and each joint's collision threshold [N m] (ResidualMonitor::
  /// collision_floor), at run time: false, nothing changed, for a reaction outside its list or a
  /// threshold outside [0, the joint's full-scale torque] (collision_thresholds_valid).
  bool set_collision(CollisionReaction reaction, const double threshold_nm[kDof]) {
    if (static_cast<int>(reaction) >= MotionNames<CollisionReaction>::kCount ||
        !collision_thresholds_valid(threshold_nm))
      return false;
    collision_reaction = reaction;
    for (int i = 0; i < kDof; ++i) residual.collision_floor(i) = lit<S>(threshold_nm[i]);
    return true;
  }
  /// Encoder counts per radian of channel i (its motor angle referred to its joint).
  double counts_per_rad(int i) const { return static_cast<double>(io.counts_per_rad(i)); }
  /// Test hook (fault injection): poisons the observer state with a NaN.
  void inject_nonfinite() { state.obs.y(0) = S(0) / S(0); }
};

/// The `momentum` law's update of the joint whose turn it is (FrictionIdentifier), from the sample the
/// residual monitor took. The sample's noise is at most the residual's quantisation bound taken as
/// twice its standard deviation; samples params::kIdentifyEvery ticks apart that the filter
/// correlates over 1 / K count as 2 / (K dt kIdentifyEvery) times fewer independent ones (the
/// integral scale of a first-order filter's correlation exp(-K |t|) is 2 / K).
template <class S>
void identify_friction(ControlTask<S>& task) {
  static constexpr std::array<S, kDof> kCorrelation = [] {
    std::array<S, kDof> c{};
    for (int i = 0; i < kDof; ++i) {
      const double f = 2.0 / (params::kResidualGain[i] * params::kDt * params::kIdentifyEvery);
      c[i] = lit<S>(f > 1 ? f : 1);
    }
    return c;
  }();
  static constexpr S kMaxRatio = lit<S>(params::kIdentifyMaxRatio);
  ResidualMonitor<S>& m = task.residual;
  const int i = m.sample_joint;
  const S half = lit<S>(0.5) * m.noise_bound(i);
  task.identifier.update(i, m.sample, m.within(i, kMaxRatio), half * half, kCorrelation[i], task.state.adapt.theta_hat,
                         task.gains.theta_max);
}

/// The checks of a completed step against what the controller commanded (docs/safety.md): the
/// stuck-encoder, tracking and friction-estimate monitors (osc/runtime/monitors.hpp).
template <class S>
std::uint32_t step_monitor_faults(ControlTask<S>& task, const std::int32_t counts[kDof], const bool moved[kDof]) {
  const StepOutput<S>& out = task.last;
  // The stuck-encoder monitor (docs/safety.md): off where the residual monitor is armed (its residual
  // and travel check judge every encoder), restarting from the tick it next runs; a trial's fitted
  // criteria otherwise. While homing, whose slow moves static friction holds and whose end names a
  // motor that did not turn (homing_faults), its torque criterion alone. Yielding, the reference follows the arm
  // and the torque follows gravity; against a contact the torque holds a joint that cannot move: neither says where
  // the arm must go, so it waits, from a collision reacted to until the next motion (the residual monitor runs on).
  std::uint32_t faults = 0;
  const bool homing = task.machine.state == MotionState::kHoming;
  if (task.residual.armed && !homing)
    task.stuck.restart = true;
  else if (task.machine.state == MotionState::kYielding || task.contact)
    task.stuck.reset(true);
  else {
    // Per encoder channel: a coupled motor turns with C^-1 qd and carries C^T tau.
    Vec6<S> tau_m, rate_m;
    const bool coupled = task.io.coupled();
    const Vec6<S>& tau = coupled ? (tau_m = motor_torques(task.io, out.tau)) : out.tau;
    const Vec6<S>& rate = coupled ? (rate_m = motor_rates(task.io, out.qd_ref)) : out.qd_ref;
    faults = task.stuck.check(tau, rate, counts, moved, task.tick, task.gains.dt, task.io.counts_per_rad, homing);
  }
  const AdaptationState<S>& ad = task.state.adapt;
  const bool adaptive = task.mode == FrictionMode::kAdaptive;
  const Vec6<S> decay = ad.w_prev.sti.cwiseAbs();
  const bool identify = adaptive && task.gains.adaptation == AdaptationLaw::kMomentum;
  const ResidualInput<S> in{task.state.data.A,
                            task.state.os.g,
                            out.tau_bias,
                            out.tau_f_hat,
                            ad.qd_hat_prev,
                            decay,
                            adaptive ? &ad.theta_hat : nullptr,
                            identify ? &task.identifier.proven : nullptr,
                            &task.state.data.J};
  task.residual.sample_joint = identify ? task.identifier.take_turn() : -1;
  task.residual.contact = task.machine.state == MotionState::kYielding || task.contact;
  faults |= task.residual.check(in, task.io, counts, moved, task.tick);
  if (identify) identify_friction(task);
  faults |= TrackingMonitor<S>::check(out.e);
  if (task.mode == FrictionMode::kAdaptive)
    faults |= ThetaBandMonitor<S>::check_part(task.state.adapt.theta_hat, task.gains.theta_max,
                                              static_cast<int>(task.tick % ThetaBandMonitor<S>::kParts));
  return faults;
}

/// The joint torque the DAC codes of this tick command (C^-T of each channel's, for a coupled
/// drive train): the step's torque where a code was clipped at its range.
template <class S>
Vec6<S> applied_torque(const ControlTask<S>& task) {
  static constexpr std::array<S, kDof> kLimit = lit_array<S>(robot::kDrives.torque_limit);
  constexpr auto kMax = static_cast<std::int32_t>(kDacMaxCode);
  Vec6<S> tau_m = task.io.coupled() ? motor_torques(task.io, task.last.tau) : task.last.tau;
  for (int i = 0; i < kDof; ++i) {
    if (task.codes[i] >= kMax) tau_m(i) = kLimit[i];
    if (task.codes[i] <= -kMax) tau_m(i) = -kLimit[i];
  }
  return task.io.coupled() ? joint_torques_of_motors(task.io, tau_m) : tau_m;
}

/// The states in which the control step runs and torque reaches the DACs.
constexpr bool motion_powered(MotionState s) {
  return s == MotionState::kHolding || motion_running(s) || s == MotionState::kStopping || s == MotionState::kYielding;
}

/// The reference of a yielding arm (a collision's reaction yield): the arm's own pose and observed
/// velocity one sample old, no acceleration. Then e = x_{k-1} - x_k and eta = x^dot^_{k-1} - x^dot^_k +
/// k_s e are of the order of one sample's motion, and (32) reduces to the bias force of (35) (gravity,
/// Coriolis and the friction estimate) with the observer's correction and a damping of
/// (k_s + k_nd) k_s dt (about 21 N s/m on x, y, z): no stiffness holds the arm where it was, and the
/// observer (22) still integrates the force that is applied.
template <class S>
Desired<S> yield_reference(const ControlTask<S>& task) {
  Desired<S> d;
  d.x = task.last.x;
  d.xd = task.last.xd_hat;
  d.xdd.setZero();
  return d;
}

/// The limits checked every tick of a motion (a category-2 stop when one is reached): each joint
/// within its limits, the Jacobian's reciprocal condition at least params::kLimitMinRcond.
template <class S>
MotionReason motion_limits_reached(const ControlTask<S>& task, const Vec6<S>& q) {
  static constexpr std::array<S, kDof> kQMin = lit_array<S>(robot::kArm.q_min);
  static constexpr std::array<S, kDof> kQMax = lit_array<S>(robot::kArm.q_max);
  static constexpr S kMinRcond = lit<S>(params::kLimitMinRcond);
  if (!motion_running(task.machine.state)) return MotionReason::kNone;
  for (int i = 0; i < kDof; ++i)
    if (q(i) < kQMin[i] || q(i) > kQMax[i]) return MotionReason::kLimitReached;
  if (task.last.rcond < kMinRcond) return MotionReason::kLimitReached;
  return MotionReason::kNone;
}

/// A collision whose reaction is not category 0 is no fault: taken out of `faults`, it is that
/// reaction's (a category-2 stop or a yield), and the contact is noted until the next motion. Else
/// category 0: the fault stays, or there was no collision.
template <class S>
CollisionReaction take_collision(ControlTask<S>& task, std::uint32_t& faults) {
  if ((faults & kFaultCollision) == 0 || task.collision_reaction == CollisionReaction::kCategory0)
    return CollisionReaction::kCategory0;
  faults &= ~static_cast<std::uint32_t>(kFaultCollision);
  task.contact = true;  // the contact may last
  return task.collision_reaction;
}

/// The tick's category-2 stop request, the first of: a collision (reaction category 2), a reached
/// limit, a stale stream, the board's (request_stop), which it takes.
template <class S>
MotionReason tick_stop_request(ControlTask<S>& task, bool stepped, const Vec6<S>& q, CollisionReaction collision) {
  MotionReason r = collision == CollisionReaction::kCategory2 ? MotionReason::kCollision : MotionReason::kNone;
  if (r == MotionReason::kNone && stepped) r = motion_limits_reached(task, q);
  if (r == MotionReason::kNone && task.gen.stream_stale()) r = MotionReason::kStaleStream;
  if (r == MotionReason::kNone) r = task.stop_request;
  task.stop_request = MotionReason::kNone;
  return r;
}

/// The faults after which the encoders' offsets are no longer trusted: the arm must be homed again.
constexpr std::uint32_t kFaultsUnhoming =
    kFaultEncoderJump | kFaultEncoderRange | kFaultEncoderStuck | kFaultPositionMismatch | kFaultIndexMissing;

/// The joint angles of motor angles e (referred to their joints): C e.
template <class S>
Vec6<S> joint_from_motor(const IoMap<S>& io, const Vec6<S>& e) {
  Vec6<S> q = e;
  for (int k = 0; k < io.terms; ++k) q(io.row[k]) += io.c[k] * e(io.col[k]);
  return q;
}

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
/// Refused busy unless the generator holds, over_limit when the plan fails.
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

/// Enable's torque ramp: the torque beyond the gravity the model predicts at q is ramped in over
/// params::kEnableRamp, tau = g + r (tau - g), r from 0 to 1.
template <class S>
void ramp_torque(ControlTask<S>& task) {
  constexpr auto kTicks = static_cast<std::uint32_t>(params::kEnableRamp * params::kControlHz);
  const std::uint64_t n = task.tick - task.ramp_start;
  if (n >= kTicks) {
    task.ramping = false;
    return;
  }
  const Vec6<S>& g = task.state.os.g;
  task.last.tau = g + math::ratio<S>(n, kTicks) * (task.last.tau - g);
}

/// The command of the tick as the state machine sees it: none while an enable from disabled waits
/// for a measured pose (the supervisor running and a checked sample in this tick: it stays
/// pending), or when preparing refused it (the
/// refusal goes into the report) or it is no longer valid (its plan's epoch passed: superseded; a
/// paper command when the generator does not hold: busy).
template <class S>
MotionCommand motion_command_of_tick(ControlTask<S>& task, bool measured, const Vec6<S>& q) {
  const TaskCommand<S>& cmd = task.pending;
  MotionReport& rep = task.report;
  if (cmd.verb == MotionVerb::kNone) return MotionCommand::kNone;
  if (cmd.verb == MotionVerb::kEnable && task.machine.state == MotionState::kDisabled &&
      (task.sup.state != SupervisorState::kRun || !measured))
    return MotionCommand::kNone;
  if (cmd.verb == MotionVerb::kDeclarePose && !measured) return MotionCommand::kNone;  // it needs the angles now
  // A home, a declare_pose and the enable of an arm not homed (it takes the pots' coarse angles) wait
  // for the pots.
  const bool coarse = cmd.verb == MotionVerb::kHome || cmd.verb == MotionVerb::kDeclarePose ||
                      (cmd.verb == MotionVerb::kEnable && !task.homed);
  if (coarse && task.pots && pots_settling(task)) return MotionCommand::kNone;
  rep.id = cmd.id;
  rep.verb = cmd.verb;
  MotionReason pre = cmd.refusal;
  const bool planned = cmd.verb == MotionVerb::kMoveTo || cmd.verb == MotionVerb::kHome;
  if (pre == MotionReason::kNone && planned && cmd.epoch != task.gen.epoch()) pre = MotionReason::kSuperseded;
  if (pre == MotionReason::kNone && cmd.verb == MotionVerb::kHome && !homing_possible(task))
    pre = MotionReason::kNoPots;
  if (pre == MotionReason::kNone && cmd.verb == MotionVerb::kDeclarePose &&
      task.machine.state == MotionState::kDisabled && pots_disagree(task, q, cmd.pose))
    pre = MotionReason::kPotsDisagree;
  if (pre == MotionReason::kNone && (cmd.verb == MotionVerb::kPaper || cmd.verb == MotionVerb::kStream) &&
      task.gen.source() != MotionSource::kHold)
    pre = MotionReason::kBusy;
  if (pre == MotionReason::kNone) return verb_command(cmd.verb);
  rep.outcome = CommandOutcome::kRefused;
  rep.refusal = pre;
  return MotionCommand::kNone;
}

/// The moves waiting in the generator's queue, which this tick drops (a re-target's or a stop's
/// brake, a hold, a fault's halt): their ids into the report, after any the tick dropped already
/// (CommandPort::after_tick answers each, aborted dropped). Called only in the ticks that drop.
template <class S>
[[gnu::noinline]] void report_dropped(ControlTask<S>& task) {
  constexpr int kMax = MotionGenerator<S>::kMaxWaiting;
  const int n = task.report.dropped_moves;
  task.report.dropped_moves = static_cast<std::uint8_t>(n + task.gen.waiting_ids(task.dropped_move_ids + n, kMax - n));
}

/// The generator holds the pose the last step measured (the next move's path starts at q); the
/// moves waiting are dropped.
template <class S>
void hold_measured_pose(ControlTask<S>& task, const Vec6<S>& q) {
  report_dropped(task);
  task.gen.hold({task.state.data.o[kDof], task.state.data.R[kDof]}, task.state.R_ref);
  task.q_queue_end = q;
}

/// The motion an abort of this tick ends, into the report: while homing, the home command (its
/// move's end, which the generator reports done in a fault's tick at the end of the move, is not the
/// home's: finish_homing reports that); otherwise the generator's running motion, unless a
/// re-target brakes it (its abort, superseded, was reported: none). A yield (a collision) that a
/// stop, an enable or a disable of the same tick left at once (holding, disabled) ends the motion
/// here, at the measured pose q: motion_apply sees no change into or out of yielding.
template <class S>
[[gnu::noinline]] void report_abort(ControlTask<S>& task, MotionState before, const Vec6<S>& q, bool yield) {
  MotionReport& rep = task.report;
  if (before == MotionState::kHoming) {
    rep.aborted_id = task.homing.id;
    rep.done_id = 0;
  } else {
    rep.aborted_id = task.gen.braking() ? 0 : task.gen.running_id();
  }
  const MotionState s = task.machine.state;
  if (yield && (s == MotionState::kHolding || s == MotionState::kDisabled)) hold_measured_pose(task, q);
}

/// A tick with faults (category 0): an encoder's fault unhomes the arm; the running motion (its
/// abort reported) and the moves waiting (named, dropped) end at once, so that from this tick on
/// nothing runs nor is queued (the state frame's queued and running_id 0) until an enable holds.
template <class S>
[[gnu::noinline]] void fault_motion(ControlTask<S>& task, std::uint32_t faults) {
  if ((faults & kFaultsUnhoming) != 0) task.homed = false;
  report_dropped(task);
  task.gen.halt();
}

/// A re-target accepted: the running motion brakes from sample `next` on, aborted superseded (once:
/// not again when it brakes already, for a re-target before), and the moves waiting are dropped.
template <class S>
[[gnu::noinline]] void retarget(ControlTask<S>& task, std::uint64_t next) {
  if (task.gen.source() != MotionSource::kHold && !task.gen.braking()) {
    task.report.aborted_id = task.gen.running_id();
    task.report.abort = MotionReason::kSuperseded;
  }
  report_dropped(task);
  task.gen.brake(next, params::kControlHz, task.limits);
}

/// What an accepted command and the machine's step ask of the generator and the controller, from
/// the next tick on.
template <class S>
void motion_apply(ControlTask<S>& task, const MotionStep& st, MotionState before, const Vec6<S>& q) {
  const std::uint64_t next = task.tick + 1;
  const bool accepted = st.outcome == CommandOutcome::kAccepted;
  const TaskCommand<S>& cmd = task.pending;
  if (accepted && (cmd.verb == MotionVerb::kMoveTo || cmd.verb == MotionVerb::kPaper ||
                   cmd.verb == MotionVerb::kStream || cmd.verb == MotionVerb::kClear))
    task.contact = false;
  if (st.enabling) {
    const Vec6<S> q_now = task.homed ? q : coarse_from_pots(task, q);
    controller_restart(task.model, task.state, q_now);
    hold_measured_pose(task, q_now);
    task.stuck.reset(true);
    task.residual.reset();
    task.contact = false;
    task.ramping = true;
    task.ramp_start = next;
  }
  if (accepted && (cmd.verb == MotionVerb::kMoveTo || cmd.verb == MotionVerb::kHome)) {  // a planned move
    if (cmd.brake) retarget(task, next);  // a home starts from holding only
    task.gen.push(cmd.move, cmd.id);
    task.gen.start_moves(next);
    task.q_queue_end = cmd.q_end;
  }
  if (accepted && cmd.verb == MotionVerb::kHome) start_homing(task, cmd.id);
  if (accepted && cmd.verb == MotionVerb::kDeclarePose) declare_pose(task, q, cmd.pose);
  if (before == MotionState::kHoming && st.machine.state != MotionState::kHoming) end_homing(task);
  if (st.completion == MotionCompletion::kHomed) finish_homing(task, q);
  if (accepted && cmd.verb == MotionVerb::kPaper)
    task.gen.start_paper(task.gains.trajectory, next, cmd.id, task.gen.held_orientation());
  if (accepted && cmd.verb == MotionVerb::kStream)
    task.gen.start_stream(cmd.period, cmd.relative, cmd.limits, cmd.id, task.stream_timeout_ticks);
  // Into yielding, the motion is dropped; out of it, the pose reached is held.
  if ((st.machine.state == MotionState::kYielding) != (before == MotionState::kYielding)) hold_measured_pose(task, q);
  if (st.machine.state == MotionState::kStopping && before != MotionState::kStopping) {
    report_dropped(task);
    task.gen.stop(next, params::kControlHz, task.limits);
    task.q_queue_end = q;  // near where the stop ends: the next check's Newton steps start the path there
  }
  if (accepted && cmd.verb == MotionVerb::kClear) {
    task.sup = {SupervisorState::kInit, 0};
    task.stuck.reset(true);  // from this tick's torques: a clear while holding is no torque change
    task.residual.reset();
    task.saturation.reset();
    task.position.reset();  // learnt again from the next samples (an encoder fault also unhomed the arm)
  }
  if (!motion_powered(st.machine.state)) task.ramping = false;
}

/// The motion stage at the end of a tick: the tick's command, faults and the generator's events
/// through the state machine (motion_next), then what it decided (motion_apply). Returns whether
/// torque may reach the DACs in this tick.
template <class S>
bool motion_update(ControlTask<S>& task, std::uint32_t faults, bool measured, const Vec6<S>& q, const MotionEvents& ev,
                   MotionReason stop_request, bool yield) {
  task.report = {};
  MotionInput in;
  in.command = motion_command_of_tick(task, measured, q);
  in.homed = task.homed;
  in.faults = faults;
  in.stop_request = stop_request;
  in.yield = yield;
  in.motion_finished = ev.finished;
  in.stopped = ev.stopped;
  const MotionState before = task.machine.state;
  const MotionStep st = motion_next(task.machine, in);
  task.machine = st.machine;
  MotionReport& rep = task.report;
  if (in.command != MotionCommand::kNone) {
    rep.outcome = st.outcome;
    rep.refusal = st.refusal;
    rep.cause = st.cause;
  }
  rep.abort = st.abort;
  rep.completion = st.completion;
  rep.done_id = ev.done_id;
  if (st.abort != MotionReason::kNone) report_abort(task, before, q, yield);
  if (faults != 0) fault_motion(task, faults);
  motion_apply(task, st, before, q);
  if (rep.verb != MotionVerb::kNone) task.pending.verb = MotionVerb::kNone;  // answered: taken
  return st.torque;
}

/// The position cross-check of a tick with a measured sample, on a HAL with potentiometers (none
/// otherwise, with the parameter pots 0, or while homing: homing_faults reads the index pulses then),
/// whether the torque is on or not (an arm moved by hand).
template <class S, class Hal>
std::uint32_t position_faults(ControlTask<S>& task, Hal& hal, const Vec6<S>& q) {
  if constexpr (hal::PositionHal<Hal>) {
    if (!task.pots || task.machine.state == MotionState::kHoming) return 0;
    std::uint16_t pots[kDof];
    const bool valid = hal.read_pots(pots);
    return task.position.check(pots, valid, q);
  } else {
    (void)task, (void)hal, (void)q;
    return 0;
  }
}

/// Homing's checks of a tick with a measured sample (homing_faults), while homing on a HAL with
/// potentiometers and index pulses (homing cannot start without: no_pots).
template <class S, class Hal>
std::uint32_t index_faults(ControlTask<S>& task, Hal& hal, const std::int32_t counts[kDof], const MotionEvents& ev) {
  if constexpr (hal::PositionHal<Hal>) {
    if (task.machine.state == MotionState::kHoming) return homing_faults(task, hal, counts, ev);
  } else {
    (void)task, (void)hal, (void)counts, (void)ev;
  }
  return 0;
}

/// One tick, the block diagram in five timed stages (TickStage): read, checks, step, monitors,
/// output; then the supervisor and the motion state machine. Returns the fault bits detected in
/// this tick. On any fault, whenever the supervisor is not in kRun or the motion state machine has
/// the torque off, and in a tick without a valid sample (read_encoders() false: no control step),
/// every DAC gets code 0 in this same tick.
template <class S, hal::ControlHal Hal>
std::uint32_t control_tick(ControlTask<S>& task, Hal& hal) {
  std::uint32_t mark[kTickStages + 1];
  mark[kStageRead] = hal.cycles();
  // read
  std::uint32_t faults = hal.io_faults();
  std::int32_t counts[kDof];
  const bool sampled = hal.read_encoders(counts);
  mark[kStageChecks] = hal.cycles();
  // checks
  bool moved[kDof] = {};
  task.jump.tick();
  if (sampled) faults |= task.range.check(counts) | task.jump.check(counts, moved);
  mark[kStageStep] = hal.cycles();
  // step
  for (int i = 0; i < kDof; ++i) task.codes[i] = 0;
  // The angles of a sample that passed the checks (the others are not converted: a wild count
  // would saturate a fixed-point angle); the start pose otherwise, unused.
  const bool measured = sampled && faults == 0;
  const Vec6<S> q = measured ? angles_from_counts(task.q_start, task.io, counts) : task.q_start;
  const bool stepped = measured && task.sup.state != SupervisorState::kFault && motion_powered(task.machine.state);
  MotionEvents ev;
  if (task.sample.valid) {
    task.gen.stream_setpoint(task.sample.x, task.sample.end, task.sample.has_velocity ? &task.sample.v : nullptr);
    task.sample.valid = false;
  }
  if (stepped) {
    const bool yielding = task.machine.state == MotionState::kYielding;
    task.desired = yielding ? yield_reference(task) : task.gen.at_tick(task.tick, params::kControlHz, ev);
    const std::uint32_t s0 = hal.cycles();
    task.last = control_step(task.model, task.gains, task.mode, task.state, q, task.desired);
    task.step_timing.add(hal.cycles() - s0);
    faults |= task.last.status;  // non_finite, singular
  }
  mark[kStageMonitors] = hal.cycles();
  // monitors
  if (stepped && task.last.status == kFaultNone) faults |= step_monitor_faults(task, counts, moved);
  if (measured) faults |= position_faults(task, hal, q);
  const CollisionReaction collision = take_collision(task, faults);
  mark[kStageOutput] = hal.cycles();
  // output
  if (stepped && task.ramping) ramp_torque(task);
  bool clipped = false;
  if (stepped) {
    // Each DAC drives a motor: C^T tau where the drive train couples the joints.
    Vec6<S> tau_m;
    const Vec6<S>& tau = task.io.coupled() ? (tau_m = motor_torques(task.io, task.last.tau)) : task.last.tau;
    for (int i = 0; i < kDof; ++i) {
      const bool c = torque_to_code(i, tau(i), task.codes[i]);
      clipped = clipped || c;
      faults |= task.saturation.check(i, c);
    }
  }
  // A fixed-point saturation in the monitors or the torque conversion (the step reports its own).
  if (math::take_arithmetic_fault<S>()) faults |= kFaultOverflow;
  // The step's own duration against the period (the next tick would have arrived).
  const std::uint32_t elapsed = hal.cycles() - mark[kStageRead];
  if (task.period_cycles != 0 && elapsed > task.period_cycles) faults |= kFaultOverrun;

  if (measured) faults |= index_faults(task, hal, counts, ev);
  task.sup = supervisor_next(task.sup, {faults, task.jump.have_counts});
  const MotionReason stop_request = tick_stop_request(task, stepped, q, collision);
  const bool torque =
      motion_update(task, faults, measured, q, ev, stop_request, collision == CollisionReaction::kYield);
  if (!torque_enabled(task.sup) || !torque)
    for (int i = 0; i < kDof; ++i) task.codes[i] = 0;
  if (!stepped || !torque_enabled(task.sup) || !torque)
    task.residual.unprime();
  else
    task.residual.applied(clipped ? applied_torque(task) : task.last.tau);
  hal.write_dacs(task.codes);
  hal.fault_output(task.sup.state == SupervisorState::kFault);
  mark[kTickStages] = hal.cycles();
  task.stages.add(mark);
  task.timing.add(mark[kTickStages] - mark[kStageRead]);
  ++task.tick;
  return faults;
}

/// Asks the next tick for a category-2 stop of the running motion, for `why` (a reason of the
/// runtime's, e.g. kLinkSilent): the tick takes it after its own (a reached limit, a stale stream)
/// and only while moving (motion_next ignores a stop request in any other state). Call it where the
/// tick runs (the control interrupt), before the tick; each tick takes the request it finds and
/// clears it.
template <class S>
void request_stop(ControlTask<S>& task, MotionReason why) {
  task.stop_request = why;
}

/// A path check's result as a refusal (none: the path is clear). A target beyond the arm's reach
/// (kUnreachable) is out of its workspace.
constexpr MotionReason path_refusal(PathStatus s) {
  switch (s) {
    case PathStatus::kOk:
      return MotionReason::kNone;
    case PathStatus::kNearSingular:
      return MotionReason::kNearSingular;
    case PathStatus::kOutOfWorkspace:
    case PathStatus::kUnreachable:
      break;
  }
  return MotionReason::kOutOfWorkspace;
}

/// The path check of a move_to prepare_move planned, or of a home's move (nothing if it refused it already).
template <class S>
void check_prepared_move(ControlTask<S>& task, TaskCommand<S>& c) {
  if ((c.verb != MotionVerb::kMoveTo && c.verb != MotionVerb::kHome) || c.refusal != MotionReason::kNone) return;
  const Vec6<S> seed = c.brake ? task.state.adapt.q_prev : task.q_queue_end;
  const PathCheck<S> pc = check_path(task.model, task.check_data, c.move, task.gen.reference_orientation(), seed);
  c.refusal = path_refusal(pc.status);
  c.q_end = pc.q_end;
}

/// Prepares a move_to in full, outside the tick (a board's main loop, the host's driver): the
/// limits, the queue and the plan (prepare_move), then the path check (check_path) from the joint
/// angles where the queue ends, or, for a move that starts where a braked motion comes to rest,
/// from the last measured ones. Put the result in task.pending for the next tick.
template <class S>
TaskCommand<S> prepare_checked_move(ControlTask<S>& task, const MoveRequest<S>& req, std::uint32_t id) {
  TaskCommand<S> c = prepare_move(task.gen, task.limits, task.tick, params::kControlHz, req, id);
  check_prepared_move(task, c);
  return c;
}

/// Prepares a home in full, outside the tick (like prepare_checked_move): the homing move from the
/// last measured angles, path-checked.
template <class S>
TaskCommand<S> prepare_checked_home(ControlTask<S>& task, std::uint32_t id) {
  TaskCommand<S> c =
      prepare_home(task.gen, home_limits(task), task.model, task.check_data, task.io, task.state.adapt.q_prev, id);
  check_prepared_move(task, c);
  return c;
}

/// Puts a setpoint of stream `id` (with its velocity, or none) into the task's mailbox for the next
/// tick (prepare_setpoint):
/// false, counted in task.dropped, when no stream of that id runs; a setpoint not yet taken is
/// replaced (and counted).
template <class S>
bool offer_setpoint(ControlTask<S>& task, std::uint32_t id, const Vec3<S>& position, const Vec3<S>& rpy, bool has_rpy,
                    bool end, const Vec6<S>* velocity = nullptr) {
  StreamSample<S> s;
  if (!prepare_setpoint(task.gen, id, position, rpy, has_rpy, end, s, velocity)) {
    ++task.dropped;
    return false;
  }
  if (task.sample.valid) ++task.dropped;
  task.sample = s;
  return true;
}

/// A tick without a new sample in which the I/O layer keeps the outputs (a short, bounded gap, e.g.
/// a sensor frame not yet in on a timer-paced link): no control step, the DACs get the previous codes
/// again, the sample clock and the age of the last encoder sample run on. It takes no command and
/// reports nothing (an empty report: the previous tick's answer is not given twice).
template <class S, hal::ControlHal Hal>
void hold_tick(ControlTask<S>& task, Hal& hal) {
  task.report = {};
  task.jump.tick();
  hal.write_dacs(task.codes);
  ++task.tick;
}

}  // namespace osc
