// Reference values of the fixed-point kernels, shared by the host tests and the Cortex-M3 kernels
// image (boards/common/mps2/kernels_image.cpp): every kernel's Q12.19 output at three states, and
// the torques of 20 control steps, as raw words. The arithmetic is integer, so the target must
// reproduce the host's values bit for bit. tests/firmware/kernels/test_fixed_kernels.cpp checks that the committed
// values (fixed_reference_values.inc) are what the host computes now (and prints new ones when a
// kernel changed); the same file checks these kernels against double within their budgets.
#pragma once

#include <cstdint>

#include "osc/control/controller.hpp"
#include "osc/robot.hpp"

namespace osc::reference {

/// One state: joint angles, joint velocities, an operational velocity (rad, rad/s, m/s).
struct Case {
  double q[kDof], qd[kDof], v[kDof];
};
constexpr Case kCases[] = {
    {{0, kPi / 4, -kPi, 0, kPi / 4, 0}, {0.1, -0.2, 0.3, 0.05, -0.1, 0.2}, {0.05, -0.02, 0.03, 0.01, 0.02, -0.01}},
    {{0, kPi / 4, kPi, 0, kPi / 4, 0}, {1, 2, 3, 1, 2, 3}, {0.1, 0.1, -0.1, 0.2, -0.2, 0.1}},
    {{0.7, 0.3, -2.6, 1.1, -0.9, 2.2}, {-0.5, 0.4, 0.8, -1.2, 0.6, -0.3}, {-0.08, 0.04, 0.06, -0.3, 0.1, 0.25}},
};
constexpr int kSteps = 20;  // control steps from controller_init at the start pose

/// Calls emit(name, matrix) for every kernel output at case c (the kernels in S; the emitted
/// matrices are of S). The workspaces are the caller's (static on the target).
template <class S, class Emit>
void kernel_outputs(const Case& c, const Model<S>& model, Data<S>& data, ArmOpSpace<S>& os, Emit&& emit) {
  const Vec6<S> q = joint_vector<S>(c.q), qd = joint_vector<S>(c.qd), v = joint_vector<S>(c.v);
  forward_kinematics(model, data, q);
  const Mat3<S> R_ref = data.R[kDof];  // phi = 0 at this state
  opspace_update(model, data, os, q, R_ref);
  emit("FK o6", data.o[kDof]);
  emit("FK R6", data.R[kDof]);
  emit("x", os.x);
  emit("J", data.J);
  emit("A", data.A);
  emit("g", os.g);
  emit("Lambda", Mat6<S>(operational_inertia(data, os)));
  emit("p", operational_gravity(os));
  emit("c", velocity_products(model, data, qd).c);
  emit("Psi h(v)", psi_quadratic(model, data, os, v));
  emit("lambda_solve", lambda_solve(os, v));
  const FrictionParams<S> fp = FrictionParams<S>::from(*robot::kFrictionPresets[0], params::kTauDec);
  emit("friction_torque", friction_torque(fp, qd));
  emit("friction_regressor", friction_regressor(qd, fp.dec));
}

/// Calls emit("tau", tau) for kSteps control steps from controller_init at the start pose, joint 2
/// moving 1e-5 rad per step (adaptive, the paper's gains, the robust law: the law whose update runs
/// in the control step, so that the images check its arithmetic too; the momentum law's runs in the
/// task).
template <class S, class Emit>
void step_outputs(const Model<S>& model, ControllerState<S>& st, Emit&& emit) {
  Gains<S> gains = Gains<S>::paper();
  gains.adaptation = AdaptationLaw::kRobust;
  const Vec6<S> q0 = joint_vector<S>(robot::kQStart);
  controller_init(model, st, q0);
  const PaperMotion<S> paper{gains.trajectory, st.data.o[kDof]};
  for (int k = 0; k < kSteps; ++k) {
    Vec6<S> q = q0;
    q(1) += lit<S>(1e-5) * S(k);
    const StepOutput<S> out =
        control_step(model, gains, FrictionMode::kAdaptive, st, q, paper.at_time(lit<S>(1e-3) * S(k)));
    emit("control_step tau", out.tau);
  }
}

}  // namespace osc::reference

namespace osc::reference {
#include "fixed_reference_values.inc"
}  // namespace osc::reference
