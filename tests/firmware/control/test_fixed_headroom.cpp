// Headroom of the Q12.19 fixed-point scalar (docs/fixed_point.md, "Headroom"): the largest values
// the operational-space kernels produce along the paper's task and at the corners of the joint
// limits, and how many integer bits the whole chain could lose before anything saturates.
//
// Two measurements:
//  - the named quantities (A, Lambda, g, p, h = Psi(x, xd) xd, F, tau, and the joint-space bracket
//    A J^{-1}(xdd - Jdot qd) of operational_force, the largest intermediate) in double, as their
//    largest magnitude;
//  - the kernel chain of one control step (opspace_update, the velocity products, F = Lambda xdd +
//    h + p formed as the control step forms it, tau = J^T F, and psi_quadratic, operational_gravity
//    and Lambda on their own) run in Q<19 + k> for k = 0, 1, 2, ...: Q<19 + k> has 2^k
//    times less range than Q12.19, so the largest k whose chain leaves the overflow flag clear says
//    that every intermediate of that chain (each product, sum and solve) stays below 4096 / 2^k.
// The task's states come from inverse kinematics of the reference (68), sampled every 10 ms over
// 120 s, with the reference's velocity and acceleration; the corners are the 64 combinations of the
// joint limits, each with its own orientation as the reference, and a velocity and acceleration
// above the task's along every position axis. A corner outside the domain (Jacobian reciprocal
// condition below 0.1 or a quantity beyond 1024) must saturate with the flag or stay accurate.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "osc/control/gains.hpp"
#include "osc/control/trajectory.hpp"
#include "osc/control/arm_opspace.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

/// Largest magnitudes of the named quantities.
struct Peaks {
  double A = 0, Lambda = 0, g = 0, p = 0, h = 0, bracket = 0, F = 0, tau = 0;
  void add(const Peaks& o) {
    A = std::max(A, o.A), Lambda = std::max(Lambda, o.Lambda), g = std::max(g, o.g), p = std::max(p, o.p);
    h = std::max(h, o.h), bracket = std::max(bracket, o.bracket), F = std::max(F, o.F), tau = std::max(tau, o.tau);
  }
  double largest() const { return std::max({A, Lambda, g, p, h, bracket, F, tau}); }
};

template <class M>
double amax(const M& m) {
  return m.template cast<double>().cwiseAbs().maxCoeff();
}

/// The kernel chain of one control step at (q, v = x dot, a = x ddot) in scalar S; returns the
/// peaks of its named quantities (in S, converted) and leaves the flags to the caller.
template <class S>
Peaks chain(const Vec6<double>& q, const Mat3<double>& R_ref, const Vec6<double>& v, const Vec6<double>& a) {
  static const Model<S> model = Model<S>::of(robot::kArm);
  auto data = std::make_unique<Data<S>>();
  auto os = std::make_unique<ArmOpSpace<S>>();
  opspace_update(model, *data, *os, Vec6<S>(q.cast<S>()), Mat3<S>(R_ref.cast<S>()));
  const Vec6<S> vs = v.cast<S>(), as = a.cast<S>();
  const Vec6<S> h = psi_quadratic(model, *data, *os, vs);
  const Vec6<S> p = operational_gravity(*os);
  const Mat6<S> Lambda = operational_inertia(*data, *os);
  // F = Lambda a + h + p as the control step forms it: one operational_force of the joint-space
  // parts, J^{-T}[A J^{-1}(a - Jdot qd_v) + c + g]. Its bracket A J^{-1}(a - Jdot qd_v) (a joint
  // torque) and c are the largest intermediates.
  const Vec6<S> qd = os->Jf.solve(vs);
  const VelocityProducts<S> vp = velocity_products(model, *data, qd);
  const Vec6<S> jdqd = analytic_jdot_qd(vp.jdot_qd, vp.w6, Vec3<S>(os->x.template tail<3>()));
  const Vec6<S> F = operational_force(*data, *os, Vec6<S>(as - jdqd), Vec6<S>(vp.c + os->g));
  const Vec6<S> tau = joint_torques(*os, F);
  const Vec6<S> bracket = data->A * os->Jf.solve(Vec6<S>(as - jdqd));
  Peaks pk;
  pk.A = amax(data->A), pk.Lambda = amax(Lambda), pk.g = amax(os->g), pk.p = amax(p), pk.h = amax(h);
  pk.bracket = std::max(amax(bracket), amax(vp.c)), pk.F = amax(F), pk.tau = amax(tau);
  return pk;
}

/// A state of the chain: joint angles, reference orientation, operational velocity and acceleration.
struct State {
  Vec6<double> q;
  Mat3<double> R_ref;
  Vec6<double> v, a;
};

/// The largest k <= kMaxBits such that the chain in Q<19 + k> leaves the flags clear at every
/// state (kMaxBits: the chain is instantiated once per k, the build's longest compile; 7 is one
/// above the 6 measured along the task).
constexpr int kMaxBits = 7;
template <int K = 0>
int headroom_bits(const std::vector<State>& states) {
  if constexpr (K > kMaxBits) {
    return kMaxBits;
  } else {
    fixed::take_flags();
    for (const auto& s : states) {
      chain<fixed::Q<19 + K>>(s.q, s.R_ref, s.v, s.a);
      if (fixed::take_flags() != 0) return K - 1;
    }
    return headroom_bits<K + 1>(states);
  }
}

void print(const char* what, const Peaks& pk) {
  std::printf("| %s | %.2f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |\n", what, pk.A, pk.Lambda, pk.g, pk.p,
              pk.h, pk.bracket, pk.F, pk.tau);
}

}  // namespace

TEST(FixedHeadroom, AlongThePapersTaskEveryIntermediateFitsWithAtLeastFourBitsToSpare) {
  const Model<double> md = Model<double>::of(robot::kArm);
  auto dd = std::make_unique<Data<double>>();
  auto od = std::make_unique<ArmOpSpace<double>>();
  Vec6<double> q = test::from_array(robot::kQStart);
  forward_kinematics(md, *dd, q);
  const Vec3<double> p0 = dd->o[kDof];
  // R_ref as the fixed-point controller holds it (rounded), so phi stays near 0 in every format.
  const Mat3<double> R_ref = dd->R[kDof].cast<Fixed>().cast<double>();
  const TrajectorySpec<double> spec = TrajectorySpec<double>::paper();
  std::vector<State> states;
  double worst_ik = 0, max_speed = 0, max_acc = 0;
  for (int n = 0; n <= 12000; ++n) {
    const Desired<double> d = trajectory(spec, p0, 0.01 * n);
    for (int it = 0; it < 4; ++it) {  // Newton from the previous sample's solution
      opspace_update(md, *dd, *od, q, R_ref);
      q += od->Jf.solve(Vec6<double>(d.x - od->x));
    }
    opspace_update(md, *dd, *od, q, R_ref);
    worst_ik = std::max(worst_ik, (d.x - od->x).cwiseAbs().maxCoeff());
    states.push_back({q, R_ref, d.xd, d.xdd});
    max_speed = std::max(max_speed, d.xd.cwiseAbs().maxCoeff());
    max_acc = std::max(max_acc, d.xdd.cwiseAbs().maxCoeff());
  }
  ASSERT_LT(worst_ik, 1e-9) << "the inverse kinematics did not follow the task";
  Peaks task;
  for (const auto& s : states) task.add(chain<double>(s.q, s.R_ref, s.v, s.a));
  const int bits = headroom_bits(states);
  std::printf("task: %zu states, |x_d dot| <= %.3f m/s, |x_d ddot| <= %.3f m/s^2\n", states.size(), max_speed, max_acc);
  std::printf("| states | A | Lambda | g | p | h | bracket | F | tau |\n|---|---|---|---|---|---|---|---|---|\n");
  print("the paper's task, 120 s", task);
  std::printf("headroom along the task: the chain runs without a flag down to Q<%d> (range %g): %d spare bits\n",
              19 + bits, 4096.0 / (1 << bits), bits);
  // The named quantities sit far inside the range (4096), and so does every intermediate.
  EXPECT_LT(task.largest(), 4096.0 / 16);
  EXPECT_GE(bits, 4);
}

TEST(FixedHeadroom, AtTheJointLimitCornersEveryQuantityFitsOrSaturatesWithTheFlag) {
  OSC_PUMA_TUNED("its domain's condition threshold is the PUMA's (no UR5e corner is within it)");
  const Model<double> md = Model<double>::of(robot::kArm);
  auto dd = std::make_unique<Data<double>>();
  auto od = std::make_unique<ArmOpSpace<double>>();
  // Above the task's largest velocity (0.063 m/s) and acceleration (0.087 m/s^2), along every
  // position axis at once.
  const Vec6<double> v = (Vec6<double>() << 0.1, 0.1, 0.1, 0, 0, 0).finished();
  const Vec6<double> a = (Vec6<double>() << 0.3, 0.3, 0.3, 0, 0, 0).finished();
  Peaks in_domain;
  int n_in = 0, n_out = 0, out_flagged = 0, out_accurate = 0;
  double min_rcond_in = 1;
  std::vector<State> corners;
  for (int corner = 0; corner < 64; ++corner) {
    Vec6<double> q;
    for (int i = 0; i < kDof; ++i) q(i) = (corner >> i) & 1 ? robot::kArm.q_max[i] : robot::kArm.q_min[i];
    forward_kinematics(md, *dd, q);
    const Mat3<double> R_ref = dd->R[kDof].cast<Fixed>().cast<double>();
    opspace_update(md, *dd, *od, q, R_ref);
    const Peaks pd = chain<double>(q, R_ref, v, a);
    fixed::take_flags();
    const Peaks pf = chain<Fixed>(q, R_ref, v, a);
    const bool flagged = fixed::take_flags() != 0;
    if (od->Jf.rcond >= 0.1 && pd.largest() <= 1024) {
      ++n_in;
      in_domain.add(pd);
      corners.push_back({q, R_ref, v, a});
      min_rcond_in = std::min(min_rcond_in, od->Jf.rcond);
      EXPECT_FALSE(flagged) << "corner " << corner << " is in the domain";
      EXPECT_NEAR(pf.tau, pd.tau, 0.05 * pd.tau + 0.1) << "corner " << corner;
    } else {
      ++n_out;
      if (flagged) {
        ++out_flagged;
      } else {
        // Unflagged outside the domain: must still be right (within a few per cent of the largest).
        ++out_accurate;
        EXPECT_NEAR(pf.tau, pd.tau, 0.05 * pd.largest()) << "corner " << corner << " unflagged but wrong";
      }
    }
  }
  std::printf("corners: %d in the domain (rcond >= %.2f), %d outside: %d flagged, %d unflagged and accurate\n", n_in,
              min_rcond_in, n_out, out_flagged, out_accurate);
  std::printf("| states | A | Lambda | g | p | h | bracket | F | tau |\n|---|---|---|---|---|---|---|---|---|\n");
  print("joint-limit corners in the domain", in_domain);
  const int bits = headroom_bits(corners);
  std::printf("headroom at the corners in the domain: no flag down to Q<%d> (range %g): %d spare bits\n", 19 + bits,
              4096.0 / (1 << bits), bits);
  EXPECT_GT(n_in, 0);
  EXPECT_GE(bits, 2);
  EXPECT_LT(in_domain.largest(), 1024.0);
}
