// The paper's experiment (Section VI) in closed loop: the firmware's control task, bound to the
// simulated plant through the HAL, tracking trajectory (68) for a given duration.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "osc/control/controller.hpp"
#include "injection.hpp"
#include "osc/control/gains.hpp"
#include "osc/link/frames.hpp"
#include "plant.hpp"

namespace sim {

/// The in-process controller's arithmetic: double, float, or the fixed-point Q12.19 of
/// osc/math/fixed.hpp.
enum class Scalar { kDouble, kFloat, kFixed };
/// Names of the scalars, in enum order (configuration, command lines).
constexpr const char* kScalarNames[] = {"double", "float", "fixed"};

struct ExperimentConfig {
  double duration = 120.0;  ///< [s]
  osc::FrictionMode mode = osc::FrictionMode::kAdaptive;
  Scalar scalar = Scalar::kDouble;  ///< controller arithmetic
  PlantConfig plant{};
  /// Encoder resolution of plant and controller alike (in-process controller only) [counts/motor rev].
  double encoder_counts_per_motor_rev = osc::robot::kDrives.encoder_counts_per_motor_rev;
  double model_error = 0.0;    ///< controller's link mass/inertia relative error
  double log_period = 0.01;    ///< time-series decimation [s]
  double final_window = 20.0;  ///< "last 20 s" statistics [s]
  double window = 60.0;        ///< length of the per-window maxima [s]
  /// The controller's gains (69), K_ad, tau_dec, adaptation law and trajectory (68), in double; the
  /// in-process controller casts them to its scalar. The firmware's defaults (params.hpp); a PIL
  /// image uses its own compiled-in values (only the adaptation law and mode go over the link).
  osc::Gains<double> gains = osc::Gains<double>::paper();
  Vec6 q_start = osc::joint_vector<double>(osc::robot::kQStart);  ///< start pose of the task [rad]
  double observer_offset[6] = {0, 0, 0, 0, 0, 0};                 ///< x^(0) - x(0), to test observer convergence
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

/// One logged sample of the time series.
struct LogRow {
  double t;
  double e[6];         // tracking error of the true plant: mm (x, y, z), deg (about X, Y, Z)
  double x_tilde[6];   // observer position error: mm, deg
  double xd_tilde[6];  // observer velocity error x^dot - x dot (true): mm/s, deg/s
  double tau[6];       // joint torque the amplifiers applied [N m]
  double theta_hat[18];
  double tau_f[6];      // true plant friction [N m]
  double tau_f_hat[6];  // estimated friction (30) [N m]
};

/// What an injected fault did (ExperimentConfig::injection).
struct InjectionResult {
  Injection injection;
  double detected = -1;         ///< [s] first tick with a fault at or after the injection (-1: never)
  std::uint32_t faults = 0;     ///< the fault bits raised in that tick
  double zero_torque = -1;      ///< [s] first sample from which every amplifier torque is zero (-1: never)
  double excursion_mm = 0;      ///< largest |p - p_d| of the true tip from injection to zero torque (or the end)
  double max_torque_after = 0;  ///< largest |tau| an amplifier applied after detection [N m]
  int max_torque_joint = -1;    ///< its joint (0-based)
};

/// Link health of a processor-in-the-loop run.
struct LinkReport {
  pil::LinkCounters firmware;         // errors the firmware counted on the sensor frames
  pil::LinkCounters host;             // errors the host counted on the actuator frames
  std::uint32_t host_code_range = 0;  // answers with a DAC code out of range (applied as zero)
  std::uint32_t zeroed_ticks = 0;     // ticks whose amplifiers got zero because of a link error
  std::string first_zeroed;           // why the first of them was zeroed
  /// The firmware's longest gap between received bytes [cycles = instructions under QEMU -icount
  /// shift=0 = ns of its virtual time], and the gaps longer than params::kLinkSilenceTicks periods.
  std::uint32_t rx_gap_max = 0, rx_long_gaps = 0;
  bool clean() const { return firmware.total() == 0 && host.total() == 0 && host_code_range == 0 && zeroed_ticks == 0; }
};

/// The state of the plant and the controller at the tick a fault latched.
struct FaultState {
  long tick = -1;                ///< sample index (-1: no fault)
  double t = -1;                 ///< [s]
  std::uint32_t faults = 0;      ///< the fault bits of that tick
  double q[6] = {}, qd[6] = {};  ///< plant joint angles [rad] and speeds [rad/s]
  double tau[6] = {};            ///< torque the amplifiers applied in the sample before [N m]
  double e[6] = {};              ///< tracking error: mm, deg
  double theta_hat[18] = {};     ///< the friction estimates
};

struct ExperimentResult {
  std::string mode;
  std::string friction_preset;
  double duration = 0;
  double max_error[6] = {};                    // over the whole run: mm, mm, mm, deg, deg, deg
  double final_max_error[6] = {};              // over the last final_window seconds
  double max_observer_error[6] = {};           // |x~| over the last final_window seconds: mm, deg
  double max_observer_velocity_error[6] = {};  // |x^dot - x dot| over the last final_window seconds: mm/s, deg/s
  bool has_observer = false;                   // the observer's errors are known (in-process controller)
  /// The statistics (errors, windows, theta^) cover the run up to the fault's tick only, when one
  /// latched: after it the amplifiers are off and the robot falls, which is no result.
  double stats_until = 0;  // [s]
  double theta_hat[18] = {};
  double theta_true[18] = {};
  double final_window = 0;         // [s] of the "last" statistics
  double theta_min_seen[18] = {};  // extremes of each theta^ over the run
  double theta_max_seen[18] = {};
  double window = 0;                                      // [s]
  std::vector<std::array<double, 6>> window_max;          // max |e| per consecutive window: mm, deg
  std::vector<std::array<double, 2>> window_theta_range;  // min and max of all theta^ per window
  std::string adaptation;                                 // the adaptation law's name
  double friction_rms_error = 0;                          // rms of tau_f_hat - tau_f over the last window [N m]
  double friction_rms = 0;                                // rms of tau_f over the last window [N m]
  double stuck_peak[6] = {};
  double stuck_dtau_peak[6] = {};         // the stuck-encoder monitor's largest torque change [N m] (in process)
  double stuck_dtau_silent_peak[6] = {};  // ... while the encoder was also silent (kStuckTorqueSilent) [N m]
  std::uint32_t status = 0;               // first fault bits reported (0: none)
  double fault_time = -1;                 // [s] of the first fault (-1: none)
  FaultState fault;                       // where and how the first fault latched
  InjectionResult injection;              // when cfg.injection.enabled
  std::string error;                      // link error (PIL), empty when the run completed
  std::uint32_t max_step_cycles = 0, mean_step_cycles = 0, max_tick_cycles = 0,
                stack_used = 0;  // firmware telemetry (PIL)
  LinkReport link;               // PIL only
  double wall_seconds = 0;
  double cpu_seconds = 0;      // CPU time of the thread that ran it (wall time counts other jobs too)
  long plant_evaluations = 0;  // articulated-body evaluations of the plant over the run
  std::vector<LogRow> log;
};

/// A run's mode as the outputs name it: "adaptive" or "none".
inline const char* mode_name(osc::FrictionMode m) { return m == osc::FrictionMode::kAdaptive ? "adaptive" : "none"; }

ExperimentResult run_experiment(const ExperimentConfig& cfg);

/// Paper tables (NOTES.md) for side-by-side printing.
extern const double kPaperTable1[6];
extern const double kPaperTable3[6];

}  // namespace sim
