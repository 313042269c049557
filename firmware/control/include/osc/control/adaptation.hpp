// Friction adaptation (26) in its sampled form (67), a robust variant of it, and the friction
// estimate (30)-(31). The law is the caller's choice (Gains::adaptation); docs/adaptation.md has
// the analysis and the measurements behind the robust law.
//
// (67): theta^(t) = theta^(t-dt) - K_ad W_j^T(q^dot(t-dt)) Dq,  Dq = q(t) - q(t-dt) - q^dot(t-dt) dt.
// Why it drifts: q(t-dt) carries the encoder quantisation nu(t-dt), and the observed velocity
// q^dot(t-dt) = J^-1 (y + k x~) carries about k nu(t-dt) through x~ (21), (23). Dq contains
// -nu(t-dt) - k nu(t-dt) dt, so the viscous rows of W_j^T(q^dot(t-dt)) Dq have the mean
// -k (1 + k dt) E[nu^2] < 0 whatever the plant does, and theta^_vis grows by K_ad k (1 + k dt) delta^2/12
// per sample (delta: one count in joint radians); the sgn rows get a bias at velocity reversals.
//
// The robust law removes the shared sample and bounds what is left:
//   - regressor W_j(q^dot(t-2dt)): one sample older than Dq's, so uncorrelated with nu(t-dt);
//   - leakage theta^ -= sigma dt theta^ (sigma = 1e-3 /s): stops the much smaller drift that
//     quantisation noise still drives through the plant (the compensation W_j(q^dot) theta^);
//   - projection onto 0 <= theta^ <= theta_max per coefficient (K_ad is diagonal, so clipping is the
//     exact projection in the K_ad^-1 metric and never makes the Lyapunov function grow).
// Everything is +, *, compare (and the regressor's exp and sgn): it runs in float, double and fixed
// point alike. The leakage is applied as sigma (dt theta^), not (sigma dt) theta^: sigma dt = 1e-6
// is half an LSB of Q12.19 and would round to twice the rate.
#pragma once

#include "osc/control/gains.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/kernels/opspace.hpp"

namespace osc {

/// What the adaptation remembers between samples.
template <class S>
struct AdaptationState {
  Vec18<S> theta_hat;    // [tau_vis; tau_cou; tau_sti] estimates (20)
  Vec6<S> q_prev;        // q(t - dt)
  Vec6<S> qd_hat_prev;   // q^dot(t - dt)
  Vec6<S> qd_hat_prev2;  // q^dot(t - 2 dt)
  // The regressor at q^dot(t - dt) and q^dot(t - 2 dt): friction_estimate computed them in those
  // samples (each costs six exponentials).
  RegressorDiagonals<S> w_prev, w_prev2;
  int samples;  // samples recorded so far (saturates at 2)
};

/// The error signal of (67): the measured increment less the observer's prediction,
/// Dq = q(t) - q(t-dt) - q^dot(t-dt) dt.
template <class S>
Vec6<S> increment_error(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q) {
  return q - a.q_prev - a.qd_hat_prev * G.dt;
}

/// The paper's sampled law (67).
template <class S>
Vec18<S> adaptation_paper(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q) {
  const Vec6<S> Dq = increment_error(G, a, q);
  return a.theta_hat - G.kad * a.w_prev.transpose_times(Dq);
}

/// The robust law: (67)'s error Dq, the regressor at q^dot(t-2dt), leakage, projection.
template <class S>
Vec18<S> adaptation_robust(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q) {
  const Vec6<S> Dq = increment_error(G, a, q);
  Vec18<S> theta = a.theta_hat - G.leakage * (G.dt * a.theta_hat);
  theta -= G.kad * a.w_prev2.transpose_times(Dq);
  for (int i = 0; i < 3 * kDof; ++i) {
    if (theta(i) < S(0)) theta(i) = S(0);
    if (theta(i) > G.theta_max(i)) theta(i) = G.theta_max(i);
  }
  return theta;
}

/// theta^(t) by the law the gains select; unchanged until the law has the samples it needs. The
/// `momentum` law leaves it as it is: the control task identifies it from the residual monitor
/// (osc/control/identification.hpp), which needs the torque the drives applied.
template <class S>
Vec18<S> adaptation_step(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q) {
  if (G.adaptation == AdaptationLaw::kMomentum) return a.theta_hat;
  if (G.adaptation == AdaptationLaw::kRobust) return a.samples >= 2 ? adaptation_robust(G, a, q) : a.theta_hat;
  return a.samples >= 1 ? adaptation_paper(G, a, q) : a.theta_hat;
}

/// Starts the adaptation at theta^(0) = 0 with no samples.
template <class S>
void adaptation_init(AdaptationState<S>& a, const Vec6<S>& q0) {
  a.theta_hat.setZero();
  a.q_prev = q0;
  a.qd_hat_prev.setZero();
  a.qd_hat_prev2.setZero();
  a.w_prev.vis.setZero(), a.w_prev.cou.setZero(), a.w_prev.sti.setZero();  // the regressor at rest
  a.w_prev2 = a.w_prev;
  a.samples = 0;
}

/// Records the sample t for the next update: theta^(t), q(t), q^dot(t) and the regressor at q^dot(t).
template <class S>
void adaptation_record(AdaptationState<S>& a, const Vec18<S>& theta_hat, const Vec6<S>& q, const Vec6<S>& qd_hat,
                       const RegressorDiagonals<S>& w) {
  a.theta_hat = theta_hat;
  a.q_prev = q;
  a.qd_hat_prev2 = a.qd_hat_prev;
  a.qd_hat_prev = qd_hat;
  a.w_prev2 = a.w_prev;
  a.w_prev = w;
  if (a.samples < 2) ++a.samples;
}
/// The same, computing the regressor at q^dot(t).
template <class S>
void adaptation_record(const Gains<S>& G, AdaptationState<S>& a, const Vec18<S>& theta_hat, const Vec6<S>& q,
                       const Vec6<S>& qd_hat) {
  adaptation_record(a, theta_hat, q, qd_hat, friction_regressor_diagonals(qd_hat, G.tau_dec));
}

/// Estimated joint friction (30): tau_f^ = W_j(q^dot) theta^.
template <class S>
Vec6<S> friction_estimate(const RegressorDiagonals<S>& w, const Vec18<S>& theta_hat) {
  return w.times(theta_hat);
}
template <class S>
Vec6<S> friction_estimate(const Gains<S>& G, const Vec18<S>& theta_hat, const Vec6<S>& qd_hat) {
  return friction_estimate(friction_regressor_diagonals(qd_hat, G.tau_dec), theta_hat);
}

}  // namespace osc
