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
constexpr double counts_per_rad(int joint, double counts_per_motor_rev = robot::kDrives.encoder_counts_per_motor_rev) {
  return counts_per_motor_rev * abs_of(robot::kArm.links[joint].gear_ratio) / (2 * kPi);
}
/// The encoder change of one control period at the joint's maximum speed [counts] (the plausible
/// step per tick is this plus one count of quantisation).
constexpr double counts_per_tick_at_max_speed(int joint, double counts_per_rad) {
  return robot::kDrives.max_joint_speed[joint] * params::kDt * counts_per_rad;
}
/// Largest DAC code magnitude of the robot's drives.
constexpr long kDacMaxCode = dac_max_code(robot::kDrives);

/// Joint angle [rad] of an encoder count, relative to the count taken at the start pose. Counts
/// and counts per radian reach 10^5: they are of the I/O scalar (math::io_scalar_t).
template <class S>
S counts_to_angle(std::int32_t counts, math::io_scalar_t<S> counts_per_rad, S q_at_zero) {
  return q_at_zero + math::quotient<S>(counts, counts_per_rad);
}
/// The same with the robot's drives.
template <class S>
S counts_to_angle(int joint, std::int32_t counts, S q_at_zero) {
  return counts_to_angle<S>(counts, lit<math::io_scalar_t<S>>(counts_per_rad(joint)), q_at_zero);
}

/// The DAC scale [codes per N m] and torque limit [N m] of each joint in the scalar W, built at
/// compile time: the conversion in the tick then calls no double-precision routine (on a core
/// without a double-precision FPU each would be a library call).
template <class W>
struct DacTable {
  W scale[kDof], limit[kDof];
  constexpr DacTable() : scale{}, limit{} {
    for (int i = 0; i < kDof; ++i) {
      scale[i] = lit<W>(static_cast<double>(kDacMaxCode) / robot::kDrives.torque_limit[i]);
      limit[i] = lit<W>(robot::kDrives.torque_limit[i]);
    }
  }
};
template <class W>
inline constexpr DacTable<W> kDacTable{};

/// DAC code of a joint torque, saturated at the code range. Returns true when it saturated. The
/// code is computed in the I/O scalar (it reaches 32767).
template <class S>
bool torque_to_code(int joint, S tau, std::int32_t& code) {
  using W = math::io_scalar_t<S>;
  constexpr W kHalf = lit<W>(0.5);
  const W scale = kDacTable<W>.scale[joint];
  const W limit = kDacTable<W>.limit[joint];
  const W t = static_cast<W>(tau);
  if (!math::isfinite(t)) {
    code = 0;
    return true;
  }
  if (t >= limit) {
    code = static_cast<std::int32_t>(kDacMaxCode);
    return true;
  }
  if (t <= -limit) {
    code = -static_cast<std::int32_t>(kDacMaxCode);
    return true;
  }
  // Below the limit the code lies within the range; round to nearest.
  const W c = t * scale;
  code = static_cast<std::int32_t>(c >= W(0) ? c + kHalf : c - kHalf);
  return false;
}

/// Joint torque [N m] that a DAC code commands (the amplifier side of the same scale).
inline double code_to_torque(int joint, std::int32_t code) {
  return static_cast<double>(code) * robot::kDrives.torque_limit[joint] / static_cast<double>(kDacMaxCode);
}

}  // namespace osc
