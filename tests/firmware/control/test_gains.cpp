// The controller's parameters (osc/control/gains.hpp): the adaptation laws' names both ways; each gain a
// user may set with the range the tables take (the element's own where the axes' differ, the widest of
// them otherwise), its paper value within it; a cast to another scalar and back keeps each value to that
// scalar's resolution and each choice as it was.
#include <gtest/gtest.h>

#include <cstring>

#include "osc/control/gains.hpp"
#include "osc/math/fixed.hpp"

using namespace osc;

namespace {

TEST(Gains, EachLawHasANameAndEachNameItsLaw) {
  ASSERT_EQ(kAdaptationLawCount, 3);
  for (AdaptationLaw law : {AdaptationLaw::kPaper, AdaptationLaw::kRobust, AdaptationLaw::kMomentum}) {
    AdaptationLaw back = law == AdaptationLaw::kPaper ? AdaptationLaw::kRobust : AdaptationLaw::kPaper;
    ASSERT_TRUE(adaptation_law_from_name(adaptation_law_name(law), back)) << adaptation_law_name(law);
    EXPECT_EQ(back, law);
  }
  AdaptationLaw law = AdaptationLaw::kRobust;
  EXPECT_TRUE(adaptation_law_from_name("momentum", law));
  EXPECT_EQ(law, AdaptationLaw::kMomentum);
  for (const char* none : {"Momentum", "", "paper ", "robust_law"}) {
    EXPECT_FALSE(adaptation_law_from_name(none, law)) << none;
    EXPECT_EQ(law, AdaptationLaw::kMomentum) << "a name of no law leaves it";
  }
  EXPECT_STREQ(kModelRateNames[static_cast<int>(ModelRate::kEveryStep)], "every_step");
  EXPECT_STREQ(kModelRateNames[static_cast<int>(ModelRate::kAlternate)], "alternate");
}

TEST(Gains, EachSettableGainHasItsRangeAndItsPaperValueWithinIt) {
  // The list's order: the gains of (69), then K_ad and tau_dec; dt is a build constant.
  ASSERT_STREQ(kGainInfo[0].name, "knd");
  ASSERT_STREQ(kGainInfo[3].name, "ki");
  ASSERT_STREQ(kGainInfo[4].param.key, "k_ad");
  ASSERT_STREQ(kGainInfo[5].param.key, "tau_dec");
  EXPECT_EQ(kGainInfo[6].param.form, GainForm::kNone);  // dt
  // Per axis with the axes' own ranges: k's translations from 1, its rotations from 25; the whole range
  // spans both.
  const GainParam& k = kGainInfo[1].param;
  EXPECT_EQ(k.form, GainForm::kPerAxis);
  EXPECT_EQ(k.lo_of(0), 1.0);
  EXPECT_EQ(k.lo_of(3), 25.0);
  EXPECT_EQ(k.lo, 1.0);
  EXPECT_EQ(k.hi, 1000.0);
  const GainParam& ki = kGainInfo[3].param;
  EXPECT_EQ(ki.hi_of(2), 1e5);
  EXPECT_EQ(ki.hi_of(5), 3500.0);
  EXPECT_EQ(ki.hi, 1e5);
  EXPECT_EQ(kGainInfo[5].param.form, GainForm::kEvery);
  EXPECT_EQ(kGainInfo[5].param.lo_of(4), 0.01);  // no own ranges: every element the one range
  const Gains<double> g = Gains<double>::paper();
  const Vec6<double>* per_axis[] = {&g.knd, &g.k, &g.ks, &g.ki};
  for (int n = 0; n < 4; ++n)
    for (int e = 0; e < kDof; ++e) {
      const GainParam& p = kGainInfo[n].param;
      EXPECT_LE(p.lo_of(e), (*per_axis[n])(e)) << p.key << "[" << e << "]";
      EXPECT_GE(p.hi_of(e), (*per_axis[n])(e)) << p.key << "[" << e << "]";
    }
  EXPECT_TRUE(g.kad >= kGainInfo[4].param.lo && g.kad <= kGainInfo[4].param.hi);
  EXPECT_TRUE(g.tau_dec(0) >= kGainInfo[5].param.lo && g.tau_dec(0) <= kGainInfo[5].param.hi);
  EXPECT_TRUE(g.leakage >= kGainInfo[11].param.lo && g.leakage <= kGainInfo[11].param.hi);
}

TEST(Gains, ACastKeepsEachValueToItsScalarsResolutionAndEachChoice) {
  Gains<double> g = Gains<double>::paper();
  g.adaptation = AdaptationLaw::kRobust;  // not the default: kept, not made again
  g.model_rate = ModelRate::kEveryStep;
  g.kad = 123.456;
  const Gains<double> f = g.cast<float>().cast<double>(), q = g.cast<Fixed>().cast<double>();
  EXPECT_EQ(f.adaptation, AdaptationLaw::kRobust);
  EXPECT_EQ(q.model_rate, ModelRate::kEveryStep);
  EXPECT_NEAR(f.kad, 123.456, 123.456 * 6e-8);
  EXPECT_NEAR(q.kad, 123.456, 0.5 / (1 << 19));  // Q12.19: half an LSB
  EXPECT_NEAR(q.dt, 1e-3, 0.5 / (1 << 19));
  for (int i = 0; i < kDof; ++i) {
    EXPECT_EQ(f.knd(i), g.knd(i)) << i;  // small integers: exact in float
    EXPECT_NEAR(q.ki(i), g.ki(i), 0.5 / (1 << 19)) << i;
  }
  for (int i = 0; i < 18; ++i) EXPECT_NEAR(q.theta_max(i), g.theta_max(i), 0.5 / (1 << 19)) << i;
  EXPECT_NEAR(q.trajectory.amplitude, g.trajectory.amplitude, 0.5 / (1 << 19));
}

}  // namespace
