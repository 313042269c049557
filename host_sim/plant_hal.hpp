// HAL binding of the firmware's encoder and DAC interfaces (hal/hal.hpp) to the simulated plant.
#pragma once

#include <cmath>
#include <cstdint>

#include "hal/hal.hpp"
#include "osc/runtime/io.hpp"
#include "plant.hpp"

namespace sim {

class PlantHal {
 public:
  /// counts_per_motor_rev: the encoders' resolution (default: the robot table's).
  PlantHal(Plant& plant, const Vec6& q_start,
           double counts_per_motor_rev = osc::robot::kDrives.encoder_counts_per_motor_rev)
      : plant_(plant), q_start_(q_start) {
    for (int i = 0; i < hal::kJoints; ++i) counts_per_rad_[i] = osc::counts_per_rad(i, counts_per_motor_rev);
  }

  /// Incremental encoders zeroed at q_start: counts = floor((q - q_start) * counts_per_rad). Every
  /// tick has a sample.
  bool read_encoders(std::int32_t counts[hal::kJoints]) const {
    for (int i = 0; i < hal::kJoints; ++i)
      counts[i] = static_cast<std::int32_t>(std::floor((plant_.q()(i) - q_start_(i)) * counts_per_rad_[i]));
    return true;
  }
  void write_dacs(const std::int32_t codes[hal::kJoints]) {
    for (int i = 0; i < hal::kJoints; ++i) codes_[i] = codes[i];
  }
  /// The host build has no cycle counter and no link: timing reads 0, no I/O faults.
  std::uint32_t cycles() const { return 0; }
  std::uint32_t io_faults() const { return 0; }
  void fault_output(bool active) { fault_ = active; }
  bool fault() const { return fault_; }
  /// Joint torques the amplifiers produce from the last DAC codes.
  Vec6 torque() const {
    Vec6 t;
    for (int i = 0; i < hal::kJoints; ++i) t(i) = osc::code_to_torque(i, codes_[i]);
    return t;
  }

 private:
  Plant& plant_;
  Vec6 q_start_;
  double counts_per_rad_[hal::kJoints];
  std::int32_t codes_[hal::kJoints] = {0, 0, 0, 0, 0, 0};
  bool fault_ = false;
};
static_assert(hal::ControlHal<PlantHal>);

}  // namespace sim
