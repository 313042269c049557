// puma_experiment: the paper's experiment (Section VI) on the simulated PUMA 560, with adaptive
// friction compensation and without, printed side by side with the paper's Tables I-III. The
// configuration (config.hpp) and its provenance go with every output (summary.hpp): console, JSON,
// CSV header, and the config.yaml written beside the time series.
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "config.hpp"
#include "experiment.hpp"
#include "experiment_cli.hpp"
#include "linked_arm.hpp"
#include "osc/control/identification.hpp"
#include "motion_script.hpp"
#include "summary.hpp"
#include "output_file.hpp"
#include "pil_client.hpp"

namespace {

using Options = sim::ExperimentOptions;

int fail(const std::string& msg) {
  std::cerr << "puma_experiment: " << msg << "\n(puma_experiment --help lists the options)\n";
  return 2;
}
/// An output that cannot be written (host_sim/output_file.hpp): the message alone.
int fail_output(const std::string& msg) {
  std::cerr << "puma_experiment: " << msg << "\n";
  return 2;
}

const char* kAxes[6] = {"e_x [mm]", "e_y [mm]", "e_z [mm]", "e_phx [deg]", "e_phy [deg]", "e_phz [deg]"};

/// Maximum tracking errors of each run, whole run and last window, beside the paper's Tables I and III.
void print_error_table(const std::vector<sim::ExperimentResult>& runs, bool paper) {
  // The paper's tables are compared with only when the set-up is the paper's.
  const char* t1 = paper ? "paper T.I" : "(T.I)";
  const char* t3 = paper ? "paper T.III" : "(T.III)";
  std::printf("\nMaximum tracking errors (simulated %s, %.0f s, friction preset '%s')%s\n", osc::robot::kArm.name,
              runs[0].duration, runs[0].friction_preset.c_str(),
              paper ? "" : "\n  (the set-up differs from the paper's: its tables, in brackets, are not comparable)");
  std::printf("%-12s", "axis");
  char last[32];
  std::snprintf(last, sizeof last, " last%gs", runs[0].final_window);  // the "last" window, as long as the run at most
  for (const auto& r : runs) std::printf(" %14s %14s", (r.mode + " all").c_str(), (r.mode + last).c_str());
  std::printf(" %10s %10s\n", t1, t3);
  for (int i = 0; i < 6; ++i) {
    std::printf("%-12s", kAxes[i]);
    for (const auto& r : runs) {
      std::printf(" %14.3f", r.max_error[i]);
      // A run that faulted before the end has no "last" window.
      if (r.status)
        std::printf(" %14s", "(faulted)");
      else
        std::printf(" %14.3f", r.final_max_error[i]);
    }
    std::printf(" %10.2f %10.2f\n", sim::kPaperTable1[i], sim::kPaperTable3[i]);
  }
  for (const auto& r : runs)
    if (r.status)
      std::printf("  [%s] faulted at %.3f s: its 'all' column covers the run up to the fault only\n", r.mode.c_str(),
                  r.fault_time);
}

/// The ratio of the errors without and with friction compensation, beside the paper's.
void print_ratio_table(const sim::ExperimentResult& ad, const sim::ExperimentResult& no, bool paper) {
  std::printf("\nRatio without / with friction compensation (whole run, last %gs; %s)\n", ad.final_window,
              paper ? "paper Table III / Table I" : "the paper's ratio is for its set-up only");
  for (int i = 0; i < 6; ++i) {
    std::printf("  %-12s %6.1fx %6.1fx", kAxes[i], no.max_error[i] / ad.max_error[i],
                no.final_max_error[i] / ad.final_max_error[i]);
    if (paper) std::printf("   paper %4.1fx", sim::kPaperTable3[i] / sim::kPaperTable1[i]);
    std::printf("\n");
  }
}

/// The adaptive run's friction estimates beside the plant's true coefficients, and their rms error.
void print_friction_table(const sim::ExperimentResult& ad) {
  static const char* names[3] = {"tau_vis [N m s/rad]", "tau_cou [N m]", "tau_sti [N m]"};
  if (ad.status)
    std::printf(
        "\nFriction estimates at the fault (t = %.3f s): not identified values (estimate / plant's true "
        "value)\n%-20s",
        ad.fault_time, "");
  else
    std::printf("\nIdentified friction coefficients after %.0f s (estimate / plant's true value, preset '%s')\n%-20s",
                ad.duration, ad.friction_preset.c_str(), "");
  for (int j = 0; j < 6; ++j) std::printf("      J%d       ", j + 1);
  std::printf("\n");
  for (int k = 0; k < 3; ++k) {
    std::printf("%-20s", names[k]);
    for (int j = 0; j < 6; ++j) std::printf(" %6.2f / %5.2f", ad.theta_hat[6 * k + j], ad.theta_true[6 * k + j]);
    std::printf("\n");
  }
  if (ad.has_identification) {
    // The excitation monitor (momentum law): each coefficient's standard deviation, * where it is
    // identified (osc::friction_identified), and the Coulomb + Stribeck sums'.
    std::printf("standard deviations of the estimates (*: identified)\n");
    static const char* sd_names[3] = {"  sd vis", "  sd cou", "  sd sti"};
    for (int k = 0; k < 3; ++k) {
      std::printf("%-20s", sd_names[k]);
      for (int j = 0; j < 6; ++j) {
        const int c = 6 * k + j;
        std::printf(" %13.3f%c", ad.theta_sd[c], osc::friction_identified(ad.theta_hat[c], ad.theta_sd[c]) ? '*' : ' ');
      }
      std::printf("\n");
    }
    std::printf("%-20s", "  cou + sti");
    for (int j = 0; j < 6; ++j) {
      const double sum = ad.theta_hat[6 + j] + ad.theta_hat[12 + j];
      std::printf(" %5.2f+-%5.3f%c", sum, ad.breakaway_sd[j],
                  osc::friction_identified(sum, ad.breakaway_sd[j]) ? '*' : ' ');
    }
    std::printf("\n");
    // The excitation monitor's gate on the Coulomb / Stribeck split (FrictionIdentifier::excite).
    std::printf("%-20s", "  split excitation");
    for (int j = 0; j < 6; ++j)
      std::printf(" %6.3f %-7s", ad.split_excitation[j],
                  osc::split_excited(ad.split_excitation[j]) ? "learned" : "held");
    std::printf("\n  (the Stribeck decay's RMS excitation; the split is learned at %.2f and above)\n",
                osc::params::kIdentifySplitExcitation);
  }
  if (!ad.status)
    std::printf("estimated vs true joint friction over the last %gs: rms error %.3f N m (rms friction %.3f N m)\n",
                ad.final_window, ad.friction_rms_error, ad.friction_rms);
}

/// The console: provenance, faults, the paper's tables, then the metrics' lines of each run.
void print_tables(const std::vector<sim::ExperimentResult>& runs, const sim::Provenance& prov) {
  std::printf("%s\nset-up: %s\n", prov.line().c_str(), prov.setup().c_str());
  for (const auto& r : runs) r.print_state(r);
  const bool paper = prov.differs.empty();
  print_error_table(runs, paper);
  const sim::ExperimentResult* ad = nullptr;
  const sim::ExperimentResult* no = nullptr;
  for (const auto& r : runs) (r.mode == "adaptive" ? ad : no) = &r;
  if (ad && no && !ad->status && !no->status) print_ratio_table(*ad, *no, paper);
  if (ad) print_friction_table(*ad);
  sim::print_metric_lines(runs);
  for (const auto& r : runs) r.print_reminder(r);
}

bool write_csv(const std::string& dir, const sim::ExperimentResult& r, const sim::Provenance& prov, std::string& err) {
  return sim::write_output(dir + "/" + sim::csv_name(r), sim::csv_text(r, prov), err);
}

/// The firmware image for --qemu and the output folders and files, checked before the runs; a
/// summary on standard output ("--json -", or /dev/stdout) gets it to itself: json_fd is then a copy
/// of it, and the tables go to standard error, so that "--json - | jq ." reads JSON only. 0: fine,
/// else the exit code (the message printed).
int prepare(Options& o, int& json_fd) {
  std::string err;
  if (o.qemu) {
    sim::Scalar image = sim::Scalar::kFloat;
    if (!sim::pil_image(o.elf, o.pil_link, o.base.pil_command, image, err)) return fail(err);
    if (o.base.scalar == sim::Scalar::kDouble) o.base.scalar = image;
    // A script's JSON names the scalar it ran in, to be compared with the in-process run of it.
    if (!o.motion.empty() && o.base.scalar != image)
      return fail(std::string("--scalar ") + sim::kScalarNames[static_cast<int>(o.base.scalar)] + ": the image " +
                  o.elf + " computes in " + sim::kScalarNames[static_cast<int>(image)]);
  }
  if (o.csv) {
    // No shell: the name is a path, never a command.
    std::error_code ec;
    std::filesystem::create_directories(o.csv_dir, ec);
    if (ec || !std::filesystem::is_directory(o.csv_dir))
      return fail_output("cannot create directory " + o.csv_dir + (ec ? ": " + ec.message() : ""));
  }
  if (!o.json.empty() && !sim::check_output(o.json, err)) return fail_output(err);
  if (!o.json.empty() && sim::is_stdout(o.json)) {
    std::fflush(stdout);
    json_fd = dup(STDOUT_FILENO);
    if (json_fd < 0 || dup2(STDERR_FILENO, STDOUT_FILENO) < 0)
      return fail_output("cannot set up standard output for --json");
  }
  return 0;
}

/// The runs the options ask for, each with its mode; their time series' paths checked (written after the runs).
bool run_configs(const Options& o, std::vector<sim::ExperimentConfig>& cfgs, std::string& err) {
  if (o.run_adaptive) cfgs.push_back(o.base), cfgs.back().mode = osc::FrictionMode::kAdaptive;
  if (o.run_none) cfgs.push_back(o.base), cfgs.back().mode = osc::FrictionMode::kNone;
  for (const auto& c : cfgs) {
    sim::ExperimentResult named;
    named.mode = sim::mode_name(c.mode);
    if (o.csv && !sim::check_output(o.csv_dir + "/" + sim::csv_name(named), err)) return false;
  }
  return true;
}

/// Runs the experiments, one thread each (they are independent; the machine has two cores), with a
/// progress bar when `bar`.
std::vector<sim::ExperimentResult> run_all(std::vector<sim::ExperimentConfig>& cfgs, bool bar) {
  std::vector<std::atomic<double>> frac(cfgs.size());
  for (auto& f : frac) f = 0;
  for (size_t i = 0; i < cfgs.size(); ++i)
    if (bar) cfgs[i].progress = [&frac, i](double x) { frac[i] = x; };
  std::vector<sim::ExperimentResult> runs(cfgs.size());
  std::vector<std::thread> threads;
  for (size_t i = 0; i < cfgs.size(); ++i) threads.emplace_back([&, i] { runs[i] = sim::run_experiment(cfgs[i]); });
  if (bar) {
    for (;;) {
      double sum = 0;
      for (auto& f : frac) sum += f;
      const double p = sum / frac.size();
      const int w = 40, n = static_cast<int>(p * w);
      std::fprintf(stderr, "\r[%s%s] %3.0f%%", std::string(n, '#').c_str(), std::string(w - n, ' ').c_str(), p * 100);
      if (p >= 1.0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    std::fprintf(stderr, "\n");
  }
  for (auto& t : threads) t.join();
  return runs;
}

/// The time series and the summary JSON (to json_fd when it is standard output). 0: fine, else the exit code.
int write_outputs(const Options& o, const std::vector<sim::ExperimentResult>& runs, const sim::Provenance& prov,
                  int json_fd) {
  std::string err;
  if (o.csv) {
    for (const auto& r : runs)
      if (!write_csv(o.csv_dir, r, prov, err)) return fail_output(err);
    std::printf("time series: %s/timeseries_*.csv, configuration: %s\n", o.csv_dir.c_str(), prov.config_file.c_str());
  }
  if (!o.json.empty()) {
    const std::string text = sim::summary_json(runs, o, prov, o.csv).dump(2) + "\n";
    std::fflush(stdout);
    const bool ok = json_fd >= 0 ? sim::write_all(json_fd, text, "standard output", err) && close(json_fd) == 0
                                 : sim::write_output(o.json, text, err);
    if (!ok)
      return fail_output(err.empty() ? "cannot write standard output: " + std::string(std::strerror(errno)) : err);
    std::printf("summary: %s\n", o.json.c_str());
  }
  return 0;
}

/// --motion: plays the script on the simulated arm (with --qemu, against the firmware image over the
/// link), prints a line per command, writes the JSON. 0: the script ran without a fault; 1: a fault,
/// a timeout or a failed link; 2: a bad script or output.
int run_motion(const Options& o, int json_fd) {
  std::string text, err;
  {
    std::ifstream f(o.motion, std::ios::binary);
    if (!f) return fail("cannot read motion script " + o.motion);
    text.assign(sim::kMaxConfigBytes + 1, '\0');
    f.read(text.data(), static_cast<std::streamsize>(text.size()));
    text.resize(static_cast<std::size_t>(f.gcount()));
    if (text.size() > sim::kMaxConfigBytes) return fail("motion script " + o.motion + " is larger than 1 MiB");
  }
  sim::MotionScript script;
  if (!sim::parse_motion_script(text, o.motion, script, err)) return fail(err);
  sim::ExperimentConfig cfg = o.base;
  cfg.mode = o.run_adaptive ? osc::FrictionMode::kAdaptive : osc::FrictionMode::kNone;
  if (script.injection.enabled) {
    if (cfg.injection.enabled)
      return fail(o.motion + ": inject: and --inject both given (" + sim::to_string(script.injection) + ", " +
                  sim::to_string(cfg.injection) + "): one injection per run");
    if (o.qemu && !sim::qemu_takes(script.injection, o.motion + ": inject:", err)) return fail(err);
    cfg.injection = script.injection;
  }
  // The image's encoders read zero at the robot's start pose, which it compiles in.
  if (o.qemu && script.start_pose && *script.start_pose != cfg.q_start)
    return fail(o.motion + ": start_pose: the firmware image starts at the robot's start pose (not with --qemu)");
  const sim::MotionRun run = sim::run_motion_script(script, cfg);
  if (!run.error.empty()) std::fprintf(stderr, "puma_experiment: %s\n", run.error.c_str());
  std::printf("motion script %s (%s, %s, %s): %s after %.3f s (%.1f s wall); max tracking error %.3f mm, %.3f deg\n",
              o.motion.c_str(), o.qemu ? ("firmware image " + o.elf).c_str() : "in process",
              sim::kScalarNames[static_cast<int>(cfg.scalar)], sim::mode_name(cfg.mode), run.result.c_str(),
              run.duration_s, run.wall_s, run.max_error_mm, run.max_error_deg);
  for (const sim::CommandRecord& r : run.commands) {
    std::printf("  %6.3f s  %-8s %-9s", r.sent_s, r.cmd.c_str(),
                r.accepted ? "accepted" : ("refused " + r.refused).c_str());
    if (r.done_s >= 0) std::printf("  done %.3f s", r.done_s);
    if (!r.aborted.empty()) std::printf("  aborted %s at %.3f s", r.aborted.c_str(), r.aborted_s);
    if (r.v > 0) std::printf("  tracking %.3f mm %.3f deg, v %.3f m/s", r.max_error_mm, r.max_error_deg, r.v);
    std::printf("\n");
  }
  if (!o.json.empty()) {
    const std::string out = sim::motion_run_json(run, o.motion, cfg);
    std::fflush(stdout);
    const bool ok = json_fd >= 0 ? sim::write_all(json_fd, out, "standard output", err) && close(json_fd) == 0
                                 : sim::write_output(o.json, out, err);
    if (!ok) return fail_output(err);
    std::printf("summary: %s\n", o.json.c_str());
  }
  if (run.controller == "pil" && !run.link.clean())
    std::fprintf(stderr, "puma_experiment: link errors (%s)\n", run.link.first_zeroed.c_str());
  return run.result == "ok" && (run.controller != "pil" || run.link.clean()) ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  std::string err;
  if (!sim::parse_experiment_args(argc, argv, o, err)) return fail(err);
  if (o.help) {
    std::cout << sim::experiment_usage();
    return 0;
  }
  if (o.print_config) {
    std::cout << sim::config_yaml(o);
    return 0;
  }
  int json_fd = -1;
  if (const int code = prepare(o, json_fd)) return code;
  if (!o.motion.empty()) return run_motion(o, json_fd);

  sim::Provenance prov;
  prov.revision = sim::git_revision();
  prov.config_text = sim::config_yaml(o);
  prov.config_hash = sim::text_hash(prov.config_text);
  prov.differs = sim::differences_from_paper(o);
  prov.plant = o.plant_preset;
  prov.plant_differs = sim::differences_from_preset(o);
  if (o.csv) {
    prov.config_file = o.csv_dir + "/config.yaml";
    if (!sim::write_output(prov.config_file, prov.config_text, err)) return fail_output(err);
  }

  std::vector<sim::ExperimentConfig> cfgs;
  if (!run_configs(o, cfgs, err)) return fail_output(err);
  // Progress bar on a terminal only, for runs longer than a second.
  const std::vector<sim::ExperimentResult> runs =
      run_all(cfgs, o.progress && isatty(STDERR_FILENO) && o.base.duration > 1.0);

  print_tables(runs, prov);
  if (const int code = write_outputs(o, runs, prov, json_fd)) return code;
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) return fail_output("cannot write standard output");
  // A fault is a failed run, unless a fault was injected on purpose (then the JSON tells how it went).
  for (const auto& r : runs)
    if ((r.status && !o.base.injection.enabled) || !r.error.empty() || !r.link.clean()) return 1;
  return 0;
}
