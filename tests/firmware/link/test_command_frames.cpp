// The command protocol's payloads (osc/link/command_frames.hpp, made by osc/link/frames.hpp): the payload
// lengths, each fitting its byte; the command and state frames field by field through the encoder and the
// parser; every command flag and every combination.
#include <gtest/gtest.h>

#include <cstring>

#include "frame_bytes.hpp"
#include "osc/link/command_frames.hpp"
#include "osc/link/commands.hpp"

using namespace osc;
using namespace osc::test;

namespace {

// ---------------------------------------------------------------- layouts

TEST(CommandFrames, PayloadLengthsFixedAndEachFitsItsByte) {
  // The sensor and actuator frames (the QEMU PIL tests and the boards depend on them): the actuator
  // frame grew by 12 bytes when the tick's stages went from 5 to 8 (issue 54: stage_cycles), the sensor
  // frame by 13 with the amplifiers' currents and fault lines (issue 56: currents, drive).
  EXPECT_EQ(pil::kSensorPayload, 4 + 24 + 12 + 1 + 1);
  EXPECT_EQ(pil::kActuatorPayload, 217);
  EXPECT_EQ(pil::kMaxFrame, 223);
  EXPECT_EQ(pil::kSensorFrame, 1);
  EXPECT_EQ(pil::kActuatorFrame, 2);
  // The new ones: fixed lengths (a change is a protocol change: docs/protocol.md).
  EXPECT_EQ(pil::kCommandFrame, 3);
  EXPECT_EQ(pil::kAnswerFrame, 4);
  EXPECT_EQ(pil::kStateFrame, 5);
  EXPECT_EQ(pil::kSetpointFrame, 6);
  EXPECT_EQ(pil::kTraceFrame, 7);
  EXPECT_EQ(pil::kSetpointVelocityFrame, 8);
  EXPECT_EQ(pil::kSetpointVelocityPayload, 4 + 1 + 12 + 12 + 24);
  EXPECT_EQ(pil::kCommandPayload, 4 + 1 + 1 + 12 + 12 + 24 + 1);
  EXPECT_EQ(pil::kSetpointPayload, 4 + 1 + 12 + 12);
  EXPECT_EQ(pil::kAnswerPayload, 4 + 1 + 1 + 1 + 4 + 4 + 4 + 1 + 1 + 1 + 1 + 1 + 4);
  EXPECT_EQ(pil::kStatePayload, 1 + 1 + 4 + 1 + 4 + 4 + 24 + 24 + 4 + 4 * pil::kLinkErrorKinds + 1 + 1);
  EXPECT_EQ(pil::kTracePayload, 4 + 4 + 1 + 3 * 24 + 36);
  EXPECT_EQ(pil::kParamFrame, 9);
  EXPECT_EQ(pil::kParamAnswerFrame, 10);
  EXPECT_EQ(pil::kParamPayload, 4 + 1 + 1 + 1 + 4);
  EXPECT_EQ(pil::kParamAnswerPayload,
            4 + 1 + 1 + 1 + 1 + 1 + 1 + 4 + 4 + 4 + 4 + 16);  // margins: observer, b bound, (37), loop
  // The identify run's estimate (issue 57): as long as the actuator frame, the largest.
  EXPECT_EQ(pil::kIdentifyFrame, 11);
  EXPECT_EQ(pil::kIdentifyPayload, 4 + 1 + 4 + 4 + 4 + 4 + 72 + 72 + 4 + 24 + 24);
  // The capture's request and answer (issue 58): test_capture_frames.cpp.
  // The identify run's payload estimate (issue 57): id, status, mass, com, inertia, pi's sd, identified.
  EXPECT_EQ(pil::kIdentifyPayloadFrame, 14);
  EXPECT_EQ(pil::kIdentifyPayloadPayload, 4 + 1 + 4 + 12 + 24 + 40 + 4);
  // Each drive's torque offset from the run (issue 57): id, status, offset, its sd.
  EXPECT_EQ(pil::kIdentifyOffsetFrame, 15);
  EXPECT_EQ(pil::kIdentifyOffsetPayload, 4 + 1 + 24 + 24);
  ASSERT_EQ(pil::kFrameTypes, 15);
  for (const pil::FrameInfo& f : pil::kFrames) {
    EXPECT_LT(f.payload, 256) << f.name;
    EXPECT_LE(f.payload, pil::kActuatorPayload) << f.name;
    EXPECT_EQ(pil::payload_length(f.type), f.payload) << f.name;
    int bytes = 0;
    for (int i = 0; i < f.field_count; ++i) bytes += f.fields[i].bytes;
    EXPECT_EQ(bytes, f.payload) << f.name;
  }
  for (int t : {0, 16, 17, 0x5A, 0xA5, 255}) EXPECT_EQ(pil::payload_length(static_cast<std::uint8_t>(t)), -1) << t;
}

// ---------------------------------------------------------------- round trips

TEST(CommandFrames, CommandRoundTripsFieldByField) {
  const pil::CommandFrame f = move_frame();
  const Bytes b = bytes_of(f);
  EXPECT_EQ(b.size(), static_cast<std::size_t>(pil::kCommandPayload + pil::kOverhead));
  EXPECT_EQ(b[2], pil::kCommandFrame);
  const pil::CommandFrame g = decoded<pil::CommandFrame>(parsed(b));
  EXPECT_EQ(g.id, f.id);
  EXPECT_EQ(g.verb, f.verb);
  EXPECT_EQ(g.flags, f.flags);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(g.position[i], f.position[i]);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(g.rpy[i], f.rpy[i]);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(g.limits[i], f.limits[i]);
  // Little-endian, in the order of the field list: id at 4, verb at 8, flags at 9, position at 10.
  EXPECT_EQ(b[4], 0x04);
  EXPECT_EQ(b[7], 0x01);
  EXPECT_EQ(b[8], static_cast<std::uint8_t>(MotionVerb::kMoveTo));
  EXPECT_EQ(b[9], f.flags);
  float x;
  std::memcpy(&x, &b[10], 4);
  EXPECT_EQ(x, 0.45f);
}

TEST(CommandFrames, EveryFlagAndEveryCombination) {
  ASSERT_EQ(pil::kCommandFlagCount, 5);
  EXPECT_STREQ(pil::kCommandFlagNames[pil::kFlagBitRelative], "relative");
  EXPECT_STREQ(pil::kCommandFlagNames[pil::kFlagBitHasRpy], "has_rpy");
  EXPECT_STREQ(pil::kCommandFlagNames[pil::kFlagBitReplace], "replace");
  EXPECT_STREQ(pil::kCommandFlagNames[pil::kFlagBitHasLimits], "has_limits");
  EXPECT_STREQ(pil::kCommandFlagNames[pil::kFlagBitPayload], "payload");
  EXPECT_EQ(pil::kCommandFlagsKnown, 0x1F);
  // payload qualifies an identify: its run estimates all ten of the payload's parameters; without it, none.
  pil::CommandFrame id = frame_from_command<double>(7, MotionVerb::kIdentify);
  EXPECT_EQ(identify_payload_mask(id), payload_mask::kNone);
  id.flags = pil::kFlagPayload;
  EXPECT_EQ(identify_payload_mask(id), payload_mask::kAll);
  MoveRequest<double> ignored;
  MotionVerb v;
  EXPECT_EQ(command_from_frame(id, ignored, v), MotionReason::kNone);
  EXPECT_EQ(v, MotionVerb::kIdentify);
  for (int flags = 0; flags < 16; ++flags) {
    pil::CommandFrame f = move_frame();
    f.flags = static_cast<std::uint8_t>(flags);
    MoveRequest<double> req;
    MotionVerb verb;
    ASSERT_EQ(command_from_frame(f, req, verb), MotionReason::kNone) << flags;
    EXPECT_EQ(req.relative, (flags & 1) != 0) << flags;
    EXPECT_EQ(req.has_rpy, (flags & 2) != 0) << flags;
    EXPECT_EQ(req.replace, (flags & 4) != 0) << flags;
    EXPECT_EQ(req.has_limits, (flags & 8) != 0) << flags;
    EXPECT_EQ(frame_from_command(f.id, verb, req).flags, flags);
  }
}

TEST(CommandFrames, StateRoundTripsFieldByField) {
  pil::StateFrame s;
  s.state = static_cast<std::uint8_t>(MotionState::kStopping);
  s.stop = static_cast<std::uint8_t>(StopCategory::kCategory2);
  s.faults = 0x80000001u;
  s.queued = 17;
  for (int i = 0; i < 6; ++i) s.x_d[i] = 0.5f * static_cast<float>(i) - 1.0f, s.x[i] = -0.25f * static_cast<float>(i);
  s.tick = 0xFFFFFFFEu;
  for (int k = 0; k < pil::kLinkErrorKinds; ++k) s.link.count[k] = 1000u * static_cast<std::uint32_t>(k) + 7u;
  s.friction_checked = 0x3F, s.friction_stale = 0x21;
  const pil::StateFrame t = decoded<pil::StateFrame>(parsed(bytes_of(s)));
  EXPECT_EQ(t.state, s.state);
  EXPECT_EQ(t.stop, s.stop);
  EXPECT_EQ(t.faults, s.faults);
  EXPECT_EQ(t.queued, s.queued);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(t.x_d[i], s.x_d[i]);
    EXPECT_EQ(t.x[i], s.x[i]);
  }
  EXPECT_EQ(t.tick, s.tick);
  for (int k = 0; k < pil::kLinkErrorKinds; ++k) EXPECT_EQ(t.link.count[k], s.link.count[k]) << k;
  EXPECT_EQ(t.friction_checked, s.friction_checked);
  EXPECT_EQ(t.friction_stale, s.friction_stale);
}

}  // namespace
