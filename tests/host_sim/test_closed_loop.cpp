// Closed-loop tests of issue 3: the firmware's control task on the simulated PUMA 560. The full
// 120 s experiment is the runner's default; CI runs shorter windows.
#include <gtest/gtest.h>

#include <cstdio>
#include <tuple>

#include "experiment.hpp"
#include "osc/kernels/opspace.hpp"
#include "osc/runtime/io.hpp"

using namespace sim;

namespace {

void print(const char* what, const ExperimentResult& r) {
  std::printf(
      "%-28s max |e| all: %.3f %.3f %.3f mm %.4f %.4f %.4f deg | last: %.3f %.3f %.3f mm %.4f %.4f %.4f deg"
      " | |x~| last: %.3f %.3f %.3f mm\n",
      what, r.max_error[0], r.max_error[1], r.max_error[2], r.max_error[3], r.max_error[4], r.max_error[5],
      r.final_max_error[0], r.final_max_error[1], r.final_max_error[2], r.final_max_error[3], r.final_max_error[4],
      r.final_max_error[5], r.max_observer_error[0], r.max_observer_error[1], r.max_observer_error[2]);
}

/// Worst-case Cartesian error of one encoder count on every joint at the start pose [mm]:
/// sum_j |J_ij| / counts_per_rad_j, maximised over the translational rows.
double position_quantum_mm() {
  const osc::Model<double> model = osc::Model<double>::of(osc::robot::kArm);
  osc::Data<double> data;
  const Vec6 q = osc::joint_vector<double>(osc::robot::kQStart);
  osc::forward_kinematics(model, data, q);
  osc::geometric_jacobian(data);
  double worst = 0;
  for (int r = 0; r < 3; ++r) {
    double s = 0;
    for (int j = 0; j < 6; ++j) s += std::abs(data.J(r, j)) / osc::counts_per_rad(j);
    worst = std::max(worst, s);
  }
  return worst * 1e3;
}

ExperimentConfig config(double duration, osc::FrictionMode mode, const osc::FrictionCoefficients& friction) {
  ExperimentConfig c;
  c.duration = duration;
  c.mode = mode;
  c.plant.friction = friction;
  c.final_window = duration / 3;
  c.log_period = 1.0;
  return c;
}

TEST(ClosedLoop, FrictionlessPlantTracksAtEncoderQuantisationLevelAndObserverConverges) {
  ExperimentConfig c = config(12, osc::FrictionMode::kNone, osc::kFrictionNone);
  // Start the observer 2 mm / 0.2 deg off: x~ must decay.
  for (int i = 0; i < 3; ++i) c.observer_offset[i] = 2e-3;
  for (int i = 3; i < 6; ++i) c.observer_offset[i] = 0.2 * osc::kPi / 180;
  const ExperimentResult r = run_experiment(c);
  print("frictionless, no comp.", r);
  const double quantum = position_quantum_mm();
  std::printf("one-count position quantum at the start pose: %.4f mm\n", quantum);
  ASSERT_EQ(r.status, 0u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(r.final_max_error[i], 2.0 * quantum) << "axis " << i;
    EXPECT_LT(r.max_observer_error[i], 0.1 * 2.0) << "axis " << i;  // decayed below a tenth of 2 mm
  }
  for (int i = 3; i < 6; ++i) {
    EXPECT_LT(r.final_max_error[i], 0.02) << "axis " << i;
    EXPECT_LT(r.max_observer_error[i], 0.1 * 0.2) << "axis " << i;
  }
}

struct WithFriction : ::testing::Test {
  static ExperimentResult adaptive, none;
  static void SetUpTestSuite() {
    adaptive = run_experiment(config(80, osc::FrictionMode::kAdaptive, osc::robot::kFrictionPaper));
    none = run_experiment(config(80, osc::FrictionMode::kNone, osc::robot::kFrictionPaper));
    print("paper friction, adaptive", adaptive);
    print("paper friction, no comp.", none);
  }
};
ExperimentResult WithFriction::adaptive, WithFriction::none;

TEST_F(WithFriction, CompensationReducesEveryTranslationalErrorAtLeastTwofold) {
  ASSERT_EQ(adaptive.status, 0u);
  ASSERT_EQ(none.status, 0u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_GT(none.max_error[i], 2.0 * adaptive.max_error[i]) << "axis " << i;
    EXPECT_GT(none.final_max_error[i], 2.0 * adaptive.final_max_error[i]) << "axis " << i;
  }
}

TEST_F(WithFriction, EstimatedFrictionTorqueMatchesThePlant) {
  std::printf("friction rms error %.3f N m of rms %.3f N m\n", adaptive.friction_rms_error, adaptive.friction_rms);
  EXPECT_LT(adaptive.friction_rms_error, 0.25 * adaptive.friction_rms);
}

TEST_F(WithFriction, CoefficientsApproachTheTrueValues) {
  // The default (momentum) law on the paper's trajectory after 80 s (one sample a residual monitor's turn, each
  // joint's every 12 ms: J1's breakaway is identified after 35 s; with a sample every 6 ms, before 2026-12-02,
  // after 30 s). J2's viscous term is the slowest: 2.66 / 2.81 / 2.75 / 3.23 against 3.7 at 40 / 50 / 60 / 80 s
  // (puma_experiment --mode adaptive --duration N --json, 2026-12-03); within 25 % at 40 s only by the
  // plant's rounding before its exact quarter turns (issue 55). What the motion excites is each
  // joint's breakaway friction, Coulomb + Stribeck (every velocity reversal of J1-J3), and the
  // viscous terms; the Coulomb / Stribeck split is not (the joints turn too slowly for the Stribeck
  // decay to show: docs/adaptation.md, section 5), and the identifier says so. The breakaway of J1-J2
  // is within 10 % of the truth and reported identified, the viscous terms of J1-J3 within 25 %.
  ASSERT_TRUE(adaptive.has_identification);
  for (int j : {0, 1}) {
    const double hat = adaptive.theta_hat[6 + j] + adaptive.theta_hat[12 + j];
    const double truth = adaptive.theta_true[6 + j] + adaptive.theta_true[12 + j];
    EXPECT_NEAR(hat, truth, 0.1 * truth) << "breakaway J" << j + 1;
    EXPECT_TRUE(osc::friction_identified(hat, adaptive.breakaway_sd[j])) << "breakaway J" << j + 1;
    EXPECT_FALSE(osc::split_excited(adaptive.split_excitation[j])) << "split J" << j + 1;
  }
  for (int j : {0, 1, 2})
    EXPECT_NEAR(adaptive.theta_hat[j], adaptive.theta_true[j], 0.25 * adaptive.theta_true[j]) << "viscous J" << j + 1;
  // Nothing diverged.
  for (int i = 0; i < 18; ++i) EXPECT_LT(std::abs(adaptive.theta_hat[i]), 20.0) << i;
}

TEST_F(WithFriction, TheRobustLawSplitsCoulombAndStribeckOfJointsOneAndTwo) {
  // The robust form of (67) learns from the tracking error instead, and its gradient does move the
  // Coulomb and Stribeck terms apart: within 25 % of the truth each after 30 s (its full 120 s
  // table: docs/experiment.md).
  ExperimentConfig c = config(30, osc::FrictionMode::kAdaptive, osc::robot::kFrictionPaper);
  c.gains.adaptation = osc::AdaptationLaw::kRobust;
  const ExperimentResult robust = run_experiment(c);
  ASSERT_EQ(robust.status, 0u);
  for (int j : {0, 1}) {
    for (int k : {1, 2}) {
      const int idx = 6 * k + j;
      EXPECT_NEAR(robust.theta_hat[idx], robust.theta_true[idx], 0.25 * robust.theta_true[idx]) << "theta " << idx;
    }
  }
}

TEST(ClosedLoop, TracksWithTenPercentModelError) {
  for (double err : {-0.1, 0.1}) {
    ExperimentConfig c = config(15, osc::FrictionMode::kAdaptive, osc::robot::kFrictionPaper);
    c.model_error = err;
    const ExperimentResult r = run_experiment(c);
    print(err < 0 ? "model -10 %, adaptive" : "model +10 %, adaptive", r);
    ASSERT_EQ(r.status, 0u);
    for (int i = 0; i < 3; ++i) EXPECT_LT(r.final_max_error[i], 1.0) << "axis " << i << " err " << err;
    for (int i = 3; i < 6; ++i) EXPECT_LT(r.final_max_error[i], 0.1) << "axis " << i << " err " << err;
  }
}

TEST(ClosedLoop, FloatControllerTracksLikeDouble) {
  ExperimentConfig c = config(15, osc::FrictionMode::kAdaptive, osc::robot::kFrictionPaper);
  const ExperimentResult d = run_experiment(c);
  c.scalar = Scalar::kFloat;
  const ExperimentResult f = run_experiment(c);
  print("double controller", d);
  print("float controller", f);
  ASSERT_EQ(f.status, 0u);
  for (int i = 0; i < 3; ++i) EXPECT_LT(f.final_max_error[i], 1.5 * d.final_max_error[i] + 0.02) << i;
}

// Issue 10: the fixed-point (Q12.19) controller against the float one, with and without
// compensation, by the issue's criterion: the 120 s experiment, the largest error over its last
// 20 s. (A 30 s run with a 10 s window was used before; its orientation errors are about one
// encoder count of the wrist, and one 10 s window's ratio spreads from 0.88 to 1.57 between the
// windows of one run: docs/fixed_point.md, "Closed loop".)
TEST(ClosedLoop, FixedPointControllerTracksLikeFloatAndCompensationHalvesTheErrors) {
  ExperimentConfig c = config(120, osc::FrictionMode::kAdaptive, osc::robot::kFrictionPaper);
  c.final_window = 20;
  c.scalar = Scalar::kFloat;
  const ExperimentResult f = run_experiment(c);
  c.scalar = Scalar::kFixed;
  const ExperimentResult x = run_experiment(c);
  c.mode = osc::FrictionMode::kNone;
  const ExperimentResult n = run_experiment(c);
  print("float controller", f);
  print("fixed-point controller", x);
  print("fixed-point, no comp.", n);
  ASSERT_EQ(f.status, 0u);
  ASSERT_EQ(x.status, 0u) << osc::fault_name(x.status);
  ASSERT_EQ(n.status, 0u) << osc::fault_name(n.status);
  for (int i = 0; i < 6; ++i) {
    EXPECT_LE(x.final_max_error[i], 1.5 * f.final_max_error[i]) << "axis " << i;
    EXPECT_GE(n.final_max_error[i], 2.0 * x.final_max_error[i]) << "axis " << i;
  }
}

TEST(Windows, PerWindowMaximaCoverTheRunAndAgreeWithTheWholeRunMaximum) {
  ExperimentConfig c = config(7, osc::FrictionMode::kAdaptive, osc::robot::kFrictionPaper);
  c.window = 2.0;
  const ExperimentResult r = run_experiment(c);
  ASSERT_EQ(r.window_max.size(), 4u);  // [0,2) [2,4) [4,6) [6,7)
  ASSERT_EQ(r.window_theta_range.size(), 4u);
  EXPECT_EQ(r.adaptation, "momentum");  // the default (osc::kDefaultAdaptationLaw)
  EXPECT_EQ(r.adaptation, osc::adaptation_law_name(osc::kDefaultAdaptationLaw));
  for (int i = 0; i < 6; ++i) {
    double m = 0;
    for (const auto& w : r.window_max) m = std::max(m, w[i]);
    EXPECT_EQ(m, r.max_error[i]) << i;
  }
  for (const auto& th : r.window_theta_range) EXPECT_LE(th[0], th[1]);
  for (int i = 0; i < 18; ++i) {
    EXPECT_GE(r.theta_hat[i], r.window_theta_range.back()[0]);
    EXPECT_LE(r.theta_hat[i], r.window_theta_range.back()[1]);
  }
}

// Issue 8: the paper's sampled law (67) drifts without bound under encoder quantisation (the
// mechanism: docs/adaptation.md). On a frictionless plant every friction estimate should stay near
// 0; 300 s separate the laws clearly (paper: theta^_vis,J1 about 12.5 and estimates below 0; robust:
// about 0.01, inside the bounds).
TEST(ClosedLoop, AdaptationDoesNotDriftOnAFrictionlessPlant) {
  auto drift = [](osc::AdaptationLaw law) {
    ExperimentConfig c = config(300, osc::FrictionMode::kAdaptive, osc::kFrictionNone);
    c.final_window = 60;
    c.gains.adaptation = law;
    const ExperimentResult r = run_experiment(c);
    bool in_bounds = true;
    for (int i = 0; i < 18; ++i)
      in_bounds = in_bounds && r.theta_min_seen[i] >= 0.0 && r.theta_max_seen[i] <= osc::params::kThetaMax[i];
    std::printf(
        "%-6s law, frictionless plant, 300 s: theta^_vis,J1 %.4f, predicted friction rms (last 60 s) %.4f N m, "
        "theta^ %s its bounds, fault %s at %.1f s\n",
        r.adaptation.c_str(), r.theta_hat[0], r.friction_rms_error, in_bounds ? "inside" : "OUTSIDE",
        r.status ? osc::fault_name(r.status) : "none", r.fault_time);
    return std::make_tuple(r.theta_hat[0], r.friction_rms_error, in_bounds, r.status, r.fault_time);
  };
  const auto [vis_robust, rms_robust, bounded_robust, status_robust, t_robust] = drift(osc::AdaptationLaw::kRobust);
  EXPECT_EQ(status_robust, 0u);
  EXPECT_LT(vis_robust, 1.0);
  EXPECT_LT(rms_robust, 0.3);  // the plant has no friction at all
  EXPECT_TRUE(bounded_robust);
  // The same criteria catch the drift of (67).
  const auto [vis_paper, rms_paper, bounded_paper, status_paper, t_paper] = drift(osc::AdaptationLaw::kPaper);
  // Near the end of the 300 s the drift reaches the supervisor's theta_bounds band (theta^ beyond
  // [-theta_max, 2 theta_max]), which is that monitor doing its job; any other fault is a failure.
  EXPECT_TRUE(status_paper == 0u || status_paper == osc::kFaultThetaBounds) << osc::fault_name(status_paper);
  if (status_paper != 0u) {
    EXPECT_GT(t_paper, 200.0);
  }
  EXPECT_GT(vis_paper, 1.0);
  EXPECT_GT(rms_paper, 0.3);
  EXPECT_FALSE(bounded_paper);
}

// The mechanism, isolated: on a frictionless plant the paper's law drifts at a rate set by the
// encoder quantum delta alone, E[q^dot Dq] ~ -k (1 + k dt) delta^2 / 12 (docs/adaptation.md): 4x finer
// encoders (delta / 4) should cut the drift about 16x. The robust law does not drift at either.
TEST(ClosedLoop, PaperLawDriftScalesWithTheSquareOfTheEncoderQuantum) {
  auto vis_j1 = [](osc::AdaptationLaw law, double cpr) {
    ExperimentConfig c = config(200, osc::FrictionMode::kAdaptive, osc::kFrictionNone);
    c.gains.adaptation = law;
    c.encoder_counts_per_motor_rev = cpr;
    const ExperimentResult r = run_experiment(c);
    EXPECT_EQ(r.status, 0u);
    std::printf("%-6s law, %6.0f counts/motor rev, frictionless, 200 s: theta^_vis,J1 %.4f\n", r.adaptation.c_str(),
                cpr, r.theta_hat[0]);
    return r.theta_hat[0];
  };
  const double coarse = vis_j1(osc::AdaptationLaw::kPaper, 1000), fine = vis_j1(osc::AdaptationLaw::kPaper, 4000);
  EXPECT_GT(coarse, 4.0);
  EXPECT_GT(coarse / fine, 8.0);  // delta^2 scaling (16x), less the small drift that remains without quantisation
  EXPECT_LT(coarse / fine, 32.0);
  EXPECT_LT(vis_j1(osc::AdaptationLaw::kRobust, 1000), 0.1);
}

// Time that never runs out: after 25 s the controller's sample counter jumps to 2^31, 2^32 - 10,
// 240 h and 50 days of uptime (rounded to the trajectory's period, so the reference is the same).
// The tracking errors from then on must equal those of the run without the jump exactly, in double,
// in float (a float n dt had stopped advancing after 4.6 h) and in fixed point.
TEST(Uptime, TrackingAfterLongUptimesEqualsTrackingAtStart) {
  for (const Scalar scalar : {Scalar::kDouble, Scalar::kFloat, Scalar::kFixed}) {
    ExperimentConfig c = config(35, osc::FrictionMode::kAdaptive, osc::robot::kFrictionPaper);
    c.scalar = scalar;
    c.final_window = 10;
    const ExperimentResult base = run_experiment(c);
    ASSERT_EQ(base.status, 0u);
    const long jump_at_tick = 25000;
    for (const std::uint64_t target : {std::uint64_t{1} << 31, (std::uint64_t{1} << 32) - 10,
                                       std::uint64_t{240} * 3600 * 1000, std::uint64_t{50} * 86400 * 1000}) {
      const std::uint64_t period = osc::kTrajectoryPeriodTicks;
      c.jump_at = jump_at_tick * 1e-3;
      c.jump_ticks = (target - jump_at_tick) / period * period;
      const ExperimentResult r = run_experiment(c);
      ASSERT_EQ(r.status, 0u);
      for (int i = 0; i < 6; ++i)
        EXPECT_EQ(r.final_max_error[i], base.final_max_error[i]) << "uptime " << target << " axis " << i;
      std::printf(
          "%s controller, counter jumps to %llu at 25 s: last 10 s max |e| %.4f %.4f %.4f mm (without: %.4f %.4f "
          "%.4f)\n",
          kScalarNames[static_cast<int>(scalar)], static_cast<unsigned long long>(jump_at_tick + c.jump_ticks),
          r.final_max_error[0], r.final_max_error[1], r.final_max_error[2], base.final_max_error[0],
          base.final_max_error[1], base.final_max_error[2]);
    }
    c.jump_at = -1;
  }
}

// Fault injection into the simulated hardware (docs/safety.md), as puma_experiment --inject does.
ExperimentResult inject(const char* spec, double duration, osc::FrictionMode mode = osc::FrictionMode::kAdaptive,
                        bool residual_monitor = false) {
  ExperimentConfig c = config(duration, mode, osc::robot::kFrictionPaper);
  c.residual_monitor = residual_monitor;
  // The trial's stuck-encoder criteria were fitted with the robust law's friction estimates (with the
  // momentum law's, a J3 encoder stuck at 21.25 s is caught only by the position check, after
  // 141 ms): the trial keeps the law they were fitted with.
  if (!residual_monitor) c.gains.adaptation = osc::AdaptationLaw::kRobust;
  std::string err;
  EXPECT_TRUE(parse_injection(spec, c.injection, err)) << err;
  const ExperimentResult r = run_experiment(c);
  const InjectionResult& ir = r.injection;
  std::printf("%-22s detected after %6.1f ms as %-14s zero torque after %6.1f ms, excursion %.2f mm\n", spec,
              (ir.detected - ir.injection.at) * 1e3, osc::fault_name(ir.faults),
              (ir.zero_torque - ir.injection.at) * 1e3, ir.excursion_mm);
  return r;
}

TEST(Injection, GarbageFirstReadingGivesZeroTorqueFromTheFirstTick) {
  for (const char* spec : {"encoder-garbage:1@0", "encoder-garbage:6@0", "encoder-garbage@0"}) {
    const ExperimentResult r = inject(spec, 0.5);
    EXPECT_EQ(r.injection.detected, 0.0) << spec;
    EXPECT_EQ(r.injection.zero_torque, 0.0) << spec;  // every amplifier at zero from tick 0 on
    EXPECT_EQ(r.injection.faults & osc::kFaultEncoderRange, osc::kFaultEncoderRange) << spec;
    EXPECT_EQ(r.injection.max_torque_after, 0.0) << spec;
  }
}

TEST(Injection, JumpOverrunAndEstopAreDetectedInTheSameTick) {
  const std::pair<const char*, std::uint32_t> cases[] = {{"encoder-jump:2@3.5", osc::kFaultEncoderJump},
                                                         {"encoder-jump:5@3.5", osc::kFaultEncoderJump},
                                                         {"overrun@3.5", osc::kFaultOverrun},
                                                         {"estop@3.5", osc::kFaultEstop}};
  for (const auto& [spec, fault] : cases) {
    const ExperimentResult r = inject(spec, 4);
    EXPECT_NEAR(r.injection.detected, 3.5, 1e-9) << spec;
    EXPECT_NEAR(r.injection.zero_torque, 3.5, 1e-9) << spec;
    EXPECT_EQ(r.injection.faults, fault) << spec;
    EXPECT_EQ(r.status, fault) << spec;  // nothing before the injection
  }
}

// A stuck encoder on any joint while the reference moves it: detected within 50 ms with a tip
// excursion of at most 5 mm (the times where this cannot hold are in docs/safety.md). Joint 3 is
// caught at 51 ms: the torque criteria's qualification (params::kStuckQualifyTicks) costs it the
// ticks beyond the first; the other joints within 26 ms.
TEST(Injection, StuckEncoderIsDetectedWithin50msAndExcursionBelow5mm) {
  for (int j = 1; j <= 6; ++j) {
    const std::string spec = "encoder-stuck:" + std::to_string(j) + "@21.25";
    const ExperimentResult r = inject(spec.c_str(), 21.5);
    ASSERT_GE(r.injection.detected, 0) << spec;
    const double allowed = j == 3 ? 0.050 + (osc::params::kStuckQualifyTicks - 1) * osc::params::kDt : 0.030;
    EXPECT_LE(r.injection.detected - 21.25, allowed + 1e-9) << spec;
    EXPECT_EQ(r.injection.zero_torque, r.injection.detected) << spec;
    EXPECT_LE(r.injection.excursion_mm, 5.0) << spec;
    EXPECT_EQ(r.fault_time, r.injection.detected) << spec;  // no fault before the injection
  }
}

// A stuck amplifier cannot be zeroed by its DAC code: the monitors notice the motion it causes, and
// the fault line (the amplifier enable) removes the torque.
TEST(Injection, StuckAmplifierIsCaughtAndDisabledByTheFaultLine) {
  const ExperimentResult r = inject("dac-stuck:2@3.5", 4.5);
  ASSERT_GE(r.injection.detected, 0);
  EXPECT_LE(r.injection.detected - 3.5, 0.6);
  EXPECT_EQ(r.injection.zero_torque, r.injection.detected);
  // The tracking bound trips first: the excursion is that bound plus what one tick adds.
  EXPECT_LE(r.injection.excursion_mm, osc::params::kTrackingLimitPosition * 1e3 + 1.0);
  EXPECT_EQ(r.injection.max_torque_after, 0.0);
}

// The residual monitor armed (run.residual_monitor=on, the default: docs/safety.md), the stuck-encoder
// monitor's fitted criteria off: a stuck joint-2 encoder mid-motion is a stuck encoder that the
// residual monitor names (J2), a stuck joint-2 amplifier a drive fault.
TEST(Injection, ResidualMonitorIsolatesAStuckEncoderAndAStuckDrive) {
  const ExperimentResult e = inject("encoder-stuck:2@21.25", 21.6, osc::FrictionMode::kAdaptive, true);
  ASSERT_GE(e.injection.detected, 0);
  EXPECT_LE(e.injection.detected - 21.25, 0.1);
  EXPECT_EQ(e.injection.faults, static_cast<std::uint32_t>(osc::kFaultEncoderStuck));
  EXPECT_GE(e.residual_detected_s, 0);
  EXPECT_EQ(e.residual_joint, 1);
  const ExperimentResult d = inject("dac-stuck:2@21.25", 21.8, osc::FrictionMode::kAdaptive, true);
  ASSERT_GE(d.injection.detected, 0);
  EXPECT_LE(d.injection.detected - 21.25, 0.5);
  EXPECT_EQ(d.injection.faults, static_cast<std::uint32_t>(osc::kFaultDriveFault));
  EXPECT_EQ(d.residual_joint, 1);
}

TEST(Injection, ParserRejectsBadSpecifications) {
  Injection inj;
  std::string err;
  for (const char* bad :
       {"", "encoder-stuck", "encoder-stuck@", "encoder-stuck@-1", "encoder-stuck@nan", "encoder-stuck:0@1",
        "encoder-stuck:7@1", "encoder-stuck:12@1", "encoder-stuck:@1", "overrun:1@1", "melt@1", "estop@1x"}) {
    err.clear();
    EXPECT_FALSE(parse_injection(bad, inj, err)) << bad;
    EXPECT_FALSE(err.empty()) << bad;
  }
  ASSERT_TRUE(parse_injection("encoder-stuck:3@12.5", inj, err));
  EXPECT_EQ(inj.kind, InjectionKind::kEncoderStuck);
  EXPECT_EQ(inj.joint, 2);
  EXPECT_EQ(inj.at, 12.5);
  EXPECT_EQ(to_string(inj), "encoder-stuck:3@12.5");
}

}  // namespace

namespace {

// The monitors never trip on the fault-free experiment, with or without compensation, on either
// friction preset of the robot description (the Corke/Armstrong-Helouvry one holds joint 1 with
// 26 N m of static friction), and keep a margin below their thresholds (an hour of each:
// docs/safety.md; CI runs 300 s of each).
TEST(Monitors, NoFalseFaultWithOrWithoutCompensation) {
  for (const osc::FrictionCoefficients* fr : {&osc::robot::kFrictionPaper, &osc::robot::kFrictionCorke})
    for (const osc::FrictionMode mode : {osc::FrictionMode::kAdaptive, osc::FrictionMode::kNone}) {
      ExperimentConfig c = config(300, mode, *fr);
      const ExperimentResult r = run_experiment(c);
      EXPECT_EQ(r.status, 0u) << fr->name << ": " << osc::fault_name(r.status) << " at " << r.fault_time << " s";
      std::printf("%-6s %-8s 300 s: stuck monitor peaks (counts / N m / N m while silent):", fr->name, r.mode.c_str());
      for (int j = 0; j < 6; ++j) {
        std::printf(" J%d %.1f/%.1f/%.1f", j + 1, r.stuck_peak[j], r.stuck_dtau_peak[j], r.stuck_dtau_silent_peak[j]);
        EXPECT_LT(r.stuck_peak[j], 0.9 * osc::params::kStuckMotionCounts) << fr->name << " J" << j + 1;
        EXPECT_LT(r.stuck_dtau_peak[j], 0.8 * osc::params::kStuckTorque[j]) << fr->name << " J" << j + 1;
        EXPECT_LT(r.stuck_dtau_silent_peak[j], 0.8 * osc::params::kStuckTorqueSilent[j]) << fr->name << " J" << j + 1;
      }
      // The residual monitor, a trial here: it would not have faulted either.
      std::printf("; residual / threshold:");
      for (int j = 0; j < 6; ++j) {
        std::printf(" %.2f", r.residual_peak_ratio[j]);
        EXPECT_LT(r.residual_peak_ratio[j], 1.0) << fr->name << " J" << j + 1;
      }
      EXPECT_LT(r.residual_detected_s, 0) << osc::fault_name(r.residual_fault) << " J" << r.residual_joint + 1;
      const double pos = std::max({r.max_error[0], r.max_error[1], r.max_error[2]});
      std::printf("; worst position error %.2f mm\n", pos);
      EXPECT_LT(pos, 0.5 * osc::params::kTrackingLimitPosition * 1e3);
    }
}

}  // namespace
