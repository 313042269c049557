// The control task the 1 kHz timer interrupt runs: read encoders -> checks -> angles ->
// reference -> control step (observer, controller, adaptation) -> monitors -> torques to DAC
// codes -> the supervisor and the motion state machine decide -> write.
// Bound to a HAL at compile time; the same code runs against the simulated plant on the host and
// on the targets.
// The HAL is the concept hal::ControlHal (hal/hal.hpp).
// This header gives all of the task: its tick (control_tick, a call per stage of OSC_TICK_STAGE_LIST:
// stage_read .. stage_output; hold_tick) and the checks its stages run are here; it includes the
// task's type (osc/runtime/task.hpp), homing (osc/runtime/homing.hpp), the tick's motion stage
// (osc/runtime/motion_stage.hpp) and the commands' preparation outside the tick
// (osc/runtime/command_prep.hpp).
#pragma once

#include <array>
#include <cstdint>

#include "hal/hal.hpp"
#include "osc/runtime/task.hpp"

namespace osc {

/// The `momentum` law's input (MomentumSample, osc/control/adaptation.hpp), from the sample the residual
/// monitor took of the joint whose turn it is. The sample's noise is at most the residual's quantisation
/// bound taken as twice its standard deviation; samples params::kIdentifyEvery ticks apart that the
/// filter correlates over 1 / K count as 2 / (K dt kIdentifyEvery) times fewer independent ones (the
/// integral scale of a first-order filter's correlation exp(-K |t|) is 2 / K).
template <class S>
MomentumSample<S> momentum_sample(const ResidualMonitor<S>& m) {
  static constexpr std::array<S, kDof> kCorrelation = [] {
    std::array<S, kDof> c{};
    for (int i = 0; i < kDof; ++i) {
      const double f = 2.0 / (params::kResidualGain[i] * params::kDt * params::kIdentifyEvery);
      c[i] = lit<S>(f > 1 ? f : 1);
    }
    return c;
  }();
  static constexpr S kMaxRatio = lit<S>(params::kIdentifyMaxRatio);
  const int i = m.sample_joint;
  const S half = lit<S>(0.5) * m.noise_bound(i);
  return {i, m.sample, m.within(i, kMaxRatio), half * half, kCorrelation[i]};
}

/// The stuck-encoder monitor's check of a completed step, per encoder channel: a coupled motor turns with C^-1 qd
/// and carries C^T tau. The joint rates the reference commands, J^-1 x_d dot, with the step's J.
template <class S>
std::uint32_t stuck_encoder_check(ControlTask<S>& task, const std::int32_t counts[kDof], const bool moved[kDof],
                                  bool homing) {
  const StepOutput<S>& out = task.last;
  Vec6<S> tau_m, rate_m;
  const Vec6<S> qd_ref = task.state.os.Jf.solve(task.desired.xd);
  const bool coupled = task.io.coupled();
  const Vec6<S>& tau = coupled ? (tau_m = motor_torques(task.io, out.tau)) : out.tau;
  const Vec6<S>& rate = coupled ? (rate_m = motor_rates(task.io, qd_ref)) : qd_ref;
  return task.stuck.check(tau, rate, counts, moved, task.tick, task.gains.dt, task.io.counts_per_rad, homing);
}

/// The checks of a completed step against what the controller commanded (docs/safety.md): the
/// stuck-encoder, tracking and friction-estimate monitors (osc/runtime/monitors.hpp).
/// rate_m: the motors' rates C^-1 q^dot^ of the step (stage_step's; unread on an uncoupled arm).
template <class S>
std::uint32_t step_monitor_faults(ControlTask<S>& task, const std::int32_t counts[kDof], const bool moved[kDof],
                                  const Vec6<S>& rate_m) {
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
  else
    faults = stuck_encoder_check(task, counts, moved, homing);
  const AdaptationState<S>& ad = task.state.adapt;
  const bool adaptive = task.mode == FrictionMode::kAdaptive;
  const Vec6<S> decay = ad.w_prev.sti.cwiseAbs();
  const bool identify = adaptive && task.gains.adaptation == AdaptationLaw::kMomentum;
  const bool coupled_friction = task.model.drives.coupled();
  const ResidualInput<S> in{task.state.data.A,
                            task.state.os.g,
                            out.tau_bias,
                            out.tau_f_hat,
                            ad.qd_hat_prev,
                            decay,
                            adaptive ? &ad.theta_hat : nullptr,
                            identify ? &ad.identifier.proven : nullptr,
                            &task.state.data.J,
                            &task.state.os,
                            &out.e,
                            coupled_friction ? &task.io : nullptr,
                            coupled_friction ? &rate_m : nullptr};
  // The residual monitor's turn: the controller's even steps, whose model turn leaves the time for it.
  const bool turn = even_step(task.state);
  task.residual.sample_joint = identify && turn ? momentum_turn(task.state.adapt) : -1;
  task.residual.contact = task.machine.state == MotionState::kYielding || task.contact;
  task.residual.holding = task.machine.state == MotionState::kHolding;
  faults |= task.residual.check(in, task.io, counts, moved, task.tick, turn);
  // The momentum law's stage of the control law, on the sample the residual monitor's last turn took, in the
  // step after it (the one that computes Psi, not the thresholds).
  if (identify && task.momentum.joint >= 0) adaptation_identify(task.gains, task.state.adapt, task.momentum);
  task.momentum.joint = -1;
  if (identify && turn) task.momentum = momentum_sample(task.residual);
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

/// The drive check of a tick (DriveMonitor), on a HAL with current readback whose monitors are wired
/// (drive_check): each amplifier's current and fault line, whether the torque is on or not (off, the
/// currents must be 0). It tells the residual monitor whether it ran and which channels it suspects.
template <class S, class Hal>
std::uint32_t drive_faults(ControlTask<S>& task, Hal& hal) {
  if constexpr (hal::CurrentHal<Hal>) {
    if (!task.drive_check) return 0;
    std::int16_t adc[kDof];
    const bool valid = hal.read_currents(adc);
    const std::uint32_t faults = task.drive.check(adc, valid, hal.amp_faults(), task.tick);
    task.residual.drives_checked = valid;
    task.residual.drive_suspect = task.drive.suspect;
    return faults;
  } else {
    (void)task, (void)hal;
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

/// What the stages of one tick hand each other (control_tick): the block diagram's wires.
template <class S>
struct TickData {
  std::uint32_t faults = 0;   // the fault bits detected in this tick so far
  std::int32_t counts[kDof];  // the encoder sample (read)
  bool sampled = false;       // read_encoders() gave a sample
  bool moved[kDof] = {};      // the channels whose count changed (the jump monitor)
  bool measured = false;      // the sample passed the checks: q holds its angles
  bool stepped = false;       // the control step runs in this tick
  Vec6<S> q;                  // the measured angles (the start pose otherwise, unused)
  MotionEvents ev;            // the motion source's events of this tick
  // The reaction to the residual monitor's collision (category 0: none, or the fault stays).
  CollisionReaction collision = CollisionReaction::kCategory0;
  bool clipped = false;    // a DAC code was clipped at its range
  bool torque = false;     // the supervisor and the motion state machine let torque reach the DACs
  std::int8_t dither = 0;  // the test dither's sign in the step's codes (0: none)
  // The step's motor rates C^-1 q^dot^ (stage_step), where a coupled friction law or an identify run reads them.
  Vec6<S> rate_m;
};

/// read: the HAL's I/O faults (E-stop, drives) and the encoder sample.
template <class S, hal::ControlHal Hal>
void stage_read(Hal& hal, TickData<S>& t) {
  t.faults = hal.io_faults();
  t.sampled = hal.read_encoders(t.counts);
}

/// checks: the encoder monitors (range, jump); the angles of a sample that passed them (the others
/// are not converted: a wild count would saturate a fixed-point angle), the start pose otherwise,
/// unused; whether the control step runs.
template <class S>
void stage_checks(ControlTask<S>& task, TickData<S>& t) {
  task.jump.tick();
  if (t.sampled) t.faults |= task.range.check(t.counts) | task.jump.check(t.counts, t.moved);
  t.measured = t.sampled && t.faults == 0;
  t.q = t.measured ? angles_from_counts(task.q_start, task.io, t.counts) : task.q_start;
  t.stepped = t.measured && task.sup.state != SupervisorState::kFault && motion_powered(task.machine.state);
}

/// reference: the stream setpoint handed to the motion source, then the desired state of a tick
/// that steps: the motion source's (its events in t.ev), a yielding arm's own pose.
template <class S>
void stage_reference(ControlTask<S>& task, TickData<S>& t) {
  if (task.sample.valid) {
    task.gen.stream_setpoint(task.sample.x, task.sample.end, task.sample.has_velocity ? &task.sample.v : nullptr);
    task.sample.valid = false;
  }
  if (!t.stepped) return;
  if (task.machine.state == MotionState::kYielding)
    task.desired = yield_reference(task);
  else if (task.gen.source() == MotionSource::kExcitation)
    task.desired = excitation_reference(task, t.ev);
  else
    task.desired = task.gen.at_tick(task.tick, params::kControlHz, t.ev);
}

/// step: the control step (observer, controller, adaptation); its stage's time is the step's (step_timing).
template <class S>
void stage_step(ControlTask<S>& task, TickData<S>& t) {
  if (!t.stepped) return;
  control_step(task.model, task.gains, task.mode, task.state, t.q, task.desired, task.last);
  t.faults |= task.last.status;  // non_finite, singular
  // An identification run's samples: its own motion only (not its stop's, whose time is slowed).
  const bool sample =
      task.gen.source() == MotionSource::kExcitation && !task.gen.braking() && task.last.status == kFaultNone;
  if (sample || task.model.drives.coupled()) t.rate_m = motor_rates(task.model.drives, task.state.adapt.qd_hat_prev);
  if (sample) task.identify.tick(task.gen.running_id(), t.q, task.last.tau, t.rate_m, task.gains.tau_dec);
}

/// monitors: the drive check (drive_faults: first, the residual monitor's isolation takes its suspects),
/// those of a completed step (step_monitor_faults: stuck encoder, residual, then the momentum
/// law's update on the residual's sample (adaptation_identify), tracking, friction-estimate band), the position
/// cross-check of a measured sample; then a collision's reaction (take_collision).
template <class S, hal::ControlHal Hal>
void stage_monitors(ControlTask<S>& task, Hal& hal, TickData<S>& t) {
  t.faults |= drive_faults(task, hal);
  if (t.stepped && task.last.status == kFaultNone) t.faults |= step_monitor_faults(task, t.counts, t.moved, t.rate_m);
  if (t.measured) t.faults |= position_faults(task, hal, t.q);
  t.collision = take_collision(task, t.faults);
}

/// codes: the step's torques (through the enable's ramp) to DAC codes, 0 without a step; the
/// saturation and oscillation monitors, a fixed-point overflow of the monitors or the conversion (the step reports
/// its own), and the overrun: the tick so far, from its first mark (start), against the period (the
/// next tick would have arrived).
template <class S, hal::ControlHal Hal>
void stage_codes(ControlTask<S>& task, Hal& hal, TickData<S>& t, std::uint32_t start) {
  if (t.stepped) {
    if (task.ramping) ramp_torque(task);
    // The test dither, where the drive check runs on current readings (the residual monitor takes it as applied).
    if (task.residual.drives_checked && task.drive.amplitude > 0) {
      t.dither = task.dither_sign();
      task.last.tau += t.dither > 0 ? task.dither_torque : Vec6<S>(-task.dither_torque);
    }
    // Each DAC drives a motor: C^T tau where the drive train couples the joints.
    Vec6<S> tau_m;
    const Vec6<S>& tau = task.io.coupled() ? (tau_m = motor_torques(task.io, task.last.tau)) : task.last.tau;
    for (int i = 0; i < kDof; ++i) {
      const bool c = torque_to_code(i, tau(i), task.codes[i]);
      t.clipped = t.clipped || c;
      t.faults |= task.saturation.check(i, c);
    }
    // The oscillation monitor's codes: the torques less the friction compensation, whose sign follows the
    // velocity estimate's and flips tick by tick at rest (OscillationMonitor).
    std::int32_t loop[kDof];
    for (int i = 0; i < kDof; ++i) torque_to_code(i, S(task.last.tau(i) - task.last.tau_f_hat(i)), loop[i]);
    t.faults |= task.oscillation.check(loop);
  } else {
    for (int i = 0; i < kDof; ++i) task.codes[i] = 0;
    task.oscillation.reset();
  }
  if (math::take_arithmetic_fault<S>()) t.faults |= kFaultOverflow;
  const std::uint32_t elapsed = hal.cycles() - start;
  if (task.period_cycles != 0 && elapsed > task.period_cycles) t.faults |= kFaultOverrun;
}

/// decide: homing's index faults, the supervisor, the tick's category-2 stop request and the motion
/// state machine, from every fault of the tick; whether torque may reach the DACs.
template <class S, hal::ControlHal Hal>
void stage_decide(ControlTask<S>& task, Hal& hal, TickData<S>& t) {
  if (t.measured) t.faults |= index_faults(task, hal, t.counts, t.ev);
  task.sup = supervisor_next(task.sup, {t.faults, task.jump.have_counts});
  const MotionReason stop_request = tick_stop_request(task, t.stepped, t.q, t.collision);
  const bool yield = t.collision == CollisionReaction::kYield;
  t.torque = motion_update(task, t.faults, t.measured, t.q, t.ev, stop_request, yield) && torque_enabled(task.sup);
}

/// output: the codes (0 where the decision has the torque off), the torque the residual monitor
/// takes as applied (none without it), the DAC write and the fault line.
template <class S, hal::ControlHal Hal>
void stage_output(ControlTask<S>& task, Hal& hal, const TickData<S>& t) {
  if (!t.torque)
    for (int i = 0; i < kDof; ++i) task.codes[i] = 0;
  if (!t.stepped || !t.torque)
    task.residual.unprime();
  else
    task.residual.applied(t.clipped ? applied_torque(task) : task.last.tau);
  hal.write_dacs(task.codes);
  hal.fault_output(task.sup.state == SupervisorState::kFault);
  task.drive.written(task.codes, t.torque ? t.dither : std::int8_t{0});
}

/// One tick, the block diagram of its stages (TickStage, OSC_TICK_STAGE_LIST), each one call, timed:
/// read, checks, reference, step, monitors, codes, decide, output. Returns the fault bits detected
/// in this tick. On any fault, whenever the supervisor is not in kRun or the motion state machine
/// has the torque off, and in a tick without a valid sample (read_encoders() false: no control
/// step), every DAC gets code 0 in this same tick.
template <class S, hal::ControlHal Hal>
std::uint32_t control_tick(ControlTask<S>& task, Hal& hal) {
  TickData<S> t;
  std::uint32_t mark[kTickStages + 1];
  mark[kStageRead] = hal.cycles();
  stage_read(hal, t);
  mark[kStageChecks] = hal.cycles();
  stage_checks(task, t);
  mark[kStageReference] = hal.cycles();
  stage_reference(task, t);
  mark[kStageStep] = hal.cycles();
  stage_step(task, t);
  mark[kStageMonitors] = hal.cycles();
  stage_monitors(task, hal, t);
  mark[kStageCodes] = hal.cycles();
  stage_codes(task, hal, t, mark[kStageRead]);
  mark[kStageDecide] = hal.cycles();
  stage_decide(task, hal, t);
  mark[kStageOutput] = hal.cycles();
  stage_output(task, hal, t);
  mark[kTickStages] = hal.cycles();
  task.stages.add(mark);
  task.timing.add(mark[kTickStages] - mark[kStageRead]);
  if (t.stepped) task.step_timing.add(mark[kStageMonitors] - mark[kStageStep]);
  ++task.tick;
  return t.faults;
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
  task.drive.written(task.codes, 0);
  ++task.tick;
}

}  // namespace osc
