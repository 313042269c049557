// The simulated arm's presets (docs/experiment.md, "The realistic plant"): `ideal`, the rigid,
// uncoupled arm with ideal drives of the paper's tables, and `realistic`, every feature of the plant
// and its sensors at its mid value. A preset sets the features only: the friction, the computation
// delay and the integration keep their own keys.
#pragma once

#include <string>
#include <vector>

#include "experiment.hpp"

namespace sim {

/// The presets' names: ideal, realistic.
std::vector<std::string> plant_preset_names();

/// Sets every feature of cfg's plant and sensors to the preset's. False for an unknown name.
bool apply_plant_preset(const std::string& name, ExperimentConfig& cfg);

}  // namespace sim
