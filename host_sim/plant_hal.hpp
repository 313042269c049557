// HAL binding of the firmware's encoder and DAC interfaces (hal/hal.hpp) to the simulated plant,
// with the simulated hardware's sensors (SensorConfig: the encoders' resolution, coupling and edge
// jitter, the DAC's resolution, the potentiometers, the index pulses) and faults (injection.hpp):
// stuck, jumping, garbage or noisy encoders, an amplifier whose input is stuck, zero or full scale,
// an amplifier off, an overrunning tick, the E-stop input. (A contact at the tip acts in the plant:
// Plant::set_contact.)
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "hal/hal.hpp"
#include "injection.hpp"
#include "osc/control/faults.hpp"
#include "osc/control/params.hpp"
#include "osc/runtime/io.hpp"
#include "plant.hpp"

namespace sim {

/// The simulated hardware's sensors: encoder resolution and coupling, encoder edge jitter, the
/// DAC's resolution, potentiometer noise and offsets. The default is the ideal plant's hardware,
/// bit for bit: uniform 1000-count encoders without coupling or jitter, 16-bit DACs.
struct SensorConfig {
  /// The encoders' resolution and coupling. They count the plant's motor_angles(): a coupled map
  /// reads the joints through C only on a plant whose motors turn as C^-1 q.
  osc::EncoderMap encoders = osc::robot::kEncodersUniform;
  /// Encoder edge jitter: each sample's edge positions move by up to +-this fraction of a count
  /// (uniform, fresh each sample); 0: none.
  double encoder_jitter = 0;
  /// The amplifiers see only the top dac_bits bits of the 16-bit codes (a coarser board's DAC,
  /// dac_quantise: to nearest); 16: today.
  int dac_bits = 16;
  double pot_noise = 0;        ///< potentiometer noise, standard deviation [ADC codes]
  double pot_offset[6] = {};   ///< potentiometer offset per joint [ADC codes]
  std::uint8_t index_off = 0;  ///< bit c: channel c's index pulse never fires (a broken index track)
  /// The amplifiers' current monitors, read back (hal::CurrentHal: read_currents gives false without): each
  /// reads its amplifier's current on osc::robot::kDriveTrain.current's ADC, with a gain error, an offset
  /// (of the DAC's full scale) and Gaussian noise [ADC codes].
  bool current_monitor = false;
  double current_gain[6] = {};
  double current_offset[6] = {};
  double current_noise = 0;
  std::uint32_t seed = 12345;  ///< the noise generators' seed (runs are reproducible)
};

/// Uniform encoders of counts_per_motor_rev on every motor, no coupling, the rest as the default.
inline SensorConfig sensors_with_resolution(double counts_per_motor_rev) {
  SensorConfig s;
  s.encoders = osc::uniform_encoders("uniform", osc::robot::kArm, counts_per_motor_rev);
  return s;
}

/// The coupling of an encoder map: C, unit lower triangular (q - q_start = C e), its inverse by
/// forward substitution, and the maps of angles and torques through them.
struct EncoderCoupling {
  double c[hal::kJoints][hal::kJoints] = {};
  double inverse[hal::kJoints][hal::kJoints] = {};
  bool coupled = false;

  explicit EncoderCoupling(const osc::EncoderMap& map) : coupled(map.coupling_terms != 0) {
    osc::coupling_matrices(map, c, inverse);
  }
  /// The motor angles (referred to their joints) of joint angles q: C^-1 q (q itself uncoupled).
  Vec6 motor_from_joint(const Vec6& q) const {
    if (!coupled) return q;
    Vec6 e;
    for (int i = 0; i < hal::kJoints; ++i) {
      e(i) = q(i);
      for (int k = 0; k < i; ++k) e(i) -= c[i][k] * e(k);
    }
    return e;
  }
  /// The joint torques that motor torques tau_m (referred to their joints) produce: C^-T tau_m
  /// (what a coupled plant applies), by back substitution of C^T tau = tau_m.
  Vec6 joint_from_motor_torques(const Vec6& tau_m) const {
    if (!coupled) return tau_m;
    Vec6 tau;
    for (int i = hal::kJoints - 1; i >= 0; --i) {
      tau(i) = tau_m(i);
      for (int k = i + 1; k < hal::kJoints; ++k) tau(i) -= c[k][i] * tau(k);
    }
    return tau;
  }
};

/// One encoder channel's count: floor((e - e_start) * counts_per_rad + edge_shift), e the motor's
/// angle referred to its joint, e_start the same at the start pose, edge_shift the sample's edge
/// jitter [counts] (0: the ideal encoder).
inline std::int32_t encoder_count(double e, double e_start, double counts_per_rad, double edge_shift = 0) {
  const double x = (e - e_start) * counts_per_rad;
  return static_cast<std::int32_t>(std::floor(edge_shift == 0 ? x : x + edge_shift));
}

/// A DAC code as a board whose DAC has only the top `bits` of the 16-bit codes outputs it: to the
/// nearest multiple of 2^(16 - bits) (ties up), within that DAC's symmetric range
/// +-(2^15 - 2^(16 - bits)). 16 bits: the code itself.
inline std::int32_t dac_quantise(std::int32_t code, int bits) {
  if (bits >= 16) return code;
  const int shift = 16 - (bits < 1 ? 1 : bits);
  const std::int32_t step = std::int32_t{1} << shift, top = 32768 - step;
  const std::int32_t q = ((code + step / 2) >> shift) * step;  // >>: floor (C++20)
  return q > top ? top : (q < -top ? -top : q);
}

/// The potentiometer's ADC: full scale 2^pot_bits - 1 codes.
/// (An arm without potentiometers, pot_bits 0: 1, never read.)
inline constexpr double kPotFullScale = osc::robot::kDriveTrain.pot_bits > 0
                                            ? static_cast<double>((1 << osc::robot::kDriveTrain.pot_bits) - 1)
                                            : 1.0;
/// A joint angle's exact (unrounded, noise-free) potentiometer code.
inline double pot_scale(int joint, double q) {
  const auto& d = osc::robot::kDriveTrain;
  return (q - d.pot_min[joint]) / (d.pot_max[joint] - d.pot_min[joint]) * kPotFullScale;
}
/// The joint angle of a potentiometer code: the inverse of pot_scale.
inline double pot_to_angle(int joint, double code) {
  const auto& d = osc::robot::kDriveTrain;
  return d.pot_min[joint] + code / kPotFullScale * (d.pot_max[joint] - d.pot_min[joint]);
}

/// One motor's index pulse: fires where the shaft angle theta = G e passes index_angle + 2 pi k,
/// either direction. Each sample latches the encoder count at the last crossing since the previous
/// sample, interpolated linearly between the two samples' counts and rounded.
class IndexPulse {
 public:
  explicit IndexPulse(double index_angle = 0) : angle_(index_angle) {}
  /// One sample: the shaft angle [rad, from its angle at q = 0] and the encoder count.
  void sample(double theta, std::int32_t count) {
    if (!std::isfinite(theta)) return;  // a diverged plant: no sample
    const long long n = turn(theta);
    if (primed_ && n != n_) {
      const long long crossed = n > n_ ? n - n_ : n_ - n;
      // The last level crossed: moving up, the top one (turn n); moving down, the bottom one (n + 1).
      const double level = angle_ + 2 * osc::kPi * static_cast<double>(n > n_ ? n : n + 1);
      const double s = (level - theta_) / (theta - theta_);
      latched_ = static_cast<std::int32_t>(
          std::lround(static_cast<double>(count_) + s * (static_cast<double>(count) - static_cast<double>(count_))));
      pending_ = true;
      pulses_ += crossed;
    }
    primed_ = true;
    n_ = n;
    theta_ = theta;
    count_ = count;
  }
  /// True once per latched pulse (the last latch in count); false when none since the last take.
  bool take(std::int32_t& count) {
    if (!pending_) return false;
    count = latched_;
    pending_ = false;
    return true;
  }
  /// Pulses seen since construction (each level crossing, either direction).
  long long pulses() const { return pulses_; }

 private:
  /// The index level below theta (levels angle_ + 2 pi k): theta in [level k, level k + 1).
  long long turn(double theta) const { return static_cast<long long>(std::floor((theta - angle_) / (2 * osc::kPi))); }
  double angle_;
  bool primed_ = false, pending_ = false;
  long long n_ = 0, pulses_ = 0;
  double theta_ = 0;
  std::int32_t count_ = 0, latched_ = 0;
};

class PlantHal {
 public:
  /// Virtual nanoseconds per control period (the overrun budget the host-built task is given).
  static constexpr std::uint32_t kPeriodNs = 1000000000u / osc::params::kControlHz;

  /// The encoders are zeroed at q_start; sensors: their resolution, coupling and noise (default:
  /// the ideal plant's); inj: a simulated hardware fault.
  PlantHal(Plant& plant, const Vec6& q_start, const SensorConfig& sensors = {}, Injection inj = {})
      : plant_(plant),
        sensors_(sensors),
        coupling_(sensors.encoders),
        // Zeroed where the motors stand: an elastic joint's motor sits off its link by the
        // deflection that holds the arm (zero on a rigid plant, and before the plant's reset).
        e_start_(coupling_.motor_from_joint(q_start) + (plant.motor_angles() - coupling_.motor_from_joint(plant.q()))),
        inj_(inj),
        rng_(sensors.seed),
        jitter_rng_(generator(sensors.seed, 1)),
        pot_rng_(generator(sensors.seed, 2)),
        current_rng_(generator(sensors.seed, 3)) {
    for (int i = 0; i < hal::kJoints; ++i) {
      counts_per_rad_[i] = sensors.encoders.counts_per_rad[i];
      // The encoder change per tick at the joint's maximum speed (the firmware's bound, less one
      // count); a coupled channel's motor turns with the other joints too.
      step_[i] = coupling_.coupled ? osc::counts_per_tick_at_max_speed(i, counts_per_rad_[i], coupling_.inverse)
                                   : osc::counts_per_tick_at_max_speed(i, counts_per_rad_[i]);
      index_[i] = IndexPulse(osc::robot::kDriveTrain.index_angle[i]);
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
  /// A stuck encoder's joint's last breakaway at or before t [s]: the first count the frozen encoder missed (the
  /// first sample whose true count differs from the frozen one), or a later first count after the joint had stood
  /// kStood without one; -1: none (no encoder-stuck injection, or the joint has not moved).
  double breakaway_before(double t) const {
    double last = -1;
    for (const double b : breakaways_)
      if (b <= t + 1e-12) last = b;
    return last;
  }
  static constexpr double kStood = 0.02;  ///< [s] without a true count: the joint stood (static friction held it)

  /// Incremental encoders on the motors, zeroed at q_start: channel i counts
  /// floor((e_i - e_start_i) * counts_per_rad_i + u), e the plant's motor angles (referred to their
  /// joints), e_start theirs at q_start, u the edge jitter. Every tick has a sample; each samples the
  /// index pulses too (on the counts before an injected fault: the board's counter latches them).
  bool read_encoders(std::int32_t counts[hal::kJoints]) {
    const Vec6 e = plant_.motor_angles();
    const double a = sensors_.encoder_jitter > 0 ? sensors_.encoder_jitter : 0.0;
    std::uniform_real_distribution<double> jitter(-a, a);
    for (int i = 0; i < hal::kJoints; ++i) {
      const double shift = a > 0 ? jitter(jitter_rng_) : 0.0;
      counts[i] = encoder_count(e(i), e_start_(i), counts_per_rad_[i], shift);
      if ((sensors_.index_off >> i & 1u) == 0) index_[i].sample(osc::robot::kArm.links[i].gear_ratio * e(i), counts[i]);
      if (!active_ || !inj_.hits(i)) continue;
      switch (inj_.kind) {
        case InjectionKind::kEncoderStuck:
          if (first_) frozen_[i] = last_true_[i] = counts[i];
          note_true_count(i, counts[i]);
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
            std::uniform_real_distribution<double> noise(-step_[i], step_[i]);
            counts[i] += static_cast<std::int32_t>(std::lround(noise(rng_)));
          }
          break;
        default:
          break;
      }
    }
    return true;
  }
  /// The codes the amplifiers receive: the controller's, unless a DAC fault holds a channel's at its
  /// last value (dac-stuck), at zero (dac-zero) or at the positive full scale (dac-full).
  void write_dacs(const std::int32_t codes[hal::kJoints]) {
    for (int i = 0; i < hal::kJoints; ++i) {
      if (!active_ || !inj_.hits(i)) {
        codes_[i] = codes[i];
        continue;
      }
      switch (inj_.kind) {
        case InjectionKind::kDacStuck:  // the code it had
          break;
        case InjectionKind::kDacZero:
          codes_[i] = 0;
          break;
        case InjectionKind::kDacFull:
          codes_[i] = static_cast<std::int32_t>(osc::kDacMaxCode);
          break;
        default:
          codes_[i] = codes[i];
      }
    }
  }
  /// The code amplifier i receives now.
  std::int32_t code(int i) const { return codes_[i]; }
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
  /// The channels' (motor) torques, referred to their joints, that the amplifiers produce from the
  /// last DAC codes, as the board's DAC resolves them (dac_quantise). The fault line disables the
  /// amplifiers (as a board's amplifier-enable output does): zero torque whatever the codes; so does
  /// an amplifier that is off (amp-off), on its own channel.
  Vec6 torque() const {
    Vec6 t;
    if (fault_) return Vec6::Zero();
    for (int i = 0; i < hal::kJoints; ++i) {
      const bool off =
          active_ && (inj_.kind == InjectionKind::kAmpOff || inj_.kind == InjectionKind::kAmpFault) && inj_.hits(i);
      t(i) = off ? 0.0 : osc::code_to_torque(i, dac_quantise(codes_[i], sensors_.dac_bits));
    }
    return t;
  }

  /// The potentiometers: code = clamp(round(pot_scale(q) + offset + noise), 0, full scale), q the
  /// plant's joint angles, the noise Gaussian of standard deviation pot_noise.
  bool read_pots(std::uint16_t codes[hal::kJoints]) {
    const Vec6& q = plant_.q();
    for (int i = 0; i < hal::kJoints; ++i) {
      double x = pot_scale(i, q(i)) + sensors_.pot_offset[i];
      if (sensors_.pot_noise > 0) x += sensors_.pot_noise * gauss_(pot_rng_);
      x = std::round(x);
      codes[i] = static_cast<std::uint16_t>(!(x > 0) ? 0.0 : (x >= kPotFullScale ? kPotFullScale : x));
    }
    return true;
  }

  /// The current monitors (SensorConfig::current_monitor; false without): each channel's amplifier current
  /// (Plant::amplifier_currents, as a joint-referred torque) on the ADC's scale, +-adc_max at +-range times
  /// the DAC's full scale: code = clamp(round((1 + gain) i / (range FS) adc_max + offset adc_max / range +
  /// noise)); an injected monitor fault: frozen, zero or half the reading.
  bool read_currents(std::int16_t adc[hal::kJoints]) {
    if (!sensors_.current_monitor) return false;
    const osc::CurrentMonitor& m = osc::robot::kDriveTrain.current;
    const auto top = static_cast<double>(osc::current_max_code(m));
    const Vec6 current = plant_.amplifier_currents();
    for (int i = 0; i < hal::kJoints; ++i) {
      const double fs = osc::robot::kDrives.torque_limit[i];
      double x = ((1 + sensors_.current_gain[i]) * current(i) / fs + sensors_.current_offset[i]) / m.range * top;
      if (sensors_.current_noise > 0) x += sensors_.current_noise * gauss_(current_rng_);
      const bool hit = active_ && inj_.hits(i);
      if (hit && inj_.kind == InjectionKind::kCurrentZero) x = 0;
      if (hit && inj_.kind == InjectionKind::kCurrentGain) x *= 0.5;
      x = std::round(x);
      auto code = static_cast<std::int16_t>(x > top ? top : (x < -top ? -top : x));
      if (hit && inj_.kind == InjectionKind::kCurrentStuck) {
        if (first_current_[i]) frozen_current_[i] = last_current_[i], first_current_[i] = false;
        code = frozen_current_[i];
      }
      last_current_[i] = code;
      adc[i] = code;
    }
    return true;
  }
  /// The amplifiers' fault lines: an injected amplifier trip (amp-fault).
  std::uint32_t amp_faults() const {
    if (!active_ || inj_.kind != InjectionKind::kAmpFault) return 0;
    return inj_.joint < 0 ? (1u << hal::kJoints) - 1u : 1u << inj_.joint;
  }

  /// The index pulse latched on a channel since the last call: true once per latch, with the
  /// encoder count at the pulse (the last one when several fired).
  bool take_index(int channel, std::int32_t& count) { return index_[channel].take(count); }
  /// Index pulses a channel has seen (either direction).
  long long index_pulses(int channel) const { return index_[channel].pulses(); }

  const SensorConfig& sensors() const { return sensors_; }
  const EncoderCoupling& coupling() const { return coupling_; }
  /// The motor angles at q_start (referred to their joints): where the encoders count from.
  const Vec6& motor_start() const { return e_start_; }

 private:
  /// A stuck channel's true count this sample (breakaway_before()).
  void note_true_count(int i, std::int32_t count) {
    if (count == last_true_[i]) return;
    if (breakaways_.empty() || t_ - last_true_change_ > kStood + 1e-12) breakaways_.push_back(t_);
    last_true_change_ = t_, last_true_[i] = count;
  }
  static constexpr double kNoiseBurst = 0.05;  // [s]
  /// A generator of its own per noise source (the encoders' jitter does not move the pots' noise).
  static std::mt19937 generator(std::uint32_t seed, std::uint32_t stream) {
    std::seed_seq seq{seed, stream};
    return std::mt19937(seq);
  }
  Plant& plant_;
  SensorConfig sensors_;
  EncoderCoupling coupling_;
  Vec6 e_start_;
  double counts_per_rad_[hal::kJoints];
  double step_[hal::kJoints];
  IndexPulse index_[hal::kJoints];
  std::int32_t codes_[hal::kJoints] = {0, 0, 0, 0, 0, 0};
  bool fault_ = false;
  Injection inj_;
  bool active_ = false, first_ = false;
  double t_ = 0, t_inj_ = 0;
  std::vector<double> breakaways_;             // breakaway_before()
  double last_true_change_ = -1;               // the last change of a stuck channel's true count [s]
  std::int32_t last_true_[hal::kJoints] = {};  // each stuck channel's true count then
  std::int32_t frozen_[hal::kJoints] = {};
  std::uint32_t clock_ = 0;
  int overrun_reads_ = 0;
  std::mt19937 rng_;                                // the injected encoder noise
  std::mt19937 jitter_rng_;                         // the encoders' edge jitter
  std::mt19937 pot_rng_;                            // the potentiometers' noise
  std::mt19937 current_rng_;                        // the current monitors' noise
  std::int16_t last_current_[hal::kJoints] = {};    // each monitor's last reading
  std::int16_t frozen_current_[hal::kJoints] = {};  // ... frozen (current-stuck)
  bool first_current_[hal::kJoints] = {true, true, true, true, true, true};
  std::normal_distribution<double> gauss_{0.0, 1.0};
};
static_assert(hal::ControlHal<PlantHal>);
static_assert(hal::PositionHal<PlantHal>, "the simulated arm has potentiometers and index pulses");
static_assert(hal::CurrentHal<PlantHal>, "the simulated arm's amplifiers have current monitors (SensorConfig)");

}  // namespace sim
