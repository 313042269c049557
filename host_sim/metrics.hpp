// The results of a run, as small accumulators ("metrics"): each sees every control sample, keeps
// what it measures under its own names (the units in the comments and the JSON keys), and writes
// its JSON keys and its console line, if it has one. ExperimentResult (experiment.hpp) derives from
// the list of them, so that r.max_error is TrackingMaxima's; run() (experiment.cpp), json_run
// (summary.cpp) and the console (print_metric_lines) go through that list in its order.
//
// A metric is a struct with its results as public members and any of, in this order of use:
//   void begin(const ExperimentConfig&);           before the first sample (its window, the true friction)
//   void observe(const Sample&);                   every control sample
//   void end();                                    after the last (an rms from its sums)
//   void to_json(Json&) const;                     its keys of the run's JSON object
//   void print(const ExperimentResult&) const;     its console line(s) for one run
// Adding one: the struct here, its functions in metrics.cpp, its name in ExperimentResult's list,
// and its tests (tests/host_sim/test_metrics.cpp). docs/architecture.md, "Adding a per-run metric".
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "injection.hpp"
#include "osc/link/frames.hpp"
#include "plant.hpp"

namespace sim {

struct ExperimentConfig;
struct ExperimentResult;
using Json = nlohmann::ordered_json;

/// n numbers as a JSON array.
Json json_array(const double* v, int n);
/// The residual monitor's first detection as JSON: {t_s, fault, joint (1-based)}, or null for none
/// (fault 0).
Json residual_detection_json(double t_s, std::uint32_t fault, int joint);

/// What the controller reports back each tick.
struct TickReport {
  std::uint32_t faults = 0;
  bool has_observer = false;  // x_tilde is available (in-process controller only)
  double x_tilde[6] = {};
  double xd_hat[6] = {};  // the observer's velocity estimate: m/s, rad/s (in-process only)
  double tau_f_hat[6] = {};
  double theta_hat[18] = {};
  bool has_identification = false;  // the `momentum` law's covariance is available (in-process only)
  double theta_sd[18] = {};         // its standard deviation per coefficient
  double breakaway_sd[6] = {};      // ... of each joint's Coulomb + Stribeck sum
  double split_excitation[6] = {};  // the Stribeck decay's excitation, RMS (FrictionIdentifier::excite)
};

/// One control sample as the metrics see it: the true plant, the controller's report, the torques.
struct Sample {
  long k = 0;               ///< sample index
  double t = 0;             ///< [s]
  bool counting = true;     ///< no fault so far: the statistics count this sample (after one the robot falls)
  bool last = false;        ///< in the run's last final_window seconds (the "last" statistics: Table I's 20 s)
  TickReport rep;           ///< what the controller reported in this sample
  double e[6] = {};         ///< tracking error of the true plant: mm (x, y, z), deg (about X, Y, Z)
  double x_tilde[6] = {};   ///< observer position error: mm, deg (NaN without an observer)
  double xd_tilde[6] = {};  ///< observer velocity error x^dot - x dot (true): mm/s, deg/s (NaN without)
  Vec6 q = Vec6::Zero(), qd = Vec6::Zero();  ///< plant joint angles [rad] and speeds [rad/s]
  Vec6 tau = Vec6::Zero();                   ///< torque the amplifiers apply from this sample on [N m]
  Vec6 tau_before = Vec6::Zero();            ///< torque they applied in the sample before [N m]
  Vec6 tau_f = Vec6::Zero();                 ///< the plant's true friction [N m]
  bool injection_active = false;             ///< an injected fault is active (ExperimentConfig::injection)
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

/// The first fault and the state at its tick. The other statistics stop there (Sample::counting).
struct FaultSnapshot {
  std::uint32_t status = 0;  ///< first fault bits reported (0: none)
  double fault_time = -1;    ///< [s] of the first fault (-1: none)
  FaultState fault;          ///< where and how the first fault latched
  double stats_until = 0;    ///< [s]: the statistics cover the run up to here
  void observe(const Sample& s);
  void to_json(Json& j) const;
  /// Its lines frame the tables (print_tables): the state before them, a reminder after.
  void print_state(const ExperimentResult& run) const;
  void print_reminder(const ExperimentResult& run) const;
};

/// Max |e| over the whole run and over its last final_window seconds: mm, mm, mm, deg, deg, deg.
/// Printed in the tables beside the paper's.
struct TrackingMaxima {
  double final_window = 0;  ///< [s] of the "last" statistics
  double max_error[6] = {};
  double final_max_error[6] = {};
  void begin(const ExperimentConfig& cfg);
  void observe(const Sample& s);
  void to_json(Json& j) const;
};

/// Max |x~| and |x^dot - x dot| over the last final_window seconds (in-process controller only).
struct ObserverMaxima {
  bool has_observer = false;                   ///< the observer's errors are known
  double max_observer_error[6] = {};           ///< mm, deg
  double max_observer_velocity_error[6] = {};  ///< mm/s, deg/s
  void observe(const Sample& s);
  void to_json(Json& j) const;
  void print(const ExperimentResult& run) const;
};

/// Max |e| and the range of all theta^ per consecutive window of `window` seconds: growth shows.
struct WindowMaxima {
  double window = 0;                                      ///< [s]
  std::vector<std::array<double, 6>> window_max;          ///< max |e| per window: mm, deg
  std::vector<std::array<double, 2>> window_theta_range;  ///< min and max of all theta^ per window
  void begin(const ExperimentConfig& cfg);
  void observe(const Sample& s);
  void to_json(Json& j) const;
  void print(const ExperimentResult& run) const;

 private:
  long window_ticks_ = 1;
};

/// The friction estimates theta^ = [vis; cou; sti] at the end (at the fault, when one latched), the
/// plant's true values, and each estimate's extremes over the run. Printed in the friction table.
struct FrictionEstimates {
  double theta_hat[18] = {};
  double theta_true[18] = {};
  double theta_min_seen[18] = {};
  double theta_max_seen[18] = {};
  bool has_identification = false;  // the `momentum` law's report below is set
  double theta_sd[18] = {};         // each coefficient's standard deviation at the end
  double breakaway_sd[6] = {};      // ... each joint's Coulomb + Stribeck sum's
  double split_excitation[6] = {};  // ... and the Stribeck decay's excitation (RMS, 1)
  void begin(const ExperimentConfig& cfg);
  void observe(const Sample& s);
  void to_json(Json& j) const;

 private:
  bool frozen_ = false;  // a fault latched: theta_hat keeps its value of that tick
};

/// The rms of the joint friction estimate's error tau_f^ - tau_f, and of tau_f, over the last
/// final_window seconds [N m]. Printed in the friction table.
struct FrictionRms {
  double friction_rms_error = 0;
  double friction_rms = 0;
  void observe(const Sample& s);
  void end();
  void to_json(Json& j) const;

 private:
  double error2_ = 0, friction2_ = 0;
  long n_ = 0;
};

/// The stuck-encoder monitor's peaks, from the in-process controller at the end of the run.
struct StuckMonitorPeaks {
  double stuck_peak[6] = {};              ///< [counts]
  double stuck_dtau_peak[6] = {};         ///< the largest torque change [N m]
  double stuck_dtau_silent_peak[6] = {};  ///< ... while the encoder was also silent (kStuckTorqueSilent) [N m]
  double residual_peak_ratio[6] = {};     ///< the residual monitor's largest |r| / threshold per joint
  double residual_peak_s[6] = {};         ///< ... and when [s]
  double residual_peak_Nm[6] = {};        ///< ... |r| or |r - r_slow| then, the channel nearer its threshold [N m]
  double residual_threshold_Nm[6] = {};   ///< ... its threshold then [N m]
  double residual_detected_s = -1;        ///< the residual monitor's first detection [s] (-1: none)
  std::uint32_t residual_fault = 0;       ///< ... its fault
  int residual_joint = -1;                ///< ... its joint (0-based)
  /// ... its residual as a weight at the flange, where the payload check fitted one (osc/runtime/payload_check.hpp):
  /// mass [kg] (> 0: the model's beyond the arm's), its centre of mass's horizontal offset [m], the misfit.
  bool residual_weight = false;
  double residual_weight_kg = 0, residual_weight_offset_m = 0, residual_weight_misfit = 0;
  double position_peak_ratio[6] = {};     ///< the position cross-check's largest |d - d_ref| / band per joint
  double oscillation_peak_ratio[6] = {};  ///< the oscillation monitor's largest half-rate amplitude / limit per joint
  double travel_peak_ratio[6] = {};       ///< the travel check's largest least travel / its limit per joint (0: off)
  double drive_peak_ratio[6] = {};        ///< the drive check's largest |error| / threshold per channel
  double dither_peak_fade[6] = {};        ///< ... its dither's largest fade, of the amplitude (0.5: the fault)
  double drive_detected_s = -1;           ///< the drive check's first detection [s] (-1: none)
  std::uint32_t drive_fault = 0;          ///< ... its fault
  int drive_channel = -1;                 ///< ... its channel (0-based)
  void to_json(Json& j) const;
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
  /// The report of a run: the firmware's counts from its last actuator frame, the host's own.
  static LinkReport of(const pil::ActuatorFrame& last, const pil::LinkCounters& host, std::uint32_t host_code_range,
                       std::uint32_t zeroed_ticks, const std::string& first_zeroed) {
    return {last.link, host, host_code_range, zeroed_ticks, first_zeroed, last.rx_gap_max, last.rx_long_gaps};
  }
};

/// The firmware's telemetry and the link's health (PIL only), from the last actuator frame.
struct FirmwareReport {
  std::uint32_t max_step_cycles = 0, mean_step_cycles = 0, max_tick_cycles = 0, stack_used = 0;
  LinkReport link;
  const char* arithmetic = "";  ///< the controller's scalar (its name)
  void begin(const ExperimentConfig& cfg);
  void to_json(Json& j) const;
  void print(const ExperimentResult& run) const;
};

/// What an injected fault did (ExperimentConfig::injection).
struct InjectionResult {
  Injection injection;
  double detected = -1;           ///< [s] first tick with a fault at or after the injection (-1: never)
  std::uint32_t faults = 0;       ///< the fault bits raised in that tick
  double zero_torque = -1;        ///< [s] first sample from which every amplifier torque is zero (-1: never)
  double excursion_mm = 0;        ///< largest |p - p_d| of the true tip from injection to zero torque (or the end)
  double max_torque_after = 0;    ///< largest |tau| an amplifier applied after detection [N m]
  int max_torque_joint = -1;      ///< its joint (0-based)
  double peak_contact_force = 0;  ///< largest |F| of an injected contact (collision, wall) [N]; 0: none
  double first_contact = -1;      ///< [s] when it first pushed (-1: never)
  double breakaway = -1;          ///< [s] a stuck encoder's joint's last breakaway before detection (-1: none)
};

/// The injected fault's detection, torque cut-off and tip excursion.
struct InjectionTracking {
  InjectionResult injection;  ///< when cfg.injection.enabled
  void begin(const ExperimentConfig& cfg);
  void observe(const Sample& s);
  void to_json(Json& j) const;
  void print(const ExperimentResult& run) const;
};

/// How the run ended (a link error stops it) and what it cost.
struct RunCost {
  std::string error;           ///< link error (PIL), empty when the run completed
  double wall_seconds = 0;     ///< [s]
  double cpu_seconds = 0;      ///< of the thread that ran it (wall time counts other jobs too) [s]
  long plant_evaluations = 0;  ///< articulated-body evaluations of the plant over the run
  void to_json(Json& j) const;
  void print(const ExperimentResult& run) const;
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

/// The time series, one row per log_period, on after a fault too (the figures show what the robot
/// did). Written as CSV (csv_text in summary.hpp), not in the JSON.
struct TimeSeries {
  std::vector<LogRow> log;
  void begin(const ExperimentConfig& cfg);
  void observe(const Sample& s);

 private:
  long log_every_ = 1;
};

/// The metrics of a run, each a base: run.each(f) calls f(metric) in the list's order (the JSON's
/// and the console's). A metric's functions are optional: callers test for them (requires).
template <class... M>
struct Metrics : M... {
  template <class F>
  void each(F&& f) {
    (f(static_cast<M&>(*this)), ...);
  }
  template <class F>
  void each(F&& f) const {
    (f(static_cast<const M&>(*this)), ...);
  }
};

}  // namespace sim
