// The fault catalogue (osc/control/faults.hpp): the bits, names and meanings made from one list. The
// bits are the fault word of the link, the supervisor's latch and the clients' decoding: against the
// catalogue written out here in bit order (docs/safety.md), a word named by its lowest bit.
#include <gtest/gtest.h>

#include <cctype>
#include <cstdint>
#include <cstring>
#include <set>
#include <string>

#include "osc/control/faults.hpp"

using namespace osc;

namespace {

TEST(Faults, TheBitsAreTheCatalogueInOrderAndTheMaskIsEveryBit) {
  const char* const names[] = {
      "non_finite",   "encoder_jump",  "saturation",      "singular",  "overrun",           "link_lost",
      "link_corrupt", "encoder_range", "encoder_stuck",   "tracking",  "theta_bounds",      "estop",
      "overflow",     "dac_bus",       "drive_fault",     "collision", "position_mismatch", "index_missing",
      "unstable",     "current_sense", "payload_mismatch"};
  ASSERT_EQ(kFaultCount, 21);
  ASSERT_EQ(static_cast<int>(sizeof(names) / sizeof(*names)), kFaultCount);
  std::set<std::string> seen;
  for (int i = 0; i < kFaultCount; ++i) {
    EXPECT_STREQ(kFaultNames[i], names[i]) << "bit " << i;
    EXPECT_STREQ(fault_name(1u << i), names[i]) << "bit " << i;
    EXPECT_TRUE(seen.insert(kFaultNames[i]).second) << kFaultNames[i] << " twice";
    for (const char* c = kFaultNames[i]; *c; ++c)
      EXPECT_TRUE(std::islower(static_cast<unsigned char>(*c)) || *c == '_') << kFaultNames[i];
    EXPECT_GT(std::strlen(kFaultDocs[i]), 10u) << kFaultNames[i];
  }
  // The enumerators are the bits of their names: the first, one in the middle, the last.
  EXPECT_EQ(kFaultNonFinite, 1u);
  EXPECT_EQ(kFaultLinkLost | kFaultLinkCorrupt, 0x60u);
  EXPECT_EQ(kFaultIndexMissing, 1u << 17);
  EXPECT_EQ(kFaultUnstable, 1u << 18);
  EXPECT_EQ(kFaultCurrentSense, 1u << 19);
  EXPECT_EQ(kAllFaults, 0x1FFFFFu);  // 21 bits, nothing above
}

TEST(Faults, AWordIsNamedByItsLowestBit) {
  EXPECT_STREQ(fault_name(0), "none");
  EXPECT_STREQ(fault_name(kFaultEstop | kFaultTracking), "tracking");
  EXPECT_STREQ(fault_name(kFaultIndexMissing | kFaultOverflow | kFaultDacBus), "overflow");
  EXPECT_STREQ(fault_name(kAllFaults), "non_finite");
}

}  // namespace
