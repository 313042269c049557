// The control task's type (ControlTask): its state, the parts it owns (model, gains, controller
// state, monitors, motion generator and state machine, homing, I/O map) and their set-up. Its tick,
// the stages that run on it, is osc/runtime/control_task.hpp.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "hal/hal.hpp"
#include "osc/control/controller.hpp"
#include "osc/runtime/command_prep.hpp"
#include "osc/runtime/homing.hpp"
#include "osc/runtime/identify_run.hpp"
#include "osc/runtime/io.hpp"
#include "osc/runtime/monitors.hpp"
#include "osc/runtime/motion_commands.hpp"
#include "osc/runtime/motion_stage.hpp"
#include "osc/runtime/supervisor.hpp"
#include "osc/runtime/timing.hpp"

namespace osc {

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
  MomentumSample<S> momentum;            // the sample the residual monitor's last turn took (joint -1: none)
  CollisionReaction collision_reaction;  // what the residual monitor's collision does (set_collision)
  std::uint32_t stream_timeout_ticks;    // a stream is stale after max(2 periods, this) without a setpoint
  bool contact;                          // a collision was reacted to (category 2, yield) since the last motion
  SaturationMonitor saturation;
  OscillationMonitor oscillation;
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
  Vec6<S> q_lo, q_hi;  // the running motion's joint limits (motion_limits_from, motion_limits_reached)
  // The drive check (osc/runtime/drive_monitor.hpp), on a HAL with current readback (hal::CurrentHal).
  DriveMonitor drive;
  bool drive_check;           // the amplifiers' current monitors are wired: the drive check runs (has_current_monitors)
  double dither_fraction;     // the test dither's amplitude, of each channel's full scale (0: off)
  Vec6<S> dither_torque;      // its joint torques: each channel gets +-dither_fraction of its full scale (C^-T)
  std::uint8_t dither_half;   // its half period [ticks] (parameter dither_half_period)
  std::uint8_t dither_phase;  // the ticks of the current sign so far
  std::int8_t dither_now;     // the current sign
  // The payload link 6 carries (parameters payload_*: set_payload), and link 6 without it (with its
  // tensor's Cholesky factor), from which set_payload builds the model's link 6 again.
  Payload payload;
  typename Model<S>::Link link6;
  Vec3<S> link6_root[2];
  // Each drive's armature correction (parameter armature_correction: set_armature) and its described
  // armature G^2 J_m (the diagonal of the model init took: Model::of's, uncoupled), which it corrects.
  double armature_correction[kDof];
  double armature_base[kDof];
  // An identification run's ticks for the main loop's filter and estimate (osc/runtime/identify_run.hpp).
  IdentifySampler<S> identify;

  void init(const Model<S>& m, const Gains<S>& g, FrictionMode fm, const Vec6In<S>& q0, std::uint32_t period = 0,
            TaskStart start = TaskStart::kPaper) {
    model = m;
    keep_described();
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
    motion_limits_from(*this, Vec6<S>(q0));
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
    momentum.joint = -1;  // none: the rest unread
    collision_reaction = CollisionReaction::kCategory0;
    stream_timeout_ticks = stream::ticks(kStreamTimeoutMin);
    contact = false;
    saturation.reset();
    oscillation.reset();
    position.reset();
    pots = has_pots(robot::kDriveTrain);
    drive.reset();
    drive_check = has_current_monitors(robot::kDriveTrain);
    dither_fraction = params::kDitherAmplitude;
    dither_half = params::kDitherHalfPeriod;
    dither_phase = 0;
    dither_now = 1;
    // The paper's procedure places the arm at q_start; absolute encoders read it from power-on.
    homed = start == TaskStart::kPaper || has_absolute_encoders(robot::kDriveTrain);
    homing = {};
    home_speed = lit_array<S>(params::kHomeSpeed);
    set_encoders(robot::kEncodersUniform);
    sup = {SupervisorState::kInit, 0};
    period_cycles = period;
    timing = {};
    step_timing = {};
    stages = {};
    identify.reset();
  }
  /// The model's link 6 and drives' armatures as described (init's model), which the payload and the armature
  /// correction then change: none of either.
  [[gnu::cold]] void keep_described() {
    payload = {};
    link6 = model.link[kDof - 1];
    link6_root[0] = model.root_diagonal[kDof - 1];
    link6_root[1] = model.root_lower[kDof - 1];
    for (int i = 0; i < kDof; ++i)
      armature_correction[i] = 0, armature_base[i] = static_cast<double>(model.armature(i));
  }
  /// The payload at the flange (osc/robots/arm.hpp, Payload): the model's link 6 becomes link 6 and
  /// the payload together (combine_bodies), which the model's every use then sees: the controller's
  /// inertia and gravity, the observer, the residual monitor and its thresholds, the path checks. No
  /// payload: link 6 as init had it, bit for bit. Outside the tick, with the torque off (the
  /// parameters' access), in double: compiled for size.
  [[gnu::cold]] void set_payload(const Payload& p) {
    payload = p;
    model = without_payload();
    if (payload_empty(p)) return;
    const RigidBody load{p.mass,
                         {p.com[0], p.com[1], p.com[2]},
                         {p.inertia[0], p.inertia[1], p.inertia[2], p.inertia[3], p.inertia[4], p.inertia[5]}};
    model.set_inertial(kDof - 1, combine_bodies(model.inertial(kDof - 1), load));
  }
  /// The model without the payload (link 6 as init had it), the armature as it is: an identify run's
  /// model when it estimates the whole payload (IdentifyRun::start's bare).
  [[gnu::cold]] Model<S> without_payload() const {
    Model<S> m = model;
    m.link[kDof - 1] = link6;
    m.root_diagonal[kDof - 1] = link6_root[0];
    m.root_lower[kDof - 1] = link6_root[1];
    return m;
  }
  /// Drive i's armature correction c: the model's armature (A(q)'s diagonal) is then the described plus
  /// the correction, which every use of A(q) sees (as the payload). On a coupled arm the rotors' inertia
  /// C^-T diag(G^2 J_m) C^-1 has terms off the diagonal, which the model leaves out (docs/adaptation.md,
  /// section 6). Outside the tick, with the torque off.
  [[gnu::cold]] void set_armature(int i, double c) {
    armature_correction[i] = c;
    model = with_armature(armature_correction);
  }
  /// The model with the drives' armature corrections `correction` (a candidate's: the parameters' check).
  [[gnu::cold]] Model<S> with_armature(const double (&correction)[kDof]) const {
    Model<S> m = model;
    for (int i = 0; i < kDof; ++i) m.armature(i) = lit<S>(armature_base[i] + correction[i]);
    return m;
  }
  /// The encoders and coupling of the arm (osc/robots/arm.hpp, EncoderMap): the angles, the
  /// torques' DAC channels, the plausible readings and steps, the stuck-encoder monitor's channels.
  [[gnu::cold]] void set_encoders(const EncoderMap& map) {  // set-up, in double: compiled for size
    io = IoMap<S>::of(map);
    model.drives = io.drives;  // the friction each motor's (DriveCoupling)
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
    set_dither(dither_fraction);
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
  /// The test dither's amplitude, a fraction of each channel's full scale (0: off; the drive check's dither
  /// check runs with it): each channel's code gets +-fraction of its full scale, the joints C^-T of it.
  [[gnu::cold]] void set_dither(double fraction) {
    dither_fraction = fraction;
    Vec6<S> d;
    for (int c = 0; c < kDof; ++c) d(c) = lit<S>(fraction * robot::kDrives.torque_limit[c]);
    dither_torque = io.coupled() ? joint_torques_of_motors(io, d) : d;
    drive.start_dither(static_cast<std::int32_t>(std::lround(fraction * static_cast<double>(kDacMaxCode))));
  }
  /// The dither's sign in this tick's codes: a square wave of dither_half ticks a sign (a tick that dithers).
  std::int8_t dither_sign() {
    if (++dither_phase > dither_half) dither_phase = 1, dither_now = static_cast<std::int8_t>(-dither_now);
    return dither_now;
  }
  /// Encoder counts per radian of channel i (its motor angle referred to its joint).
  double counts_per_rad(int i) const { return static_cast<double>(io.counts_per_rad(i)); }
  /// Test hook (fault injection): poisons the observer state with a NaN.
  void inject_nonfinite() { state.obs.y(0) = S(0) / S(0); }
};

}  // namespace osc
