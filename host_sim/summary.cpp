// The outputs' contents (see summary.hpp): the summary JSON by nlohmann-json, the time series CSV.
#include "summary.hpp"

#include <sstream>

#include "injection.hpp"

namespace sim {
namespace {

/// A time in seconds, or null for "never" (negative).
json json_time(double t) { return t < 0 ? json(nullptr) : json(t); }

json json_array(const double* v, int n) { return json(std::vector<double>(v, v + n)); }

/// The names of the fault bits.
json json_faults(std::uint32_t bits) {
  json a = json::array();
  for (int i = 0; i < osc::kFaultCount; ++i)
    if (bits & (1u << i)) a.push_back(osc::kFaultNames[i]);
  return a;
}

}  // namespace

json json_run(const ExperimentResult& r, bool csv) {
  json j;
  j["mode"] = r.mode;
  j["duration_s"] = r.duration;
  j["friction_preset"] = r.friction_preset;
  j["adaptation"] = r.adaptation;
  if (csv) j["timeseries"] = csv_name(r);
  // Statistics cover the run up to its first fault (the whole run without one).
  j["stats_until_s"] = r.stats_until;
  j["faults"] = json_faults(r.status);
  j["fault_time_s"] = json_time(r.fault_time);
  if (r.status) {
    const FaultState& f = r.fault;
    j["fault"] = {{"names", json_faults(f.faults)},
                  {"tick", f.tick},
                  {"time_s", f.t},
                  {"q_rad", json_array(f.q, 6)},
                  {"qd_rad_s", json_array(f.qd, 6)},
                  {"tau_Nm", json_array(f.tau, 6)},
                  {"error_mm_deg", json_array(f.e, 6)},
                  {"theta_hat", json_array(f.theta_hat, 18)}};
  } else {
    j["fault"] = nullptr;
  }
  j["final_window_s"] = r.final_window;
  j["max_error_mm"] = json_array(r.max_error, 3);
  j["max_error_deg"] = json_array(r.max_error + 3, 3);
  j["final_max_error_mm"] = json_array(r.final_max_error, 3);
  j["final_max_error_deg"] = json_array(r.final_max_error + 3, 3);
  if (r.has_observer) {
    j["final_max_observer_error_mm_deg"] = json_array(r.max_observer_error, 6);
    j["final_max_observer_velocity_error_mm_s_deg_s"] = json_array(r.max_observer_velocity_error, 6);
  }
  j["window_s"] = r.window;
  json w = json::array(), wt = json::array();
  for (const auto& m : r.window_max) w.push_back(json_array(m.data(), 6));
  for (const auto& m : r.window_theta_range) wt.push_back(json_array(m.data(), 2));
  j["window_max_error"] = w;
  j["window_theta_range"] = wt;
  j["theta_hat"] = json_array(r.theta_hat, 18);
  j["theta_true"] = json_array(r.theta_true, 18);
  j["theta_min_seen"] = json_array(r.theta_min_seen, 18);
  j["theta_max_seen"] = json_array(r.theta_max_seen, 18);
  j["friction_rms_error_Nm"] = r.friction_rms_error;
  j["friction_rms_Nm"] = r.friction_rms;
  j["stuck_monitor_peak_counts"] = json_array(r.stuck_peak, 6);
  j["stuck_monitor_peak_dtau_Nm"] = json_array(r.stuck_dtau_peak, 6);
  j["stuck_monitor_peak_dtau_silent_Nm"] = json_array(r.stuck_dtau_silent_peak, 6);
  if (r.max_step_cycles) {
    j["firmware_step_instructions_max"] = r.max_step_cycles;
    j["firmware_step_instructions_mean"] = r.mean_step_cycles;
    j["firmware_tick_instructions_max"] = r.max_tick_cycles;
    j["firmware_stack_used_bytes"] = r.stack_used;
    json link;
    const pil::LinkCounters* sides[2] = {&r.link.firmware, &r.link.host};
    for (int s = 0; s < 2; ++s) {
      json c;
      for (int k = 0; k < pil::kLinkErrorKinds; ++k) c[pil::kLinkErrorNames[k]] = sides[s]->count[k];
      if (s) c["code_range"] = r.link.host_code_range;
      link[s ? "host" : "firmware"] = c;
    }
    link["zeroed_ticks"] = r.link.zeroed_ticks;
    link["rx_gap_max_instructions"] = r.link.rx_gap_max;
    link["rx_long_gaps"] = r.link.rx_long_gaps;
    if (!r.link.first_zeroed.empty()) link["first_zeroed"] = r.link.first_zeroed;
    j["link"] = link;
  }
  if (r.injection.injection.enabled) {
    const InjectionResult& ir = r.injection;
    j["injection"] = {{"kind", info(ir.injection.kind).name},
                      {"joint", ir.injection.joint < 0 ? json(nullptr) : json(ir.injection.joint + 1)},
                      {"at_s", ir.injection.at},
                      {"detected_s", json_time(ir.detected)},
                      {"fault", ir.detected < 0 ? json(nullptr) : json(osc::fault_name(ir.faults))},
                      {"faults", json_faults(ir.faults)},
                      {"zero_torque_s", json_time(ir.zero_torque)},
                      {"excursion_mm", ir.excursion_mm},
                      {"max_torque_after_detection_Nm", ir.max_torque_after}};
  }
  if (!r.error.empty()) j["error"] = r.error;
  j["wall_s"] = r.wall_seconds;
  j["cpu_s"] = r.cpu_seconds;
  j["plant_evaluations"] = r.plant_evaluations;
  return j;
}

std::string csv_name(const ExperimentResult& r) { return "timeseries_" + r.mode + ".csv"; }

json summary_json(const std::vector<ExperimentResult>& runs, const Settings& cfg, const Provenance& prov, bool csv) {
  json root;
  root["program"] = "puma_experiment";
  root["git_revision"] = prov.revision;
  root["config_hash"] = prov.config_hash;
  if (!prov.config_file.empty()) root["config_file"] = prov.config_file;
  root["config"] = config_json(cfg);
  root["paper_setup"] = prov.differs.empty();
  root["differs_from_paper"] = prov.differs;
  root["paper"] = {{"table1_max_error_mm_deg", json_array(kPaperTable1, 6)},
                   {"table3_max_error_mm_deg", json_array(kPaperTable3, 6)}};
  json a = json::array();
  for (const auto& r : runs) a.push_back(json_run(r, csv));
  root["runs"] = a;
  return root;
}

/// The time series of a run. The first line is a comment with the provenance; a column that the
/// run does not have (the observer over the link, the friction estimates without compensation)
/// is left out.
std::string csv_text(const ExperimentResult& r, const Provenance& prov) {
  const bool adaptive = r.mode == "adaptive";
  std::ostringstream f;
  f.precision(9);
  f << "# " << prov.line() << "; mode " << r.mode << "; " << prov.setup() << "\n";
  f << "t,e_x_mm,e_y_mm,e_z_mm,e_phx_deg,e_phy_deg,e_phz_deg";
  static const char* const kAx[6] = {"x_mm", "y_mm", "z_mm", "phx_deg", "phy_deg", "phz_deg"};
  static const char* const kVel[6] = {"x_mm_s", "y_mm_s", "z_mm_s", "phx_deg_s", "phy_deg_s", "phz_deg_s"};
  if (r.has_observer) {
    for (int i = 0; i < 6; ++i) f << ",xt_" << kAx[i];
    for (int i = 0; i < 6; ++i) f << ",xdt_" << kVel[i];
  }
  // theta^ = [vis; cou; sti], six joints each (model (2)): named by coefficient and joint.
  static const char* const kCoeff[3] = {"vis", "cou", "sti"};
  if (adaptive)
    for (int i = 0; i < 18; ++i) f << ",theta_" << kCoeff[i / 6] << "_j" << i % 6 + 1;
  for (int i = 0; i < 6; ++i) f << ",tau_j" << i + 1 << "_Nm";
  for (int i = 0; i < 6; ++i) f << ",tau_f_j" << i + 1 << "_Nm";
  if (adaptive)
    for (int i = 0; i < 6; ++i) f << ",tau_f_hat_j" << i + 1 << "_Nm";
  f << "\n";
  for (const auto& row : r.log) {
    f << row.t;
    for (double v : row.e) f << "," << v;
    if (r.has_observer) {
      for (double v : row.x_tilde) f << "," << v;
      for (double v : row.xd_tilde) f << "," << v;
    }
    if (adaptive)
      for (double v : row.theta_hat) f << "," << v;
    for (double v : row.tau) f << "," << v;
    for (double v : row.tau_f) f << "," << v;
    if (adaptive)
      for (double v : row.tau_f_hat) f << "," << v;
    f << "\n";
  }
  return f.str();
}

}  // namespace sim
