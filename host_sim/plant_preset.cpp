#include "plant_preset.hpp"

#include "osc/robot.hpp"

namespace sim {
namespace {

/// Today's plant: every feature off (PlantConfig's and SensorConfig's defaults).
void ideal(ExperimentConfig& cfg) {
  const PlantConfig p;
  const SensorConfig z;
  cfg.published_encoders = false;
  cfg.plant.coupling = p.coupling;
  cfg.plant.motor_inertia = p.motor_inertia;
  cfg.plant.amp_lag = p.amp_lag;
  cfg.plant.amp_current_limit = p.amp_current_limit;
  for (int i = 0; i < 6; ++i) {
    cfg.plant.amp_gain_error[i] = p.amp_gain_error[i];
    cfg.plant.amp_offset[i] = p.amp_offset[i];
    cfg.sensors.pot_offset[i] = z.pot_offset[i];
  }
  cfg.plant.ripple = p.ripple;
  cfg.plant.ripple_cycles = p.ripple_cycles;
  cfg.plant.backlash = p.backlash;
  cfg.plant.elastic_hz = p.elastic_hz;
  cfg.plant.friction_drift = p.friction_drift;
  cfg.plant.friction_drift_period = p.friction_drift_period;
  cfg.sensors.dac_bits = z.dac_bits;
  cfg.sensors.encoder_jitter = z.encoder_jitter;
  cfg.sensors.pot_noise = z.pot_noise;
  cfg.sensors.current_monitor = z.current_monitor;
  cfg.sensors.current_noise = z.current_noise;
  for (int i = 0; i < 6; ++i)
    cfg.sensors.current_gain[i] = z.current_gain[i], cfg.sensors.current_offset[i] = z.current_offset[i];
}

/// Every feature at its mid value. The published values where there are any (the encoders, the
/// coupling, the AKB86 motor inertias, the motor torque limits: osc::robot::kDriveTrain); the
/// others are estimates, each the middle of the range docs/experiment.md states.
void realistic(ExperimentConfig& cfg) {
  ideal(cfg);
  cfg.published_encoders = true;
  cfg.plant.coupling = true;
  cfg.plant.motor_inertia = &osc::robot::kDriveTrain.motor_inertia_alt;
  cfg.plant.amp_lag = 0.35e-3;  // estimate: a current loop of 0.2-0.5 ms
  cfg.plant.amp_current_limit = true;
  // Estimates: gain errors within +-1 %, offsets of 0.1 % of each channel's full scale, signs mixed.
  const double gain[6] = {0.008, -0.006, 0.004, -0.009, 0.005, -0.003};
  const double sign[6] = {1, -1, 1, -1, 1, -1};
  for (int i = 0; i < 6; ++i) {
    cfg.plant.amp_gain_error[i] = gain[i];
    cfg.plant.amp_offset[i] = sign[i] * 1e-3 * osc::robot::kDrives.torque_limit[i];
  }
  cfg.plant.ripple = 0.02;         // estimate: a few percent
  cfg.plant.ripple_cycles = 8;     // estimate: the motor's poles and commutator, per revolution
  cfg.plant.backlash = 0.5e-3;     // estimate: 0.1-1 mrad at the joint
  cfg.plant.elastic_hz = 20;       // estimate: 15-25 Hz locked-motor resonance on J1-J3
  cfg.plant.friction_drift = 0.3;  // +-30 % over an hour
  cfg.plant.friction_drift_period = 3600;
  cfg.sensors.dac_bits = 16;         // the board's AD5754R
  cfg.sensors.encoder_jitter = 0.1;  // estimate: edges within +-0.1 count
  cfg.sensors.pot_noise = 2;         // estimate: 2 codes rms of a 12-bit ADC
  // Estimates: offsets up to 20 codes, about the +-1.7 degrees a PUMA's pot is good for.
  const double pot[6] = {12, -8, 15, -20, 6, -10};
  for (int i = 0; i < 6; ++i) cfg.sensors.pot_offset[i] = pot[i];
  // The amplifiers' current monitors (the drive sheet's current_monitor group: gain within +-2 %, offset within
  // 0.2 % of full scale, 2 codes of noise): half of each, signs mixed.
  cfg.sensors.current_monitor = true;
  cfg.sensors.current_noise = 1;
  const double current_gain[6] = {0.01, -0.008, 0.006, -0.01, 0.007, -0.005};
  for (int i = 0; i < 6; ++i)
    cfg.sensors.current_gain[i] = current_gain[i], cfg.sensors.current_offset[i] = sign[i] * 1e-3;
}

struct Preset {
  const char* name;
  void (*apply)(ExperimentConfig&);
};
constexpr Preset kPresets[] = {{"ideal", ideal}, {"realistic", realistic}};

}  // namespace

std::vector<std::string> plant_preset_names() {
  std::vector<std::string> names;
  for (const Preset& p : kPresets) names.emplace_back(p.name);
  return names;
}

bool apply_plant_preset(const std::string& name, ExperimentConfig& cfg) {
  for (const Preset& p : kPresets)
    if (name == p.name) return p.apply(cfg), true;
  return false;
}

}  // namespace sim
