// The drive sheet (YAML): docs/arms.md describes its fields. Every group carries `source:` (where a
// published value was read) or `estimate:` (the reasoning behind a value that is not published),
// or both; the header copies them as comments.
#include <algorithm>
#include <cctype>
#include <initializer_list>
#include <set>
#include <string>

#include <yaml-cpp/yaml.h>

#include "armgen.hpp"

namespace armgen {

namespace {

/// A node of the sheet and its path (for the errors).
class Reader {
 public:
  Reader(YAML::Node n, std::string path) : node_(std::move(n)), path_(std::move(path)) {}

  const std::string& path() const { return path_; }
  std::string child_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  bool has(const std::string& key) const { return node_.IsMap() && node_[key]; }
  Reader at(const std::string& key) const {
    if (!node_.IsMap()) throw Error("sheet_value", where() + " is not a map");
    const YAML::Node n = node_[key];
    if (!n)
      throw Error("sheet_missing_field", "no " + child_path(key) + " in " + (path_.empty() ? "the sheet" : path_));
    return {n, child_path(key)};
  }
  /// The keys of a map, each one of `allowed` (sheet_unknown_field): a braced list of names, or a container.
  template <class C = std::initializer_list<const char*>>
  void only(const C& allowed) const {
    if (!node_.IsMap()) throw Error("sheet_value", where() + " is not a map");
    for (const auto& kv : node_) {
      const std::string k = kv.first.as<std::string>();
      if (std::none_of(allowed.begin(), allowed.end(), [&](const auto& a) { return k == a; }))
        throw Error("sheet_unknown_field", child_path(k) + " is not a field of the sheet (docs/arms.md)");
    }
  }
  std::string str() const {
    if (!node_.IsScalar()) throw Error("sheet_value", where() + " is not a text");
    return node_.as<std::string>();
  }
  Value value() const {
    if (!node_.IsScalar()) throw Error("sheet_value", where() + " is not a number");
    return parse_value(node_.as<std::string>(), path_);
  }
  Six six() const {
    if (!node_.IsSequence()) throw Error("sheet_value", where() + " is not a list of six values");
    if (node_.size() != 6)
      throw Error("sheet_wrong_length",
                  path_ + " has " + std::to_string(node_.size()) + " values, not 6 (one per joint)");
    Six s;
    for (std::size_t i = 0; i < 6; ++i) s[i] = Reader(node_[i], path_ + "[" + std::to_string(i) + "]").value();
    return s;
  }
  int integer(int lo, int hi) const {
    const Value v = value();
    if (v.v != static_cast<int>(v.v) || v.v < lo || v.v > hi)
      throw Error("sheet_value", path_ + " = " + v.text + ": a whole number from " + std::to_string(lo) + " to " +
                                     std::to_string(hi) + " expected");
    return static_cast<int>(v.v);
  }
  std::vector<std::pair<std::string, Reader>> entries() const {
    if (!node_.IsMap()) throw Error("sheet_value", where() + " is not a map");
    std::vector<std::pair<std::string, Reader>> out;
    for (const auto& kv : node_) {
      const std::string k = kv.first.as<std::string>();
      out.emplace_back(k, Reader(kv.second, child_path(k)));
    }
    return out;
  }
  std::vector<Reader> list() const {
    if (!node_.IsSequence()) throw Error("sheet_value", where() + " is not a list");
    std::vector<Reader> out;
    for (std::size_t i = 0; i < node_.size(); ++i) out.emplace_back(node_[i], path_ + "[" + std::to_string(i) + "]");
    return out;
  }
  /// The group's `source:` and `estimate:` texts; one of them at least (sheet_no_source).
  Text text() const {
    Text t;
    if (has("source")) t.source = at("source").str();
    if (has("estimate")) t.estimate = at("estimate").str();
    if (t.source.empty() && t.estimate.empty())
      throw Error("sheet_no_source", (path_.empty() ? std::string("the sheet") : path_) +
                                         " has neither source: (where it was published) nor estimate: (the reasoning)");
    return t;
  }

 private:
  std::string where() const { return path_.empty() ? "the sheet" : path_; }
  YAML::Node node_;
  std::string path_;
};

bool identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

void require_identifier(const std::string& s, const std::string& where) {
  if (!identifier(s)) throw Error("sheet_value", where + " = \"" + s + "\": a C++ identifier expected");
}

/// Each value of `s` > 0 (or >= 0 with `zero_ok`).
void require_positive(const Six& s, const std::string& where, bool zero_ok = false) {
  for (int i = 0; i < 6; ++i)
    if (s[i].v < 0 || (!zero_ok && s[i].v == 0))
      throw Error("sheet_value",
                  where + "[" + std::to_string(i) + "] = " + s[i].text + ": must be " + (zero_ok ? ">= 0" : "> 0"));
}
void require_positive(const Value& v, const std::string& where, bool zero_ok = false) {
  if (v.v < 0 || (!zero_ok && v.v == 0))
    throw Error("sheet_value", where + " = " + v.text + ": must be " + (zero_ok ? ">= 0" : "> 0"));
}

void read_encoders(const Reader& r, Sheet& s) {
  const Reader enc = r.at("encoders");
  enc.only({"model", "arm"});
  const Reader model = enc.at("model");
  model.only({"counts_per_motor_rev", "source", "estimate"});
  s.model_cpr = model.at("counts_per_motor_rev").value();
  require_positive(s.model_cpr, model.child_path("counts_per_motor_rev"));
  s.model_encoder_text = model.text();
  const Reader arm = enc.at("arm");
  arm.only({"name", "kind", "rad_per_count", "counts_per_motor_rev", "counts_per_joint_rev", "coupling", "source",
            "estimate"});
  s.encoder_name = arm.at("name").str();
  const std::string kind = arm.at("kind").str();
  if (kind != "incremental" && kind != "absolute")
    throw Error("sheet_value", arm.child_path("kind") + " = " + kind + ": incremental or absolute");
  s.absolute = kind == "absolute";
  int units = 0;
  for (const char* unit : {"rad_per_count", "counts_per_motor_rev", "counts_per_joint_rev"})
    if (arm.has(unit)) {
      s.encoder_unit = unit, s.encoder = arm.at(unit).six(), ++units;
      require_positive(s.encoder, arm.child_path(unit));
    }
  if (units != 1)
    throw Error(units == 0 ? "sheet_missing_field" : "sheet_value",
                arm.path() + ": one of rad_per_count, counts_per_motor_rev, counts_per_joint_rev");
  if (arm.has("coupling"))
    for (const Reader& c : arm.at("coupling").list()) {
      c.only({"joint", "motor", "c"});
      Coupling k{c.at("joint").integer(1, 6), c.at("motor").integer(1, 6), c.at("c").value()};
      if (k.joint <= k.motor)
        throw Error("sheet_value", c.path() + ": joint > motor (the coupling matrix is unit lower triangular)");
      s.coupling.push_back(k);
    }
  if (s.coupling.size() > 6)
    throw Error("sheet_value", arm.child_path("coupling") + ": at most 6 terms (kMaxCouplingTerms)");
  s.encoder_text = arm.text();
}

void read_drives(const Reader& r, Sheet& s) {
  const Reader gear = r.at("gear_ratio");
  gear.only({"value", "source", "estimate"});
  s.gear = gear.at("value").six();
  s.gear_text = gear.text();
  for (int i = 0; i < 6; ++i)
    if (s.gear[i].v == 0)
      throw Error("sheet_value", gear.child_path("value") + ": gear ratio 0 on joint " + std::to_string(i + 1));

  const Reader motor = r.at("motor_inertia");
  motor.only({"sets", "alternative", "source", "estimate"});
  if (motor.has("source") || motor.has("estimate")) s.motor_text = motor.text();
  for (const Reader& set : motor.at("sets").list()) {
    set.only({"name", "value", "source", "estimate"});
    MotorSet m{set.at("name").str(), set.at("value").six(), set.text()};
    require_identifier(m.name, set.child_path("name"));
    require_positive(m.jm, set.child_path("value"), true);
    s.motor_sets.push_back(m);
  }
  if (s.motor_sets.empty()) throw Error("sheet_missing_field", motor.child_path("sets") + " is empty");
  s.motor_alt = 0;
  if (motor.has("alternative")) {
    const std::string alt = motor.at("alternative").str();
    auto it = std::find_if(s.motor_sets.begin(), s.motor_sets.end(), [&](const MotorSet& m) { return m.name == alt; });
    if (it == s.motor_sets.end())
      throw Error("sheet_value", motor.child_path("alternative") + " = " + alt + ": no such set");
    s.motor_alt = static_cast<int>(it - s.motor_sets.begin());
  }

  read_encoders(r, s);

  const Reader dac = r.at("dac");
  dac.only({"bits", "full_scale_torque", "source", "estimate"});
  s.dac_bits = dac.at("bits").integer(2, 31);
  s.dac_full_scale = dac.at("full_scale_torque").six();
  require_positive(s.dac_full_scale, dac.child_path("full_scale_torque"));
  s.dac_text = dac.text();

  const auto six_group = [&](const char* key, Six& v, Text& t) {
    const Reader g = r.at(key);
    g.only({"value", "source", "estimate"});
    v = g.at("value").six();
    require_positive(v, g.child_path("value"));
    t = g.text();
  };
  six_group("torque_constant", s.torque_constant, s.torque_constant_text);
  six_group("motor_torque_limit", s.motor_torque_limit, s.motor_torque_limit_text);
  six_group("plausible_joint_speed", s.joint_speed, s.joint_speed_text);

  if (r.has("potentiometers")) {
    const Reader p = r.at("potentiometers");
    p.only({"bits", "min", "max", "source", "estimate"});
    s.pots = true;
    s.pot_bits = p.at("bits").integer(1, 30);
    s.pot_min = p.at("min").six();
    s.pot_max = p.at("max").six();
    for (int i = 0; i < 6; ++i)
      if (s.pot_min[i].v >= s.pot_max[i].v)
        throw Error("sheet_value", p.path() + ": min >= max on joint " + std::to_string(i + 1));
    s.pot_text = p.text();
  }
  if (r.has("index_pulses")) {
    const Reader p = r.at("index_pulses");
    p.only({"angle", "source", "estimate"});
    s.index = true;
    s.index_angle = p.at("angle").six();
    s.index_text = p.text();
  }
  if (r.has("current_monitor")) {
    const Reader p = r.at("current_monitor");
    p.only({"bits", "range", "gain", "offset", "noise", "source", "estimate"});
    s.current = true;
    s.current_bits = p.at("bits").integer(2, 16);
    s.current_range = p.at("range").value();
    s.current_gain = p.at("gain").value();
    s.current_offset = p.at("offset").value();
    s.current_noise = p.at("noise").value();
    if (s.current_range.v < 1)
      throw Error("sheet_value", p.child_path("range") + ": below 1 (the ADC must span the DAC's full-scale current)");
    for (const auto& [key, v] : {std::pair{"gain", s.current_gain}, std::pair{"offset", s.current_offset},
                                 std::pair{"noise", s.current_noise}})
      if (v.v < 0) throw Error("sheet_value", p.child_path(key) + ": negative");
    s.current_text = p.text();
  }
}

void read_friction(const Reader& r, Sheet& s) {
  const Reader f = r.at("friction");
  f.only({"presets"});
  std::set<std::string> names;
  for (const Reader& p : f.at("presets").list()) {
    FrictionPreset fp;
    fp.name = p.at("name").str();
    require_identifier(fp.name, p.child_path("name"));
    if (fp.name == "none" || !names.insert(fp.name).second)
      throw Error("sheet_value", p.child_path("name") + " = " + fp.name + ": used twice (or \"none\", the firmware's)");
    fp.motor = p.has("motor");
    if (fp.motor) {
      p.only({"name", "motor", "source", "estimate"});
      const Reader m = p.at("motor");
      m.only({"viscous", "coulomb_pos", "coulomb_neg"});
      fp.a = m.at("viscous").six(), fp.b = m.at("coulomb_pos").six(), fp.c = m.at("coulomb_neg").six();
      require_positive(fp.a, m.child_path("viscous"), true);
    } else {
      p.only({"name", "vis", "cou", "sti", "source", "estimate"});
      fp.a = p.at("vis").six(), fp.b = p.at("cou").six(), fp.c = p.at("sti").six();
      require_positive(fp.a, p.child_path("vis"), true);
      require_positive(fp.b, p.child_path("cou"), true);
      require_positive(fp.c, p.child_path("sti"), true);
    }
    fp.text = p.text();
    s.friction.push_back(fp);
  }
  if (s.friction.empty()) throw Error("sheet_missing_field", "friction.presets is empty");

  const Reader b = r.at("model_error_bounds");
  b.only({"link_inertia", "amp_gain", "amp_offset", "ripple", "amp_lag", "encoder_edge", "friction_band", "source",
          "estimate"});
  const std::pair<const char*, Value*> scalars[] = {
      {"link_inertia", &s.link_inertia}, {"amp_gain", &s.amp_gain},
      {"amp_offset", &s.amp_offset},     {"ripple", &s.ripple},
      {"amp_lag", &s.amp_lag},           {"encoder_edge", &s.encoder_edge}};
  for (const auto& [key, v] : scalars) {
    *v = b.at(key).value();
    require_positive(*v, b.child_path(key), true);
  }
  const Reader band = b.at("friction_band");
  band.only({"presets", "drift"});
  for (const Reader& n : band.at("presets").list()) {
    const std::string name = n.str();
    if (!names.count(name)) throw Error("sheet_value", n.path() + " = " + name + ": no such friction preset");
    s.band.push_back(name);
  }
  if (s.band.empty()) throw Error("sheet_missing_field", band.child_path("presets") + " is empty");
  s.drift = band.at("drift").value();
  require_positive(s.drift, band.child_path("drift"), true);
  s.bounds_text = b.text();
}

Pose read_pose(const Reader& p, bool named) {
  Pose pose;
  if (named) {
    pose.name = p.at("name").str();
    if (pose.name.empty()) throw Error("sheet_value", p.child_path("name") + " is empty");
    pose.doc = p.at("doc").str();
  } else if (p.has("doc")) {
    pose.doc = p.at("doc").str();
  }
  if (p.has("symbol") || !named) {
    pose.symbol = p.at("symbol").str();
    require_identifier(pose.symbol, p.child_path("symbol"));
  }
  pose.q = p.at("q").six();
  return pose;
}

void read_poses(const Reader& r, Sheet& s) {
  const Reader poses = r.at("poses");
  poses.only({"start", "named", "reference"});
  const Reader start = poses.at("start");
  start.only({"name", "q", "doc", "source", "estimate"});
  s.start = read_pose(start, true);
  s.start_text = start.text();
  std::set<std::string> names{s.start.name}, symbols;
  if (poses.has("named")) {
    const Reader named = poses.at("named");
    named.only({"list", "source", "estimate"});
    s.named_text = named.text();
    for (const Reader& p : named.at("list").list()) {
      p.only({"name", "q", "doc", "symbol"});
      s.named.push_back(read_pose(p, true));
      if (!names.insert(s.named.back().name).second)
        throw Error("sheet_value", p.child_path("name") + " = " + s.named.back().name + ": used twice");
    }
  }
  if (s.named.size() + 1 > 255)
    throw Error("sheet_value", "poses: more than 255 named poses (a pose's code is a byte)");
  if (poses.has("reference")) {
    const Reader ref = poses.at("reference");
    ref.only({"list", "source", "estimate"});
    s.reference_text = ref.text();
    for (const Reader& p : ref.at("list").list()) {
      p.only({"symbol", "q", "doc"});
      s.reference.push_back(read_pose(p, false));
    }
  }
  for (const std::vector<Pose>* list : {&s.named, &s.reference})
    for (const Pose& p : *list)
      if (!p.symbol.empty() && (p.symbol == "kQStart" || !symbols.insert(p.symbol).second))
        throw Error("sheet_value", "poses: the symbol " + p.symbol + " is used twice");
}

/// A group of positive numbers with its source: each key's value into its field; its text.
Text positive_group(const Reader& r, const char* group, std::initializer_list<std::pair<const char*, Value*>> fields) {
  const Reader g = r.at(group);
  std::vector<const char*> keys{"source", "estimate"};
  for (const auto& [key, v] : fields) keys.push_back(key);
  g.only(keys);
  for (const auto& [key, v] : fields) {
    *v = g.at(key).value();
    require_positive(*v, g.child_path(key));
  }
  return g.text();
}

void read_rest(const Reader& r, Sheet& s) {
  const Reader op = r.at("operational_point");
  op.only({"frame", "xyz", "rpy", "source", "estimate"});
  if (op.has("frame")) s.op_frame = op.at("frame").str();
  for (const char* key : {"xyz", "rpy"}) {
    std::array<Value, 3>& v = key[0] == 'x' ? s.op_xyz : s.op_rpy;
    if (!op.has(key)) continue;
    const std::vector<Reader> l = op.at(key).list();
    if (l.size() != 3)
      throw Error("sheet_wrong_length", op.child_path(key) + " has " + std::to_string(l.size()) + " values, not 3");
    for (int i = 0; i < 3; ++i) v[i] = l[i].value();
  }
  s.op_text = op.text();

  s.cart_text =
      positive_group(r, "cartesian_maxima",
                     {{"velocity", &s.cart_velocity}, {"acceleration", &s.cart_acceleration}, {"jerk", &s.cart_jerk}});
  s.payload_text = positive_group(
      r, "payload", {{"mass", &s.payload_mass}, {"com_reach", &s.payload_com_reach}, {"inertia", &s.payload_inertia}});
}

}  // namespace

Sheet read_sheet(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw Error("sheet_parse", path + ": " + e.what());
  }
  const Reader r(root, "");
  r.only({"arm",
          "name",
          "urdf",
          "about",
          "kinematics",
          "joint_limits",
          "inertial_exceptions",
          "gravity",
          "gear_ratio",
          "motor_inertia",
          "encoders",
          "dac",
          "torque_constant",
          "motor_torque_limit",
          "plausible_joint_speed",
          "potentiometers",
          "index_pulses",
          "current_monitor",
          "friction",
          "model_error_bounds",
          "poses",
          "operational_point",
          "cartesian_maxima",
          "payload"});
  Sheet s;
  s.path = path;
  s.arm = r.at("arm").str();
  require_identifier(s.arm, "arm");
  s.name = r.at("name").str();
  s.urdf = r.at("urdf").str();
  if (r.has("about")) s.about = r.at("about").str();
  s.kinematics = r.at("kinematics").text();
  r.at("kinematics").only({"source", "estimate"});
  s.joint_limits = r.at("joint_limits").text();
  r.at("joint_limits").only({"source", "estimate"});
  if (r.has("inertial_exceptions"))
    for (const auto& [link, why] : r.at("inertial_exceptions").entries()) {
      why.only({"source", "estimate"});
      s.inertial_exceptions[link] = why.text();
    }
  const Reader g = r.at("gravity");
  g.only({"value", "source", "estimate"});
  s.gravity = g.at("value").value();
  require_positive(s.gravity, "gravity.value");
  s.gravity_text = g.text();
  read_drives(r, s);
  read_friction(r, s);
  read_poses(r, s);
  read_rest(r, s);
  return s;
}

}  // namespace armgen
