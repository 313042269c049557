// The paper's experiment (Section VI) in closed loop: the firmware's control task, bound to the
// simulated plant through the HAL, tracking trajectory (68) for a given duration.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "osc/control/controller.hpp"
#include "injection.hpp"
#include "metrics.hpp"
#include "osc/control/gains.hpp"
#include "osc/link/frames.hpp"
#include "osc/runtime/motion_states.hpp"
#include "osc/runtime/parameters.hpp"
#include "plant.hpp"
#include "plant_hal.hpp"

namespace sim {

/// The in-process controller's arithmetic: double, float, or the fixed-point Q12.19 of
/// osc/math/fixed.hpp.
enum class Scalar { kDouble, kFloat, kFixed };
/// Names of the scalars, in enum order (configuration, command lines).
constexpr const char* kScalarNames[] = {"double", "float", "fixed"};

/// The runtime parameters' defaults (osc::param_default), by the table's slots.
inline std::array<double, osc::kParamSlots> default_params() {
  std::array<double, osc::kParamSlots> a{};
  for (int i = 0; i < osc::kParamCount; ++i)
    for (int e = 0; e < osc::kParams[i].count; ++e) a[osc::param_slot(i) + e] = osc::param_default(i, e);
  return a;
}

struct ExperimentConfig {
  double duration = 120.0;  ///< [s]
  osc::FrictionMode mode = osc::FrictionMode::kAdaptive;
  Scalar scalar = Scalar::kDouble;  ///< controller arithmetic
  PlantConfig plant{};
  /// Encoder resolution of plant and controller alike (in-process controller only) [counts/motor rev],
  /// on every motor: the uniform encoders.
  double encoder_counts_per_motor_rev = osc::robot::kDrives.encoder_counts_per_motor_rev;
  /// The arm's own encoders instead (osc::robot::kDriveTrain.encoders' resolutions).
  bool published_encoders = false;
  /// The plant's sensors: jitter, DAC resolution, potentiometers (the encoders' map is encoder_map()'s).
  SensorConfig sensors{};
  /// The encoders of plant and controller alike: uniform or the arm's own, coupled as the plant is
  /// (plant.coupling).
  osc::EncoderMap encoder_map() const {
    osc::EncoderMap m = published_encoders
                            ? osc::robot::kDriveTrain.encoders
                            : osc::uniform_encoders("uniform", osc::robot::kArm, encoder_counts_per_motor_rev);
    if (published_encoders) m.name = plant.coupling ? "trident" : "trident, uncoupled";
    if (!plant.coupling) m.coupling_terms = 0;
    if (plant.coupling && !published_encoders) {
      m.coupling_terms = osc::robot::kDriveTrain.encoders.coupling_terms;
      for (int k = 0; k < m.coupling_terms; ++k) m.coupling[k] = osc::robot::kDriveTrain.encoders.coupling[k];
    }
    return m;
  }
  /// The plant's sensors with encoder_map()'s encoders.
  SensorConfig sensor_config() const {
    SensorConfig s = sensors;
    s.encoders = encoder_map();
    return s;
  }
  double model_error = 0.0;  ///< controller's link mass/inertia relative error
  /// The residual monitor raises the faults in place of the stuck-encoder monitor (the runtime
  /// parameter residual_monitor, armed by default); false runs it as a trial (in-process controller
  /// only: an image runs its parameter's default, docs/safety.md).
  bool residual_monitor = osc::params::kResidualMonitorArmed;
  /// What a collision does, and each joint's collision threshold [N m] (0: the derived threshold
  /// alone); with residual_monitor only (osc::ControlTask::set_collision).
  osc::CollisionReaction collision_reaction = osc::CollisionReaction::kCategory0;
  double collision_threshold[6] = {0, 0, 0, 0, 0, 0};
  /// The runtime parameters (osc/runtime/parameters.hpp) of the in-process controller that have no
  /// field of their own here (runtime_param_key: null): their values, by the table's slots.
  std::array<double, osc::kParamSlots> params = default_params();
  double log_period = 0.01;    ///< time-series decimation [s]
  double final_window = 20.0;  ///< "last 20 s" statistics [s]
  double window = 60.0;        ///< length of the per-window maxima [s]
  /// The controller's gains (69), K_ad, tau_dec, adaptation law and trajectory (68), in double; the
  /// in-process controller casts them to its scalar. The firmware's defaults (params.hpp); a PIL
  /// image uses its own compiled-in values (only the adaptation law and mode go over the link).
  osc::Gains<double> gains = osc::Gains<double>::paper();
  Vec6 q_start = osc::joint_vector<double>(osc::robot::kQStart);  ///< start pose of the task [rad]
  /// The simulated arm's pose at power-on (motion scripts, in process): none, the arm placed at the
  /// start pose and declared there (the paper's procedure); else the pose where it powers on, its
  /// encoders counting from there while the firmware assumes q_start: not homed, it refuses motion
  /// (not_homed) until a home or a declare_pose (plant.power_on_pose; power_on_text as configured:
  /// start, random:SEED, or the pose's degrees).
  std::optional<Vec6> power_on_pose;
  std::string power_on_text = "start";
  double observer_offset[6] = {0, 0, 0, 0, 0, 0};  ///< x^(0) - x(0), to test observer convergence
  /// Uptime test (in-process controller only): at jump_at [s] the controller's sample counter
  /// advances by jump_ticks, as if it had been running that much longer (a multiple of the
  /// trajectory's period keeps the reference unchanged).
  double jump_at = -1;
  std::uint64_t jump_ticks = 0;
  Injection injection;                            ///< a fault of the simulated hardware (none by default)
  std::function<void(double fraction)> progress;  ///< optional progress callback
  /// Processor-in-the-loop: the command that starts the firmware (e.g. qemu-system-arm with the
  /// image, see PilClient::qemu_command); empty runs the host-built controller in process.
  std::vector<std::string> pil_command;
  double pil_timeout = 10.0;  ///< wall-clock wait per actuator frame [s]
};

/// A random power-on pose (plant.power_on_pose random:SEED): each joint of `around` moved by up to
/// +-25 degrees, uniformly, within the joint limits less 5 degrees, the wrist's q5 kept 15 degrees
/// from its singularity at 0.
inline Vec6 random_power_on_pose(std::uint32_t seed, const Vec6& around) {
  constexpr double kDeg = osc::kPi / 180;
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> u(-25 * kDeg, 25 * kDeg);
  Vec6 q = around;
  for (int i = 0; i < 6; ++i) {
    q(i) += u(g);
    q(i) = std::min(std::max(q(i), osc::robot::kArm.q_min[i] + 5 * kDeg), osc::robot::kArm.q_max[i] - 5 * kDeg);
  }
  if (std::abs(q(4)) < 15 * kDeg) q(4) = q(4) < 0 ? -15 * kDeg : 15 * kDeg;
  return q;
}

/// The configuration key of a runtime parameter that the host keys by a name of its own (a law's or a
/// reaction's name rather than its code), or null: the key is then run.<the parameter's name>, made
/// from the table (host_sim/config.cpp). test_gain_keys checks both kinds against the table.
constexpr const char* runtime_param_key(osc::RuntimeParam p) {
  switch (p) {
    case osc::RuntimeParam::kParamAdaptation:
      return "run.adaptation";
    case osc::RuntimeParam::kParamCollisionReaction:
      return "run.collision_reaction";
    case osc::RuntimeParam::kParamCollisionThreshold:
      return "run.collision_threshold";
    case osc::RuntimeParam::kParamResidualMonitor:
      return "run.residual_monitor";
    default:
      return nullptr;
  }
}

/// Whether a parameter's host key is run.<its name>, made from the table (a runtime parameter without a
/// key of its own).
constexpr bool runtime_param_generated(const osc::ParamInfo& p) {
  return p.gain < 0 && runtime_param_key(p.runtime) == nullptr;
}

/// The residual monitor's settings of a run on the task of a host-built controller
/// (osc::ControlTask): armed or a trial, the collision's reaction and thresholds; and the runtime
/// parameters of cfg.params, each checked as a board's param set would (osc::param_value_status).
template <class Task>
void configure_monitors(Task& task, const ExperimentConfig& cfg) {
  task.residual.armed = cfg.residual_monitor;
  if (!task.set_collision(cfg.collision_reaction, cfg.collision_threshold))
    throw std::invalid_argument("run.collision_threshold: outside [0, the joint's full-scale torque]");
  for (int i = 0; i < osc::kParamCount; ++i) {
    const osc::ParamInfo& p = osc::kParams[i];
    if (!runtime_param_generated(p)) continue;
    // Before the first tick, as a board's boot applies its stored record: each value checked, the
    // access (torque off) not, the task starting in the paper's motion.
    for (int e = 0; e < p.count; ++e) {
      const double v = cfg.params[osc::param_slot(i) + e];
      const osc::ParamStatus st = osc::param_value_status<std::decay_t<decltype(task.gains.dt)>>(i, e, v);
      if (st != osc::ParamStatus::kOk)
        throw std::invalid_argument(std::string("run.") + p.name + ": " + osc::param_status_name(st));
      osc::param_put(task, i, e, v);
    }
  }
}

/// A run: its name and set-up, then its metrics (metrics.hpp), in the order of its JSON and console
/// lines. A new per-run metric is one more name in this list.
struct ExperimentResult
    : Metrics<FaultSnapshot, TrackingMaxima, ObserverMaxima, WindowMaxima, FrictionEstimates, FrictionRms,
              StuckMonitorPeaks, FirmwareReport, InjectionTracking, RunCost, TimeSeries> {
  std::string mode;  // "adaptive" or "none"
  std::string friction_preset;
  double duration = 0;     // [s]
  std::string adaptation;  // the adaptation law's name
};

/// A run's mode as the outputs name it: "adaptive" or "none".
inline const char* mode_name(osc::FrictionMode m) { return m == osc::FrictionMode::kAdaptive ? "adaptive" : "none"; }

ExperimentResult run_experiment(const ExperimentConfig& cfg);

/// Paper tables (NOTES.md) for side-by-side printing.
extern const double kPaperTable1[6];
extern const double kPaperTable3[6];

}  // namespace sim
