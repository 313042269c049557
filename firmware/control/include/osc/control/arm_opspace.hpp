// The built arm's operational-space state: OpSpace (osc/kernels/opspace.hpp) with the factor of J
// that the arm of this build (osc/robot.hpp, CMake OSC_ROBOT) takes: the block factor where it has a
// spherical wrist at its operational point, the pivoted LU where it has not (JacobianFactorFor).
#pragma once

#include "osc/kernels/opspace.hpp"
#include "osc/robot.hpp"

namespace osc {

/// Whether the built arm has a spherical wrist at its operational point (J block lower-triangular).
inline constexpr bool kArmSphericalWrist = has_spherical_wrist(robot::kArm);

template <class S>
using ArmJacobianFactor = JacobianFactorFor<S, kArmSphericalWrist>;

template <class S>
using ArmOpSpace = OpSpace<S, ArmJacobianFactor<S>>;

}  // namespace osc
