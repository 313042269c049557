// Control kernels of issue 3: adaptation (67), faults, allocation-free stepping, each stage of the step
// against its equations, and the dynamics model's rate. The trajectory (68) and the observer's
// discretisation are in test_trajectory.cpp and test_observer.cpp.
#include <gtest/gtest.h>

#include <cstdio>

#include "controller_fixtures.hpp"
#include "osc/control/controller.hpp"
#include "test_util.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST(Adaptation, SampledLawMatchesEquation67) {
  // Two steps at rest-free poses: the second step's theta^ must equal
  // theta^ - K_ad W_j^T(q^dot_prev) [q - q_prev - q^dot_prev dt], computed here independently.
  const Model<double> model = Model<double>::of(robot::kArm);
  Gains<double> G = Gains<double>::paper();
  G.adaptation = AdaptationLaw::kPaper;
  auto st = std::make_unique<ControllerState<double>>();
  const Vec6<double> q0 = q_start();
  controller_init(model, *st, q0);
  const PaperMotion<double> paper{G.trajectory, st->data.o[kDof]};
  st->obs.y << 0.01, -0.02, 0.015, 0.01, -0.01, 0.02;  // a non-zero observed velocity
  control_step(model, G, FrictionMode::kAdaptive, *st, q0, paper.at_time(0.0));
  const Vec6<double> qdh = st->adapt.qd_hat_prev;
  ASSERT_GT(qdh.cwiseAbs().minCoeff(), 0.0);
  Vec6<double> q1 = q0;
  q1 << q0(0) + 2e-5, q0(1) - 1e-5, q0(2) + 3e-5, q0(3), q0(4) + 1e-5, q0(5) - 2e-5;
  control_step(model, G, FrictionMode::kAdaptive, *st, q1, paper.at_time(1e-3));
  Vec18<double> expect;
  for (int i = 0; i < kDof; ++i) {
    const double Dq = q1(i) - q0(i) - qdh(i) * 1e-3;
    const double s = qdh(i) > 0 ? 1 : -1;
    expect(i) = -500 * qdh(i) * Dq;
    expect(6 + i) = -500 * s * Dq;
    expect(12 + i) = -500 * s * std::exp(-qdh(i) * qdh(i)) * Dq;
  }
  EXPECT_LT((st->adapt.theta_hat - expect).norm(), 1e-12 * (1 + expect.norm()));
}

TEST(Adaptation, NoCompensationModeNeverAdapts) {
  const Model<double> model = Model<double>::of(robot::kArm);
  const Gains<double> G = Gains<double>::paper();
  auto st = std::make_unique<ControllerState<double>>();
  Vec6<double> q = q_start();
  controller_init(model, *st, q);
  const PaperMotion<double> paper{G.trajectory, st->data.o[kDof]};
  for (int k = 0; k < 50; ++k) {
    q(0) += 1e-5;
    const StepOutput<double> out = control_step(model, G, FrictionMode::kNone, *st, q, paper.at_time(k * 1e-3));
    ASSERT_EQ(out.status, kFaultNone);
    EXPECT_EQ(out.tau_f_hat.norm(), 0.0);
  }
  EXPECT_EQ(st->adapt.theta_hat.norm(), 0.0);
}

/// A controller in double just initialised at the start pose, with the paper's motion about it.
struct ControlStep : ::testing::Test {
  const Model<double> model = Model<double>::of(robot::kArm);
  const Gains<double> G = Gains<double>::paper();
  std::unique_ptr<ControllerState<double>> st = std::make_unique<ControllerState<double>>();
  PaperMotion<double> paper;
  void SetUp() override {
    controller_init(model, *st, q_start());
    paper = {G.trajectory, st->data.o[kDof], 0};
  }
};

TEST_F(ControlStep, FaultsCommandZeroTorque) {
  Vec6<double> q = q_start();
  q(3) = std::numeric_limits<double>::quiet_NaN();
  StepOutput<double> out = control_step(model, G, FrictionMode::kAdaptive, *st, q, paper.at_time(0.0));
  EXPECT_EQ(out.status, kFaultNonFinite);
  EXPECT_EQ(out.tau.norm(), 0.0);
  out = control_step(model, G, FrictionMode::kAdaptive, *st, q_start(),
                     paper.at_time(std::numeric_limits<double>::infinity()));
  EXPECT_EQ(out.status, kFaultNonFinite);
  EXPECT_EQ(out.tau.norm(), 0.0);
  // Wrist singularity (q5 = 0).
  q = q_start();
  q(4) = 0.0;
  out = control_step(model, G, FrictionMode::kAdaptive, *st, q, paper.at_time(0.0));
  EXPECT_EQ(out.status, kFaultSingular);
  EXPECT_EQ(out.tau.norm(), 0.0);
  // A healthy step afterwards works and produces finite torques.
  out = control_step(model, G, FrictionMode::kAdaptive, *st, q_start(), paper.at_time(0.0));
  EXPECT_EQ(out.status, kFaultNone);
  EXPECT_TRUE(math::all_finite(out.tau));
}

// A non-finite friction estimate, any of its 18 coefficients, NaN or infinite, stops the step with non_finite
// and zero torque: it reaches tau through tau_f^ = W theta^ even where its regressor column is 0 (at rest, the
// first step: 0 times NaN or infinity is NaN), so the step checks tau, not theta^ itself.
TEST_F(ControlStep, NonFiniteFrictionEstimateStopsTheStep) {
  for (const double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()})
    for (int k = 0; k < 3 * kDof; ++k) {
      auto s = std::make_unique<ControllerState<double>>();
      controller_init(model, *s, q_start());
      s->adapt.theta_hat(k) = bad;
      const StepOutput<double> out = control_step(model, G, FrictionMode::kAdaptive, *s, q_start(), paper.at_time(0.0));
      EXPECT_EQ(out.status, kFaultNonFinite) << k << " " << bad;
      EXPECT_EQ(out.tau.norm(), 0.0) << k;
    }
}

TEST_F(ControlStep, AtRestAtTheStartItHoldsGravity) {
  // x = x_d, observer at rest: F = p(x), so Gamma = J^T p = g(q).
  const StepOutput<double> out = control_step(model, G, FrictionMode::kAdaptive, *st, q_start(), paper.at_time(0.0));
  ASSERT_EQ(out.status, kFaultNone);
  Data<double> data;
  forward_kinematics(model, data, q_start());
  EXPECT_LT((out.tau - gravity_torques(model, data)).norm(), 1e-9);
}

// control_step tracks the desired state it is given, whatever its source: the tracking error is
// d.x - x, and a non-finite d is the fault non_finite with zero torque.
TEST_F(ControlStep, TracksTheDesiredStateItIsGiven) {
  Desired<double> d;
  d.x << st->data.o[kDof] + Vec3<double>(0.004, -0.002, 0.001), 0.001, -0.002, 0.003;
  d.xd << 0.01, 0.02, -0.01, 0, 0.01, 0;
  d.xdd.setZero();
  const StepOutput<double> out = control_step(model, G, FrictionMode::kAdaptive, *st, q_start(), d);
  ASSERT_EQ(out.status, kFaultNone);
  EXPECT_LT((out.e - (d.x - out.x)).norm(), 1e-15);
  EXPECT_GT(out.e.norm(), 1e-3);
  for (int part = 0; part < 3; ++part) {
    Desired<double> bad = d;
    Vec6<double>& v = part == 0 ? bad.x : part == 1 ? bad.xd : bad.xdd;
    v(part + 2) = std::numeric_limits<double>::quiet_NaN();
    const StepOutput<double> o = control_step(model, G, FrictionMode::kAdaptive, *st, q_start(), bad);
    EXPECT_EQ(o.status, kFaultNonFinite) << part;
    EXPECT_EQ(o.tau.norm(), 0.0) << part;
  }
}

// The paper's motion counts its time from the sample it started at, with the integer sample count
// (trajectory_time), so that a motion started later is the same motion shifted.
TEST(PaperMotion, StartsWhereItIsStartedAndCountsFromItsStartTick) {
  const Vec3<double> p0(0.5, -0.1, 0.2);
  const PaperMotion<double> now{kPaperTrajectory, p0, 0}, later{kPaperTrajectory, p0, 123456};
  EXPECT_LT((now.at_tick(0, 1000).x.head<3>() - p0).norm(), 1e-15);  // the envelope starts at zero
  for (std::uint64_t n : {0ull, 1ull, 2500ull, 30000ull, 1000000ull}) {
    const Desired<double> a = now.at_tick(n, 1000), b = later.at_tick(123456 + n, 1000);
    EXPECT_EQ(a.x, b.x) << n;
    EXPECT_EQ(a.xd, b.xd) << n;
    EXPECT_EQ(a.xdd, b.xdd) << n;
    EXPECT_EQ(a.x, trajectory(kPaperTrajectory, p0, trajectory_time(kPaperTrajectory, n, 1000)).x) << n;
  }
}

template <class S>
void run_steps_without_allocation() {
  const Model<S> model = Model<S>::of(robot::kArm);
  const Gains<S> G = Gains<S>::paper();
  auto st = std::make_unique<ControllerState<S>>();
  Vec6<S> q = q_start().cast<S>();
  controller_init(model, *st, q);
  const PaperMotion<S> paper{G.trajectory, st->data.o[kDof]};
  test::NoMalloc guard;
  for (int k = 0; k < 20; ++k) {
    q(1) += lit<S>(1e-5);
    const StepOutput<S> out = control_step(model, G, FrictionMode::kAdaptive, *st, q, paper.at_time(lit<S>(k * 1e-3)));
    ASSERT_EQ(out.status, kFaultNone);
  }
}

TEST(ControlStepScalars, AllocationFreeInDoubleAndFloat) {
  run_steps_without_allocation<double>();
  run_steps_without_allocation<float>();
}

TEST_F(Stages, FrictionEstimateIsEquation30) {
  Vec18<double> theta;
  for (int i = 0; i < 18; ++i) theta(i) = 0.3 + 0.1 * i;
  const Vec6<double> qd = v6(0.2, -0.1, 0.0, 0.5, -0.3, 1.0);  // includes a joint at rest
  FrictionParams<double> fp;
  fp.vis = theta.head<6>();
  fp.cou = theta.segment<6>(6);
  fp.sti = theta.tail<6>();
  fp.dec = G.tau_dec;
  EXPECT_LT((friction_estimate(G, theta, qd) - friction_torque(fp, qd)).norm(), 1e-14);
}

TEST_F(Stages, AdaptationWaitsForItsFirstSampleThenFollowsEquation67) {
  G.adaptation = AdaptationLaw::kPaper;
  AdaptationState<double> a{};
  a.theta_hat.setConstant(1.0);
  a.q_prev = q;
  a.qd_hat_prev = v6(0.1, -0.2, 0.3, 0.0, 0.5, -0.6);
  a.qd_hat_prev2 = v6(9, 9, 9, 9, 9, 9);                              // not used by (67)
  a.w_prev = friction_regressor_diagonals(a.qd_hat_prev, G.tau_dec);  // what the last sample recorded
  a.w_prev2 = friction_regressor_diagonals(a.qd_hat_prev2, G.tau_dec);
  a.samples = 0;
  const Vec6<double> q1 = q + v6(1e-4, -2e-4, 3e-4, 0, 5e-4, -6e-4);
  EXPECT_EQ(adaptation_step(G, a, q1), a.theta_hat);
  a.samples = 1;
  const Vec18<double> t = adaptation_step(G, a, q1);
  for (int i = 0; i < kDof; ++i) {
    const double Dq = q1(i) - q(i) - a.qd_hat_prev(i) * G.dt, w = a.qd_hat_prev(i);
    const double s = w > 0 ? 1 : (w < 0 ? -1 : 0);
    EXPECT_NEAR(t(i), 1 - 500 * w * Dq, 1e-12);
    EXPECT_NEAR(t(6 + i), 1 - 500 * s * Dq, 1e-12);
    EXPECT_NEAR(t(12 + i), 1 - 500 * s * std::exp(-w * w) * Dq, 1e-12);
  }
}

TEST_F(Stages, RobustLawUsesTheOlderRegressorLeaksAndProjects) {
  EXPECT_EQ(Gains<double>::paper().adaptation, AdaptationLaw::kMomentum);  // the default
  G.adaptation = AdaptationLaw::kRobust;
  AdaptationState<double> a{};
  for (int i = 0; i < 18; ++i) a.theta_hat(i) = 0.5 * params::kThetaMax[i];
  a.theta_hat(0) = params::kThetaMax[0] - 1e-9;  // pushed over its upper bound below
  a.theta_hat(7) = 1e-9;                         // pushed under 0 below
  a.q_prev = q;
  a.qd_hat_prev = v6(0.1, -0.2, 0.3, 0.0, 0.5, -0.6);
  a.qd_hat_prev2 = v6(-0.2, 0.1, 0.3, 0.05, -0.5, 0.4);
  a.w_prev = friction_regressor_diagonals(a.qd_hat_prev, G.tau_dec);  // what the last samples recorded
  a.w_prev2 = friction_regressor_diagonals(a.qd_hat_prev2, G.tau_dec);
  const Vec6<double> q1 = q + v6(1e-3, 2e-3, 3e-4, 1e-4, 5e-4, -6e-4);
  a.samples = 1;
  EXPECT_EQ(adaptation_step(G, a, q1), a.theta_hat);  // needs two samples
  a.samples = 2;
  const Vec18<double> t = adaptation_step(G, a, q1);
  const double leak = 1 - params::kAdaptationLeakage * G.dt;
  int clipped_hi = 0, clipped_lo = 0;
  for (int i = 0; i < kDof; ++i) {
    const double Dq = q1(i) - q(i) - a.qd_hat_prev(i) * G.dt, w = a.qd_hat_prev2(i);  // regressor at t - 2 dt
    const double s = w > 0 ? 1 : (w < 0 ? -1 : 0);
    const double raw[3] = {leak * a.theta_hat(i) - 500 * w * Dq, leak * a.theta_hat(6 + i) - 500 * s * Dq,
                           leak * a.theta_hat(12 + i) - 500 * s * std::exp(-w * w) * Dq};
    for (int k = 0; k < 3; ++k) {
      const int idx = 6 * k + i;
      const double want = std::min(std::max(raw[k], 0.0), params::kThetaMax[idx]);
      clipped_hi += raw[k] > params::kThetaMax[idx];
      clipped_lo += raw[k] < 0;
      EXPECT_NEAR(t(idx), want, 1e-12) << idx;
    }
  }
  EXPECT_GT(clipped_hi, 0);  // the projection was exercised both ways
  EXPECT_GT(clipped_lo, 0);
}

/// The arm's coupled drive train (the PUMA's wrist; a map with a term below the wrist on an arm without one): C built
/// here from the map's terms, dense, and the model's DriveCoupling of C^-1.
struct CoupledTrain {
  Mat6<double> C = Mat6<double>::Identity();
  DriveCoupling<double> drives;
  CoupledTrain() {
    EncoderMap map = robot::kDriveTrain.encoders;
    if (map.coupling_terms == 0) map.coupling[map.coupling_terms++] = {5, 4, -0.18};
    for (int k = 0; k < map.coupling_terms; ++k) C(map.coupling[k].row, map.coupling[k].col) += map.coupling[k].c;
    double c[kDof][kDof], inverse[kDof][kDof];
    coupling_matrices(map, c, inverse);
    drives = DriveCoupling<double>::of(inverse);
  }
  Vec6<double> motors(const Vec6<double>& qd) const { return C.triangularView<Eigen::UnitLower>().solve(qd); }
  Vec6<double> joints(const Vec6<double>& f) const { return C.transpose().triangularView<Eigen::UnitUpper>().solve(f); }
};

// On a coupled drive train (q = C e) each motor has model (2)'s friction at its own rate: the step's estimate is
// C^-T f(C^-1 q^dot) (against the friction model at C^-1 q^dot, C solved here by Eigen), and the paper's law (67)
// takes the motors' error C^-1 Dq against the motors' regressor (the joints' regressor C^-T W transposed).
TEST_F(Stages, OnACoupledDriveTrainTheFrictionIsEachMotorsAtItsRate) {
  const CoupledTrain train;
  ASSERT_TRUE(train.drives.coupled());
  const Vec6<double> qd = v6(0.2, -0.1, 0.3, 0.5, -0.3, 0.05);
  EXPECT_LT((motor_rates(train.drives, qd) - train.motors(qd)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((joint_torques_of_motors(train.drives, qd) - train.joints(qd)).cwiseAbs().maxCoeff(), 1e-15);
  // J6's motor turns the other way from its joint here (e6' = q6' - 0.013 q4' + 0.18 q5' < 0 < q6').
  const Vec6<double> e = train.motors(qd);
  EXPECT_LT(e(5) * qd(5), 0.0);

  // The step's estimate, from a controller whose observer moves at qd: the coupled model's against the same step
  // of the uncoupled one (the estimate does not feed back within a step).
  Vec18<double> theta;
  for (int i = 0; i < 18; ++i) theta(i) = 0.3 + 0.1 * i;
  Model<double> coupled = model;
  coupled.drives = train.drives;
  StepOutput<double> out[2];
  Vec6<double> qd_hat[2];
  for (int m = 0; m < 2; ++m) {
    auto st = std::make_unique<ControllerState<double>>();
    controller_init(model, *st, q);
    st->adapt.theta_hat = theta;
    opspace_update(model, st->data, st->os, q, st->R_ref);
    st->obs.y = st->os.Ja * qd;  // the observer's velocity (x~ = 0): q^dot = qd
    out[m] = control_step(m ? coupled : model, G, FrictionMode::kAdaptive, *st, q, Desired<double>{os.x, {}, {}});
    ASSERT_EQ(out[m].status, kFaultNone);
    qd_hat[m] = st->adapt.qd_hat_prev;
  }
  EXPECT_LT((qd_hat[0] - qd).cwiseAbs().maxCoeff(), 1e-9);
  FrictionParams<double> fp;
  fp.vis = theta.head<6>(), fp.cou = theta.segment<6>(6), fp.sti = theta.tail<6>(), fp.dec = G.tau_dec;
  EXPECT_LT((out[0].tau_f_hat - friction_torque(fp, qd_hat[0])).cwiseAbs().maxCoeff(), 1e-12);
  const Vec6<double> want = train.joints(friction_torque(fp, Vec6<double>(train.motors(qd_hat[1]))));
  EXPECT_LT((out[1].tau_f_hat - want).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((out[1].tau_f_hat - out[0].tau_f_hat).cwiseAbs().maxCoeff(), 0.1);  // J6's sign, J5's share

  // (67) on the motors' error.
  G.adaptation = AdaptationLaw::kPaper;
  AdaptationState<double> a{};
  a.theta_hat.setConstant(1.0);
  a.q_prev = q;
  a.qd_hat_prev = qd;
  a.w_prev = friction_regressor_diagonals(train.motors(qd), G.tau_dec);
  a.samples = 1;
  const Vec6<double> q1 = q + v6(1e-4, -2e-4, 3e-4, 2e-4, 5e-4, -6e-4);
  const Vec18<double> t = adaptation_step(G, a, q1, train.drives);
  const Vec6<double> Dq = train.motors(Vec6<double>(q1 - q - qd * G.dt)), w = train.motors(qd);
  for (int i = 0; i < kDof; ++i) {
    const double sg = w(i) > 0 ? 1 : (w(i) < 0 ? -1 : 0);
    EXPECT_NEAR(t(i), 1 - 500 * w(i) * Dq(i), 1e-12) << i;
    EXPECT_NEAR(t(6 + i), 1 - 500 * sg * Dq(i), 1e-12) << i;
    EXPECT_NEAR(t(12 + i), 1 - 500 * sg * std::exp(-w(i) * w(i)) * Dq(i), 1e-12) << i;
  }
  EXPECT_NE(t(11), adaptation_step(G, a, q1)(11));  // J6's Coulomb: not the joints' law
}

TEST_F(Stages, ForceCommandIsEquations31_36) {
  const Vec3<double> p0 = data.o[kDof] + Vec3<double>(0.01, -0.02, 0.005);
  const Desired<double> d = trajectory(kPaperTrajectory, p0, 3.3);
  ObserverOutput<double> ob;
  ob.x_tilde = v6(1e-4, -2e-4, 1e-4, 1e-4, 0, -1e-4);
  ob.xd_hat = v6(0.02, -0.01, 0.03, 0.01, -0.02, 0.01);
  ob.qd_hat = os.Jf.solve(ob.xd_hat);
  const Vec6<double> tau_f_hat = v6(1, -1, 2, 0.1, 0.2, -0.1);
  PsiTerms<double> psi;
  const ForceCommand<double> c = force_command(model, G, data, os, d, ob, tau_f_hat, psi, true);
  // Each operational force on its own, as the paper writes (35), with Lambda formed.
  const Vec6<double> e = d.x - os.x;  // (36)
  const Vec6<double> v = d.xd + G.ks.cwiseProduct(e);
  const Vec6<double> psi_v = psi_bilinear(model, data, os, ob.xd_hat, v);  // Psi(x, x^dot) v
  const Vec6<double> p = operational_gravity(os);
  const Vec6<double> f_hat = operational_friction(os, tau_f_hat);  // (31)
  const Mat6<double> Lambda = operational_inertia(data, os);
  const Vec6<double> w_e = Lambda * (d.xdd + G.ks.cwiseProduct(d.xd - ob.xd_hat)) + psi_v + p + f_hat;  // (35)
  const Vec6<double> F =
      (G.ks + G.knd).cwiseProduct(v - ob.xd_hat) + w_e - G.ki.cwiseProduct(ob.x_tilde);  // (32), (34)
  EXPECT_LT((c.e - e).norm(), 1e-15);
  EXPECT_LT((c.F - F).norm(), 1e-10 * (1 + F.norm()));
  // The bias force the observer reuses: h(x, x^dot) + p + f^.
  const Vec6<double> hpf = psi_quadratic(model, data, os, ob.xd_hat) + p + f_hat;
  const Vec6<double> bias = os.Ja.transpose().partialPivLu().solve(c.bias.tau) - Lambda * c.bias.a;
  EXPECT_LT((bias - hpf).norm(), 1e-10 * (1 + hpf.norm()));
  EXPECT_GT(c.bias.a.norm(), 0.0);  // the Jdot part is not empty at this velocity
}

}  // namespace

// ---------------------------------------------------------------- the model's rate
// ModelRate::kAlternate: the model (A, its factors, g) on the controller's even steps, Psi's velocity
// products on its odd ones, each held one step; kEveryStep: both every step.
TEST(ModelRate, TurnsAlternateFromTheFirstStepWhichComputesTheModel) {
  for (std::uint32_t n = 0; n < 6; ++n) {
    const DynamicsTurn a = dynamics_turn(ModelRate::kAlternate, n), e = dynamics_turn(ModelRate::kEveryStep, n);
    EXPECT_EQ(a.model, n % 2 == 0) << n;
    EXPECT_NE(a.model, a.velocity) << n;
    EXPECT_TRUE(e.model && e.velocity) << n;
  }
  EXPECT_EQ(Gains<double>::paper().model_rate, ModelRate::kAlternate);  // the default (kDefaultModelRate)
}

// Two controllers, one at each rate, given the same measured angles (a joint-space ramp about the start pose) and
// the paper's motion. The first step, at the pose they started at, is the same but for rounding (the observer
// starts at rest: every velocity product is 0, which the alternate controller holds). After it, each step's held terms
// are those the other computes one step earlier: A and g of the previous angles, Psi of the previous velocity.
TEST(ModelRate, AlternateHoldsEachTermOneStepAndTracksTheEveryStepController) {
  const Model<double> model = Model<double>::of(robot::kArm);
  Gains<double> Ge = Gains<double>::paper(), Ga = Ge;
  Ge.model_rate = ModelRate::kEveryStep;
  Ga.model_rate = ModelRate::kAlternate;
  auto se = std::make_unique<ControllerState<double>>(), sa = std::make_unique<ControllerState<double>>();
  Vec6<double> q = q_start();
  controller_init(model, *se, q);
  controller_init(model, *sa, q);
  const PaperMotion<double> paper{Ge.trajectory, se->data.o[kDof], 0};
  const Vec6<double> rate = (Vec6<double>() << 0.2, -0.15, 0.25, 0.4, -0.3, 0.5).finished();  // rad/s
  Mat6<double> A_prev;
  Vec6<double> g_prev;
  PsiTerms<double> psi_prev{};
  double worst = 0, scale = 0;
  for (int k = 0; k < 400; ++k) {
    if (k > 0) q += rate * 1e-3;  // the first step at the pose the controllers started at
    const Desired<double> d = paper.at_tick(static_cast<std::uint64_t>(k), 1000);
    const StepOutput<double> oe = control_step(model, Ge, FrictionMode::kAdaptive, *se, q, d);
    const StepOutput<double> oa = control_step(model, Ga, FrictionMode::kAdaptive, *sa, q, d);
    ASSERT_EQ(oe.status, kFaultNone);
    ASSERT_EQ(oa.status, kFaultNone);
    if (k == 0) {
      EXPECT_LT((oa.tau - oe.tau).norm(), 1e-12 * oe.tau.norm());
    } else if (k % 2 == 1) {  // a velocity turn: the model of the step before
      EXPECT_EQ(sa->data.A, A_prev) << k;
      EXPECT_EQ(sa->os.g, g_prev) << k;
    } else {  // a model turn: the velocity products of the step before
      EXPECT_EQ(sa->psi.c_yy, psi_prev.c_yy) << k;
      EXPECT_EQ(sa->psi.c_yz, psi_prev.c_yz) << k;
      EXPECT_EQ(sa->data.A, se->data.A) << k;  // computed now, at the same angles
    }
    A_prev = se->data.A;
    g_prev = se->os.g;
    psi_prev = sa->psi;
    worst = std::max(worst, (oa.tau - oe.tau).cwiseAbs().maxCoeff());
    scale = std::max(scale, oe.tau.cwiseAbs().maxCoeff());
  }
  // A term one period old differs by its rate times 1 ms: a few 1e-4 of the torque at these speeds.
  std::printf("alternate model rate: worst torque difference %.3g N m of %.3g N m\n", worst, scale);
  EXPECT_GT(worst, 0.0);
  EXPECT_LT(worst, 2e-3 * scale);
}
