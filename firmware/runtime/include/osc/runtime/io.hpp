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
/// The same for a motor channel of a coupled drive train, inverse = C^-1: its motor turns with
/// (C^-1 qd)_i, at most sum_j |C^-1_ij| times joint j's maximum speed.
inline double counts_per_tick_at_max_speed(int channel, double counts_per_rad, const double (&inverse)[kDof][kDof]) {
  double speed = robot::kDrives.max_joint_speed[channel];
  for (int j = 0; j < kDof; ++j)
    if (j != channel) speed += abs_of(inverse[channel][j]) * robot::kDrives.max_joint_speed[j];
  return speed * params::kDt * counts_per_rad;
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

/// An encoder map (osc/robots/arm.hpp, EncoderMap) in the task's scalars: each channel's counts per
/// radian (the I/O scalar), the coupling's terms, and those of its inverse (the motors' rates from
/// the joints', for the monitors). Built at initialisation, in double: C^-1 of a unit lower
/// triangular C by forward substitution.
template <class S>
struct IoMap {
  Vec6<math::io_scalar_t<S>> counts_per_rad;
  int terms;
  std::int8_t row[kMaxCouplingTerms], col[kMaxCouplingTerms];
  S c[kMaxCouplingTerms];
  DriveCoupling<S> drives;     // C^-1's terms (the motors' rates from the joints')
  double inverse[kDof][kDof];  // C^-1, for the monitors' set-up

  bool coupled() const { return terms != 0; }

  [[gnu::cold]] static IoMap of(const EncoderMap& map) {
    IoMap m{};
    for (int i = 0; i < kDof; ++i) m.counts_per_rad(i) = lit<math::io_scalar_t<S>>(map.counts_per_rad[i]);
    m.terms = map.coupling_terms;
    for (int k = 0; k < map.coupling_terms; ++k) {
      const CouplingTerm& t = map.coupling[k];
      m.row[k] = static_cast<std::int8_t>(t.row);
      m.col[k] = static_cast<std::int8_t>(t.col);
      m.c[k] = lit<S>(t.c);
    }
    double C[kDof][kDof];
    coupling_matrices(map, C, m.inverse);
    m.drives = DriveCoupling<S>::of(m.inverse);
    return m;
  }
};

namespace detail {
/// The coupling's terms of C e added to q (C unit lower triangular: its diagonal's e is in q already).
template <class S>
void add_coupling(const IoMap<S>& io, const Vec6<S>& e, Vec6<S>& q) {
  for (int k = 0; k < io.terms; ++k) q(io.row[k]) += io.c[k] * e(io.col[k]);
}
}  // namespace detail

/// The joint <- motor map of the drive train, the one the task uses (its angles from the encoders,
/// homing's corrections and turns): the joint angles q0 + C e of motor angles e (referred to their
/// joints), q0 the joints' at e = 0, summed as (q0 + e) + C's terms off the diagonal.
template <class S>
Vec6<S> joint_from_motor(const IoMap<S>& io, const Vec6<S>& e, const Vec6<S>& q0) {
  Vec6<S> q = q0 + e;
  detail::add_coupling(io, e, q);
  return q;
}
/// The same from zero: the joints' angles C e of motor angles e.
template <class S>
Vec6<S> joint_from_motor(const IoMap<S>& io, const Vec6<S>& e) {
  Vec6<S> q = e;
  detail::add_coupling(io, e, q);
  return q;
}

/// Encoder counts to joint angles: q = q_start + C e, e_i = counts_i / counts_per_rad_i (joint_from_motor).
template <class S>
Vec6<S> angles_from_counts(const Vec6<S>& q_start, const IoMap<S>& io, const std::int32_t counts[kDof]) {
  Vec6<S> e;
  for (int i = 0; i < kDof; ++i) e(i) = math::quotient<S>(counts[i], io.counts_per_rad(i));
  return joint_from_motor(io, e, q_start);
}

/// The motors' torques, referred to their joints, that give joint torques tau: C^T tau.
template <class S>
Vec6<S> motor_torques(const IoMap<S>& io, const Vec6<S>& tau) {
  Vec6<S> t = tau;
  for (int k = 0; k < io.terms; ++k) t(io.col[k]) += io.c[k] * tau(io.row[k]);
  return t;
}

/// The motors' rates of joint rates qd, C^-1 qd, and the joint torques of motor torques, C^-T tau_m (DriveCoupling).
template <class S>
Vec6<S> motor_rates(const IoMap<S>& io, const Vec6<S>& qd) {
  return motor_rates(io.drives, qd);
}
template <class S>
Vec6<S> joint_torques_of_motors(const IoMap<S>& io, const Vec6<S>& tau_m) {
  return joint_torques_of_motors(io.drives, tau_m);
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
[[gnu::always_inline]] inline bool torque_to_code(int joint, S tau, std::int32_t& code) {
  using W = math::io_scalar_t<S>;
  constexpr W kHalf = lit<W>(0.5);
  const W scale = kDacTable<W>.scale[joint];
  const W limit = kDacTable<W>.limit[joint];
  const W t = static_cast<W>(tau);
  if constexpr (std::is_floating_point_v<W>) {
    // One comparison for the common case: |t| below the limit (false for a NaN, an infinity and beyond).
    if (!((t < W(0) ? -t : t) < limit)) {
      code = t >= limit ? static_cast<std::int32_t>(kDacMaxCode)
                        : (t <= -limit ? -static_cast<std::int32_t>(kDacMaxCode) : 0);
      return true;
    }
    const W c = t * scale;
    code = static_cast<std::int32_t>(c >= W(0) ? c + kHalf : c - kHalf);
    return false;
  }
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
