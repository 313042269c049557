#include "motion_script.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>

#include "motion_sim.hpp"

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
  if (v == osc::MotionVerb::kStream)
    return k == "file" || k == "rate_hz" || k == "relative" || k == "cut_s" || k == "v" || k == "a" || k == "j";
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
  std::filesystem::path file = n["file"].as<std::string>("");
  if (file.is_relative()) file = std::filesystem::path(script_name).parent_path() / file;
  if (!read_stream_csv(file.string(), s.path, s.path_rpy, err)) return err = where + ".file: " + err, false;
  return parse_options(n, where, s.move, err);
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
  YAML::Emitter e;
  e << YAML::Flow << n;
  s.text = e.c_str();
  return true;
}

bool parse_top(const YAML::Node& root, MotionScript& script, std::string& err) {
  for (const auto& kv : root) {
    const std::string k = kv.first.as<std::string>("");
    if (k != "steps" && k != "start_pose" && k != "timeout" && k != "settle")
      return err = k + ": not a key of a motion script (steps, start_pose, timeout, settle)", false;
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

/// The player: sends the steps in order, keeps each command's record, the state log and the faults.
template <class S>
class Player {
 public:
  Player(const MotionScript& script, const ExperimentConfig& cfg)
      : script_(script), sim_(script.start_pose.value_or(cfg.q_start), cfg.injection, cfg.plant, cfg.mode, cfg.gains) {}

  MotionRun run() {
    const double dt = osc::params::kDt;
    double end_at = -1;
    log_state(0);
    for (long k = 0;; ++k) {
      const double t = k * dt;
      if (t > script_.timeout) return finish(t, "timeout");
      if (next_ < script_.steps.size() && due(t)) send(t);
      stream_setpoint(k);
      if (next_ == script_.steps.size() && end_at < 0 && at_rest() && sim_.idle()) end_at = t + script_.settle;
      if (end_at >= 0 && t >= end_at) return finish(t, "ok");
      was_powered_ = osc::motion_powered(sim_.task().machine.state);
      const std::uint32_t f = sim_.tick();
      observe(t + dt, f);
      if (f != 0 && run_.fault_s < 0) run_.fault_s = t;
    }
  }

 private:
  bool at_rest() const {
    const osc::MotionState s = sim_.task().machine.state;
    return s != osc::MotionState::kMoving && s != osc::MotionState::kStopping;
  }
  /// The next step's time has come: its at: (or the moment its after: done held first) plus its delay.
  bool due(double t) {
    if (!sim_.idle()) return false;
    const MotionStepSpec& s = script_.steps[next_];
    if (ready_s_ < 0) {
      const bool answered = run_.commands.empty() || run_.commands.back().answered_s >= 0;
      if (!s.after_done && !s.after_answered)
        ready_s_ = s.at;
      else if (answered && (s.after_answered || at_rest()))
        ready_s_ = t;
    }
    return ready_s_ >= 0 && t >= ready_s_ + s.delay - 1e-9;
  }
  void send(double t) {
    const MotionStepSpec& s = script_.steps[next_++];
    ready_s_ = -1;
    CommandRecord r;
    r.cmd = osc::motion_name(s.verb);
    r.step = s.text;
    r.id = static_cast<std::uint32_t>(run_.commands.size() + 1);
    r.sent_s = t;
    if (s.verb == osc::MotionVerb::kMoveTo) {
      sim_.move_to(cast_request(s.move), r.id);
    } else if (s.verb == osc::MotionVerb::kStream) {
      sim_.stream(cast_request(s.move), r.id);
      stream_ = {&s, r.id, 0, -1};
    } else
      sim_.command(s.verb, r.id);
    run_.commands.push_back(r);
  }
  static osc::MoveRequest<S> cast_request(const osc::MoveRequest<double>& m) {
    osc::MoveRequest<S> r;
    r.position = m.position.cast<S>();
    r.rpy = m.rpy.cast<S>();
    r.relative = m.relative, r.has_rpy = m.has_rpy, r.replace = m.replace, r.has_limits = m.has_limits;
    r.period = m.period;
    r.limits = {
        {static_cast<S>(m.limits.linear.v), static_cast<S>(m.limits.linear.a), static_cast<S>(m.limits.linear.j)},
        {static_cast<S>(m.limits.angular.v), static_cast<S>(m.limits.angular.a), static_cast<S>(m.limits.angular.j)}};
    return r;
  }
  CommandRecord* record(std::uint32_t id) {
    return id >= 1 && id <= run_.commands.size() ? &run_.commands[id - 1] : nullptr;
  }
  void observe(double t, std::uint32_t faults);
  /// The running stream's setpoint due before tick k: the n-th, n periods after the tick the stream
  /// started in, at the path's time n T (linear between rows); the last, at the path's end, ends it.
  void stream_setpoint(long k) {
    const MotionStepSpec* s = stream_.step;
    const CommandRecord* r = record(stream_.id);
    if (!s || !r || r->answered_s < 0) return;
    if (!r->accepted || r->done_s >= 0 || r->aborted_s >= 0) return void(stream_ = {});
    if (stream_.first_tick < 0) stream_.first_tick = k;  // the tick after the one that accepted it
    const long period = static_cast<long>(s->move.period);
    if ((k - stream_.first_tick) % period != 0) return;
    const double t = static_cast<double>(stream_.sent) * period * osc::params::kDt;
    if (s->cut_s >= 0 && t > s->cut_s + 1e-9) return;
    const std::vector<std::array<double, 7>>& p = s->path;
    const bool end = t >= p.back()[0] - 1e-9;
    std::size_t i = 1;
    while (i < p.size() && p[i][0] < t) ++i;
    std::array<double, 7> x = p.back();
    if (!end) {
      const double f = (t - p[i - 1][0]) / (p[i][0] - p[i - 1][0]);
      for (int c = 1; c < 7; ++c) x[c] = p[i - 1][c] + f * (p[i][c] - p[i - 1][c]);
    }
    const Vec3 pos(x[1], x[2], x[3]), rpy(x[4], x[5], x[6]);
    sim_.setpoint(stream_.id, pos, s->path_rpy ? &rpy : nullptr, end);
    ++stream_.sent;
    if (end) stream_.step = nullptr;
  }
  void track();
  void log_state(double t) {
    const char* name = osc::motion_name(sim_.task().machine.state);
    if (run_.states.empty() || run_.states.back().state != name) run_.states.push_back({t, name});
  }
  MotionRun finish(double t, const char* result) {
    run_.duration_s = t;
    run_.result = run_.faults != 0 ? "faulted" : result;
    return run_;
  }

  const MotionScript& script_;
  MotionSim<S> sim_;
  MotionRun run_;
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

/// The tick's report into the records: answers, motions done or aborted, stops completed.
template <class S>
void Player<S>::observe(double t, std::uint32_t faults) {
  run_.faults |= faults;
  const osc::MotionReport& rep = sim_.task().report;
  if (CommandRecord* r = rep.outcome != osc::CommandOutcome::kNone ? record(rep.id) : nullptr) {
    r->answered_s = t;
    r->accepted = rep.outcome == osc::CommandOutcome::kAccepted;
    if (!r->accepted) r->refused = osc::motion_name(rep.refusal), r->cause = rep.cause;
    const bool motion = rep.verb == osc::MotionVerb::kMoveTo || rep.verb == osc::MotionVerb::kPaper ||
                        rep.verb == osc::MotionVerb::kStream;
    r->running = r->accepted && motion;
    // Done at once unless it started a motion or a stop (a stop or disable from holding has nothing to stop).
    if (r->accepted && !motion && sim_.task().machine.state != osc::MotionState::kStopping) r->done_s = t;
  }
  if (CommandRecord* r = record(rep.done_id)) r->done_s = t, r->running = false;
  if (CommandRecord* r = rep.abort != osc::MotionReason::kNone ? record(rep.aborted_id) : nullptr)
    r->aborted = osc::motion_name(rep.abort), r->aborted_s = t, r->running = false;
  // The moves waiting behind it are dropped with it (not the re-targeting move answered in this tick).
  if (rep.abort != osc::MotionReason::kNone)
    for (CommandRecord& r : run_.commands)
      if (r.running && r.id != rep.aborted_id && !(rep.outcome != osc::CommandOutcome::kNone && r.id == rep.id))
        r.aborted = osc::motion_name(rep.abort), r.aborted_s = t, r.running = false;
  if (rep.completion != osc::MotionCompletion::kNone)  // a stop or disable that reached rest
    for (CommandRecord& r : run_.commands)
      if (r.accepted && r.done_s < 0 && (r.cmd == "stop" || r.cmd == "disable")) r.done_s = t;
  track();
  log_state(t);
}

/// Tracking error and the reference's own maxima, into every command whose motion runs.
template <class S>
void Player<S>::track() {
  if (!was_powered_ || !osc::motion_powered(sim_.task().machine.state)) {
    have_prev_ = false;
    return;
  }
  const osc::Desired<S>& d = sim_.task().desired;
  const Vec6 x = sim_.pose();
  const Vec6 xr = d.x.template cast<double>();
  const double e_mm = (xr.head<3>() - x.head<3>()).norm() * 1e3;
  const double e_deg = (xr.tail<3>() - x.tail<3>()).norm() / kDegToRad;
  const osc::Vec3<double> v = d.xd.template head<3>().template cast<double>();
  const osc::Vec3<double> a = d.xdd.template head<3>().template cast<double>();
  const Mat3 Einv = osc::angular_to_phi_rate<double>(xr.tail<3>());
  const osc::Vec3<double> w = Einv.inverse() * d.xd.template tail<3>().template cast<double>();
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
  if (cfg.scalar == Scalar::kFloat) return Player<float>(script, cfg).run();
  if (cfg.scalar == Scalar::kFixed) return Player<osc::Fixed>(script, cfg).run();
  return Player<double>(script, cfg).run();
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
  j["commands"] = cmds;
  ordered_json states = ordered_json::array();
  for (const auto& s : run.states) states.push_back({{"t", s.t}, {"state", s.state}});
  j["states"] = states;
  j["limits"] = {{"v", osc::params::kMoveLinear[0]},   {"a", osc::params::kMoveLinear[1]},
                 {"j", osc::params::kMoveLinear[2]},   {"w", osc::params::kMoveAngular[0]},
                 {"wd", osc::params::kMoveAngular[1]}, {"wdd", osc::params::kMoveAngular[2]}};
  return j.dump(2) + "\n";
}

}  // namespace sim
