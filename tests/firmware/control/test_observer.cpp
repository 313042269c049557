// The observer (osc/control/observer.hpp): its output (21), (23), (28) and its update (22) against an
// independent, dense evaluation of the equations, and its discretisation's error map stable with the
// paper's gains at 1 ms along the task.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdio>
#include <string>

#include "controller_fixtures.hpp"
#include "osc/control/observer.hpp"

using namespace osc;
using namespace osc::test;

namespace {

// The discrete observer error map of the semi-implicit Euler scheme, linearised about a pose:
// [x~; y~]_{n+1} = [[I - k dt - B dt^2, -dt I], [B dt, I]] [x~; y~]_n with B = Lambda^{-1} k_i.
// Its spectral radius must be below 1 at the start pose and along the trajectory.
double spectral_radius(const Mat6<double>& Lambda, bool semi_implicit) {
  const Gains<double> G = Gains<double>::paper();
  const double dt = G.dt;
  const Mat6<double> B = Lambda.llt().solve(Mat6<double>(G.ki.asDiagonal()));
  Eigen::Matrix<double, 12, 12> M;
  const Mat6<double> I = Mat6<double>::Identity();
  const Mat6<double> K = G.k.asDiagonal();
  M.topLeftCorner<6, 6>() = I - K * dt - (semi_implicit ? Mat6<double>(B * dt * dt) : Mat6<double>::Zero());
  M.topRightCorner<6, 6>() = -dt * I;
  M.bottomLeftCorner<6, 6>() = B * dt;
  M.bottomRightCorner<6, 6>() = I;
  return M.eigenvalues().cwiseAbs().maxCoeff();
}

TEST(Observer, DiscretisationIsStableWithThePaperGainsAt1ms) {
  const Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  ArmOpSpace<double> os;
  forward_kinematics(model, data, q_start());
  const Mat3<double> R_ref = data.R[kDof];
  double worst_semi = 0, worst_explicit = 0;
  // Along a sweep of the task workspace around the start pose.
  for (double s = -1; s <= 1; s += 0.25) {
    Vec6<double> q = q_start();
    q(0) += 0.1 * s;
    q(1) += 0.08 * s;
    q(2) -= 0.1 * s;
    opspace_update(model, data, os, q, R_ref);
    worst_semi = std::max(worst_semi, spectral_radius(operational_inertia(data, os), true));
    worst_explicit = std::max(worst_explicit, spectral_radius(operational_inertia(data, os), false));
  }
  RecordProperty("spectral_radius_semi_implicit", std::to_string(worst_semi));
  RecordProperty("spectral_radius_explicit", std::to_string(worst_explicit));
  std::printf("observer error map spectral radius: semi-implicit %.6f, explicit Euler %.6f\n", worst_semi,
              worst_explicit);
  EXPECT_LT(worst_semi, 1.0);
}

TEST_F(Stages, ObserverOutputIsEquations21_23_28) {
  const Vec6<double> x_hat = os.x + v6(1e-3, -2e-3, 5e-4, 1e-3, 0, -1e-3);
  const Vec6<double> y = v6(0.02, -0.01, 0.03, 0.1, -0.05, 0.02);
  const ObserverOutput<double> o = observer_output(G, os, x_hat, y);
  EXPECT_LT((o.x_tilde - (os.x - x_hat)).norm(), 1e-15);
  for (int i = 0; i < kDof; ++i) EXPECT_NEAR(o.xd_hat(i), y(i) + G.k(i) * o.x_tilde(i), 1e-15);
  EXPECT_LT((os.Ja * o.qd_hat - o.xd_hat).norm(), 1e-12);  // (28): x^dot = Ja q^dot
}

TEST_F(Stages, ObserverUpdateIsEquation22) {
  const Vec6<double> x_hat = os.x + v6(1e-3, -2e-3, 5e-4, 1e-3, 0, -1e-3);
  const Vec6<double> y = v6(0.02, -0.01, 0.03, 0.1, -0.05, 0.02);
  const Vec6<double> F = v6(10, -20, 35, 1, -2, 0.5);
  BiasForce<double> bias;  // h + p + f = J^-T tau - Lambda a
  bias.tau = v6(3, -40, 12, 0.5, -0.3, 0.1);
  bias.a = v6(0.2, -0.1, 0.3, 1.0, -2.0, 0.5);
  const Vec6<double> xt = os.x - x_hat;
  const ObserverState<double> n = observer_update(G, os, x_hat, y, xt, F, bias);
  // Lambda (y' - y) / dt = F - (h + p + f) + k_i x~, with Lambda formed and everything solved densely here.
  const Mat6<double> Lambda = operational_inertia(data, os);
  const Vec6<double> hpf = os.Ja.transpose().partialPivLu().solve(bias.tau) - Lambda * bias.a;
  const Vec6<double> rhs = F - hpf + G.ki.cwiseProduct(xt);
  const Vec6<double> y_expect = y + G.dt * Lambda.partialPivLu().solve(rhs);
  EXPECT_LT((n.y - y_expect).norm(), 1e-9 * (1 + y_expect.norm()));
  EXPECT_LT((n.x_hat - (x_hat + G.dt * (n.y + G.k.cwiseProduct(xt)))).norm(), 1e-15);
}

}  // namespace
