// The outputs' contents (see summary.hpp): the summary JSON by nlohmann-json, the time series CSV.
#include "summary.hpp"

#include <sstream>
#include <type_traits>

namespace sim {
json json_run(const ExperimentResult& r, bool csv) {
  json j;
  j["mode"] = r.mode;
  j["duration_s"] = r.duration;
  j["friction_preset"] = r.friction_preset;
  j["adaptation"] = r.adaptation;
  if (csv) j["timeseries"] = csv_name(r);
  r.each([&j](const auto& metric) {
    if constexpr (requires { metric.to_json(j); }) metric.to_json(j);
  });
  return j;
}

void print_metric_lines(const std::vector<ExperimentResult>& runs) {
  if (runs.empty()) return;
  // Metric by metric, each run's line: the runs' lines of a metric stand together.
  runs[0].each([&runs](const auto& first) {
    using Metric = std::remove_cvref_t<decltype(first)>;
    if constexpr (requires { first.print(runs[0]); })
      for (const ExperimentResult& r : runs) static_cast<const Metric&>(r).print(r);
  });
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
  root["plant"] = {{"preset", prov.plant}, {"differs_from_preset", prov.plant_differs}};
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
