// puma_experiment's command line (see experiment_cli.hpp), parsed by CLI11.
#include "experiment_cli.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "injection.hpp"

namespace sim {
namespace {

/// A named option that stands for a configuration key (--duration 30 is --set run.duration=30).
struct Shorthand {
  const char* flag;
  const char* key;
  const char* help;
};
constexpr Shorthand kShorthands[] = {
    {"--duration", "run.duration", "simulated seconds per run (default 120; 1..86400)"},
    {"--mode", "run.modes", "both | adaptive | none (default both)"},
    {"--scalar", "run.scalar", "the controller's arithmetic: double | float | fixed (default double)"},
    {"--adaptation", "run.adaptation", "friction adaptation law: paper | robust | momentum (default momentum)"},
    {"--final-window", "run.final_window", "length of the \"last\" statistics in seconds (default 20; 1..3600)"},
    {"--plant", "plant.preset",
     "the simulated arm: ideal (the paper's tables) | realistic (every feature of docs/experiment.md's plant "
     "table at its mid value) (default ideal)"},
    {"--friction", "plant.friction.preset", "plant friction preset: paper | corke | none (default paper)"},
    {"--model-error", "controller.model_error", "controller link mass/inertia relative error (default 0; -0.5..0.5)"},
    {"--encoder-cpr", "plant.encoder_cpr", "encoder counts per motor revolution, plant and controller (default 1000)"},
    {"--substep", "plant.substep", "plant RK4 step in seconds (default 1e-4; 1e-6..1e-3)"},
    {"--smooth-steps", "plant.smooth_steps",
     "plant RK4 substeps taken at once away from velocity reversals (default 8; 1..16)"},
    {"--delay", "plant.delay", "computation delay inside the sample in seconds (default 2e-4; 0..1e-3)"},
};

/// Keys the firmware image compiles in: with --qemu they must keep their defaults.
constexpr const char* kHostOnlyKeys[] = {
    "controller.knd",      "controller.k",       "controller.ks",          "controller.ki",        "controller.k_ad",
    "controller.tau_dec",  "controller.leakage", "controller.model_error", "trajectory.amplitude", "trajectory.period",
    "trajectory.envelope", "start_pose",         "plant.encoder_cpr",      "plant.power_on_pose",  "run.model_rate"};

constexpr const char* kPowerOnNeedsMotion =
    "plant.power_on_pose applies to a motion script (--motion), whose steps home the arm or declare its pose; the "
    "paper's experiment starts at the declared start pose";

struct Parsed {
  std::vector<std::pair<const Shorthand*, std::string>> shorthands;
  std::vector<std::string> sets;
  std::vector<std::string> plant_sets;
  std::string inject;
  std::string pil_link;
};

void build(CLI::App& app, ExperimentOptions& o, Parsed& p, std::vector<std::vector<std::string>>& values) {
  app.description("The paper's experiment (Section VI) on the simulated " + std::string(osc::robot::kArm.name) +
                  ", with adaptive friction compensation and without. The configuration's defaults are the paper's "
                  "set-up; --print-config shows every key.");
  app.set_help_flag("-h,--help", "this text");
  app.option_defaults()->disable_flag_override()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_option("--config", o.config_file, "read the configuration from this YAML file (see --print-config)")
      ->type_name("FILE");
  app.add_option("--set", p.sets,
                 "set one configuration key, after --config and the options below "
                 "(e.g. --set trajectory.amplitude=0.1); repeatable")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  app.add_option("--plant-set", p.plant_sets,
                 "set one of the plant's keys, after --plant (e.g. --plant-set elastic_hz=20 for plant.elastic_hz; "
                 "--print-config lists them); repeatable")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  app.add_flag("--print-config", o.print_config, "print the effective configuration as YAML and exit");
  app.add_option(
         "--motion", o.motion,
         "play a motion script (timed commands: enable, move_to, paper, stop, disable, clear, home, declare_pose; "
         "docs/motion.md, examples/) on the simulated arm instead of the paper's experiment")
      ->type_name("FILE.yaml");
  values.resize(std::size(kShorthands));
  for (size_t i = 0; i < std::size(kShorthands); ++i)
    app.add_option(kShorthands[i].flag, values[i], std::string(kShorthands[i].help) + "; sets " + kShorthands[i].key)
        ->type_name("V")
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_flag("--qemu", o.qemu, "run the controller as the firmware image in qemu-system-arm (PIL)");
  app.add_option("--elf", o.elf, "firmware image for --qemu (default: the m4f build's pil_firmware.elf)")
      ->type_name("FILE");
  app.add_option("--pil-link", p.pil_link,
                 "how the frames reach the image with --qemu: semihosting (QEMU's semihosting console, a frame "
                 "per read or write; default) | uart (the board's UART0, a byte at a time, as on a board)")
      ->type_name("LINK");
  app.add_option("--json", o.json, "write the summary as JSON")->type_name("FILE");
  app.add_option("--csv-dir", o.csv_dir, "write time series CSV files and config.yaml there (default: out)")
      ->type_name("DIR");
  app.add_option("--inject", p.inject, inject_help())->type_name("KIND[:ARGS]@S");
  app.add_flag(
      "--no-csv", [&o](std::int64_t) { o.csv = false; }, "do not write time series");
  app.add_flag(
      "--no-progress", [&o](std::int64_t) { o.progress = false; }, "no progress bar");
}

/// Reads a configuration file of at most kMaxConfigBytes (a device such as /dev/zero, or a file that
/// is no configuration, would otherwise be read without end).
bool read_file(const std::string& path, std::string& text, std::string& err) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return err = "cannot read configuration file " + path, false;
  text.assign(kMaxConfigBytes + 1, '\0');
  f.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (f.bad()) return err = "cannot read configuration file " + path, false;
  text.resize(static_cast<std::size_t>(f.gcount()));
  if (text.size() > kMaxConfigBytes)
    return err = "configuration file " + path + " is larger than " + std::to_string(kMaxConfigBytes >> 20) +
                 " MiB: not a configuration (puma_experiment --print-config shows one)",
           false;
  return true;
}

}  // namespace

bool qemu_takes(const Injection& inj, const std::string& where, std::string& err) {
  if (!inj.enabled || info(inj.kind).qemu) return true;
  return err = where + " " + info(inj.kind).name +
               " applies to the host-built controller only, not with --qemu (it acts on the task's tick clock or "
               "E-stop input; the image has its own, which the link's injection requests reach)",
         false;
}

std::string experiment_usage() {
  CLI::App app("", "puma_experiment");
  ExperimentOptions o;
  Parsed p;
  std::vector<std::vector<std::string>> values;
  build(app, o, p, values);
  return app.help();
}

bool parse_experiment_args(int argc, char** argv, ExperimentOptions& o, std::string& err) {
  CLI::App app("", "puma_experiment");
  Parsed p;
  std::vector<std::vector<std::string>> values;
  build(app, o, p, values);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    o.help = true;
    return true;
  } catch (const CLI::ParseError& e) {
    return err = e.what(), false;
  }
  // In the order given on the command line: the last of a repeated option wins, each one checked.
  for (const CLI::Option* opt : app.parse_order())
    for (size_t i = 0; i < values.size(); ++i)
      if (opt == app.get_option(kShorthands[i].flag)) {
        const std::size_t seen = std::count_if(p.shorthands.begin(), p.shorthands.end(),
                                               [&](const auto& sv) { return sv.first == &kShorthands[i]; });
        p.shorthands.emplace_back(&kShorthands[i], values[i].at(seen));
      }

  if (!o.config_file.empty()) {
    std::string text;
    if (!read_file(o.config_file, text, err)) return false;
    if (!apply_config(text, o.config_file, o, err)) return false;
  }
  for (const auto& [s, v] : p.shorthands)
    if (!set_key(s->key, v, o, err)) {
      // "run.duration: 0 is out of range" reads "--duration: 0 is out of range (run.duration)".
      const std::string key = s->key;
      if (err.rfind(key + ":", 0) == 0) err = std::string(s->flag) + err.substr(key.size()) + " (" + key + ")";
      return false;
    }
  for (const std::string& a : p.plant_sets)
    if (!apply_setting("plant." + a, o, err)) return err = "--plant-set: " + err, false;
  for (const std::string& a : p.sets)
    if (!apply_setting(a, o, err)) return err = "--set: " + err, false;
  if (!validate_settings(o, err)) return false;

  if (!p.inject.empty() || app.get_option("--inject")->count() > 0)
    if (!parse_injection(p.inject, o.base.injection, err)) return false;
  if (o.elf.empty()) return err = "--elf needs a file name", false;
  if (app.get_option("--pil-link")->count() > 0) {
    if (!parse_pil_link(p.pil_link, o.pil_link))
      return err = "--pil-link: '" + p.pil_link + "' is not a link: semihosting | uart", false;
    if (!o.qemu) return err = "--pil-link applies with --qemu only", false;
  }
  if (app.get_option("--json")->count() > 0 && o.json.empty()) return err = "--json needs a file name", false;
  if (app.get_option("--motion")->count() > 0 && o.motion.empty()) return err = "--motion needs a file name", false;
  if (o.csv_dir.empty()) return err = "--csv-dir needs a directory", false;
  if (o.base.power_on_pose && o.motion.empty()) return err = kPowerOnNeedsMotion, false;

  if (o.qemu) {
    // The image's controller is compiled in: only the mode and the adaptation law go over the link.
    const std::vector<std::string> changed = differences_from_paper(o);
    for (const char* key : kHostOnlyKeys)
      for (const std::string& d : changed)
        if (d == key)
          return err = d +
                       " applies to the host-built controller only, not with --qemu (the firmware image "
                       "compiles in its defaults)",
                 false;
    // The image reads its encoders as the uniform, uncoupled ones it compiles in.
    if (o.base.published_encoders || o.base.plant.coupling)
      return err = std::string(o.base.plant.coupling ? "plant.coupling" : "plant.encoders") +
                   " applies to the host-built controller only, not with --qemu (the firmware image compiles in "
                   "uniform, uncoupled encoders)",
             false;
    if (o.base.residual_monitor != osc::params::kResidualMonitorArmed)
      return err =
                 "run.residual_monitor=trial applies to the host-built controller only, not with --qemu (the "
                 "runner does not set the image's parameters: the image runs its default, the residual monitor "
                 "armed; a board makes it a trial with its parameter residual_monitor, e.g. oscctl param set "
                 "residual_monitor 0)",
             false;
    if (!qemu_takes(o.base.injection, "--inject", err)) return false;
  }
  return true;
}

}  // namespace sim
