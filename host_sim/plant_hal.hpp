// HAL binding of the firmware's encoder and DAC interfaces (hal/hal.hpp) to the simulated plant,
// with the simulated hardware's faults (injection.hpp): stuck, jumping, garbage or noisy encoders,
// a stuck amplifier, an overrunning tick, the E-stop input.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "hal/hal.hpp"
#include "injection.hpp"
#include "osc/control/faults.hpp"
#include "osc/control/params.hpp"
#include "osc/runtime/io.hpp"
#include "plant.hpp"

namespace sim {

class PlantHal {
 public:
  /// Virtual nanoseconds per control period (the overrun budget the host-built task is given).
  static constexpr std::uint32_t kPeriodNs = 1000000000u / osc::params::kControlHz;

  /// counts_per_motor_rev: the encoders' resolution (default: the robot table's).
  PlantHal(Plant& plant, const Vec6& q_start,
           double counts_per_motor_rev = osc::robot::kDrives.encoder_counts_per_motor_rev, Injection inj = {})
      : plant_(plant), q_start_(q_start), inj_(inj) {
    for (int i = 0; i < hal::kJoints; ++i) {
      counts_per_rad_[i] = osc::counts_per_rad(i, counts_per_motor_rev);
      // The encoder change per tick at the joint's maximum speed (the firmware's bound, less one count).
      step_[i] = osc::counts_per_tick_at_max_speed(i, counts_per_rad_[i]);
    }
  }

  /// The simulated time of the sample about to be taken: activates an injected fault.
  void begin_sample(double t) {
    const bool was = active_;
    active_ = inj_.enabled && t >= inj_.at - 1e-12;
    first_ = active_ && !was;
    if (first_) t_inj_ = t;
    t_ = t;
  }
  bool injection_active() const { return active_; }

  /// Incremental encoders zeroed at q_start: counts = floor((q - q_start) * counts_per_rad). Every
  /// tick has a sample.
  bool read_encoders(std::int32_t counts[hal::kJoints]) {
    for (int i = 0; i < hal::kJoints; ++i) {
      counts[i] = static_cast<std::int32_t>(std::floor((plant_.q()(i) - q_start_(i)) * counts_per_rad_[i]));
      if (!active_ || !inj_.hits(i)) continue;
      switch (inj_.kind) {
        case InjectionKind::kEncoderStuck:
          if (first_) frozen_[i] = counts[i];
          counts[i] = frozen_[i];
          break;
        case InjectionKind::kEncoderJump:
          counts[i] += static_cast<std::int32_t>(std::ceil(10 * step_[i]));
          break;
        case InjectionKind::kEncoderGarbage:
          counts[i] = std::numeric_limits<std::int32_t>::max();
          break;
        case InjectionKind::kEncoderNoise:
          if (t_ < t_inj_ + kNoiseBurst) {
            std::uniform_real_distribution<double> u(-step_[i], step_[i]);
            counts[i] += static_cast<std::int32_t>(std::lround(u(rng_)));
          }
          break;
        default:
          break;
      }
    }
    return true;
  }
  void write_dacs(const std::int32_t codes[hal::kJoints]) {
    for (int i = 0; i < hal::kJoints; ++i)
      if (!(active_ && inj_.kind == InjectionKind::kDacStuck && inj_.hits(i))) codes_[i] = codes[i];
  }
  /// A virtual clock: one nanosecond per read, and three periods more inside an injected overrun.
  std::uint32_t cycles() {
    clock_ += 1;
    if (active_ && first_ && inj_.kind == InjectionKind::kOverrun && ++overrun_reads_ == 2) clock_ += 3 * kPeriodNs;
    return clock_;
  }
  /// The E-stop input.
  std::uint32_t io_faults() const {
    return active_ && inj_.kind == InjectionKind::kEstop ? static_cast<std::uint32_t>(osc::kFaultEstop) : 0u;
  }
  void fault_output(bool active) { fault_ = active; }
  bool fault() const { return fault_; }
  /// Joint torques the amplifiers produce from the last DAC codes. The fault line disables the
  /// amplifiers (as a board's amplifier-enable output does): zero torque whatever the codes.
  Vec6 torque() const {
    Vec6 t;
    if (fault_) return Vec6::Zero();
    for (int i = 0; i < hal::kJoints; ++i) t(i) = osc::code_to_torque(i, codes_[i]);
    return t;
  }

 private:
  static constexpr double kNoiseBurst = 0.05;  // [s]
  Plant& plant_;
  Vec6 q_start_;
  double counts_per_rad_[hal::kJoints];
  double step_[hal::kJoints];
  std::int32_t codes_[hal::kJoints] = {0, 0, 0, 0, 0, 0};
  bool fault_ = false;
  Injection inj_;
  bool active_ = false, first_ = false;
  double t_ = 0, t_inj_ = 0;
  std::int32_t frozen_[hal::kJoints] = {};
  std::uint32_t clock_ = 0;
  int overrun_reads_ = 0;
  std::mt19937 rng_{12345};
};
static_assert(hal::ControlHal<PlantHal>);

}  // namespace sim
