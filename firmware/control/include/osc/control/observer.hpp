// The model-based operational-space velocity observer (21)-(23) and the observed joint velocity
// (28).
//
// Discretisation (semi-implicit Euler, x measured at the sample instant):
//   x~_n = x_n - x^_n,  x^dot_n = y_n + k x~_n                             (21), (23)
//   y_{n+1} = y_n + dt Lambda^{-1}[F_n - Psi(x, x^dot_n) x^dot_n - p - f^ + k_i x~_n]   (22)
//   x^_{n+1} = x^_n + dt (y_{n+1} + k x~_n)
// For the linearised error dynamics x~'' + k x~' + b x~ = 0 (b an eigenvalue of Lambda^{-1} k_i) this
// map has determinant 1 - k dt and is stable for b dt^2 < 4 - 2 k dt. At the start pose b reaches
// 2.7e4 s^-2 (rotational rows, Lambda eigenvalues down to 0.11), so b dt^2 = 0.027 against a bound of
// 3.9: a wide margin. Explicit Euler would need b dt < k, i.e. 26.6 < 32 there: stable by a margin of
// only 1.2, and lost for Lambda eigenvalues below k_i dt / k = 0.094. The paper's gains need nothing
// else at 1 ms (tests/firmware/control/test_observer.cpp checks the spectral radius along the task).
#pragma once

#include "osc/control/gains.hpp"
#include "osc/control/arm_opspace.hpp"

namespace osc {

template <class S>
struct ObserverOutput {
  Vec6<S> x_tilde;  // x~ = x - x^ (23)
  Vec6<S> xd_hat;   // x^dot = y + k x~ (21)
  Vec6<S> qd_hat;   // q^dot = J^{-1} x^dot (28)
};

/// The observer's output at the measured x (os.x): (23), (21), (28).
template <class S>
ObserverOutput<S> observer_output(const Gains<S>& G, const ArmOpSpace<S>& os, const Vec6<S>& x_hat, const Vec6<S>& y) {
  ObserverOutput<S> o;
  o.x_tilde = os.x - x_hat;
  o.xd_hat = y + G.k.cwiseProduct(o.x_tilde);
  o.qd_hat = os.Jf.solve(o.xd_hat);
  return o;
}

template <class S>
struct ObserverState {
  Vec6<S> x_hat, y;
};

/// h + p + f^ of (22), the model's velocity, gravity and friction forces at the observed velocity, in
/// the joint-space form psi_terms gives them: h + p + f^ = J^{-T} tau - Lambda a, with
/// tau = B(q, q^dot) q^dot + g + tau_f^ and a = Jdot_a(q^dot) q^dot (Psi(x, y) y = J^{-T} B(q, q_y) q_y
/// - Lambda Jdot_a q_y, p = J^{-T} g, f^ = J^{-T} tau_f^). operational_force(data, os, -a, tau) is the
/// force itself.
template <class S>
struct BiasForce {
  Vec6<S> tau;  // joint torque part
  Vec6<S> a;    // operational acceleration part
};

/// The observer update (22) over one sample, driven by the force F the controller commands in it;
/// bias = h(x, x^dot) + p + f^. Mapped to joint space, Lambda^{-1}(F - bias + k_i x~) is the
/// operational acceleration J A^{-1}(J^T (F + k_i x~) - bias.tau) + bias.a: one product with J^T,
/// one L D L^T solve with A and one product with J.
template <class S>
ObserverState<S> observer_update(const Gains<S>& G, const ArmOpSpace<S>& os, const Vec6<S>& x_hat, const Vec6<S>& y,
                                 const Vec6<S>& x_tilde, const Vec6<S>& F, const BiasForce<S>& bias) {
  const Vec6<S> tau = os.Ja.transpose() * (F + G.ki.cwiseProduct(x_tilde)) - bias.tau;
  const Vec6<S> y_dot = operational_acceleration(os, tau, bias.a);
  ObserverState<S> n;
  n.y = y + G.dt * y_dot;
  n.x_hat = x_hat + G.dt * (n.y + G.k.cwiseProduct(x_tilde));
  return n;
}

}  // namespace osc
