// The experiment's controller.<key> entries come from the gains' one list (OSC_GAINS_FIELDS): every
// gain with a key is a configuration key with its range, unit and paper value; the others are not.
#include <gtest/gtest.h>

#include <charconv>
#include <string>

#include "config.hpp"

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
    const auto value = [&p](double v) {
      const std::string n = number(v);
      return p.form == osc::GainForm::kPerAxis ? "[" + n + ", " + n + ", " + n + ", " + n + ", " + n + ", " + n + "]"
                                               : n;
    };
    sim::Settings s;
    std::string err;
    const std::string key = std::string("controller.") + p.key;
    EXPECT_TRUE(sim::set_key(key, value(p.hi), s, err)) << err;
    EXPECT_FALSE(sim::set_key(key, value(p.hi * 2 + 1), s, err)) << key;
    EXPECT_NE(err.find("out of range"), std::string::npos) << err;
  }
}

}  // namespace
