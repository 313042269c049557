// The kernels against the published PUMA 560 test vectors of ../shared/reference/puma560.md,
// sections 5 and 6 (the values: tests/support/puma560_published.hpp).
#include <gtest/gtest.h>

#include "osc/kernels/friction.hpp"
#include "osc/kernels/opspace.hpp"
#include "osc/robot.hpp"
#include "puma560_published.hpp"
#include "test_util.hpp"

using namespace osc;
using osc::test::from_array;
namespace published = osc::test::published;

namespace {

struct Fixture : ::testing::Test {
  Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data{};
  Vec6<double> qn = from_array(puma560::kQn);

  void at(const Vec6<double>& q) {
    forward_kinematics(model, data, q);
    geometric_jacobian(data);
    joint_inertia(model, data);
  }
  /// Toolbox friction (motor-side B, Tc referred to the link), which its rne adds: -tau_f.
  static Vec6<double> toolbox_friction_compensation(const Vec6<double>& qd) {
    Vec6<double> t;
    for (int i = 0; i < kDof; ++i) {
      const double G = std::abs(robot::kArm.links[i].gear_ratio);
      const double tc = qd(i) > 0 ? puma560::kMotorCoulombPos[i] : (qd(i) < 0 ? puma560::kMotorCoulombNeg[i] : 0.0);
      t(i) = G * (puma560::kMotorViscous[i] * G * qd(i) + tc);
    }
    return t;
  }
  Vec6<double> rne(const Vec6<double>& qd, const Vec6<double>& qdd, bool gravity) {
    return rnea(model, data, qd, qdd, gravity).tau + toolbox_friction_compensation(qd);
  }
};

void expect_vec(const Vec6<double>& got, const double (&want)[6], double tol) {
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(got(i), want[i], tol) << "element " << i;
}

void expect_mat(const Mat6<double>& got, const double (&want)[36], double tol) {
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) EXPECT_NEAR(got(i, j), want[6 * i + j], tol) << "(" << i << "," << j << ")";
}

TEST_F(Fixture, GravityLoadAtQn) {
  at(qn);
  expect_vec(gravity_torques(model, data), published::kGravityQn, 0.5e-4);
}

TEST_F(Fixture, InverseDynamicsCasesAtQn) {
  at(qn);
  const Vec6<double> one = Vec6<double>::Ones(), zero = Vec6<double>::Zero();
  expect_vec(rne(zero, one, true), published::kRneZeroOne, 0.5e-4);
  expect_vec(rne(one, one, true), published::kRneOneOne, 0.5e-3);
  expect_vec(rne(one, zero, true), published::kRneOneZero, 0.5e-4);
  expect_vec(rne(one, one, false), published::kRneOneOneNoGravity, 0.5e-4);
}

TEST_F(Fixture, ExternalWrenchAtQn) {
  // fext = [f; n] in frame 6, exerted by the end effector: adds J_e^T fext (J_e in frame 6).
  at(qn);
  Vec6<double> fext;
  fext << 1, 2, 3, 1, 2, 3;
  const Mat3<double> R6 = data.R[kDof];
  Vec6<double> w0;
  w0 << R6 * fext.head<3>(), R6 * fext.tail<3>();
  const Vec6<double> tau =
      rnea(model, data, Vec6<double>::Zero(), Vec6<double>::Zero(), true).tau + data.J.transpose() * w0;
  expect_vec(tau, published::kRneWrench, 0.5e-4);
}

TEST_F(Fixture, InertiaTimesAccelerationAtQn) {
  at(qn);
  Vec6<double> qdd;
  qdd << 1, 2, 3, 1, 2, 3;
  expect_vec(data.A * qdd, published::kInertiaTimesQdd, 0.5e-4);
}

TEST_F(Fixture, ForwardDynamicsAccelCase) {
  Vec6<double> q = qn, qd, tau;
  qd << 0.1, 0.2, 0.8, 0.2, 0.5, 1.0;
  tau << 1.0, 3.2, 1.8, 0.1, 0.7, 4.6;
  at(q);
  // accel: q_dd = A^{-1} (tau - rne(q, qd, 0)) with the toolbox friction included.
  const Vec6<double> qdd = data.A.llt().solve(tau - rne(qd, Vec6<double>::Zero(), true));
  expect_vec(qdd, published::kAccel, 0.5e-4);
}

TEST_F(Fixture, InertiaMatrixAtQn) {
  at(qn);
  expect_mat(data.A, published::kInertiaQn, 0.5e-4);
}

TEST_F(Fixture, CoriolisMatrixAtQn) {
  at(qn);
  Vec6<double> qd;
  qd << 1, 2, 3, 1, 2, 3;
  expect_mat(coriolis_matrix(model, data, qd), published::kCoriolisQn, 0.5e-4);
}

TEST_F(Fixture, OperationalInertiaAtQnGeometricJacobian) {
  at(qn);
  SphericalWristJacobianFactor<double> Jf;
  Jf.compute(data.J);
  expect_mat(operational_inertia(data.A, Jf), published::kLambdaQn, 0.5e-4);
}

TEST_F(Fixture, ForwardKinematicsAndJacobianDerivedValues) {
  at(qn);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(data.o[kDof](i), published::kTipQn[i], 0.5e-5);
  Mat3<double> R;
  R << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  EXPECT_LT((data.R[kDof] - R).norm(), 1e-12);
  expect_mat(data.J, published::kJacobianQn, 0.5e-4 + 1e-9);  // printed to 4 decimals (0.15005 -> 0.1501)

  at(from_array(puma560::kQz));
  EXPECT_NEAR(data.o[kDof](0), published::kTipQzX, 0.5e-5);
  EXPECT_NEAR(data.o[kDof](2), published::kTipQzZ, 0.5e-5);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(data.A(i, i), published::kInertiaQzDiagonal[i], 0.5e-4);
  EXPECT_NEAR(data.A(0, 1), published::kInertiaQz12, 0.5e-4);
  EXPECT_NEAR(data.A(0, 2), published::kInertiaQz13, 0.5e-4);
  EXPECT_NEAR(data.A(1, 2), published::kInertiaQz23, 0.5e-4);
  expect_vec(gravity_torques(model, data), published::kGravityQz, 0.5e-4);
  // qz is wrist-singular: the Jacobian factor reports it.
  SphericalWristJacobianFactor<double> Jf;
  Jf.compute(data.J);
  EXPECT_LT(Jf.rcond, 1e-12);
}

}  // namespace
