// Simulated PUMA 560: rigid-body dynamics (1) in double by the articulated-body algorithm (its own
// code path, independent of the controller's CRBA/RNEA/operational-space kernels), true friction
// by model (2), RK4 integration at a fine step, zero-order-hold torques applied after the
// controller's computation delay inside each sample.
#pragma once

#include <Eigen/Core>

#include "osc/control/params.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/robot.hpp"

namespace sim {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

struct PlantConfig {
  osc::FrictionCoefficients friction = osc::robot::kFrictionPaper;
  double tau_dec = osc::params::kTauDec;
  double substep = 1e-4;  ///< RK4 step [s] (10 kHz) wherever a joint's velocity changes sign
  /// Away from velocity reversals (every joint's velocity keeps its sign through the step, so the
  /// friction of model (2) is smooth) RK4 takes this many substeps at once; 1 = fixed step.
  int smooth_steps = 8;
  double compute_delay = 0.2e-3;  ///< from the encoder sample to the DAC update [s]
  double link_scale = 1.0;        ///< scales every link mass and inertia (model-error studies)
};

/// Articulated-body forward dynamics of the PUMA 560 (armature on each joint's scalar inertia),
/// Featherstone's algorithm with every spatial quantity expressed at the base origin in base axes,
/// so that no transform is needed between links.
class ArticulatedBody {
 public:
  explicit ArticulatedBody(double link_scale = 1.0);
  /// q_dd for joint torques tau (friction already subtracted), gravity along -z0.
  Vec6 forward_dynamics(const Vec6& q, const Vec6& qd, const Vec6& tau) const;

 private:
  struct Body {
    double mass;
    Vec3 com;      // COM in the joint frame B_i (origin o_{i-1}, z = axis i)
    Mat3 inertia;  // about the COM, axes of B_i
  };
  Body body_[6];
  Mat3 rot_fixed_[6];  // rotation of F_{i-1} in B_{i-1}: Rx(alpha_{i-1})
  Vec3 pos_fixed_[6];  // origin of F_{i-1} in B_{i-1}: (a_{i-1}, 0, d_{i-1})
  double armature_[6];
};

/// The robot: state, friction, integration.
class Plant {
 public:
  explicit Plant(const PlantConfig& cfg = {});
  void reset(const Vec6& q0, const Vec6& qd0 = Vec6::Zero());
  /// Advances one control sample of length dt: tau_old is held for the computation delay, then tau_new.
  void advance_sample(const Vec6& tau_old, const Vec6& tau_new, double dt);
  /// The holding brakes: engaged, advance_sample() keeps every joint where it is, at rest (a PUMA's
  /// brakes hold the arm while its power is off; the commanded-motion simulation engages them while
  /// the controller is disabled or in fault).
  void set_brakes(bool engaged) { braked_ = engaged; }
  bool brakes() const { return braked_; }
  /// Integrates for duration with constant torque tau.
  void integrate(const Vec6& tau, double duration);

  Vec6 friction(const Vec6& qd) const;
  Vec6 acceleration(const Vec6& q, const Vec6& qd, const Vec6& tau) const;
  /// Kinetic plus potential energy (for integration checks).
  double energy() const;

  const Vec6& q() const { return q_; }
  /// The motors' angles, each referred to its joint through its gears: what the encoders count and
  /// where the index pulses fire. The joint angles themselves on today's rigid, uncoupled plant.
  Vec6 motor_angles() const { return q_; }
  const Vec6& qd() const { return qd_; }
  double time() const { return t_; }
  const PlantConfig& config() const { return cfg_; }
  /// Articulated-body evaluations since construction (cost accounting for tests and benchmarks).
  long evaluations() const { return evaluations_; }

 private:
  void rk4(const Vec6& tau, double h);
  /// One RK4 step of h if no joint velocity changes sign at any stage; otherwise leaves the state.
  bool rk4_smooth(const Vec6& tau, double h);
  PlantConfig cfg_;
  ArticulatedBody body_;
  osc::FrictionParams<double> friction_;  // the true friction, model (2) (the kernels' friction_torque)
  Vec6 q_ = Vec6::Zero(), qd_ = Vec6::Zero();
  double t_ = 0;
  bool braked_ = false;
  mutable long evaluations_ = 0;
};

}  // namespace sim
