// Friction adaptation: the control law's stage that learns theta^ = [tau_vis; tau_cou; tau_sti] (20),
// and the friction estimate (30)-(31) it feeds. Three laws, each a stage of the control law; the
// gains select one (Gains::adaptation, AdaptationLaw), as does the runtime parameter `adaptation`;
// docs/adaptation.md has the analysis and the measurements behind each:
//   law       stage                equation, reference                                  runs
//   paper     adaptation_paper     (26) in its sampled form (67)                         in control_step
//   robust    adaptation_robust    (67)'s error, the regressor one sample older,         (adaptation_step),
//                                  leakage, projection (below; docs/adaptation.md 1-3)  before the observer
//   momentum  adaptation_identify  a Kalman filter per joint on the momentum residual's  after the step, on the
//                                  friction sample (docs/adaptation.md section 5;       residual's sample of it
//                                  osc/control/identification.hpp)                      (MomentumSample)
// The momentum law learns from the torque the step commanded and the drives applied, which the
// residual monitor (osc/runtime/residual_monitor.hpp) filters after the step: its update is the last
// stage of the tick's control law, called by the runtime with that sample between the monitors that
// take it and the check of theta^'s band (osc/runtime/control_task.hpp, step_monitor_faults). Its
// filter (FrictionIdentifier) is part of the adaptation's state. adaptation_step leaves theta^ as it
// is under this law.
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
#include "osc/control/identification.hpp"
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
  // The momentum law's filter: each joint's estimate, covariance and excitation (identification.hpp).
  FrictionIdentifier<S> identifier;
};

/// The momentum law's input: one joint's friction sample, which the residual monitor took after the
/// step (osc/runtime/residual_monitor.hpp), and what weighs it in the update (FrictionIdentifier::update).
template <class S>
struct MomentumSample {
  int joint;                 // the joint sampled (momentum_turn)
  FrictionSample<S> sample;  // y = H(tau_f), phi = H(W_j), H(g), whether the joint moved long enough
  bool residual_low;         // the joint's residual within params::kIdentifyMaxRatio of its threshold
  S noise_var;               // the variance the residual's quantisation bound implies [N^2 m^2]
  S correlation;             // samples correlated through the residual's filter: each counts this many times less
};

/// The error signal of (67): the measured increment less the observer's prediction,
/// Dq = q(t) - q(t-dt) - q^dot(t-dt) dt.
template <class S>
Vec6<S> increment_error(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q) {
  return q - a.q_prev - a.qd_hat_prev * G.dt;
}

/// (67)'s error as the motors see it: C^-1 Dq on a coupled drive train, whose friction regressor is the motors'
/// (the joints' regressor C^-T W, so that its transpose times Dq is W^T C^-1 Dq).
template <class S>
Vec6<S> motor_increment_error(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q,
                              const DriveCoupling<S>& drives) {
  return motor_rates(drives, increment_error(G, a, q));  // Dq itself on an uncoupled arm (no terms)
}

/// The paper's law (26) in its sampled form (67).
template <class S>
Vec18<S> adaptation_paper(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q,
                          const DriveCoupling<S>& drives = {}) {
  const Vec6<S> Dq = motor_increment_error(G, a, q, drives);
  return a.theta_hat - G.kad * a.w_prev.transpose_times(Dq);
}

/// The robust law: (67)'s error Dq, the regressor at q^dot(t-2dt), leakage, projection.
template <class S>
Vec18<S> adaptation_robust(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q,
                           const DriveCoupling<S>& drives = {}) {
  const Vec6<S> Dq = motor_increment_error(G, a, q, drives);
  Vec18<S> theta = a.theta_hat - G.leakage * (G.dt * a.theta_hat);
  theta -= G.kad * a.w_prev2.transpose_times(Dq);
  for (int i = 0; i < 3 * kDof; ++i) {
    if (theta(i) < S(0)) theta(i) = S(0);
    if (theta(i) > G.theta_max(i)) theta(i) = G.theta_max(i);
  }
  return theta;
}

/// theta^(t) by the law the gains select, paper (67) or robust; unchanged until the law has the
/// samples it needs. The `momentum` law leaves it as it is here: its stage is adaptation_identify.
template <class S>
Vec18<S> adaptation_step(const Gains<S>& G, const AdaptationState<S>& a, const Vec6<S>& q,
                         const DriveCoupling<S>& drives = {}) {
  if (G.adaptation == AdaptationLaw::kMomentum) return a.theta_hat;
  if (G.adaptation == AdaptationLaw::kRobust) return a.samples >= 2 ? adaptation_robust(G, a, q, drives) : a.theta_hat;
  return a.samples >= 1 ? adaptation_paper(G, a, q, drives) : a.theta_hat;
}

/// The joint whose friction sample the momentum law takes in this tick (the residual monitor takes it
/// after the step): the joints take turns, params::kIdentifyEvery ticks apart each.
template <class S>
int momentum_turn(AdaptationState<S>& a) {
  return a.identifier.take_turn();
}

/// The momentum law (docs/adaptation.md, section 5): joint s.joint's Kalman update from the residual's
/// friction sample s, and that joint's coefficients of theta^ the new estimate projected within
/// [0, theta_max] in the metric of P^-1 (FrictionIdentifier::update). Runs after the step whose
/// torque the sample compares, once per tick the law is selected.
template <class S>
IdentifyOutcome adaptation_identify(const Gains<S>& G, AdaptationState<S>& a, const MomentumSample<S>& s) {
  return a.identifier.update(s.joint, s.sample, s.residual_low, s.noise_var, s.correlation, a.theta_hat, G.theta_max);
}

/// Restarts the samples at q (an enable, a homing's end): what the laws learnt, theta^ and the
/// momentum law's filter, is kept.
template <class S>
void adaptation_restart(AdaptationState<S>& a, const Vec6<S>& q) {
  a.q_prev = q;
  a.qd_hat_prev.setZero();
  a.qd_hat_prev2.setZero();
  a.w_prev.vis.setZero(), a.w_prev.cou.setZero(), a.w_prev.sti.setZero();  // the regressor at rest
  a.w_prev2 = a.w_prev;
  a.samples = 0;
}

/// Starts the adaptation at theta^(0) = 0 with no samples, the momentum law's filter at its prior.
template <class S>
void adaptation_init(AdaptationState<S>& a, const Vec6<S>& q0) {
  a.theta_hat.setZero();
  a.identifier.reset();
  adaptation_restart(a, q0);
}

/// Records the sample t for the next update: q(t), q^dot(t) and the regressor at q^dot(t) (theta^(t): the
/// caller's, adaptation_step's where it changed).
template <class S>
void adaptation_record(AdaptationState<S>& a, const Vec6<S>& q, const Vec6<S>& qd_hat, const RegressorDiagonals<S>& w) {
  a.q_prev = q;
  a.qd_hat_prev2 = a.qd_hat_prev;
  a.qd_hat_prev = qd_hat;
  a.w_prev2 = a.w_prev;
  a.w_prev = w;
  if (a.samples < 2) ++a.samples;
}
/// The same with theta^(t), computing the regressor at q^dot(t).
template <class S>
void adaptation_record(const Gains<S>& G, AdaptationState<S>& a, const Vec18<S>& theta_hat, const Vec6<S>& q,
                       const Vec6<S>& qd_hat) {
  a.theta_hat = theta_hat;
  adaptation_record(a, q, qd_hat, friction_regressor_diagonals(qd_hat, G.tau_dec));
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
