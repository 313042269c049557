// What puma_experiment writes: the provenance every output carries (program revision, the
// configuration's hash and file, how it differs from the paper's set-up), the summary JSON
// (nlohmann-json) and the time series CSV.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "config.hpp"
#include "experiment.hpp"

namespace sim {

using json = nlohmann::ordered_json;

/// What every output records about the run's origin: program revision, configuration (hash and
/// full text) and how it differs from the paper's set-up.
struct Provenance {
  std::string revision, config_text, config_hash, config_file;
  std::vector<std::string> differs;        // keys that differ from the paper's set-up
  std::string plant = "ideal";             // the plant's preset
  std::vector<std::string> plant_differs;  // its features that differ from the preset's
  std::string line() const {
    std::string s = "puma_experiment " + revision + ", configuration " + config_hash;
    if (!config_file.empty()) s += " (" + config_file + ")";
    return s;
  }
  std::string setup() const {
    std::string s = "plant " + plant;
    for (size_t i = 0; i < plant_differs.size(); ++i) s += (i ? ", " : " but ") + plant_differs[i];
    if (differs.empty()) return s + "; the paper's set-up";
    s += "; differs from the paper's set-up in";
    for (size_t i = 0; i < differs.size(); ++i) s += (i ? ", " : " ") + differs[i];
    return s;
  }
};

/// One run as JSON: its name and set-up, then each metric's keys (metrics.hpp), in the list's order.
json json_run(const ExperimentResult& r, bool csv);

/// The metrics' console lines (observer, windows, firmware, injection, cost), metric by metric, a
/// line per run.
void print_metric_lines(const std::vector<ExperimentResult>& runs);

/// The summary: provenance, the effective configuration, the paper's tables, and every run once.
json summary_json(const std::vector<ExperimentResult>& runs, const Settings& cfg, const Provenance& prov, bool csv);

/// The file name of a run's time series ("timeseries_<mode>.csv").
std::string csv_name(const ExperimentResult& r);

/// The time series of a run. The first line is a comment with the provenance; a column that the
/// run does not have (the observer over the link, the friction estimates without compensation)
/// is left out.
std::string csv_text(const ExperimentResult& r, const Provenance& prov);

}  // namespace sim
