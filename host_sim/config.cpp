// The experiment's configuration (see config.hpp): one table of entries, read and written with
// yaml-cpp.
#include "config.hpp"

#include "osc/control/sampled_loop.hpp"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iterator>
#include <sstream>
#include <type_traits>

#include "osc_git_revision.hpp"

namespace sim {
namespace {

using json = nlohmann::ordered_json;

constexpr double kDeg = osc::kPi / 180.0;

/// Shortest text that reads back as the same double ("0.05", "120", "0.0001").
std::string number_text(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string range_text(double lo, double hi) { return "[" + number_text(lo) + ", " + number_text(hi) + "]"; }

enum class Kind { kNumber, kList, kName };

/// One entry of the configuration. Values travel as JSON values in the file's units (numbers, lists
/// of numbers, names); `get` reads one from the settings and `put` stores a checked one, returning
/// an error text for what only it can check (empty: fine).
struct Entry {
  std::string key;
  std::string doc;  // unit and meaning: the YAML comment and --help
  Kind kind;
  double lo = 0, hi = 0;           // kNumber, and each element of a kList
  std::vector<std::string> names;  // kName: the values allowed
  bool paper = true;               // part of the paper's set-up (differences_from_paper)
  bool feature = false;            // a feature of the plant, which plant.preset sets (differences_from_preset)
  std::function<json(const Settings&)> get = nullptr;
  std::function<std::string(Settings&, const json&)> put = nullptr;
  std::function<bool(const Settings&)> shown = nullptr;  // printed only when true (null: always)
  std::function<void(const Settings&, double& lo, double& hi, int element)> element_range =
      nullptr;                  // per-element bounds
  int count = 6;                // kList: its elements
  std::string range_note = "";  // the comment's range where element_range gives them (empty: none shown)
};

json vec_json(const double* v, int n, double scale = 1) {
  json a = json::array();
  for (int i = 0; i < n; ++i) a.push_back(v[i] * scale);
  return a;
}
json vec_json(const Vec6& v, double scale = 1) { return vec_json(v.data(), 6, scale); }

std::string mode_name(const Settings& s) {
  return s.run_adaptive && s.run_none ? "both" : s.run_adaptive ? "adaptive" : "none";
}

/// The robot's friction preset of that name (osc::robot::kFrictionPresets), or null.
const osc::FrictionCoefficients* friction_preset(const std::string& name) {
  for (const auto* p : osc::robot::kFrictionPresets)
    if (name == p->name) return p;
  return nullptr;
}

/// The preset names, then "custom".
std::vector<std::string> friction_preset_names() {
  std::vector<std::string> names;
  for (const auto* p : osc::robot::kFrictionPresets) names.emplace_back(p->name);
  names.emplace_back("custom");
  return names;
}

/// Sets one coefficient list of the plant's friction (0 vis, 1 cou, 2 sti): the friction is then custom.
std::function<std::string(Settings&, const json&)> put_friction(int which) {
  return [which](Settings& s, const json& v) {
    osc::FrictionCoefficients& f = s.base.plant.friction;
    double* dst = which == 0 ? f.vis : which == 1 ? f.cou : f.sti;
    for (int i = 0; i < 6; ++i) dst[i] = v[i].get<double>();
    f.name = "custom";
    return std::string();
  };
}

/// A number entry stored in the settings as is.
void number(std::vector<Entry>& t, std::string key, std::string doc, double lo, double hi, bool paper,
            std::function<double&(Settings&)> ref) {
  Entry e{std::move(key), std::move(doc), Kind::kNumber, lo, hi, {}, paper};
  e.get = [ref](const Settings& s) { return json(ref(const_cast<Settings&>(s))); };
  e.put = [ref](Settings& s, const json& v) {
    ref(s) = v.get<double>();
    return std::string();
  };
  t.push_back(e);
}

/// A list of six numbers, each in [lo, hi], stored scaled by `scale` into the settings.
void list6(std::vector<Entry>& t, std::string key, std::string doc, double lo, double hi, bool paper,
           std::function<Vec6&(Settings&)> ref, double scale = 1) {
  Entry e{std::move(key), std::move(doc), Kind::kList, lo, hi, {}, paper};
  e.get = [ref, scale](const Settings& s) { return vec_json(ref(const_cast<Settings&>(s)), 1 / scale); };
  e.put = [ref, scale](Settings& s, const json& v) {
    for (int i = 0; i < 6; ++i) ref(s)(i) = v[i].get<double>() * scale;
    return std::string();
  };
  t.push_back(e);
}

/// A name entry: one of `names`.
void name(std::vector<Entry>& t, std::string key, std::string doc, std::vector<std::string> names, bool paper,
          std::function<std::string(const Settings&)> get, std::function<void(Settings&, const std::string&)> put) {
  Entry e{std::move(key), std::move(doc), Kind::kName, 0, 0, std::move(names), paper};
  e.get = [get](const Settings& s) { return json(get(s)); };
  e.put = [put](Settings& s, const json& v) {
    put(s, v.get<std::string>());
    return std::string();
  };
  t.push_back(e);
}

/// The names of an enumeration of motion_states.hpp, in code order.
template <class E>
std::vector<std::string> names_of() {
  return {std::begin(osc::MotionNames<E>::kNames), std::end(osc::MotionNames<E>::kNames)};
}

/// The runtime parameters (osc/runtime/parameters.hpp) that the entries above do not key by name:
/// run.<name>, a number or a list of the parameter's elements, each in its element's range, from the
/// one table (the run's task takes them at its start: sim::configure_monitors).
void add_runtime_param_entries(std::vector<Entry>& t) {
  for (int i = 0; i < osc::kParamCount; ++i) {
    const osc::ParamInfo& p = osc::kParams[i];
    if (!runtime_param_generated(p)) continue;
    const std::string key = std::string("run.") + p.name;
    const std::string doc = std::string(p.doc) + (*p.unit ? std::string(" [") + p.unit + "]" : "");
    const int slot = osc::param_slot(i), n = p.count;
    Entry e{key, doc, n == 1 ? Kind::kNumber : Kind::kList, p.lo_of(0), p.hi_of(0), {}, false};
    e.count = n;
    e.get = [slot, n](const Settings& s) {
      if (n == 1) return json(s.base.params[slot]);
      json a = json::array();
      for (int k = 0; k < n; ++k) a.push_back(s.base.params[slot + k]);
      return a;
    };
    e.put = [i, slot, n](Settings& s, const json& v) {
      double in[6] = {};
      for (int k = 0; k < n; ++k) in[k] = n == 1 ? v.get<double>() : v[k].get<double>();
      if (i == osc::kPayloadInertiaParam && !osc::inertia_semidefinite(in))
        return std::string("not positive semi-definite: ") + osc::param_status_name(osc::ParamStatus::kNotPhysical);
      for (int k = 0; k < n; ++k) s.base.params[slot + k] = in[k];
      return std::string();
    };
    e.element_range = [i](const Settings&, double& lo, double& hi, int k) {
      lo = osc::kParams[i].lo_of(k);
      hi = osc::kParams[i].hi_of(k);
    };
    t.push_back(e);
  }
}

void add_run_entries(std::vector<Entry>& t) {
  number(t, "run.duration", "simulated seconds per run [s]", 1, 86400, true,
         [](Settings& s) -> double& { return s.base.duration; });
  name(t, "run.modes", "with friction compensation (Table I), without (Table III), or both",
       {"both", "adaptive", "none"}, false, mode_name, [](Settings& s, const std::string& m) {
         s.run_adaptive = m != "none";
         s.run_none = m != "adaptive";
       });
  name(
      t, "run.scalar", "the controller's arithmetic (fixed: Q12.19 fixed point, docs/fixed_point.md)",
      std::vector<std::string>(std::begin(kScalarNames), std::end(kScalarNames)), false,
      [](const Settings& s) { return std::string(kScalarNames[static_cast<int>(s.base.scalar)]); },
      [](Settings& s, const std::string& m) {
        for (int i = 0; i < static_cast<int>(std::size(kScalarNames)); ++i)
          if (m == kScalarNames[i]) s.base.scalar = static_cast<Scalar>(i);
      });
  name(
      t, "run.adaptation",
      "friction adaptation law: paper is (67) exactly, robust adds projection and leakage, momentum identifies the "
      "friction from the residual monitor's momentum residual (docs/adaptation.md)",
      std::vector<std::string>(osc::kAdaptationLawNames, osc::kAdaptationLawNames + osc::kAdaptationLawCount), false,
      [](const Settings& s) { return std::string(osc::adaptation_law_name(s.base.gains.adaptation)); },
      [](Settings& s, const std::string& m) { osc::adaptation_law_from_name(m, s.base.gains.adaptation); });
  name(
      t, "run.model_rate",
      "how often the control step refreshes the arm's dynamics model: alternate (default) computes A(q), its factors "
      "and g(q) on one step and the velocity products on the next, each held a step; every_step computes both every "
      "step (osc/control/controller.hpp, dynamics_turn)",
      std::vector<std::string>(osc::kModelRateNames, osc::kModelRateNames + osc::kModelRateCount), true,
      [](const Settings& s) { return std::string(osc::kModelRateNames[static_cast<int>(s.base.gains.model_rate)]); },
      [](Settings& s, const std::string& m) {
        for (int i = 0; i < osc::kModelRateCount; ++i)
          if (m == osc::kModelRateNames[i]) s.base.gains.model_rate = static_cast<osc::ModelRate>(i);
      });
  name(
      t, "run.residual_monitor",
      "on (default): the residual monitor raises encoder_stuck, drive_fault and collision, the stuck-encoder "
      "monitor off but while homing; trial: the residual monitor is computed and reported, the stuck-encoder monitor "
      "raises encoder_stuck (docs/safety.md); the firmware's parameter residual_monitor (1 on, 0 trial)",
      {"trial", "on"}, false, [](const Settings& s) { return std::string(s.base.residual_monitor ? "on" : "trial"); },
      [](Settings& s, const std::string& m) { s.base.residual_monitor = m == "on"; });
  name(
      t, "run.collision_reaction", "what a collision does, with run.residual_monitor=on (docs/safety.md)",
      names_of<osc::CollisionReaction>(), false,
      [](const Settings& s) { return std::string(osc::motion_name(s.base.collision_reaction)); },
      [](Settings& s, const std::string& m) {
        for (int i = 0; i < osc::MotionNames<osc::CollisionReaction>::kCount; ++i)
          if (m == osc::MotionNames<osc::CollisionReaction>::kNames[i])
            s.base.collision_reaction = static_cast<osc::CollisionReaction>(i);
      });
  Entry c{"run.collision_threshold",
          "each joint's collision threshold [N m]: a collision is reported once a residual is beyond it too (0: "
          "the derived threshold alone; at most the joint's full-scale torque)",
          Kind::kList,
          0,
          1e9,
          {},
          false};
  c.get = [](const Settings& s) { return vec_json(s.base.collision_threshold, 6); };
  c.put = [](Settings& s, const json& v) {
    for (int i = 0; i < 6; ++i) s.base.collision_threshold[i] = v[i].get<double>();
    return std::string();
  };
  c.element_range = [](const Settings&, double& lo, double& hi, int i) {
    lo = 0;
    hi = osc::robot::kDrives.torque_limit[i];
  };
  t.push_back(c);
  number(t, "run.final_window", "length of the \"last\" statistics at the end of each run [s] (Table I: 20)", 1, 3600,
         true, [](Settings& s) -> double& { return s.base.final_window; });
  number(t, "run.window", "length of the windows of the per-window worst errors [s]", 1, 3600, false,
         [](Settings& s) -> double& { return s.base.window; });
  add_runtime_param_entries(t);
}

/// The entry controller.<key> of one gain of OSC_GAINS_FIELDS, as its parameter column says (form F:
/// a list of six, a number, or one number for every element), checked against the gain's type here.
/// A gain without a key (GainForm::kNone) has no entry.
template <osc::GainForm F, class T>
void add_gain(std::vector<Entry>& t, const osc::GainParam& p, const char* doc, T osc::Gains<double>::*gain) {
  if constexpr (F == osc::GainForm::kNone) return;
  const std::string key = std::string("controller.") + p.key;
  const std::string text = std::string(doc) + (*p.unit ? std::string(" [") + p.unit + "]" : "");
  if constexpr (F == osc::GainForm::kPerAxis) {
    static_assert(std::is_same_v<T, Vec6>, "a per-axis parameter is a vector of six");
    list6(t, key, text, p.lo, p.hi, true, [gain](Settings& s) -> Vec6& { return s.base.gains.*gain; });
    if (p.lo_each || p.hi_each) {  // each element its own range (the translations', the rotations')
      t.back().element_range = [p](const Settings&, double& lo, double& hi, int k) {
        lo = p.lo_of(k);
        hi = p.hi_of(k);
      };
      t.back().range_note =
          "x y z " + range_text(p.lo_of(0), p.hi_of(0)) + ", rotations " + range_text(p.lo_of(3), p.hi_of(3));
    }
  } else if constexpr (F == osc::GainForm::kOne) {
    static_assert(std::is_same_v<T, double>, "a parameter of one number is a number");
    number(t, key, text, p.lo, p.hi, true, [gain](Settings& s) -> double& { return s.base.gains.*gain; });
  } else if constexpr (F == osc::GainForm::kEvery) {
    static_assert(std::is_same_v<T, Vec6>, "one number for every element: a vector of six");
    Entry e{key, text, Kind::kNumber, p.lo, p.hi, {}, true};
    e.get = [gain](const Settings& s) { return json((s.base.gains.*gain)(0)); };
    e.put = [gain](Settings& s, const json& v) {
      (s.base.gains.*gain).setConstant(v.get<double>());
      return std::string();
    };
    t.push_back(e);
  }
}

void add_controller_entries(std::vector<Entry>& t) {
  // The gains' keys come from their one list, in its order: gains (69), diagonal, axes x, y, z, then
  // the rotations about X, Y, Z; K_ad, tau_dec, the leakage.
  namespace gain_param = osc::gain_param;  // the parameter column's helpers
#define SIM_GAIN_ENTRY(type, name, paper, doc, param) add_gain<(param).form>(t, param, doc, &osc::Gains<double>::name);
  OSC_GAINS_FIELDS(SIM_GAIN_ENTRY)
#undef SIM_GAIN_ENTRY
  number(t, "controller.model_error", "relative error of the controller's link masses and inertias", -0.5, 0.5, true,
         [](Settings& s) -> double& { return s.base.model_error; });
}

/// Trajectory (68) with one of amplitude, period or envelope changed. omega keeps the exact value
/// of params.hpp for the paper's period.
void reshape(Settings& s, double amplitude, std::uint64_t period_ticks, double envelope) {
  osc::TrajectorySpec<double>& spec = s.base.gains.trajectory;
  const osc::TrajectorySpec<double> old = spec;
  spec = osc::trajectory_spec(amplitude, period_ticks, envelope, osc::params::kDt);
  if (period_ticks == old.period_ticks) spec.omega = old.omega;
  if (period_ticks == osc::kTrajectoryPeriodTicks) spec.omega = osc::params::kOmega;
}

void add_trajectory_entries(std::vector<Entry>& t) {
  Entry a{"trajectory.amplitude", "of each sinusoid about the start position [m]", Kind::kNumber, 0, 0.2, {}, true};
  a.get = [](const Settings& s) { return json(s.base.gains.trajectory.amplitude); };
  a.put = [](Settings& s, const json& v) {
    const osc::TrajectorySpec<double> o = s.base.gains.trajectory;
    reshape(s, v.get<double>(), o.period_ticks, o.envelope);
    return std::string();
  };
  t.push_back(a);
  Entry p{
      "trajectory.period", "of the sinusoids [s], a whole number of samples (1 ms)", Kind::kNumber, 0.5, 60, {}, true};
  p.get = [](const Settings& s) {
    return json(static_cast<double>(s.base.gains.trajectory.period_ticks) * osc::params::kDt);
  };
  p.put = [](Settings& s, const json& v) {
    const double period = v.get<double>();
    const double ticks = std::round(period / osc::params::kDt);
    if (std::abs(ticks * osc::params::kDt - period) > 1e-9)
      return number_text(period) + " s is not a whole number of samples of " + number_text(osc::params::kDt) + " s";
    const osc::TrajectorySpec<double> o = s.base.gains.trajectory;
    reshape(s, o.amplitude, static_cast<std::uint64_t>(ticks), o.envelope);
    return std::string();
  };
  t.push_back(p);
  Entry c{"trajectory.envelope", "rate c of the envelope 1 - exp(-c t^3) [1/s^3]", Kind::kNumber, 1e-3, 10, {}, true};
  c.get = [](const Settings& s) { return json(s.base.gains.trajectory.envelope); };
  c.put = [](Settings& s, const json& v) {
    const osc::TrajectorySpec<double> o = s.base.gains.trajectory;
    reshape(s, o.amplitude, o.period_ticks, v.get<double>());
    return std::string();
  };
  t.push_back(c);
}

/// The start pose, in degrees within the joint limits.
void add_start_pose_entry(std::vector<Entry>& t) {
  Entry q{"start_pose", "joint angles q1..q6 at the start [deg], within the joint limits", Kind::kList, -360, 360, {},
          true};
  q.get = [](const Settings& s) { return vec_json(s.base.q_start, 1 / kDeg); };
  q.put = [](Settings& s, const json& v) {
    for (int i = 0; i < 6; ++i) {
      double rad = v[i].get<double>() * kDeg;
      // The printed degrees read back as the description's radians exactly.
      if (std::abs(rad - osc::robot::kQStart[i]) < 1e-12) rad = osc::robot::kQStart[i];
      s.base.q_start(i) = rad;
    }
    return std::string();
  };
  q.element_range = [](const Settings&, double& lo, double& hi, int i) {
    lo = std::round(osc::robot::kArm.q_min[i] / kDeg * 1e6) / 1e6;
    hi = std::round(osc::robot::kArm.q_max[i] / kDeg * 1e6) / 1e6;
  };
  t.push_back(q);
}

/// The simulated arm's pose at power-on: start (placed at the start pose, declared there), random:SEED,
/// or six joint angles in degrees within the joint limits (experiment.hpp, ExperimentConfig::power_on_pose).
void add_power_on_entry(std::vector<Entry>& t) {
  Entry e{"plant.power_on_pose",
          "the simulated arm's pose at power-on (motion scripts): start (placed at the start pose and declared "
          "there), random:SEED (the start pose, each joint moved by up to +-25 deg), or six joint angles [deg]; "
          "other than start, the firmware is not homed: motion is refused until a home or a declare_pose step",
          Kind::kName,
          0,
          0,
          {},
          true};
  e.get = [](const Settings& s) -> json {
    if (s.base.power_on_text.empty()) return vec_json(*s.base.power_on_pose, 1 / kDeg);
    return s.base.power_on_text;
  };
  e.put = [](Settings& s, const json& v) {
    ExperimentConfig& c = s.base;
    if (v.is_array()) {
      if (v.size() != 6) return std::string("expected start, random:SEED or six joint angles in degrees");
      Vec6 q;
      for (int i = 0; i < 6; ++i) {
        q(i) = v[i].get<double>() * kDeg;
        if (q(i) < osc::robot::kArm.q_min[i] || q(i) > osc::robot::kArm.q_max[i])
          return "joint " + std::to_string(i + 1) + ": " + number_text(v[i].get<double>()) +
                 " deg is outside its limits " +
                 range_text(osc::robot::kArm.q_min[i] / kDeg, osc::robot::kArm.q_max[i] / kDeg);
      }
      c.power_on_pose = q;
      c.power_on_text.clear();
      return std::string();
    }
    const std::string text = v.get<std::string>();
    if (text == "start") {
      c.power_on_pose.reset();
      c.power_on_text = text;
      return std::string();
    }
    unsigned long seed = 0;
    const char* digits = text.c_str() + 7;
    char* end = nullptr;
    if (text.rfind("random:", 0) == 0 && *digits >= '0' && *digits <= '9') seed = std::strtoul(digits, &end, 10);
    if (end == nullptr || *end != '\0' || seed > 0xffffffffUL)
      return "'" + text + "' is not start, random:SEED (SEED a whole number) or six joint angles in degrees";
    c.power_on_pose = random_power_on_pose(static_cast<std::uint32_t>(seed), c.q_start);
    c.power_on_text = text;
    return std::string();
  };
  t.push_back(e);
}

/// The plant's friction: a preset of the robot by name, or custom coefficients.
void add_plant_friction_entries(std::vector<Entry>& t) {
  Entry f{"plant.friction.preset",
          "the simulated robot's friction: a preset of the robot (the PUMA 560's: paper, Table II; corke, "
          "the toolbox's; none), or custom (vis, cou, sti below; setting any of them makes it custom)",
          Kind::kName,
          0,
          0,
          friction_preset_names(),
          true};
  f.get = [](const Settings& s) { return json(std::string(s.base.plant.friction.name)); };
  f.put = [](Settings& s, const json& v) {
    const std::string n = v.get<std::string>();
    if (const osc::FrictionCoefficients* p = friction_preset(n))
      s.base.plant.friction = *p;
    else
      s.base.plant.friction.name = "custom";  // keeps the coefficients it has
    return std::string();
  };
  t.push_back(f);
  const char* const kCoef[3][2] = {{"plant.friction.vis", "viscous coefficients per joint [N m s/rad]"},
                                   {"plant.friction.cou", "Coulomb levels per joint [N m]"},
                                   {"plant.friction.sti", "Stribeck excess per joint [N m]"}};
  for (int k = 0; k < 3; ++k) {
    Entry c{kCoef[k][0], kCoef[k][1], Kind::kList, 0, 200, {}, true};
    c.get = [k](const Settings& s) {
      const osc::FrictionCoefficients& fr = s.base.plant.friction;
      return vec_json(k == 0 ? fr.vis : k == 1 ? fr.cou : fr.sti, 6);
    };
    c.put = put_friction(k);
    c.shown = [](const Settings& s) { return std::string(s.base.plant.friction.name) == "custom"; };
    t.push_back(c);
  }
}

/// A name entry of two values, off and on, for a flag.
void flag(std::vector<Entry>& t, std::string key, std::string doc, std::function<bool&(Settings&)> ref) {
  name(
      t, std::move(key), std::move(doc), {"off", "on"}, true,
      [ref](const Settings& s) { return std::string(ref(const_cast<Settings&>(s)) ? "on" : "off"); },
      [ref](Settings& s, const std::string& v) { ref(s) = v == "on"; });
}

/// A list of six numbers stored in a plain array.
void array6(std::vector<Entry>& t, std::string key, std::string doc, double lo, double hi,
            std::function<double*(Settings&)> ref) {
  Entry e{std::move(key), std::move(doc), Kind::kList, lo, hi, {}, true};
  e.get = [ref](const Settings& s) { return vec_json(ref(const_cast<Settings&>(s)), 6); };
  e.put = [ref](Settings& s, const json& v) {
    for (int i = 0; i < 6; ++i) ref(s)[i] = v[i].get<double>();
    return std::string();
  };
  t.push_back(e);
}

/// The plant's features from the DAC on: its resolution, the ripple, the gears, the sensors, the drift.
void add_plant_feature_tail(std::vector<Entry>& t) {
  Entry d{"plant.dac_bits",
          "the DACs' resolution the amplifiers see [bits] (the board's AD5754R: 16)",
          Kind::kNumber,
          8,
          16,
          {},
          true};
  d.get = [](const Settings& s) { return json(s.base.sensors.dac_bits); };
  d.put = [](Settings& s, const json& v) {
    const double n = v.get<double>();
    if (n != std::floor(n)) return number_text(n) + " is not a whole number";
    s.base.sensors.dac_bits = static_cast<int>(n);
    return std::string();
  };
  t.push_back(d);
  number(t, "plant.ripple", "torque ripple, relative amplitude (0: none; estimate: 0.01..0.05)", 0, 0.2, true,
         [](Settings& s) -> double& { return s.base.plant.ripple; });
  Entry r{"plant.ripple_cycles",
          "ripple periods per motor revolution (the motor's pole frequency)",
          Kind::kNumber,
          0,
          64,
          {},
          true};
  r.get = [](const Settings& s) { return json(s.base.plant.ripple_cycles); };
  r.put = [](Settings& s, const json& v) {
    const double n = v.get<double>();
    if (n != std::floor(n)) return number_text(n) + " is not a whole number";
    s.base.plant.ripple_cycles = static_cast<int>(n);
    return std::string();
  };
  t.push_back(r);
  number(t, "plant.backlash",
         "gear backlash on J1-J3, the dead band at the joint [rad] (0: none; estimate: 0.1e-3..1e-3)", 0, 5e-3, true,
         [](Settings& s) -> double& { return s.base.plant.backlash; });
  number(t, "plant.elastic_hz",
         "joint elasticity on J1-J3: the locked-motor resonance at the start pose [Hz] (0: rigid; estimate: 15..25)", 0,
         200, true, [](Settings& s) -> double& { return s.base.plant.elastic_hz; });
  number(t, "plant.encoder_jitter", "encoder edge jitter, the edges' spread [counts] (0: none)", 0, 0.5, true,
         [](Settings& s) -> double& { return s.base.sensors.encoder_jitter; });
  number(t, "plant.pot_noise", "potentiometer noise, standard deviation [ADC codes]", 0, 100, true,
         [](Settings& s) -> double& { return s.base.sensors.pot_noise; });
  array6(t, "plant.pot_offset", "potentiometer offsets per joint [ADC codes]", -500, 500,
         [](Settings& s) { return s.base.sensors.pot_offset; });
  number(t, "plant.friction_drift",
         "friction's drift with temperature, relative amplitude over plant.friction_drift_period (0: none)", 0, 0.9,
         true, [](Settings& s) -> double& { return s.base.plant.friction_drift; });
  number(t, "plant.friction_drift_period", "the period of friction's drift [s]", 60, 86400, true,
         [](Settings& s) -> double& { return s.base.plant.friction_drift_period; });
}

/// The plant's features (docs/experiment.md, "The realistic plant"): the preset first, then each
/// feature, so that a file read in its printed order applies the preset and then its differences.
void add_plant_feature_entries(std::vector<Entry>& t) {
  const std::size_t first = t.size() + 1;  // after plant.preset
  name(
      t, "plant.preset",
      "the simulated arm: ideal (rigid, uncoupled, ideal drives: the paper's tables) or realistic (every feature "
      "below at its mid value); setting it sets every feature below",
      plant_preset_names(), true, [](const Settings& s) { return s.plant_preset; },
      [](Settings& s, const std::string& n) {
        apply_plant_preset(n, s.base);
        s.plant_preset = n;
      });
  name(
      t, "plant.encoders",
      "encoder resolution: uniform (plant.encoder_cpr on every motor) or trident (the PUMA's own, per joint: 1000 "
      "counts per motor revolution, about 797 on J2)",
      {"uniform", "trident"}, true,
      [](const Settings& s) { return std::string(s.base.published_encoders ? "trident" : "uniform"); },
      [](Settings& s, const std::string& v) { s.base.published_encoders = v == "trident"; });
  flag(t, "plant.coupling",
       "the wrist coupling (q5 = e5 - 0.0139 e4, q6 = e6 + 0.0130 e4 - 0.1806 e5): the encoders count motor "
       "angles, the DACs command motor torques (C^T tau), the motor inertias and friction act on the motors",
       [](Settings& s) -> bool& { return s.base.plant.coupling; });
  name(
      t, "plant.motor_inertia",
      "the plant's motor inertias: the sheet's first set (the controller's model; the PUMA's: toolbox) or its second "
      "(the PUMA's: akb86, +45/+105/+50 % on J1-J3)",
      {osc::robot::kMotorInertiaModel.name, osc::robot::kDriveTrain.motor_inertia_alt.name}, true,
      [](const Settings& s) {
        return std::string(s.base.plant.motor_inertia ? s.base.plant.motor_inertia->name
                                                      : osc::robot::kMotorInertiaModel.name);
      },
      [](Settings& s, const std::string& v) {
        s.base.plant.motor_inertia =
            v == osc::robot::kDriveTrain.motor_inertia_alt.name ? &osc::robot::kDriveTrain.motor_inertia_alt : nullptr;
      });
  number(t, "plant.amp_lag",
         "the amplifiers' current loops, first-order time constant [s] (0: none; estimate: 0.2e-3..0.5e-3)", 0, 5e-3,
         true, [](Settings& s) -> double& { return s.base.plant.amp_lag; });
  flag(t, "plant.amp_current_limit", "the amplifiers' current limits (the drive train's motor torque limits)",
       [](Settings& s) -> bool& { return s.base.plant.amp_current_limit; });
  array6(t, "plant.amp_gain_error", "the amplifiers' gain errors per channel, relative", -0.2, 0.2,
         [](Settings& s) { return s.base.plant.amp_gain_error; });
  array6(t, "plant.amp_offset", "the amplifiers' offsets per channel, joint-referred [N m]", -10, 10,
         [](Settings& s) { return s.base.plant.amp_offset; });
  flag(t, "plant.current_monitor",
       "the amplifiers' current monitors, read back (the drive check and its test dither run: docs/safety.md)",
       [](Settings& s) -> bool& { return s.base.sensors.current_monitor; });
  array6(t, "plant.current_gain", "the current monitors' gain errors per channel, relative", -0.2, 0.2,
         [](Settings& s) { return s.base.sensors.current_gain; });
  array6(t, "plant.current_offset", "the current monitors' offsets per channel, of the DAC's full scale", -0.05, 0.05,
         [](Settings& s) { return s.base.sensors.current_offset; });
  number(t, "plant.current_noise", "the current monitors' noise, standard deviation [ADC codes]", 0, 100, true,
         [](Settings& s) -> double& { return s.base.sensors.current_noise; });
  add_plant_feature_tail(t);
  // The plant's preset and features model the paper's robot more or less closely: they do not change
  // the paper's set-up (the outputs name them apart: Provenance::plant).
  t[first - 1].paper = false;
  for (std::size_t i = first; i < t.size(); ++i) t[i].feature = true, t[i].paper = false;
}

/// The payload the simulated arm carries at its flange (the truth; the controller's model knows it
/// through run.payload_*, the firmware's parameters). Up to twice the arm's rating, so that a run can
/// carry more than the model may be told.
void add_plant_payload_entries(std::vector<Entry>& t) {
  const osc::PayloadRating& r = osc::robot::kPayloadRating;
  number(t, "plant.payload_mass", "the payload the simulated arm carries at its flange [kg]", 0, 2 * r.mass, true,
         [](Settings& s) -> double& { return s.base.plant.payload.mass; });
  Entry c{"plant.payload_com",
          "its centre of mass in frame 6 [m]",
          Kind::kList,
          -2 * r.com_reach,
          2 * r.com_reach,
          {},
          true};
  c.count = 3;
  c.get = [](const Settings& s) { return vec_json(s.base.plant.payload.com, 3); };
  c.put = [](Settings& s, const json& v) {
    for (int i = 0; i < 3; ++i) s.base.plant.payload.com[i] = v[i].get<double>();
    return std::string();
  };
  t.push_back(c);
  Entry i{"plant.payload_inertia",
          "its inertia about its centre of mass, frame-6 axes: Ixx, Iyy, Izz, Ixy, Ixz, Iyz [kg m^2]",
          Kind::kList,
          -2 * r.inertia,
          2 * r.inertia,
          {},
          true};
  i.put = [](Settings& s, const json& v) {
    double in[6];
    for (int k = 0; k < 6; ++k) in[k] = v[k].get<double>();
    if (!osc::inertia_semidefinite(in)) return std::string("not positive semi-definite (no rigid body has it)");
    for (int k = 0; k < 6; ++k) s.base.plant.payload.inertia[k] = in[k];
    return std::string();
  };
  i.get = [](const Settings& s) { return vec_json(s.base.plant.payload.inertia, 6); };
  t.push_back(i);
}

void add_plant_entries(std::vector<Entry>& t) {
  add_plant_feature_entries(t);
  add_plant_payload_entries(t);
  add_plant_friction_entries(t);
  number(t, "plant.tau_dec", "the simulated robot's Stribeck decay tau_dec [s^2/rad^2]", 0.01, 100, true,
         [](Settings& s) -> double& { return s.base.plant.tau_dec; });
  number(t, "plant.encoder_cpr", "encoder counts per motor revolution, plant and controller alike", 100, 1e7, true,
         [](Settings& s) -> double& { return s.base.encoder_counts_per_motor_rev; });
  number(t, "plant.delay", "computation delay from the encoder sample to the DAC update [s]", 0, osc::params::kDt, true,
         [](Settings& s) -> double& { return s.base.plant.compute_delay; });
  number(t, "plant.substep", "the plant's RK4 step [s] (through velocity reversals)", 1e-6, 1e-3, false,
         [](Settings& s) -> double& { return s.base.plant.substep; });
  Entry e{"plant.smooth_steps",
          "substeps the plant's RK4 takes at once while no joint velocity changes sign (1: fixed step)",
          Kind::kNumber,
          1,
          16,
          {},
          false};
  e.get = [](const Settings& s) { return json(s.base.plant.smooth_steps); };
  e.put = [](Settings& s, const json& v) {
    const double n = v.get<double>();
    if (n != std::floor(n)) return number_text(n) + " is not a whole number";
    s.base.plant.smooth_steps = static_cast<int>(n);
    return std::string();
  };
  t.push_back(e);
}

/// The configuration's entries, in the order of the printed file.
const std::vector<Entry>& entries() {
  static const std::vector<Entry> kEntries = [] {
    std::vector<Entry> t;
    add_run_entries(t);
    add_controller_entries(t);
    add_trajectory_entries(t);
    add_start_pose_entry(t);
    add_power_on_entry(t);
    add_plant_entries(t);
    return t;
  }();
  return kEntries;
}

const Entry* find_entry(const std::string& key) {
  for (const Entry& e : entries())
    if (key == e.key) return &e;
  return nullptr;
}

std::string allowed_names(const Entry& e) {
  if (e.names.empty()) return "a name or a list of numbers";
  std::string s;
  for (size_t i = 0; i < e.names.size(); ++i) s += (i ? (i + 1 == e.names.size() ? " or " : ", ") : "") + e.names[i];
  return s;
}

/// The scalar text of a node, for messages.
std::string node_text(const YAML::Node& n) {
  if (n.IsScalar()) return "'" + n.Scalar() + "'";
  YAML::Emitter out;
  out << YAML::Flow << n;
  return out.c_str();
}

bool read_number(const YAML::Node& n, double& v) {
  if (!n.IsScalar()) return false;
  const std::string& t = n.Scalar();
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

/// Checks a node against the entry and stores it; err names the key.
bool set_entry(const Entry& e, const YAML::Node& n, Settings& s, std::string& err) {
  const std::string key = e.key;
  json v;
  switch (e.kind) {
    case Kind::kNumber: {
      double x;
      if (!read_number(n, x)) return err = key + ": expected a number, got " + node_text(n), false;
      if (!std::isfinite(x)) return err = key + ": the value must be finite", false;
      if (x < e.lo || x > e.hi)
        return err = key + ": " + number_text(x) + " is out of range " + range_text(e.lo, e.hi), false;
      v = x;
      break;
    }
    case Kind::kList: {
      if (!n.IsSequence() || n.size() != static_cast<std::size_t>(e.count))
        return err = key + ": expected a list of " + std::to_string(e.count) + " numbers like " +
                     (e.count == 6 ? "[1, 2, 3, 4, 5, 6]" : "[1, 2, 3]") + ", got " + node_text(n),
               false;
      v = json::array();
      for (int i = 0; i < e.count; ++i) {
        double x, lo = e.lo, hi = e.hi;
        if (e.element_range) e.element_range(s, lo, hi, i);
        const std::string where = key + "[" + std::to_string(i + 1) + "]";
        if (!read_number(n[i], x)) return err = where + ": expected a number, got " + node_text(n[i]), false;
        if (!std::isfinite(x)) return err = where + ": the value must be finite", false;
        if (x < lo || x > hi)
          return err = where + ": " + number_text(x) + " is out of range " + range_text(lo, hi), false;
        v.push_back(x);
      }
      break;
    }
    case Kind::kName: {
      if (e.names.empty() && n.IsSequence()) {  // a name or a list of numbers, which put() checks
        v = json::array();
        for (std::size_t i = 0; i < n.size(); ++i) {
          double x;
          if (!read_number(n[i], x) || !std::isfinite(x))
            return err = key + "[" + std::to_string(i + 1) + "]: expected a number, got " + node_text(n[i]), false;
          v.push_back(x);
        }
        break;
      }
      const std::string t = n.IsScalar() ? n.Scalar() : "";
      bool ok = e.names.empty() && n.IsScalar();
      for (const auto& name : e.names) ok = ok || t == name;
      if (!ok) return err = key + ": expected " + allowed_names(e) + ", got " + node_text(n), false;
      v = t;
      break;
    }
  }
  const std::string why = e.put(s, v);
  if (!why.empty()) return err = key + ": " + why, false;
  return true;
}

/// Walks a mapping; every leaf must be an entry of the table.
bool apply_node(const YAML::Node& map, const std::string& prefix, const std::string& source, Settings& s,
                std::string& err) {
  for (const auto& kv : map) {
    const std::string key = prefix + kv.first.as<std::string>();
    const Entry* e = find_entry(key);
    if (e) {
      if (!set_entry(*e, kv.second, s, err)) return err = source + ": " + err, false;
    } else if (kv.second.IsMap()) {
      bool known_section = false;
      for (const Entry& x : entries()) known_section = known_section || std::string(x.key).rfind(key + ".", 0) == 0;
      if (!known_section) return err = source + ": unknown key '" + key + "' (--print-config lists the keys)", false;
      if (!apply_node(kv.second, key + ".", source, s, err)) return false;
    } else {
      return err = source + ": unknown key '" + key + "' (--print-config lists the keys)", false;
    }
  }
  return true;
}

}  // namespace

bool apply_config(const std::string& text, const std::string& source, Settings& s, std::string& err) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& x) {
    return err = source + ": not valid YAML: " + x.what(), false;
  }
  if (root.IsNull()) return true;  // an empty file changes nothing
  if (!root.IsMap()) return err = source + ": expected a mapping of keys (like 'run:' and 'trajectory:')", false;
  try {
    return apply_node(root, "", source, s, err);
  } catch (const YAML::Exception& x) {
    return err = source + ": " + x.what(), false;
  }
}

bool set_key(const std::string& key, const std::string& value, Settings& s, std::string& err) {
  const Entry* e = find_entry(key);
  if (!e) return err = "unknown key '" + key + "' (--print-config lists the keys)", false;
  YAML::Node n;
  try {
    n = YAML::Load(value);
  } catch (const YAML::Exception& x) {
    return err = key + ": '" + value + "' is not a YAML value: " + x.msg, false;
  }
  try {
    return set_entry(*e, n, s, err);
  } catch (const YAML::Exception& x) {
    return err = key + ": " + x.what(), false;
  }
}

bool apply_setting(const std::string& assignment, Settings& s, std::string& err) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    return err = "--set: expected key=value (like trajectory.amplitude=0.1), got '" + assignment + "'", false;
  return set_key(assignment.substr(0, eq), assignment.substr(eq + 1), s, err);
}

bool validate_settings(const Settings& s, std::string& err) {
  // The controller refuses a Jacobian whose reciprocal condition is below min_rcond (the singular
  // fault): a start pose there would fault at the first tick.
  const osc::Model<double> model = osc::Model<double>::of(osc::robot::kArm);
  osc::Data<double> data;
  osc::ArmOpSpace<double> os;
  osc::forward_kinematics(model, data, Vec6(s.base.q_start));
  const Mat3 R = data.R[osc::kDof];
  osc::opspace_update(model, data, os, Vec6(s.base.q_start), R);
  if (!(os.Jf.rcond >= 2 * s.base.gains.min_rcond)) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "start_pose: too close to a singularity (Jacobian reciprocal condition %.2g, the "
                  "controller needs %.2g or more)",
                  static_cast<double>(os.Jf.rcond), 2 * s.base.gains.min_rcond);
    return err = buf, false;
  }
  // The gains' discrete-time checks at the start pose, as the board's param set makes them
  // (osc/control/sampled_loop.hpp): each gain within its range can still lose the loop with others.
  const osc::GainMargins m = osc::gain_margins(s.base.gains, osc::lambda_inverse(data.A, os.Ja));
  if (!m.observer_stable() || !m.loop_stable()) {
    char buf[240];
    std::snprintf(buf, sizeof buf,
                  "controller: the gains would make the %s unstable at the start pose (observer margin %.3g, "
                  "loop margin %.3g: the knd, k, ks, ki together; docs/protocol.md, \"Parameters\")",
                  m.observer_stable() ? "sampled loop" : "discrete observer", m.observer, m.loop);
    return err = buf, false;
  }
  // A collision's settings act through the armed residual monitor alone.
  bool collision_set = s.base.collision_reaction != osc::CollisionReaction::kCategory0;
  for (double t : s.base.collision_threshold) collision_set = collision_set || t != 0;
  if (collision_set && !s.base.residual_monitor)
    return err = "run.collision_reaction and run.collision_threshold apply with run.residual_monitor=on", false;
  return true;
}

std::string config_yaml(const Settings& s) {
  YAML::Emitter out;
  out.SetIndent(2);
  out << YAML::BeginMap;
  std::vector<std::string> open;  // the sections open now
  for (const Entry& e : entries()) {
    if (e.shown && !e.shown(s)) continue;
    std::vector<std::string> parts;
    std::stringstream ks(e.key);
    for (std::string p; std::getline(ks, p, '.');) parts.push_back(p);
    size_t common = 0;
    while (common < open.size() && common + 1 < parts.size() && open[common] == parts[common]) ++common;
    while (open.size() > common) out << YAML::EndMap, open.pop_back();
    for (size_t j = open.size(); j + 1 < parts.size(); ++j) {
      out << YAML::Key << parts[j] << YAML::Value << YAML::BeginMap;
      open.push_back(parts[j]);
    }
    out << YAML::Key << parts.back() << YAML::Value;
    const json v = e.get(s);
    std::string range;
    if (v.is_array()) {
      out << YAML::Flow << YAML::BeginSeq;
      for (const auto& x : v) out << number_text(x.get<double>());
      out << YAML::EndSeq;
    } else if (v.is_number()) {
      out << number_text(v.get<double>());
    } else {
      out << v.get<std::string>();
    }
    if (e.kind == Kind::kName)
      range = allowed_names(e);
    else if (!e.element_range)
      range = range_text(e.lo, e.hi);
    else
      range = e.range_note;
    out << YAML::Comment(std::string(e.doc) + (range.empty() ? "" : "; " + range));
  }
  while (!open.empty()) out << YAML::EndMap, open.pop_back();
  out << YAML::EndMap;
  std::string text =
      "# puma_experiment configuration: feed it back with --config FILE, change one entry with\n"
      "# --set key=value. The defaults are the paper's set-up (Section VI), from the firmware's\n"
      "# headers (params.hpp, the robot description).\n";
  return text + out.c_str() + "\n";
}

json config_json(const Settings& s) {
  json root = json::object();
  for (const Entry& e : entries()) {
    if (e.shown && !e.shown(s)) continue;
    json* node = &root;
    std::stringstream ks(e.key);
    std::vector<std::string> parts;
    for (std::string p; std::getline(ks, p, '.');) parts.push_back(p);
    for (size_t j = 0; j + 1 < parts.size(); ++j) node = &(*node)[parts[j]];
    (*node)[parts.back()] = e.get(s);
  }
  return root;
}

namespace {
/// Does the entry's value differ between a and b (lists compared to 1e-9, relative: degrees of the
/// same radians)?
bool differs(const Entry& e, const Settings& s, const Settings& ref) {
  const json a = e.get(s), b = e.get(ref);
  if (a == b) return false;
  if (!(a.is_array() && b.is_array() && a.size() == b.size())) return true;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::abs(a[i].get<double>() - b[i].get<double>()) > 1e-9 * (1 + std::abs(b[i].get<double>()))) return true;
  return false;
}
/// The settings of s's plant preset, everything else as the paper's.
Settings preset_of(const Settings& s) {
  Settings ref;
  apply_plant_preset(s.plant_preset, ref.base);
  ref.plant_preset = s.plant_preset;
  return ref;
}
}  // namespace

std::vector<std::string> differences_from_preset(const Settings& s) {
  const Settings ref = preset_of(s);
  std::vector<std::string> keys;
  for (const Entry& e : entries())
    if (e.feature && differs(e, s, ref)) keys.push_back(e.key);
  return keys;
}

std::vector<std::string> differences_from_paper(const Settings& s) {
  const Settings paper;
  std::vector<std::string> keys;
  for (const Entry& e : entries()) {
    if (!e.paper) continue;
    const json a = e.get(s), b = e.get(paper);
    bool same = a == b;
    if (!same && a.is_array() && b.is_array() && a.size() == b.size()) {  // degrees of the same radians
      same = true;
      for (size_t i = 0; i < a.size(); ++i)
        same = same && std::abs(a[i].get<double>() - b[i].get<double>()) <= 1e-9 * (1 + std::abs(b[i].get<double>()));
    }
    if (!same) keys.push_back(e.key);
  }
  return keys;
}

std::string text_hash(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

const char* git_revision() { return OSC_GIT_REVISION; }

}  // namespace sim
