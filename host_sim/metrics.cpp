// The run's metrics (metrics.hpp): for each, what it does with a sample, its JSON keys and its
// console line, side by side.
#include "metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "experiment.hpp"
#include "osc/control/identification.hpp"

namespace sim {
namespace {

/// A time in seconds, or null for "never" (negative).
Json json_time(double t) { return t < 0 ? Json(nullptr) : Json(t); }

/// The names of the fault bits.
Json json_faults(std::uint32_t bits) {
  Json a = Json::array();
  for (int i = 0; i < osc::kFaultCount; ++i)
    if (bits & (1u << i)) a.push_back(osc::kFaultNames[i]);
  return a;
}

}  // namespace

Json json_array(const double* v, int n) { return Json(std::vector<double>(v, v + n)); }

Json residual_detection_json(double t_s, std::uint32_t fault, int joint) {
  if (fault == 0) return Json(nullptr);
  return Json{{"t_s", t_s}, {"fault", osc::fault_name(fault)}, {"joint", joint + 1}};
}

// ---- FaultSnapshot

void FaultSnapshot::observe(const Sample& s) {
  if (s.rep.faults != 0 && status == 0) {
    status = s.rep.faults, fault_time = s.t;
    FaultState& fs = fault;
    fs.tick = s.k, fs.t = s.t, fs.faults = s.rep.faults;
    for (int i = 0; i < 6; ++i) fs.q[i] = s.q(i), fs.qd[i] = s.qd(i), fs.tau[i] = s.tau_before(i), fs.e[i] = s.e[i];
    for (int i = 0; i < 18; ++i) fs.theta_hat[i] = s.rep.theta_hat[i];
  }
  if (s.counting) stats_until = s.t + osc::params::kDt;
}

void FaultSnapshot::to_json(Json& j) const {
  // Statistics cover the run up to its first fault (the whole run without one).
  j["stats_until_s"] = stats_until;
  j["faults"] = json_faults(status);
  j["fault_time_s"] = json_time(fault_time);
  if (!status) {
    j["fault"] = nullptr;
    return;
  }
  const FaultState& f = fault;
  j["fault"] = {{"names", json_faults(f.faults)},
                {"tick", f.tick},
                {"time_s", f.t},
                {"q_rad", json_array(f.q, 6)},
                {"qd_rad_s", json_array(f.qd, 6)},
                {"tau_Nm", json_array(f.tau, 6)},
                {"error_mm_deg", json_array(f.e, 6)},
                {"theta_hat", json_array(f.theta_hat, 18)}};
}

void FaultSnapshot::print_state(const ExperimentResult& run) const {
  if (!status) return;
  const char* m = run.mode.c_str();
  const FaultState& f = fault;
  std::printf("[%s] FAULT %s at tick %ld, t = %.3f s (latched; zero torque from that tick on)\n", m,
              osc::fault_name(f.faults), f.tick, f.t);
  std::printf("[%s]   every fault bit:", m);
  for (int i = 0; i < osc::kFaultCount; ++i)
    if (f.faults & (1u << i)) std::printf(" %s", osc::kFaultNames[i]);
  std::printf("\n[%s]   q [deg]:      ", m);
  for (double v : f.q) std::printf(" %9.3f", v * 180 / osc::kPi);
  std::printf("\n[%s]   qdot [deg/s]: ", m);
  for (double v : f.qd) std::printf(" %9.3f", v * 180 / osc::kPi);
  std::printf("\n[%s]   tau [N m]:    ", m);
  for (double v : f.tau) std::printf(" %9.3f", v);
  std::printf("\n[%s]   error:         %.3f %.3f %.3f mm  %.4f %.4f %.4f deg\n", m, f.e[0], f.e[1], f.e[2], f.e[3],
              f.e[4], f.e[5]);
  std::printf("[%s]   the statistics below cover 0..%.3f s; the robot after the fault is no result\n", m, stats_until);
}

void FaultSnapshot::print_reminder(const ExperimentResult& run) const {
  if (status)
    std::printf("[%s] FAULT %s at t = %.3f s (tick %ld)\n", run.mode.c_str(), osc::fault_name(fault.faults), fault_time,
                fault.tick);
}

// ---- TrackingMaxima

void TrackingMaxima::begin(const ExperimentConfig& cfg) { final_window = std::min(cfg.final_window, cfg.duration); }

void TrackingMaxima::observe(const Sample& s) {
  if (!s.counting) return;
  for (int i = 0; i < 6; ++i) {
    max_error[i] = std::max(max_error[i], std::abs(s.e[i]));
    if (s.last) final_max_error[i] = std::max(final_max_error[i], std::abs(s.e[i]));
  }
}

void TrackingMaxima::to_json(Json& j) const {
  j["final_window_s"] = final_window;
  j["max_error_mm"] = json_array(max_error, 3);
  j["max_error_deg"] = json_array(max_error + 3, 3);
  j["final_max_error_mm"] = json_array(final_max_error, 3);
  j["final_max_error_deg"] = json_array(final_max_error + 3, 3);
}

// ---- ObserverMaxima

void ObserverMaxima::observe(const Sample& s) {
  has_observer = s.rep.has_observer;
  if (!s.counting || !s.last || !has_observer) return;
  for (int i = 0; i < 6; ++i) {
    max_observer_error[i] = std::max(max_observer_error[i], std::abs(s.x_tilde[i]));
    max_observer_velocity_error[i] = std::max(max_observer_velocity_error[i], std::abs(s.xd_tilde[i]));
  }
}

void ObserverMaxima::to_json(Json& j) const {
  if (!has_observer) return;
  j["final_max_observer_error_mm_deg"] = json_array(max_observer_error, 6);
  j["final_max_observer_velocity_error_mm_s_deg_s"] = json_array(max_observer_velocity_error, 6);
}

void ObserverMaxima::print(const ExperimentResult& run) const {
  if (!has_observer || run.status) return;
  const double* x = max_observer_error;
  const double* v = max_observer_velocity_error;
  std::printf(
      "[%s] observer error over the last %gs: |x~| max %.4f %.4f %.4f mm  %.5f %.5f %.5f deg; velocity "
      "%.2f %.2f %.2f mm/s  %.3f %.3f %.3f deg/s\n",
      run.mode.c_str(), run.final_window, x[0], x[1], x[2], x[3], x[4], x[5], v[0], v[1], v[2], v[3], v[4], v[5]);
}

// ---- WindowMaxima

void WindowMaxima::begin(const ExperimentConfig& cfg) {
  window = cfg.window;
  window_ticks_ = std::max(1L, std::lround(cfg.window / osc::params::kDt));
}

void WindowMaxima::observe(const Sample& s) {
  if (!s.counting) return;
  if (s.k % window_ticks_ == 0) {
    window_max.push_back({0, 0, 0, 0, 0, 0});
    window_theta_range.push_back({s.rep.theta_hat[0], s.rep.theta_hat[0]});
  }
  auto& wmax = window_max.back();
  auto& wth = window_theta_range.back();
  for (int i = 0; i < 18; ++i) {
    wth[0] = std::min(wth[0], s.rep.theta_hat[i]);
    wth[1] = std::max(wth[1], s.rep.theta_hat[i]);
  }
  for (int i = 0; i < 6; ++i) wmax[i] = std::max(wmax[i], std::abs(s.e[i]));
}

void WindowMaxima::to_json(Json& j) const {
  j["window_s"] = window;
  Json w = Json::array(), wt = Json::array();
  for (const auto& m : window_max) w.push_back(json_array(m.data(), 6));
  for (const auto& m : window_theta_range) wt.push_back(json_array(m.data(), 2));
  j["window_max_error"] = w;
  j["window_theta_range"] = wt;
}

/// The worst max |e| per window over the run, in blocks of about ten, so that growth shows.
void WindowMaxima::print(const ExperimentResult& run) const {
  const size_t n = window_max.size();
  if (n < 3) return;
  const size_t block = std::max<size_t>(1, n / 10);
  std::printf("\n[%s] worst max |e| per %.0f s window (x, y, z mm; about X, Y, Z deg) and the range of theta^:\n",
              run.mode.c_str(), window);
  for (size_t b = 0; b < n; b += block) {
    double w[6] = {}, lo = 1e300, hi = -1e300;
    for (size_t k = b; k < std::min(n, b + block); ++k) {
      for (int i = 0; i < 6; ++i) w[i] = std::max(w[i], window_max[k][i]);
      lo = std::min(lo, window_theta_range[k][0]);
      hi = std::max(hi, window_theta_range[k][1]);
    }
    std::printf("  t %6.0f..%6.0f s: %.3f %.3f %.3f mm  %.4f %.4f %.4f deg   theta^ in [%.2f, %.2f]\n", b * window,
                std::min(n, b + block) * window, w[0], w[1], w[2], w[3], w[4], w[5], lo, hi);
  }
}

// ---- FrictionEstimates

void FrictionEstimates::begin(const ExperimentConfig& cfg) {
  for (int i = 0; i < 6; ++i) {
    theta_true[i] = cfg.plant.friction.vis[i];
    theta_true[6 + i] = cfg.plant.friction.cou[i];
    theta_true[12 + i] = cfg.plant.friction.sti[i];
  }
}

void FrictionEstimates::observe(const Sample& s) {
  if (!frozen_) {
    std::copy(s.rep.theta_hat, s.rep.theta_hat + 18, theta_hat);
    has_identification = s.rep.has_identification;
    std::copy(s.rep.theta_sd, s.rep.theta_sd + 18, theta_sd);
    std::copy(s.rep.breakaway_sd, s.rep.breakaway_sd + 6, breakaway_sd);
    std::copy(s.rep.split_excitation, s.rep.split_excitation + 6, split_excitation);
  }
  frozen_ = !s.counting;
  if (!s.counting) return;
  for (int i = 0; i < 18; ++i) {
    theta_min_seen[i] = s.k == 0 ? s.rep.theta_hat[i] : std::min(theta_min_seen[i], s.rep.theta_hat[i]);
    theta_max_seen[i] = s.k == 0 ? s.rep.theta_hat[i] : std::max(theta_max_seen[i], s.rep.theta_hat[i]);
  }
}

void FrictionEstimates::to_json(Json& j) const {
  j["theta_hat"] = json_array(theta_hat, 18);
  j["theta_true"] = json_array(theta_true, 18);
  j["theta_min_seen"] = json_array(theta_min_seen, 18);
  j["theta_max_seen"] = json_array(theta_max_seen, 18);
  if (!has_identification) return;
  // The excitation monitor's verdicts (osc::friction_identified): per coefficient, then per joint's
  // Coulomb + Stribeck sum.
  Json id;
  id["theta_sd"] = json_array(theta_sd, 18);
  id["breakaway_sd"] = json_array(breakaway_sd, 6);
  // The Coulomb / Stribeck split's excitation and whether it is learned (its gate).
  id["split_excitation"] = json_array(split_excitation, 6);
  for (int i = 0; i < 6; ++i) id["split_learned"].push_back(osc::split_excited(split_excitation[i]));
  for (int i = 0; i < 18; ++i) id["theta_identified"].push_back(osc::friction_identified(theta_hat[i], theta_sd[i]));
  for (int i = 0; i < 6; ++i)
    id["breakaway_identified"].push_back(
        osc::friction_identified(theta_hat[6 + i] + theta_hat[12 + i], breakaway_sd[i]));
  j["identification"] = id;
}

// ---- FrictionRms

void FrictionRms::observe(const Sample& s) {
  if (!s.counting || !s.last) return;
  for (int i = 0; i < 6; ++i) {
    const double df = s.rep.tau_f_hat[i] - s.tau_f(i);
    error2_ += df * df;
    friction2_ += s.tau_f(i) * s.tau_f(i);
  }
  ++n_;
}

void FrictionRms::end() {
  if (n_ == 0) return;
  friction_rms_error = std::sqrt(error2_ / (6.0 * n_));
  friction_rms = std::sqrt(friction2_ / (6.0 * n_));
}

void FrictionRms::to_json(Json& j) const {
  j["friction_rms_error_Nm"] = friction_rms_error;
  j["friction_rms_Nm"] = friction_rms;
}

// ---- StuckMonitorPeaks

void StuckMonitorPeaks::to_json(Json& j) const {
  j["stuck_monitor_peak_counts"] = json_array(stuck_peak, 6);
  j["stuck_monitor_peak_dtau_Nm"] = json_array(stuck_dtau_peak, 6);
  j["stuck_monitor_peak_dtau_silent_Nm"] = json_array(stuck_dtau_silent_peak, 6);
  j["residual_monitor_peak_ratio"] = json_array(residual_peak_ratio, 6);
  j["residual_monitor_peak_s"] = json_array(residual_peak_s, 6);
  j["residual_monitor_peak_Nm"] = json_array(residual_peak_Nm, 6);
  j["residual_monitor_threshold_at_peak_Nm"] = json_array(residual_threshold_Nm, 6);
  j["position_check_peak_ratio"] = json_array(position_peak_ratio, 6);
  j["oscillation_monitor_peak_ratio"] = json_array(oscillation_peak_ratio, 6);
  j["residual_monitor_travel_ratio"] = json_array(travel_peak_ratio, 6);
  j["residual_monitor_detection"] = residual_detection_json(residual_detected_s, residual_fault, residual_joint);
  if (residual_weight)
    j["residual_monitor_detection"]["weight"] = Json{
        {"mass_kg", residual_weight_kg}, {"offset_m", residual_weight_offset_m}, {"misfit", residual_weight_misfit}};
  j["drive_check_peak_ratio"] = json_array(drive_peak_ratio, 6);
  j["drive_check_dither_fade"] = json_array(dither_peak_fade, 6);
  j["drive_check_detection"] = residual_detection_json(drive_detected_s, drive_fault, drive_channel);
}

// ---- FirmwareReport

namespace {
/// "none", or the nonzero link error counters as "name n, ...".
std::string counters_text(const pil::LinkCounters& c) {
  std::string s;
  for (int k = 0; k < pil::kLinkErrorKinds; ++k)
    if (c.count[k])
      s += (s.empty() ? "" : ", ") + std::string(pil::kLinkErrorNames[k]) + " " + std::to_string(c.count[k]);
  return s.empty() ? "none" : s;
}
}  // namespace

void FirmwareReport::begin(const ExperimentConfig& cfg) { arithmetic = kScalarNames[static_cast<int>(cfg.scalar)]; }

void FirmwareReport::to_json(Json& j) const {
  if (!max_step_cycles) return;
  j["firmware_step_instructions_max"] = max_step_cycles;
  j["firmware_step_instructions_mean"] = mean_step_cycles;
  j["firmware_tick_instructions_max"] = max_tick_cycles;
  j["firmware_stack_used_bytes"] = stack_used;
  Json l;
  const pil::LinkCounters* sides[2] = {&link.firmware, &link.host};
  for (int s = 0; s < 2; ++s) {
    Json c;
    for (int k = 0; k < pil::kLinkErrorKinds; ++k) c[pil::kLinkErrorNames[k]] = sides[s]->count[k];
    if (s) c["code_range"] = link.host_code_range;
    l[s ? "host" : "firmware"] = c;
  }
  l["zeroed_ticks"] = link.zeroed_ticks;
  l["rx_gap_max_instructions"] = link.rx_gap_max;
  l["rx_long_gaps"] = link.rx_long_gaps;
  if (!link.first_zeroed.empty()) l["first_zeroed"] = link.first_zeroed;
  j["link"] = l;
}

void FirmwareReport::print(const ExperimentResult& run) const {
  if (!max_step_cycles) return;
  const char* m = run.mode.c_str();
  std::printf(
      "[%s] firmware control step (observer + controller + adaptation, %s): max %u, mean %u "
      "instructions (QEMU -icount shift=0); whole tick incl. link I/O max %u; stack used %u bytes\n",
      m, arithmetic, max_step_cycles, mean_step_cycles, max_tick_cycles, stack_used);
  std::printf(
      "[%s] link: longest gap between received bytes %u cycles (ns of target time in QEMU), %u over %d periods; "
      "errors counted by the firmware: %s; by the host: %s, codes out of range %u; ticks zeroed %u%s%s\n",
      m, link.rx_gap_max, link.rx_long_gaps, osc::params::kLinkSilenceTicks, counters_text(link.firmware).c_str(),
      counters_text(link.host).c_str(), link.host_code_range, link.zeroed_ticks,
      link.first_zeroed.empty() ? "" : ", the first: ", link.first_zeroed.c_str());
}

// ---- InjectionTracking

void InjectionTracking::begin(const ExperimentConfig& cfg) { injection.injection = cfg.injection; }

void InjectionTracking::observe(const Sample& s) {
  if (!s.injection_active) return;
  InjectionResult& ir = injection;
  if (s.rep.faults != 0 && ir.detected < 0) ir.detected = s.t, ir.faults = s.rep.faults;
  if (ir.zero_torque < 0) {
    ir.excursion_mm = std::max(ir.excursion_mm, std::sqrt(s.e[0] * s.e[0] + s.e[1] * s.e[1] + s.e[2] * s.e[2]));
    if ((s.tau.array() == 0.0).all()) ir.zero_torque = s.t;
  }
  if (ir.detected >= 0)
    for (int i = 0; i < 6; ++i)
      if (std::abs(s.tau(i)) > ir.max_torque_after) ir.max_torque_after = std::abs(s.tau(i)), ir.max_torque_joint = i;
}

void InjectionTracking::to_json(Json& j) const {
  if (!injection.injection.enabled) return;
  const InjectionResult& ir = injection;
  j["injection"] = {{"kind", info(ir.injection.kind).name},
                    {"joint", ir.injection.joint < 0 ? Json(nullptr) : Json(ir.injection.joint + 1)},
                    {"at_s", ir.injection.at},
                    {"detected_s", json_time(ir.detected)},
                    {"fault", ir.detected < 0 ? Json(nullptr) : Json(osc::fault_name(ir.faults))},
                    {"faults", json_faults(ir.faults)},
                    {"zero_torque_s", json_time(ir.zero_torque)},
                    {"excursion_mm", ir.excursion_mm},
                    {"max_torque_after_detection_Nm", ir.max_torque_after},
                    {"peak_contact_force_N", ir.peak_contact_force},
                    {"first_contact_s", json_time(ir.first_contact)},
                    {"breakaway_s", json_time(ir.breakaway)}};
}

void InjectionTracking::print(const ExperimentResult& run) const {
  if (!injection.injection.enabled) return;
  const InjectionResult& ir = injection;
  std::printf("[%s] injected %s: ", run.mode.c_str(), to_string(ir.injection).c_str());
  if (ir.detected < 0)
    std::printf("never detected");
  else
    std::printf("detected after %.1f ms as %s", (ir.detected - ir.injection.at) * 1e3, osc::fault_name(ir.faults));
  if (ir.zero_torque < 0)
    std::printf(", torque never zero");
  else
    std::printf(", zero torque after %.1f ms", (ir.zero_torque - ir.injection.at) * 1e3);
  std::printf(", tip excursion %.2f mm, largest torque after detection %.2f N m", ir.excursion_mm, ir.max_torque_after);
  if (ir.injection.contact()) std::printf(", peak contact force %.1f N", ir.peak_contact_force);
  if (ir.breakaway >= 0)
    std::printf(", the joint's last breakaway before it after %.1f ms", (ir.breakaway - ir.injection.at) * 1e3);
  std::printf("\n");
}

// ---- RunCost

void RunCost::to_json(Json& j) const {
  if (!error.empty()) j["error"] = error;
  j["wall_s"] = wall_seconds;
  j["cpu_s"] = cpu_seconds;
  j["plant_evaluations"] = plant_evaluations;
}

void RunCost::print(const ExperimentResult& run) const {
  const char* m = run.mode.c_str();
  if (!error.empty()) std::printf("[%s] LINK ERROR: %s\n", m, error.c_str());
  std::printf(
      "[%s] simulated %.0f s in %.2f s wall (%.3gx real time); %.2f s CPU (%.3gx real time); "
      "%.1f plant evaluations per sample\n",
      m, run.duration, wall_seconds, run.duration / wall_seconds, cpu_seconds, run.duration / cpu_seconds,
      static_cast<double>(plant_evaluations) / (run.duration / osc::params::kDt));
}

// ---- TimeSeries

void TimeSeries::begin(const ExperimentConfig& cfg) {
  log_every_ = std::max(1L, std::lround(cfg.log_period / osc::params::kDt));
}

void TimeSeries::observe(const Sample& s) {
  if (s.k % log_every_ != 0) return;
  LogRow r;
  r.t = s.t;
  for (int i = 0; i < 6; ++i) {
    r.e[i] = s.e[i];
    r.x_tilde[i] = s.x_tilde[i];
    r.xd_tilde[i] = s.xd_tilde[i];
    r.tau[i] = s.tau(i);
    r.tau_f[i] = s.tau_f(i);
    r.tau_f_hat[i] = s.rep.tau_f_hat[i];
  }
  for (int i = 0; i < 18; ++i) r.theta_hat[i] = s.rep.theta_hat[i];
  log.push_back(r);
}

}  // namespace sim
