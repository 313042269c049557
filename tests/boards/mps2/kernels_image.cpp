// Exercises every kernel in the board's scalar (board::Scalar: float on the M4F's FPU, Q12.19 fixed
// point on the M3, or float in soft-float routines on the M3 for comparison), checks them against
// the published PUMA 560 vectors (in a PUMA build; another arm's is checked by its identities alone:
// J1's gravity 0 about a vertical base axis, c = B qd, the factors' solutions), and reports the
// instructions each takes (QEMU -icount shift=0). In fixed point, in a PUMA build, it also compares
// every kernel with the host's results bit for bit (tests/support/fixed_reference.hpp); in any build
// it requires the arithmetic flag clear. Exit status 0 = pass.
#include <cstdint>

#include "board.hpp"
#include "osc/control/jerk_profile.hpp"
#include "osc/control/sampled_loop.hpp"
#include "osc/kernels/lu.hpp"
#include "osc/control/excitation.hpp"
#include "osc/link/capture.hpp"
#include "osc/runtime/control_task.hpp"
#include "fixed_reference.hpp"
#include "osc/robot.hpp"
#include "puma560_published.hpp"
#include "text.hpp"

namespace {

using namespace osc;
namespace published = osc::test::published;
using F = board::Scalar;
constexpr bool kFixed = fixed::is_q_v<F>;

int g_failures = 0;

template <class T>
double d(T v) {
  return static_cast<double>(v);
}

void check(const char* what, double got, double want, double tol) {
  const double err = got > want ? got - want : want - got;
  if (!(err <= tol)) {
    cortex_m::text::Line()
        .str("FAIL ")
        .str(what)
        .str(" got ")
        .fix(static_cast<float>(got), 5)
        .str(" want ")
        .fix(static_cast<float>(want), 5)
        .emit();
    ++g_failures;
  }
}

/// A result the compiler must compute where it stands (in the timed scope), although nothing reads
/// it: its address escapes into an empty asm that clobbers memory.
template <class T>
void keep(const T& v) {
  asm volatile("" : : "r"(&v) : "memory");
}

/// Instructions from construction to destruction; the memory clobbers keep the timed kernel, which
/// reads the global workspace, between the two counter reads.
struct Timer {
  const char* name;
  std::uint32_t t0;
  explicit Timer(const char* n) : name(n) {
    asm volatile("" : : : "memory");
    t0 = board::cycles();
  }
  ~Timer() {
    asm volatile("" : : : "memory");
    const std::uint32_t dt = board::cycles() - t0;
    cortex_m::text::Line().str("  ").str(name).str(": ").u32(dt).str(" instructions").emit();
  }
};

// Kept out of the stack: Data, OpSpace and the controller state are a few kB each.
Model<F> g_model;
Data<F> g_data;
ArmOpSpace<F> g_os;
ControllerState<F> g_state;

/// The joint-space kernels at qn, against the published gravity, inertia and Coriolis values.
/// The payload check's fit (osc/runtime/payload_check.hpp), which runs in a tick that detects within a second of an
/// enable: the residual as a weight at the flange. Here 2.5 kg's weight at frame 6's origin and a horizontal moment, at
/// the pose joint_space_kernels left in g_data; the fit gives the mass back.
void payload_check_kernel() {
  const Vec6<F> r = g_data.J.row(2).transpose() * lit<F>(2.5 * robot::kArm.gravity) +
                    g_data.J.row(3).transpose() * lit<F>(0.5) - g_data.J.row(4).transpose() * lit<F>(0.25);
  FlangeWeight<F> w;
  {
    Timer t("flange_weight (the payload check's fit, in a tick that detects within a second of an enable)");
    w = flange_weight(g_data.J, r);
  }
  check("flange_weight: the mass of 2.5 kg's weight", static_cast<double>(w.mass), 2.5, 0.01);
}
void joint_space_kernels(const Vec6<F>& qn, const Vec6<F>& qd) {
  Vec6<F> one, g, c, tau;
  one.setOnes();
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
    keep(g);
  }
  {
    Timer t("rnea (qd = qdd = 1)");
    tau = rnea(g_model, g_data, one, one, true).tau;
    keep(tau);  // checked by nothing below
  }
  {
    Timer t("velocity_products (c, Jdot qd)");
    c = velocity_products(g_model, g_data, qd).c;
    keep(c);
  }
  {
    Timer t("coriolis_matrix (Christoffel)");
    B = coriolis_matrix(g_model, g_data, qd);
    keep(B);
  }
  if constexpr (test::kPumaBuild) {
    const double tol = 2e-3;
    check("g2", d(g(1)), published::kGravityQn[1], tol * published::kGravityQn[1]);
    check("g3", d(g(2)), published::kGravityQn[2], tol * published::kGravityQn[2]);
    check("g5", d(g(4)), published::kGravityQn[4], 2e-4);
    for (int i = 0; i < 6; ++i) {
      const double m = published::kInertiaQn[6 * i + i];
      check("M_ii", d(g_data.A(i, i)), m, 1e-3 * m + 1e-4);
    }
    check("B(1,2)", d(B(0, 1)), published::kCoriolisQn[1], 2e-3);
    check("B(2,3)", d(B(1, 2)), published::kCoriolisQn[6 + 2], 2e-3);
  } else {
    check("g1 (a vertical base axis)", d(g(0)), 0.0, 1e-3);
    check("A symmetric", d((g_data.A - g_data.A.transpose()).norm()), 0.0, 1e-3);
  }
  check("c = B qd", d((B * qd - c).norm()), 0.0, 1e-3);
}

FrictionIdentifier<F> g_identifier;

/// One joint's update of the momentum law (osc/control/identification.hpp), a sample that counts:
/// the worst a tick adds to the monitors stage with that law. From the prior, a sample of J2's
/// friction at the regressor W moves theta^'s J2 coefficients toward it and nothing else.
void identification_kernel(const Regressor<F>& W, const Vec6<F>& fr) {
  g_identifier.reset();
  Vec18<F> theta = Vec18<F>::Zero();
  const Vec18<F> theta_max = Gains<F>::paper().theta_max;
  const FrictionSample<F> s{fr(1), Vec3<F>(W(1, 1), W(1, kDof + 1), W(1, 2 * kDof + 1)), F(40), true};
  IdentifyOutcome o;
  {
    Timer t("FrictionIdentifier::update (one joint, momentum law)");
    o = g_identifier.update(1, s, true, F(0.25), F(6), theta, theta_max);
    keep(theta);
  }
  check("identifier took the sample", o == IdentifyOutcome::kUpdated ? 1.0 : 0.0, 1.0, 0.0);
  check("identifier moved J2 only", d(theta(0) + theta(2) + theta(kDof) + theta(2 * kDof + 5)), 0.0, 0.0);
  check("identifier moved J2's sum toward the sample", d(theta(kDof + 1) + theta(2 * kDof + 1)) > 0 ? 1.0 : 0.0, 1.0,
        0.0);
}

/// Friction (2) and its regressor (19), consistent with each other; returns the friction torque.
Vec6<F> friction_kernels(const Vec6<F>& qd) {
  Vec6<F> fr;
  Regressor<F> W;
  const FrictionParams<F> fp = FrictionParams<F>::from(*robot::kFrictionPresets[0], 1.0);
  {
    Timer t("friction_torque (2)");
    fr = friction_torque(fp, qd);
    keep(fr);
  }
  {
    Timer t("friction_regressor (19)");
    W = friction_regressor(qd, fp.dec);
    keep(W);
  }
  check("W theta = tau_f", d((W * fp.theta() - fr).norm()), 0.0, 1e-4);
  identification_kernel(W, fr);
  return fr;
}

/// The operational-space update at q0, and the wrist factor and Lambda at qn against the published
/// Lambda.
void operational_inertia_kernels(const Vec6<F>& q0, const Vec6<F>& qn) {
  forward_kinematics(g_model, g_data, q0);
  const Mat3<F> R_ref = g_data.R[kDof];
  {
    Timer t("opspace_update (FK, J, A, g, Ja, J factor, LDLT of A)");
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
    keep(Jg);
  }
  // The general factor (arms without a spherical wrist) at the same J: the same solutions.
  PivotedLuJacobianFactor<F> Jlu;
  {
    Timer t("PivotedLuJacobianFactor::compute (LU, exact rcond)");
    Jlu.compute(g_data.J);
    keep(Jlu);
  }
  {
    Timer t("operational_inertia (Lambda)");
    if constexpr (kArmSphericalWrist)
      Lg = operational_inertia(g_data.A, Jg);
    else
      Lg = operational_inertia(g_data.A, Jlu);
    keep(Lg);
  }
  if constexpr (test::kPumaBuild) {
    check("Lambda(1,1)", d(Lg(0, 0)), published::kLambdaQn[0], 0.05);
    check("Lambda(3,3)", d(Lg(2, 2)), published::kLambdaQn[6 * 2 + 2], 0.05);
    check("Lambda(6,6)", d(Lg(5, 5)), published::kLambdaQn[6 * 5 + 5], 2e-3);
  }
  Vec6<F> b;
  b << lit<F>(0.3), lit<F>(-0.2), lit<F>(0.1), lit<F>(0.5), lit<F>(-0.4), lit<F>(0.2);
  if constexpr (kArmSphericalWrist) {
    check("rcond(qn) > 1e-3", d(Jg.rcond) > 1e-3 ? 1.0 : 0.0, 1.0, 0.0);
    check("LU solve = block solve", d((Jlu.solve(b) - Jg.solve(b)).norm()), 0.0, 1e-3);
    check("LU solve_transpose = block", d((Jlu.solve_transpose(b) - Jg.solve_transpose(b)).norm()), 0.0, 1e-3);
  }
  // J x = b and J^T y = b solved: the residuals (in the scalar's precision).
  check("J (LU solve b) = b", d((g_data.J * Jlu.solve(b) - b).norm()), 0.0, 2e-3);
  check("J^T (LU solve_transpose b) = b", d((g_data.J.transpose() * Jlu.solve_transpose(b) - b).norm()), 0.0, 2e-3);
  check("LU rcond(qn) > 1e-3", d(Jlu.rcond) > 1e-3 ? 1.0 : 0.0, 1.0, 0.0);
  // Back to q0 for what follows.
  opspace_update(g_model, g_data, g_os, q0, R_ref);
}

/// Psi, p, f, Gamma = J^T F, the Lambda solve and Jdot qd at q0 (after opspace_update).
void operational_force_kernels(const Vec6<F>& qd, const Vec6<F>& fr) {
  Vec6<F> v, h, hb, p, f, G, l, jd;
  v << lit<F>(0.05), lit<F>(-0.02), lit<F>(0.03), lit<F>(0.01), lit<F>(0.02), lit<F>(-0.01);
  {
    Timer t("psi_quadratic h(v)");
    h = psi_quadratic(g_model, g_data, g_os, v);
    keep(h);
  }
  {
    Timer t("psi_bilinear Psi(x,y)z");
    hb = psi_bilinear(g_model, g_data, g_os, v, v);
    keep(hb);
  }
  check("Psi(v)v = h(v)", d((h - hb).norm()), 0.0, 1e-3 * (1 + d(h.norm())));
  {
    Timer t("operational_gravity p");
    p = operational_gravity(g_os);
    keep(p);
  }
  {
    Timer t("operational_friction f");
    f = operational_friction(g_os, fr);
    keep(f);  // checked by nothing below
  }
  {
    Timer t("joint_torques J^T F");
    G = joint_torques(g_os, p);
    keep(G);
  }
  check("J^T p = g", d((G - g_os.g).norm()), 0.0, 1e-3 * d(g_os.g.norm()));
  {
    Timer t("lambda_solve");
    l = lambda_solve(g_os, v);
    keep(l);
  }
  check("Lambda Lambda^-1 v = v", d((operational_inertia(g_data, g_os) * l - v).norm()), 0.0, 1e-3);
  {
    Timer t("analytic_jdot_qd");
    jd = analytic_jdot_qd(g_model, g_data, g_os, qd);
    keep(jd);
  }
}

/// The control step (observer, controller, adaptation) over a few samples: worst and mean.
void control_step_kernels(const Vec6<F>& q0) {
  const Gains<F> gains = Gains<F>::paper();
  controller_init(g_model, g_state, q0);
  const PaperMotion<F> paper{gains.trajectory, g_state.data.o[kDof]};
  std::uint32_t worst = 0, sum = 0;
  for (int k = 0; k < 20; ++k) {
    Vec6<F> q = q0;
    q(1) += lit<F>(1e-5) * F(k);
    const Desired<F> des = paper.at_time(lit<F>(1e-3) * F(k));
    const std::uint32_t t0 = board::cycles();
    const StepOutput<F> out = control_step(g_model, gains, FrictionMode::kAdaptive, g_state, q, des);
    const std::uint32_t dt = board::cycles() - t0;
    if (dt > worst) worst = dt;
    sum += dt;
    check("control_step status", static_cast<double>(out.status), 0.0, 0.0);
  }
  cortex_m::text::Line()
      .str("  control_step (observer + controller + adaptation), worst of 20: ")
      .u32(worst)
      .str(", mean ")
      .u32(sum / 20)
      .str(" instructions")
      .emit();
  check("control_step holds gravity at rest", d((g_state.obs.x_hat - g_os.x).norm()) < 1.0 ? 1.0 : 0.0, 1.0, 0.0);
}

/// A parameter set of a gain, as a board's main loop answers it (outside the tick): Lambda^-1 at the
/// start pose in double, then the observer's and the sampled loop's checks (gain_margins; the loop's
/// in float). The paper's gains keep a loop margin of 2.83 (in steps of sqrt 2) there.
void gain_check_kernels(const Vec6<F>& q0) {
  forward_kinematics(g_model, g_data, q0);
  const Mat3<F> R = g_data.R[kDof];
  opspace_update(g_model, g_data, g_os, q0, R);
  Mat6<double> li;
  GainMargins m;
  {
    Timer t("lambda_inverse in double (a param set's pose)");
    li = lambda_inverse<double>(g_data.A.template cast<double>(), g_os.Ja.template cast<double>());
    keep(li);
  }
  {
    Timer t("gain_margins (a param set of a gain: the observer's and the sampled loop's checks)");
    m = gain_margins(Gains<double>::paper(), li);
    keep(m);
  }
  check("the paper's gains: loop margin", m.loop, 2.83, 0.01);
}

/// The jerk-limited profile: plan() from a moving start (a bisection on the peak velocity) and the
/// worst at() over the move at 1 ms, as the tick calls it; the end reached.
JerkProfile<F> g_profile;
void jerk_profile_kernels() {
  const JerkLimits<F> lim{lit<F>(1), lit<F>(5), lit<F>(50)};
  {
    Timer t("JerkProfile::plan (moving start, bisection)");
    keep(g_profile.plan(lit<F>(0.2), lit<F>(0.8), lit<F>(2), lit<F>(0.38), lim));
  }
  std::uint32_t worst = 0;
  ProfileState<F> s{};
  for (std::uint64_t k = 0; k < 700; ++k) {
    const F t = math::ratio<F>(k, 1000);
    const std::uint32_t t0 = board::cycles();
    s = g_profile.at(t);
    keep(s);
    const std::uint32_t dt = board::cycles() - t0;
    if (dt > worst) worst = dt;
  }
  cortex_m::text::Line().str("  JerkProfile::at, worst of 700: ").u32(worst).str(" instructions").emit();
  check("profile ends at the target", d(s.p), 0.38, 1e-4);
}

/// A stream (issue 23): setpoints at 50 Hz, every axis moving (30 mm each, 0.1 rad of each angle) over
/// 1 s, ending there, without or with their velocities; the generator's worst tick (the follower's
/// six axes) with the stop lead the tick's limit check takes, and done at the last setpoint.
MotionGenerator<F> g_stream_gen;
void stream_kernels(const Vec6<F>& x0, const Mat3<F>& R, bool velocity) {
  MotionGenerator<F>& gen = g_stream_gen;
  gen.hold({x0.template head<3>(), R}, R);
  gen.start_stream(20, false, CartesianLimits<F>::defaults(), 2);
  std::uint32_t worst = 0;
  MotionEvents ev;
  Vec6<F> end = x0, v;
  v << lit<F>(0.03), lit<F>(0.03), lit<F>(0.03), lit<F>(0.1), lit<F>(0.1), lit<F>(0.1);
  for (std::uint64_t k = 0; k < 4000 && ev.done_id == 0; ++k) {
    if (k % 20 == 0 && k <= 1000) {
      const F s = math::ratio<F>(k, 1000);
      end = x0;
      for (int i = 0; i < 3; ++i) end(i) += lit<F>(0.03) * s;
      for (int i = 3; i < 6; ++i) end(i) += lit<F>(0.1) * s;
      gen.stream_setpoint(end, k == 1000, velocity ? &v : nullptr);
    }
    const std::uint32_t t0 = board::cycles();
    keep(gen.at_tick(k, params::kControlHz, ev));
    keep(gen.stream_stop_lead());  // the tick's joint-limit check takes it (motion_limits_reached)
    const std::uint32_t dt = board::cycles() - t0;
    if (dt > worst) worst = dt;
  }
  cortex_m::text::Line()
      .str(velocity ? "  MotionGenerator::at_tick, a stream with velocities, and its stop lead, worst tick: "
                    : "  MotionGenerator::at_tick, a stream, and its stop lead, worst tick: ")
      .u32(worst)
      .str(" instructions")
      .emit();
  check("the stream ends done at its last setpoint",
        d((gen.hold_pose().p - end.template head<3>()).norm()) + (ev.done_id == 2 ? 0 : 1), 0.0, 1e-4);
}

/// The motion generator (issue 23): a move's plan and path check (both when a command is prepared,
/// outside the tick), and the generator's worst tick over the move (a line and a rotation) at 1 ms.
MotionGenerator<F> g_gen;
CartesianMove<F> g_move;
void motion_kernels(const Vec6<F>& q0) {
  forward_kinematics(g_model, g_data, q0);
  const Pose<F> from{g_data.o[kDof], g_data.R[kDof]};
  Pose<F> to = from;
  to.p += Vec3<F>(lit<F>(0.05), lit<F>(-0.04), lit<F>(0.03));
  to.R = axis_rotation<F>(Vec3<F>::UnitZ(), lit<F>(0.2)) * from.R;
  const CartesianLimits<F> lim = CartesianLimits<F>::defaults();
  {
    Timer t("CartesianMove::plan (a line and a rotation, synchronised)");
    keep(g_move.plan(from, to, lim, from.R));
  }
  PathCheck<F> pc;
  {
    Timer t("check_path (16 samples and the end, the sampled loop judged at each)");
    const loop::PathLoop gains = loop::path_loop(Gains<double>::paper(), params::kPathLoopMargin);  // as command_prep
    pc = check_path(g_model, g_data, g_move, from.R, q0, &gains);
  }
  check("the move's path is clear", static_cast<double>(pc.status), 0.0, 0.0);
  g_gen.hold(from, from.R);
  g_gen.push(g_move, 1);
  g_gen.start_moves(0);
  std::uint32_t worst = 0;
  MotionEvents ev;
  const std::uint64_t n = static_cast<std::uint64_t>(static_cast<double>(g_move.duration()) * 1000) + 2;
  Desired<F> des{};
  for (std::uint64_t k = 0; k < n; ++k) {
    const std::uint32_t t0 = board::cycles();
    des = g_gen.at_tick(k, params::kControlHz, ev);
    keep(des);
    const std::uint32_t dt = board::cycles() - t0;
    if (dt > worst) worst = dt;
  }
  cortex_m::text::Line().str("  MotionGenerator::at_tick, a move, worst tick: ").u32(worst).str(" instructions").emit();
  check("the move ends done at its target", d((des.x.template head<3>() - to.p).norm()) + (ev.done_id == 1 ? 0 : 1),
        0.0, 1e-4);
  check("no saturation in fixed point", math::take_arithmetic_fault<F>() ? 1.0 : 0.0, 0.0, 0.0);
  stream_kernels(des.x, from.R, false);
  stream_kernels(des.x, from.R, true);
}

/// The on-board capture's cost to the tick (issue 58, osc/link/capture.hpp): sample() idle, and armed with one and
/// with eight channels (the signals of the list in turn, from a task at the start pose), worst of 50 ticks.
ControlTask<F> g_task;
float g_capture_ring[pil::kCaptureValues];
SignalCapture g_capture;
std::uint32_t capture_worst(int channels) {
  pil::CaptureFrame f;
  f.op = pil::kCaptureOpArm;
  f.channels = static_cast<std::uint8_t>(channels);
  for (int c = 0; c < channels; ++c) f.signal[c] = static_cast<std::uint8_t>((c + 6) % pil::kCaptureSignalCount);
  f.trigger = pil::kCaptureTriggerFault;
  f.pre = 10;
  f.divider = 1;
  check("the capture arms", g_capture.handle(g_task, f).status, 0.0, 0.0);
  std::uint32_t worst = 0;
  for (int k = 0; k < 50; ++k) {
    ++g_task.tick;
    const std::uint32_t t0 = board::cycles();
    g_capture.sample(g_task);
    const std::uint32_t dt = board::cycles() - t0;
    if (dt > worst) worst = dt;
  }
  return worst;
}
void capture_kernels(const Vec6<F>& q0) {
  g_task.init(Model<F>::of(robot::kArm), Gains<F>::paper(), FrictionMode::kAdaptive, q0, 0);
  g_capture.attach(g_capture_ring, pil::kCaptureValues);
  {
    Timer t("SignalCapture::sample, idle (every tick while no capture is armed)");
    g_capture.sample(g_task);
  }
  const std::uint32_t one = capture_worst(1), eight = capture_worst(8);
  cortex_m::text::Line()
      .str("  SignalCapture::sample, 1 channel armed, worst of 50: ")
      .u32(one)
      .str(" instructions")
      .emit();
  cortex_m::text::Line()
      .str("  SignalCapture::sample, 8 channels armed, worst of 50: ")
      .u32(eight)
      .str(" instructions")
      .emit();
}

/// An identify run's cost (issue 57): its check (check_excitation, where the command is prepared: outside the
/// tick), and in the tick the reference stage's excitation_reference (the Fourier series at the tick, mapped into the
/// controller's coordinates) and the step stage's IdentifySampler::tick (the run's signals into its ring), and in the
/// main loop after each tick IdentifyRun::poll (the run's filter, a sample's regression rows every
/// params::kRunSampleTicks), each the worst of the run's first 2 000 ticks, from the task at the start pose.
ExcitationMotion<F> g_excitation;
IdentifyRun<F> g_identify_run;
void identify_kernels(const Vec6<F>& q0) {
  // One whole check, as the identify command's preparation (command_prep.hpp) runs it at each scale it tries: every
  // tick of a period, the sampled loop judged at each. On the PUMA at the tests' identify pose (q5 = 1.2 rad), at
  // the scale it passes at, 0.656; the preparation checks 1, then 0.729 and 0.590 and 0.656 (halving), the failing
  // ones stopping at a tick along the way, so a run costs at most four of these (excitation_check.hpp).
  Vec6<F> q_run = q0;
  if (test::kPumaBuild) q_run(4) = lit<F>(1.2);
  const ExcitationLimits<F> lim = ExcitationLimits<F>::defaults();
  check("the excitation plans", static_cast<double>(g_excitation.plan(q_run, lim)), 0.0, 0.0);
  g_excitation.set_scale(lit<F>(0.6561));
  ExcitationCheck<F> ec;
  {
    Timer t("check_excitation, one scale (10 001 ticks, the sampled loop judged at each)");
    const loop::PathLoop gains = loop::path_loop(Gains<double>::paper(), params::kPathLoopMargin);
    forward_kinematics(g_model, g_data, q_run);
    ec = check_excitation(g_model, g_data, g_excitation, Mat3<F>(g_data.R[kDof]), lim, &gains);
  }
  if (test::kPumaBuild)
    check("the identify pose's excitation passes at 0.656", static_cast<double>(ec.status), 0.0, 0.0);
  g_task.gen.start_excitation(g_excitation, g_task.tick, 7);
  g_identify_run.start(7, payload_mask::kNone, g_model, g_model);
  std::uint32_t worst_ref = 0, worst_record = 0, worst_poll = 0;
  MotionEvents ev;
  const Vec6<F> dec = g_task.gains.tau_dec;
  int taken = 0;
  for (int k = 0; k < 2000; ++k) {
    ++g_task.tick;
    std::uint32_t t0 = board::cycles();
    const Desired<F> des = excitation_reference(g_task, ev);
    keep(des);
    std::uint32_t dt = board::cycles() - t0;
    if (dt > worst_ref) worst_ref = dt;
    const JointSample<F> js = g_excitation.at_tick(static_cast<std::uint64_t>(k + 1));
    t0 = board::cycles();
    g_task.identify.tick(7, js.q, g_task.last.tau, js.qd, dec);
    dt = board::cycles() - t0;
    if (dt > worst_record) worst_record = dt;
    t0 = board::cycles();
    taken += g_identify_run.poll(g_task.identify);
    dt = board::cycles() - t0;
    if (dt > worst_poll) worst_poll = dt;
  }
  cortex_m::text::Line()
      .str("  excitation_reference, worst of 2000 ticks: ")
      .u32(worst_ref)
      .str(" instructions")
      .emit();
  cortex_m::text::Line()
      .str("  IdentifySampler::tick (the run's signals into the ring), worst of 2000 ticks: ")
      .u32(worst_record)
      .str(" instructions")
      .emit();
  cortex_m::text::Line()
      .str("  IdentifyRun::poll after a tick (main loop: the filter, a sample's rows every 5th), worst of 2000: ")
      .u32(worst_poll)
      .str(" instructions")
      .emit();
  check("the run's samples", static_cast<double>(taken), 2000.0 / params::kRunSampleTicks, 0.0);
  check("none lost", static_cast<double>(g_identify_run.lost()), 0.0, 0.0);
  // The solve at the run's end (main loop, once): the three passes of the weighted least squares and the report's
  // sigmas, in doubles (soft-float on both cores). Its cost does not depend on the samples taken; the rest of the
  // period first (untimed), so that every joint has its rows and the solve goes all the way.
  for (int k = 2000; k < static_cast<int>(excitation::kPeriodTicks); ++k) {
    ++g_task.tick;
    const JointSample<F> js = g_excitation.at_tick(static_cast<std::uint64_t>(k + 1));
    g_task.identify.tick(7, js.q, g_task.last.tau, js.qd, dec);
    g_identify_run.poll(g_task.identify);
  }
  IdentifyReport report;
  {
    Timer t("IdentifyRun::finish, the estimate's solve at the run's end (main loop)");
    report = g_identify_run.finish();
  }
  check("the solve went through (not too few samples, not singular)",
        report.status == IdentifyStatus::kTooFewSamples || report.status == IdentifyStatus::kIllConditioned ? 1.0 : 0.0,
        0.0, 0.0);
  check("no saturation in fixed point", math::take_arithmetic_fault<F>() ? 1.0 : 0.0, 0.0, 0.0);
}

/// In fixed point: every kernel against the host's Q12.19 results, bit for bit, and the flags clear
/// (the committed values are the PUMA's; another arm's fixed point is compared with the host's in
/// closed loop, motion_tour_qemu).
void fixed_reference_check() {
  if constexpr (kFixed && test::kPumaBuild) {
    // Every kernel against the host's Q12.19 results, bit for bit.
    int n = 0, mismatches = 0;
    const int count = static_cast<int>(sizeof(reference::kValues) / sizeof(reference::kValues[0]));
    auto emit = [&](const char* name, const auto& m) {
      for (int j = 0; j < m.cols(); ++j)
        for (int i = 0; i < m.rows(); ++i, ++n) {
          const std::int32_t want = n < count ? reference::kValues[n] : 0;
          if (m(i, j).raw() == want) continue;
          if (++mismatches <= 5)
            cortex_m::text::Line()
                .str("FAIL reference ")
                .str(name)
                .str(" word ")
                .i32(n)
                .str(": got ")
                .i32(m(i, j).raw())
                .str(" want ")
                .i32(want)
                .emit();
        }
    };
    fixed::take_flags();
    for (const reference::Case& rc : reference::kCases) reference::kernel_outputs(rc, g_model, g_data, g_os, emit);
    reference::step_outputs(g_model, g_state, emit);
    const std::uint32_t flags = fixed::take_flags();
    cortex_m::text::Line()
        .str("reference values (host, Q12.19): ")
        .i32(n)
        .str(" words, ")
        .i32(mismatches)
        .str(" differ; arithmetic flags ")
        .u32(flags)
        .emit();
    if (n != count) ++g_failures;
    if (flags != 0) ++g_failures;
    g_failures += mismatches;
  }
}

}  // namespace

int main() {
  board::cycle_counter_init();
  cortex_m::text::Line()
      .str("kernels_image: ")
      .str(robot::kArm.name)
      .str(" kernels in ")
      .str(board::kScalarName)
      .str(" on ")
      .str(board::kCore)
      .str(kArmSphericalWrist ? ", J by its blocks (a spherical wrist)" : ", J by a pivoted LU")
      .emit();
  g_model = Model<F>::of(robot::kArm);
  // The published vectors' pose on the PUMA; the start pose on another arm.
  const Vec6<F> qn = joint_vector<F>(test::kPumaBuild ? puma560::kQn : robot::kQStart),
                q0 = joint_vector<F>(robot::kQStart);
  Vec6<F> qd;
  qd << 1, 2, 3, 1, 2, 3;
  joint_space_kernels(qn, qd);
  payload_check_kernel();
  const Vec6<F> fr = friction_kernels(qd);
  operational_inertia_kernels(q0, qn);
  operational_force_kernels(qd, fr);
  control_step_kernels(q0);
  gain_check_kernels(q0);
  jerk_profile_kernels();
  fixed_reference_check();
  motion_kernels(q0);
  capture_kernels(q0);
  identify_kernels(q0);
  cortex_m::text::Line().str("stack used: ").u32(board::stack_used()).str(" bytes").emit();
  cortex_m::text::Line().str(g_failures ? "FAILED checks: " : "all checks passed: failures = ").i32(g_failures).emit();
  return g_failures ? 1 : 0;
}
