// The simulated plant (host_sim/): articulated-body dynamics against the kernels' inverse
// dynamics, energy conservation of the integrator, step-size adequacy, and the HAL binding.
#include <gtest/gtest.h>

#include <cmath>

#include "experiment.hpp"
#include "hal/hal.hpp"
#include "osc/kernels/dynamics.hpp"
#include "osc/runtime/io.hpp"
#include "plant_hal.hpp"
#include "test_util.hpp"

using namespace sim;

namespace {

Vec6 q_start() { return osc::joint_vector<double>(osc::robot::kQStart); }

TEST(Plant, ArticulatedBodyInvertsTheKernelsInverseDynamics) {
  // ABA (plant) and CRBA/RNEA (controller kernels) are separate code paths: A qdd + c + g must
  // reproduce the torque that produced qdd.
  osc::test::RandomStates rs;
  const osc::Model<double> model = osc::Model<double>::of(osc::robot::kArm);
  osc::Data<double> data;
  ArticulatedBody body;
  double worst = 0;
  for (int k = 0; k < 500; ++k) {
    const Vec6 q = rs.q_nonsingular(), qd = rs.vec(2.0), tau = rs.vec(30.0);
    const Vec6 qdd = body.forward_dynamics(q, qd, tau);
    osc::forward_kinematics(model, data, q);
    const Vec6 back = osc::rnea(model, data, qd, qdd, true).tau;
    worst = std::max(worst, (back - tau).norm() / (1.0 + tau.norm()));
  }
  std::printf("ABA vs RNEA worst relative torque error: %.3e\n", worst);
  EXPECT_LT(worst, 1e-11);
}

TEST(Plant, EnergyIsConservedWithoutTorqueAndFriction) {
  PlantConfig cfg;
  cfg.friction = osc::kFrictionNone;
  Plant plant(cfg);
  Vec6 qd0;
  qd0 << 0.5, -0.3, 0.4, 1.0, -0.8, 1.2;
  plant.reset(q_start(), qd0);
  const double E0 = plant.energy();
  double drift = 0;
  for (int k = 0; k < 2000; ++k) {  // 2 s of free motion (falling and swinging under gravity)
    plant.integrate(Vec6::Zero(), 1e-3);
    drift = std::max(drift, std::abs(plant.energy() - E0));
  }
  const double scale = std::abs(E0) + 0.5 * qd0.squaredNorm();
  std::printf("energy drift over 2 s at a 0.1 ms RK4 step: %.3e J (E0 = %.3f J)\n", drift, E0);
  EXPECT_LT(drift, 1e-6 * scale);
}

TEST(Plant, FrictionFollowsModel2) {
  Plant plant;
  Vec6 qd;
  qd << 0.5, -0.5, 0.0, 2.0, -1e-3, 0.1;
  const Vec6 f = plant.friction(qd);
  const auto& p = osc::robot::kFrictionPaper;
  for (int i = 0; i < 6; ++i) {
    const double s = qd(i) > 0 ? 1 : (qd(i) < 0 ? -1 : 0);
    EXPECT_DOUBLE_EQ(f(i), p.vis[i] * qd(i) + (p.cou[i] + p.sti[i] * std::exp(-qd(i) * qd(i))) * s);
  }
  EXPECT_EQ(f(2), 0.0);  // sgn(0) = 0
}

/// 2 s of the plant in open loop from the start pose: gravity compensation plus a sinusoidal torque
/// that makes every joint reverse. Each 1 ms sample goes through Plant::integrate or, with
/// `sampled`, Plant::advance_sample (the smooth-step path); the joint angles at the end, and the
/// articulated-body evaluations it took in `evaluations` (when given).
Vec6 open_loop(const PlantConfig& cfg, bool sampled, long* evaluations) {
  Plant plant(cfg);
  plant.reset(q_start());
  osc::Data<double> data;
  const osc::Model<double> model = osc::Model<double>::of(osc::robot::kArm);
  for (int k = 0; k < 2000; ++k) {
    osc::forward_kinematics(model, data, plant.q());
    Vec6 tau = osc::gravity_torques(model, data);
    for (int i = 0; i < 6; ++i) tau(i) += (i < 3 ? 15.0 : 3.0) * std::sin(2 * osc::kPi * (0.7 + 0.2 * i) * k * 1e-3);
    if (sampled)
      plant.advance_sample(tau, tau, 1e-3);
    else
      plant.integrate(tau, 1e-3);
  }
  if (evaluations) *evaluations = plant.evaluations();
  return plant.q();
}

/// How two runs of the same experiment differ: the largest difference of a logged tracking error
/// sample (mm, deg) and of the max-error statistics (mm, deg).
struct RunDifference {
  double pos = 0, ang = 0, max_pos = 0, max_ang = 0;
  RunDifference(const ExperimentResult& a, const ExperimentResult& b) {
    for (int i = 0; i < 6; ++i) {
      double& sample = i < 3 ? pos : ang;  // x, y, z in mm; the angles in deg
      for (size_t k = 0; k < a.log.size() && k < b.log.size(); ++k)
        sample = std::max(sample, std::abs(a.log[k].e[i] - b.log[k].e[i]));
      double& stat = i < 3 ? max_pos : max_ang;
      stat = std::max(stat, std::abs(a.max_error[i] - b.max_error[i]));
    }
  }
};

TEST(Plant, HalvingTheStepInOpenLoop) {
  // Integration error alone (no feedback): 2 s under a sinusoidal torque that makes every joint
  // reverse. Without friction the dynamics are smooth and RK4 converges to round-off; with the
  // paper's friction the sgn() of model (2) is discontinuous at zero velocity, fixed-step
  // integration is first order at each reversal, and a joint that the torque cannot break away
  // chatters about zero velocity; the difference is then of the order of an encoder count.
  auto run = [](double h, const osc::FrictionCoefficients& friction) {
    PlantConfig cfg;
    cfg.substep = h;
    cfg.friction = friction;
    return open_loop(cfg, false, nullptr);
  };
  const double smooth = (run(1e-4, osc::kFrictionNone) - run(5e-5, osc::kFrictionNone)).cwiseAbs().maxCoeff();
  const double rough =
      (run(1e-4, osc::robot::kFrictionPaper) - run(5e-5, osc::robot::kFrictionPaper)).cwiseAbs().maxCoeff();
  std::printf(
      "open loop, step 1e-4 vs 5e-5 s, max joint-angle difference after 2 s: %.2e rad without friction, "
      "%.2e rad with the paper's friction\n",
      smooth, rough);
  EXPECT_LT(smooth, 1e-9);
  EXPECT_LT(rough, 5e-4);  // a few encoder counts (one count is 6e-5 .. 1.2e-4 rad on joints 1-3)
}

TEST(Plant, HalvingTheStepChangesA10sClosedLoopRunByLessThanTolerance) {
  // In closed loop a one-count encoder flip propagates, so samples may differ by about one count;
  // the run's statistics must agree.
  ExperimentConfig a;
  a.duration = 10;
  a.final_window = 5;
  a.log_period = 0.001;
  // The robust law: the momentum law's identification takes or leaves a sample at a gate, and a count
  // that flips then parts the two runs' theta^ for seconds (J1's viscous coefficient by up to 3 N m
  // s/rad, J4's Coulomb level by 2.7 N m, measured), which measures the gates, not the plant's step.
  a.gains.adaptation = osc::AdaptationLaw::kRobust;
  ExperimentConfig b = a;
  b.plant.substep = a.plant.substep / 2;
  const ExperimentResult ra = run_experiment(a), rb = run_experiment(b);
  ASSERT_EQ(ra.log.size(), rb.log.size());
  const RunDifference diff(ra, rb);
  const double dpos = diff.pos, dang = diff.ang, dmax_pos = diff.max_pos, dmax_ang = diff.max_ang;
  std::printf(
      "closed loop, step %.0e vs %.0e s: max sample difference %.3f mm %.4f deg; max-error statistics "
      "differ by %.4f mm %.5f deg\n",
      a.plant.substep, b.plant.substep, dpos, dang, dmax_pos, dmax_ang);
  // Stated tolerance on the table entries: one encoder quantum at the start pose (0.069 mm) and 0.05 deg. The
  // orientation's peak over the last 5 s moves with any count that flips: measured on 2026-12-02 over substeps of
  // 4e-5 .. 1e-4 s, e_phz's peak spans 0.053-0.088 deg with the alternate model rate and 0.056-0.079 deg with
  // the model every step (the 0.01 deg stated before held for this one pair of steps by chance).
  EXPECT_LT(dmax_pos, 0.069);
  EXPECT_LT(dmax_ang, 0.05);
  // Samples: two to three encoder quanta (measured 0.10 mm).
  EXPECT_LT(dpos, 0.2);
}

TEST(Plant, SmoothStepsAgreeWithTheFixedStep) {
  // Away from velocity reversals the plant takes smooth_steps substeps in one RK4 step; through a
  // reversal it falls back to the fixed substep. Open loop (the sinusoidal torque of the halving
  // test, every joint reversing): without friction the result matches the fixed step to round-off
  // of RK4's error, with friction to the order of the halving difference. Closed loop: the run's
  // statistics agree within the halving test's tolerances, at under half the evaluations.
  auto run = [](int smooth, const osc::FrictionCoefficients& friction, long* evaluations) {
    PlantConfig cfg;
    cfg.smooth_steps = smooth;
    cfg.friction = friction;
    return open_loop(cfg, true, evaluations);
  };
  const int s = PlantConfig{}.smooth_steps;
  ASSERT_GT(s, 1);
  long n_fixed = 0, n_smooth = 0;
  const double smooth =
      (run(1, osc::kFrictionNone, &n_fixed) - run(s, osc::kFrictionNone, &n_smooth)).cwiseAbs().maxCoeff();
  const double rough =
      (run(1, osc::robot::kFrictionPaper, nullptr) - run(s, osc::robot::kFrictionPaper, nullptr)).cwiseAbs().maxCoeff();
  std::printf(
      "open loop, %d substeps at once vs fixed: max joint-angle difference after 2 s %.2e rad without friction, "
      "%.2e rad with the paper's friction; %.1f vs %.1f evaluations per sample\n",
      s, smooth, rough, n_smooth / 2000.0, n_fixed / 2000.0);
  EXPECT_LT(smooth, 1e-9);
  EXPECT_LT(rough, 5e-4);
  EXPECT_EQ(n_fixed, 2000 * 40);
  EXPECT_LT(n_smooth, n_fixed / 2);

  ExperimentConfig a;
  a.duration = 10;
  a.final_window = 5;
  a.log_period = 0.001;
  a.plant.smooth_steps = 1;
  ExperimentConfig b = a;
  b.plant.smooth_steps = s;
  const ExperimentResult ra = run_experiment(a), rb = run_experiment(b);
  ASSERT_EQ(ra.log.size(), rb.log.size());
  const RunDifference diff(ra, rb);
  const double dpos = diff.pos, dang = diff.ang, dmax_pos = diff.max_pos, dmax_ang = diff.max_ang;
  const double per_sample_a = static_cast<double>(ra.plant_evaluations) / 10000,
               per_sample_b = static_cast<double>(rb.plant_evaluations) / 10000;
  std::printf(
      "closed loop, %d substeps at once vs fixed: max sample difference %.3f mm %.4f deg; max-error statistics "
      "differ by %.4f mm %.5f deg; %.1f vs %.1f evaluations per sample\n",
      s, dpos, dang, dmax_pos, dmax_ang, per_sample_b, per_sample_a);
  EXPECT_LT(dmax_pos, 0.069);
  EXPECT_LT(dmax_ang, 0.01);
  EXPECT_LT(dpos, 0.15);
  EXPECT_NEAR(per_sample_a, 40.0, 1e-9);
  EXPECT_LT(per_sample_b, per_sample_a / 2);
}

TEST(PlantHal, EncodersQuantiseAndDacsScaleAndSaturate) {
  Plant plant;
  const Vec6 q0 = q_start();
  Vec6 q = q0;
  q(1) += 0.01;
  q(2) -= 0.02;
  plant.reset(q);
  PlantHal hal(plant, q0);
  std::int32_t counts[6];
  hal.read_encoders(counts);
  EXPECT_EQ(counts[0], 0);
  EXPECT_EQ(counts[1], static_cast<std::int32_t>(std::floor(0.01 * osc::counts_per_rad(1))));
  EXPECT_EQ(counts[2], static_cast<std::int32_t>(std::floor(-0.02 * osc::counts_per_rad(2))));
  // Angle reconstruction is within one count.
  for (int i = 0; i < 6; ++i) {
    const double back = osc::counts_to_angle<double>(i, counts[i], q0(i));
    EXPECT_LE(q(i) - back, 1.0 / osc::counts_per_rad(i) + 1e-12);
    EXPECT_GE(q(i) - back, 0.0);
  }
  // DAC: rounding, saturation, and a non-finite torque giving code 0.
  std::int32_t code = 7;
  EXPECT_FALSE(osc::torque_to_code(1, 10.0, code));
  EXPECT_NEAR(osc::code_to_torque(1, code), 10.0, osc::robot::kDrives.torque_limit[1] / osc::kDacMaxCode);
  EXPECT_TRUE(osc::torque_to_code(1, 1e6, code));
  EXPECT_EQ(code, osc::kDacMaxCode);
  EXPECT_TRUE(osc::torque_to_code(1, -1e6, code));
  EXPECT_EQ(code, -osc::kDacMaxCode);
  EXPECT_TRUE(osc::torque_to_code(1, std::nan(""), code));
  EXPECT_EQ(code, 0);
  const std::int32_t codes[6] = {100, -200, 300, 0, osc::kDacMaxCode, -osc::kDacMaxCode};
  hal.write_dacs(codes);
  EXPECT_DOUBLE_EQ(hal.torque()(4), osc::robot::kDrives.torque_limit[4]);
  EXPECT_DOUBLE_EQ(hal.torque()(5), -osc::robot::kDrives.torque_limit[5]);
}

TEST(Hal, EncoderUnwrapExtendsA16BitCounterAcrossWraps) {
  hal::EncoderUnwrap<16> enc;
  std::int64_t truth = 0;
  std::uint32_t raw = 0;
  // Move forward past several wraps, then back below zero, in steps below half the range.
  for (int k = 0; k < 1000; ++k) {
    const int step = k < 600 ? 500 : -900;
    truth += step;
    raw = static_cast<std::uint32_t>(truth) & 0xFFFFu;
    ASSERT_EQ(enc.update(raw), truth) << k;
  }
  EXPECT_LT(truth, 0);
}

TEST(Hal, EncoderUnwrapWrapsModularlyPastTheInt32Range) {
  // A 32-bit position that runs past INT32_MAX wraps to INT32_MIN (modular), never through signed
  // overflow.
  hal::EncoderUnwrap<16> enc;
  enc.position = 2147483647 - 100;
  std::uint32_t raw = 0;
  raw = (raw + 300) & 0xFFFFu;
  EXPECT_EQ(enc.update(raw), static_cast<std::int32_t>(-2147483647 - 1 + 199));
}

}  // namespace
