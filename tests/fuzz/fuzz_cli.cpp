// Fuzz target: puma_experiment's command-line parser (host_sim/experiment_cli.cpp,
// sim::parse_experiment_args), with argv made of the input's NUL-separated strings (at most 64).
//
// Invariants: the parser never crashes (CLI11 and yaml-cpp exceptions are caught inside) and either
//  - succeeds with an empty error and every value within its documented range: duration [1, 86400],
//    encoder counts per motor revolution [100, 1e7], model error [-0.5, 0.5], RK4 substep
//    [1e-6, 1e-3], whole RK4 substeps at once [1, 16], delay [0, dt], final window [1, 3600], all finite; a known
//    friction preset, scalar and adaptation law; at least one mode to run; non-empty file names; trajectory within its
//    ranges with a whole period; and its effective configuration, printed and read back into the defaults, prints the
//    same again (--print-config is a fixed point); or
//  - fails with a message;
// and parsing the same arguments again gives the same answer.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "experiment_cli.hpp"
#include "fuzz_util.hpp"

namespace {

bool in_range(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// By name and values (each translation unit may have its own copy of a preset's name).
bool same_friction(const osc::FrictionCoefficients& a, const osc::FrictionCoefficients& b) {
  return std::strcmp(a.name, b.name) == 0 && std::memcmp(a.vis, b.vis, sizeof a.vis) == 0 &&
         std::memcmp(a.cou, b.cou, sizeof a.cou) == 0 && std::memcmp(a.sti, b.sti, sizeof a.sti) == 0;
}

void check_options(const sim::ExperimentOptions& o) {
  FUZZ_CHECK(in_range(o.base.duration, 1, 86400));
  FUZZ_CHECK(in_range(o.base.encoder_counts_per_motor_rev, 100, 1e7));
  FUZZ_CHECK(in_range(o.base.model_error, -0.5, 0.5));
  FUZZ_CHECK(in_range(o.base.plant.substep, 1e-6, 1e-3));
  FUZZ_CHECK(o.base.plant.smooth_steps >= 1 && o.base.plant.smooth_steps <= 16);
  FUZZ_CHECK(in_range(o.base.plant.compute_delay, 0, osc::params::kDt));
  FUZZ_CHECK(in_range(o.base.final_window, 1, 3600));
  const auto& fr = o.base.plant.friction;
  bool custom_ok = std::strcmp(fr.name, "custom") == 0;
  for (int i = 0; i < 6; ++i)
    custom_ok = custom_ok && in_range(fr.vis[i], 0, 200) && in_range(fr.cou[i], 0, 200) && in_range(fr.sti[i], 0, 200);
  FUZZ_CHECK(same_friction(fr, osc::robot::kFrictionPaper) || same_friction(fr, osc::robot::kFrictionCorke) ||
             same_friction(fr, osc::kFrictionNone) || custom_ok);
  const auto& tr = o.base.gains.trajectory;
  FUZZ_CHECK(in_range(tr.amplitude, 0, 0.2) && in_range(tr.envelope, 1e-3, 10));
  FUZZ_CHECK(tr.period_ticks >= 500 && tr.period_ticks <= 60000 && tr.settled_ticks % tr.period_ticks == 0);
  for (int i = 0; i < 6; ++i)
    FUZZ_CHECK(o.base.q_start(i) >= osc::robot::kArm.q_min[i] - 1e-9 &&
               o.base.q_start(i) <= osc::robot::kArm.q_max[i] + 1e-9);
  // The printed configuration reads back to itself.
  const std::string text = sim::config_yaml(o);
  sim::Settings back;
  std::string err;
  FUZZ_CHECK(sim::apply_config(text, "printed", back, err));
  FUZZ_CHECK(sim::config_yaml(back) == text);
  FUZZ_CHECK(o.base.scalar == sim::Scalar::kDouble || o.base.scalar == sim::Scalar::kFloat);
  FUZZ_CHECK(static_cast<int>(o.base.gains.adaptation) >= 0 &&
             static_cast<int>(o.base.gains.adaptation) < osc::kAdaptationLawCount);
  FUZZ_CHECK(o.run_adaptive || o.run_none);
  FUZZ_CHECK(!o.elf.empty() && !o.csv_dir.empty());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> args{"puma_experiment"};
  std::string cur;
  for (std::size_t i = 0; i < size; ++i) {
    if (data[i] == 0) {
      args.push_back(cur);
      cur.clear();
      if (args.size() > 64) break;
    } else {
      cur += static_cast<char>(data[i]);
    }
  }
  if (!cur.empty() && args.size() <= 64) args.push_back(cur);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const int argc = static_cast<int>(args.size());

  sim::ExperimentOptions o;
  std::string err;
  const bool ok = sim::parse_experiment_args(argc, argv.data(), o, err);
  if (ok) {
    FUZZ_CHECK(err.empty());
    if (!o.help) check_options(o);  // with --help nothing else is read (the program prints the help and exits)
  } else {
    FUZZ_CHECK(!err.empty());
  }

  sim::ExperimentOptions again;
  std::string err2;
  FUZZ_CHECK(sim::parse_experiment_args(argc, argv.data(), again, err2) == ok);
  FUZZ_CHECK(err2 == err);
  if (ok) {
    FUZZ_CHECK(again.help == o.help && again.base.duration == o.base.duration && again.json == o.json &&
               again.csv_dir == o.csv_dir && again.elf == o.elf && again.qemu == o.qemu);
  }
  return 0;
}
