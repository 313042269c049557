// Friction adaptation (26) in its sampled form (67), and the friction estimate (30)-(31).
// The law is the caller's choice (Gains::adaptation).
#pragma once

#include "osc/control/gains.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/kernels/opspace.hpp"

namespace osc {

/// What the adaptation remembers between samples.
template <class S>
struct AdaptationState {
  Vec18<S> theta_hat;  // [tau_vis; tau_cou; tau_sti] estimates (20)
  Vec6<S> q_prev;      // q(t - dt)
  Vec6<S> qd_hat_prev; // q^dot(t - dt)
  bool have_prev;      // false until one sample has been taken
};

/// The paper's sampled law (67):
///   theta^(t) = theta^(t-dt) - K_ad W_j^T(q^dot(t-dt)) [q(t) - q(t-dt) - q^dot(t-dt) dt].
template <class S>
Vec18<S> adaptation_paper(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q) {
  const Vec6<S> Dq = q - a.q_prev - a.qd_hat_prev * G.dt;
  return a.theta_hat - G.kad * (friction_regressor(a.qd_hat_prev, G.tau_dec).transpose() * Dq);
}

/// theta^(t) by the law the gains select; unchanged before the first sample.
template <class S>
Vec18<S> adaptation_step(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q) {
  if (!a.have_prev) return a.theta_hat;
  switch (G.adaptation) {
    case AdaptationLaw::kPaper:
      break;
  }
  return adaptation_paper(G, a, q);
}

/// Estimated joint friction (30): tau_f^ = W_j(q^dot) theta^.
template <class S>
Vec6<S> friction_estimate(const Gains<S>& G, const Vec18<S>& theta_hat, const Vec6<S>& qd_hat) {
  return friction_regressor(qd_hat, G.tau_dec) * theta_hat;
}

}  // namespace osc
