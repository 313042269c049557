// The published PUMA 560 test vectors of ../shared/reference/puma560.md, sections 5 and 6.
#include <gtest/gtest.h>

#include "osc/kernels/friction.hpp"
#include "osc/kernels/opspace.hpp"
#include "osc/robot.hpp"
#include "test_util.hpp"

using namespace osc;
using osc::test::from_array;

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

void expect_vec(const Vec6<double>& got, std::initializer_list<double> want, double tol) {
  int i = 0;
  for (double w : want) {
    EXPECT_NEAR(got(i), w, tol) << "element " << i;
    ++i;
  }
}

void expect_mat(const Mat6<double>& got, const double (&want)[36], double tol) {
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) EXPECT_NEAR(got(i, j), want[6 * i + j], tol) << "(" << i << "," << j << ")";
}

TEST_F(Fixture, GravityLoadAtQn) {
  at(qn);
  expect_vec(gravity_torques(model, data), {0, 31.6399, 6.0351, 0, 0.0283, 0}, 0.5e-4);
}

TEST_F(Fixture, InverseDynamicsCasesAtQn) {
  at(qn);
  const Vec6<double> one = Vec6<double>::Ones(), zero = Vec6<double>::Zero();
  expect_vec(rne(zero, one, true), {3.35311, 36.0025, 7.42596, 0.190043, 0.203441, 0.194133}, 0.5e-4);
  expect_vec(rne(one, one, true), {32.4952, 60.867, 17.7436, 1.45452, 1.29911, 0.713781}, 0.5e-3);
  expect_vec(rne(one, zero, true), {29.1421, 56.5044, 16.3528, 1.26448, 1.12392, 0.519648}, 0.5e-4);
  expect_vec(rne(one, one, false), {32.4952, 29.2271, 11.7085, 1.45452, 1.27086, 0.713781}, 0.5e-4);
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
  expect_vec(tau, {0.642756, 29.0866, 4.70321, 2.82843, -1.97175, 3}, 0.5e-4);
}

TEST_F(Fixture, InertiaTimesAccelerationAtQn) {
  at(qn);
  Vec6<double> qdd;
  qdd << 1, 2, 3, 1, 2, 3;
  expect_vec(data.A * qdd, {3.1500, 9.4805, 3.6189, 0.1901, 0.3519, 0.5823}, 0.5e-4);
}

TEST_F(Fixture, ForwardDynamicsAccelCase) {
  Vec6<double> q = qn, qd, tau;
  qd << 0.1, 0.2, 0.8, 0.2, 0.5, 1.0;
  tau << 1.0, 3.2, 1.8, 0.1, 0.7, 4.6;
  at(q);
  // accel: q_dd = A^{-1} (tau - rne(q, qd, 0)) with the toolbox friction included.
  const Vec6<double> qdd = data.A.llt().solve(tau - rne(qd, Vec6<double>::Zero(), true));
  expect_vec(qdd, {-7.4102, -9.8432, -10.9694, -4.4314, -0.9881, 21.0228}, 0.5e-4);
}

TEST_F(Fixture, InertiaMatrixAtQn) {
  at(qn);
  const double M[36] = {3.6594,  -0.4044, 0.1006, -0.0025, 0.0000, -0.0000,  //
                        -0.4044, 4.4137,  0.3509, 0.0000,  0.0024, 0.0000,   //
                        0.1006,  0.3509,  0.9378, 0.0000,  0.0015, 0.0000,   //
                        -0.0025, 0.0000,  0.0000, 0.1925,  0.0000, 0.0000,   //
                        0.0000,  0.0024,  0.0015, 0.0000,  0.1713, 0.0000,   //
                        -0.0000, 0.0000,  0.0000, 0.0000,  0.0000, 0.1941};
  expect_mat(data.A, M, 0.5e-4);
}

TEST_F(Fixture, CoriolisMatrixAtQn) {
  at(qn);
  Vec6<double> qd;
  qd << 1, 2, 3, 1, 2, 3;
  const double C[36] = {-0.1735, -2.0494, -0.1178, -0.0002, -0.0045, 0.0001,   //
                        0.6274,  1.1572,  1.9287,  -0.0015, -0.0003, -0.0000,  //
                        -0.3608, -0.7734, -0.0018, -0.0009, -0.0064, -0.0000,  //
                        0.0011,  0.0005,  -0.0001, 0.0002,  0.0002,  -0.0001,  //
                        -0.0002, 0.0028,  0.0046,  -0.0002, -0.0000, -0.0000,  //
                        0.0001,  0.0000,  0.0000,  0.0000,  0.0000,  0};
  expect_mat(coriolis_matrix(model, data, qd), C, 0.5e-4);
}

TEST_F(Fixture, OperationalInertiaAtQnGeometricJacobian) {
  at(qn);
  SphericalWristJacobianFactor<double> Jf;
  Jf.compute(data.J);
  const double L[36] = {17.2954, -2.7542, -9.6233, -0.0000, 0.2795,  0.0000,   //
                        -2.7542, 12.1909, 1.2459,  -0.3254, -0.0703, -0.9652,  //
                        -9.6233, 1.2459,  13.3348, -0.0000, 0.2767,  -0.0000,  //
                        -0.0000, -0.3254, -0.0000, 0.1941,  0.0000,  0.1941,   //
                        0.2795,  -0.0703, 0.2767,  0.0000,  0.1713,  0.0000,   //
                        0.0000,  -0.9652, -0.0000, 0.1941,  0.0000,  0.5791};
  expect_mat(operational_inertia(data.A, Jf), L, 0.5e-4);
}

TEST_F(Fixture, ForwardKinematicsAndJacobianDerivedValues) {
  at(qn);
  EXPECT_NEAR(data.o[kDof](0), 0.59630, 0.5e-5);
  EXPECT_NEAR(data.o[kDof](1), -0.15005, 0.5e-5);
  EXPECT_NEAR(data.o[kDof](2), -0.01435, 0.5e-5);
  Mat3<double> R;
  R << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  EXPECT_LT((data.R[kDof] - R).norm(), 1e-12);
  const double J[36] = {0.1501, 0.0144, 0.3197, 0, 0, 0, 0.5963, 0,  0, 0,  0, 0, 0, 0.5963, 0.2910,  0, 0, 0, 0,
                        0,      0,      0.7071, 0, 1, 0, -1,     -1, 0, -1, 0, 1, 0, 0,      -0.7071, 0, 0};
  expect_mat(data.J, J, 0.5e-4 + 1e-9);  // printed to 4 decimals (0.15005 -> 0.1501)

  at(from_array(puma560::kQz));
  EXPECT_NEAR(data.o[kDof](0), 0.45210, 0.5e-5);
  EXPECT_NEAR(data.o[kDof](2), 0.43180, 0.5e-5);
  const double Mz[6] = {3.9611, 4.4566, 0.9387, 0.1924, 0.1713, 0.1941};
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(data.A(i, i), Mz[i], 0.5e-4);
  EXPECT_NEAR(data.A(0, 1), -0.1627, 0.5e-4);
  EXPECT_NEAR(data.A(0, 2), -0.1389, 0.5e-4);
  EXPECT_NEAR(data.A(1, 2), 0.3727, 0.5e-4);
  expect_vec(gravity_torques(model, data), {0, 37.4837, 0.2489, 0, 0, 0}, 0.5e-4);
  // qz is wrist-singular: the Jacobian factor reports it.
  SphericalWristJacobianFactor<double> Jf;
  Jf.compute(data.J);
  EXPECT_LT(Jf.rcond, 1e-12);
}

}  // namespace
