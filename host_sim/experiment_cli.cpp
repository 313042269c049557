// puma_experiment's command line (see experiment_cli.hpp).
#include "experiment_cli.hpp"

#include "injection.hpp"

#include "cli.hpp"

namespace sim {

const char* const kExperimentUsage =
    "usage: puma_experiment [options]\n"
    "  --duration S        simulated seconds per run (default 120; 1..86400)\n"
    "  --mode M            both | adaptive | none (default both)\n"
    "  --friction P        plant friction preset: paper | corke | none (default paper)\n"
    "  --scalar T          controller arithmetic: double | float (default double)\n"
    "  --adaptation L      friction adaptation law: paper (default: the firmware's)\n"
    "  --model-error F     controller link mass/inertia relative error (default 0; -0.5..0.5)\n"
    "  --encoder-cpr C     encoder counts per motor revolution, plant and controller (default 1000; 100..1e7)\n"
    "  --substep S         plant RK4 step in seconds (default 1e-4; 1e-6..1e-3)\n"
    "  --delay S           computation delay inside the sample (default 2e-4; 0..1e-3)\n"
    "  --qemu              run the controller as the firmware image in qemu-system-arm (PIL)\n"
    "  --elf FILE          firmware image for --qemu (default: the m4f build's pil_firmware.elf)\n"
    "  --json FILE         write the summary as JSON\n"
    "  --csv-dir DIR       write time series CSV files there (default: out)\n"
    "  --inject KIND[:J]@S inject a fault into the simulated hardware at S seconds, on joint J (1..6;\n"
    "                      default every joint): encoder-stuck | encoder-jump | encoder-garbage |\n"
    "                      encoder-noise | dac-stuck | overrun | estop (docs/safety.md)\n"
    "  --final-window S    length of the \"last\" statistics at the end of the run (default 20; 1..3600)\n"
    "  --no-csv            do not write time series\n"
    "  --no-progress       no progress bar\n"
    "  --help              this text\n";

bool parse_experiment_args(int argc, char** argv, ExperimentOptions& o, std::string& err) {
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    // --flag=value is --flag value.
    std::string inline_value;
    const auto eq = a.find('=');
    const bool has_inline = a.rfind("--", 0) == 0 && eq != std::string::npos;
    if (has_inline) {
      inline_value = a.substr(eq + 1);
      a.resize(eq);
    }
    const char* v = has_inline ? inline_value.c_str() : i + 1 < argc ? argv[i + 1] : nullptr;
    bool took = false;
    auto take = [&]() -> const char* {
      took = true;
      if (!has_inline) ++i;
      return v;
    };
    if (a == "--help" || a == "-h") {
      o.help = true;
      return true;
    } else if (a == "--duration") {
      if (!parse_number(a, take(), 1, 86400, o.duration, err)) return false;
    } else if (a == "--mode") {
      const char* m = take();
      const std::string s = m ? m : "";
      if (s == "both") o.run_adaptive = o.run_none = true;
      else if (s == "adaptive") o.run_adaptive = true, o.run_none = false;
      else if (s == "none") o.run_adaptive = false, o.run_none = true;
      else return err = "--mode: expected both, adaptive or none, got '" + s + "'", false;
    } else if (a == "--friction") {
      const char* m = take();
      const std::string s = m ? m : "";
      if (s == "paper") o.base.plant.friction = osc::robot::kFrictionPaper;
      else if (s == "corke") o.base.plant.friction = osc::robot::kFrictionCorke;
      else if (s == "none") o.base.plant.friction = osc::kFrictionNone;
      else return err = "--friction: expected paper, corke or none, got '" + s + "'", false;
    } else if (a == "--scalar") {
      const char* m = take();
      const std::string s = m ? m : "";
      if (s == "double") o.base.scalar = Scalar::kDouble;
      else if (s == "float") o.base.scalar = Scalar::kFloat;
      else return err = "--scalar: expected double or float, got '" + s + "'", false;
    } else if (a == "--adaptation") {
      const char* m = take();
      const std::string s = m ? m : "";
      if (!osc::adaptation_law_from_name(s, o.base.adaptation)) {
        err = "--adaptation: expected";
        for (int k = 0; k < osc::kAdaptationLawCount; ++k) err += std::string(k ? " or " : " ") + osc::kAdaptationLawNames[k];
        return err += ", got '" + s + "'", false;
      }
    } else if (a == "--encoder-cpr") {
      if (!parse_number(a, take(), 100, 1e7, o.base.encoder_counts_per_motor_rev, err)) return false;
    } else if (a == "--model-error") {
      if (!parse_number(a, take(), -0.5, 0.5, o.base.model_error, err)) return false;
    } else if (a == "--substep") {
      if (!parse_number(a, take(), 1e-6, 1e-3, o.base.plant.substep, err)) return false;
    } else if (a == "--delay") {
      if (!parse_number(a, take(), 0, osc::params::kDt, o.base.plant.compute_delay, err)) return false;
    } else if (a == "--qemu") {
      o.qemu = true;
    } else if (a == "--elf") {
      const char* f = take();
      if (!f || !*f) return err = "--elf needs a file name", false;
      o.elf = f;
    } else if (a == "--json") {
      const char* f = take();
      if (!f || !*f) return err = "--json needs a file name", false;
      o.json = f;
    } else if (a == "--csv-dir") {
      const char* f = take();
      if (!f || !*f) return err = "--csv-dir needs a directory", false;
      o.csv_dir = f;
    } else if (a == "--final-window") {
      if (!parse_number(a, take(), 1, 3600, o.base.final_window, err)) return false;
    } else if (a == "--inject") {
      const char* f = take();
      if (!parse_injection(f ? f : "", o.base.injection, err)) return false;
    } else if (a == "--no-csv") {
      o.csv = false;
    } else if (a == "--no-progress") {
      o.progress = false;
    } else {
      return err = "unknown option '" + a + "'", false;
    }
    if (has_inline && !took) return err = a + " takes no value", false;
  }
  return true;
}

}  // namespace sim
