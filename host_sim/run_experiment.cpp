// puma_experiment: the paper's experiment (Section VI) on the simulated PUMA 560, with adaptive
// friction compensation and without, printed side by side with the paper's Tables I-III.
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "experiment.hpp"
#include "experiment_cli.hpp"
#include "injection.hpp"
#include "pil_client.hpp"

namespace {

using Options = sim::ExperimentOptions;

int fail(const std::string& msg) {
  std::cerr << "puma_experiment: " << msg << "\n(puma_experiment --help lists the options)\n";
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
    if (c.count[k]) s += (s.empty() ? "" : ", ") + std::string(pil::kLinkErrorNames[k]) + " " + std::to_string(c.count[k]);
  return s.empty() ? "none" : s;
}

void print_tables(const std::vector<sim::ExperimentResult>& runs) {
  std::printf("\nMaximum tracking errors (simulated PUMA 560, %.0f s, friction preset '%s')\n", runs[0].duration,
              runs[0].friction_preset.c_str());
  std::printf("%-12s", "axis");
  char last[32];
  std::snprintf(last, sizeof last, " last%gs", runs[0].final_window);  // the "last" window, as long as the run at most
  for (const auto& r : runs) std::printf(" %14s %14s", (r.mode + " all").c_str(), (r.mode + last).c_str());
  std::printf(" %10s %10s\n", "paper T.I", "paper T.III");
  for (int i = 0; i < 6; ++i) {
    std::printf("%-12s", kAxes[i]);
    for (const auto& r : runs) std::printf(" %14.3f %14.3f", r.max_error[i], r.final_max_error[i]);
    std::printf(" %10.2f %10.2f\n", sim::kPaperTable1[i], sim::kPaperTable3[i]);
  }
  const sim::ExperimentResult* ad = nullptr;
  const sim::ExperimentResult* no = nullptr;
  for (const auto& r : runs) (r.mode == "adaptive" ? ad : no) = &r;
  if (ad && no) {
    std::printf("\nRatio without / with friction compensation (whole run, last 20 s; paper Table III / Table I)\n");
    for (int i = 0; i < 6; ++i)
      std::printf("  %-12s %6.1fx %6.1fx   paper %4.1fx\n", kAxes[i], no->max_error[i] / ad->max_error[i],
                  no->final_max_error[i] / ad->final_max_error[i], sim::kPaperTable3[i] / sim::kPaperTable1[i]);
  }
  if (ad) {
    static const char* names[3] = {"tau_vis [N m s/rad]", "tau_cou [N m]", "tau_sti [N m]"};
    std::printf("\nIdentified friction coefficients after %.0f s (estimate / plant's true value; paper Table II is "
                "the plant's default)\n%-20s",
                ad->duration, "");
    for (int j = 0; j < 6; ++j) std::printf("      J%d       ", j + 1);
    std::printf("\n");
    for (int k = 0; k < 3; ++k) {
      std::printf("%-20s", names[k]);
      for (int j = 0; j < 6; ++j) std::printf(" %6.2f / %5.2f", ad->theta_hat[6 * k + j], ad->theta_true[6 * k + j]);
      std::printf("\n");
    }
    std::printf("estimated vs true joint friction over the last 20 s: rms error %.3f N m (rms friction %.3f N m)\n",
                ad->friction_rms_error, ad->friction_rms);
  }
  for (const auto& r : runs) print_windows(r);
  for (const auto& r : runs) {
    if (!r.error.empty()) std::printf("[%s] LINK ERROR: %s\n", r.mode.c_str(), r.error.c_str());
    if (r.max_step_cycles)
      std::printf("[%s] firmware control step (observer + controller + adaptation, float): max %u, mean %u "
                  "instructions (QEMU -icount shift=0); whole tick incl. link I/O max %u; stack used %u bytes\n",
                  r.mode.c_str(), r.max_step_cycles, r.mean_step_cycles, r.max_tick_cycles, r.stack_used);
    if (r.max_step_cycles) {
      std::printf("[%s] link: longest gap between received bytes %u cycles (ns of target time in QEMU), %u over %d periods; "
                  "errors counted by the firmware: %s; by the host: %s, codes out of range %u; ticks zeroed %u%s%s\n",
                  r.mode.c_str(), r.link.rx_gap_max, r.link.rx_long_gaps, osc::params::kLinkSilenceTicks,
                  counters_text(r.link.firmware).c_str(), counters_text(r.link.host).c_str(), r.link.host_code_range,
                  r.link.zeroed_ticks, r.link.first_zeroed.empty() ? "" : ", the first: ", r.link.first_zeroed.c_str());
    }
    std::printf("[%s] simulated %.0f s in %.2f s wall (%.3gx real time)\n", r.mode.c_str(), r.duration,
                r.wall_seconds, r.duration / r.wall_seconds);
    if (r.status) {
      std::printf("[%s] FAULT at t = %.3f s:", r.mode.c_str(), r.fault_time);
      for (int i = 0; i < osc::kFaultCount; ++i)
        if (r.status & (1u << i)) std::printf(" %s", osc::kFaultNames[i]);
      std::printf(" (latched; zero torque from that tick on)\n");
    }
    if (r.injection.injection.enabled) {
      const sim::InjectionResult& ir = r.injection;
      std::printf("[%s] injected %s: ", r.mode.c_str(), sim::to_string(ir.injection).c_str());
      if (ir.detected < 0) std::printf("never detected");
      else std::printf("detected after %.1f ms as %s", (ir.detected - ir.injection.at) * 1e3, osc::fault_name(ir.faults));
      if (ir.zero_torque < 0) std::printf(", torque never zero");
      else std::printf(", zero torque after %.1f ms", (ir.zero_torque - ir.injection.at) * 1e3);
      std::printf(", tip excursion %.2f mm, largest torque after detection %.2f N m\n", ir.excursion_mm,
                  ir.max_torque_after);
    }
  }
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\', out += c;
    else if (static_cast<unsigned char>(c) < 0x20) out += ' ';
    else out += c;
  }
  return out + "\"";
}

void json_array(std::ostream& os, const double* v, int n, double scale = 1) {
  os << "[";
  for (int i = 0; i < n; ++i) os << (i ? ", " : "") << v[i] * scale;
  os << "]";
}

/// A time in seconds, or null for "never" (negative).
std::string json_time(double t) {
  if (t < 0) return "null";
  std::ostringstream os;
  os.precision(9);
  os << t;
  return os.str();
}

/// The names of the fault bits, as a JSON array.
std::string json_faults(std::uint32_t bits) {
  std::string s = "[";
  for (int i = 0; i < osc::kFaultCount; ++i)
    if (bits & (1u << i)) s += (s.size() > 1 ? ", " : "") + json_string(osc::kFaultNames[i]);
  return s + "]";
}

void json_run(std::ostream& os, const sim::ExperimentResult& r, const char* indent) {
  os << indent << "\"mode\": \"" << r.mode << "\",\n";
  os << indent << "\"duration_s\": " << r.duration << ",\n";
  os << indent << "\"friction_preset\": \"" << r.friction_preset << "\",\n";
  os << indent << "\"adaptation\": \"" << r.adaptation << "\",\n";
  os << indent << "\"window_s\": " << r.window << ",\n";
  os << indent << "\"window_max_error\": [";
  for (size_t w = 0; w < r.window_max.size(); ++w) {
    os << (w ? ", " : "");
    json_array(os, r.window_max[w].data(), 6);
  }
  os << "],\n" << indent << "\"window_theta_range\": [";
  for (size_t w = 0; w < r.window_theta_range.size(); ++w) {
    os << (w ? ", " : "");
    json_array(os, r.window_theta_range[w].data(), 2);
  }
  os << "],\n" << indent << "\"theta_min_seen\": ";
  json_array(os, r.theta_min_seen, 18);
  os << ",\n" << indent << "\"theta_max_seen\": ";
  json_array(os, r.theta_max_seen, 18);
  os << ",\n" << indent << "\"final_window_s\": " << r.final_window << ",\n";
  os << indent << "\"max_error_mm\": ";
  json_array(os, r.max_error, 3);
  os << ",\n" << indent << "\"max_error_deg\": ";
  json_array(os, r.max_error + 3, 3);
  os << ",\n" << indent << "\"final20s_max_error_mm\": ";
  json_array(os, r.final_max_error, 3);
  os << ",\n" << indent << "\"final20s_max_error_deg\": ";
  json_array(os, r.final_max_error + 3, 3);
  os << ",\n" << indent << "\"theta_hat\": ";
  json_array(os, r.theta_hat, 18);
  os << ",\n" << indent << "\"theta_true\": ";
  json_array(os, r.theta_true, 18);
  os << ",\n" << indent << "\"friction_rms_error_Nm\": " << r.friction_rms_error;
  os << ",\n" << indent << "\"fault_status\": " << r.status;
  if (r.max_step_cycles) {
    os << ",\n" << indent << "\"firmware_step_instructions_max\": " << r.max_step_cycles;
    os << ",\n" << indent << "\"firmware_step_instructions_mean\": " << r.mean_step_cycles;
    os << ",\n" << indent << "\"firmware_tick_instructions_max\": " << r.max_tick_cycles;
    os << ",\n" << indent << "\"firmware_stack_used_bytes\": " << r.stack_used;
    os << ",\n" << indent << "\"link\": {";
    const pil::LinkCounters* sides[2] = {&r.link.firmware, &r.link.host};
    for (int s = 0; s < 2; ++s) {
      os << (s ? ", \"host\": {" : "\"firmware\": {");
      for (int k = 0; k < pil::kLinkErrorKinds; ++k)
        os << (k ? ", " : "") << "\"" << pil::kLinkErrorNames[k] << "\": " << sides[s]->count[k];
      if (s) os << ", \"code_range\": " << r.link.host_code_range;
      os << "}";
    }
    os << ", \"zeroed_ticks\": " << r.link.zeroed_ticks << ", \"rx_gap_max_instructions\": " << r.link.rx_gap_max
       << ", \"rx_long_gaps\": " << r.link.rx_long_gaps;
    if (!r.link.first_zeroed.empty()) os << ", \"first_zeroed\": " << json_string(r.link.first_zeroed);
    os << "}";
  }
  os << ",\n" << indent << "\"stuck_monitor_peak_counts\": ";
  json_array(os, r.stuck_peak, 6);
  os << ",\n" << indent << "\"stuck_monitor_peak_dtau_Nm\": ";
  json_array(os, r.stuck_dtau_peak, 6);
  os << ",\n" << indent << "\"faults\": " << json_faults(r.status);
  os << ",\n" << indent << "\"fault_time_s\": " << json_time(r.fault_time);
  if (r.injection.injection.enabled) {
    const sim::InjectionResult& ir = r.injection;
    const std::string in2 = std::string(indent) + "  ";
    os << ",\n" << indent << "\"injection\": {\n";
    os << in2 << "\"kind\": \"" << sim::info(ir.injection.kind).name << "\",\n";
    os << in2 << "\"joint\": " << (ir.injection.joint < 0 ? "null" : std::to_string(ir.injection.joint + 1)) << ",\n";
    os << in2 << "\"at_s\": " << ir.injection.at << ",\n";
    os << in2 << "\"detected_s\": " << json_time(ir.detected) << ",\n";
    os << in2 << "\"fault\": " << (ir.detected < 0 ? "null" : json_string(osc::fault_name(ir.faults))) << ",\n";
    os << in2 << "\"faults\": " << json_faults(ir.faults) << ",\n";
    os << in2 << "\"zero_torque_s\": " << json_time(ir.zero_torque) << ",\n";
    os << in2 << "\"excursion_mm\": " << ir.excursion_mm << ",\n";
    os << in2 << "\"max_torque_after_detection_Nm\": " << ir.max_torque_after << "\n";
    os << indent << "}";
  }
  if (!r.error.empty()) os << ",\n" << indent << "\"error\": " << json_string(r.error);
  os << ",\n" << indent << "\"wall_s\": " << r.wall_seconds << "\n";
}

/// Writes a temporary file beside path, then renames it: an existing file is never left
/// half-written, and nothing is left behind on failure.
bool write_atomically(const std::string& path, const std::string& text, std::string& err) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (f) f << text;
    f.close();
    if (!f) {
      std::remove(tmp.c_str());
      return err = "cannot write " + path, false;
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return err = "cannot write " + path + " (rename failed)", false;
  }
  return true;
}

/// Before the run: an output file can be created there (the file itself is written at the end).
bool check_writable(const std::string& path, std::string& err) {
  if (std::filesystem::is_directory(path)) return err = "cannot write " + path + ": it is a directory", false;
  const std::string tmp = path + ".tmp";
  std::ofstream f(tmp);
  const bool ok = static_cast<bool>(f);
  f.close();
  std::remove(tmp.c_str());
  if (!ok) return err = "cannot write " + path + " (does its directory exist and is it writable?)", false;
  return true;
}

/// The --qemu image must be a 32-bit little-endian ARM ELF file.
bool check_arm_elf(const std::string& path, std::string& err) {
  std::ifstream f(path, std::ios::binary);
  unsigned char h[20] = {};
  if (!f.read(reinterpret_cast<char*>(h), sizeof h))
    return err = "firmware image " + path + " is not an ELF file (too short or unreadable)", false;
  if (h[0] != 0x7F || h[1] != 'E' || h[2] != 'L' || h[3] != 'F')
    return err = "firmware image " + path + " is not an ELF file; pass the .elf the m4f build makes", false;
  if (h[4] != 1 || h[5] != 1 || (h[18] | (h[19] << 8)) != 40)
    return err = "firmware image " + path + " is not a 32-bit little-endian ARM ELF file", false;
  return true;
}

bool write_json(const std::string& path, const std::vector<sim::ExperimentResult>& runs, std::string& err) {
  std::ostringstream os;
  os.precision(9);
  os << "{\n";
  json_run(os, runs[0], "  ");  // the primary run (adaptive when it ran)
  os.seekp(-1, std::ios_base::end);
  os << ",\n  \"runs\": [\n";
  for (size_t i = 0; i < runs.size(); ++i) {
    os << "    {\n";
    json_run(os, runs[i], "      ");
    os << "    }" << (i + 1 < runs.size() ? "," : "") << "\n";
  }
  os << "  ]\n}\n";
  return write_atomically(path, os.str(), err);
}

bool write_csv(const std::string& dir, const sim::ExperimentResult& r, std::string& err) {
  const std::string path = dir + "/timeseries_" + r.mode + ".csv";
  std::ostringstream f;
  f << "t,e_x_mm,e_y_mm,e_z_mm,e_phx_deg,e_phy_deg,e_phz_deg,xt_x_mm,xt_y_mm,xt_z_mm,xt_phx_deg,xt_phy_deg,xt_phz_deg";
  // theta^ = [vis; cou; sti], six joints each (model (2)): named by coefficient and joint.
  static const char* const kCoeff[3] = {"vis", "cou", "sti"};
  for (int i = 0; i < 18; ++i) f << ",theta_hat_" << kCoeff[i / 6] << "_J" << i % 6 + 1;
  for (int i = 0; i < 6; ++i) f << ",tau_f_" << i;
  for (int i = 0; i < 6; ++i) f << ",tau_f_hat_" << i;
  f << "\n";
  for (const auto& row : r.log) {
    f << row.t;
    for (double v : row.e) f << "," << v;
    for (double v : row.x_tilde) f << "," << v;
    for (double v : row.theta_hat) f << "," << v;
    for (double v : row.tau_f) f << "," << v;
    for (double v : row.tau_f_hat) f << "," << v;
    f << "\n";
  }
  return write_atomically(path, f.str(), err);
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  std::string err;
  if (!sim::parse_experiment_args(argc, argv, o, err)) return fail(err);
  if (o.help) {
    std::cout << sim::kExperimentUsage;
    return 0;
  }
  o.base.duration = o.duration;
  if (o.qemu) {
    if (o.base.model_error != 0) return fail("--model-error applies to the host-built controller only, not with --qemu");
    if (o.base.encoder_counts_per_motor_rev != osc::robot::kDrives.encoder_counts_per_motor_rev)
      return fail("--encoder-cpr applies to the host-built controller only, not with --qemu");
    if (o.base.injection.enabled && !sim::info(o.base.injection.kind).per_joint)
      return fail(std::string("--inject ") + sim::info(o.base.injection.kind).name +
                  " applies to the host-built controller only, not with --qemu");
    if (access(o.elf.c_str(), R_OK) != 0)
      return fail("firmware image " + o.elf + " not found: build it with 'cmake --preset m4f && cmake --build --preset m4f'");
    if (!check_arm_elf(o.elf, err)) return fail(err);
    if (o.base.scalar == sim::Scalar::kDouble) o.base.scalar = sim::Scalar::kFloat;  // the firmware computes in float
    o.base.pil_command = sim::PilClient::qemu_command("qemu-system-arm", o.elf);
  }
  if (o.csv && !o.csv_dir.empty()) {
    // No shell: the name is a path, never a command.
    std::error_code ec;
    std::filesystem::create_directories(o.csv_dir, ec);
    if (ec || !std::filesystem::is_directory(o.csv_dir))
      return fail("cannot create directory " + o.csv_dir + (ec ? ": " + ec.message() : ""));
  }

  if (!o.json.empty() && !check_writable(o.json, err)) return fail(err);

  std::vector<sim::ExperimentConfig> cfgs;
  if (o.run_adaptive) cfgs.push_back(o.base), cfgs.back().mode = osc::FrictionMode::kAdaptive;
  if (o.run_none) cfgs.push_back(o.base), cfgs.back().mode = osc::FrictionMode::kNone;

  // Progress bar on a terminal only, for runs longer than a second.
  const bool bar = o.progress && isatty(STDERR_FILENO) && o.duration > 1.0;
  std::vector<std::atomic<double>> frac(cfgs.size());
  for (auto& f : frac) f = 0;
  for (size_t i = 0; i < cfgs.size(); ++i)
    if (bar) cfgs[i].progress = [&frac, i](double x) { frac[i] = x; };

  // The runs are independent: one thread each (the machine has two cores).
  std::vector<sim::ExperimentResult> runs(cfgs.size());
  std::vector<std::thread> threads;
  for (size_t i = 0; i < cfgs.size(); ++i)
    threads.emplace_back([&, i] { runs[i] = sim::run_experiment(cfgs[i]); });
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

  print_tables(runs);
  if (o.csv) {
    for (const auto& r : runs)
      if (!write_csv(o.csv_dir, r, err)) return fail(err);
    std::printf("time series: %s/timeseries_*.csv\n", o.csv_dir.c_str());
  }
  if (!o.json.empty()) {
    if (!write_json(o.json, runs, err)) return fail(err);
    std::printf("summary: %s\n", o.json.c_str());
  }
  // A fault is a failed run, unless a fault was injected on purpose (then the JSON tells how it went).
  for (const auto& r : runs)
    if ((r.status && !o.base.injection.enabled) || !r.error.empty() || !r.link.clean()) return 1;
  return 0;
}
