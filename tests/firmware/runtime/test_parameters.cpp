// The runtime parameters' access (osc/runtime/parameters.hpp): the defaults a new task has, checked sets,
// the observer's stability margin against the spectral radius of the discrete observer's error map, every
// gain's bounds, records, the pots switch. The table itself: test_param_table.cpp; its link:
// tests/firmware/link/test_param_frames.cpp.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <type_traits>

#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/parameters.hpp"
#include "task_util.hpp"
#include "test_util.hpp"

namespace {

using namespace osc;
using osc::test::disabled_task;

/// The spectral radius of the observer's linearised error map at a pose, from observer.hpp's
/// discretisation with the arm still (x fixed, F and the bias forces cancelling to first order):
///   e' = e - dt (y' ... ) : [e; y]' = [[I - dt K - dt^2 M, -dt I], [dt M, I]] [e; y],  M = Lambda^-1 K_i,
/// with e = x - x^ and K = diag(k). An independent statement of the stability the margin bounds.
double observer_spectral_radius(const Gains<double>& g, const Mat6<double>& lambda_inv) {
  const double dt = g.dt;
  const Mat6<double> M = lambda_inv * g.ki.asDiagonal();
  Eigen::Matrix<double, 12, 12> A;
  A.topLeftCorner<6, 6>() = Mat6<double>::Identity() - dt * Mat6<double>(g.k.asDiagonal()) - dt * dt * M;
  A.topRightCorner<6, 6>() = -dt * Mat6<double>::Identity();
  A.bottomLeftCorner<6, 6>() = dt * M;
  A.bottomRightCorner<6, 6>() = Mat6<double>::Identity();
  return Eigen::EigenSolver<Eigen::Matrix<double, 12, 12>>(A).eigenvalues().cwiseAbs().maxCoeff();
}

/// The table's defaults are what a task starts with: the gains' paper values, the configured
/// motion limits, the collision reaction and thresholds, the stream timeout.
template <class S>
void defaults_are_a_new_tasks() {
  auto t = disabled_task<S>();
  const ParamRecord now = param_capture(*t), def = param_defaults();
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e) {
      const int k = param_slot(i) + e;
      EXPECT_NEAR(now.value[k], def.value[k], 1e-5 * std::fabs(def.value[k]) + 1e-6)
          << kParams[i].name << "[" << e << "]";
    }
  EXPECT_EQ(param_default(param_index("knd"), 3), params::kKnd[3]);
  EXPECT_EQ(param_default(param_index("move_angular"), 2), params::kMoveAngular[2]);
  EXPECT_EQ(param_default(param_index("stream_timeout"), 0), kStreamTimeoutMin);
}
TEST(Parameters, DefaultsAreANewTasksDouble) { defaults_are_a_new_tasks<double>(); }

TEST(Parameters, HomeSpeedIsTheHomingMovesSpeedWithinTheMoveLimits) {
  auto t = disabled_task<double>();
  const int i = param_index("home_speed");
  ASSERT_GE(i, 0);
  EXPECT_EQ(home_limits(*t).linear.v, params::kHomeSpeed[0]);
  EXPECT_EQ(home_limits(*t).angular.v, params::kHomeSpeed[1]);
  EXPECT_EQ(home_limits(*t).linear.a, params::kMoveLinear[1]);  // accelerations and jerks: the move's
  ASSERT_EQ(param_set(*t, i, 0, 0.01), ParamStatus::kOk);
  ASSERT_EQ(param_set(*t, i, 1, 0.02), ParamStatus::kOk);
  EXPECT_EQ(home_limits(*t).linear.v, 0.01);
  EXPECT_EQ(home_limits(*t).angular.v, 0.02);
  // At most the configured move speed; a slower move limit caps it too.
  EXPECT_EQ(param_set(*t, i, 0, params::kMoveLinear[0] * 1.5), ParamStatus::kOutOfRange);
  ASSERT_EQ(param_set(*t, param_index("move_linear"), 0, 0.005), ParamStatus::kOk);
  EXPECT_EQ(home_limits(*t).linear.v, 0.005);
}
TEST(Parameters, DefaultsAreANewTasksFloat) { defaults_are_a_new_tasks<float>(); }
TEST(Parameters, DefaultsAreANewTasksFixed) { defaults_are_a_new_tasks<Fixed>(); }

/// Every element set to a value inside its range reads back, in the task's scalar.
template <class S>
void every_element_sets_and_reads_back() {
  auto t = disabled_task<S>();
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e) {
      const ParamInfo& p = kParams[i];
      const bool code = param_is_code(p);
      // A value between the default and the top of the range, that keeps the observer stable (a
      // payload's products a tenth of their bound, so that the tensor stays positive semi-definite).
      const bool product = p.runtime == RuntimeParam::kParamPayloadInertia && e >= 3;
      const double v = code ? p.hi_of(e)
                       : product
                           ? 0.1 * p.hi_of(e)
                           : param_default(i, e) * 0.75 + 0.25 * std::fmin(p.hi_of(e), 4 * param_default(i, e) + 1);
      if (std::fabs(v) >= param_scalar_max<S>()) {  // beyond a fixed-point scalar: refused, unchanged
        EXPECT_EQ(param_set(*t, i, e, v), ParamStatus::kOutOfRange) << p.name;
        EXPECT_NEAR(param_get(*t, i, e), param_default(i, e), 1e-3) << p.name;
        continue;
      }
      ASSERT_EQ(param_set(*t, i, e, v), ParamStatus::kOk) << p.name << "[" << e << "] = " << v;
      EXPECT_NEAR(param_get(*t, i, e), v, 2e-6 * std::fabs(v) + 1e-5) << p.name;
    }
  // A gain of form `every` sets every element of its vector.
  const int tau = param_index("tau_dec");
  ASSERT_EQ(param_set(*t, tau, 0, 2.5), ParamStatus::kOk);
  for (int j = 0; j < kDof; ++j) EXPECT_NEAR(static_cast<double>(t->gains.tau_dec(j)), 2.5, 1e-5);
  // The runtime ones reach what the task uses.
  ASSERT_EQ(param_set(*t, param_index("move_linear"), 1, 0.5), ParamStatus::kOk);
  EXPECT_NEAR(static_cast<double>(t->limits.linear.a), 0.5, 1e-5);
  ASSERT_EQ(param_set(*t, param_index("collision_threshold"), 4, 12.0), ParamStatus::kOk);
  EXPECT_NEAR(static_cast<double>(t->residual.collision_floor(4)), 12.0, 1e-4);
  ASSERT_EQ(param_set(*t, param_index("collision_reaction"), 0, 2.0), ParamStatus::kOk);
  EXPECT_EQ(t->collision_reaction, CollisionReaction::kYield);
  ASSERT_EQ(param_set(*t, param_index("stream_timeout"), 0, 0.05), ParamStatus::kOk);
  EXPECT_EQ(t->stream_timeout_ticks, 50u);
  ASSERT_EQ(param_set(*t, param_index("adaptation"), 0, 2.0), ParamStatus::kOk);
  EXPECT_EQ(t->gains.adaptation, AdaptationLaw::kMomentum);
  const int armed = param_index("residual_monitor");
  ASSERT_EQ(param_set(*t, armed, 0, 0.0), ParamStatus::kOk);
  EXPECT_FALSE(t->residual.armed);
  ASSERT_EQ(param_set(*t, armed, 0, 1.0), ParamStatus::kOk);
  EXPECT_TRUE(t->residual.armed);
  EXPECT_EQ(param_set(*t, armed, 0, 0.5), ParamStatus::kOutOfRange);  // a switch: 0 or 1
  EXPECT_TRUE(t->residual.armed);
  ASSERT_EQ(param_set(*t, armed, 0, 0.0), ParamStatus::kOk);
  EXPECT_FALSE(t->residual.armed);
}
TEST(Parameters, EveryElementSetsAndReadsBackDouble) { every_element_sets_and_reads_back<double>(); }
TEST(Parameters, EveryElementSetsAndReadsBackFloat) { every_element_sets_and_reads_back<float>(); }
TEST(Parameters, EveryElementSetsAndReadsBackFixed) { every_element_sets_and_reads_back<Fixed>(); }

TEST(Parameters, AFixedPointBuildRefusesWhatItsScalarWouldSaturate) {
  auto t = disabled_task<Fixed>();
  const int ki = param_index("ki");
  EXPECT_EQ(param_set(*t, ki, 0, 4096.0), ParamStatus::kOutOfRange);  // Q12.19 holds less than 4096
  EXPECT_EQ(param_set(*t, ki, 0, 4000.0), ParamStatus::kOk);
  EXPECT_EQ(param_value_status<double>(ki, 0, 1e5), ParamStatus::kOk);  // double holds it
}

TEST(Parameters, EachBadSetIsRefusedByNameAndChangesNothing) {
  auto t = disabled_task<double>();
  const ParamRecord before = param_capture(*t);
  const int knd = param_index("knd"), thr = param_index("collision_threshold"), law = param_index("adaptation");
  EXPECT_EQ(param_set(*t, kParamCount, 0, 1.0), ParamStatus::kUnknownParam);
  EXPECT_EQ(param_set(*t, -1, 0, 1.0), ParamStatus::kUnknownParam);
  EXPECT_EQ(param_set(*t, knd, 6, 1.0), ParamStatus::kBadElement);
  EXPECT_EQ(param_set(*t, param_index("k_ad"), 1, 1.0), ParamStatus::kBadElement);
  EXPECT_EQ(param_set(*t, knd, 0, std::numeric_limits<double>::quiet_NaN()), ParamStatus::kNotFinite);
  EXPECT_EQ(param_set(*t, knd, 0, std::numeric_limits<double>::infinity()), ParamStatus::kNotFinite);
  EXPECT_EQ(param_set(*t, knd, 0, 1e-4), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, knd, 0, 2e5), ParamStatus::kOutOfRange);
  // Per-element ranges: each joint's threshold up to its own full-scale torque.
  EXPECT_EQ(param_set(*t, thr, 5, robot::kDrives.torque_limit[5] * 1.001), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, thr, 0, -0.1), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, law, 0, 1.5), ParamStatus::kOutOfRange);  // a code is a whole number
  EXPECT_EQ(param_set(*t, law, 0, 3.0), ParamStatus::kOutOfRange);
  // Torque on: a gain is refused, a runtime parameter of access `always` is not.
  t->machine.state = MotionState::kHolding;
  EXPECT_EQ(param_set(*t, knd, 0, 100.0), ParamStatus::kTorqueOn);
  EXPECT_EQ(param_set(*t, law, 0, 0.0), ParamStatus::kTorqueOn);
  // The monitors are not swapped under a running arm.
  const double other = params::kResidualMonitorArmed ? 0.0 : 1.0;  // the switch away from its default
  EXPECT_EQ(param_set(*t, param_index("residual_monitor"), 0, other), ParamStatus::kTorqueOn);
  EXPECT_EQ(t->residual.armed, params::kResidualMonitorArmed);
  const ParamRecord mid = param_capture(*t);
  for (int k = 0; k < kParamSlots; ++k) EXPECT_EQ(mid.value[k], before.value[k]) << k;
  EXPECT_EQ(param_set(*t, thr, 0, 30.0), ParamStatus::kOk);
  t->machine.state = MotionState::kFault;  // in fault the torque is off
  EXPECT_EQ(param_set(*t, knd, 0, 100.0), ParamStatus::kOk);
}

// A payload set through the parameters is the model's link 6 with it (Model::of with the payload, bit for
// bit in double), reaches the dynamics, and setting it back to nothing restores link 6 bit for bit.
template <class S>
void payload_sets_link_six() {
  auto t = disabled_task<S>();
  const typename Model<S>::Link bare = t->model.link[kDof - 1];
  Payload p;
  p.mass = 1.5, p.com[0] = 0.1, p.com[2] = 0.05;
  const double in[6] = {2e-3, 3e-3, 4e-3, 5e-4, 0, -2e-4};
  std::copy(in, in + 6, p.inertia);
  ASSERT_EQ(param_set(*t, param_index("payload_mass"), 0, p.mass), ParamStatus::kOk);
  for (int e = 0; e < 3; ++e) ASSERT_EQ(param_set(*t, param_index("payload_com"), e, p.com[e]), ParamStatus::kOk);
  for (int e = 0; e < 6; ++e) ASSERT_EQ(param_set(*t, param_index("payload_inertia"), e, in[e]), ParamStatus::kOk);
  const Model<S> want = Model<S>::of(robot::kArm, 0.0, p);
  const auto& got = t->model.link[kDof - 1];
  const auto& ref = want.link[kDof - 1];
  const double tol = std::is_same_v<S, double> ? 0 : 1e-5;  // float and Q round the combination's inputs
  EXPECT_NEAR(static_cast<double>(got.mass), static_cast<double>(ref.mass), tol);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(static_cast<double>(got.com(k)), static_cast<double>(ref.com(k)), tol);
    EXPECT_NEAR(static_cast<double>(got.inertia(k)), static_cast<double>(ref.inertia(k)), tol);
    EXPECT_NEAR(static_cast<double>(got.products(k)), static_cast<double>(ref.products(k)), tol);
  }
  EXPECT_FALSE(got.diagonal);
  EXPECT_NEAR(static_cast<double>(got.mass), robot::kArm.links[kDof - 1].mass + 1.5, 1e-5);
  // The gravity torque carries the payload: J2 holds its weight.
  Data<S> d0, d1;
  const Vec6<S> q = joint_vector<S>(robot::kQStart);
  const Model<S> bare_model = Model<S>::of(robot::kArm);
  forward_kinematics(bare_model, d0, q);
  forward_kinematics(t->model, d1, q);
  EXPECT_GT(std::fabs(static_cast<double>(gravity_torques(t->model, d1)(1) - gravity_torques(bare_model, d0)(1))), 1.0);
  // Nothing again: link 6 as it was, bit for bit.
  ASSERT_EQ(param_set(*t, param_index("payload_mass"), 0, 0.0), ParamStatus::kOk);
  for (int e = 0; e < 6; ++e) ASSERT_EQ(param_set(*t, param_index("payload_inertia"), 5 - e, 0.0), ParamStatus::kOk);
  const auto& back = t->model.link[kDof - 1];
  EXPECT_TRUE(back.mass == bare.mass && back.com == bare.com && back.inertia == bare.inertia &&
              back.products == bare.products && back.diagonal == bare.diagonal);
}
TEST(Parameters, APayloadIsTheModelsLinkSixDouble) { payload_sets_link_six<double>(); }
TEST(Parameters, APayloadIsTheModelsLinkSixFloat) { payload_sets_link_six<float>(); }
TEST(Parameters, APayloadIsTheModelsLinkSixFixed) { payload_sets_link_six<Fixed>(); }

// Issue 57's bad payloads, each refused by name with nothing changed: a mass below 0 or beyond the arm's
// rating, a centre of mass outside the stated envelope, NaN, an inertia no body has, and any of them
// under torque.
TEST(Parameters, ABadPayloadIsRefusedByName) {
  auto t = disabled_task<double>();
  const int mass = param_index("payload_mass"), com = param_index("payload_com"), in = param_index("payload_inertia");
  const double rating = robot::kPayloadRating.mass, reach = robot::kPayloadRating.com_reach;
  EXPECT_EQ(param_set(*t, mass, 0, -0.1), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, mass, 0, rating * 1.01), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, mass, 0, std::numeric_limits<double>::quiet_NaN()), ParamStatus::kNotFinite);
  EXPECT_EQ(param_set(*t, com, 2, reach * 1.01), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, com, 0, -reach * 1.01), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, com, 3, 0.0), ParamStatus::kBadElement);
  EXPECT_EQ(param_set(*t, in, 0, -1e-4), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, in, 3, 1e-3), ParamStatus::kNotPhysical);  // a product before its moments
  ASSERT_EQ(param_set(*t, in, 0, 2e-3), ParamStatus::kOk);
  ASSERT_EQ(param_set(*t, in, 1, 2e-3), ParamStatus::kOk);
  EXPECT_EQ(param_set(*t, in, 3, 2.5e-3), ParamStatus::kNotPhysical);  // |Ixy| > sqrt(Ixx Iyy)
  EXPECT_EQ(param_set(*t, in, 3, 1.5e-3), ParamStatus::kOk);
  EXPECT_EQ(param_set(*t, mass, 0, rating), ParamStatus::kOk);  // the rating itself
  EXPECT_DOUBLE_EQ(t->payload.mass, rating);
  t->machine.state = MotionState::kHolding;
  EXPECT_EQ(param_set(*t, mass, 0, 1.0), ParamStatus::kTorqueOn);
  EXPECT_DOUBLE_EQ(t->payload.mass, rating);
  // A record whose inertia no body has is refused whole.
  t->machine.state = MotionState::kDisabled;
  ParamRecord r = param_capture(*t);
  r.value[param_slot(in) + 4] = 0.004f;  // within its range, but Ixx Izz < Ixz^2
  EXPECT_EQ(param_apply(*t, r), ParamStatus::kBadRecord);
  EXPECT_DOUBLE_EQ(t->payload.inertia[4], 0.0);
}

// The payload allowance (a payload not yet identified): set, each joint's floor of the residual monitor's model
// error takes the allowance's torque (the mass's weight at flange_lever(), by hand), in every scalar; refused by
// name below 0, beyond the rating, NaN, under torque; not saved: a record holds its default, 0, and a load or a
// power-on starts from it.
template <class S>
void payload_allowance_raises_the_floor() {
  auto t = disabled_task<S>();
  const int a = param_index("payload_allowance");
  const Vec6<S> floor = t->residual.error_floor;
  ASSERT_EQ(param_set(*t, a, 0, 2.0), ParamStatus::kOk);
  EXPECT_DOUBLE_EQ(param_get(*t, a, 0), 2.0);
  for (int i = 0; i < kDof; ++i) {
    const double expected = 2.0 * robot::kArm.gravity * flange_lever(i);
    EXPECT_NEAR(static_cast<double>(t->residual.allowance(i)), expected, 1e-4 * expected) << i;
    EXPECT_NEAR(static_cast<double>(t->residual.error_floor(i) - floor(i)), expected, 1e-4 * expected + 1e-5) << i;
  }
  ParamRecord r = param_capture(*t);
  EXPECT_EQ(r.value[param_slot(a)], 0.0f);
  ASSERT_EQ(param_apply(*t, r), ParamStatus::kOk);
  EXPECT_EQ(param_get(*t, a, 0), 0.0);
  EXPECT_EQ(t->residual.allowance(1), S(0));
}
TEST(Parameters, ThePayloadAllowanceRaisesTheResidualFloorDouble) { payload_allowance_raises_the_floor<double>(); }
TEST(Parameters, ThePayloadAllowanceRaisesTheResidualFloorFloat) { payload_allowance_raises_the_floor<float>(); }
TEST(Parameters, ThePayloadAllowanceRaisesTheResidualFloorFixed) { payload_allowance_raises_the_floor<Fixed>(); }

TEST(Parameters, ABadPayloadAllowanceIsRefusedByName) {
  auto t = disabled_task<double>();
  const int a = param_index("payload_allowance");
  EXPECT_EQ(param_set(*t, a, 0, -0.1), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, a, 0, robot::kPayloadRating.mass * 1.01), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, a, 0, std::numeric_limits<double>::quiet_NaN()), ParamStatus::kNotFinite);
  t->machine.state = MotionState::kHolding;
  EXPECT_EQ(param_set(*t, a, 0, 1.0), ParamStatus::kTorqueOn);
  EXPECT_EQ(param_get(*t, a, 0), 0.0);
  EXPECT_EQ(kParams[a].persists, false);
}

// The torque-on states are one list (motion_powered): a torque_off parameter is written in exactly the
// states of the machine's list the tick does not power (disabled, fault), checked here against the
// list written out, and against the state machine's own torque; an unreadable state code is refused.
TEST(Parameters, TorqueOffIsEveryStateTheMachineDoesNotPower) {
  auto t = disabled_task<double>();
  const int knd = param_index("knd");
  const double value = Gains<double>::paper().knd(0);
  for (int code = 0; code <= MotionNames<MotionState>::kCount; ++code) {
    const auto s = static_cast<MotionState>(code);
    const bool on = s == MotionState::kHolding || s == MotionState::kMoving || s == MotionState::kHoming ||
                    s == MotionState::kStopping || s == MotionState::kYielding;
    const bool known = code < MotionNames<MotionState>::kCount;
    EXPECT_EQ(motion_powered(s), on) << code;
    t->machine.state = s;
    EXPECT_EQ(param_torque_off(*t), known && !on) << code;
    EXPECT_EQ(param_set(*t, knd, 0, value), known && !on ? ParamStatus::kOk : ParamStatus::kTorqueOn) << code;
    if (known && s != MotionState::kFault) {
      MotionInput in{};
      in.command = MotionCommand::kNone;
      EXPECT_EQ(motion_next({s, false}, in).torque, on) << code;
    }
  }
}

/// The margin against the discrete observer's error map: wherever the margin says stable (above 1),
/// the map's spectral radius is below 1 (the margin bounds b from above), and gains whose map is
/// unstable are refused. Swept over k and k_i of one axis group at a time, at the start pose.
TEST(Parameters, ObserverMarginIsConservativeAgainstTheErrorMapsSpectralRadius) {
  auto t = disabled_task<double>();
  const Mat6<double> li = task_lambda_inverse(*t);
  // The paper's gains: b bounded near observer.hpp's 2.7e4, a wide margin, (37) met.
  const GainMargins paper = param_margins(*t);
  EXPECT_GT(paper.b_max, 2.7e4);
  EXPECT_LT(paper.b_max, 4e4);
  EXPECT_GT(paper.observer, 50);
  EXPECT_GT(paper.condition37, 1);
  EXPECT_LT(observer_spectral_radius(Gains<double>::paper(), li), 1);
  int stable = 0, refused = 0, unstable_refused = 0;
  for (const double k : {10.0, 108.0, 500.0, 1000.0, 1500.0, 1900.0, 1990.0, 2100.0})
    for (const double ki : {1e2, 2e3, 1e4, 1e5, 3e5, 1e6}) {
      Gains<double> g = Gains<double>::paper();
      g.k.setConstant(k);
      g.ki.setConstant(ki);
      const GainMargins m = gain_margins(g, li);
      const double rho = observer_spectral_radius(g, li);
      if (m.observer > 1) {
        ++stable;
        EXPECT_LT(rho, 1) << "k " << k << " ki " << ki << ": margin " << m.observer;
      } else {
        ++refused;
      }
      if (rho > 1) {
        ++unstable_refused;
        EXPECT_LE(m.observer, 1) << "k " << k << " ki " << ki;
      }
    }
  EXPECT_GT(stable, 10);
  EXPECT_GT(unstable_refused, 3);  // the sweep reaches unstable gains, and each is refused
  // Through param_set: a k beyond 2 / dt, and a k_i that makes b dt^2 exceed the room, are outside
  // their ranges now (the ranges keep the sampled loop stable, which asks more than the observer).
  EXPECT_EQ(param_set(*t, param_index("k"), 0, 2100.0), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, param_index("ki"), 3, 1e6), ParamStatus::kOutOfRange);
  // A record is judged by the same margin: k of 2100 in a stored record would be refused by it too.
  Gains<double> g = Gains<double>::paper();
  g.k(0) = 2100;
  EXPECT_EQ(gain_status(gain_margins(g, li)), ParamStatus::kUnstableObserver);
}

/// Issue 53, defect 4: `param set ks 100000` was accepted and the next enable latched non_finite.
/// Each gain's range now stops where the PUMA's loop would be lost: every element's bounds are accepted at
/// the start pose, with the other gains at the paper's values, and beyond them is out_of_range. Two
/// gains within their ranges that together would lose the loop are refused unstable_loop, by name,
/// and change nothing. The ranges are every arm's (params.hpp): on another arm a bound may lose its loop,
/// and is then refused by name (unstable_loop or unstable_observer) with its margin below 1, never taken.
TEST(Parameters, EveryGainBoundRunsAndBeyondItIsRefused) {
  EXPECT_EQ((param_value_status<double>(param_index("ks"), 0, 1e5)), ParamStatus::kOutOfRange);
  int refused = 0;
  for (int i = 0; i < kParamCount; ++i) {
    const ParamInfo& p = kParams[i];
    if (p.gain < 0) continue;
    for (int e = 0; e < p.count; ++e)
      for (const bool top : {false, true}) {
        auto t = disabled_task<double>();
        const double v = top ? p.hi_of(e) : p.lo_of(e);
        GainMargins m;
        const ParamStatus s = param_set(*t, i, e, v, &m);
        if (!test::kPumaBuild && (s == ParamStatus::kUnstableLoop || s == ParamStatus::kUnstableObserver)) {
          EXPECT_LT(s == ParamStatus::kUnstableLoop ? m.loop : m.observer, 1) << p.name << "[" << e << "] = " << v;
          std::printf("%s[%d] = %g: refused %s on this arm\n", p.name, e, v, param_status_name(s));
          ++refused;
          continue;
        }
        EXPECT_EQ(s, ParamStatus::kOk) << p.name << "[" << e << "] = " << v;
        EXPECT_GE(m.loop, 1) << p.name << "[" << e << "] = " << v;
        EXPECT_GT(m.observer, 1) << p.name << "[" << e << "] = " << v;
        if (top || v > 0) {
          const double beyond = top ? v * 1.01 : v * 0.99;
          EXPECT_EQ(param_set(*t, i, e, beyond), ParamStatus::kOutOfRange) << p.name << "[" << e << "]";
        }
      }
  }
  std::printf("%d gain bounds refused by name on this arm\n", refused);
  OSC_PUMA_TUNED("the pairs of gains below lose the PUMA's loop together");
  // A rotation's k at its bottom (a lightly damped observer) and its k_i at its top.
  auto t = disabled_task<double>();
  const int k = param_index("k"), ki = param_index("ki");
  ASSERT_EQ(param_set(*t, k, 3, 25.0), ParamStatus::kOk);
  const ParamRecord before = param_capture(*t);
  GainMargins m;
  EXPECT_EQ(param_set(*t, ki, 3, 3500.0, &m), ParamStatus::kUnstableLoop);
  EXPECT_LT(m.loop, 1);
  EXPECT_GT(m.observer, 1);  // the observer alone would have taken it: the old check
  const ParamRecord after = param_capture(*t);
  for (int n = 0; n < kParamSlots; ++n) EXPECT_EQ(after.value[n], before.value[n]) << n;
  // The whole rotation's k_nd and k_s at their tops lose the loop too.
  auto u = disabled_task<double>();
  for (int e = 3; e < 6; ++e) ASSERT_EQ(param_set(*u, param_index("knd"), e, 100.0), ParamStatus::kOk);
  for (int e = 3; e < 5; ++e) ASSERT_EQ(param_set(*u, param_index("ks"), e, 100.0), ParamStatus::kOk);
  EXPECT_EQ(param_set(*u, param_index("ks"), 5, 100.0), ParamStatus::kUnstableLoop);
}

// Issue 57: each drive's armature correction is the model's armature, the described plus it: against
// the model of the arm described with 1.5 times its motors' inertia (Model::of), in A(q) too; back to
// the described bit for bit; and a correction that would lose the sampled loop is refused by name.
template <class S>
void armature_correction_is_the_models() {
  auto t = disabled_task<S>();
  const int a = param_index("armature_correction");
  ArmDescription heavier = robot::kArm;
  for (LinkParams& l : heavier.links) l.motor_inertia *= 1.5;
  const Model<S> want = Model<S>::of(heavier), described = Model<S>::of(robot::kArm);
  for (int e = 0; e < kDof; ++e) {
    const LinkParams& l = robot::kArm.links[e];
    ASSERT_EQ(param_set(*t, a, e, 0.5 * l.gear_ratio * l.gear_ratio * l.motor_inertia), ParamStatus::kOk) << e;
  }
  const double tol = std::is_same_v<S, double> ? 1e-12 : 1e-5;
  Data<S> got, ref;
  const Vec6<S> q = joint_vector<S>(robot::kQStart);
  forward_kinematics(t->model, got, q);
  forward_kinematics(want, ref, q);
  joint_inertia(t->model, got);
  joint_inertia(want, ref);
  for (int e = 0; e < kDof; ++e) {
    EXPECT_NEAR(static_cast<double>(t->model.armature(e)), static_cast<double>(want.armature(e)), tol) << e;
    EXPECT_NEAR(static_cast<double>(got.A(e, e)), static_cast<double>(ref.A(e, e)), 4 * tol) << e;
    EXPECT_NEAR(param_get(*t, a, e), static_cast<double>(want.armature(e) - described.armature(e)), tol) << e;
  }
  for (int e = 0; e < kDof; ++e) ASSERT_EQ(param_set(*t, a, e, 0.0), ParamStatus::kOk);
  for (int e = 0; e < kDof; ++e) EXPECT_TRUE(t->model.armature(e) == described.armature(e)) << e;
}
TEST(Parameters, TheArmatureCorrectionIsTheModelsDouble) { armature_correction_is_the_models<double>(); }
TEST(Parameters, TheArmatureCorrectionIsTheModelsFloat) { armature_correction_is_the_models<float>(); }
TEST(Parameters, TheArmatureCorrectionIsTheModelsFixed) { armature_correction_is_the_models<Fixed>(); }

// A lighter armature is a larger inverse mass: with a wrist's k_i just inside the loop's bound, the wrist drive's
// armature at the bottom of its range (20 % lighter) would lose the loop, and is refused unstable_loop (a set and a
// record alike); bad values are refused by name; nothing changes.
TEST(Parameters, AnArmatureThatLosesTheLoopIsRefused) {
  auto t = disabled_task<double>();
  const int a = param_index("armature_correction"), k = param_index("k"), ki = param_index("ki");
  ASSERT_EQ(param_set(*t, k, 3, 25.0), ParamStatus::kOk);
  double lo = params::kKi[3], hi = kParams[ki].hi_of(3);  // the bound: stable at lo
  ASSERT_GE(param_margins(*t).loop, 1);
  for (int n = 0; n < 40; ++n) {
    const double mid = 0.5 * (lo + hi);
    (param_margins(*t, ki, 3, mid).loop >= 1 && param_margins(*t, ki, 3, mid).observer > 1 ? lo : hi) = mid;
  }
  if (hi >= kParams[ki].hi_of(3)) GTEST_SKIP() << "k_i within its range never loses this arm's loop";
  ASSERT_EQ(param_set(*t, ki, 3, 0.97 * lo), ParamStatus::kOk);
  const ParamRecord before = param_capture(*t);
  const double light = kParams[a].lo_of(3);
  EXPECT_NEAR(light, -0.2 * static_cast<double>(t->model.armature(3)), 1e-12);
  GainMargins m;
  EXPECT_EQ(param_set(*t, a, 3, light, &m), ParamStatus::kUnstableLoop);
  EXPECT_LT(m.loop, 1);
  EXPECT_EQ(param_set(*t, a, 3, light * 1.01), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, a, 3, std::numeric_limits<double>::quiet_NaN()), ParamStatus::kNotFinite);
  EXPECT_EQ(param_set(*t, a, 6, 0.0), ParamStatus::kBadElement);
  ParamRecord r = before;
  r.value[param_slot(a) + 3] = static_cast<float>(0.999 * light);  // within the range in f32
  EXPECT_EQ(param_apply(*t, r), ParamStatus::kUnstableLoop);
  const ParamRecord after = param_capture(*t);
  for (int n = 0; n < kParamSlots; ++n) EXPECT_EQ(after.value[n], before.value[n]) << n;
  // A heavier one is taken (smaller inverse masses), and refused under torque.
  EXPECT_EQ(param_set(*t, a, 3, -light), ParamStatus::kOk);
  t->machine.state = MotionState::kHolding;
  EXPECT_EQ(param_set(*t, a, 3, 0.0), ParamStatus::kTorqueOn);
}

// Issue 57: what the friction law has learnt is a parameter. friction_vis, _cou and _sti read theta^ as the law has
// it now (so that param save keeps it), and a set (an identify run's, a stored record's at power-on) is where the
// law goes on from: the controller's friction estimate at the next step is the set coefficients' (model (2)).
TEST(Parameters, TheFrictionEstimateIsAParameter) {
  auto t = disabled_task<double>();
  const int vis = param_index("friction_vis"), cou = param_index("friction_cou"), sti = param_index("friction_sti");
  ASSERT_GE(vis, 0);
  EXPECT_EQ(cou, vis + 1);
  EXPECT_EQ(sti, vis + 2);
  // Read: theta^ as the law left it.
  for (int k = 0; k < 3 * kDof; ++k) t->state.adapt.theta_hat(k) = 0.1 * (k + 1);
  for (int k = 0; k < 3 * kDof; ++k) EXPECT_DOUBLE_EQ(param_get(*t, vis + k / kDof, k % kDof), 0.1 * (k + 1)) << k;
  // Set: the preset's coefficients, each in its place.
  const FrictionCoefficients& f = *robot::kFrictionPresets[0];
  for (int e = 0; e < kDof; ++e) {
    ASSERT_EQ(param_set(*t, vis, e, f.vis[e]), ParamStatus::kOk);
    ASSERT_EQ(param_set(*t, cou, e, f.cou[e]), ParamStatus::kOk);
    ASSERT_EQ(param_set(*t, sti, e, f.sti[e]), ParamStatus::kOk);
  }
  const Vec6<double> qd(0.3, -0.2, 0.1, -0.5, 0.4, -0.6);
  const Vec6<double> tau = friction_estimate(t->gains, t->state.adapt.theta_hat, qd);
  for (int i = 0; i < kDof; ++i) {
    const double s = qd(i) > 0 ? 1 : -1;
    const double want = f.vis[i] * qd(i) + s * (f.cou[i] + f.sti[i] * std::exp(-t->gains.tau_dec(i) * qd(i) * qd(i)));
    EXPECT_NEAR(tau(i), want, 1e-12) << i;
  }
  // Within [0, theta_max], with the torque off.
  EXPECT_EQ(param_set(*t, vis, 0, -0.01), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, cou, 1, params::kThetaMax[kDof + 1] * 1.01), ParamStatus::kOutOfRange);
  EXPECT_EQ(param_set(*t, sti, 2, std::numeric_limits<double>::infinity()), ParamStatus::kNotFinite);
  // A stored record (a power-on's) gives theta^ whole.
  ParamRecord r = param_capture(*t);
  auto u = disabled_task<double>();
  EXPECT_EQ(u->state.adapt.theta_hat, Vec18<double>::Zero());  // a cold start
  ASSERT_EQ(param_apply(*u, r), ParamStatus::kOk);
  EXPECT_LT((u->state.adapt.theta_hat - t->state.adapt.theta_hat).cwiseAbs().maxCoeff(), 1e-6);  // f32 records
  t->machine.state = MotionState::kMoving;
  EXPECT_EQ(param_set(*t, vis, 0, 1.0), ParamStatus::kTorqueOn);
  EXPECT_DOUBLE_EQ(t->state.adapt.theta_hat(0), f.vis[0]);
}

TEST(Parameters, Condition37OnlyWarns) {
  auto t = disabled_task<double>();
  GainMargins m;
  // k_s k_nd / 2 <= 1: (37) cannot hold; set anyway, with the margin telling it.
  ASSERT_EQ(param_set(*t, param_index("ks"), 3, 0.01, &m), ParamStatus::kOk);
  EXPECT_LE(m.condition37, 1);
  EXPECT_GT(m.observer, 1);
  EXPECT_GE(m.loop, 1);
  EXPECT_NEAR(m.condition37, 0.01 * 35 / 2, 1e-12);
}

TEST(Parameters, RecordsApplyWholeOrNotAtAll) {
  auto t = disabled_task<float>();
  ParamRecord r = param_defaults();
  r.value[param_slot(param_index("ks")) + 1] = 50;
  r.value[param_slot(param_index("stream_timeout"))] = 0.04f;
  ASSERT_EQ(param_apply(*t, r), ParamStatus::kOk);
  EXPECT_FLOAT_EQ(t->gains.ks(1), 50);
  EXPECT_EQ(t->stream_timeout_ticks, 40u);
  ParamRecord bad = param_defaults();
  bad.value[param_slot(param_index("collision_threshold")) + 2] = 1e6;  // beyond J3's full scale
  EXPECT_EQ(param_apply(*t, bad), ParamStatus::kBadRecord);
  EXPECT_FLOAT_EQ(t->gains.ks(1), 50);  // unchanged
  ParamRecord unstable = param_defaults();
  unstable.value[param_slot(param_index("k")) + 3] = 25;  // each within its range, together not
  unstable.value[param_slot(param_index("ki")) + 3] = 3500;
  EXPECT_EQ(param_apply(*t, unstable), ParamStatus::kUnstableLoop);
  unstable.value[param_slot(param_index("k"))] = 2500;  // beyond its range
  EXPECT_EQ(param_apply(*t, unstable), ParamStatus::kBadRecord);
  EXPECT_FLOAT_EQ(t->gains.ks(1), 50);
  t->machine.state = MotionState::kMoving;
  EXPECT_EQ(param_apply(*t, param_defaults()), ParamStatus::kTorqueOn);
}

/// A HAL with potentiometers that counts its reads: the tick reads them (the position cross-check)
/// only while the parameter pots is 1.
struct PotsHal {
  int pot_reads = 0;
  bool read_encoders(std::int32_t c[kDof]) {
    for (int i = 0; i < kDof; ++i) c[i] = 0;
    return true;
  }
  void write_dacs(const std::int32_t*) {}
  std::uint32_t cycles() { return 0; }
  std::uint32_t io_faults() { return 0; }
  void fault_output(bool) {}
  bool read_pots(std::uint16_t c[kDof]) {
    ++pot_reads;
    for (int i = 0; i < kDof; ++i) c[i] = 2000;
    return true;
  }
  bool take_index(int, std::int32_t&) { return false; }
};
static_assert(hal::ControlHal<PotsHal> && hal::PositionHal<PotsHal>);

TEST(Parameters, PotsZeroTurnsThePositionCrossCheckOff) {
  OSC_PUMA_ONLY();
  auto t = disabled_task<double>();
  PotsHal hal;
  control_tick(*t, hal);
  EXPECT_EQ(hal.pot_reads, 1);
  ASSERT_EQ(param_set(*t, param_index("pots"), 0, 0.0), ParamStatus::kOk);
  EXPECT_FALSE(t->pots);
  control_tick(*t, hal);
  EXPECT_EQ(hal.pot_reads, 1);
  EXPECT_EQ(param_set(*t, param_index("pots"), 0, 0.5), ParamStatus::kOutOfRange);
  ASSERT_EQ(param_set(*t, param_index("pots"), 0, 1.0), ParamStatus::kOk);
  control_tick(*t, hal);
  EXPECT_EQ(hal.pot_reads, 2);
}

}  // namespace
