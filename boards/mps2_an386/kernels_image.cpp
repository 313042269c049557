// Exercises every kernel in float on the Cortex-M4F, checks them against the published PUMA 560
// vectors, and reports the instructions each takes (QEMU -icount shift=0). Exit status 0 = pass.
#include <cstdint>

#include "board.hpp"
#include "osc/runtime/control_task.hpp"
#include "osc/robot.hpp"
#include "text.hpp"

namespace {

using namespace osc;
using F = float;

int g_failures = 0;

void check(const char* what, F got, F want, F tol) {
  const F err = math::abs(got - want);
  if (!(err <= tol)) {
    cortex_m::text::Line().str("FAIL ").str(what).str(" got ").fix(got, 5).str(" want ").fix(want, 5).emit();
    ++g_failures;
  }
}

struct Timer {
  const char* name;
  std::uint32_t t0 = board::cycles();
  explicit Timer(const char* n) : name(n) {}
  ~Timer() {
    const std::uint32_t dt = board::cycles() - t0;
    cortex_m::text::Line().str("  ").str(name).str(": ").u32(dt).str(" instructions").emit();
  }
};

// Kept out of the stack: Data, OpSpace and the controller state are a few kB each.
Model<F> g_model;
Data<F> g_data;
OpSpace<F> g_os;
ControllerState<F> g_state;

}  // namespace

int main() {
  board::cycle_counter_init();
  board::semihost::write("kernels_image: PUMA 560 kernels in float on Cortex-M4F\n");
  g_model = Model<F>::of(robot::kArm);
  const Vec6<F> qn = joint_vector<F>(puma560::kQn), q0 = joint_vector<F>(robot::kQStart);
  Vec6<F> qd, one;
  qd << 1, 2, 3, 1, 2, 3;
  one.setOnes();
  Vec6<F> g, c, tau;
  Mat6<F> B;
  {
    Timer t("forward_kinematics");
    forward_kinematics(g_model, g_data, qn);
  }
  {
    Timer t("geometric_jacobian");
    geometric_jacobian(g_data);
  }
  {
    Timer t("joint_inertia (CRBA)");
    joint_inertia(g_model, g_data);
  }
  {
    Timer t("gravity_torques");
    g = gravity_torques(g_model, g_data);
  }
  {
    Timer t("rnea (qd = qdd = 1)");
    tau = rnea(g_model, g_data, one, one, true).tau;
  }
  {
    Timer t("velocity_products (c, Jdot qd)");
    c = velocity_products(g_model, g_data, qd).c;
  }
  {
    Timer t("coriolis_matrix (Christoffel)");
    B = coriolis_matrix(g_model, g_data, qd);
  }
  const F tol = 2e-3f;
  check("g2", g(1), 31.6399f, tol * 31.6399f);
  check("g3", g(2), 6.0351f, tol * 6.0351f);
  check("g5", g(4), 0.0283f, 2e-4f);
  const F Mdiag[6] = {3.6594f, 4.4137f, 0.9378f, 0.1925f, 0.1713f, 0.1941f};
  for (int i = 0; i < 6; ++i) check("M_ii", g_data.A(i, i), Mdiag[i], 1e-3f * Mdiag[i] + 1e-4f);
  // rne(qn, 1, 1) without the toolbox's friction: published value minus that friction.
  check("B(1,2)", B(0, 1), -2.0494f, 2e-3f);
  check("B(2,3)", B(1, 2), 1.9287f, 2e-3f);
  check("c = B qd", (B * qd - c).norm(), 0.0f, 1e-3f);
  (void)tau;

  Vec6<F> fr;
  Regressor<F> W;
  FrictionParams<F> fp{};
  for (int i = 0; i < kDof; ++i) {
    fp.vis(i) = static_cast<F>(robot::kFrictionPaper.vis[i]);
    fp.cou(i) = static_cast<F>(robot::kFrictionPaper.cou[i]);
    fp.sti(i) = static_cast<F>(robot::kFrictionPaper.sti[i]);
    fp.dec(i) = 1;
  }
  {
    Timer t("friction_torque (2)");
    fr = friction_torque(fp, qd);
  }
  {
    Timer t("friction_regressor (19)");
    W = friction_regressor(qd, fp.dec);
  }
  check("W theta = tau_f", (W * fp.theta() - fr).norm(), 0.0f, 1e-4f);

  forward_kinematics(g_model, g_data, q0);
  const Mat3<F> R_ref = g_data.R[kDof];
  {
    Timer t("opspace_update (FK, J, A, g, Ja, LU, LLT, Lambda)");
    opspace_update(g_model, g_data, g_os, q0, R_ref);
  }
  SphericalWristJacobianFactor<F> Jg;
  Mat6<F> Lg;
  forward_kinematics(g_model, g_data, qn);
  geometric_jacobian(g_data);
  joint_inertia(g_model, g_data);
  {
    Timer t("SphericalWristJacobianFactor::compute");
    Jg.compute(g_data.J);
  }
  {
    Timer t("operational_inertia (Lambda)");
    Lg = operational_inertia(g_data.A, Jg);
  }
  check("Lambda(1,1)", Lg(0, 0), 17.2954f, 0.05f);
  check("Lambda(3,3)", Lg(2, 2), 13.3348f, 0.05f);
  check("Lambda(6,6)", Lg(5, 5), 0.5791f, 2e-3f);
  check("rcond(qn) > 1e-3", Jg.rcond > 1e-3f ? 1.0f : 0.0f, 1.0f, 0.0f);

  opspace_update(g_model, g_data, g_os, q0, R_ref);
  Vec6<F> v, h, hb, p, f, G, l, jd;
  v << 0.05f, -0.02f, 0.03f, 0.01f, 0.02f, -0.01f;
  {
    Timer t("psi_quadratic h(v)");
    h = psi_quadratic(g_model, g_data, g_os, v);
  }
  {
    Timer t("psi_bilinear Psi(x,y)z");
    hb = psi_bilinear(g_model, g_data, g_os, v, v);
  }
  check("Psi(v)v = h(v)", (h - hb).norm(), 0.0f, 1e-3f * (1 + h.norm()));
  {
    Timer t("operational_gravity p");
    p = operational_gravity(g_os);
  }
  {
    Timer t("operational_friction f");
    f = operational_friction(g_os, fr);
  }
  {
    Timer t("joint_torques J^T F");
    G = joint_torques(g_os, p);
  }
  check("J^T p = g", (G - g_os.g).norm(), 0.0f, 1e-3f * g_os.g.norm());
  {
    Timer t("lambda_solve");
    l = lambda_solve(g_os, v);
  }
  check("Lambda Lambda^-1 v = v", (g_os.Lambda * l - v).norm(), 0.0f, 1e-3f);
  {
    Timer t("analytic_jdot_qd");
    jd = analytic_jdot_qd(g_model, g_data, g_os, qd);
  }
  (void)f;

  // The full control step (observer, controller, adaptation), a few samples.
  const Gains<F> gains = Gains<F>::paper();
  controller_init(g_model, g_state, q0);
  std::uint32_t worst = 0;
  for (int k = 0; k < 20; ++k) {
    Vec6<F> q = q0;
    q(1) += 1e-5f * static_cast<F>(k);
    const std::uint32_t t0 = board::cycles();
    const StepOutput<F> out = control_step(g_model, gains, FrictionMode::kAdaptive, g_state, q, 1e-3f * static_cast<F>(k));
    const std::uint32_t dt = board::cycles() - t0;
    if (dt > worst) worst = dt;
    check("control_step status", static_cast<F>(out.status), 0.0f, 0.0f);
  }
  cortex_m::text::Line().str("  control_step (observer + controller + adaptation), worst of 20: ").u32(worst).str(" instructions").emit();
  check("control_step holds gravity at rest", (g_state.obs.x_hat - g_os.x).norm() < 1.0f ? 1.0f : 0.0f, 1.0f, 0.0f);

  cortex_m::text::Line().str("stack used: ").u32(board::stack_used()).str(" bytes").emit();
  cortex_m::text::Line().str(g_failures ? "FAILED checks: " : "all checks passed: failures = ").i32(g_failures).emit();
  return g_failures ? 1 : 0;
}
