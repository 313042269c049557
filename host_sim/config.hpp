// The experiment's configuration file (YAML, read and written by yaml-cpp): gains (69), K_ad,
// tau_dec, the trajectory (68), the start pose, the plant and the run. Every entry is one row of a
// table in config.cpp, which knows its key, unit, range and whether it belongs to the paper's
// set-up (the gains' rows come from their one list, OSC_GAINS_FIELDS in osc/control/gains.hpp);
// the defaults are the firmware's compile-time values (params.hpp, the robot description), read
// from those headers, never written a second time.
//
//   puma_experiment --print-config > c.yaml        the effective configuration, with units and ranges
//   puma_experiment --config c.yaml --set trajectory.amplitude=0.1
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiment.hpp"
#include "plant_preset.hpp"

namespace sim {

/// Everything a configuration file sets: the experiment and which modes run.
struct Settings {
  ExperimentConfig base;
  bool run_adaptive = true, run_none = true;
  std::string plant_preset = "ideal";  ///< the plant's preset (plant_preset.hpp); its features may then differ
};

/// Applies a YAML document (the text of `source`, a file name for messages) to s. Unknown keys,
/// values of the wrong type and values out of range are errors that name the key; s may then be
/// partly changed (the caller stops).
bool apply_config(const std::string& text, const std::string& source, Settings& s, std::string& err);

/// Applies one `key=value` (--set), the value in YAML (a number, a name, or a list like [1, 2, 3]).
bool apply_setting(const std::string& assignment, Settings& s, std::string& err);

/// Sets one key to a value written as in YAML (the named command-line options use this).
bool set_key(const std::string& key, const std::string& value, Settings& s, std::string& err);

/// Checks what no single entry can: a start pose away from the singularities the controller refuses.
bool validate_settings(const Settings& s, std::string& err);

/// The effective configuration as a YAML document, with units and ranges as comments: it reads
/// back into the same settings.
std::string config_yaml(const Settings& s);

/// The same configuration as a JSON object (for the summary).
nlohmann::ordered_json config_json(const Settings& s);

/// The keys whose values differ from the paper's set-up (Section VI; the defaults). Keys that do not
/// change the set-up (the modes, the arithmetic, the adaptation law, the statistics window, the
/// plant's integration step) are not listed.
std::vector<std::string> differences_from_paper(const Settings& s);

/// The plant's features (plant.*) whose values differ from its preset's.
std::vector<std::string> differences_from_preset(const Settings& s);

/// A short stable hash of a text (FNV-1a, 64 bit, as 16 hex digits).
std::string text_hash(const std::string& text);

/// The git revision the program was built from ("unknown" outside a git checkout; "-dirty" when
/// the tree had uncommitted changes).
const char* git_revision();

}  // namespace sim
