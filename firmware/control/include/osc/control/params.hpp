// Controller, task and supervision parameters of the paper's experiment (Section VI): the single
// source of truth for firmware, simulator and tests. The robot's own facts (model, limits, drives,
// friction presets, start pose) are its description (osc/robot.hpp).
#pragma once

#include "osc/robot.hpp"

namespace osc::params {

constexpr unsigned kControlHz = 1000;     ///< control rate: the timer interrupt [Hz]
constexpr double kDt = 1.0 / kControlHz;  ///< sampling time [s]
/// From the encoder sample to the DAC update [s]: the simulated arm's delay, and the longest that the
/// gains' check (osc/control/sampled_loop.hpp) assumes. The boards' worst-case ticks are within it
/// on the STM32F4 at 168 MHz (16 000 cycles, 0.1 ms); a 72 MHz Cortex-M3 running the fixed-point
/// build's 44 000 would take 0.6 ms (docs/protocol.md, "Parameters").
constexpr double kActuationDelay = 0.2e-3;

/// Gains (69), diagonal, one entry per operational axis: x, y, z, then the three rotations.
constexpr double kKnd[6] = {120, 120, 120, 35, 35, 35};
constexpr double kK[6] = {108, 108, 108, 32, 32, 32};
constexpr double kKs[6] = {97, 97, 97, 30, 30, 30};
constexpr double kKi[6] = {2000, 2000, 2000, 3000, 3000, 3000};
/// The ranges of the gains (69) a user may set, each element's [lo; hi] (x y z, then the rotations).
/// Each bound, the other gains at the paper's values, keeps the sampled closed loop stable at the
/// start pose (osc/control/sampled_loop.hpp; tests/firmware/runtime/test_parameters.cpp checks each
/// and how far it is from where the loop is lost) and holds the simulated arm
/// (tests/host_sim/test_gain_extremes.cpp). A set within its range is judged again at the pose where
/// it is made (param set: unstable_observer, unstable_loop).
constexpr double kKndRange[2][6] = {{1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3}, {5000, 5000, 5000, 100, 100, 100}};
constexpr double kKRange[2][6] = {{1, 1, 1, 25, 25, 25}, {1000, 1000, 1000, 1000, 1000, 1000}};
constexpr double kKsRange[2][6] = {{1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3}, {1000, 1000, 1000, 100, 100, 100}};
constexpr double kKiRange[2][6] = {{1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3}, {1e5, 1e5, 1e5, 3500, 3500, 3500}};
constexpr double kKad = 500;   ///< every diagonal entry of K_ad (18x18)
constexpr double kTauDec = 1;  ///< every tau_dec (known Stribeck coefficient) [s^2/rad^2]

/// The robust adaptation law (osc/control/adaptation.hpp, docs/adaptation.md).
/// Projection bounds of theta = [vis; cou; sti] for a PUMA 560: three times the larger of the paper's
/// Table II and the Corke/Armstrong-Helouvry values per joint, rounded up; the Stribeck excess is
/// bounded like the Coulomb level. The lower bounds are 0 (friction dissipates).
constexpr double kThetaMax[18] = {18, 30, 18, 2, 6, 3,   // vis [N m s/rad]
                                  80, 32, 20, 4, 3, 4,   // cou [N m]
                                  80, 32, 20, 4, 3, 4};  // sti [N m]
/// Leakage (sigma-modification towards 0) [1/s]: a time constant of 1000 s, slow against the
/// adaptation (about 60 s) and fast against the residual quantisation drift.
constexpr double kAdaptationLeakage = 1e-3;

/// Trajectory (68): amplitude, angular frequency (period 5 s, f = 1) and envelope rate.
constexpr double kAmplitude = 0.050;  ///< [m]
constexpr double kOmega = 0.4 * kPi;  ///< [rad/s]
constexpr double kEnvelope = 0.05;    ///< 1 - exp(-kEnvelope t^3)

/// Reciprocal-condition threshold of the Jacobian below which the controller refuses to act.
constexpr double kMinJacobianRcond = 1e-3;

/// Motion generation (osc/control/cartesian_move.hpp, docs/motion.md): the configured maxima of a
/// move's reference, translation of the operational point [m/s, m/s^2, m/s^3] and rotation about the
/// move's axis [rad/s, rad/s^2, rad/s^3]. A command may ask for less, never more (over_limit).
/// The translation's are the arm's (its drive sheet's cartesian_maxima), each chosen so that the
/// controller tracks a move at them within 1 mm (docs/arms.md); the rotation's are every arm's.
constexpr double kMoveLinear[3] = {robot::kCartesianMaxima.velocity, robot::kCartesianMaxima.acceleration,
                                   robot::kCartesianMaxima.jerk};
constexpr double kMoveAngular[3] = {0.5, 1.0, 10.0};
/// A planned path keeps every joint this far inside its limits [rad] (out_of_workspace).
constexpr double kWorkspaceMargin = 0.05;
/// ... and the Jacobian's reciprocal condition at least this (near_singular): ten times the
/// controller's own threshold, so that a path that passes the check never reaches it.
constexpr double kPathMinRcond = 10 * kMinJacobianRcond;
/// ... and the sampled closed loop stable at every sample with the bounds of Lambda^-1 there times this
/// (unstable_loop; osc/control/sampled_loop.hpp). 1: the row bounds (Gershgorin) lie above Lambda^-1's
/// eigenvalues already, and that is the room for an axis growing lighter between two samples (on the
/// PUMA 30 % at the end of MotionSim's basic move, where 1.25 refused a move whose coupled loop is
/// stable with Lambda^-1 1.25 times larger; the sampled-loop test asserts 10 % on 95 % of random
/// poses).
constexpr double kPathLoopMargin = 1.0;
/// While moving, a Jacobian whose reciprocal condition falls below this stops the motion (category
/// 2, limit_reached), before the controller's own threshold faults (category 0).
constexpr double kLimitMinRcond = 2 * kMinJacobianRcond;
/// A motion that starts with a joint this close to one of its limits, or past it, may take the joint
/// this much further out than where it started before the tick's limit check stops it (limit_reached)
/// [rad]: an arm at rest at a limit (where a stream's stop leaves it, up to its overshoot) can be moved
/// away, its tracking's first wobble (0.003 rad/s measured) not taken for a motion out of it. A
/// fraction of the encoders' kJointLimitMargin.
constexpr double kLimitStartSlack = 0.005;
/// Points checked along a planned path, besides its end (inverse kinematics at each).
constexpr int kPathCheckPoints = 16;
/// Moves a queue holds beyond the one running.
constexpr int kMoveQueueLength = 16;
/// Enable: the torque beyond the gravity the model predicts is ramped in over this time [s].
constexpr double kEnableRamp = 0.05;

/// The excitation motion of an identification run (osc/control/excitation.hpp, docs/adaptation.md section 6;
/// Swevers et al. 1997, Gaz et al. 2019): a Fourier series per joint of kExcitationHarmonics harmonics of
/// 1 / kExcitationPeriod, repeated kExcitationPeriods times, at rest at its start pose at the start of
/// every period. The reference stays kExcitationPositionMargin inside each joint's limits, below the
/// speed bound (kExcitationMaxSpeed or the drive's plausible speed, whichever is lower) by
/// kExcitationSpeedMargin, and needs at most kExcitationTorqueFraction of each joint's torque limit
/// (its rigid-body torque plus the model-error band's strongest friction). 1.5 rad/s: the speed at which
/// the Stribeck term has decayed by 90 % (tau_dec = 1), so that its split from the Coulomb level is
/// observed (shared/reference/drives-and-identification.md section 7.1); the margins are Gaz's (5 deg,
/// 10 deg/s), the period his order (13.3 s), the duration within issue 57's 90 s.
constexpr int kExcitationHarmonics = 5;
constexpr double kExcitationPeriod = 10;  ///< [s], a whole number of control ticks
constexpr int kExcitationPeriods = 8;
constexpr double kExcitationMaxDuration = 90;                ///< [s]
constexpr double kExcitationMaxSpeed = 1.5;                  ///< [rad/s]
constexpr double kExcitationSpeedMargin = 10 * kPi / 180;    ///< [rad/s]
constexpr double kExcitationPositionMargin = 5 * kPi / 180;  ///< [rad]
constexpr double kExcitationTorqueFraction = 0.8;            ///< of robot::kDrives.torque_limit
/// How far the design's speed may be cut where it does not fit (excitation.hpp, "Fitting the design"):
/// a joint's travel at the start pose may cut its speed to kExcitationMinScale of its design speed, and
/// the motion runs at the largest of the scales 1, kExcitationScaleStep, its square, ... (while at least
/// kExcitationMinScale: 1, 0.9, 0.81, 0.729, 0.656, 0.590, 0.531) whose check passes, found in at most four
/// checks (excitation_check.hpp); where none passes, it is refused. Steps of 0.9 rather than 0.8: the run keeps
/// more of its speed where the first scale that passes lies between two of 0.8's, and the Coulomb / Stribeck split
/// is told by the speed (at the tests' identify pose 0.656 against 0.64: J1's Stribeck sigma 0.93 of issue 57's
/// bar against 1.03; docs/adaptation.md, section 6).
constexpr double kExcitationMinScale = 0.5;
constexpr double kExcitationScaleStep = 0.9;
/// The plan aims this fraction of each bound (speed, travel), so that the scalar's rounding never puts
/// a sample of the reference over it.
constexpr double kExcitationPlanFill = 0.99;
/// The design: each joint's velocity coefficients, a_k on cos(k w t) and b_k on sin(k w t), k = 1..5, in
/// units the plan scales (excitation.hpp, "The design"). Joints 1, 3, 5 move with cosines, 2, 4, 6 with
/// sines; each row solves sum a_k = sum k^2 a_k = 0, or sum b_k / k = sum k b_k = 0.
constexpr double kExcitationCos[kDof][kExcitationHarmonics] = {{2, 3, -12, 9, -2},    // J1
                                                               {0, 0, 0, 0, 0},       // J2
                                                               {0, 3, 0, -7, 4},      // J3
                                                               {0, 0, 0, 0, 0},       // J4
                                                               {7, -6, 3, -10, 6},    // J5
                                                               {0, 0, 0, 0, 0}};      // J6
constexpr double kExcitationSin[kDof][kExcitationHarmonics] = {{0, 0, 0, 0, 0},       // J1
                                                               {4, -2, -9, -12, 15},  // J2
                                                               {0, 0, 0, 0, 0},       // J3
                                                               {6, -18, 0, 20, -10},  // J4
                                                               {0, 0, 0, 0, 0},       // J5
                                                               {0, 2, -9, 12, -5}};   // J6
/// The identification run's state-variable filter (osc/control/identify_filter.hpp): F(s) = w^2 / (s + w)^2 at
/// w = kIdentifyFilterOmega [rad/s], 10 Hz, twenty times the excitation's highest harmonic (kExcitationHarmonics /
/// kExcitationPeriod = 0.5 Hz). The rigid-body model evaluated at the filtered states differs from the filtered
/// torque by the model's nonlinearity through F, as (its harmonics / w)^2; the noise of qdd_f (s F of the velocity
/// estimate: identify_filter.hpp, "The rates") grows as w. On the PUMA's excitation with a 1.5 kg payload
/// (test_identify_estimate.cpp, IdentifyRun, with qdd_f = s^2 F q then), at 5, 10, 15 and 20 Hz: noise-free, the
/// worst friction coefficient 20, 4.7, 2.1 and 2.4 % off; with the encoders' quantum, J1's torque-prediction error
/// 1.1, 4.3, 9.4 and 16 %, the mass 0.34, 0.09, 0.16 and 0.54 % off, the centre of mass 0.20, 0.16, 1.1 and 3.4 mm.
/// w^2 = 3948 fits Q12.19.
constexpr double kIdentifyFilterOmega = 2 * kPi * 10;
/// A joint's row of a run's sample enters the estimate only while its filtered rate |s F q_i| is at least
/// kIdentifyMinRowSpeed [rad/s]. About a reversal the sign of the velocity estimate the friction columns are formed
/// at differs from the joint's for a few ticks, and F spreads that error over its window; the sign and Stribeck
/// columns, nearly alike below 1 rad/s, turn it into a large error in the Coulomb / Stribeck split. On the ideal
/// plant at 0.64 of the excitation's design (test_identify_sim.cpp), every row: J1's Coulomb 1.6 against 4.9, its
/// viscous 7.9 against 5.8; rows from 0.05 rad/s: 4.7 and 5.9, every coefficient within 6 %.
constexpr double kIdentifyMinRowSpeed = 0.05;
/// The identification run's estimate (osc/control/identify_estimate.hpp). At least kIdentifyMinSamples samples: a
/// joint's residual variance from 200 degrees of freedom is within sqrt(2 / 200) = 10 % of itself, so that a
/// coefficient's reported 2 sigma is a normal one. The column-normalised information matrix's condition at most
/// kIdentifyMaxCondition (the regressor's 1 000): the excitation gives 4 600-5 500 at the PUMA's start pose, 14 000
/// at the smallest scale its plan accepts (0.512), most of it each joint's Coulomb / Stribeck split (2 700-4 600 at
/// 1.3 rad/s: test_identify_estimate.cpp); at the runs' pose in closed loop (q5 = 1.3 rad, 0.64 of the design, 0.84
/// rad/s) the friction alone gives 62 000 and with the armatures and a payload's ten 97 700-100 400
/// (test_identify_sim.cpp), the split again, which its sigma reports. Columns alike are singular (a decay column the
/// sign's, a joint that does not move) or far beyond (every joint at 5 % of the speed: 5.5e7). Every
/// joint's torque-prediction error (the rms residual over the rms of the torque the model leaves) at most
/// kIdentifyMaxPredictionError: Servotronix softMC's RelTeMax default, 20 %
/// (shared/reference/drives-and-identification.md section 7.4).
constexpr unsigned kIdentifyMinSamples = 200;
constexpr double kIdentifyMaxCondition = 1e6;
constexpr double kIdentifyMaxPredictionError = 0.2;

/// Supervision limits.
/// How far an encoder reading may lie outside the joint limits (overtravel to the hard stops)
/// before it is implausible, from the first sample on [rad].
constexpr double kJointLimitMargin = 0.1;
/// Consecutive ticks a torque may stay clipped at the DAC range before the saturation fault.
constexpr int kSaturationTicks = 50;
/// Oscillation monitor (`unstable`): the largest amplitude of a joint torque's component at half the tick rate
/// (every other tick up, then down; the torque less its friction compensation), averaged over about
/// 2^kOscillationShift ticks, as a share of the joint's torque range (its DAC's full scale). Beyond it the sampled
/// loop is lost: the gains are too high for the arm's inertia at the pose (docs/safety.md, "The oscillation
/// monitor": twice the healthy runs' largest, 13.3 % at the gains' tops, with a little to spare).
constexpr double kOscillationLimit = 0.30;
/// The oscillation monitor's averaging: a first-order filter of 2^kOscillationShift ticks.
constexpr int kOscillationShift = 4;
/// Stuck-encoder monitor: the joint motion the reference commands while an encoder stands still,
/// accumulated from the last count change, beyond which the encoder is stuck [counts]
/// (docs/safety.md derives it and kStuckTorque from the fault-free peaks, 1.5 times the largest over
/// both friction presets of the robot description, paper and corke, with and without compensation:
/// the heavier the static friction, the longer a joint sticks at a reversal).
constexpr double kStuckMotionCounts = 165;
/// ... or the commanded joint torque has changed by more than this since the encoder's last change
/// [N m]: a joint held by static friction breaks away within a bounded torque change, a joint whose
/// encoder is stuck while it moves makes the controller ramp its torque without bound.
/// J1 of the corke preset (static friction 26 N m) needs 52 N m to reverse.
constexpr double kStuckTorque[6] = {78, 34, 22, 19, 6, 10};
/// ... or by more than this [N m] when the joint was moving (its last interval between counts at
/// most kStuckFastInterval ticks) and its encoder has since been silent for kStuckIntervals of
/// those intervals: a moving joint that should have counted, not one that slowed to a reversal and
/// is held there by static friction.
constexpr double kStuckTorqueSilent[6] = {33, 20, 12, 8, 4, 9};
constexpr int kStuckFastInterval = 5;
/// ... and the encoder has been silent for more than this many of its recent intervals between
/// counts.
constexpr int kStuckIntervals = 10;
/// A torque criterion counts once it has held for this many ticks in a row: a torque beyond it for
/// a tick or two (the compensation's sign flipping with the velocity estimate at a reversal) moves
/// a joint by a fraction of a count before the amplifier's lag and the inertia let it count.
constexpr int kStuckQualifyTicks = 3;
/// The residual monitor (osc/runtime/monitors.hpp; docs/safety.md, "The residual monitor"):
/// - the bandwidth of its first-order filter per joint [1/s]: 50 on J1-J3 (a torque step of three
///   times a threshold crosses it within 8 ms); 20 on the wrist, whose velocity estimate comes from
///   the observer's rotational rows, underdamped (k = 32, k_i = 3000: damping 0.1-0.4), and a faster
///   filter would pass their ringing;
/// - the largest response of the residual to a unit step of unexplained torque, through the
///   observer and that filter (the L1 norm of their impulse response over the arm's range of
///   Lambda^-1 k_i, scripts/residual_gain.py): each threshold is scaled by it;
/// - the ticks a residual must stay beyond its threshold before it is a fault.
constexpr double kResidualGain[6] = {50, 50, 50, 20, 20, 20};
constexpr double kResidualPeakFactor[6] = {1.1, 1.1, 1.1, 1.2, 1.2, 1.2};
constexpr int kResidualQualifyTicks = 3;
/// The residual monitor's change channel: the bandwidth of the slow filter whose output the change
/// residual r - r_slow leaves out [1/s]. A model error that changes more slowly than this (a friction
/// coefficient off by a constant, an inertia error under a smooth motion) stays out of it, while a
/// step of external torque passes: 0.52 of it at 17 ms (with kResidualGain 50).
constexpr double kResidualSlowGain = 10;
/// Each threshold is this many times the bound derived from the model's error (both channels): a
/// healthy residual stays within its bound, at most 1 / kResidualMargin of the threshold, and the
/// sweep of healthy runs checks exactly that (docs/safety.md); the rest is room for what the bounds
/// leave out.
constexpr double kResidualMargin = 2;
/// The fixed-point pose x(q)'s rounding, per coordinate, in units of its resolution (the LSB of Q12.19:
/// 1.9 um, 1.9 urad): the residual monitor's velocity noise takes it (ResidualConstants::pose_rounding).
/// Measured against double over 1000 random states (tests/firmware/control/test_arm_opspace.cpp, which
/// asserts it on the built arm): the UR5e's at most 2.9 LSB, the PUMA 560's 3.4.
constexpr int kPoseRoundingLsb = 4;
/// A joint whose friction the residual monitor takes on the model's sliding curve has counted within
/// this many ticks of its last count (besides counting one way, beyond its velocity noise and lag):
/// 0.017-0.02 rad/s at the joints' quanta. Slower, a joint held against its static friction may
/// creep in stick-slip, its friction anywhere within the static band while its velocity estimate
/// shows a steady crawl, and it is judged against that band. Measured: J4 held after a noisy stream
/// (Corke's friction, uncompensated) crept at 0.008 rad/s, a count every 10 ticks, for seconds;
/// judged as sliding, it reached 1.03 of its change threshold (docs/safety.md).
constexpr int kResidualSlideInterval = 5;
/// The same as a speed [rad/s], for an encoder fine enough that kResidualSlideInterval ticks between counts is
/// slower than this: a UR5e's count is 3.8 urad, so a joint creeping at 0.8 mrad/s counts every 5 ticks. Such a
/// joint moves, for the residual monitor's friction bound, its stillness envelope and the identification's
/// samples, only when its encoder made this speed's counts over the last kResidualSlideInterval ticks as well
/// (EncoderActivity::slide_counts; a UR5e joint held by static friction crept at 0.2 mrad/s in the plant, its
/// observed q^dot 10 mrad/s off by the friction the model lacked). The PUMA's encoders resolve it (0.012-0.023
/// rad/s at 5 ticks): the count interval alone decides there, as before.
constexpr double kResidualSlideSpeed = 0.01;
/// The residual monitor raises its faults (encoder_stuck, drive_fault, collision) by default, and the
/// stuck-encoder monitor's fitted criteria are off but while homing (the runtime parameter
/// residual_monitor; docs/safety.md). Off,
/// it is a trial: it records what it would raise, and the stuck-encoder monitor's trajectory-tuned
/// criteria raise encoder_stuck as before.
constexpr bool kResidualMonitorArmed = true;
/// The residual monitor's travel check: a joint whose least motion since its encoder's last count,
/// under the torque applied and the model's error bounds (its friction at the band's strongest),
/// exceeds this many counts must have counted: its encoder (or something holding the joint) is at
/// fault. One count is the geometry (the next edge, or the last one back); the second is margin.
constexpr double kResidualTravelCounts = 2;
/// A payload the model has wrong (osc/runtime/payload_check.hpp; docs/safety.md, "A payload the model has wrong"):
/// within kPayloadCheckTicks of an enable (the arm held still), a finding of the residual monitor whose residual is
/// the weight of a point mass at the flange is payload_mismatch, not encoder_stuck or collision:
/// - at most kPayloadFitMisfit of the residual's square left unexplained by the best such weight, and at least
///   kPayloadSpread of it off its largest joint (one joint's torque is that joint's drive or encoder);
/// - a weight of kPayloadMismatchMass or more (and at most twice the arm's rated payload);
/// - the fit's 3x3 system is taken only where its determinant is at least kPayloadFitConditioning times its trace
///   cubed (a pose where a weight's three columns differ).
constexpr int kPayloadCheckTicks = 1000;
constexpr double kPayloadFitMisfit = 0.02;
constexpr double kPayloadSpread = 0.005;
constexpr double kPayloadMismatchMass = 0.2;
constexpr double kPayloadFitConditioning = 1e-4;
/// ... and within that window, a finding that would be encoder_stuck on a joint that has counted more than this many
/// counts one way since the enable while its reference lies more than this many the other way from its reading (it
/// was moved off its reference, which a stuck encoder cannot show: ResidualMonitor::off_reference) is a load the model
/// has wrong or a drive, as at a pose held since the enable.
constexpr int kPayloadAwayCounts = 2;
/// The drive check (osc/runtime/drive_monitor.hpp; docs/safety.md, "The drive check"), on a HAL with
/// current readback:
/// - its threshold is kDriveMargin times the stated bounds of the amplifiers' and the current monitors'
///   errors (robot::kModelErrorBounds, robot::kDriveTrain.current): about 1.6 % of full scale plus 8 % of the
///   command (drives-and-identification.md section 3 estimates 2 % and 6 %);
/// - a reading beyond it for kDriveQualifyTicks in a row is a drive_fault (a glitch of one conversion is not);
/// - the test dither: +-kDitherAmplitude of each channel's full scale on its DAC code, a square wave of
///   kDitherHalfPeriod ticks a sign (125 Hz), the default of the runtime parameter dither; its demodulation
///   filters over 2^kDitherWindowShift readings (8: a frozen DAC at half its level in 6 readings, 8 ticks).
constexpr double kDriveMargin = 2;
constexpr int kDriveQualifyTicks = 3;
constexpr double kDitherAmplitude = 0.01;
constexpr int kDitherHalfPeriod = 4;
constexpr int kDitherWindowShift = 3;
/// The residual monitor's turn: every this many control steps (the controller's even steps, on which the
/// alternate model rate computes A and g, not Psi: osc/control/controller.hpp, even_step), it updates each joint's
/// bound, change channel and thresholds and advances the travel check's bounds, on the inputs' means over the
/// turn where they alternate tick by tick (the applied torque, r). The residual, its qualification against the
/// thresholds and the travel check's counts and drive run every tick. The M4F's and the M3's tick budgets
/// (docs/benchmarks.md); the detection times it gives are docs/safety.md's.
constexpr int kResidualTurnEvery = 2;
/// Friction identified from the residual (the `momentum` law, osc/control/identification.hpp;
/// docs/adaptation.md, "Identification from the residual"):
/// - each joint's Kalman update comes every kIdentifyEvery ticks, the joints in turn, one sample a turn of the
///   residual monitor (kResidualTurnEvery: 6 joints, 12 ticks; the filtered samples are correlated over
///   1/kResidualGain = 20-50 ms: a sample every 12 ms loses little);
/// - a joint's sample counts once it has moved, encoder counting, for kIdentifySettle of the
///   residual filter's time constants (the filter then holds no standstill, where friction is not
///   the model's W theta), and only at speeds of kIdentifyMinSpeed times its velocity noise or more;
/// - and while its residual is at most kIdentifyMaxRatio of its threshold (a contact's torque is no
///   friction), and its innovation within kIdentifyGate standard deviations;
/// - the coefficients drift: a random walk of kIdentifyDrift times the band's top per hour (the
///   band's own +-30 % with temperature, robot::kModelErrorBounds).
constexpr int kIdentifyEvery = 6 * kResidualTurnEvery;
constexpr double kIdentifyMinSpeed = 4;
constexpr double kIdentifySettle = 3;
constexpr double kIdentifyMaxRatio = 0.5;
constexpr double kIdentifyGate = 4;
constexpr double kIdentifyDrift = 0.3;
/// The samples the identification's noise measure averages over (its mean squared innovation), per
/// joint: about 1.5 s of updates.
constexpr int kIdentifyNoiseSamples = 256;
/// A coefficient is reported identified when its standard deviation is at most this fraction of it.
constexpr double kIdentifiedFraction = 0.025;
/// A friction set (a saved record applied at power-on, an identify run's applied: FrictionIdentifier::seed) is
/// checked once per joint and coefficient, the viscous and the breakaway torque (Coulomb + Stribeck), when the
/// momentum law first knows it within kIdentifiedFraction of the set value (FrictionFit::judge): it no longer
/// fits the arm (stale) when it lies more than this fraction of itself from the law's estimate. The torque it
/// predicts is then more than 20 % off, the identification run's own failure bar (kIdentifyMaxPredictionError,
/// Servotronix's RelTeMax); the bar is eight of the estimate's standard deviations then, so that a set that fits
/// (within 10 %, four of them) is not called stale, nor one 30 % off found to fit.
constexpr double kSavedFitFraction = 0.2;
/// The residual monitor's travel check takes each joint's identified viscous coefficient and
/// breakaway torque (Coulomb + Stribeck) at this many standard deviations above its estimate, in
/// place of the band's top (FrictionIdentifier::prove; docs/safety.md, "The identified band"): in
/// kTravelTiers tiers of standard deviation, kIdentifiedFraction of the estimate doubled tier by
/// tier, 1.1, 1.2, 1.4 and 1.8 times the estimate.
constexpr double kTravelIdentifiedSd = 4;
constexpr int kTravelTiers = 4;
/// The excitation monitor's gate on the Coulomb / Stribeck split: the split is learned only while the
/// recent motion makes the Stribeck decay column, sgn(qd) (exp(-tau_dec qd^2) - 1), vary independently
/// of the viscous and Coulomb columns by at least this much (RMS, a fraction of the Stribeck level).
/// A sinusoid of 0.15 rad/s gives 0.003, of 0.4 rad/s 0.012, of 0.8-1.5 rad/s 0.025-0.03 (tau_dec = 1):
/// the decay is nearly a line in the speed, so the split shows only in what a line leaves. Below the
/// gate the two levels are collinear: their sum is learned and their split held (a Schmidt, or
/// consider, update), as a misfit of a few hundredths of a N m would move it by newtons.
/// The motion's moments are averaged over blocks of kIdentifyExciteBlock counted samples per joint,
/// and the blocks over kIdentifyExciteBlocks of them (4 096 samples, about 25 s of motion).
constexpr double kIdentifySplitExcitation = 0.02;
/// A measurement build's switch, never a product image's: OSC_TICK_WORST_CASE (the timer image
/// timer_worst_firmware, docs/benchmarks.md) makes every turn of the momentum law take its longest
/// path, so that the tick's worst case is measured on an arm at rest: every sample counts (settled,
/// the residual low, no outlier) and a block of moments folds every 4 samples.
#ifdef OSC_TICK_WORST_CASE
constexpr bool kTickWorstCase = true;
#else
constexpr bool kTickWorstCase = false;
#endif
constexpr int kIdentifyExciteBlock = kTickWorstCase ? 4 : 64;
constexpr int kIdentifyExciteBlocks = 64;
/// The position cross-check (osc/runtime/monitors.hpp, PositionCrossCheck; docs/safety.md, "The
/// position cross-check"): each joint's potentiometer angle minus its encoder angle, low-pass filtered
/// (time constant kPositionFilter [s], the joints updated in turn, kPositionJointsPerTick a tick), must
/// stay within kPositionBand [rad] of its value once settled (after kPositionSettle filter time
/// constants), for kPositionQualify updates in a row, else position_mismatch. The band per joint is
/// derived, not fitted (tests/firmware/control/test_params.cpp recomputes it):
///   6 codes of the potentiometer (its span / 4095: 0.94 to 2.35 mrad): the filtered difference of a
///     noise of up to 4 codes rms (twice the realistic plant's estimate) and the quantisation, the
///     settled value's own error included (sigma about 1 code);
/// + on J1-J3, twice the elastic deflection at full-scale torque, tau_fs / K with K the stiffness of a
///   locked-motor resonance of 15 Hz (the lower end of the published 15-25 Hz) at the start pose,
///   K = (2 pi 15)^2 A_ii(q_start): the pot reads the link, the encoder the motor;
/// + 1 mrad of gear backlash at the joint (the top of the published 0.1-1 mrad).
constexpr double kPositionFilter = 0.05;
constexpr int kPositionJointsPerTick = 2;
constexpr double kPositionSettle = 5;
constexpr int kPositionQualify = 3;
constexpr double kPositionBandCodes = 6;
constexpr double kPositionElasticHz = 15;
constexpr double kPositionBacklash = 1e-3;
constexpr double kPositionBand[6] = {0.0157, 0.0180, 0.0299, 0.0087, 0.0067, 0.0152};
/// Homing (osc/runtime/control_task.hpp, docs/safety.md "Homing"): the pots' coarse angles pick each
/// motor's revolution, and the index pulse the exact count in it. Every motor turns, toward the
/// middle of its joint's travel, by at most (1 + kHomeMargin) revolutions (the index is within one
/// revolution; the margin covers the tracking lag), along a straight line of the wrist centre and a
/// rotation at the homing speeds (parameter home_speed: [m/s, rad/s]; the move limits' accelerations
/// and jerks), and the move brakes once every index is found. A pot whose coarse angle is off the
/// index position by more than kHomeBand of a revolution is position_mismatch: up to half a
/// revolution the revolution it picks is right, beyond it the wrong one (J2: 1.67 degrees), so the band
/// leaves a tenth of a turn of margin to detect a pot drifting toward it (J1 2.3, J2 1.3, J3 2.7, J4-J6
/// 1.9 to 2.0 degrees; the realistic plant's pot offsets, the +-1.7 degrees a PUMA's pot is good for,
/// reach 0.32 of a turn on J4).
constexpr double kHomeSpeed[2] = {0.04, 0.1};
constexpr double kHomeMargin = 0.05;
constexpr double kHomeBand = 0.4;
/// declare_pose: each potentiometer's angle within this of the declared pose [rad], or pots_disagree.
constexpr double kDeclareBand = 2 * kPi / 180;

/// Tracking-error bounds on the measured error e (36): position [m] and each orientation
/// coordinate [rad]; about twice the worst fault-free error without friction compensation on the
/// heavier (corke) friction preset (7.0 mm, 0.43 deg).
constexpr double kTrackingLimitPosition = 0.015;
constexpr double kTrackingLimitOrientation = 0.02;
/// The supervisor's bounds on the friction estimates: the robust law's projection set [0, theta_max]
/// widened by theta_max on each side, [-theta_max, 2 theta_max]. The robust law never leaves
/// [0, theta_max]; (67), which has no bounds, faults when it drifts that far.
constexpr double kThetaFaultBand = 1.0;

/// Link supervision (osc/link/node.hpp; docs/firmware.md, "Link supervision"). Every link error
/// (bad CRC, header or length, junk or lost-sync bytes, a frame cut short, a wrong sequence number,
/// silence) zeroes the DAC codes of the next tick without latching; repeated errors latch.
/// Silence on a board whose timer paces the ticks: the DACs keep their codes over at most this many
/// ticks without a sensor frame; the next tick without one is a silence error (zero codes).
constexpr int kLinkSilenceTicks = 2;
/// Silence when the host paces the ticks (lockstep processor in the loop, as in QEMU): no byte for
/// this long [s of the target's virtual time] is a silence error (or a short frame, if one had
/// started). Not kLinkSilenceTicks periods: in lockstep the target's clock runs on while it waits (polls, or sleeps in
/// WFI) for the host's next frame, and that wait is the host's wall-clock time (the plant's step, the pipe, the
/// scheduler of a shared machine) turned into target time: gaps of up to 1.7 ms measured in healthy runs
/// (docs/firmware.md), too close to 2 ms. The plant is frozen meanwhile, so the wait costs it no torque.
constexpr double kLinkTimeout = 0.1;
/// Error ticks (ticks with at least one link error) that latch a link fault when they fall within
/// kLinkErrorWindow ticks: link_lost when the last was a silence, link_corrupt otherwise. Fewer cost
/// one tick of zero torque each (at most 0.2 % of the ticks) and are counted; three in a second is
/// a link that loses more than one frame in 333, no longer one with rare bit errors, and a CRC-16
/// passes 1 in 65 536 corrupted frames, so the latch also bounds the rate of undetected ones.
constexpr int kLinkErrorLimit = 3;
constexpr int kLinkErrorWindow = 1000;

/// The command link of a board whose encoders are local (the STM32F4 board's USART; not the PIL
/// link, whose frames carry the encoders): once a host has sent a command, no frame at all for this
/// long [s] while a motion runs stops the motion, category 2, aborted `link_silent`. Half a second:
/// far above a healthy host's gaps (a client keeps the link alive every 0.1 s while a motion runs),
/// yet short against a moving arm's travel: Crazyflie's commander levels the vehicle after 500 ms
/// without a setpoint (and stops the motors after 2 s), PX4 fails safe after 1 s without offboard
/// setpoints (COM_OF_LOSS_T). The board counts it in ticks: kCommandLinkTimeout * kControlHz.
constexpr double kCommandLinkTimeout = 0.5;

/// The command link's in-frame timeout (pil::Parser::expire; docs/protocol.md, "Framing and
/// resynchronisation"): a frame that has started and then receives no byte for this long [s] is cut
/// short, and the bytes after its first are scanned again for a frame. Applied by every end of the
/// command protocol: the STM32F4 board's USART (in ticks), the virtual board and the clients (wall
/// time). A sender writes a frame's bytes back to back: at 115 200 baud a whole frame of the longest
/// type (pil::kMaxFrame bytes) takes under 20 ms, its gaps none. The PIL link's is kLinkTimeout.
constexpr double kFrameTimeout = 0.02;

}  // namespace osc::params
