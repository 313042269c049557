// The payload regressor (osc/kernels/payload.hpp) against Orocos KDL 1.5.1: the arm's chain from its table
// (tests/support/kdl_puma.hpp) with and without the payload as one more rigid segment at frame 6, KDL's inverse
// dynamics of each, their difference against Y pi at random states and random payloads; at rest against the
// weight through KDL's Jacobian; the parameter conversions against KDL's parallel axes and back; float and
// Q12.19 against double at the same quantised inputs.
//
// Error measure: rel = ||ours - reference|| / max(||reference||, kFloor), Euclidean, N m. kFloor = 1e-3 N m is
// below every payload torque met here (0.4-81 N m), so never active (asserted).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <random>

#include "kdl_puma.hpp"
#include "osc/kernels/dynamics.hpp"
#include "osc/kernels/payload.hpp"
#include "osc/math/fixed.hpp"
#include "test_util.hpp"

using namespace osc;
using test::from_kdl;
using test::to_kdl;

namespace {

constexpr int kStates = 1000;
constexpr double kFloor = 1e-3;
const KDL::Vector kGravityVec(0, 0, -robot::kArm.gravity);

template <class S>
const Model<S>& model() {
  static const Model<S> m = Model<S>::of(robot::kArm);
  return m;
}

/// Random payloads as the tests of issue 57 ask: mass 0.1-5 kg, COM anywhere within 0.2 m of the flange, and the
/// inertia of a solid box of sides 0.02-0.3 m turned by a random rotation (positive definite, and physical: its
/// principal moments satisfy the triangle inequality).
struct RandomPayloads {
  std::mt19937_64 rng{57};
  std::uniform_real_distribution<double> u{0.0, 1.0};

  Payload next() {
    Payload b{};
    b.mass = 0.1 + 4.9 * u(rng);
    Eigen::Vector3d c;
    do c = Eigen::Vector3d(2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1);
    while (c.norm() > 1);  // uniform in the ball of radius 0.2 m
    c *= 0.2;
    const double x = 0.02 + 0.28 * u(rng), y = 0.02 + 0.28 * u(rng), z = 0.02 + 0.28 * u(rng);
    const Eigen::Vector3d principal = b.mass / 12 * Eigen::Vector3d(y * y + z * z, x * x + z * z, x * x + y * y);
    const Eigen::Matrix3d R =
        Eigen::Quaterniond(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized().toRotationMatrix();
    const Eigen::Matrix3d I = R * principal.asDiagonal() * R.transpose();
    for (int k = 0; k < 3; ++k) b.com[k] = c(k);
    const double e[6] = {I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)};
    std::copy(e, e + 6, b.inertia);
    return b;
  }
};

KDL::RigidBodyInertia kdl_inertia(const Payload& b) {
  const double* I = b.inertia;
  return KDL::RigidBodyInertia(b.mass, KDL::Vector(b.com[0], b.com[1], b.com[2]),
                               KDL::RotationalInertia(I[0], I[1], I[2], I[3], I[4], I[5]));
}

/// The arm's chain with the payload as one more rigid segment, its frame frame 6's (identity placement).
KDL::Chain with_payload(const Payload& b) {
  KDL::Chain chain = test::puma560_chain();
  chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), KDL::Frame::Identity(), kdl_inertia(b)));
  return chain;
}

/// Y pi in scalar S at (q, qd, qdd), the kernels' workspace filled as payload_regressor asks.
template <class S>
Vec6<S> payload_torque(const Vec6<S>& q, const Vec6<S>& qd, const Vec6<S>& qdd, const PayloadParams<S>& p) {
  Data<S> data;
  test::NoMalloc guard;
  forward_kinematics(model<S>(), data, q);
  geometric_jacobian(data);
  return payload_regressor(model<S>(), data, qd, qdd) * p.vector();
}

// ---------------------------------------------------------------- against KDL

TEST(PayloadKdl, RegressorTimesParametersIsKdlsInverseDynamicsWithLessWithoutThePayload) {
  const KDL::Chain arm = test::puma560_chain();
  KDL::ChainIdSolver_RNE id_arm(arm, kGravityVec);
  const KDL::Wrenches none(arm.getNrOfSegments(), KDL::Wrench::Zero());
  test::RandomStates rs;
  RandomPayloads payloads;
  double worst = 0, smallest = 1e9, largest = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(2.0), qdd = rs.vec(5.0);
    const Payload b = payloads.next();
    const KDL::Chain chain = with_payload(b);
    KDL::ChainIdSolver_RNE id(chain, kGravityVec);
    KDL::JntArray t_with(kDof), t_without(kDof);
    ASSERT_GE(id.CartToJnt(to_kdl(q), to_kdl(qd), to_kdl(qdd),
                           KDL::Wrenches(chain.getNrOfSegments(), KDL::Wrench::Zero()), t_with),
              0);
    ASSERT_GE(id_arm.CartToJnt(to_kdl(q), to_kdl(qd), to_kdl(qdd), none, t_without), 0);
    const Vec6<double> ref = from_kdl(t_with) - from_kdl(t_without);
    const Vec6<double> ours = payload_torque<double>(q, qd, qdd, PayloadParams<double>::from(b));
    worst = std::max(worst, (ours - ref).norm() / std::max(ref.norm(), kFloor));
    smallest = std::min(smallest, ref.norm());
    largest = std::max(largest, ref.norm());
  }
  std::printf(
      "Y pi vs KDL (with - without the payload), %d states: worst relative error %.2e (||tau|| %.3f-%.1f N m)\n",
      kStates, worst, smallest, largest);
  EXPECT_LE(worst, 1e-9);
  EXPECT_GT(smallest, kFloor);  // the floor never decided
}

TEST(PayloadKdl, AtRestItIsTheWeightThroughKdlsJacobianTransposeAndTheInertiaDoesNotShow) {
  // qd = qdd = 0: the payload's weight m g_vec (g_vec = (0, 0, -g)) at its COM R c from the flange:
  // tau = -J_v^T m g_vec - J_w^T (R m c x g_vec), with KDL's frame-6 pose and geometric Jacobian.
  const KDL::Chain arm = test::puma560_chain();
  KDL::ChainFkSolverPos_recursive fk(arm);
  KDL::ChainJntToJacSolver jac(arm);
  test::RandomStates rs;
  RandomPayloads payloads;
  const Eigen::Vector3d g_vec(0, 0, -robot::kArm.gravity);
  double worst = 0;
  for (int k = 0; k < 200; ++k) {
    const Vec6<double> q = rs.q_nonsingular();
    const Payload b = payloads.next();
    KDL::Frame F;
    KDL::Jacobian J(kDof);
    ASSERT_GE(fk.JntToCart(to_kdl(q), F), 0);
    ASSERT_GE(jac.JntToJac(to_kdl(q), J), 0);
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s) R(r, s) = F.M(r, s);
    const Eigen::Vector3d mc = b.mass * R * Eigen::Vector3d(b.com[0], b.com[1], b.com[2]);
    const Vec6<double> ref =
        -J.data.topRows<3>().transpose() * (b.mass * g_vec) - J.data.bottomRows<3>().transpose() * mc.cross(g_vec);

    Data<double> data;
    forward_kinematics(model<double>(), data, q);
    geometric_jacobian(data);
    const PayloadRegressor<double> Y =
        payload_regressor(model<double>(), data, Vec6<double>::Zero(), Vec6<double>::Zero());
    EXPECT_EQ(Y.rightCols<6>(), (Eigen::Matrix<double, kDof, 6>::Zero())) << k;  // no motion, no inertia
    worst = std::max(worst, (Y * PayloadParams<double>::from(b).vector() - ref).norm() / ref.norm());
  }
  std::printf("at rest: Y pi vs the weight through KDL's J^T, worst relative error %.2e\n", worst);
  EXPECT_LE(worst, 1e-12);
}

TEST(PayloadKdl, TheFlangeMotionIsTheNewtonEulerPassAndTheRegressorIsLinearInTheState) {
  // flange_motion is rnea's forward recursion along the frame origins: rnea (against KDL in test_kdl) returns
  // the same w6, alpha6 and acc6. Y(qd, 0) + Y(0, qdd) - Y(0, 0) = Y(qd, qdd) would hide a qd-qdd cross term
  // (there is none): checked too, on the torque of a payload.
  test::RandomStates rs;
  RandomPayloads payloads;
  for (int k = 0; k < 100; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(2.0), qdd = rs.vec(5.0);
    Data<double> data;
    forward_kinematics(model<double>(), data, q);
    const FlangeMotion<double> m = flange_motion(model<double>(), data, qd, qdd);
    const RneaOut<double> r = rnea(model<double>(), data, qd, qdd, true);
    EXPECT_LT((m.w - r.w6).norm(), 1e-13) << k;
    EXPECT_LT((m.wd - r.alpha6).norm(), 1e-12) << k;
    EXPECT_LT((m.a - r.acc6).norm(), 1e-12) << k;
    const PayloadParams<double> p = PayloadParams<double>::from(payloads.next());
    const Vec6<double> z = Vec6<double>::Zero();
    const Vec6<double> sum = payload_torque(q, qd, z, p) + payload_torque(q, z, qdd, p) - payload_torque(q, z, z, p);
    EXPECT_LT((sum - payload_torque(q, qd, qdd, p)).norm(), 1e-12) << k;
  }
}

// ---------------------------------------------------------------- the parameters

TEST(PayloadParams, FromADatasheetIsKdlsRigidBodyInertiaAboutTheFlangeAndBackIsTheDatasheet) {
  RandomPayloads payloads;
  for (int k = 0; k < 1000; ++k) {
    const Payload b = payloads.next();
    const PayloadParams<double> p = PayloadParams<double>::from(b);
    // KDL keeps a rigid body's inertia about its reference point (the segment's frame, here frame 6).
    const KDL::RigidBodyInertia ref = kdl_inertia(b);
    const KDL::RotationalInertia Io = ref.getRotationalInertia();
    EXPECT_NEAR(p.mass, ref.getMass(), 1e-15);
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(p.moment(r), ref.getMass() * ref.getCOG()(r), 1e-15) << k;
    const double io[6] = {Io.data[0], Io.data[1], Io.data[2], Io.data[4], Io.data[5], Io.data[8]};  // pi's order
    for (int e = 0; e < 6; ++e) EXPECT_NEAR(p.inertia(e), io[e], 1e-14) << k << " " << e;
    // ... and back.
    const Payload back = p.body();
    EXPECT_NEAR(back.mass, b.mass, 1e-15);
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(back.com[r], b.com[r], 1e-15) << k;
    for (int e = 0; e < 6; ++e) EXPECT_NEAR(back.inertia[e], b.inertia[e], 1e-14) << k << " " << e;
    EXPECT_EQ(PayloadParams<double>::of(p.vector()).vector(), p.vector());
  }
  // No mass, no centre of mass: the inertia stays as it is.
  PayloadParams<double> none;
  none.inertia << 1, 0, 0, 2, 0, 3;
  const Payload b = none.body();
  EXPECT_EQ(b.mass, 0);
  EXPECT_EQ(b.com[0], 0);
  EXPECT_EQ(b.inertia[1], 2);
}

// ---------------------------------------------------------------- float and Q12.19

/// The worst |Y pi - double's| [N m] of scalar S over random states and payloads, at the inputs rounded to S
/// (the double kernel at the same rounded state).
template <class S>
double worst_against_double(double& worst_relative) {
  test::RandomStates rs;
  RandomPayloads payloads;
  double worst = 0;
  worst_relative = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<S> q = rs.q_nonsingular().cast<S>(), qd = rs.vec(2.0).cast<S>(), qdd = rs.vec(5.0).cast<S>();
    const PayloadParams<S> p = PayloadParams<S>::from(payloads.next());
    PayloadParams<double> pd;
    pd.mass = static_cast<double>(p.mass);
    pd.moment = p.moment.template cast<double>();
    pd.inertia = p.inertia.template cast<double>();
    const Vec6<double> ref =
        payload_torque<double>(q.template cast<double>(), qd.template cast<double>(), qdd.template cast<double>(), pd);
    const Vec6<double> ours = payload_torque<S>(q, qd, qdd, p).template cast<double>();
    EXPECT_FALSE(math::take_arithmetic_fault<S>()) << k;
    worst = std::max(worst, (ours - ref).cwiseAbs().maxCoeff());
    worst_relative = std::max(worst_relative, (ours - ref).norm() / std::max(ref.norm(), kFloor));
  }
  return worst;
}

TEST(PayloadScalars, FloatAndQ1219AgreeWithDoubleWithinTheirBudgets) {
  // Budgets: about twice the worst measured (as docs/fixed_point.md's kernel budgets). Float: its epsilon 6e-8 times
  // the sums' sizes (J's entries up to 1 m, the wrench regressor's up to about 30: a, |w|^2, |wd|) on torques up to
  // 80 N m: measured 2.0e-5 N m, 1.1e-6 relative. Q12.19: the frames' and J's own rounding (docs/fixed_point.md: J
  // within 5.5e-6 over 1000 states, budget 1.4e-5) times the payload's force at the flange (5 kg at up to 20 m/s^2:
  // 100 N) is 5e-4 N m, the relative error of J (2.7e-5) on the torque; pi's rounding (2^-20 on inertias of
  // 1e-4-0.3 kg m^2 times |wd| <= 10 rad/s^2) adds 1e-5 N m at most: measured 5.1e-4 N m, 2.7e-5 relative, which
  // is what g(q) shows in fixed point (6.8e-4 N m on 35 N m there).
  double rel_float = 0, rel_fixed = 0;
  const double abs_float = worst_against_double<float>(rel_float);
  const double abs_fixed = worst_against_double<Fixed>(rel_fixed);
  std::printf("Y pi vs double: float worst %.2e N m (relative %.2e), Q12.19 worst %.2e N m (relative %.2e)\n",
              abs_float, rel_float, abs_fixed, rel_fixed);
  EXPECT_LE(abs_float, 4e-5);
  EXPECT_LE(rel_float, 2.5e-6);
  EXPECT_LE(abs_fixed, 1e-3);
  EXPECT_LE(rel_fixed, 6e-5);
}

}  // namespace
