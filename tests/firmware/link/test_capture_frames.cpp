// The capture's frames and lists (osc/link/capture_frames.hpp): the payload lengths, fixed and within the
// largest frame; every list's names distinct and non-empty; each signal's elements as its field in the task
// holds them; a capture_data frame's values through the encoder and the parser, bit for bit.
#include <gtest/gtest.h>

#include <cstring>
#include <set>
#include <string>

#include "frame_bytes.hpp"
#include "osc/link/capture_frames.hpp"
#include "osc/link/frames.hpp"

using namespace osc::test;

namespace {

TEST(CaptureFrames, PayloadLengthsFixedWithinTheLargestFrame) {
  EXPECT_EQ(pil::kCaptureFrame, 12);
  EXPECT_EQ(pil::kCaptureDataFrame, 13);
  EXPECT_EQ(pil::kCapturePayload, 4 + 1 + 1 + 8 + 8 + 1 + 1 + 4 + 4 + 1 + 4);
  EXPECT_EQ(pil::kCaptureDataPayload,
            4 + 1 + 1 + 1 + 1 + 8 + 8 + 1 + 1 + 4 + 4 + 4 + 4 + 4 + 1 + 4 * pil::kCaptureChunk);
  EXPECT_LE(pil::kCaptureDataPayload, pil::kMaxPayload);
  // A done capture's every value is readable: offsets and counts fit their fields.
  EXPECT_LE(pil::kCaptureChunk, 255);
  EXPECT_EQ(pil::kCaptureValues % pil::kCaptureChannels, 0);
}

template <int N>
void expect_distinct(const char* const (&names)[N]) {
  std::set<std::string> seen;
  for (const char* n : names) {
    EXPECT_GT(std::strlen(n), 0u);
    EXPECT_TRUE(seen.insert(n).second) << n;
  }
}

TEST(CaptureFrames, ListsNamedOnceEach) {
  expect_distinct(pil::kCaptureOpNames);
  expect_distinct(pil::kCaptureTriggerNames);
  expect_distinct(pil::kCaptureStateNames);
  expect_distinct(pil::kCaptureStatusNames);
  std::set<std::string> seen;
  for (const pil::CaptureSignalInfo& s : pil::kCaptureSignals) {
    EXPECT_TRUE(seen.insert(s.name).second) << s.name;
    EXPECT_GT(std::strlen(s.doc), 0u) << s.name;
    EXPECT_LT(s.elements, 256) << s.name;  // an element is a byte
  }
  // The element counts of the task's fields: 6 pose coordinates, a joint each, theta's 3 per joint, the stages.
  EXPECT_EQ(pil::kCaptureSignals[pil::kCaptureSignalError].elements, 6);
  EXPECT_EQ(pil::kCaptureSignals[pil::kCaptureSignalResidual].elements, osc::kDof);
  EXPECT_EQ(pil::kCaptureSignals[pil::kCaptureSignalThetaHat].elements, 3 * osc::kDof);
  EXPECT_EQ(pil::kCaptureSignals[pil::kCaptureSignalStageCycles].elements, osc::kTickStages);
}

TEST(CaptureFrames, DataValuesRoundTripBitForBit) {
  pil::CaptureDataFrame a;
  a.id = 0xA1B2C3D4u;
  a.op = pil::kCaptureOpRead;
  a.state = pil::kCaptureStateDone;
  a.channels = 3;
  a.signal[2] = pil::kCaptureSignalResidual;
  a.element[2] = 5;
  a.trigger_tick = 0xFFFFFFF0u;
  a.first_tick = 0xFFFFFF00u;
  a.offset = 4095;
  a.count = pil::kCaptureChunk;
  for (int k = 0; k < pil::kCaptureChunk; ++k)
    a.values[k] = k % 2 ? -1.0f / static_cast<float>(k) : 1e-30f * static_cast<float>(k);
  const pil::Parser p = parsed(bytes_of(a));
  pil::CaptureDataFrame b;
  ASSERT_TRUE(p.decode(b));
  EXPECT_EQ(std::memcmp(b.values, a.values, sizeof a.values), 0);
  EXPECT_EQ(b.id, a.id);
  EXPECT_EQ(b.trigger_tick, a.trigger_tick);
  EXPECT_EQ(b.first_tick, a.first_tick);
  EXPECT_EQ(b.offset, a.offset);
  EXPECT_EQ(b.signal[2], a.signal[2]);
  EXPECT_EQ(b.element[2], a.element[2]);
  pil::CaptureFrame c;
  EXPECT_FALSE(p.decode(c));  // a type of its own
}

}  // namespace
