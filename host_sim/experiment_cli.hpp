// puma_experiment's command line: the options and their parser, apart from main() so that the
// parser can be tested and fuzzed (tests/fuzz/fuzz_cli.cpp) without running an experiment.
#pragma once

#include <string>

#include "experiment.hpp"

namespace sim {

extern const char* const kExperimentUsage;

struct ExperimentOptions {
  double duration = 120;
  bool run_adaptive = true, run_none = true;
  ExperimentConfig base;
  std::string json, csv_dir = "out";
  bool csv = true, progress = true;
  bool qemu = false;
  bool help = false;  ///< --help or -h: print kExperimentUsage and exit 0 (later arguments unread)
  std::string elf = OSC_DEFAULT_PIL_ELF;
};

/// Parses argv[1..argc-1] into o. Returns false with a message in err on the first bad argument.
bool parse_experiment_args(int argc, char** argv, ExperimentOptions& o, std::string& err);

}  // namespace sim
