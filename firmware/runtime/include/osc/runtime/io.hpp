// Conversions between hardware units and SI at the HAL boundary: encoder counts -> joint angles,
// joint torques -> DAC codes (saturated, never garbage: a non-finite torque becomes code 0).
#pragma once

#include <cstdint>

#include "osc/control/params.hpp"
#include "osc/kernels/model.hpp"
#include "osc/robot.hpp"

namespace osc {

/// Encoder counts per joint radian of the robot's drives, or of encoders with another resolution
/// (counts per motor revolution, after quadrature decoding).
constexpr double counts_per_rad(int joint,
                                double counts_per_motor_rev = robot::kDrives.encoder_counts_per_motor_rev) {
  return counts_per_motor_rev * abs_of(robot::kArm.links[joint].gear_ratio) / (2 * kPi);
}
/// The encoder change of one control period at the joint's maximum speed [counts] (the plausible
/// step per tick is this plus one count of quantisation).
constexpr double counts_per_tick_at_max_speed(int joint, double counts_per_rad) {
  return robot::kDrives.max_joint_speed[joint] * params::kDt * counts_per_rad;
}
/// Largest DAC code magnitude of the robot's drives.
constexpr long kDacMaxCode = dac_max_code(robot::kDrives);

/// Joint angle [rad] of an encoder count, relative to the count taken at the start pose.
template <class S>
S counts_to_angle(std::int32_t counts, S counts_per_rad, S q_at_zero) {
  return q_at_zero + static_cast<S>(counts) / counts_per_rad;
}
/// The same with the robot's drives.
template <class S>
S counts_to_angle(int joint, std::int32_t counts, S q_at_zero) {
  return counts_to_angle<S>(counts, lit<S>(counts_per_rad(joint)), q_at_zero);
}

/// DAC code of a joint torque, saturated at the code range. Returns true when it saturated.
template <class S>
bool torque_to_code(int joint, S tau, std::int32_t& code) {
  const S scale = lit<S>(static_cast<double>(kDacMaxCode) / robot::kDrives.torque_limit[joint]);
  const S c = tau * scale;
  const S max = lit<S>(static_cast<double>(kDacMaxCode));
  if (!math::isfinite(c)) {
    code = 0;
    return true;
  }
  if (c >= max) {
    code = static_cast<std::int32_t>(kDacMaxCode);
    return true;
  }
  if (c <= -max) {
    code = -static_cast<std::int32_t>(kDacMaxCode);
    return true;
  }
  // Round to nearest.
  code = static_cast<std::int32_t>(c >= S(0) ? c + lit<S>(0.5) : c - lit<S>(0.5));
  return false;
}

/// Joint torque [N m] that a DAC code commands (the amplifier side of the same scale).
inline double code_to_torque(int joint, std::int32_t code) {
  return static_cast<double>(code) * robot::kDrives.torque_limit[joint] / static_cast<double>(kDacMaxCode);
}

}  // namespace osc
