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
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "config.hpp"
#include "experiment.hpp"
#include "experiment_cli.hpp"
#include "summary.hpp"
#include "injection.hpp"
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

/// The worst max |e| per window over the run, in blocks of about ten, so that growth shows.
void print_windows(const sim::ExperimentResult& r) {
  const size_t n = r.window_max.size();
  if (n < 3) return;
  const size_t block = std::max<size_t>(1, n / 10);
  std::printf("\n[%s] worst max |e| per %.0f s window (x, y, z mm; about X, Y, Z deg) and the range of theta^:\n",
              r.mode.c_str(), r.window);
  for (size_t b = 0; b < n; b += block) {
    double w[6] = {}, lo = 1e300, hi = -1e300;
    for (size_t k = b; k < std::min(n, b + block); ++k) {
      for (int i = 0; i < 6; ++i) w[i] = std::max(w[i], r.window_max[k][i]);
      lo = std::min(lo, r.window_theta_range[k][0]);
      hi = std::max(hi, r.window_theta_range[k][1]);
    }
    std::printf("  t %6.0f..%6.0f s: %.3f %.3f %.3f mm  %.4f %.4f %.4f deg   theta^ in [%.2f, %.2f]\n", b * r.window,
                std::min(n, b + block) * r.window, w[0], w[1], w[2], w[3], w[4], w[5], lo, hi);
  }
}

/// "none", or the nonzero link error counters as "name n, ...".
std::string counters_text(const pil::LinkCounters& c) {
  std::string s;
  for (int k = 0; k < pil::kLinkErrorKinds; ++k)
    if (c.count[k])
      s += (s.empty() ? "" : ", ") + std::string(pil::kLinkErrorNames[k]) + " " + std::to_string(c.count[k]);
  return s.empty() ? "none" : s;
}

/// The fault of a run in words: names, tick, time and the state at that moment.
void print_fault(const sim::ExperimentResult& r) {
  const sim::FaultState& f = r.fault;
  std::printf("[%s] FAULT %s at tick %ld, t = %.3f s (latched; zero torque from that tick on)\n", r.mode.c_str(),
              osc::fault_name(f.faults), f.tick, f.t);
  std::printf("[%s]   every fault bit:", r.mode.c_str());
  for (int i = 0; i < osc::kFaultCount; ++i)
    if (f.faults & (1u << i)) std::printf(" %s", osc::kFaultNames[i]);
  std::printf("\n[%s]   q [deg]:      ", r.mode.c_str());
  for (double v : f.q) std::printf(" %9.3f", v * 180 / osc::kPi);
  std::printf("\n[%s]   qdot [deg/s]: ", r.mode.c_str());
  for (double v : f.qd) std::printf(" %9.3f", v * 180 / osc::kPi);
  std::printf("\n[%s]   tau [N m]:    ", r.mode.c_str());
  for (double v : f.tau) std::printf(" %9.3f", v);
  std::printf("\n[%s]   error:         %.3f %.3f %.3f mm  %.4f %.4f %.4f deg\n", r.mode.c_str(), f.e[0], f.e[1], f.e[2],
              f.e[3], f.e[4], f.e[5]);
  std::printf("[%s]   the statistics below cover 0..%.3f s; the robot after the fault is no result\n", r.mode.c_str(),
              r.stats_until);
}

void print_tables(const std::vector<sim::ExperimentResult>& runs, const sim::Provenance& prov, sim::Scalar scalar) {
  std::printf("%s\nset-up: %s\n", prov.line().c_str(), prov.setup().c_str());
  for (const auto& r : runs)
    if (r.status) print_fault(r);
  const bool paper = prov.differs.empty();
  // The paper's tables are compared with only when the set-up is the paper's.
  const char* t1 = paper ? "paper T.I" : "(T.I)";
  const char* t3 = paper ? "paper T.III" : "(T.III)";
  std::printf("\nMaximum tracking errors (simulated PUMA 560, %.0f s, friction preset '%s')%s\n", runs[0].duration,
              runs[0].friction_preset.c_str(),
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
  const sim::ExperimentResult* ad = nullptr;
  const sim::ExperimentResult* no = nullptr;
  for (const auto& r : runs) (r.mode == "adaptive" ? ad : no) = &r;
  if (ad && no && !ad->status && !no->status) {
    std::printf("\nRatio without / with friction compensation (whole run, last %gs; %s)\n", ad->final_window,
                paper ? "paper Table III / Table I" : "the paper's ratio is for its set-up only");
    for (int i = 0; i < 6; ++i) {
      std::printf("  %-12s %6.1fx %6.1fx", kAxes[i], no->max_error[i] / ad->max_error[i],
                  no->final_max_error[i] / ad->final_max_error[i]);
      if (paper) std::printf("   paper %4.1fx", sim::kPaperTable3[i] / sim::kPaperTable1[i]);
      std::printf("\n");
    }
  }
  if (ad) {
    static const char* names[3] = {"tau_vis [N m s/rad]", "tau_cou [N m]", "tau_sti [N m]"};
    if (ad->status)
      std::printf(
          "\nFriction estimates at the fault (t = %.3f s): not identified values (estimate / plant's true "
          "value)\n%-20s",
          ad->fault_time, "");
    else
      std::printf("\nIdentified friction coefficients after %.0f s (estimate / plant's true value, preset '%s')\n%-20s",
                  ad->duration, ad->friction_preset.c_str(), "");
    for (int j = 0; j < 6; ++j) std::printf("      J%d       ", j + 1);
    std::printf("\n");
    for (int k = 0; k < 3; ++k) {
      std::printf("%-20s", names[k]);
      for (int j = 0; j < 6; ++j) std::printf(" %6.2f / %5.2f", ad->theta_hat[6 * k + j], ad->theta_true[6 * k + j]);
      std::printf("\n");
    }
    if (!ad->status)
      std::printf("estimated vs true joint friction over the last %gs: rms error %.3f N m (rms friction %.3f N m)\n",
                  ad->final_window, ad->friction_rms_error, ad->friction_rms);
  }
  for (const auto& r : runs)
    if (r.has_observer && !r.status)
      std::printf(
          "[%s] observer error over the last %gs: |x~| max %.4f %.4f %.4f mm  %.5f %.5f %.5f deg; velocity "
          "%.2f %.2f %.2f mm/s  %.3f %.3f %.3f deg/s\n",
          r.mode.c_str(), r.final_window, r.max_observer_error[0], r.max_observer_error[1], r.max_observer_error[2],
          r.max_observer_error[3], r.max_observer_error[4], r.max_observer_error[5], r.max_observer_velocity_error[0],
          r.max_observer_velocity_error[1], r.max_observer_velocity_error[2], r.max_observer_velocity_error[3],
          r.max_observer_velocity_error[4], r.max_observer_velocity_error[5]);
  for (const auto& r : runs) print_windows(r);
  for (const auto& r : runs) {
    if (!r.error.empty()) std::printf("[%s] LINK ERROR: %s\n", r.mode.c_str(), r.error.c_str());
    if (r.max_step_cycles)
      std::printf(
          "[%s] firmware control step (observer + controller + adaptation, %s): max %u, mean %u "
          "instructions (QEMU -icount shift=0); whole tick incl. link I/O max %u; stack used %u bytes\n",
          r.mode.c_str(), sim::kScalarNames[static_cast<int>(scalar)], r.max_step_cycles, r.mean_step_cycles,
          r.max_tick_cycles, r.stack_used);
    if (r.max_step_cycles) {
      std::printf(
          "[%s] link: longest gap between received bytes %u cycles (ns of target time in QEMU), %u over %d periods; "
          "errors counted by the firmware: %s; by the host: %s, codes out of range %u; ticks zeroed %u%s%s\n",
          r.mode.c_str(), r.link.rx_gap_max, r.link.rx_long_gaps, osc::params::kLinkSilenceTicks,
          counters_text(r.link.firmware).c_str(), counters_text(r.link.host).c_str(), r.link.host_code_range,
          r.link.zeroed_ticks, r.link.first_zeroed.empty() ? "" : ", the first: ", r.link.first_zeroed.c_str());
    }
    std::printf(
        "[%s] simulated %.0f s in %.2f s wall (%.3gx real time); %.2f s CPU (%.3gx real time); "
        "%.1f plant evaluations per sample\n",
        r.mode.c_str(), r.duration, r.wall_seconds, r.duration / r.wall_seconds, r.cpu_seconds,
        r.duration / r.cpu_seconds, static_cast<double>(r.plant_evaluations) / (r.duration / osc::params::kDt));
    if (r.injection.injection.enabled) {
      const sim::InjectionResult& ir = r.injection;
      std::printf("[%s] injected %s: ", r.mode.c_str(), sim::to_string(ir.injection).c_str());
      if (ir.detected < 0)
        std::printf("never detected");
      else
        std::printf("detected after %.1f ms as %s", (ir.detected - ir.injection.at) * 1e3, osc::fault_name(ir.faults));
      if (ir.zero_torque < 0)
        std::printf(", torque never zero");
      else
        std::printf(", zero torque after %.1f ms", (ir.zero_torque - ir.injection.at) * 1e3);
      std::printf(", tip excursion %.2f mm, largest torque after detection %.2f N m\n", ir.excursion_mm,
                  ir.max_torque_after);
    }
  }
  for (const auto& r : runs)
    if (r.status)
      std::printf("[%s] FAULT %s at t = %.3f s (tick %ld)\n", r.mode.c_str(), osc::fault_name(r.fault.faults),
                  r.fault_time, r.fault.tick);
}

bool write_csv(const std::string& dir, const sim::ExperimentResult& r, const sim::Provenance& prov, std::string& err) {
  return sim::write_output(dir + "/" + sim::csv_name(r), sim::csv_text(r, prov), err);
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
  if (o.qemu) {
    if (access(o.elf.c_str(), R_OK) != 0)
      return fail("firmware image " + o.elf +
                  " not found: build it with 'cmake --preset m4f && cmake --build --preset m4f'");
    // The M4F firmware computes in float (the M3 image in fixed point: --scalar fixed says so).
    if (o.base.scalar == sim::Scalar::kDouble) o.base.scalar = sim::Scalar::kFloat;
    o.base.pil_command = sim::PilClient::qemu_command("qemu-system-arm", o.elf, o.pil_link, err);
    if (o.base.pil_command.empty()) return fail(err);
  }
  if (o.csv) {
    // No shell: the name is a path, never a command.
    std::error_code ec;
    std::filesystem::create_directories(o.csv_dir, ec);
    if (ec || !std::filesystem::is_directory(o.csv_dir))
      return fail_output("cannot create directory " + o.csv_dir + (ec ? ": " + ec.message() : ""));
  }
  if (!o.json.empty() && !sim::check_output(o.json, err)) return fail_output(err);
  // A summary on standard output ("--json -", or /dev/stdout) has it to itself: the tables go to
  // standard error, so that "--json - | jq ." reads JSON only.
  int json_fd = -1;
  if (!o.json.empty() && sim::is_stdout(o.json)) {
    std::fflush(stdout);
    json_fd = dup(STDOUT_FILENO);
    if (json_fd < 0 || dup2(STDERR_FILENO, STDOUT_FILENO) < 0)
      return fail_output("cannot set up standard output for --json");
  }

  sim::Provenance prov;
  prov.revision = sim::git_revision();
  prov.config_text = sim::config_yaml(o);
  prov.config_hash = sim::text_hash(prov.config_text);
  prov.differs = sim::differences_from_paper(o);
  if (o.csv) {
    prov.config_file = o.csv_dir + "/config.yaml";
    if (!sim::write_output(prov.config_file, prov.config_text, err)) return fail_output(err);
  }

  std::vector<sim::ExperimentConfig> cfgs;
  if (o.run_adaptive) cfgs.push_back(o.base), cfgs.back().mode = osc::FrictionMode::kAdaptive;
  if (o.run_none) cfgs.push_back(o.base), cfgs.back().mode = osc::FrictionMode::kNone;
  // The time series are written after the run: their paths are checked before it.
  for (const auto& c : cfgs) {
    sim::ExperimentResult named;
    named.mode = sim::mode_name(c.mode);
    if (o.csv && !sim::check_output(o.csv_dir + "/" + sim::csv_name(named), err)) return fail_output(err);
  }

  // Progress bar on a terminal only, for runs longer than a second.
  const bool bar = o.progress && isatty(STDERR_FILENO) && o.base.duration > 1.0;
  std::vector<std::atomic<double>> frac(cfgs.size());
  for (auto& f : frac) f = 0;
  for (size_t i = 0; i < cfgs.size(); ++i)
    if (bar) cfgs[i].progress = [&frac, i](double x) { frac[i] = x; };

  // The runs are independent: one thread each (the machine has two cores).
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

  print_tables(runs, prov, o.base.scalar);
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
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) return fail_output("cannot write standard output");
  // A fault is a failed run, unless a fault was injected on purpose (then the JSON tells how it went).
  for (const auto& r : runs)
    if ((r.status && !o.base.injection.enabled) || !r.error.empty() || !r.link.clean()) return 1;
  return 0;
}
