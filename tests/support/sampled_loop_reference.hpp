// The sampled closed loop of the observer and the controller over the arm, linearised at rest, written
// out from observer.hpp's and controller.hpp's update equations (not from sampled_loop.hpp's
// polynomial): the independent reference that the gains' check (osc/control/sampled_loop.hpp) and the
// path check's loop test are held to. Eigen's EigenSolver gives the map's spectral radius.
#pragma once

#include <Eigen/Eigenvalues>

#include "osc/control/arm_opspace.hpp"
#include "osc/control/gains.hpp"
#include "osc/control/params.hpp"
#include "osc/control/sampled_loop.hpp"
#include "osc/robot.hpp"

namespace osc::test {

/// The DAC's delay in samples (params::kActuationDelay over the sample time).
constexpr double kLoopPhi = params::kActuationDelay / params::kDt;

/// One sample of the linearised loop of n axes (x_d fixed at 0, the model's forces cancelling):
/// state (x, v, x^, y, w) of n each, w the acceleration the DAC holds from the previous sample.
/// Written from the update equations, not from the header's polynomial.
template <int N>
Eigen::Matrix<double, 5 * N, 1> loop_step(const Eigen::Matrix<double, 5 * N, 1>& s,
                                          const Eigen::Matrix<double, N, N>& M,  // Lambda^-1
                                          const Eigen::Matrix<double, N, 1>& k, const Eigen::Matrix<double, N, 1>& ks,
                                          const Eigen::Matrix<double, N, 1>& knd, const Eigen::Matrix<double, N, 1>& ki,
                                          double dt, double phi) {
  using V = Eigen::Matrix<double, N, 1>;
  const V x = s.template segment<N>(0), v = s.template segment<N>(N), xh = s.template segment<N>(2 * N),
          y = s.template segment<N>(3 * N), w = s.template segment<N>(4 * N);
  const V xt = x - xh;                                     // (23)
  const V xdh = y + k.cwiseProduct(xt);                    // (21)
  const V a_r = -ks.cwiseProduct(xdh);                     // x_d ddot + k_s (x_d dot - x^dot), x_d at rest
  const V eta = -ks.cwiseProduct(x) - xdh;                 // (34): x_d dot + k_s e - x^dot, e = -x
  const V u_cmd = a_r + M * (ks + knd).cwiseProduct(eta);  // Lambda^-1 (32) less its -k_i x~
  const V u = u_cmd - M * ki.cwiseProduct(xt);             // the arm: (32) whole
  Eigen::Matrix<double, 5 * N, 1> n;
  const V yn = y + dt * u_cmd;  // (22): the model's forces and k_i x~ cancel in Lambda^-1(F - bias + k_i x~)
  n.template segment<N>(3 * N) = yn;
  n.template segment<N>(2 * N) = xh + dt * (yn + k.cwiseProduct(xt));
  const double d1 = phi * dt, d2 = (1 - phi) * dt;  // w for d1, then u
  const V x1 = x + d1 * v + d1 * d1 / 2 * w, v1 = v + d1 * w;
  n.template segment<N>(0) = x1 + d2 * v1 + d2 * d2 / 2 * u;
  n.template segment<N>(N) = v1 + d2 * u;
  n.template segment<N>(4 * N) = u;
  return n;
}

/// The map's matrix, column by column, and its spectral radius.
template <int N, class... A>
inline double loop_spectral_radius(const A&... a) {
  constexpr int n = 5 * N;
  Eigen::Matrix<double, n, n> T;
  for (int c = 0; c < n; ++c) T.col(c) = loop_step<N>(Eigen::Matrix<double, n, 1>::Unit(c), a...);
  return Eigen::EigenSolver<Eigen::Matrix<double, n, n>>(T, false).eigenvalues().cwiseAbs().maxCoeff();
}

/// The coupled loop of the six axes through Lambda^-1 at the gains g: its spectral radius (below 1: stable).
inline double coupled_spectral_radius(const Gains<double>& g, const Mat6<double>& lambda_inv, double phi = kLoopPhi) {
  return loop_spectral_radius<6>(lambda_inv, g.k, g.ks, g.knd, g.ki, g.dt, phi);
}

/// Lambda^-1 at q (the build's arm) in the controller's coordinates relative to R_ref: its A and analytic Jacobian.
inline Mat6<double> lambda_inverse_at(const Vec6<double>& q, const Mat3<double>& R_ref) {
  static const Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  ArmOpSpace<double> os;
  opspace_update(model, data, os, q, R_ref);
  return lambda_inverse(data.A, os.Ja);
}

}  // namespace osc::test
