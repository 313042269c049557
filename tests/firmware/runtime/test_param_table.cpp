// The runtime parameter table (osc/runtime/param_table.hpp): one declaration, the gains first with their
// keys, ranges and units, then the runtime list; the layout version that stored records carry.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "osc/runtime/param_table.hpp"
#include "osc/runtime/parameters.hpp"

namespace {

using namespace osc;

TEST(Parameters, OneTableGainsFirstThenTheRuntimeList) {
  std::set<std::string> names;
  int gains = 0, slots = 0;
  for (int i = 0; i < kParamCount; ++i) {
    const ParamInfo& p = kParams[i];
    EXPECT_TRUE(names.insert(p.name).second) << p.name << " twice";
    EXPECT_EQ(param_index(p.name), i);
    EXPECT_EQ(param_slot(i), slots);
    slots += p.count;
    EXPECT_TRUE(p.count >= 1 && p.count <= kDof) << p.name;
    for (int e = 0; e < p.count; ++e) {
      // A range of one value only where the arm lacks what the parameter turns on (pots: 0 without pots).
      if (std::string(p.name) == "pots" && !has_pots(robot::kDriveTrain)) {
        EXPECT_EQ(p.hi_of(e), 0.0) << p.name;
      } else {
        EXPECT_LT(p.lo_of(e), p.hi_of(e)) << p.name;
      }
      EXPECT_EQ(param_value_status(i, e, param_default(i, e)), ParamStatus::kOk) << p.name << "[" << e << "]";
    }
    if (p.gain >= 0) {
      // The gains come first, with their key, range and unit from OSC_GAINS_FIELDS.
      EXPECT_EQ(i, gains++);
      const GainParam& g = kGainInfo[p.gain].param;
      EXPECT_STREQ(p.name, g.key);
      EXPECT_EQ(p.lo, g.lo);
      EXPECT_EQ(p.hi, g.hi);
      EXPECT_STREQ(p.unit, g.unit);
      EXPECT_EQ(p.access, ParamAccess::kTorqueOff);
    }
  }
  EXPECT_EQ(gains, 7);  // knd, k, ks, ki, k_ad, tau_dec, leakage: the host's controller.* keys
  EXPECT_EQ(slots, kParamSlots);
  EXPECT_EQ(kParamSlots, 4 * 6 + 3 + (1 + 3 + 3 + 1 + 6 + 1 + 1 + 2 + 1 + 1 + 1 + 1) + (1 + 3 + 6 + 1) + 6 +
                             18);  // + the payload and its allowance, the armature, theta^
  EXPECT_EQ(param_index("no_such"), -1);
  EXPECT_LT(kParamCount, 256);  // an index fits the frame's byte
}

TEST(Parameters, LayoutVersionIsOfTheTable) {
  EXPECT_NE(kParamLayout, 0);
  // A fixed value: a change of any name or element count changes it, and this test with it (the
  // stored records of the old table are then not loaded: layout_mismatch).
  EXPECT_EQ(kParamLayout, 59115);
}

}  // namespace
