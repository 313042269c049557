// The adaptive observer-controller of the paper. One call of control_step() is one sample: encoder
// angles q(t) and the desired state d = (x_d, x_d dot, x_d ddot) in, joint torques out. d comes from
// a motion source (motion.hpp; the paper's is trajectory (68)). It reads as the block diagram, one
// stage per call:
//   kinematics and dynamics at q           opspace_update          (4), (5)   (the dynamics on its turns:
//                                                                             dynamics_turn, Gains::model_rate)
//   friction adaptation                    adaptation_step         (26)/(67) or robust  adaptation.hpp
//   observer output                        observer_output         (21), (23), (28)  observer.hpp
//   friction estimate                      friction_estimate       (30)
//   force command                          force_command           (31)-(36)
//   joint torques                          joint_torques           (5)
//   observer update                        observer_update         (22)      observer.hpp
// and, after the step, the `momentum` law's stage, adaptation_identify (adaptation.hpp; docs/adaptation.md
// section 5), on the residual monitor's sample of this step, which the runtime passes it.
// The operational forces of (35) and (22) (Lambda a, Psi, p, f) are summed in their joint-space form,
// J^{-T} tau + Lambda a, and each sum costs one solve with J^T (operational_force) or one L D L^T solve
// with A (operational_acceleration), not one per term. All state lives in ControllerState; nothing is
// allocated.
#pragma once

#include <cstdint>

#include "osc/control/adaptation.hpp"
#include "osc/control/faults.hpp"
#include "osc/control/gains.hpp"
#include "osc/control/observer.hpp"
#include "osc/control/motion.hpp"
#include "osc/control/arm_opspace.hpp"

namespace osc {

template <class S>
struct ControllerState {
  Mat3<S> R_ref;             // start orientation: reference of the orientation coordinates
  ObserverState<S> obs;      // x^, y (21)-(22)
  AdaptationState<S> adapt;  // theta^, the previous sample (67), the momentum law's filter
  Data<S> data;              // workspace
  ArmOpSpace<S> os;
  /// Psi's joint-space terms (force_command), held between the steps that compute them (ModelRate::kAlternate).
  PsiTerms<S> psi;
  /// The steps since the controller (re)started: whose turn it is (dynamics_turn).
  std::uint32_t steps = 0;
};

/// Which parts of the arm's dynamics a step computes; the others are held from the step before.
struct DynamicsTurn {
  bool model;     // A(q), its L D L^T factors, g(q) (opspace_update)
  bool velocity;  // Psi's velocity products (psi_terms, force_command)
};

/// Whether the controller's step number n (0: its first since a (re)start) is one of its even steps.
constexpr bool is_even_step(std::uint32_t n) { return (n & 1u) == 0; }

/// Whether the controller's last step was one of its even steps (its first, third, ...): the alternate model
/// rate's model turns, and the residual monitor's turns (params::kResidualTurnEvery), whatever the rate.
template <class S>
bool even_step(const ControllerState<S>& st) {
  return is_even_step(st.steps - 1u);
}

/// Every step computes both (ModelRate::kEveryStep), or they alternate (kAlternate): the model on a
/// controller's first step and every other one after it, the velocity products on the steps between. A step
/// then solves with the A and g of the step before, or adds the Psi terms of the step before, each one period
/// (params::kDt) old. The first step needs no Psi of its own: the observer starts at rest at the pose it is
/// started at (y = 0, x~ = 0), so q^dot = 0 there and every velocity product is 0, as controller_init and
/// controller_restart set them (a count away from that pose, q^dot = J^-1 k x~ and the products are of its square).
inline DynamicsTurn dynamics_turn(ModelRate rate, std::uint32_t steps) {
  if (rate == ModelRate::kEveryStep) return {true, true};
  const bool model = is_even_step(steps);
  return {model, !model};
}

/// What one step produced (for logging, supervision and tests).
template <class S>
struct StepOutput {
  Vec6<S> tau;        // joint torques Gamma = J^T F
  Vec6<S> x, e;       // measured x, tracking error e = x_d - x (36)
  Vec6<S> x_tilde;    // observer position error (23)
  Vec6<S> xd_hat;     // observed velocity (21)
  Vec6<S> tau_f_hat;  // estimated friction (30)
  Vec6<S> tau_bias;   // c(q, q^dot) + g(q) + tau_f^ at the observed velocity (the residual monitor)
  S rcond;
  std::uint32_t status;  // kFaultNone, or kFaultNonFinite / kFaultSingular / kFaultOverflow (then tau = 0)
};

namespace detail {
/// The observer at the pose whose forward kinematics st.data holds: x^ = x there, y = -k x~ = 0; the
/// orientation coordinates taken relative to the orientation there (R_ref).
template <class S>
void observer_here(ControllerState<S>& st) {
  st.R_ref = st.data.R[kDof];
  st.obs.x_hat << st.data.o[kDof], Vec3<S>::Zero();
  st.obs.y.setZero();
  st.psi.c_yy.setZero();
  st.psi.jdot_yy.setZero();
  st.psi.c_yz.setZero();
  st.psi.jdot_yz.setZero();
  st.steps = 0;
  // The pivoted LU's rcond by halves (its first step exact), a 1 ms lag on a singular stop whose margin is
  // a factor 2 (motion_stage.hpp); the block factor's is cheap and exact.
  if constexpr (requires { st.os.Jf.rcond_by_halves(); }) st.os.Jf.rcond_by_halves();
}
/// The observer at the measured pose q (observer_here, after the forward kinematics at q).
template <class S>
void observer_start(const Model<S>& model, ControllerState<S>& st, const Vec6In<S>& q) {
  forward_kinematics(model, st.data, q);
  observer_here(st);
}
}  // namespace detail

/// Starts the observer at the measured pose: x^(0) = x(0), y(0) = -k x~(0) = 0; theta^(0) = 0 and the
/// momentum law's filter at its prior. The orientation coordinates are taken relative to the
/// orientation at q0 (R_ref).
template <class S>
void controller_init(const Model<S>& model, ControllerState<S>& st, const Vec6In<S>& q0) {
  detail::observer_start(model, st, q0);
  adaptation_init(st.adapt, Vec6<S>(q0));
}

/// Restarts the observer at the measured pose q (an enable after a disable or a cleared fault):
/// as controller_init, but what the adaptation learnt so far (theta^, the momentum law's filter) is kept.
template <class S>
void controller_restart(const Model<S>& model, ControllerState<S>& st, const Vec6In<S>& q) {
  detail::observer_start(model, st, q);
  adaptation_restart(st.adapt, Vec6<S>(q));
}

/// Re-references the controller at the pose of the step just taken, q (holding, at rest: where an identify run
/// starts): the orientation coordinates taken relative to the orientation there and the observer restarted there,
/// as controller_restart does, without its forward kinematics (the step's, in st.data). The step's operational
/// coordinates and analytic Jacobian are put in the new coordinates, for a reference taken from them in the next
/// tick (excitation_reference): x with phi = 0, where E(phi) = I and J_a is the geometric Jacobian. What the
/// adaptation learnt is kept.
template <class S>
void controller_rereference(ControllerState<S>& st, const Vec6In<S>& q) {
  detail::observer_here(st);
  st.os.x = st.obs.x_hat;
  st.os.Ja = st.data.J;
  adaptation_restart(st.adapt, Vec6<S>(q));
}

template <class S>
struct ForceCommand {
  Vec6<S> F;          // operational force (32)
  Vec6<S> e;          // tracking error (36)
  BiasForce<S> bias;  // h(x, x^dot) + p + f^, which the observer update (22) reuses
};

/// The force command (32) with w_e (35), the tracking error (36) and the observed filtered
/// tracking error (34), at the measured x and the observed velocity x^dot, with the estimated joint
/// friction tau_f^ (30). Psi's terms are computed into `psi` on the steps whose turn it is (`velocity`,
/// dynamics_turn), and those of the step before used otherwise.
template <class S>
ForceCommand<S> force_command(const Model<S>& model, const Gains<S>& G, const Data<S>& data, const ArmOpSpace<S>& os,
                              const Desired<S>& d, const ObserverOutput<S>& ob, const Vec6<S>& tau_f_hat,
                              PsiTerms<S>& psi, bool velocity) {
  ForceCommand<S> c;
  c.e = d.x - os.x;  // (36)
  const Vec6<S> v = d.xd + G.ks.cwiseProduct(c.e);
  const Vec6<S> eta_p = v - ob.xd_hat;  // (34)
  // Psi(x, x^dot) x^dot and Psi(x, x^dot) v in their joint-space parts, from one pass (q^dot = J^{-1} x^dot).
  if (velocity) psi = psi_terms(model, data, os, ob.qd_hat, v);
  // (35): w_e = Lambda a_r + Psi(x, x^dot) v + p + f^, a_r = x_d ddot + k_s (x_d dot - x^dot). Each term
  // is an operational_force, so their sum is one: J^{-T}[A J^{-1}(a_r - Jdot_a(q^dot, q_v)) + B(q, q^dot) q_v
  // + g + tau_f^], with f^ = J^{-T} tau_f^ (31).
  const Vec6<S> a_r = d.xdd + G.ks.cwiseProduct(d.xd - ob.xd_hat);
  const Vec6<S> w_e = operational_force(data, os, Vec6<S>(a_r - psi.jdot_yz), Vec6<S>(psi.c_yz + os.g + tau_f_hat));
  c.F = (G.ks + G.knd).cwiseProduct(eta_p) + w_e - G.ki.cwiseProduct(ob.x_tilde);  // (32)
  c.bias.tau = psi.c_yy + os.g + tau_f_hat;
  c.bias.a = psi.jdot_yy;
  return c;
}

/// A step that stops short with `status`: every output 0 but those already set (the pose and J's
/// condition of a singular or failed step); the torque 0.
template <class S>
void step_stopped(StepOutput<S>& out, std::uint32_t status) {
  out.tau.setZero();
  out.e.setZero();
  out.x_tilde.setZero();
  out.xd_hat.setZero();
  out.tau_f_hat.setZero();
  out.tau_bias.setZero();
  out.status = status;
}

/// One sample of the adaptive observer-controller: encoder angles q, desired state d (a motion
/// source's, motion.hpp). Writes every field of `out` (the control task's record of its last step,
/// without a copy of it).
template <class S>
void control_step(const Model<S>& model, const Gains<S>& G, FrictionMode mode, ControllerState<S>& st,
                  const Vec6In<S>& q, const Desired<S>& d, StepOutput<S>& out) {
  if (!math::all_finite(q) || !math::all_finite(d.x) || !math::all_finite(d.xd) || !math::all_finite(d.xdd)) {
    out.x.setZero();
    out.rcond = S(0);
    return step_stopped(out, kFaultNonFinite);
  }
  ArmOpSpace<S>& os = st.os;
  const DynamicsTurn turn = dynamics_turn(G.model_rate, st.steps++);
  opspace_update(model, st.data, os, q, st.R_ref, turn.model);
  out.rcond = os.Jf.rcond;
  out.x = os.x;
  if (!(os.Jf.rcond >= G.min_rcond)) {
    // Factoring a singular J divides by near-zeros: in fixed point those saturations are this
    // fault, not another one.
    math::take_arithmetic_fault<S>();
    return step_stopped(out, kFaultSingular);
  }
  const bool adaptive = mode == FrictionMode::kAdaptive;
  // theta^(t): the paper's law (67) or the robust law update it in the step; the momentum law's stage runs after
  // the step (adaptation_identify), so it is used as it is, without a copy.
  const bool updates = adaptive && G.adaptation != AdaptationLaw::kMomentum;
  Vec18<S> theta_next;
  if (updates) theta_next = adaptation_step(G, st.adapt, q, model.drives);
  const Vec18<S>& theta_hat = updates ? theta_next : st.adapt.theta_hat;
  const ObserverOutput<S> ob = observer_output(G, os, st.obs.x_hat, st.obs.y);
  // The regressor at q^dot(t): the friction estimate now, the adaptation in the next two samples. On a coupled
  // drive train each motor's, at the motors' rates C^-1 q^dot, its torques to the joints through C^-T.
  const bool coupled = model.drives.coupled();
  const RegressorDiagonals<S> w =
      friction_regressor_diagonals(coupled ? motor_rates(model.drives, ob.qd_hat) : ob.qd_hat, G.tau_dec);
  Vec6<S> tau_f_hat = adaptive ? friction_estimate(w, theta_hat) : Vec6<S>(Vec6<S>::Zero());
  if (coupled) tau_f_hat = joint_torques_of_motors(model.drives, tau_f_hat);
  const ForceCommand<S> c = force_command(model, G, st.data, os, d, ob, tau_f_hat, st.psi, turn.velocity);
  const Vec6<S> tau = joint_torques(os, c.F);
  const ObserverState<S> next = observer_update(G, os, st.obs.x_hat, st.obs.y, ob.x_tilde, c.F, c.bias);
  // A non-finite theta^ shows in tau: every coefficient enters tau_f^ = W theta^ as a product (0 times NaN or
  // infinity is NaN), tau_f^ enters F, and F tau (test_controller: NonFiniteFrictionEstimateStopsTheStep).
  if (!math::all_finite(tau) || !math::all_finite(next.y) || !math::all_finite(next.x_hat))
    return step_stopped(out, kFaultNonFinite);
  // A fixed-point result that saturated anywhere in the step (math::take_arithmetic_fault).
  if (math::take_arithmetic_fault<S>()) return step_stopped(out, kFaultOverflow);
  st.obs = next;
  if (updates) st.adapt.theta_hat = theta_next;
  adaptation_record(st.adapt, Vec6<S>(q), ob.qd_hat, w);
  out.tau = tau;
  out.e = c.e;
  out.x_tilde = ob.x_tilde;
  out.xd_hat = ob.xd_hat;
  out.tau_f_hat = tau_f_hat;
  out.tau_bias = c.bias.tau;
  out.status = kFaultNone;
}

/// The same, returning the step's output.
template <class S>
StepOutput<S> control_step(const Model<S>& model, const Gains<S>& G, FrictionMode mode, ControllerState<S>& st,
                           const Vec6In<S>& q, const Desired<S>& d) {
  StepOutput<S> out;
  control_step(model, G, mode, st, q, d, out);
  return out;
}

}  // namespace osc
