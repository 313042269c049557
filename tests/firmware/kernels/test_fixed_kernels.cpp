// Accuracy of the fixed-point kernels (Q12.19, osc/kernels/fixed.hpp) against double at 1000
// random states within the joint limits, with the error budget of each kernel stated here and in
// docs/fixed_point.md.
//
// The states: test::RandomStates::q_nonsingular (every joint within its limits, |sin q5| and
// |cos(q3 + 0.047)| >= 0.2) within the fixed-point controller's domain: Jacobian reciprocal
// condition >= 0.1 (0.28 at the start pose of the task), every output of the kernels (in double) at
// most kDomain = 1024 in magnitude, a quarter of the Q12.19 range (along the task Lambda stays below
// 75, the forces below 100 N), and for the control step the torques within the amplifiers' limits
// (beyond, the DACs clip). Near the shoulder singularity (the wrist centre over the joint-1 axis,
// which q_nonsingular does not exclude) Lambda grows as 1/sigma_min^2 and Psi as 1/sigma_min^3,
// beyond any 32-bit format: there the fixed-point kernels must saturate with the flag raised (the
// supervisor's `overflow` fault) or stay accurate (checked for the kernels; reported for the step,
// which is ill-conditioned there in any precision). Every fixed-point computation in the domain must
// leave the flag clear.
//
// Budgets: absolute, in the kernel's units, the largest error over every entry, about twice the
// worst error measured (printed). The Q12.19 resolution (1.9e-6) explains them: FK and J are sums of
// a few rounded products of lengths < 1 m (a few LSB); A, g, c accumulate through the six links
// (tens of LSB times the masses and lengths); Lambda, p and Psi multiply by the inverses of the 3x3
// blocks of J, whose cofactors are rounded before the division by det (3.5e-4 of the largest entry).
// The control step's torque amplifies the few-LSB error of x through the gains (k (k_s + k_nd) +
// k_s Lambda k, about 3e5 N/m at Lambda = 30): a torque error of up to a few N m, which is at most
// half of what one encoder count (50 um at the tip) does to the same controller in double at the
// same state (that relative budget is checked state by state).
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "osc/control/controller.hpp"
#include "fixed_reference.hpp"
#include "osc/runtime/io.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

constexpr int kStates = 1000;
/// The domain of the fixed-point kernels (see the file comment).
constexpr double kDomain = 1024;
constexpr double kDomainRcond = 0.1;
/// Outside the domain, unflagged results must still be accurate to this error relative to their
/// largest entry.
constexpr double kOutsideRelative = 2e-2;

// The budgets (absolute; units of each kernel).
constexpr double kBudgetPosition = 1.2e-5;  // FK: frame-6 origin [m]
constexpr double kBudgetRotation = 1.4e-5;  // FK: R6 entries [1]
constexpr double kBudgetPhi = 1.4e-5;       // FK: orientation coordinates [rad] (atan2, asin)
constexpr double kBudgetJacobian = 1.4e-5;  // J, geometric [m/rad, 1]
constexpr double kBudgetInertia = 1.6e-4;   // A [kg m^2]
constexpr double kBudgetGravity = 2e-3;     // g [N m]
constexpr double kBudgetVelocity = 1.4e-4;  // c [N m], |qd_i| <= 1 rad/s
constexpr double kBudgetLambda = 0.3;       // Lambda [kg, kg m, kg m^2]
constexpr double kBudgetOpGravity = 3e-2;   // p [N, N m]
constexpr double kBudgetPsi = 0.12;         // h(v) = Psi(x, v) v [N, N m], |v| <= 0.2
constexpr double kBudgetRegressor = 4e-6;   // W_j [rad/s, 1]
constexpr double kBudgetTau = 3.0;          // control_step tau [N m]
constexpr double kBudgetQdHat = 1e-2;       // control_step's observed joint velocity q^dot [rad/s]
constexpr double kBudgetTauPerCount = 0.5;  // ... and at most this fraction of one encoder count's effect

/// Largest absolute difference between a fixed-point and a double Eigen object.
template <class A, class B>
double err(const A& fixed_value, const B& double_value) {
  return (fixed_value.template cast<double>() - double_value).cwiseAbs().maxCoeff();
}

struct Worst {
  double v = 0;
  void operator()(double e) { v = std::max(v, e); }
};

/// Largest magnitude of the double results.
template <class... V>
double largest(const V&... v) {
  double m = 0;
  ((m = std::max(m, v.cwiseAbs().maxCoeff())), ...);
  return m;
}

TEST(FixedKernels, AgreeWithDoubleWithinTheirBudgets) {
  test::RandomStates rs;
  const Model<double> md = Model<double>::of(robot::kArm);
  const Model<Fixed> mf = Model<Fixed>::of(robot::kArm);
  auto dd = std::make_unique<Data<double>>();
  auto df = std::make_unique<Data<Fixed>>();
  auto od = std::make_unique<ArmOpSpace<double>>();
  auto of = std::make_unique<ArmOpSpace<Fixed>>();
  Worst wp, wR, wphi, wJ, wA, wg, wc, wL, wpg, wh, wW, outside_rel, wLr, whr, wpgr;
  double max_lambda = 0;
  int in_domain = 0, outside = 0, outside_flagged = 0;
  fixed::take_flags();
  while (in_domain < kStates) {
    const int k = in_domain + outside;
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(1.0), v = rs.vec(0.2);
    // The reference orientation: the state's own (phi = 0) or a nearby one (phi up to ~0.3 rad).
    forward_kinematics(md, *dd, Vec6<double>(k % 2 ? q : Vec6<double>(q + rs.vec(0.15))));
    const Mat3<double> R_ref = dd->R[kDof].cast<Fixed>().cast<double>();
    const Vec6<Fixed> qf = q.cast<Fixed>(), qdf = qd.cast<Fixed>(), vf = v.cast<Fixed>();
    // The double kernels see the same quantised inputs.
    const Vec6<double> qq = qf.cast<double>(), qdq = qdf.cast<double>(), vq = vf.cast<double>();
    const Vec6<Fixed> dec = Vec6<Fixed>::Constant(Fixed(params::kTauDec));
    ASSERT_EQ(fixed::take_flags(), 0u);
    Vec6<double> c, pg, h;
    Vec6<Fixed> cf, pgf, hf;
    Regressor<double> W;
    Regressor<Fixed> Wf;
    {
      test::NoMalloc guard;
      opspace_update(md, *dd, *od, qq, R_ref);
      opspace_update(mf, *df, *of, qf, Mat3<Fixed>(R_ref.cast<Fixed>()));
      c = velocity_products(md, *dd, qdq).c;
      cf = velocity_products(mf, *df, qdf).c;
      pg = operational_gravity(*od);
      pgf = operational_gravity(*of);
      h = psi_quadratic(md, *dd, *od, vq);
      hf = psi_quadratic(mf, *df, *of, vf);
      W = friction_regressor(qdq, Vec6<double>(Vec6<double>::Constant(params::kTauDec)));
      Wf = friction_regressor(qdf, dec);
    }
    const Mat6<double> Ld = operational_inertia(*dd, *od);
    const Mat6<Fixed> Lf = operational_inertia(*df, *of);
    const bool flagged = fixed::take_flags() != 0;
    if (largest(Ld, pg, h, c, od->g) > kDomain || od->Jf.rcond < kDomainRcond) {
      ++outside;
      if (flagged) {
        ++outside_flagged;
      } else {
        const double rel = std::max({err(Lf, Ld) / largest(Ld), err(hf, h) / largest(h), err(pgf, pg) / largest(pg)});
        outside_rel(rel);
        EXPECT_LE(rel, kOutsideRelative) << "an unflagged, inaccurate result at state " << k;
      }
      continue;
    }
    ++in_domain;
    EXPECT_FALSE(flagged) << "state " << k;
    wp(err(df->o[kDof], dd->o[kDof]));
    wR(err(df->R[kDof], dd->R[kDof]));
    wphi(err(Vec3<Fixed>(of->x.tail<3>()), Vec3<double>(od->x.tail<3>())));
    wJ(err(df->J, dd->J));
    wA(err(df->A, dd->A));
    wg(err(of->g, od->g));
    wL(err(Lf, Ld));
    wLr(err(Lf, Ld) / largest(Ld));
    whr(err(hf, h) / largest(h));
    wpgr(err(pgf, pg) / largest(pg));
    max_lambda = std::max(max_lambda, largest(Ld));
    wc(err(cf, c));
    wpg(err(pgf, pg));
    wh(err(hf, h));
    wW(err(Wf, W));
  }
  std::printf("outside the domain: %d states (%.1f %%), %d of them flagged, the others' Lambda within %.1e relative\n",
              outside, 100.0 * outside / (outside + in_domain), outside_flagged, outside_rel.v);
  std::printf("fixed vs double, worst |error| over %d states (budget):\n", kStates);
  std::printf("  FK position %.2e m (%.1e), R %.2e (%.1e), phi %.2e rad (%.1e)\n", wp.v, kBudgetPosition, wR.v,
              kBudgetRotation, wphi.v, kBudgetPhi);
  std::printf("  J %.2e (%.1e), A %.2e kg m^2 (%.1e), g %.2e N m (%.1e), c %.2e N m (%.1e)\n", wJ.v, kBudgetJacobian,
              wA.v, kBudgetInertia, wg.v, kBudgetGravity, wc.v, kBudgetVelocity);
  std::printf("  Lambda %.2e (%.1e; largest |Lambda_ij| %.1f), p %.2e (%.1e), Psi %.2e (%.1e), W %.2e (%.1e)\n", wL.v,
              kBudgetLambda, max_lambda, wpg.v, kBudgetOpGravity, wh.v, kBudgetPsi, wW.v, kBudgetRegressor);
  std::printf("  relative to the largest entry: Lambda %.2e, p %.2e, Psi %.2e\n", wLr.v, wpgr.v, whr.v);
  EXPECT_LE(wp.v, kBudgetPosition);
  EXPECT_LE(wR.v, kBudgetRotation);
  EXPECT_LE(wphi.v, kBudgetPhi);
  EXPECT_LE(wJ.v, kBudgetJacobian);
  EXPECT_LE(wA.v, kBudgetInertia);
  EXPECT_LE(wg.v, kBudgetGravity);
  EXPECT_LE(wc.v, kBudgetVelocity);
  EXPECT_LE(wL.v, kBudgetLambda);
  EXPECT_LE(wpg.v, kBudgetOpGravity);
  EXPECT_LE(wh.v, kBudgetPsi);
  EXPECT_LE(wW.v, kBudgetRegressor);
}

/// A controller state in double and the same state in fixed point.
template <class S>
void set_state(ControllerState<S>& st, const Mat3<double>& R_ref, const Vec6<double>& x_hat, const Vec6<double>& y,
               const Vec18<double>& theta, const Vec6<double>& q_prev, const Vec6<double>& qd1,
               const Vec6<double>& qd2) {
  st.R_ref = R_ref.cast<S>();
  st.obs.x_hat = x_hat.cast<S>();
  st.obs.y = y.cast<S>();
  st.adapt.theta_hat = theta.cast<S>();
  st.adapt.q_prev = q_prev.cast<S>();
  st.adapt.qd_hat_prev = qd1.cast<S>();
  st.adapt.qd_hat_prev2 = qd2.cast<S>();
  // The regressors the two previous samples recorded, at the kernel's own rounding of q^dot.
  const Vec6<S> dec = Vec6<S>::Constant(lit<S>(params::kTauDec));
  st.adapt.w_prev = friction_regressor_diagonals(st.adapt.qd_hat_prev, dec);
  st.adapt.w_prev2 = friction_regressor_diagonals(st.adapt.qd_hat_prev2, dec);
  st.adapt.samples = 2;
}

/// v rounded to Q12.19 (the double controller starts from exactly the fixed-point state).
template <class V>
auto quantised(const V& v) {
  return v.template cast<Fixed>().template cast<double>().eval();
}

TEST(FixedKernels, ControlStepTorqueAgreesWithDoubleWithinItsBudget) {
  test::RandomStates rs;
  const Model<double> md = Model<double>::of(robot::kArm);
  const Model<Fixed> mf = Model<Fixed>::of(robot::kArm);
  const Gains<double> gd = Gains<double>::paper();
  const Gains<Fixed> gf = gd.cast<Fixed>();
  auto sd = std::make_unique<ControllerState<double>>();
  auto sf = std::make_unique<ControllerState<Fixed>>();
  double worst = 0, worst_rel = 0, max_tau = 0;
  Worst outside_rel;
  double outside_rcond = 0, worst_vs_count = 0;
  int skipped_at_rest = 0;
  double worst_qd_hat = 0;
  int in_domain = 0, outside = 0, outside_flagged = 0;
  fixed::take_flags();
  while (in_domain < kStates) {
    const int k = in_domain + outside;
    // A state the controller meets in service: a time along the task, tracking errors within the
    // tracking monitor's bounds (3 mm and 5 mrad per axis; it faults at 10 mm, 20 mrad), the observer
    // within 1 mm and 1 mrad of x, observed velocities up to 0.1 m/s and 0.3 rad/s, theta^ up to a
    // sixth of its bounds (twice the paper's friction or more).
    const Vec6<double> q = quantised(rs.q_nonsingular());
    const double t = static_cast<double>(Fixed(30.0 * 0.5 * (rs.u(rs.rng) + 1)));
    const Vec3<double> zero = Vec3<double>::Zero();
    const Vec3<double> offset = trajectory(gd.trajectory, zero, t).x.head<3>();
    forward_kinematics(md, sd->data, q);
    const Vec3<double> p0 = quantised(Vec3<double>(sd->data.o[kDof] - offset + 0.003 * rs.vec(1.0).head<3>()));
    forward_kinematics(md, sd->data, Vec6<double>(q + rs.vec(0.005)));
    const Mat3<double> R_ref = quantised(sd->data.R[kDof]);
    forward_kinematics(md, sd->data, q);
    Vec6<double> x;
    x << sd->data.o[kDof], orientation_coordinates(sd->data.R[kDof], R_ref);
    Vec6<double> off = rs.vec(0.001), y = rs.vec(0.1);
    y.tail<3>() *= 3;
    Vec18<double> theta;
    for (int i = 0; i < 18; ++i) theta(i) = 0.5 * (rs.u(rs.rng) + 1) * params::kThetaMax[i] / 6;
    const Vec6<double> x_hat = quantised(Vec6<double>(x + off)), yq = quantised(y);
    const Vec6<double> q_prev = quantised(Vec6<double>(q - rs.vec(1e-4)));
    const Vec6<double> qd1 = quantised(rs.vec(0.5)), qd2 = quantised(rs.vec(0.5));
    const Vec18<double> th = quantised(theta);
    set_state(*sd, R_ref, x_hat, yq, th, q_prev, qd1, qd2);
    set_state(*sf, R_ref, x_hat, yq, th, q_prev, qd1, qd2);
    StepOutput<double> od;
    StepOutput<Fixed> of;
    {
      test::NoMalloc guard;
      od = control_step(md, gd, FrictionMode::kAdaptive, *sd, q, trajectory(gd.trajectory, p0, t));
      of = control_step(mf, gf, FrictionMode::kAdaptive, *sf, q.cast<Fixed>(),
                        trajectory(gf.trajectory, Vec3<Fixed>(p0.cast<Fixed>()), Fixed(t)));
    }
    if (od.status == kFaultSingular) {  // the controller refuses to act: nothing to compare
      ++outside;
      continue;
    }
    ASSERT_EQ(od.status, 0u);
    const double e = err(of.tau, od.tau);
    // The largest velocity-product force of the step: h(x^dot + v) of the force command (32)-(35).
    const Vec6<double> x_tilde = sd->os.x - x_hat;
    const Vec6<double> xd_hat = yq + gd.k.cwiseProduct(x_tilde);
    const Desired<double> des = trajectory(gd.trajectory, p0, t);
    const Vec6<double> v = des.xd + gd.ks.cwiseProduct(des.x - sd->os.x);
    const Vec6<double> h = psi_quadratic(md, sd->data, sd->os, Vec6<double>(xd_hat + v));
    // sgn is discontinuous at rest (3): where an observed joint velocity is within 1e-3 rad/s of 0 the
    // Coulomb term's sign is decided by rounding, in any precision. Such states are skipped.
    // The same holds wherever the two controllers' observed joint velocities have opposite signs: x
    // carries a few LSB of rounding, which the observer gain k (up to 108/s) and J^{-1} turn into up
    // to a few 1e-3 rad/s of q^dot. That difference itself is bounded below (kBudgetQdHat).
    const Vec6<double> qd_hat = sd->os.Jf.solve(xd_hat);
    bool opposite_signs = false;
    double qd_hat_error = 0;
    if (of.status == 0u) {
      const Vec6<double> qd_hat_f = sf->os.Jf.solve(of.xd_hat).cast<double>();
      qd_hat_error = err(qd_hat_f, qd_hat);
      opposite_signs = (qd_hat.array() * qd_hat_f.array()).minCoeff() <= 0;
    }
    if (qd_hat.cwiseAbs().minCoeff() < 1e-3 || opposite_signs) {
      ++skipped_at_rest;
      continue;
    }
    bool within_drives = true;  // the torques within the amplifiers' limits (beyond, the DACs clip)
    for (int i = 0; i < kDof; ++i)
      within_drives = within_drives && std::abs(od.tau(i)) <= robot::kDrives.torque_limit[i];
    if (largest(operational_inertia(sd->data, sd->os), h) > kDomain || sd->os.Jf.rcond < kDomainRcond ||
        !within_drives) {
      ++outside;
      if (of.status == kFaultOverflow) {
        ++outside_flagged;
      } else {
        // Near a singularity the step is ill-conditioned in any precision: reported, not bounded.
        EXPECT_EQ(of.status, 0u);
        if (e / largest(od.tau) > outside_rel.v) outside_rcond = sd->os.Jf.rcond;
        outside_rel(e / largest(od.tau));
      }
      continue;
    }
    ++in_domain;
    ASSERT_EQ(of.status, 0u) << fault_name(of.status) << " at state " << k;
    worst_qd_hat = std::max(worst_qd_hat, qd_hat_error);
    // What one encoder count does to the double controller's torque at this state: the largest
    // change of tau when one joint reading moves by one count.
    double per_count = 0;
    for (int j = 0; j < kDof; ++j) {
      Vec6<double> qc = q;
      qc(j) += 1.0 / counts_per_rad(j);
      set_state(*sd, R_ref, x_hat, yq, th, q_prev, qd1, qd2);
      const StepOutput<double> oc =
          control_step(md, gd, FrictionMode::kAdaptive, *sd, qc, trajectory(gd.trajectory, p0, t));
      per_count = std::max(per_count, err(oc.tau, od.tau));
    }
    worst_vs_count = std::max(worst_vs_count, e / per_count);
    EXPECT_LE(e, kBudgetTauPerCount * per_count) << "state " << k;
    worst = std::max(worst, e);
    worst_rel = std::max(worst_rel, e / od.tau.cwiseAbs().maxCoeff());
    max_tau = std::max(max_tau, od.tau.cwiseAbs().maxCoeff());
  }
  std::printf(
      "outside the domain: %d states, %d of them flagged (overflow), the others' tau within %.1e relative "
      "(the worst at rcond %.1e); %d states skipped at a joint velocity reversal\n",
      outside, outside_flagged, outside_rel.v, outside_rcond, skipped_at_rest);
  std::printf(
      "control_step tau: worst |error| %.2e N m (budget %.1f), relative to max |tau| %.1e; largest |tau| %.1f N m; "
      "worst error / effect of one encoder count %.3f (budget %.2f)\n",
      worst, kBudgetTau, worst_rel, max_tau, worst_vs_count, kBudgetTauPerCount);
  std::printf("observed joint velocity q^dot: worst |error| %.2e rad/s (budget %.1e)\n", worst_qd_hat, kBudgetQdHat);
  EXPECT_LE(worst, kBudgetTau);
  EXPECT_LE(worst_qd_hat, kBudgetQdHat);
  EXPECT_EQ(fixed::take_flags(), 0u);
}

// The reference values the Cortex-M3 kernels image compares with bit for bit
// (tests/support/fixed_reference.hpp): the committed ones must be what the host computes now. When a kernel
// changes, this test prints the new file (between the markers) for tests/support/fixed_reference_values.inc.
TEST(FixedKernels, TheTargetImagesReferenceValuesAreWhatTheHostComputes) {
  const Model<Fixed> model = Model<Fixed>::of(robot::kArm);
  auto data = std::make_unique<Data<Fixed>>();
  auto os = std::make_unique<ArmOpSpace<Fixed>>();
  auto st = std::make_unique<ControllerState<Fixed>>();
  std::vector<std::int32_t> got;
  auto emit = [&got](const char*, const auto& m) {
    for (int j = 0; j < m.cols(); ++j)
      for (int i = 0; i < m.rows(); ++i) got.push_back(m(i, j).raw());
  };
  fixed::take_flags();
  for (const reference::Case& c : reference::kCases) reference::kernel_outputs(c, model, *data, *os, emit);
  reference::step_outputs(model, *st, emit);
  EXPECT_EQ(fixed::take_flags(), 0u);
  const std::vector<std::int32_t> committed(std::begin(reference::kValues), std::end(reference::kValues));
  if (got != committed) {
    std::printf("---- tests/support/fixed_reference_values.inc ----\n");
    std::printf(
        "// Generated by FixedKernels.TheTargetImagesReferenceValuesAreWhatTheHostComputes\n"
        "// (tests/firmware/kernels/test_fixed_kernels.cpp): the raw Q12.19 outputs of kernel_outputs\n"
        "// for each case, then step_outputs (tests/support/fixed_reference.hpp), %zu words.\n"
        "constexpr std::int32_t kValues[] = {",
        got.size());
    for (std::size_t k = 0; k < got.size(); ++k)
      std::printf("%s%d", k % 10 ? ", " : (k ? ",\n    " : "\n    "), got[k]);
    std::printf("};\n---- end ----\n");
  }
  EXPECT_EQ(got, committed);
}

}  // namespace
