// The residual monitor (osc/runtime/residual_monitor.hpp; docs/safety.md, "The residual monitor") on
// an arm frozen at the start pose (ResidualRig): the residual and the change residual in closed form,
// each fault's isolation (drive, collision, stuck encoder), nothing below the thresholds, the wrist's
// velocity noise against the observer's mixing, and a contact the task reacted to. Its thresholds:
// test_residual_thresholds.cpp; its travel check: test_residual_travel.cpp.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "monitor_fixtures.hpp"
#include "osc/runtime/residual_monitor.hpp"
#include "test_util.hpp"

using namespace osc;
using namespace osc::test;

namespace {

// ---- The residual monitor (docs/safety.md, "The residual monitor")

TYPED_TEST(Monitors, ResidualIsTheExternalTorqueThroughAFirstOrderFilter) {
  using S = TypeParam;
  ResidualRig<S> rig;
  const bool still[kDof] = {};
  const Vec6<double> ext = closed_form_torque();
  const double tol = kClosedFormTol<S>;
  rig.step(Vec6<double>::Zero(), still);  // primes it
  for (int n = 1; n <= 100; ++n) {
    rig.step(ext, still);
    for (int i = 0; i < kDof; ++i) {
      const double expect = closed_form_residual(ext(i), i, n);
      ASSERT_NEAR(static_cast<double>(rig.m.r(i)), expect, tol + 1e-6 * std::abs(expect)) << "J" << i + 1 << " n " << n;
    }
  }
}

// The change channel: d = r - r_slow every step, r_slow the residual through the slow filter
// (params::kResidualSlowGain) on the monitor's turns (every kResidualTurnEvery steps: the prime's and every
// other one), fed r's mean over the turn; on the same external torque, r in closed form, r_slow by its recursion.
TYPED_TEST(Monitors, TheChangeResidualIsTheResidualLessItsSlowPart) {
  using S = TypeParam;
  static_assert(params::kResidualTurnEvery == 2);
  ResidualRig<S> rig;
  const bool still[kDof] = {};
  const Vec6<double> ext = closed_form_torque();
  const double tol = kClosedFormTol<S>;
  const double Ks = params::kResidualSlowGain * params::kDt * params::kResidualTurnEvery;
  Vec6<double> slow = Vec6<double>::Zero();
  rig.step(Vec6<double>::Zero(), still);
  for (int n = 1; n <= 400; ++n) {
    rig.step(ext, still);
    for (int i = 0; i < kDof; ++i) {
      const double r = closed_form_residual(ext(i), i, n);
      if (n % 2 == 0) slow(i) += Ks * (0.5 * (r + closed_form_residual(ext(i), i, n - 1)) - slow(i));
      ASSERT_NEAR(static_cast<double>(rig.m.d(i)), r - slow(i), tol + 1e-6 * std::abs(r)) << "J" << i + 1 << " n " << n;
    }
  }
  // A constant torque leaves it: after 400 ms, about e^(-2) K / (K - K_slow) of the step is left.
  for (int i = 0; i < kDof; ++i) EXPECT_LT(std::abs(static_cast<double>(rig.m.d(i))), 0.2 * std::abs(ext(i)));
}

TYPED_TEST(Monitors, ResidualIsolatesDriveCollisionAndStuckEncoder) {
  using S = TypeParam;
  const bool all[kDof] = {true, true, true, true, true, true};
  {  // Three times the threshold on J2 alone, every encoder counting: a drive that does not deliver.
    ResidualRig<S> rig;
    rig.m.armed = true;
    rig.step(Vec6<double>::Zero(), all);
    Vec6<double> ext = Vec6<double>::Zero();
    ext(1) = 3 * static_cast<double>(rig.m.threshold(1));
    std::uint32_t kind = 0;
    const int n = ticks_to_fault(rig, ext, all, kind);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultDriveFault));
    // Beyond the threshold once 1 - (1 - K dt)^n > 1/3 (n >= 9 at 50 /s), then for 3 ticks.
    EXPECT_GE(n, params::kResidualQualifyTicks + 5);
    EXPECT_LE(n, 15);
    EXPECT_EQ(rig.m.joint, 1);
  }
  {  // The same on J1, J2 and J3 together: a contact.
    ResidualRig<S> rig;
    rig.m.armed = true;
    rig.step(Vec6<double>::Zero(), all);
    Vec6<double> ext = Vec6<double>::Zero();
    for (int i = 0; i < 3; ++i) ext(i) = (i == 1 ? -3 : 3) * static_cast<double>(rig.m.threshold(i));
    std::uint32_t kind = 0;
    EXPECT_GT(ticks_to_fault(rig, ext, all, kind), 0);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultCollision));
  }
  {  // J2's encoder counts every tick, then stops while its joint is pushed on: a stuck encoder.
    ResidualRig<S> rig;
    rig.m.armed = true;
    for (int n = 0; n < 20; ++n) rig.step(Vec6<double>::Zero(), all);
    bool j2_silent[kDof] = {true, true, true, true, true, true};
    j2_silent[1] = false;
    Vec6<double> ext = Vec6<double>::Zero();
    ext(1) = 3 * static_cast<double>(rig.m.threshold(1));
    std::uint32_t kind = 0;
    EXPECT_GT(ticks_to_fault(rig, ext, j2_silent, kind), params::kStuckIntervals);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultEncoderStuck));
  }
  {  // Not armed: the detection is recorded, never returned.
    ResidualRig<S> rig;
    rig.m.armed = false;
    rig.step(Vec6<double>::Zero(), all);
    Vec6<double> ext = Vec6<double>::Zero();
    ext(1) = 3 * static_cast<double>(rig.m.threshold(1));
    std::uint32_t kind = 0;
    EXPECT_EQ(ticks_to_fault(rig, ext, all, kind), -1);
    EXPECT_EQ(rig.m.detected, static_cast<std::uint32_t>(kFaultDriveFault));
    EXPECT_EQ(rig.m.joint, 1);
  }
}

// Below its threshold nothing is reported, however long it lasts.
TYPED_TEST(Monitors, ResidualBelowItsThresholdNeverFaults) {
  using S = TypeParam;
  ResidualRig<S> rig;
  rig.m.armed = true;
  // These torques hold the still joints beyond their static friction, which the travel check
  // rightly calls a fault (TravelCheck* below): the residual's channels alone here.
  rig.m.travel_limit.setZero();
  const bool still[kDof] = {};
  rig.step(Vec6<double>::Zero(), still);
  Vec6<double> ext;
  for (int i = 0; i < kDof; ++i) ext(i) = (i % 2 ? -0.8 : 0.8) * static_cast<double>(rig.m.threshold(i));
  for (int n = 0; n < 1000; ++n) ASSERT_EQ(rig.step(ext, still, false), 0u) << n;
  EXPECT_EQ(rig.m.detected, 0u);
  // Close to 0.8: the thresholds grew a little with the torque commanded (the amplifiers' share).
  for (int i = 0; i < kDof; ++i) EXPECT_GT(rig.m.peak_ratio(i), lit<S>(0.6)) << i;
}

// The wrist's velocity noise (ResidualMonitor::wrist_noise; docs/safety.md): the observer's estimate
// carries the encoders' quantisation e as J^-1 diag(k) J e. Against that matrix, solved by Eigen's LU at
// random poses (q5 from 0.06 rad to pi - 0.06), the monitor's noise bound covers every joint's worst
// case sum_j |(J^-1 diag(k) J)_ij| delta_j / 2; on J4 and J6, where |sin q5| < 0.3 and the mixing
// dominates, within kLoose times it (the bound takes the worst direction of the arm's rotation, which
// at some poses lies along z5, where it is not amplified).
TEST(Residual, TheWristsVelocityNoiseCoversTheObserversMixing) {
  ResidualRig<double> rig;
  const Vec6<double> k = Gains<double>::paper().k;
  Mat6<double> Dk = k.asDiagonal();
  std::mt19937 rng(7);
  Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  double widest = 0, loosest = 0;
  constexpr double kLoose = 10;  // measured 8.9: the bound takes the worst direction of J_21 e_arm
  for (int n = 0; n < 200; ++n) {
    Vec6<double> q;
    for (int i = 0; i < kDof; ++i)
      q(i) = std::uniform_real_distribution<double>(robot::kArm.q_min[i], robot::kArm.q_max[i])(rng);
    const double s5 = std::abs(std::sin(q(4)));
    if (s5 < std::sin(0.06)) continue;
    forward_kinematics(model, data, q);
    geometric_jacobian(data);
    const Mat6<double> M = data.J.partialPivLu().solve(Dk * data.J);
    rig.m.wrist_noise(data.J);
    for (int i = 0; i < kDof; ++i) {
      double exact = 0;
      for (int j = 0; j < kDof; ++j) exact += std::abs(M(i, j)) * 0.5 / counts_per_rad(j);
      EXPECT_GE(rig.m.velocity_noise(i), exact * (1 - 1e-9)) << "J" << i + 1 << " q5 " << q(4);
      if (i == 3 || i == 5) {
        if (s5 < 0.3) {
          loosest = std::max(loosest, rig.m.velocity_noise(i) / exact);
          EXPECT_LE(rig.m.velocity_noise(i), kLoose * exact) << "J" << i + 1 << " q5 " << q(4);
        }
        widest = std::max(widest, rig.m.velocity_noise(i) / rig.m.noise_base(i));
      }
    }
  }
  EXPECT_GT(widest, 10) << "some pose near the wrist singularity, where the mixing dominates";
  std::printf("wrist noise bound / exact, |sin q5| < 0.3: at most %.2f\n", loosest);
}

// The general velocity-noise bound (ResidualMonitor::mixed_noise, the one an arm without a spherical wrist
// takes; on the built arm here, with its own factor of J): at random poses clear of singularities and
// reference orientations off the pose's, it is every joint's worst case sum_j |(Ja^-1 diag(k) Ja)_ij|
// delta_j / 2, Ja the analytic Jacobian, that matrix formed by Eigen's LU.
TEST(Residual, TheMixedVelocityNoiseCoversTheObserversMixing) {
  ResidualRig<double> rig;
  const Vec6<double> k = Gains<double>::paper().k;
  const Mat6<double> Dk = k.asDiagonal();
  test::RandomStates rs;
  Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  ArmOpSpace<double> os;
  double worst = 0;
  for (int n = 0; n < 300; ++n) {
    const Vec6<double> q = rs.q_nonsingular();
    forward_kinematics(model, data, Vec6<double>(q + rs.vec(0.2)));
    const Mat3<double> R_ref = data.R[kDof];
    opspace_update(model, data, os, q, R_ref, false);
    const Mat6<double> M = os.Ja.partialPivLu().solve(Dk * os.Ja);
    rig.m.mixed_noise(os.Ja, os.Jf, 0, kDof);
    for (int i = 0; i < kDof; ++i) {
      double exact = 0;
      for (int j = 0; j < kDof; ++j) exact += std::abs(M(i, j)) * 0.5 / counts_per_rad(j);
      worst = std::max(worst, std::abs(rig.m.velocity_noise(i) / exact - 1));
    }
  }
  std::printf("mixed noise bound against the exact worst case: relative %.1e\n", worst);
  EXPECT_LE(worst, 1e-9);
}

// A contact the task reacted to (ResidualMonitor::note_contact): the push stays in r while the arm
// yields or holds against it. When the contact begins, the monitor notes it, so that the same push
// raises nothing, however long it lasts, while a change of the push by several change thresholds
// after it still does. When the contact ends, the floors drop back and a push still there is found
// again.
TYPED_TEST(Monitors, AContactsPushIsNotedAndWhatChangesAfterItJudged) {
  using S = TypeParam;
  const bool still[kDof] = {};
  ResidualRig<S> rig;
  rig.m.armed = true;
  for (int n = 0; n < 300; ++n) ASSERT_EQ(rig.step(Vec6<double>::Zero(), still, false), 0u) << n;
  // A push on J2 and J3 at twice their thresholds: a collision.
  Vec6<double> ext = Vec6<double>::Zero();
  ext(1) = 2 * static_cast<double>(rig.m.threshold(1));
  ext(2) = 2 * static_cast<double>(rig.m.threshold(2));
  std::uint32_t kind = 0;
  for (int n = 0; n < 200 && kind == 0; ++n) kind = rig.step(ext, still, false);
  ASSERT_EQ(kind, static_cast<std::uint32_t>(kFaultCollision)) << fault_name(kind);
  // The task reacts (yield, or a category-2 stop): contact. The push lasts 1 s, and is let be.
  rig.m.contact = true;
  for (int n = 0; n < 1000; ++n) ASSERT_EQ(rig.step(ext, still, false), 0u) << n;
  EXPECT_NEAR(static_cast<double>(rig.m.r(1)), ext(1), 0.02 * ext(1)) << "the push is still in r";
  EXPECT_LT(rig.m.peak_ratio(1), lit<S>(2.5));
  EXPECT_LT(rig.m.ratio_of(1), lit<S>(0.8));
  // J3's push grows by three of its change thresholds: found, within 50 ms.
  ResidualRig<S> grown = rig;
  Vec6<double> more = ext;
  more(2) += 3 * static_cast<double>(grown.m.change_threshold(2));
  const int ticks = ticks_to_fault(grown, more, still, kind);
  EXPECT_GT(ticks, 0);
  EXPECT_LE(ticks, 50);
  EXPECT_NE(kind, 0u);
  // The contact ends with the push still there: found again once the bound has decayed.
  rig.m.contact = false;
  EXPECT_GT(ticks_to_fault(rig, ext, still, kind), 0);
  EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultCollision)) << fault_name(kind);
}

// The slide test's counts (EncoderActivity::slide_counts): none where the encoder resolves the slide
// speed at kResidualSlideInterval ticks a count (the PUMA's every joint); otherwise that speed's counts over
// the window, kResidualSlideSpeed kResidualSlideInterval dt / quantum, whole (the UR5e's 3.8 urad: 13).
TEST(Residual, AFineEncoderMustMakeTheSlideSpeedsCounts) {
  const double identity[kDof][kDof] = {{1, 0, 0, 0, 0, 0}, {0, 1, 0, 0, 0, 0}, {0, 0, 1, 0, 0, 0},
                                       {0, 0, 0, 1, 0, 0}, {0, 0, 0, 0, 1, 0}, {0, 0, 0, 0, 0, 1}};
  ResidualMonitor<double> m;
  m.reset();
  Vec6<double> quantum;
  for (int i = 0; i < kDof; ++i) quantum(i) = 1 / counts_per_rad(i);
  m.set(quantum, Gains<double>::paper().k, identity);
  for (int i = 0; i < kDof; ++i) {
    const double speed = quantum(i) / (params::kResidualSlideInterval * params::kDt);  // a count per window
    EXPECT_EQ(m.activity.slide_counts[i], speed >= params::kResidualSlideSpeed
                                              ? 0u
                                              : 1u * static_cast<unsigned>(params::kResidualSlideSpeed / speed))
        << i;
  }
  const double ur5e = 2 * kPi / (16384 * 101.0);  // 3.8 urad
  m.set(Vec6<double>::Constant(ur5e), Gains<double>::paper().k, identity);
  for (int i = 0; i < kDof; ++i) EXPECT_EQ(m.activity.slide_counts[i], 13u) << i;
  // Ten times coarser: 1.3 counts a window, one whole.
  m.set(Vec6<double>::Constant(10 * ur5e), Gains<double>::paper().k, identity);
  for (int i = 0; i < kDof; ++i) EXPECT_EQ(m.activity.slide_counts[i], 1u) << i;
}

}  // namespace
