// The experiment's controller.<key> entries come from the gains' one list (OSC_GAINS_FIELDS): every
// gain with a key is a configuration key with its range, unit and paper value; the others are not.
#include <gtest/gtest.h>

#include <charconv>
#include <string>

#include "config.hpp"
#include "experiment.hpp"

namespace {

/// The printed configuration's line of a key of the controller section ("" if there is none).
std::string controller_line(const std::string& yaml, const std::string& key) {
  const std::string at = "\n  " + key + ": ";
  const auto section = yaml.find("\ncontroller:\n");
  const auto p = yaml.find(at, section);
  if (section == std::string::npos || p == std::string::npos || yaml.find("\ntrajectory:", section) < p) return "";
  return yaml.substr(p + 1, yaml.find('\n', p + 1) - p - 1);
}

/// As the configuration prints numbers: the shortest text that reads back.
std::string number(double v) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

TEST(GainKeys, EveryGainWithAKeyIsAControllerEntryWithItsRangeAndUnit) {
  const std::string yaml = sim::config_yaml(sim::Settings{});
  int keys = 0;
  for (const osc::GainInfo& g : osc::kGainInfo) {
    const osc::GainParam& p = g.param;
    const std::string line = controller_line(yaml, p.key);
    if (p.form == osc::GainForm::kNone) {
      EXPECT_EQ(line, "") << g.name;
      continue;
    }
    ++keys;
    ASSERT_NE(line, "") << g.name << ": no controller." << p.key;
    EXPECT_LT(p.lo, p.hi) << g.name;
    EXPECT_NE(line.find(std::string("# ") + g.doc), std::string::npos) << line;
    if (*p.unit) {
      EXPECT_NE(line.find(std::string(" [") + p.unit + "]; "), std::string::npos) << line;
    }
    if (p.lo_each)  // each element's range: the translations', the rotations'
      EXPECT_NE(line.find("; x y z [" + number(p.lo_of(0)) + ", " + number(p.hi_of(0)) + "], rotations [" +
                          number(p.lo_of(3)) + ", " + number(p.hi_of(3)) + "]"),
                std::string::npos)
          << line;
    else
      EXPECT_NE(line.find("; [" + number(p.lo) + ", " + number(p.hi) + "]"), std::string::npos) << line;
    // The paper's value is inside the range, so that the printed configuration reads back.
    std::string err;
    sim::Settings s;
    const std::string value = line.substr(line.find(": ") + 2, line.find("  #") - line.find(": ") - 2);
    EXPECT_TRUE(sim::set_key("controller." + std::string(p.key), value, s, err)) << err;
  }
  EXPECT_EQ(keys, 7);  // knd, k, ks, ki, k_ad, tau_dec, leakage
}

TEST(GainKeys, ARangeIsEnforcedAtItsBounds) {
  for (const osc::GainInfo& g : osc::kGainInfo) {
    const osc::GainParam& p = g.param;
    if (p.form == osc::GainForm::kNone) continue;
    // Every element at its bound (scaled, shifted): a list of six, or the number.
    const auto value = [&p](bool hi, double scale, double shift) {
      if (p.form != osc::GainForm::kPerAxis) return number((hi ? p.hi : p.lo) * scale + shift);
      std::string t = "[";
      for (int e = 0; e < 6; ++e) t += (e ? ", " : "") + number((hi ? p.hi_of(e) : p.lo_of(e)) * scale + shift);
      return t + "]";
    };
    sim::Settings s;
    std::string err;
    const std::string key = std::string("controller.") + p.key;
    EXPECT_TRUE(sim::set_key(key, value(true, 1, 0), s, err)) << err;
    EXPECT_TRUE(sim::set_key(key, value(false, 1, 0), s, err)) << err;
    EXPECT_FALSE(sim::set_key(key, value(true, 2, 1), s, err)) << key;
    EXPECT_NE(err.find("out of range"), std::string::npos) << err;
    if (p.lo > 0) {
      EXPECT_FALSE(sim::set_key(key, value(false, 0.5, 0), s, err)) << key;
      EXPECT_NE(err.find("out of range"), std::string::npos) << err;
    }
  }
}

/// A list of the parameter's elements at their bound (hi: the top; otherwise the bottom), scaled.
std::string bounds_text(const osc::ParamInfo& p, bool hi, double scale, double shift = 0) {
  std::string t = p.count > 1 ? "[" : "";
  for (int e = 0; e < p.count; ++e) t += (e ? ", " : "") + number((hi ? p.hi_of(e) : p.lo_of(e)) * scale + shift);
  return t + (p.count > 1 ? "]" : "");
}

// Every runtime parameter of the firmware's table (osc/runtime/parameters.hpp) is a host key: its own
// (a law's or a reaction's name: as many names as codes; the thresholds: each joint's range), or
// run.<name> made from the table with each element's range and the table's default.
TEST(GainKeys, EveryRuntimeParameterIsAHostKeyWithTheTablesRanges) {
  const std::string yaml = sim::config_yaml(sim::Settings{});
  int generated = 0;
  for (int i = 0; i < osc::kParamCount; ++i) {
    const osc::ParamInfo& p = osc::kParams[i];
    if (p.gain >= 0) {
      EXPECT_NE(controller_line(yaml, p.name), "") << p.name;  // the gains' entries (the test above)
      continue;
    }
    const char* own = sim::runtime_param_key(p.runtime);
    const std::string key = own ? own : std::string("run.") + p.name;
    EXPECT_NE(yaml.find("\n  " + key.substr(4) + ": "), std::string::npos) << key;
    sim::Settings s;
    std::string err;
    if (p.runtime == osc::RuntimeParam::kParamAdaptation) {
      EXPECT_EQ(p.hi + 1, osc::kAdaptationLawCount);
      for (int k = 0; k < osc::kAdaptationLawCount; ++k)
        EXPECT_TRUE(sim::set_key(key, osc::kAdaptationLawNames[k], s, err)) << err;
      continue;
    }
    if (p.runtime == osc::RuntimeParam::kParamResidualMonitor) {  // trial (0) or on (1)
      EXPECT_EQ(p.hi, 1);
      EXPECT_TRUE(sim::set_key(key, "on", s, err)) << err;
      EXPECT_TRUE(s.base.residual_monitor);
      EXPECT_TRUE(sim::set_key(key, "trial", s, err)) << err;
      EXPECT_FALSE(s.base.residual_monitor);
      EXPECT_FALSE(sim::set_key(key, "1", s, err));
      continue;
    }
    if (p.runtime == osc::RuntimeParam::kParamCollisionReaction) {
      EXPECT_EQ(p.hi + 1, osc::MotionNames<osc::CollisionReaction>::kCount);
      for (int k = 0; k < osc::MotionNames<osc::CollisionReaction>::kCount; ++k)
        EXPECT_TRUE(sim::set_key(key, osc::MotionNames<osc::CollisionReaction>::kNames[k], s, err)) << err;
      continue;
    }
    // A number or a list: each element's range is the table's, at both ends (a payload's inertia with
    // every product at its bottom is no body's: refused by name).
    EXPECT_TRUE(sim::set_key(key, bounds_text(p, true, 1), s, err)) << key << ": " << err;
    if (p.runtime == osc::RuntimeParam::kParamPayloadInertia) {
      EXPECT_FALSE(sim::set_key(key, bounds_text(p, false, 1), s, err)) << key;
      EXPECT_NE(err.find("not_physical"), std::string::npos) << err;
    } else {
      EXPECT_TRUE(sim::set_key(key, bounds_text(p, false, 1), s, err)) << key << ": " << err;
    }
    EXPECT_FALSE(sim::set_key(key, bounds_text(p, true, 1.001, 1e-6), s, err)) << key;
    EXPECT_NE(err.find("out of range"), std::string::npos) << err;
    EXPECT_FALSE(sim::set_key(key, bounds_text(p, false, 1, -1e-3), s, err)) << key;
    if (own) continue;
    ++generated;
    // Its default is the table's, as the host's configuration prints it.
    std::string def = p.count > 1 ? "[" : "";
    for (int e = 0; e < p.count; ++e) def += (e ? ", " : "") + number(osc::param_default(i, e));
    def += p.count > 1 ? "]" : "";
    EXPECT_NE(yaml.find("\n  " + key.substr(4) + ": " + def), std::string::npos) << key << " default " << def;
  }
  // move_linear, move_angular, stream_timeout, pots, home_speed, drive_check, dither_amplitude, dither_half_period,
  // payload_mass, payload_com, payload_inertia, payload_allowance, armature_correction, friction_vis, friction_cou,
  // friction_sti
  EXPECT_EQ(generated, 16);
}

}  // namespace
