// The residual monitor's constants of the arm (ResidualConstants, built at compile time in each
// scalar) and what it reads of a completed step (ResidualInput): osc/runtime/residual_monitor.hpp
// takes them.
#pragma once

#include "osc/control/controller.hpp"
#include "osc/control/identification.hpp"
#include "osc/runtime/io.hpp"

namespace osc {

/// The residual monitor's constants of the arm, in the scalar S (robot::kModelErrorBounds, the
/// drive train's motor-inertia sets, the amplifiers' offsets, the filters' gains at the control rate
/// params::kDt): built at compile time, so that a tick multiplies no two constants.
template <class S>
struct ResidualConstants {
  // The friction band per coefficient as its middle and half-width: theta^'s farthest distance from
  // the band is |theta^ - mid| + half.
  S vis_mid[kDof], vis_half[kDof], sti_mid[kDof], sti_half[kDof];
  // The Coulomb band's ends, and the Stribeck band's lower end: a breakaway proven at B puts the
  // Coulomb level at most B - sti_lo.
  S cou_lo[kDof], cou_hi[kDof], sti_lo[kDof];
  S vis_hi[kDof];          // the viscous band's upper end [N m s/rad]
  S static_band[kDof];     // the Coulomb and Stribeck bands' upper ends together [N m]
  S static_lo[kDof];       // ... their lower ends, the least breakaway torque, over kResidualMargin [N m]
  S speed_cap[kDof];       // the joint's largest speed (robot::kDrives.max_joint_speed) [rad/s]
  S armature_delta[kDof];  // |J_m(alternative set) - J_m(model)| G^2 [kg m^2]
  S offset[kDof];          // an amplifier's offset bound [N m]
  S gain[kDof];            // the residual's filter gain K [1/s]
  S keep[kDof];            // 1 - K dt: what the filter keeps of its last value
  S quantum_gain[kDof];    // 2 K: the velocity noise's bound through A and the filter, per rad/s [1/s]
  S lag_gain[kDof];        // T K: the current loop's lag T times K
  // The same filters over a turn of params::kResidualTurnEvery ticks (the bound, the accelerations, the change
  // channel's regressors).
  S turn_gain_dt[kDof];  // K dt kResidualTurnEvery
  S turn_keep[kDof];     // 1 - K dt kResidualTurnEvery
  S peak_margin[kDof];   // params::kResidualMargin times the joint's peak factor
  S link_inertia, gain_ripple, amp_gain, ripple;
  S slow_dt;  // params::kResidualSlowGain dt kResidualTurnEvery: the slow filter, a turn at a time
  S margin;   // params::kResidualMargin
  // The pose x's own rounding in fixed point, per coordinate (kPoseRoundingLsb of Q<F>; 0 in float and double):
  // the observer's x~ carries it as it carries the encoders' quanta (ResidualMonitor::mixed_noise) [m, rad].
  S pose_rounding;
  constexpr ResidualConstants()
      : vis_mid{},
        vis_half{},
        sti_mid{},
        sti_half{},
        cou_lo{},
        cou_hi{},
        sti_lo{},
        vis_hi{},
        static_band{},
        static_lo{},
        speed_cap{},
        armature_delta{},
        offset{},
        gain{},
        keep{},
        quantum_gain{},
        lag_gain{},
        turn_gain_dt{},
        turn_keep{},
        peak_margin{},
        link_inertia{},
        gain_ripple{},
        amp_gain{},
        ripple{},
        slow_dt{},
        margin{},
        pose_rounding{} {
    const ModelErrorBounds& b = robot::kModelErrorBounds;
    constexpr double kTurnDt = params::kResidualTurnEvery * params::kDt;
    const FrictionCoefficients &lo = b.friction_lo, &hi = b.friction_hi;
    for (int i = 0; i < kDof; ++i) {
      vis_mid[i] = lit<S>(0.5 * (lo.vis[i] + hi.vis[i])), vis_half[i] = lit<S>(0.5 * (hi.vis[i] - lo.vis[i]));
      cou_lo[i] = lit<S>(lo.cou[i]), cou_hi[i] = lit<S>(hi.cou[i]), sti_lo[i] = lit<S>(lo.sti[i]);
      sti_mid[i] = lit<S>(0.5 * (lo.sti[i] + hi.sti[i])), sti_half[i] = lit<S>(0.5 * (hi.sti[i] - lo.sti[i]));
      vis_hi[i] = lit<S>(hi.vis[i]);
      static_band[i] = lit<S>(hi.cou[i] + hi.sti[i]);
      static_lo[i] = lit<S>((lo.cou[i] + lo.sti[i]) / params::kResidualMargin);
      speed_cap[i] = lit<S>(robot::kDrives.max_joint_speed[i]);
      const double G = abs_of(robot::kArm.links[i].gear_ratio);
      armature_delta[i] =
          lit<S>(abs_of(robot::kDriveTrain.motor_inertia_alt.jm[i] - robot::kArm.links[i].motor_inertia) * G * G);
      offset[i] = lit<S>(b.amp_offset * robot::kDrives.torque_limit[i]);
      const double K = params::kResidualGain[i];
      gain[i] = lit<S>(K);
      keep[i] = lit<S>(1 - K * params::kDt);
      quantum_gain[i] = lit<S>(2 * K);
      lag_gain[i] = lit<S>(b.amp_lag * K);
      turn_gain_dt[i] = lit<S>(K * kTurnDt);
      turn_keep[i] = lit<S>(1 - K * kTurnDt);
      peak_margin[i] = lit<S>(params::kResidualMargin * params::kResidualPeakFactor[i]);
    }
    link_inertia = lit<S>(b.link_inertia);
    gain_ripple = lit<S>(b.amp_gain + b.ripple);
    amp_gain = lit<S>(b.amp_gain);
    ripple = lit<S>(b.ripple);
    if constexpr (fixed::is_q_v<S>) pose_rounding = S::from_raw(params::kPoseRoundingLsb);
    slow_dt = lit<S>(params::kResidualSlowGain * kTurnDt);
    margin = lit<S>(params::kResidualMargin);
  }
};
template <class S>
inline constexpr ResidualConstants<S> kResidualConstants{};

/// What the residual monitor reads of a completed step (joint space).
template <class S>
struct ResidualInput {
  const Mat6<S>& A;       // joint inertia A(q), armature included
  const Vec6<S>& g;       // gravity torques g(q)
  const Vec6<S>& bias;    // c(q, q^dot) + g + tau_f^ (StepOutput::tau_bias)
  const Vec6<S>& tau_f;   // tau_f^
  const Vec6<S>& qd;      // the observed joint velocity q^dot (28)
  const Vec6<S>& decay;   // |exp(-tau_dec q^dot^2)| where q^dot != 0 (the regressor's Stribeck column)
  const Vec18<S>* theta;  // theta^, or nullptr without compensation (tau_f^ = 0)
  /// The friction the identification proves (FrictionIdentifier::proven; the travel check's), or
  /// nullptr: the band's tops.
  const FrictionBounds<S>* proven = nullptr;
  /// The geometric Jacobian of the wrist centre (Data::J), whose wrist columns carry the wrist's axes:
  /// the velocity estimate's noise on the wrist (ResidualMonitor::wrist_noise), or nullptr: none
  /// (a velocity that is not the observer's).
  const Mat6<S>* J = nullptr;
  /// For an arm without a spherical wrist: the step's analytic Jacobian and its factor, the observer's,
  /// whose mixing of the encoders' quanta the velocity estimate carries (ResidualMonitor::mixed_noise);
  /// nullptr as J.
  const ArmOpSpace<S>* os = nullptr;
  /// The step's tracking error x_d - x (StepOutput::e), or nullptr: in joint space through os's factor, where the
  /// reference has taken each joint (ResidualMonitor::off_reference).
  const Vec6<S>* e = nullptr;
  /// A coupled drive train (ControlTask::io), whose friction is each motor's at the motors' rates (DriveCoupling):
  /// the friction regressors and the momentum law's samples are then the motors', or nullptr: the joints' (C = I).
  const IoMap<S>* io = nullptr;
  const Vec6<S>* rate = nullptr;  // with io: the motors' rates C^-1 q^dot
};

}  // namespace osc
