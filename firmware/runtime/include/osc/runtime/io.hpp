// Conversions between hardware units and SI at the HAL boundary: encoder counts -> joint angles,
// joint torques -> DAC codes (saturated, never garbage: a non-finite torque becomes code 0).
#pragma once

#include <cstdint>

#include "osc/kernels/model.hpp"
#include "osc/control/params.hpp"

namespace osc {

/// Joint angle [rad] of an encoder count, relative to the count taken at the start pose.
template <class S>
S counts_to_angle(int joint, std::int32_t counts, S q_at_zero) {
  return q_at_zero + static_cast<S>(counts) / lit<S>(params::encoder_counts_per_rad(joint));
}

/// DAC code of a joint torque, saturated at the code range. Returns true when it saturated.
template <class S>
bool torque_to_code(int joint, S tau, std::int32_t& code) {
  const S scale = lit<S>(static_cast<double>(params::kDacMaxCode) / params::kTorqueLimit[joint]);
  const S c = tau * scale;
  const S max = lit<S>(static_cast<double>(params::kDacMaxCode));
  if (!math::isfinite(c)) {
    code = 0;
    return true;
  }
  if (c >= max) {
    code = static_cast<std::int32_t>(params::kDacMaxCode);
    return true;
  }
  if (c <= -max) {
    code = -static_cast<std::int32_t>(params::kDacMaxCode);
    return true;
  }
  // Round to nearest.
  code = static_cast<std::int32_t>(c >= S(0) ? c + lit<S>(0.5) : c - lit<S>(0.5));
  return false;
}

/// Joint torque [N m] that a DAC code commands (the amplifier side of the same scale).
inline double code_to_torque(int joint, std::int32_t code) {
  return static_cast<double>(code) * params::kTorqueLimit[joint] / static_cast<double>(params::kDacMaxCode);
}

}  // namespace osc
