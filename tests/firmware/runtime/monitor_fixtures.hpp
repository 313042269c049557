// What the tests of the tick's monitors share (test_encoder_monitors.cpp, test_step_monitors.cpp,
// test_residual_*.cpp): the typed suite Monitors over the three scalars, and the residual monitor's
// rig, an arm frozen at the start pose and simulated exactly in double.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <type_traits>

#include "osc/kernels/dynamics.hpp"
#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/monitors.hpp"

namespace osc::test {

template <class S>
class Monitors : public ::testing::Test {};
using Scalars = ::testing::Types<double, float, Fixed>;
TYPED_TEST_SUITE(Monitors, Scalars);

/// A rigid arm frozen at the start pose's inertia, gravity torques and no friction, simulated
/// exactly in double: A qdd = tau + tau_ext - g. The monitor gets the true velocity as its q^dot, so
/// the residual is the external torque through the first-order filter alone:
/// r_n = tau_ext (1 - (1 - K dt)^n), exactly. With `jacobian`, the monitor gets frame 6's Jacobian at the start pose
/// as the control step gives it (its payload check, osc/runtime/payload_check.hpp; the wrist's velocity noise from
/// its axes, which raises J4's and J6's thresholds); without, neither.
template <class S>
struct ResidualRig {
  Mat6<double> A;
  Vec6<double> g, qd = Vec6<double>::Zero(), tau = Vec6<double>::Zero();
  std::int32_t counts[kDof] = {};
  ResidualMonitor<S> m;
  IoMap<S> io = IoMap<S>::of(robot::kEncodersUniform);
  std::uint64_t tick = 0;
  double dt = params::kDt;
  const FrictionBounds<S>* proven = nullptr;  // the identification's friction (the travel check's)
  Mat6<S> J;
  bool jacobian = false;
  /// The step's operational space and tracking error (ResidualMonitor::off_reference), or nullptr: none.
  const ArmOpSpace<S>* os = nullptr;
  Vec6<S> e = Vec6<S>::Zero();

  ResidualRig() {
    Model<double> model = Model<double>::of(robot::kArm);
    Data<double> data;
    forward_kinematics(model, data, joint_vector<double>(robot::kQStart));
    joint_inertia(model, data);
    geometric_jacobian(data);
    A = data.A;
    J = data.J.cast<S>();
    g << 0, 40, 10, 0.1, 0.5, 0.01;
    tau = g;  // holds the arm
    Vec6<S> quantum;
    for (int i = 0; i < kDof; ++i) quantum(i) = lit<S>(1 / counts_per_rad(i));
    m.reset();
    m.set(quantum, Gains<S>::paper().k, io.inverse);
  }
  /// One tick: the encoders of `counting` joints advance one count (every tick: moving steadily),
  /// the others stand still. Free: the arm moves under tau + tau_ext. Held: it stays at rest under
  /// tau = g while the monitor is told tau - tau_ext was commanded (drives that do not deliver what
  /// was asked of them, or a contact that holds the arm against the difference).
  std::uint32_t step(const Vec6<double>& tau_ext, const bool counting[kDof], bool free = true) {
    bool moved[kDof];
    for (int i = 0; i < kDof; ++i) {
      moved[i] = counting[i] || tick == 0;
      if (counting[i]) ++counts[i];
    }
    const Mat6<S> As = A.cast<S>();
    const Vec6<S> gs = g.cast<S>(), zero = Vec6<S>::Zero(), qds = qd.cast<S>();
    Vec6<S> decay = Vec6<S>::Ones();
    const ResidualInput<S> in{
        As, gs, gs, zero, qds, decay, nullptr, proven, jacobian ? &J : nullptr, os, os ? &e : nullptr};
    const std::uint32_t f = m.check(in, io, counts, moved, tick, tick % params::kResidualTurnEvery == 0);
    m.applied(free ? Vec6<S>(tau.cast<S>()) : Vec6<S>((tau - tau_ext).cast<S>()));
    if (free) qd += dt * A.ldlt().solve(tau + tau_ext - g);
    ++tick;
    return f;
  }
};

/// The external torque of the residual's closed-form tests [N m], and each scalar's tolerance.
inline Vec6<double> closed_form_torque() {
  Vec6<double> ext;
  ext << 3, -5, 2, 0.5, -0.3, 0.2;
  return ext;
}
template <class S>
constexpr double kClosedFormTol = std::is_same_v<S, double>  ? 1e-9
                                  : std::is_same_v<S, float> ? 2e-3
                                                             : 0.05;
/// Joint i's residual n checks after a constant torque `ext` began (the check after the prime is
/// n = 1): the arm moves from the prime on, so the first period's torque shows in the next check.
inline double closed_form_residual(double ext, int i, int n) {
  return ext * (1 - std::pow(1 - params::kResidualGain[i] * params::kDt, n - 1));
}

/// Ticks until the monitor reports a fault under a constant external torque (-1: none in 200).
template <class S>
int ticks_to_fault(ResidualRig<S>& rig, const Vec6<double>& ext, const bool counting[kDof], std::uint32_t& kind) {
  kind = 0;
  for (int n = 0; n < 200; ++n)
    if ((kind = rig.step(n == 0 ? Vec6<double>::Zero() : ext, counting, false)) != 0) return n;
  return -1;
}

}  // namespace osc::test
