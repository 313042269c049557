// The adaptive observer-controller of the paper: velocity observer (21)-(23), operational-space
// controller (32)-(36), friction adaptation (26) in its sampled form (67) with the estimated
// friction (30)-(31). One call of control_step() is one sample: encoder angles q(t) in, joint
// torques out. All state lives in ControllerState; nothing is allocated.
//
// Observer discretisation (semi-implicit Euler, x measured at the sample instant):
//   x~_n = x_n - x^_n,  x^dot_n = y_n + k x~_n                             (21), (23)
//   y_{n+1} = y_n + dt Lambda^{-1}[F_n - Psi(x, x^dot_n) x^dot_n - p - f^ + k_i x~_n]   (22)
//   x^_{n+1} = x^_n + dt (y_{n+1} + k x~_n)
// For the linearised error dynamics x~'' + k x~' + b x~ = 0 (b an eigenvalue of Lambda^{-1} k_i) this
// map has determinant 1 - k dt and is stable for b dt^2 < 4 - 2 k dt. At the start pose b reaches
// 2.7e4 s^-2 (rotational rows, Lambda eigenvalues down to 0.11), so b dt^2 = 0.027 against a bound of
// 3.9: a wide margin. Explicit Euler would need b dt < k, i.e. 26.6 < 32 there: stable by a margin of
// only 1.2, and lost for Lambda eigenvalues below k_i dt / k = 0.094. The paper's gains need nothing
// else at 1 ms (tests/test_controller.cpp checks the spectral radius along the task).
#pragma once

#include <cstdint>

#include "osc/kernels/friction.hpp"
#include "osc/kernels/opspace.hpp"
#include "osc/control/params.hpp"
#include "osc/control/trajectory.hpp"

namespace osc {

/// Gains (69), K_ad, tau_dec and dt; defaults from params.hpp.
template <class S>
struct Gains {
  Vec6<S> knd, k, ks, ki;
  S kad;
  Vec6<S> tau_dec;
  S dt;
  S min_rcond;

  static Gains paper() {
    Gains g;
    for (int i = 0; i < kDof; ++i) {
      g.knd(i) = lit<S>(params::kKnd[i]);
      g.k(i) = lit<S>(params::kK[i]);
      g.ks(i) = lit<S>(params::kKs[i]);
      g.ki(i) = lit<S>(params::kKi[i]);
      g.tau_dec(i) = lit<S>(params::kTauDec);
    }
    g.kad = lit<S>(params::kKad);
    g.dt = lit<S>(params::kDt);
    g.min_rcond = lit<S>(params::kMinJacobianRcond);
    return g;
  }
};

/// With adaptive friction compensation (Table I), or without (f^ = 0, no adaptation: Table III).
enum class FrictionMode : std::uint8_t { kAdaptive, kNone };

/// Status bits of one control step. Any bit set means the step commanded zero torque.
enum StepStatus : std::uint32_t {
  kStepOk = 0,
  kStepNonFinite = 1u << 0,   ///< a non-finite input, state or output
  kStepSingular = 1u << 1,    ///< Jacobian reciprocal condition below Gains::min_rcond
};

template <class S>
struct ControllerState {
  // Task.
  Vec3<S> p0;         // start position (trajectory centre)
  Mat3<S> R_ref;      // start orientation: reference of the orientation coordinates
  // Observer (21)-(22).
  Vec6<S> x_hat, y;
  // Adaptation (67).
  Vec18<S> theta_hat;
  Vec6<S> q_prev, qd_hat_prev;
  bool have_prev;
  // Workspace.
  Data<S> data;
  OpSpace<S> os;
};

/// What one step produced (for logging, supervision and tests).
template <class S>
struct StepOutput {
  Vec6<S> tau;        // joint torques Gamma = J^T F
  Vec6<S> x, e;       // measured x, tracking error e = x_d - x (36)
  Vec6<S> x_tilde;    // observer position error (23)
  Vec6<S> xd_hat;     // observed velocity (21)
  Vec6<S> tau_f_hat;  // estimated joint friction (30)
  S rcond;
  std::uint32_t status;
};

/// Starts the observer at the measured pose: x^(0) = x(0), y(0) = -k x~(0) = 0; theta^(0) = 0.
template <class S>
void controller_init(const Model<S>& model, ControllerState<S>& st, const Vec6In<S>& q0) {
  forward_kinematics(model, st.data, q0);
  st.p0 = st.data.o[kDof];
  st.R_ref = st.data.R[kDof];
  st.x_hat << st.p0, Vec3<S>::Zero();
  st.y.setZero();
  st.theta_hat.setZero();
  st.q_prev = q0;
  st.qd_hat_prev.setZero();
  st.have_prev = false;
}

/// One sample of the adaptive observer-controller at time t with encoder angles q.
template <class S>
StepOutput<S> control_step(const Model<S>& model, const Gains<S>& G, FrictionMode mode, ControllerState<S>& st,
                           const Vec6In<S>& q, S t) {
  StepOutput<S> out{};
  out.tau.setZero();
  out.x.setZero();
  out.e.setZero();
  out.x_tilde.setZero();
  out.xd_hat.setZero();
  out.tau_f_hat.setZero();
  out.rcond = S(0);
  out.status = kStepOk;
  if (!math::all_finite(q) || !math::isfinite(t)) {
    out.status = kStepNonFinite;
    return out;
  }
  OpSpace<S>& os = st.os;
  opspace_update(model, st.data, os, q, st.R_ref);
  out.rcond = os.Jf.rcond;
  out.x = os.x;
  if (!(os.Jf.rcond >= G.min_rcond)) {
    out.status = kStepSingular;
    return out;
  }
  // Friction adaptation (67): theta^ -= K_ad W_j^T(q^dot(t-dt)) [q(t) - q(t-dt) - q^dot(t-dt) dt].
  Vec18<S> theta_hat = st.theta_hat;
  if (mode == FrictionMode::kAdaptive && st.have_prev) {
    const Vec6<S> Dq = q - st.q_prev - st.qd_hat_prev * G.dt;
    theta_hat -= G.kad * (friction_regressor(st.qd_hat_prev, G.tau_dec).transpose() * Dq);
  }
  // Observer output (21), (23); observed joint velocity (28).
  const Vec6<S> x_tilde = os.x - st.x_hat;
  const Vec6<S> xd_hat = st.y + G.k.cwiseProduct(x_tilde);
  const Vec6<S> qd_hat = os.Jf.solve(xd_hat);
  // Estimated friction (30), (31).
  Vec6<S> tau_f_hat = Vec6<S>::Zero();
  if (mode == FrictionMode::kAdaptive) tau_f_hat = friction_regressor(qd_hat, G.tau_dec) * theta_hat;
  const Vec6<S> f_hat = operational_friction(os, tau_f_hat);
  // Tracking error (36) and observed filtered tracking error (34).
  const Desired<S> d = trajectory(st.p0, t);
  const Vec6<S> e = d.x - os.x;
  const Vec6<S> v = d.xd + G.ks.cwiseProduct(e);
  const Vec6<S> eta_p = v - xd_hat;
  // Psi(x, x^dot) x^dot and Psi(x, x^dot)(x_d dot + k_s e) by polarisation of h(v) = Psi(x,v) v.
  const Vec6<S> h_xd = psi_quadratic(model, st.data, os, xd_hat);
  const Vec6<S> psi_v = lit<S>(0.5) * (psi_quadratic(model, st.data, os, xd_hat + v) - h_xd -
                                       psi_quadratic(model, st.data, os, v));
  const Vec6<S> p = operational_gravity(os);
  // w_e (35) and the force command (32); torques Gamma = J^T F (5).
  const Vec6<S> w_e = os.Lambda * (d.xdd + G.ks.cwiseProduct(d.xd - xd_hat)) + psi_v + p + f_hat;
  const Vec6<S> F = (G.ks + G.knd).cwiseProduct(eta_p) + w_e - G.ki.cwiseProduct(x_tilde);
  const Vec6<S> tau = joint_torques(os, F);
  // Observer update (22), driven by the same F.
  const Vec6<S> y_dot = lambda_solve(os, F - h_xd - p - f_hat + G.ki.cwiseProduct(x_tilde));
  const Vec6<S> y_next = st.y + G.dt * y_dot;
  const Vec6<S> x_hat_next = st.x_hat + G.dt * (y_next + G.k.cwiseProduct(x_tilde));
  if (!math::all_finite(tau) || !math::all_finite(y_next) || !math::all_finite(x_hat_next) ||
      !math::all_finite(theta_hat)) {
    out.status = kStepNonFinite;
    return out;
  }
  st.y = y_next;
  st.theta_hat = theta_hat;
  st.x_hat = x_hat_next;
  st.q_prev = q;
  st.qd_hat_prev = qd_hat;
  st.have_prev = true;
  out.tau = tau;
  out.e = e;
  out.x_tilde = x_tilde;
  out.xd_hat = xd_hat;
  out.tau_f_hat = tau_f_hat;
  return out;
}

}  // namespace osc
