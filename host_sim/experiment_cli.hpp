// puma_experiment's command line (CLI11) and configuration (config.hpp), apart from main() so that
// the parser can be tested and fuzzed (tests/fuzz/fuzz_cli.cpp) without running an experiment.
#pragma once

#include <cstddef>
#include <string>

#include "config.hpp"
#include "injection.hpp"
#include "pil_client.hpp"

namespace sim {

struct ExperimentOptions : Settings {
  std::string config_file;    ///< --config (empty: the defaults)
  std::string motion;         ///< --motion: a motion script (motion_script.hpp) instead of the paper's experiment
  bool print_config = false;  ///< --print-config: print the effective configuration and exit 0
  std::string json, csv_dir = "out";
  bool csv = true, progress = true;
  bool qemu = false;
  PilLink pil_link = PilLink::kSemihosting;  ///< --pil-link: how the frames reach the image in QEMU
  bool help = false;                         ///< --help or -h: print usage() and exit 0
  std::string elf = OSC_DEFAULT_PIL_ELF;
};

/// The largest configuration file --config reads.
constexpr std::size_t kMaxConfigBytes = std::size_t{1} << 20;

/// Whether an injection (from `where`: --inject, a script's inject:) can act on a run with --qemu:
/// the plant, the encoders and the amplifiers are the host's, the tick's clock and E-stop input the
/// image's. False with err naming the kind.
bool qemu_takes(const Injection& inj, const std::string& where, std::string& err);

/// The generated help text.
std::string experiment_usage();

/// Parses argv[1..argc-1] into o: the configuration file, then the named options (--duration,
/// --mode, ...), then every --set, each checked with the key it sets. An option given more than once
/// takes its last value (scripts/run.sh gives --json and --csv-dir before the user's own), each value
/// checked. Returns false with one short message in err on the first bad argument, key or value;
/// nothing has run yet.
bool parse_experiment_args(int argc, char** argv, ExperimentOptions& o, std::string& err);

}  // namespace sim
