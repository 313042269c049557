#include "motion_script.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>

#include "client/stream_path.hpp"
#include "linked_arm.hpp"
#include "motion_sim.hpp"
#include "osc/link/command_port.hpp"

namespace sim {
namespace {

constexpr double kDegToRad = osc::kPi / 180.0;

/// The verb of a command name ("none" is no command a script can give).
bool verb_of(const std::string& name, osc::MotionVerb& v) {
  for (int i = 1; i < osc::MotionNames<osc::MotionVerb>::kCount; ++i)
    if (name == osc::MotionNames<osc::MotionVerb>::kNames[i]) return v = static_cast<osc::MotionVerb>(i), true;
  return false;
}

std::string verb_list() {
  std::string s;
  for (int i = 1; i < osc::MotionNames<osc::MotionVerb>::kCount; ++i)
    s += std::string(i > 1 ? " | " : "") + osc::MotionNames<osc::MotionVerb>::kNames[i];
  return s;
}

/// A finite number, or an error naming the key.
bool number(const YAML::Node& n, const std::string& key, double& out, std::string& err) {
  try {
    out = n.as<double>();
  } catch (const YAML::Exception&) {
    return err = key + ": not a number", false;
  }
  if (!std::isfinite(out)) return err = key + ": not a finite number", false;
  return true;
}

/// A list of three finite numbers.
bool triple(const YAML::Node& n, const std::string& key, osc::Vec3<double>& out, std::string& err) {
  if (!n.IsSequence() || n.size() != 3) return err = key + ": needs a list of three numbers", false;
  for (int i = 0; i < 3; ++i)
    if (!number(n[i], key + "[" + std::to_string(i) + "]", out(i), err)) return false;
  return true;
}

/// The keys of a step that apply to its command.
bool known_key(const std::string& k, osc::MotionVerb v) {
  if (k == "at" || k == "after" || k == "cmd" || k == "delay") return true;
  if (v == osc::MotionVerb::kDeclarePose) return k == "pose";
  if (v == osc::MotionVerb::kStream)
    return k == "file" || k == "rate_hz" || k == "relative" || k == "cut_s" || k == "velocity" || k == "v" ||
           k == "a" || k == "j";
  if (v != osc::MotionVerb::kMoveTo) return false;
  return k == "position" || k == "rpy_deg" || k == "relative" || k == "replace" || k == "v" || k == "a" || k == "j";
}

/// The options move_to and stream share: relative, and the linear limits v, a, j.
bool parse_options(const YAML::Node& n, const std::string& where, osc::MoveRequest<double>& m, std::string& err) {
  try {
    if (n["relative"]) m.relative = n["relative"].as<bool>();
    if (n["replace"]) m.replace = n["replace"].as<bool>();
  } catch (const YAML::Exception&) {
    return err = where + ": relative and replace take true or false", false;
  }
  m.limits = osc::CartesianLimits<double>::defaults();
  double* lim[3] = {&m.limits.linear.v, &m.limits.linear.a, &m.limits.linear.j};
  const char* names[3] = {"v", "a", "j"};
  for (int i = 0; i < 3; ++i)
    if (n[names[i]]) {
      if (!number(n[names[i]], where + "." + names[i], *lim[i], err)) return false;
      m.has_limits = true;
    }
  return true;
}

bool parse_move(const YAML::Node& n, const std::string& where, osc::MoveRequest<double>& m, std::string& err) {
  if (!n["position"]) return err = where + ".position: move_to needs a position [x, y, z] in metres", false;
  if (!triple(n["position"], where + ".position", m.position, err)) return false;
  if (n["rpy_deg"]) {
    if (!triple(n["rpy_deg"], where + ".rpy_deg", m.rpy, err)) return false;
    m.rpy *= kDegToRad;
    m.has_rpy = true;
  }
  return parse_options(n, where, m, err);
}

bool parse_stream(const YAML::Node& n, const std::string& where, const std::string& script_name, MotionStepSpec& s,
                  std::string& err) {
  if (!n["file"]) return err = where + ".file: stream needs a file (CSV of t, x, y, z[, roll, pitch, yaw])", false;
  if (!n["rate_hz"]) return err = where + ".rate_hz: stream needs a rate, 10 to 1000 Hz", false;
  double rate = 0;
  if (!number(n["rate_hz"], where + ".rate_hz", rate, err)) return false;
  if (!(rate >= 10 && rate <= 1000)) return err = where + ".rate_hz: 10 <= rate_hz <= 1000", false;
  const double period = osc::params::kControlHz / rate;
  s.move.period = static_cast<std::uint32_t>(std::lround(period));
  if (std::fabs(period - s.move.period) > 1e-9)
    return err = where + ".rate_hz: " + n["rate_hz"].as<std::string>("") +
                 " Hz is not a whole number of 1 ms ticks (1000, 500, 250, 100, 50, 20, 10, ...)",
           false;
  if (n["cut_s"]) {
    if (!number(n["cut_s"], where + ".cut_s", s.cut_s, err)) return false;
    if (s.cut_s < 0) return err = where + ".cut_s: a time from the stream's start, at least 0", false;
  }
  try {
    if (n["velocity"]) s.velocity = n["velocity"].as<bool>();
  } catch (const YAML::Exception&) {
    return err = where + ".velocity: takes true or false", false;
  }
  std::filesystem::path file = n["file"].as<std::string>("");
  if (file.is_relative()) file = std::filesystem::path(script_name).parent_path() / file;
  if (!read_stream_csv(file.string(), s.path, s.path_rpy, err)) return err = where + ".file: " + err, false;
  return parse_options(n, where, s.move, err);
}

/// declare_pose's pose: a name of the robot's named poses (osc::robot::kNamedPoses), its code in the
/// command frame's period field (the protocol's).
bool parse_pose(const YAML::Node& n, const std::string& where, MotionStepSpec& s, std::string& err) {
  std::string names;
  for (int i = 0; i < osc::robot::kNamedPoseCount; ++i)
    names += std::string(i ? " | " : "") + osc::robot::kNamedPoses[i].name;
  if (!n["pose"]) return err = where + ".pose: declare_pose needs a pose: " + names, false;
  const std::string name = n["pose"].as<std::string>("");
  const int code = osc::robot::named_pose_code(name);
  if (code >= 0) return s.move.period = static_cast<std::uint32_t>(code), true;
  return err = where + ".pose: '" + name + "' is not a named pose: " + names, false;
}

bool parse_step(const YAML::Node& n, const std::string& where, const std::string& script_name, MotionStepSpec& s,
                std::string& err) {
  if (!n.IsMap()) return err = where + ": a step is a map with cmd: and at: or after:", false;
  if (!n["cmd"]) return err = where + ".cmd: missing (" + verb_list() + ")", false;
  const std::string cmd = n["cmd"].as<std::string>("");
  if (!verb_of(cmd, s.verb)) return err = where + ".cmd: '" + cmd + "' is not a command: " + verb_list(), false;
  if (n["at"] && n["after"]) return err = where + ": at: and after: exclude each other", false;
  if (n["at"]) {
    if (!number(n["at"], where + ".at", s.at, err)) return false;
    if (s.at < 0) return err = where + ".at: a time from the start, at least 0", false;
  } else if (n["after"]) {
    const std::string a = n["after"].as<std::string>("");
    if (a != "done" && a != "answered") return err = where + ".after: '" + a + "' is not done | answered", false;
    (a == "done" ? s.after_done : s.after_answered) = true;
  } else {
    return err = where + ": needs at: SECONDS, or after: done | answered", false;
  }
  for (const auto& kv : n) {
    const std::string k = kv.first.as<std::string>("");
    if (!known_key(k, s.verb)) return err = where + "." + k + ": not a key of " + cmd, false;
  }
  if (n["delay"]) {
    if (!number(n["delay"], where + ".delay", s.delay, err)) return false;
    if (s.delay < 0 || s.delay > 86400) return err = where + ".delay: 0 <= delay <= 86400 s", false;
  }
  if (s.verb == osc::MotionVerb::kMoveTo && !parse_move(n, where, s.move, err)) return false;
  if (s.verb == osc::MotionVerb::kStream && !parse_stream(n, where, script_name, s, err)) return false;
  if (s.verb == osc::MotionVerb::kDeclarePose && !parse_pose(n, where, s, err)) return false;
  YAML::Emitter e;
  e << YAML::Flow << n;
  s.text = e.c_str();
  return true;
}

bool parse_top(const YAML::Node& root, MotionScript& script, std::string& err) {
  for (const auto& kv : root) {
    const std::string k = kv.first.as<std::string>("");
    if (k != "steps" && k != "start_pose" && k != "timeout" && k != "settle" && k != "inject")
      return err = k + ": not a key of a motion script (steps, start_pose, timeout, settle, inject)", false;
  }
  if (root["inject"]) {
    const YAML::Node n = root["inject"];
    if (!n.IsScalar()) return err = "inject: needs KIND[:ARGS]@SECONDS, as --inject takes it", false;
    // parse_injection's messages name --inject; here the key.
    if (!parse_injection(n.Scalar(), script.injection, err))
      return err = "inject: " + (err.rfind("--inject: ", 0) == 0 ? err.substr(10) : err), false;
  }
  if (root["timeout"] && !number(root["timeout"], "timeout", script.timeout, err)) return false;
  if (root["settle"] && !number(root["settle"], "settle", script.settle, err)) return false;
  if (!(script.timeout > 0 && script.timeout <= 86400)) return err = "timeout: 0 < timeout <= 86400 s", false;
  if (!(script.settle >= 0 && script.settle <= 3600)) return err = "settle: 0 <= settle <= 3600 s", false;
  if (root["start_pose"]) {
    const YAML::Node p = root["start_pose"];
    if (!p.IsSequence() || p.size() != 6) return err = "start_pose: needs six joint angles in degrees", false;
    Vec6 q;
    for (int i = 0; i < 6; ++i) {
      if (!number(p[i], "start_pose[" + std::to_string(i) + "]", q(i), err)) return false;
      q(i) *= kDegToRad;
      if (q(i) < osc::robot::kArm.q_min[i] || q(i) > osc::robot::kArm.q_max[i])
        return err = "start_pose[" + std::to_string(i) + "]: outside joint " + std::to_string(i + 1) + "'s limits",
               false;
    }
    script.start_pose = q;
  }
  return true;
}

}  // namespace

bool read_stream_csv(const std::string& path, std::vector<std::array<double, 7>>& rows, bool& has_rpy,
                     std::string& err) {
  std::ifstream in(path);
  if (!in) return err = path + ": cannot be read", false;
  rows.clear();
  int columns = 0;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const std::string where = path + ":" + std::to_string(n) + ": ";
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[line.find_first_not_of(" \t")] == '#') continue;
    std::vector<double> v;
    std::stringstream ss(line);
    std::string cell;
    bool numeric = true;
    while (std::getline(ss, cell, ',')) {
      char* end = nullptr;
      const double x = std::strtod(cell.c_str(), &end);
      if (end == cell.c_str() ||
          cell.find_first_not_of(" \t", static_cast<std::size_t>(end - cell.c_str())) != std::string::npos)
        numeric = false;
      v.push_back(x);
    }
    if (!numeric && rows.empty() && columns == 0) {  // the header
      columns = -1;
      continue;
    }
    if (!numeric) return err = where + "not a row of numbers", false;
    if (v.size() != 4 && v.size() != 7)
      return err = where + std::to_string(v.size()) + " columns: t, x, y, z[, roll, pitch, yaw] needs 4 or 7", false;
    if (columns > 0 && static_cast<int>(v.size()) != columns)
      return err = where + "every row needs the same columns (" + std::to_string(columns) + ")", false;
    columns = static_cast<int>(v.size());
    for (double x : v)
      if (!std::isfinite(x)) return err = where + "not a finite number", false;
    std::array<double, 7> r{};
    for (std::size_t i = 0; i < v.size(); ++i) r[i] = i >= 4 ? v[i] * kDegToRad : v[i];
    if (rows.empty() && r[0] != 0) return err = where + "the path's time starts at 0", false;
    if (!rows.empty() && !(r[0] > rows.back()[0])) return err = where + "t must increase from row to row", false;
    rows.push_back(r);
  }
  if (rows.empty()) return err = path + ": no rows (t, x, y, z[, roll, pitch, yaw])", false;
  has_rpy = columns == 7;
  return true;
}

bool parse_motion_script(const std::string& text, const std::string& name, MotionScript& script, std::string& err) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return err = name + ": not YAML: " + e.msg, false;
  }
  if (!root.IsMap() || !root["steps"] || !root["steps"].IsSequence() || root["steps"].size() == 0)
    return err = name + ": a motion script is a map with a non-empty list steps:", false;
  if (!parse_top(root, script, err)) return err = name + ": " + err, false;
  for (std::size_t i = 0; i < root["steps"].size(); ++i) {
    MotionStepSpec s;
    if (!parse_step(root["steps"][i], "steps[" + std::to_string(i) + "]", name, s, err))
      return err = name + ": " + err, false;
    script.steps.push_back(s);
  }
  return true;
}

namespace {

/// The controller in process: the firmware's control task over the simulated arm (MotionSim), its
/// commands through the command port (osc/link/command_port.hpp) as over a link, its answers read
/// back from the port's answer frames.
template <class S>
class HostArm {
 public:
  HostArm(const MotionScript& script, const ExperimentConfig& cfg)
      : sim_(script.start_pose.value_or(cfg.q_start), cfg.injection, cfg.plant, cfg.mode, cfg.gains,
             cfg.sensor_config(), cfg.power_on_pose) {
    configure_monitors(sim_.task(), cfg);
    port_.state_period = 0;
  }
  bool ok(std::string&) const { return true; }
  bool command(const pil::CommandFrame& f, std::string&) {
    port_.enqueue(sim_.task(), f, writer());
    port_.poll(sim_.task(), writer());
    return true;
  }
  template <class Frame>
  bool setpoint(const Frame& f, std::string&) {
    osc::offer_setpoint_frame(sim_.task(), f);
    return true;
  }
  bool tick(TickView& v, std::string&) {
    v.faults = sim_.tick();
    port_.after_tick_and_poll(sim_.task(), writer());
    v.reports.swap(reports_);
    reports_.clear();
    const osc::ControlTask<S>& t = sim_.task();
    v.state = t.machine.state;
    v.x_d = t.desired.x.template cast<double>();
    v.xd_d = t.desired.xd.template cast<double>();
    v.xdd_d = t.desired.xdd.template cast<double>();
    v.pose = sim_.pose();
    v.has_theta = true;
    for (int i = 0; i < 18; ++i) v.theta_hat[i] = static_cast<double>(t.state.adapt.theta_hat(i));
    return true;
  }
  void finish(MotionRun& run) {
    run.controller = "in-process";
    run.peak_contact_force = sim_.plant().peak_contact_force();
    run.first_contact_s = sim_.plant().first_contact_time();
    const osc::ResidualMonitor<S>& m = sim_.task().residual;
    run.has_residual = true;
    for (int i = 0; i < 6; ++i) {
      const double limit = static_cast<double>(m.travel_limit(i));
      run.residual_peak_ratio[i] = static_cast<double>(m.peak_ratio(i));
      run.residual_travel_ratio[i] = limit > 0 ? static_cast<double>(m.travel_peak(i)) / limit : 0;
    }
    if (m.detected != 0) {
      run.residual_fault = m.detected;
      run.residual_joint = static_cast<unsigned char>(m.joint);  // set: 0..5
      run.residual_detected_s = static_cast<double>(m.detected_tick) / osc::params::kControlHz;
    }
  }

 private:
  auto writer() {
    return [this](const std::uint8_t* b, int n) {
      for (int i = 0; i < n; ++i) {
        pil::AnswerFrame a;
        for (pil::Parser::Result r = parser_.feed(b[i]); r != pil::Parser::kPending; r = parser_.next())
          if (r == pil::Parser::kFrame && parser_.decode(a)) reports_.push_back(osc::report_from_frame(a));
      }
    };
  }
  MotionSim<S> sim_;
  osc::CommandPort<S> port_;
  pil::Parser parser_;
  std::vector<osc::MotionReport> reports_;
};

/// The controller of a PIL image over the link (linked_arm.hpp) as the player's: the script's start
/// pose, the link's health into the run.
class ScriptLinkedArm : public LinkedArm {
 public:
  ScriptLinkedArm(const MotionScript& script, const ExperimentConfig& cfg)
      : LinkedArm(script.start_pose.value_or(cfg.q_start), cfg), power_on_(cfg.power_on_pose.has_value()) {}
  bool ok(std::string& err) const {
    if (power_on_) return err = "plant.power_on_pose applies to the controller in process, not over the link", false;
    return LinkedArm::ok(err);
  }
  void finish(MotionRun& run) {
    run.controller = "pil";
    run.pil_command = program();
    run.link = link_report();
    run.peak_contact_force = plant().peak_contact_force();
    run.first_contact_s = plant().first_contact_time();
    stop();
  }

 private:
  bool power_on_;
};

/// The player: sends the steps in order as command frames (and a stream's setpoints as setpoint
/// frames) to a controller, in process or over the link (Arm: HostArm<S>, ScriptLinkedArm), and keeps each
/// command's record, the state log and the faults from what each tick shows (TickView).
template <class Arm>
class Player {
 public:
  Player(const MotionScript& script, const ExperimentConfig& cfg) : script_(script), arm_(script, cfg) {}

  MotionRun run() {
    const double dt = osc::params::kDt;
    double end_at = -1;
    std::string err;
    log_state(0);
    if (!arm_.ok(err)) return fail(0, err);
    for (long k = 0;; ++k) {
      const double t = k * dt;
      if (t > script_.timeout) return finish(t, "timeout");
      if (next_ < script_.steps.size() && due(t) && !send(t, err)) return fail(t, err);
      if (!stream_setpoint(k, err)) return fail(t, err);
      if (next_ == script_.steps.size() && end_at < 0 && at_rest() && idle()) end_at = t + script_.settle;
      if (end_at >= 0 && t >= end_at) return finish(t, "ok");
      was_powered_ = osc::motion_powered(state_);
      if (!arm_.tick(view_, err)) return fail(t, err);
      observe(t + dt);
      if (view_.faults != 0 && run_.fault_s < 0) run_.fault_s = t;
    }
  }

 private:
  bool at_rest() const { return !osc::motion_running(state_) && state_ != osc::MotionState::kStopping; }
  /// Every command sent has been answered (the controller's mailbox is free: it holds one command).
  bool idle() const { return run_.commands.empty() || run_.commands.back().answered_s >= 0; }
  /// The next step's time has come: its at: (or the moment its after: done held first) plus its delay.
  bool due(double t) {
    if (!idle()) return false;
    const MotionStepSpec& s = script_.steps[next_];
    if (ready_s_ < 0) {
      if (!s.after_done && !s.after_answered)
        ready_s_ = s.at;
      else if (s.after_answered || at_rest())
        ready_s_ = t;
    }
    return ready_s_ >= 0 && t >= ready_s_ + s.delay - 1e-9;
  }
  /// Sends the next step: its command as a frame (numbers as f32, the protocol's, in every backend).
  bool send(double t, std::string& err) {
    const MotionStepSpec& s = script_.steps[next_++];
    ready_s_ = -1;
    CommandRecord r;
    r.cmd = osc::motion_name(s.verb);
    r.step = s.text;
    r.id = static_cast<std::uint32_t>(run_.commands.size() + 1);
    r.sent_s = t;
    if (view_.has_theta) r.theta_at_sent.assign(view_.theta_hat, view_.theta_hat + 18);
    if (s.verb == osc::MotionVerb::kStream) stream_ = {&s, r.id, 0, -1};
    run_.commands.push_back(r);
    return arm_.command(osc::frame_from_command<double>(r.id, s.verb, s.move), err);
  }
  CommandRecord* record(std::uint32_t id) {
    return id >= 1 && id <= run_.commands.size() ? &run_.commands[id - 1] : nullptr;
  }
  void observe(double t);
  void observe(double t, const osc::MotionReport& rep);
  /// The running stream's setpoint due before tick k: the n-th, n periods after the tick the stream
  /// started in, at the path's time n T (linear between rows); the last, at the path's end, ends it.
  bool stream_setpoint(long k, std::string& err) {
    const MotionStepSpec* s = stream_.step;
    const CommandRecord* r = record(stream_.id);
    if (!s || !r || r->answered_s < 0) return true;
    if (!r->accepted || r->done_s >= 0 || r->aborted_s >= 0) return stream_ = {}, true;
    if (stream_.first_tick < 0) stream_.first_tick = k;  // the tick after the one that accepted it
    const long period = static_cast<long>(s->move.period);
    if ((k - stream_.first_tick) % period != 0) return true;
    const double t = static_cast<double>(stream_.sent) * period * osc::params::kDt;
    if (s->cut_s >= 0 && t > s->cut_s + 1e-9) return true;
    std::size_t i = 1;
    bool end = false;
    const osc::client::StreamPoint x = osc::client::path_at(s->path, t, i, end);
    const osc::Vec3<double>* rpy = s->path_rpy ? &x.rpy : nullptr;
    const std::uint32_t id = stream_.id;
    ++stream_.sent;
    if (end) stream_.step = nullptr;
    if (s->velocity)
      return arm_.setpoint(osc::setpoint_velocity_frame<double>(id, x.position, rpy, x.velocity, end), err);
    return arm_.setpoint(osc::setpoint_frame<double>(id, x.position, rpy, end), err);
  }
  void track();
  void log_state(double t) {
    const char* name = osc::motion_name(state_);
    if (run_.states.empty() || run_.states.back().state != name) run_.states.push_back({t, name});
  }
  MotionRun finish(double t, const char* result) {
    run_.duration_s = t;
    run_.result = run_.faults != 0 ? "faulted" : result;
    arm_.finish(run_);
    return run_;
  }
  /// The controller failed (it did not start, or its link was lost): the run ends there.
  MotionRun fail(double t, const std::string& err) {
    run_.error = err;
    finish(t, "error");
    run_.result = "error";
    return run_;
  }

  const MotionScript& script_;
  Arm arm_;
  TickView view_;
  MotionRun run_;
  osc::MotionState state_ = osc::MotionState::kDisabled;  // after the last tick
  std::size_t next_ = 0;
  double ready_s_ = -1;       // when the next step's condition held first (-1: not yet)
  bool was_powered_ = false;  // the torque was on before this tick (its step ran: a reference to track)
  osc::Vec3<double> w_prev_ = osc::Vec3<double>::Zero(), wd_prev_ = osc::Vec3<double>::Zero();
  osc::Vec3<double> a_prev_ = osc::Vec3<double>::Zero();
  bool have_prev_ = false;
  struct {
    const MotionStepSpec* step = nullptr;  // the stream being sent (null: none)
    std::uint32_t id = 0;
    long sent = 0;         // setpoints sent
    long first_tick = -1;  // the tick of its first setpoint
  } stream_;
};

/// The tick into the records: its answers, motions done or aborted, stops completed; the tracking.
template <class Arm>
void Player<Arm>::observe(double t) {
  state_ = view_.state;
  run_.faults |= view_.faults;
  for (const osc::MotionReport& rep : view_.reports) observe(t, rep);
  track();
  log_state(t);
}

/// One answer into the records.
template <class Arm>
void Player<Arm>::observe(double t, const osc::MotionReport& rep) {
  if (CommandRecord* r = rep.outcome != osc::CommandOutcome::kNone ? record(rep.id) : nullptr) {
    r->answered_s = t;
    r->accepted = rep.outcome == osc::CommandOutcome::kAccepted;
    if (!r->accepted) r->refused = osc::motion_name(rep.refusal), r->cause = rep.cause;
    const bool motion = rep.verb == osc::MotionVerb::kMoveTo || rep.verb == osc::MotionVerb::kPaper ||
                        rep.verb == osc::MotionVerb::kStream || rep.verb == osc::MotionVerb::kIdentify;
    r->running = r->accepted && motion;
    // Done at once unless it started a motion or a stop (a stop or disable from holding has nothing to stop).
    if (r->accepted && !motion && state_ != osc::MotionState::kStopping) r->done_s = t;
  }
  if (CommandRecord* r = record(rep.done_id)) r->done_s = t, r->running = false;
  // Aborted, or dropped from the queue (an answer of its own): every motion ends in one answer.
  if (CommandRecord* r = rep.abort != osc::MotionReason::kNone ? record(rep.aborted_id) : nullptr)
    r->aborted = osc::motion_name(rep.abort), r->aborted_s = t, r->running = false;
  if (rep.completion != osc::MotionCompletion::kNone)  // a stop or disable that reached rest
    for (CommandRecord& r : run_.commands)
      if (r.accepted && r.done_s < 0 && (r.cmd == "stop" || r.cmd == "disable")) r.done_s = t;
}

/// Tracking error and the reference's own maxima, into every command whose motion runs.
template <class Arm>
void Player<Arm>::track() {
  if (!was_powered_ || !osc::motion_powered(state_)) {
    have_prev_ = false;
    return;
  }
  const Vec6& x = view_.pose;
  const Vec6& xr = view_.x_d;
  const double e_mm = (xr.head<3>() - x.head<3>()).norm() * 1e3;
  const double e_deg = (xr.tail<3>() - x.tail<3>()).norm() / kDegToRad;
  const osc::Vec3<double> v = view_.xd_d.head<3>();
  const osc::Vec3<double> a = view_.xdd_d.head<3>();
  const Mat3 Einv = osc::angular_to_phi_rate<double>(xr.tail<3>());
  const osc::Vec3<double> w = Einv.inverse() * view_.xd_d.tail<3>();
  const double hz = osc::params::kControlHz;
  const double j = have_prev_ ? (a - a_prev_).norm() * hz : 0, wd = have_prev_ ? (w - w_prev_).norm() * hz : 0;
  a_prev_ = a, w_prev_ = w, have_prev_ = true;
  run_.max_error_mm = std::max(run_.max_error_mm, e_mm);
  run_.max_error_deg = std::max(run_.max_error_deg, e_deg);
  for (CommandRecord& r : run_.commands) {
    if (!r.running) continue;
    r.max_error_mm = std::max(r.max_error_mm, e_mm), r.max_error_deg = std::max(r.max_error_deg, e_deg);
    r.v = std::max(r.v, v.norm()), r.a = std::max(r.a, a.norm()), r.j = std::max(r.j, j);
    r.w = std::max(r.w, w.norm()), r.wd = std::max(r.wd, wd);
  }
}

}  // namespace

MotionRun run_motion_script(const MotionScript& script, const ExperimentConfig& cfg) {
  const auto wall0 = std::chrono::steady_clock::now();
  MotionRun run = !cfg.pil_command.empty()       ? Player<ScriptLinkedArm>(script, cfg).run()
                  : cfg.scalar == Scalar::kFloat ? Player<HostArm<float>>(script, cfg).run()
                  : cfg.scalar == Scalar::kFixed ? Player<HostArm<osc::Fixed>>(script, cfg).run()
                                                 : Player<HostArm<double>>(script, cfg).run();
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return run;
}

std::string motion_run_json(const MotionRun& run, const std::string& script_name, const ExperimentConfig& cfg) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["script"] = script_name;
  j["scalar"] = kScalarNames[static_cast<int>(cfg.scalar)];
  j["mode"] = mode_name(cfg.mode);
  j["result"] = run.result;
  j["duration_s"] = run.duration_s;
  j["max_error_mm"] = run.max_error_mm;
  j["max_error_deg"] = run.max_error_deg;
  ordered_json faults = ordered_json::array();
  for (int i = 0; i < osc::kFaultCount; ++i)
    if (run.faults & (1u << i)) faults.push_back(osc::kFaultNames[i]);
  j["faults"] = faults;
  j["fault_s"] = run.fault_s >= 0 ? ordered_json(run.fault_s) : ordered_json(nullptr);
  auto time_or_null = [](double t) { return t >= 0 ? ordered_json(t) : ordered_json(nullptr); };
  if (cfg.injection.enabled)
    j["injection"] = {{"spec", to_string(cfg.injection)},
                      {"peak_contact_force_N", run.peak_contact_force},
                      {"first_contact_s", time_or_null(run.first_contact_s)}};
  if (run.has_residual) {
    j["residual_monitor"] = {
        {"peak_ratio", json_array(run.residual_peak_ratio, 6)},
        {"travel_ratio", json_array(run.residual_travel_ratio, 6)},
        {"detection", residual_detection_json(run.residual_detected_s, run.residual_fault, run.residual_joint)}};
  }
  if (!run.error.empty()) j["error"] = run.error;
  auto name_or_null = [](const std::string& s) { return s.empty() ? ordered_json(nullptr) : ordered_json(s); };
  ordered_json cmds = ordered_json::array();
  for (const CommandRecord& r : run.commands)
    cmds.push_back({{"cmd", r.cmd},
                    {"step", r.step},
                    {"id", r.id},
                    {"sent_s", r.sent_s},
                    {"answered_s", time_or_null(r.answered_s)},
                    {"accepted", r.accepted},
                    {"refused", name_or_null(r.refused)},
                    {"done_s", time_or_null(r.done_s)},
                    {"aborted", name_or_null(r.aborted)},
                    {"aborted_s", time_or_null(r.aborted_s)},
                    {"max_error_mm", r.max_error_mm},
                    {"max_error_deg", r.max_error_deg},
                    {"reference_max", {{"v", r.v}, {"a", r.a}, {"j", r.j}, {"w", r.w}, {"wd", r.wd}}}});
  // In process, the friction estimates when each command was sent (a hold's or a repeated move's
  // effect on them: docs/adaptation.md).
  for (std::size_t k = 0; k < run.commands.size(); ++k)
    if (!run.commands[k].theta_at_sent.empty()) cmds[k]["theta_hat_at_sent"] = run.commands[k].theta_at_sent;
  j["commands"] = cmds;
  ordered_json states = ordered_json::array();
  for (const auto& s : run.states) states.push_back({{"t", s.t}, {"state", s.state}});
  j["states"] = states;
  j["limits"] = {{"v", osc::params::kMoveLinear[0]},   {"a", osc::params::kMoveLinear[1]},
                 {"j", osc::params::kMoveLinear[2]},   {"w", osc::params::kMoveAngular[0]},
                 {"wd", osc::params::kMoveAngular[1]}, {"wdd", osc::params::kMoveAngular[2]}};
  // How the run went, not what it did: the controller's kind and link, the wall-clock time (the
  // same script's JSON in process and over the link differ in these only).
  ordered_json ctl = {{"kind", run.controller}};
  if (run.controller == "pil") {
    ctl["command"] = run.pil_command;
    ctl["link"] = {{"clean", run.link.clean()},
                   {"zeroed_ticks", run.link.zeroed_ticks},
                   {"first_zeroed", run.link.first_zeroed},
                   {"firmware_errors", run.link.firmware.total()},
                   {"host_errors", run.link.host.total()},
                   {"rx_gap_max_cycles", run.link.rx_gap_max}};
  }
  j["controller"] = ctl;
  j["wall_s"] = run.wall_s;
  return j.dump(2) + "\n";
}

}  // namespace sim
