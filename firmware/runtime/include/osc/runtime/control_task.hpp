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
#include "osc/runtime/monitors.hpp"
#include "osc/runtime/supervisor.hpp"
#include "osc/runtime/timing.hpp"

namespace osc {

static_assert(has_spherical_wrist(robot::kArm),
              "the kernels factor J block-triangularly (SphericalWristJacobianFactor): the robot needs a "
              "spherical wrist centred at the frame-6 origin");

template <class S>
struct ControlTask {
  Model<S> model;
  Gains<S> gains;
  FrictionMode mode;
  Vec6<S> q_start;                            // joint angles at which the encoders read zero
  Vec6<math::io_scalar_t<S>> counts_per_rad;  // encoder counts per joint radian (the robot's drives by default)
  std::uint64_t tick;                         // samples since start (64 bits: never wraps in service)
  ControllerState<S> state;
  PaperMotion<S> motion;      // the motion source: the paper's (68) about the start pose
  StepOutput<S> last;         // the most recent step, for telemetry
  std::int32_t codes[kDof];   // the most recent DAC codes
  EncoderRangeMonitor range;  // the encoder checks (osc/runtime/monitors.hpp)
  EncoderJumpMonitor jump;
  StuckEncoderMonitor<S> stuck;  // the step's checks
  SaturationMonitor saturation;
  Supervisor sup;
  std::uint32_t period_cycles;  // overrun budget per step (0: not checked)
  StepTiming timing;            // the whole tick: I/O, step, supervision
  StepTiming step_timing;       // the control step alone: observer + controller + adaptation
  TickTiming stages;            // each stage of the tick (TickStage)

  void init(const Model<S>& m, const Gains<S>& g, FrictionMode fm, const Vec6In<S>& q0, std::uint32_t period = 0) {
    model = m;
    gains = g;
    mode = fm;
    q_start = q0;
    tick = 0;
    controller_init(model, state, q0);
    motion = {gains.trajectory, state.data.o[kDof], 0};
    for (int i = 0; i < kDof; ++i) codes[i] = 0;
    jump.reset();
    stuck.reset();
    saturation.reset();
    set_encoder_resolution(robot::kDrives.encoder_counts_per_motor_rev);
    sup = {SupervisorState::kInit, 0};
    period_cycles = period;
    timing = {};
    step_timing = {};
    stages = {};
  }
  /// Encoders of another resolution than the robot table's (counts per motor revolution, after
  /// quadrature decoding): the count scaling and the plausible step per tick follow it.
  void set_encoder_resolution(double counts_per_motor_rev) {
    for (int i = 0; i < kDof; ++i) {
      const double c = osc::counts_per_rad(i, counts_per_motor_rev);
      counts_per_rad(i) = lit<math::io_scalar_t<S>>(c);
      jump.set(i, c);
      range.set(i, static_cast<double>(q_start(i)), c);
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

/// The checks of a completed step against what the controller commanded (docs/safety.md): the
/// stuck-encoder, tracking and friction-estimate monitors (osc/runtime/monitors.hpp).
template <class S>
std::uint32_t step_monitor_faults(ControlTask<S>& task, const bool moved[kDof]) {
  const StepOutput<S>& out = task.last;
  std::uint32_t faults = task.stuck.check(out, moved, task.tick, task.gains.dt, task.counts_per_rad);
  faults |= TrackingMonitor<S>::check(out.e);
  if (task.mode == FrictionMode::kAdaptive)
    faults |= ThetaBandMonitor<S>::check(task.state.adapt.theta_hat, task.gains.theta_max);
  return faults;
}

/// One tick, the block diagram in five timed stages (TickStage): read, checks, step, monitors,
/// output. Returns the fault bits detected in this tick. On any fault, whenever the supervisor is
/// not in kRun, and in a tick without a valid sample (read_encoders() false: no control step), every
/// DAC gets code 0 in this same tick.
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
  const bool stepped = sampled && task.sup.state != SupervisorState::kFault && faults == 0;
  if (stepped) {
    const Vec6<S> q = angles_from_counts(task.q_start, task.counts_per_rad, counts);
    const Desired<S> d = task.motion.at_tick(task.tick, params::kControlHz);
    const std::uint32_t s0 = hal.cycles();
    task.last = control_step(task.model, task.gains, task.mode, task.state, q, d);
    task.step_timing.add(hal.cycles() - s0);
    faults |= task.last.status;  // non_finite, singular
  }
  mark[kStageMonitors] = hal.cycles();
  // monitors
  if (stepped && task.last.status == kFaultNone) faults |= step_monitor_faults(task, moved);
  mark[kStageOutput] = hal.cycles();
  // output
  if (stepped)
    for (int i = 0; i < kDof; ++i)
      faults |= task.saturation.check(i, torque_to_code(i, task.last.tau(i), task.codes[i]));
  // A fixed-point saturation in the monitors or the torque conversion (the step reports its own).
  if (math::take_arithmetic_fault<S>()) faults |= kFaultOverflow;
  // The step's own duration against the period (the next tick would have arrived).
  const std::uint32_t elapsed = hal.cycles() - mark[kStageRead];
  if (task.period_cycles != 0 && elapsed > task.period_cycles) faults |= kFaultOverrun;

  task.sup = supervisor_next(task.sup, {faults, task.jump.have_counts});
  if (!torque_enabled(task.sup))
    for (int i = 0; i < kDof; ++i) task.codes[i] = 0;
  hal.write_dacs(task.codes);
  hal.fault_output(task.sup.state == SupervisorState::kFault);
  mark[kTickStages] = hal.cycles();
  task.stages.add(mark);
  task.timing.add(mark[kTickStages] - mark[kStageRead]);
  ++task.tick;
  return faults;
}

/// A tick without a new sample in which the I/O layer keeps the outputs (a short, bounded gap, e.g.
/// a sensor frame not yet in on a timer-paced link): no control step, the DACs get the previous codes
/// again, the sample clock and the age of the last encoder sample run on.
template <class S, hal::ControlHal Hal>
void hold_tick(ControlTask<S>& task, Hal& hal) {
  task.jump.tick();
  hal.write_dacs(task.codes);
  ++task.tick;
}

}  // namespace osc
