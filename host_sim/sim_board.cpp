// osc_sim --pty: the simulated PUMA 560 as a virtual board. The firmware's control task runs in
// process over the simulated arm (MotionSim, started disabled) in real time, one tick a millisecond
// (times --speed), paced by clock_nanosleep on absolute CLOCK_MONOTONIC deadlines, and serves the
// command protocol (docs/protocol.md, "The command protocol") on a pseudo-terminal through the
// controller's own end of it (osc/link/command_port.hpp): bytes read each tick into the link's
// parser (at most one setpoint a tick, as over a UART), command and setpoint frames into the task's
// mailboxes, answer frames and a state frame
// every 1 / --state-hz s back. Its first line on standard output is the terminal's path:
//
//   $ osc_sim --pty &
//   pty: /dev/pts/7
//   $ oscctl --port /dev/pts/7 enable
//
// As a board whose encoders are local, it stops a motion when the client's link is silent for
// params::kCommandLinkTimeout (link_silent; --no-link-watch turns that off), cuts a frame short after
// params::kFrameTimeout of silence within it and scans its bytes again (pil::Parser), and counts the
// link's errors into the state frames (field link). --inject KIND[:ARGS]@S injects a simulated
// hardware fault or contact (injection.hpp), so that a client's fault handling can be tested.
//
// In process it is a board that estimates: an identify run's samples are summed after each tick, and the run's
// estimate goes to the client as an identify frame when its motion ends (osc/link/identify_port.hpp). Its parameter
// store is in RAM unless --param-file FILE keeps it in a file, the image of two flash sectors as a board's flash
// holds them (file_flash.hpp, persist::FlashParamStore): a restarted simulator then applies the newest record at its
// start, as a board's boot does, and says so on stderr ("params loaded, sequence N", or "params defaults (why)").
//
// A tick that starts more than a period after its deadline is an overrun: the loop catches up
// without sleeping (at most kMaxCatchUpNs of wall time behind; further behind, the schedule
// restarts from now: a slip) and counts them; the counts are printed at exit. SIGINT and SIGTERM
// end the run cleanly (exit status 0); a bad option is a named error, exit status 2.
//
// With --qemu the controller is the PIL firmware image (boards/common/mps2/pil_firmware.cpp) in QEMU
// instead, in lockstep over the PIL link (linked_arm.hpp), the simulated arm still here, paced the
// same way (QEMU runs a tick faster than real time): the client's command and setpoint frames go
// over the link before the next tick's sensor frame, the image's answer and state frames (it sends
// one every osc::kStatePeriod ticks) come back to the terminal. Nothing else from the client goes on
// the link: its keep-alive state frames are dropped (counted with the frames that are not commands),
// as a host's state frame is a link error to the PIL node. A lost link ends the run (status 1).
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "cli_parse.hpp"
#include "config.hpp"          // apply_setting: --plant-set
#include "experiment_cli.hpp"  // qemu_takes
#include "file_flash.hpp"
#include "injection.hpp"
#include "linked_arm.hpp"
#include "motion_sim.hpp"
#include "osc/link/command_port.hpp"
#include "osc/link/identify_port.hpp"
#include "param_store.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_signal(int) { g_stop = 1; }

constexpr long kNsPerTick = 1'000'000;       // 1 ms: params::kControlHz
constexpr long kMaxCatchUpNs = 100'000'000;  // further behind than this: restart the schedule
constexpr std::size_t kOutputBytes = 8192;   // frames waiting for the terminal; more are dropped
static_assert(osc::params::kControlHz == 1000, "the virtual board's tick is 1 ms");

struct Options {
  bool pty = false;
  std::string scalar = "double";
  std::vector<double> start_pose;  // degrees
  int state_hz = 50;
  double duration = 0;  // simulated seconds; 0: until SIGINT / SIGTERM
  double speed = 1;
  bool qemu = false;
  std::string elf = OSC_DEFAULT_PIL_ELF;  // the image puma_experiment --qemu runs by default
  std::string inject;                     // KIND[:ARGS]@S (injection.hpp)
  bool no_link_watch = false;             // the command link's silence does not stop a motion
  std::string param_file;                 // the parameter store's image (empty: the store in RAM)
  std::vector<std::string> plant_sets;    // KEY=VALUE of the simulated arm's (config.hpp's plant.*)
};

/// The master side of a pseudo-terminal whose slave is in raw mode. Frames are written whole or not
/// at all (a full buffer drops the frame), and only while a client has the slave open: a frame no
/// one reads would reach the next client stale.
class PtyMaster {
 public:
  ~PtyMaster() {
    if (fd_ >= 0) close(fd_);
  }
  bool open(std::string& err) {
    fd_ = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (fd_ < 0) return err = std::string("posix_openpt: ") + std::strerror(errno), false;
    if (grantpt(fd_) != 0 || unlockpt(fd_) != 0)
      return err = std::string("grantpt/unlockpt: ") + std::strerror(errno), false;
    const char* name = ptsname(fd_);
    if (!name) return err = std::string("ptsname: ") + std::strerror(errno), false;
    slave_ = name;
    // Raw mode on the slave's side (no echo, no line editing, 8 bits); the setting stays with the
    // terminal once this descriptor is closed.
    const int s = ::open(name, O_RDWR | O_NOCTTY);
    if (s < 0) return err = slave_ + ": " + std::strerror(errno), false;
    termios t{};
    const bool ok = tcgetattr(s, &t) == 0 && (cfmakeraw(&t), tcsetattr(s, TCSANOW, &t) == 0);
    close(s);
    if (!ok) return err = slave_ + ": cannot set raw mode: " + std::strerror(errno), false;
    return true;
  }
  const std::string& slave() const { return slave_; }

  /// Whether a client has the slave open now. A new client starts with an empty output buffer.
  bool poll_client() {
    pollfd p{fd_, POLLIN, 0};
    const bool now = ::poll(&p, 1, 0) >= 0 && !(p.revents & POLLHUP);
    if (now && !connected_) out_.clear();
    connected_ = now;
    return now;
  }
  /// Bytes from the client (0: none, or no client).
  int read(std::uint8_t* buf, int n) {
    if (!connected_) return 0;
    const ssize_t r = ::read(fd_, buf, static_cast<std::size_t>(n));
    return r > 0 ? static_cast<int>(r) : 0;
  }
  /// A frame for the client: queued whole, or dropped (no client, or the buffer full). A state frame, which the
  /// next one supersedes, takes at most half the buffer: behind a client that fell behind, an answer or an identify
  /// run's report still finds room (state frames had filled it, and the report was lost).
  void queue(const std::uint8_t* b, int n) {
    const bool state = n > 2 && b[2] == pil::kStateFrame;
    if (!connected_ || out_.size() + static_cast<std::size_t>(n) > (state ? kOutputBytes / 2 : kOutputBytes)) {
      ++dropped_;
      return;
    }
    out_.insert(out_.end(), b, b + n);
  }
  /// Writes what the terminal takes now.
  void flush() {
    if (!connected_ || out_.empty()) return;
    const ssize_t w = ::write(fd_, out_.data(), out_.size());
    if (w > 0) out_.erase(out_.begin(), out_.begin() + w);
  }
  long dropped() const { return dropped_; }

 private:
  int fd_ = -1;
  std::string slave_;
  bool connected_ = false;
  std::vector<std::uint8_t> out_;
  long dropped_ = 0;
};

/// The real-time schedule: tick k's deadline is start + k period (restarted after a slip).
class Pacer {
 public:
  explicit Pacer(double speed) : period_(std::llround(static_cast<double>(kNsPerTick) / speed)) {
    clock_gettime(CLOCK_MONOTONIC, &start_);
  }
  /// Waits for the next tick's deadline (not at all when behind); false when a signal asked to stop.
  bool wait() {
    const long long due = ns(start_) + k_ * period_;
    const long long now = now_ns();
    if (now < due) {
      const timespec d{static_cast<time_t>(due / 1'000'000'000), static_cast<long>(due % 1'000'000'000)};
      while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &d, nullptr) == EINTR)
        if (g_stop) return false;
    } else {
      const long long lag = now - due;
      if (lag > period_) ++overruns;
      if (lag > worst_lag_ns) worst_lag_ns = lag;
      if (lag > kMaxCatchUpNs) {  // too far behind to catch up: simulated time lags wall time from here
        ++slips;
        clock_gettime(CLOCK_MONOTONIC, &start_);
        k_ = 0;
      }
    }
    ++k_;
    return !g_stop;
  }
  long overruns = 0, slips = 0;
  long long worst_lag_ns = 0;

 private:
  static long long ns(const timespec& t) { return static_cast<long long>(t.tv_sec) * 1'000'000'000 + t.tv_nsec; }
  static long long now_ns() {
    timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return ns(t);
  }
  long long period_;
  timespec start_{};
  long long k_ = 0;
};

double wall_seconds() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// The controller in process: the firmware's control task over the simulated arm (MotionSim), the
/// client's frames through its command port, and a board's command-link watch (CommandLinkWatch: a
/// motion running after params::kCommandLinkTimeout without a frame from the client is stopped,
/// link_silent), as on a board whose encoders are local; --no-link-watch turns it off.
template <class S>
class InProcessBoard {
 public:
  InProcessBoard(const sim::Vec6& q0, int state_hz, const sim::Injection& inj, bool link_watch, double speed,
                 const sim::PlantConfig& plant = {})
      : sim_(q0, inj, plant),
        watch_(static_cast<std::uint32_t>(std::lround(osc::CommandLinkWatch::kTimeoutTicks * std::max(1.0, speed)))),
        link_watch_(link_watch) {
    port_.state_period = static_cast<std::uint32_t>(osc::params::kControlHz / state_hz);
    port_.capture.attach(capture_ring_.data(), pil::kCaptureValues);  // a board's capture buffer
  }
  /// A complete frame from the client: a command or a setpoint is taken (true), any other type not.
  /// Any valid frame keeps the command link alive.
  template <class Write>
  bool on_frame(const pil::Parser& p, Write&& write) {
    watch_.heard();
    return port_.on_frame(sim_.task(), p, write);
  }
  /// One tick; its frames to write (an answer, an identify run's report, a state frame when due).
  template <class Write>
  bool tick(Write&& write, std::string&) {
    if (link_watch_) watch_.before_tick(sim_.task(), port_.commanded());
    sim_.tick();
    port_.after_tick_and_poll(sim_.task(), write);  // the tick's frames; the next command into the freed mailbox
    identify_.after_tick(sim_.task(), write);       // an identify run's samples; its report when its motion ends
    return true;
  }
  /// The parameter store in the file `path` (FileFlash), as a board's in its flash: its newest record applied now,
  /// as a board's boot applies it, and every save and load through it. The line that says what was applied (a
  /// board's boot line) into `said`. False with a named error when the file is not a store's image.
  bool open_store(const std::string& path, std::string& said, std::string& err) {
    if (!flash_.open(path, err)) return false;
    port_.set_param_storage(store_.storage());
    const persist::BootLoad b = store_.apply_to(sim_.task());
    const char* why = b.defaults_why();
    said = why ? std::string("defaults (") + why + ")" : "loaded, sequence " + std::to_string(b.load.sequence);
    return true;
  }
  /// The counters of the client's link that the state frames carry.
  pil::LinkCounters& link() { return port_.link; }
  bool report() const {
    std::fprintf(stderr,
                 "osc_sim: command link watch %s (%u ticks): %u link_silent stop requests; %u resent commands\n",
                 link_watch_ ? "on" : "off (--no-link-watch)", watch_.timeout_ticks(), watch_.stops(), port_.resends);
    return true;
  }

 private:
  sim::MotionSim<S> sim_;
  osc::CommandPort<S> port_;
  std::vector<float> capture_ring_ = std::vector<float>(pil::kCaptureValues);
  osc::IdentifyPort<S> identify_;
  osc::CommandLinkWatch watch_;
  bool link_watch_;
  sim::FileFlash flash_{persist::kImageSectorWords};
  persist::NoWatchdog no_watchdog_;
  persist::FlashParamStore<sim::FileFlash, persist::NoWatchdog> store_{flash_, no_watchdog_};
};

/// The controller of a PIL image in QEMU over the link, the simulated arm here (linked_arm.hpp): the
/// client's command, setpoint, param and capture frames onto the link before the next tick's sensor frame, the
/// image's answer, state, param_answer and capture_data frames of each tick back, and its identify and
/// identify_offset frames (and identify_payload frame) when a run ends. No other frame goes on the link.
class QemuBoard {
 public:
  QemuBoard(const sim::ExperimentConfig& cfg, const std::string& elf)
      : arm_(cfg.q_start, cfg, pil::kConfigStateFrames), elf_(elf) {}
  bool ok(std::string& err) const { return arm_.ok(err); }
  template <class Write>
  bool on_frame(const pil::Parser& p, Write&&) {
    pil::CommandFrame c;
    pil::SetpointFrame s;
    pil::SetpointVelocityFrame sv;
    if (p.decode(c)) {
      if (err_.empty()) arm_.command(c, err_);
      return true;
    }
    if (p.decode(s)) {
      if (err_.empty()) arm_.setpoint(s, err_);
      return true;
    }
    if (p.decode(sv)) {
      if (err_.empty()) arm_.setpoint(sv, err_);
      return true;
    }
    pil::ParamFrame pf;
    if (p.decode(pf)) {
      if (err_.empty()) arm_.param(pf, err_);
      return true;
    }
    pil::CaptureFrame cf;
    if (p.decode(cf)) {
      if (err_.empty()) arm_.capture(cf, err_);
      return true;
    }
    return false;  // a keep-alive (a state frame) or a frame no controller takes: dropped
  }
  template <class Write>
  bool tick(Write&& write, std::string& err) {
    if (!err_.empty()) return err = err_, false;
    if (!arm_.tick(view_, err)) return false;
    std::uint8_t buf[pil::kMaxFrame];
    for (const pil::AnswerFrame& f : arm_.replies().answers) write(buf, pil::encode(f, buf));
    for (pil::StateFrame f : arm_.replies().states) {
      f.link = link_;  // the client's link (this terminal's), not the image's PIL link
      write(buf, pil::encode(f, buf));
    }
    for (const pil::ParamAnswerFrame& f : arm_.replies().params) write(buf, pil::encode(f, buf));
    for (const pil::CaptureDataFrame& f : arm_.replies().captures) write(buf, pil::encode(f, buf));
    for (const pil::IdentifyFrame& f : arm_.replies().identifies) write(buf, pil::encode(f, buf));
    for (const pil::IdentifyOffsetFrame& f : arm_.replies().identify_offsets) write(buf, pil::encode(f, buf));
    for (const pil::IdentifyPayloadFrame& f : arm_.replies().identify_payloads) write(buf, pil::encode(f, buf));
    return true;
  }
  /// The counters of the client's link that the state frames carry.
  pil::LinkCounters& link() { return link_; }
  /// The link's health on stderr; whether it was clean.
  bool report() const {
    const sim::LinkReport r = arm_.link_report();
    std::fprintf(stderr,
                 "osc_sim: firmware image %s: link %s: %u errors counted by the firmware, %u by the host, %u "
                 "out-of-range answers, %u zeroed ticks%s%s\n",
                 elf_.c_str(), r.clean() ? "clean" : "not clean", r.firmware.total(), r.host.total(), r.host_code_range,
                 r.zeroed_ticks, r.first_zeroed.empty() ? "" : "; the first: ", r.first_zeroed.c_str());
    return r.clean();
  }

 private:
  sim::LinkedArm arm_;
  std::string elf_;
  std::string err_;  // a command or setpoint that could not be sent: the link is gone
  sim::TickView view_;
  pil::LinkCounters link_;
};

/// Runs the board until the duration or a signal; prints the run's counts on stderr. Status 0, or 1
/// when the controller failed (its link lost) before a signal asked to stop.
template <class Board>
int serve(const Options& o, Board& board, PtyMaster& pty) {
  pil::Parser parser;
  const long long ticks = o.duration > 0 ? std::llround(o.duration * osc::params::kControlHz) : -1;
  const auto write = [&pty](const std::uint8_t* b, int n) { pty.queue(b, n); };
  Pacer pacer(o.speed);
  long long k = 0;
  long frames = 0, other_frames = 0, link_errors = 0;
  bool had_client = false;
  std::string err;
  const double t0 = wall_seconds();
  double last_rx = t0;           // wall time of the last byte received
  std::vector<std::uint8_t> rx;  // bytes received and not yet parsed: those after a tick's setpoint
  std::size_t rx_at = 0;
  for (; ticks < 0 || k < ticks; ++k) {
    if (!pacer.wait()) break;
    const bool client = pty.poll_client();
    if (client && !had_client) {  // a new client: no half frame of the last one's, nor its bytes held
      parser.reset();
      rx.clear();
      rx_at = 0;
    }
    had_client = client;
    // Every event of the bytes received: frames to the board, errors counted for the client; true
    // when a setpoint was among the frames.
    const auto take = [&](pil::Parser::Result r) {
      bool setpoint = false;
      for (; r != pil::Parser::kPending; r = parser.next()) {
        if (r == pil::Parser::kFrame) {
          ++frames;
          setpoint |= parser.type() == pil::kSetpointFrame || parser.type() == pil::kSetpointVelocityFrame;
          if (!board.on_frame(parser, write)) ++other_frames;
        } else {
          ++link_errors;
          board.link()[pil::Parser::error_of(r)] +=
              r == pil::Parser::kJunk ? static_cast<std::uint32_t>(parser.junk()) : 1u;
        }
      }
      return setpoint;
    };
    std::uint8_t buf[512];
    const double now = wall_seconds();
    for (int n; (n = pty.read(buf, sizeof buf)) > 0;) rx.insert(rx.end(), buf, buf + n);
    // At most one setpoint a tick, the bytes after it the next tick's: a UART delivers a setpoint
    // frame in more than a tick (115 200 baud), so a board never takes two in one tick. Without
    // this, a simulator that the host's scheduler held back for a stream's period and that then
    // catches up would find two setpoints waiting, and the newer would replace the older untaken
    // (counted dropped: docs/protocol.md), which the board it stands for would not do.
    if (rx_at < rx.size()) last_rx = now;
    while (rx_at < rx.size())
      if (take(parser.feed(rx[rx_at++]))) break;
    if (rx_at == rx.size()) rx.clear(), rx_at = 0;
    // A frame begun and silent for the in-frame timeout (wall time): cut short, its bytes scanned again.
    if (parser.in_frame() && now - last_rx >= osc::params::kFrameTimeout) take(parser.expire());
    if (!board.tick(write, err)) break;
    pty.flush();
  }
  const double wall = wall_seconds() - t0;
  std::fprintf(stderr,
               "osc_sim: %lld ticks (%.3f s simulated) in %.3f s of wall time; %ld frames in, %ld not commands "
               "(keep-alives among them: dropped), %ld link errors; %ld frames out dropped (no client, or not read)\n",
               k, static_cast<double>(k) / osc::params::kControlHz, wall, frames, other_frames, link_errors,
               pty.dropped());
  std::fprintf(stderr,
               "osc_sim: %s%ld overruns (ticks started more than a period late), %ld slips, worst lag %.3f ms\n",
               pacer.overruns > 0 ? "warning: " : "", pacer.overruns, pacer.slips,
               static_cast<double>(pacer.worst_lag_ns) * 1e-6);
  board.report();
  if (err.empty() || g_stop) return 0;
  std::fprintf(stderr, "osc_sim: the controller failed: %s\n", err.c_str());
  return 1;
}

/// The start pose [rad]: the robot's, or --start-pose within the joint limits and away from a
/// singularity (the controller's threshold doubled, as puma_experiment's start_pose).
bool start_pose(const Options& o, sim::Vec6& q, std::string& err) {
  for (int i = 0; i < osc::kDof; ++i) q(i) = osc::robot::kQStart[i];
  if (o.start_pose.empty()) return true;
  for (int i = 0; i < osc::kDof; ++i) {
    q(i) = o.start_pose[static_cast<std::size_t>(i)] * osc::kPi / 180.0;
    if (!(q(i) >= osc::robot::kArm.q_min[i] && q(i) <= osc::robot::kArm.q_max[i]))
      return err = "--start-pose: joint " + std::to_string(i + 1) + " outside its limits", false;
  }
  const osc::Model<double> model = osc::Model<double>::of(osc::robot::kArm);
  osc::Data<double> data;
  osc::ArmOpSpace<double> os;
  osc::forward_kinematics(model, data, q);
  const sim::Mat3 R = data.R[osc::kDof];
  osc::opspace_update(model, data, os, q, R);
  if (!(os.Jf.rcond >= 2 * osc::Gains<double>::paper().min_rcond))
    return err = "--start-pose: too close to a singularity for the controller", false;
  return true;
}

void build(CLI::App& app, Options& o) {
  app.description(
      "The simulated " + std::string(osc::robot::kArm.name) +
      " as a virtual board: the firmware's control task over the simulated arm, in real "
      "time, serving the command protocol (docs/protocol.md) on a pseudo-terminal whose path is the first line "
      "on standard output (\"pty: /dev/pts/N\"). The arm starts disabled. SIGINT or SIGTERM ends it (status 0). "
      "The controller runs in process, or with --qemu as the PIL firmware image in QEMU over the PIL link "
      "(the arm simulated here, the frames relayed).");
  app.set_help_flag("-h,--help", "this text");
  app.option_defaults()->disable_flag_override()->multi_option_policy(CLI::MultiOptionPolicy::Throw);
  app.add_flag("--pty", o.pty, "serve the command protocol on a new pseudo-terminal (required)");
  app.add_option("--scalar", o.scalar,
                 "the controller's arithmetic: double | float | fixed (default double; with --qemu the image's, "
                 "which it must match: float on the M4F, fixed on the M3)")
      ->check(CLI::IsMember({"double", "float", "fixed"}));
  app.add_option("--start-pose", o.start_pose,
                 "joint angles q1..q6 at the start [deg] (default: the robot's; not with --qemu)")
      ->expected(6)
      ->type_name("Q1 .. Q6");
  app.add_option("--state-hz", o.state_hz,
                 "state frames per simulated second: 1000 / N for a whole N (default 50; with --qemu the "
                 "image's 50 only)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--duration", o.duration, "stop after this many simulated seconds (default: run until a signal)")
      ->check(CLI::Range(0.001, 1e6));
  app.add_option("--speed", o.speed,
                 "real-time factor: simulated seconds per wall second (default 1; above 1 for faster runs, "
                 "e.g. in tests)")
      ->check(CLI::Range(0.01, 100.0));
  app.add_flag("--qemu", o.qemu,
               "the controller is the PIL firmware image in qemu-system-arm (lockstep over its link, the "
               "semihosting console), the arm simulated here; a lost link ends the run (status 1)");
  app.add_option("--elf", o.elf, "the firmware image for --qemu (default: the m4f build's pil_firmware.elf)")
      ->type_name("FILE");
  app.add_option("--inject", o.inject,
                 sim::inject_help() +
                     "; S counts simulated seconds from the start (a way to test a client's fault "
                     "handling; with --qemu the kinds the image's link carries)")
      ->type_name("KIND[:ARGS]@S");
  app.add_option("--param-file", o.param_file,
                 "the board's parameter store, kept in FILE as a flash image of two sectors (created erased when "
                 "missing): at the start its newest record is applied, as a board's boot does (stderr: \"params "
                 "loaded, sequence N\" or \"params defaults (why)\"), and param save and load go to it. Without it "
                 "the store is in RAM, lost at exit. With --qemu the image keeps its store there (through "
                 "semihosting) and applies it at its start; the file is the same image either way")
      ->type_name("FILE");
  app.add_flag("--no-link-watch", o.no_link_watch,
               "a motion goes on when the client's link is silent (by default, as on a board whose encoders are "
               "local, a motion running 0.5 s without a frame from the client is stopped: link_silent; 0.5 s of the "
               "client's time, the wall clock's: 0.5 s times --speed of simulated time when above 1); in process "
               "only: with --qemu the image's link is the PIL link, and no command-link watch runs");
  app.add_option("--plant-set", o.plant_sets,
                 "set one of the simulated arm's keys, as puma_experiment --plant-set (its --print-config lists "
                 "plant.*), e.g. --plant-set payload_mass=1.5 for a payload the controller's model is not told "
                 "(param set payload_mass, or identify --payload --apply, tells it); repeatable; in process and "
                 "with --qemu alike (the arm is simulated here)")
      ->type_name("KEY=VALUE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
}

/// --param-file with --qemu: the file checked (an image of the store, or created erased: FileFlash::open) and named
/// on the image's semihosting command line ("params=PATH", absolute: boards/common/mps2/semihost_flash.hpp), where
/// the image keeps its store. QEMU's option list takes no comma in a value, the image's line no space.
bool image_param_file(const std::string& file, std::vector<std::string>& qemu, std::string& err) {
  {
    sim::FileFlash check(persist::kImageSectorWords);
    if (!check.open(file, err)) return err = "--param-file: " + err, false;
  }
  char* real = realpath(file.c_str(), nullptr);
  const std::string path = real ? real : file;
  std::free(real);
  if (path.find_first_of(", ") != std::string::npos)
    return err = "--param-file " + path + ": a path with a comma or a space cannot go on QEMU's command line", false;
  for (std::size_t i = 0; i + 1 < qemu.size(); ++i)
    if (qemu[i] == "-semihosting-config") {
      qemu[i + 1] += ",arg=params=" + path;
      return true;
    }
  return err = "--param-file: the image's QEMU command line has no semihosting configuration", false;
}

/// The options that the in-process controller and the image constrain differently; err on the first
/// bad one. With --qemu: the image's command line and scalar into cfg.
bool check_options(const CLI::App& app, Options& o, sim::ExperimentConfig& cfg, std::string& err) {
  if (!o.pty) return err = "--pty is required: the pseudo-terminal is the virtual board (in process, or --qemu)", false;
  if (osc::params::kControlHz % o.state_hz != 0)
    return err = "--state-hz " + std::to_string(o.state_hz) +
                 ": not 1000 / N for a whole N (1000, 500, 250, 200, 100, 50, ...)",
           false;
  if (!o.inject.empty() || app.count("--inject") > 0)
    if (!sim::parse_injection(o.inject, cfg.injection, err)) return err = "--inject: " + err, false;
  sim::Settings plant;  // the simulated arm's keys, checked by the configuration's table
  for (const std::string& a : o.plant_sets)
    if (!sim::apply_setting("plant." + a, plant, err)) return err = "--plant-set: " + err, false;
  if (!sim::validate_settings(plant, err)) return err = "--plant-set: " + err, false;
  cfg.plant = plant.base.plant;
  if (!o.qemu) {
    if (app.count("--elf") > 0) return err = "--elf applies with --qemu only", false;
    return start_pose(o, cfg.q_start, err);
  }
  if (o.no_link_watch)
    return err = "--no-link-watch applies in process only: with --qemu no command-link watch runs", false;
  if (!sim::qemu_takes(cfg.injection, "--inject", err)) return false;
  constexpr int kImageStateHz = static_cast<int>(osc::params::kControlHz / osc::kStatePeriod);
  if (o.state_hz != kImageStateHz)
    return err = "--state-hz " + std::to_string(o.state_hz) + ": the firmware image sends " +
                 std::to_string(kImageStateHz) + " state frames a second (not with --qemu)",
           false;
  if (!o.start_pose.empty())
    return err = "--start-pose: the firmware image starts at the robot's start pose (not with --qemu)", false;
  if (o.elf.empty()) return err = "--elf needs a file name", false;
  sim::Scalar image = sim::Scalar::kFloat;
  if (!sim::pil_image(o.elf, sim::PilLink::kSemihosting, cfg.pil_command, image, err)) return false;
  const char* name = sim::kScalarNames[static_cast<int>(image)];
  if (app.count("--scalar") > 0 && o.scalar != name)
    return err = "--scalar " + o.scalar + ": the image " + o.elf + " computes in " + name, false;
  o.scalar = name;
  cfg.scalar = image;
  return o.param_file.empty() || image_param_file(o.param_file, cfg.pil_command, err);
}

/// Opens the terminal, prints its path and serves it with the board until the end.
template <class Board>
int run(const Options& o, Board& board) {
  PtyMaster pty;
  std::string err;
  if (!pty.open(err)) {
    std::fprintf(stderr, "osc_sim: %s\n", err.c_str());
    return 1;
  }
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::printf("pty: %s\n", pty.slave().c_str());
  std::fflush(stdout);
  return serve(o, board, pty);
}

template <class S>
int run_in_process(const Options& o, const sim::ExperimentConfig& cfg) {
  InProcessBoard<S> board(cfg.q_start, o.state_hz, cfg.injection, !o.no_link_watch, o.speed, cfg.plant);
  if (!o.param_file.empty()) {
    std::string said, err;
    if (!board.open_store(o.param_file, said, err)) {
      std::fprintf(stderr, "osc_sim: --param-file: %s\n", err.c_str());
      return 2;
    }
    std::fprintf(stderr, "osc_sim: params %s (%s)\n", said.c_str(), o.param_file.c_str());
  }
  return run(o, board);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("", "osc_sim");
  Options o;
  build(app, o);
  if (const int status = sim::parse_command_line(app, argc, argv, "osc_sim"); status >= 0) return status;
  std::string err;
  sim::ExperimentConfig cfg;
  if (!check_options(app, o, cfg, err)) {
    std::fprintf(stderr, "osc_sim: %s\n", err.c_str());
    return 2;
  }
  if (o.qemu) {
    if (!o.param_file.empty())
      std::fprintf(stderr, "osc_sim: params in %s: the image applies its newest record at its start\n",
                   o.param_file.c_str());
    QemuBoard board(cfg, o.elf);  // the image started, its hello received, before the terminal opens
    if (!board.ok(err)) {
      std::fprintf(stderr, "osc_sim: the firmware image %s did not start: %s\n", o.elf.c_str(), err.c_str());
      return 1;
    }
    return run(o, board);
  }
  if (o.scalar == "float") return run_in_process<float>(o, cfg);
  if (o.scalar == "fixed") return run_in_process<osc::Fixed>(o, cfg);
  return run_in_process<double>(o, cfg);
}
