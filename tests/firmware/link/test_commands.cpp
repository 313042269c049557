// The command protocol's frames (osc/link/command_frames.hpp, made by osc/link/frames.hpp) and their
// conversions (osc/link/commands.hpp): the payload lengths, the sensor and actuator frames unchanged
// byte for byte, round trips of every frame type through the encoder and the parser, every flag,
// each kind of bad field refused with bad_command, the answer and state frames of a running task
// (PilNode<double> on a fake board), and a command answered in the tick after it arrives; the node's
// command port: command and setpoint frames over the link, the answer, state and trace frames after
// each tick's actuator frame, the configuration bits of the first sensor frame.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "osc/link/command_port.hpp"
#include "osc/link/commands.hpp"
#include "osc/link/node.hpp"
#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"

using namespace osc;

namespace {

using Bytes = std::vector<std::uint8_t>;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

template <class F>
Bytes bytes_of(const F& f) {
  Bytes b(pil::kMaxFrame);
  b.resize(static_cast<std::size_t>(pil::encode(f, b.data())));
  return b;
}

/// Feeds a frame's bytes to a fresh parser: kPending until the last byte, kFrame there.
pil::Parser parsed(const Bytes& b) {
  pil::Parser p;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const pil::Parser::Result r = p.feed(b[i]);
    EXPECT_EQ(r, i + 1 < b.size() ? pil::Parser::kPending : pil::Parser::kFrame) << "byte " << i;
  }
  return p;
}

/// Decodes a parsed frame as every type: only its own succeeds; returns that decoding.
template <class F>
F decoded(const pil::Parser& p) {
  pil::SensorFrame s;
  pil::ActuatorFrame a;
  pil::CommandFrame c;
  pil::AnswerFrame n;
  pil::StateFrame t;
  pil::SetpointFrame sp;
  pil::TraceFrame tr;
  pil::SetpointVelocityFrame sv;
  pil::ParamFrame pf;
  pil::ParamAnswerFrame pa;
  const int ok = p.decode(s) + p.decode(a) + p.decode(c) + p.decode(n) + p.decode(t) + p.decode(sp) + p.decode(tr) +
                 p.decode(sv) + p.decode(pf) + p.decode(pa);
  EXPECT_EQ(ok, 1);
  F f;
  EXPECT_TRUE(p.decode(f));
  return f;
}

/// A move_to of dz along z from where the queue ends (1 cm: half a second at the configured limits),
/// with `replace` a re-target.
pil::CommandFrame small_move(std::uint32_t id, double dz = 0.01, bool replace = false) {
  MoveRequest<double> req;
  req.relative = true;
  req.replace = replace;
  req.position(2) = dz;
  return frame_from_command(id, MotionVerb::kMoveTo, req);
}

/// The answers that end command `id` (answer_ends: done, or aborted with a reason).
std::vector<pil::AnswerFrame> endings(const std::vector<pil::AnswerFrame>& answers, std::uint32_t id) {
  std::vector<pil::AnswerFrame> e;
  for (const pil::AnswerFrame& a : answers)
    if (answer_ends(a, id)) e.push_back(a);
  return e;
}

// ---------------------------------------------------------------- layouts

TEST(CommandFrames, PayloadLengthsFixedAndEachFitsItsByte) {
  // The sensor and actuator frames (the QEMU PIL tests and the boards depend on them): the actuator
  // frame grew by 12 bytes when the tick's stages went from 5 to 8 (issue 54: stage_cycles).
  EXPECT_EQ(pil::kSensorPayload, 29);
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
  EXPECT_EQ(pil::kStatePayload, 1 + 1 + 4 + 1 + 4 + 4 + 24 + 24 + 4 + 4 * pil::kLinkErrorKinds);
  EXPECT_EQ(pil::kTracePayload, 4 + 4 + 1 + 3 * 24 + 36);
  EXPECT_EQ(pil::kParamFrame, 9);
  EXPECT_EQ(pil::kParamAnswerFrame, 10);
  EXPECT_EQ(pil::kParamPayload, 4 + 1 + 1 + 1 + 4);
  EXPECT_EQ(pil::kParamAnswerPayload,
            4 + 1 + 1 + 1 + 1 + 1 + 1 + 4 + 4 + 4 + 4 + 16);  // margins: observer, b bound, (37), loop
  ASSERT_EQ(pil::kFrameTypes, 10);
  for (const pil::FrameInfo& f : pil::kFrames) {
    EXPECT_LT(f.payload, 256) << f.name;
    EXPECT_LE(f.payload, pil::kActuatorPayload) << f.name;
    EXPECT_EQ(pil::payload_length(f.type), f.payload) << f.name;
    int bytes = 0;
    for (int i = 0; i < f.field_count; ++i) bytes += f.fields[i].bytes;
    EXPECT_EQ(bytes, f.payload) << f.name;
  }
  for (int t : {0, 11, 12, 0x5A, 0xA5, 255}) EXPECT_EQ(pil::payload_length(static_cast<std::uint8_t>(t)), -1) << t;
}

TEST(CommandFrames, SensorAndActuatorFramesUnchangedByteForByte) {
  // docs/protocol.md's worked examples, as encoded before the command frames existed (the actuator
  // frame with the 8 tick stages of issue 54).
  pil::SensorFrame s;
  s.seq = 1234;
  const std::int32_t counts[pil::kJoints] = {1500, -2750, 40, -3, 0, 12};
  for (int i = 0; i < pil::kJoints; ++i) s.counts[i] = counts[i];
  const Bytes sensor = {0xA5, 0x5A, 0x01, 0x1D, 0xD2, 0x04, 0x00, 0x00, 0xDC, 0x05, 0x00, 0x00,
                        0x42, 0xF5, 0xFF, 0xFF, 0x28, 0x00, 0x00, 0x00, 0xFD, 0xFF, 0xFF, 0xFF,
                        0x00, 0x00, 0x00, 0x00, 0x0C, 0x00, 0x00, 0x00, 0x00, 0x4A, 0xF2};
  EXPECT_EQ(bytes_of(s), sensor);
  pil::ActuatorFrame a;
  a.seq = 1234;
  const std::int32_t codes[pil::kJoints] = {120, -9100, 2047, 0, -15, 3};
  for (int i = 0; i < pil::kJoints; ++i) a.codes[i] = codes[i];
  a.state = 1;
  a.step_cycles = 9560;
  a.max_cycles = 9600;
  a.mean_cycles = 9500;
  a.tick_max_cycles = 13640;
  a.stack_used = 2960;
  a.theta_hat[0] = 1.5f;
  a.tau_f_hat[0] = -0.25f;
  a.link[pil::kErrSeq] = 1;
  a.rx_gap_max = 250000;
  const Bytes b = bytes_of(a);
  ASSERT_EQ(b.size(), 223u);
  EXPECT_EQ(b[3], 217);
  EXPECT_EQ(b[221], 0xED);  // the CRC covers every byte before it
  EXPECT_EQ(b[222], 0x01);
  EXPECT_EQ(b[4 + 181 + 4 * pil::kErrSeq], 1);  // the link counters' offset
}

// ---------------------------------------------------------------- round trips

TEST(CommandFrames, EveryFrameTypeRoundTripsThroughTheParser) {
  // Random payloads of each type: parsed, decoded as that type only, re-encoded to the same bytes.
  std::mt19937 rng(23);
  for (const pil::FrameInfo& info : pil::kFrames) {
    for (int trial = 0; trial < 50; ++trial) {
      std::uint8_t buf[pil::kMaxFrame];
      buf[0] = pil::kSync0;
      buf[1] = pil::kSync1;
      buf[2] = info.type;
      buf[3] = static_cast<std::uint8_t>(info.payload);
      for (int i = 0; i < info.payload; ++i) buf[4 + i] = static_cast<std::uint8_t>(rng());
      const std::uint16_t crc = pil::crc16(buf + 2, info.payload + 2);
      buf[4 + info.payload] = static_cast<std::uint8_t>(crc & 0xFF);
      buf[5 + info.payload] = static_cast<std::uint8_t>(crc >> 8);
      const Bytes in(buf, buf + info.payload + pil::kOverhead);
      const pil::Parser p = parsed(in);
      ASSERT_EQ(p.type(), info.type);
      Bytes out;
      switch (info.type) {
        case pil::kSensorFrame:
          out = bytes_of(decoded<pil::SensorFrame>(p));
          break;
        case pil::kActuatorFrame:
          out = bytes_of(decoded<pil::ActuatorFrame>(p));
          break;
        case pil::kCommandFrame:
          out = bytes_of(decoded<pil::CommandFrame>(p));
          break;
        case pil::kAnswerFrame:
          out = bytes_of(decoded<pil::AnswerFrame>(p));
          break;
        case pil::kStateFrame:
          out = bytes_of(decoded<pil::StateFrame>(p));
          break;
        case pil::kSetpointFrame:
          out = bytes_of(decoded<pil::SetpointFrame>(p));
          break;
        case pil::kTraceFrame:
          out = bytes_of(decoded<pil::TraceFrame>(p));
          break;
        case pil::kSetpointVelocityFrame:
          out = bytes_of(decoded<pil::SetpointVelocityFrame>(p));
          break;
        case pil::kParamFrame:
          out = bytes_of(decoded<pil::ParamFrame>(p));
          break;
        case pil::kParamAnswerFrame:
          out = bytes_of(decoded<pil::ParamAnswerFrame>(p));
          break;
      }
      ASSERT_EQ(out, in) << info.name;
    }
  }
}

pil::CommandFrame move_frame() {
  pil::CommandFrame f;
  f.id = 0x01020304;
  f.verb = static_cast<std::uint8_t>(MotionVerb::kMoveTo);
  f.flags = pil::kFlagHasRpy | pil::kFlagHasLimits;
  const float p[3] = {0.45f, -0.125f, 0.3f}, r[3] = {0.25f, -0.5f, 3.0f};
  const float l[6] = {0.05f, 0.2f, 2.0f, 0.4f, 0.75f, 8.0f};
  for (int i = 0; i < 3; ++i) f.position[i] = p[i], f.rpy[i] = r[i];
  for (int i = 0; i < 6; ++i) f.limits[i] = l[i];
  return f;
}

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

TEST(CommandFrames, DecodedCommandIsTheRequestAndEncodesBack) {
  MoveRequest<double> req;
  MotionVerb verb;
  const pil::CommandFrame f = move_frame();
  ASSERT_EQ(command_from_frame(f, req, verb), MotionReason::kNone);
  EXPECT_EQ(verb, MotionVerb::kMoveTo);
  EXPECT_EQ(req.position, Vec3<double>(0.45f, -0.125f, 0.3f));
  EXPECT_EQ(req.rpy, Vec3<double>(0.25f, -0.5f, 3.0f));
  EXPECT_FALSE(req.relative);
  EXPECT_TRUE(req.has_rpy);
  EXPECT_FALSE(req.replace);
  EXPECT_TRUE(req.has_limits);
  EXPECT_EQ(req.limits.linear.v, 0.05f);
  EXPECT_EQ(req.limits.linear.a, 0.2f);
  EXPECT_EQ(req.limits.linear.j, 2.0f);
  EXPECT_EQ(req.limits.angular.v, 0.4f);
  EXPECT_EQ(req.limits.angular.a, 0.75f);
  EXPECT_EQ(req.limits.angular.j, 8.0f);
  EXPECT_EQ(bytes_of(frame_from_command(f.id, verb, req)), bytes_of(f));
  Bytes host(pil::kMaxFrame);
  host.resize(static_cast<std::size_t>(encode_command(f.id, verb, req, host.data())));
  EXPECT_EQ(host, bytes_of(f));
  // float and Q12.19 decode the same numbers (within their resolution).
  MoveRequest<float> rf;
  MoveRequest<Fixed> rq;
  ASSERT_EQ(command_from_frame(f, rf, verb), MotionReason::kNone);
  ASSERT_EQ(command_from_frame(f, rq, verb), MotionReason::kNone);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(rf.position(i), f.position[i]);
    EXPECT_NEAR(static_cast<double>(rq.position(i)), f.position[i], 2e-6);
    EXPECT_NEAR(static_cast<double>(rq.rpy(i)), f.rpy[i], 2e-6);
  }
  EXPECT_NEAR(static_cast<double>(rq.limits.angular.j), 8.0, 2e-6);
}

TEST(CommandFrames, EveryVerbDecodes) {
  for (int v = 0; v < MotionNames<MotionVerb>::kCount; ++v) {
    pil::CommandFrame f;
    f.id = 7;
    f.verb = static_cast<std::uint8_t>(v);
    if (static_cast<MotionVerb>(v) == MotionVerb::kStream) f.period = 20;
    MoveRequest<double> req;
    MotionVerb verb;
    EXPECT_EQ(command_from_frame(f, req, verb), MotionReason::kNone) << motion_name(static_cast<MotionVerb>(v));
    EXPECT_EQ(verb, static_cast<MotionVerb>(v));
    EXPECT_EQ(bytes_of(frame_from_command(7, verb, req)), bytes_of(f));
  }
}

TEST(CommandFrames, EveryFlagAndEveryCombination) {
  ASSERT_EQ(pil::kCommandFlagCount, 4);
  EXPECT_STREQ(pil::kCommandFlagNames[pil::kFlagBitRelative], "relative");
  EXPECT_STREQ(pil::kCommandFlagNames[pil::kFlagBitHasRpy], "has_rpy");
  EXPECT_STREQ(pil::kCommandFlagNames[pil::kFlagBitReplace], "replace");
  EXPECT_STREQ(pil::kCommandFlagNames[pil::kFlagBitHasLimits], "has_limits");
  EXPECT_EQ(pil::kCommandFlagsKnown, 0x0F);
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

TEST(CommandFrames, AnswerRoundTripsFieldByField) {
  MotionReport r;
  r.id = 0xA1B2C3D4;
  r.verb = MotionVerb::kClear;
  r.outcome = CommandOutcome::kRefused;
  r.refusal = MotionReason::kFaulted;
  r.cause = kFaultEstop | kFaultTracking;
  r.done_id = 77;
  r.aborted_id = 78;
  r.abort = MotionReason::kStopCommand;
  r.completion = MotionCompletion::kStopped;
  const pil::AnswerFrame a = frame_from_report(r, MotionState::kFault, 3, 0x100000005ull);
  const pil::AnswerFrame b = decoded<pil::AnswerFrame>(parsed(bytes_of(a)));
  EXPECT_EQ(b.id, r.id);
  EXPECT_EQ(b.verb, static_cast<std::uint8_t>(MotionVerb::kClear));
  EXPECT_EQ(b.outcome, static_cast<std::uint8_t>(CommandOutcome::kRefused));
  EXPECT_EQ(b.refusal, static_cast<std::uint8_t>(MotionReason::kFaulted));
  EXPECT_EQ(b.cause, r.cause);
  EXPECT_EQ(b.done_id, 77u);
  EXPECT_EQ(b.aborted_id, 78u);
  EXPECT_EQ(b.abort, static_cast<std::uint8_t>(MotionReason::kStopCommand));
  EXPECT_EQ(b.completion, static_cast<std::uint8_t>(MotionCompletion::kStopped));
  EXPECT_EQ(b.state, static_cast<std::uint8_t>(MotionState::kFault));
  EXPECT_EQ(b.stop, static_cast<std::uint8_t>(StopCategory::kCategory0));
  EXPECT_EQ(b.queued, 3);
  EXPECT_EQ(b.tick, 5u);  // the low 32 bits
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
}

// ---------------------------------------------------------------- refusals

struct BadField {
  const char* what;
  void (*spoil)(pil::CommandFrame&);
};

const BadField kBad[] = {
    {"verb one past the list", [](pil::CommandFrame& f) { f.verb = MotionNames<MotionVerb>::kCount; }},
    {"verb 255", [](pil::CommandFrame& f) { f.verb = 255; }},
    {"flag bit 4", [](pil::CommandFrame& f) { f.flags |= 1u << 4; }},
    {"flag bit 7", [](pil::CommandFrame& f) { f.flags |= 1u << 7; }},
    {"position NaN", [](pil::CommandFrame& f) { f.position[1] = kNaN; }},
    {"position +inf", [](pil::CommandFrame& f) { f.position[0] = kInf; }},
    {"position -inf", [](pil::CommandFrame& f) { f.position[2] = -kInf; }},
    {"position beyond +10 m", [](pil::CommandFrame& f) { f.position[0] = 10.001f; }},
    {"position beyond -10 m", [](pil::CommandFrame& f) { f.position[2] = -10.5f; }},
    {"rpy NaN", [](pil::CommandFrame& f) { f.rpy[0] = kNaN; }},
    {"rpy inf", [](pil::CommandFrame& f) { f.rpy[2] = kInf; }},
    {"rpy beyond +2 pi", [](pil::CommandFrame& f) { f.rpy[1] = 6.2832f; }},
    {"rpy beyond -2 pi", [](pil::CommandFrame& f) { f.rpy[2] = -7.0f; }},
    {"rpy NaN without has_rpy",
     [](pil::CommandFrame& f) {
       f.flags = 0;
       f.rpy[0] = kNaN;
     }},
    {"limit NaN without has_limits",
     [](pil::CommandFrame& f) {
       f.flags = 0;
       f.limits[4] = kNaN;
     }},
    {"limit inf", [](pil::CommandFrame& f) { f.limits[0] = kInf; }},
    {"linear v 0", [](pil::CommandFrame& f) { f.limits[0] = 0.0f; }},
    {"linear a -0", [](pil::CommandFrame& f) { f.limits[1] = -0.0f; }},
    {"linear j negative", [](pil::CommandFrame& f) { f.limits[2] = -1.0f; }},
    {"angular v negative", [](pil::CommandFrame& f) { f.limits[3] = -1e-30f; }},
    {"angular a 0", [](pil::CommandFrame& f) { f.limits[4] = 0.0f; }},
    {"angular j NaN", [](pil::CommandFrame& f) { f.limits[5] = kNaN; }},
};

TEST(CommandFrames, EachBadFieldIsRefusedWithBadCommand) {
  for (const BadField& bad : kBad) {
    pil::CommandFrame f = move_frame();
    bad.spoil(f);
    MoveRequest<double> req;
    req.has_rpy = true;  // cleared by the refusal
    MotionVerb verb = MotionVerb::kStop;
    EXPECT_EQ(command_from_frame(f, req, verb), MotionReason::kBadCommand) << bad.what;
    // The verb is the frame's when its code is in the list, so that the refusal can echo it.
    EXPECT_EQ(verb, f.verb < MotionNames<MotionVerb>::kCount ? MotionVerb::kMoveTo : MotionVerb::kNone) << bad.what;
    EXPECT_FALSE(req.has_rpy) << bad.what;
    // Through the parser too: a bad command is a valid frame (the link is fine), refused when decoded.
    MotionVerb v2;
    EXPECT_EQ(command_from_frame(decoded<pil::CommandFrame>(parsed(bytes_of(f))), req, v2), MotionReason::kBadCommand);
  }
  // Every verb is checked the same way (an enable with a NaN is a broken client all the same).
  pil::CommandFrame f;
  f.verb = static_cast<std::uint8_t>(MotionVerb::kEnable);
  f.position[0] = kNaN;
  MoveRequest<double> req;
  MotionVerb verb;
  EXPECT_EQ(command_from_frame(f, req, verb), MotionReason::kBadCommand);
  EXPECT_EQ(verb, MotionVerb::kEnable);
}

TEST(CommandFrames, BoundsAreInclusiveAndLimitsIgnoredWithoutTheFlag) {
  pil::CommandFrame f = move_frame();
  f.position[0] = 10.0f;
  f.position[1] = -10.0f;
  f.rpy[0] = 6.2831850f;  // the largest float below 2 pi
  f.rpy[1] = -6.2831850f;
  f.limits[0] = 1e-30f;  // tiny, but above 0 (prepare_move decides whether it is usable)
  MoveRequest<double> req;
  MotionVerb verb;
  EXPECT_EQ(command_from_frame(f, req, verb), MotionReason::kNone);
  f.flags = 0;
  for (float& l : f.limits) l = -1.0f;  // not used: not checked but for being finite
  EXPECT_EQ(command_from_frame(f, req, verb), MotionReason::kNone);
  EXPECT_FALSE(req.has_limits);
}

TEST(CommandFrames, StreamPeriodBoundsAndOtherVerbsIgnoreIt) {
  pil::CommandFrame f;
  f.id = 5;
  f.verb = static_cast<std::uint8_t>(MotionVerb::kStream);
  MoveRequest<double> req;
  MotionVerb verb;
  for (int period : {0, 101, 255}) {
    f.period = static_cast<std::uint8_t>(period);
    EXPECT_EQ(command_from_frame(f, req, verb), MotionReason::kBadCommand) << period;
    EXPECT_EQ(verb, MotionVerb::kStream);
  }
  for (int period : {1, 20, 100}) {
    f.period = static_cast<std::uint8_t>(period);
    ASSERT_EQ(command_from_frame(f, req, verb), MotionReason::kNone) << period;
    EXPECT_EQ(req.period, static_cast<std::uint32_t>(period));
  }
  f.verb = static_cast<std::uint8_t>(MotionVerb::kMoveTo);
  f.period = 0;
  EXPECT_EQ(command_from_frame(f, req, verb), MotionReason::kNone);
  // Limits above the maxima: prepare_stream's over_limit; within: accepted with them.
  const CartesianLimits<double> max = CartesianLimits<double>::defaults();
  f.verb = static_cast<std::uint8_t>(MotionVerb::kStream);
  f.period = 10;
  f.flags = pil::kFlagHasLimits | pil::kFlagRelative;
  const double lim[6] = {max.linear.v / 2, max.linear.a, max.linear.j, max.angular.v, max.angular.a, max.angular.j};
  for (int i = 0; i < 6; ++i) f.limits[i] = static_cast<float>(lim[i]);
  const MotionGenerator<double> g;
  TaskCommand<double> c = prepare_frame_command(g, max, 1, params::kControlHz, f);
  EXPECT_EQ(c.refusal, MotionReason::kNone);
  EXPECT_EQ(c.verb, MotionVerb::kStream);
  EXPECT_EQ(c.period, 10u);
  EXPECT_TRUE(c.relative);
  EXPECT_NEAR(c.limits.linear.v, max.linear.v / 2, 1e-7);
  f.limits[1] = static_cast<float>(2 * max.linear.a);
  EXPECT_EQ(prepare_frame_command(g, max, 1, params::kControlHz, f).refusal, MotionReason::kOverLimit);
}

TEST(CommandFrames, SetpointRoundTripsAndBadOnesAreDropped) {
  const Vec3<double> p(0.5, -0.25, 0.125), rpy(0.5, -0.25, 1.0);
  pil::SetpointFrame f = setpoint_frame<double>(9, p, &rpy, true);
  EXPECT_EQ(f.flags, pil::kSetpointEnd | pil::kSetpointHasRpy);
  const pil::SetpointFrame g = decoded<pil::SetpointFrame>(parsed(bytes_of(f)));
  EXPECT_EQ(bytes_of(g), bytes_of(f));
  EXPECT_EQ(g.id, 9u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(g.position[i], static_cast<float>(p(i)));
    EXPECT_EQ(g.rpy[i], static_cast<float>(rpy(i)));
  }
  EXPECT_EQ(setpoint_frame<double>(9, p, nullptr, false).flags, 0);
  // No stream runs: dropped and counted; so is a bad one.
  auto task = std::make_unique<ControlTask<double>>();
  task->init(Model<double>::of(robot::kArm), Gains<double>::paper(), FrictionMode::kAdaptive,
             joint_vector<double>(robot::kQStart), 0, TaskStart::kDisabled);
  EXPECT_FALSE(offer_setpoint_frame(*task, f));
  EXPECT_EQ(task->dropped, 1u);
  EXPECT_FALSE(task->sample.valid);
  for (auto spoil :
       {+[](pil::SetpointFrame& s) { s.flags = 4; }, +[](pil::SetpointFrame& s) { s.position[1] = kNaN; },
        +[](pil::SetpointFrame& s) { s.rpy[2] = 7.0f; }, +[](pil::SetpointFrame& s) { s.position[0] = 11.0f; }}) {
    pil::SetpointFrame b = f;
    spoil(b);
    EXPECT_FALSE(offer_setpoint_frame(*task, b));
  }
  EXPECT_EQ(task->dropped, 5u);
}

TEST(CommandFrames, SetpointWithVelocityRoundTripsAndBadOnesAreDropped) {
  const Vec3<double> p(0.5, -0.25, 0.125), rpy(0.5, -0.25, 1.0);
  Vec6<double> v;
  v << 0.01, -0.02, 0.03, 0.1, -0.2, 0.3;
  const pil::SetpointVelocityFrame f = setpoint_velocity_frame<double>(9, p, &rpy, v, false);
  EXPECT_EQ(f.flags, pil::kSetpointHasRpy);
  const pil::SetpointVelocityFrame g = decoded<pil::SetpointVelocityFrame>(parsed(bytes_of(f)));
  EXPECT_EQ(bytes_of(g), bytes_of(f));
  for (int i = 0; i < 6; ++i) EXPECT_EQ(g.velocity[i], static_cast<float>(v(i)));
  // A stream running from the held pose: taken, its velocity as the follower's rates (the angular
  // velocity through E^{-1} at the setpoint's orientation coordinates).
  auto task = std::make_unique<ControlTask<double>>();
  task->init(Model<double>::of(robot::kArm), Gains<double>::paper(), FrictionMode::kAdaptive,
             joint_vector<double>(robot::kQStart), 0, TaskStart::kDisabled);
  task->gen.start_stream(10, false, CartesianLimits<double>::defaults(), 9);
  ASSERT_TRUE(offer_setpoint_frame(*task, f));
  ASSERT_TRUE(task->sample.valid && task->sample.has_velocity);
  const Vec3<double> phi = task->sample.x.tail<3>();
  // To f32's rounding of the frame's numbers (1e-8 here): GCC 12.2 at -O3 vectorises (SLP) this
  // test's double -> f32 -> double round trip without the rounding to f32 for some of the entries
  // (measured: clang, GCC with -fno-tree-slp-vectorize and UBSan builds round each one).
  EXPECT_NEAR((phi_rate_to_angular<double>(phi) * task->sample.v.tail<3>() - v.tail<3>()).norm(), 0, 1e-7);
  EXPECT_NEAR((task->sample.v.head<3>() - v.head<3>()).norm(), 0, 1e-8);
  // Without has_rpy the angular velocity is 0; with end all of it.
  pil::SetpointVelocityFrame h = f;
  h.flags = 0;
  ASSERT_TRUE(offer_setpoint_frame(*task, h));
  EXPECT_EQ(task->sample.v.tail<3>().norm(), 0.0);
  EXPECT_GT(task->sample.v.head<3>().norm(), 0.0);
  h.flags = pil::kSetpointEnd;
  ASSERT_TRUE(offer_setpoint_frame(*task, h));
  EXPECT_EQ(task->sample.v.norm(), 0.0);
  const std::uint32_t replaced = task->dropped;  // a setpoint not yet taken, replaced: counted
  for (auto spoil :
       {+[](pil::SetpointVelocityFrame& s) { s.velocity[3] = kNaN; },
        +[](pil::SetpointVelocityFrame& s) { s.velocity[0] = 10.5f; },
        +[](pil::SetpointVelocityFrame& s) { s.flags = 4; }, +[](pil::SetpointVelocityFrame& s) { s.rpy[2] = 7.0f; }}) {
    pil::SetpointVelocityFrame b = f;
    spoil(b);
    EXPECT_FALSE(offer_setpoint_frame(*task, b));
  }
  EXPECT_EQ(task->dropped, replaced + 4u);
}

TEST(CommandFrames, ReasonsListKeepsItsCodesAndEndsWithTheCollisionReasons) {
  // Appended only: the codes clients know stay.
  EXPECT_STREQ(motion_name(MotionReason::kBadCommand), "bad_command");
  EXPECT_EQ(static_cast<int>(MotionReason::kBadCommand), 14);
  EXPECT_STREQ(motion_name(MotionReason::kLinkSilent), "link_silent");
  EXPECT_EQ(static_cast<int>(MotionReason::kLinkSilent), 15);
  EXPECT_EQ(static_cast<int>(MotionReason::kCollision), 16);
  EXPECT_EQ(static_cast<int>(MotionReason::kYielding), 17);
  EXPECT_EQ(static_cast<int>(MotionReason::kNotHomed), 18);  // issue 27's, after them
  EXPECT_EQ(static_cast<int>(MotionReason::kUnknownPose), 22);
  EXPECT_EQ(static_cast<int>(MotionReason::kDropped), 23);  // issue 53's, after them
  EXPECT_EQ(static_cast<int>(MotionReason::kDropped) + 1, MotionNames<MotionReason>::kCount);
  // The states too: yielding after fault.
  EXPECT_EQ(static_cast<int>(MotionState::kFault), 4);
  EXPECT_EQ(static_cast<int>(MotionState::kYielding), 5);
}

// ---------------------------------------------------------------- preparing

MotionGenerator<double> holding_generator() {
  MotionGenerator<double> g;
  g.hold({Vec3<double>(0.5, 0.1, 0.3), rpy_rotation<double>({0.1, -0.2, 0.3})}, Mat3<double>::Identity());
  return g;
}

TEST(CommandFrames, PrepareFrameCommand) {
  const MotionGenerator<double> g = holding_generator();
  const CartesianLimits<double> max = CartesianLimits<double>::defaults();
  pil::CommandFrame f = move_frame();
  f.flags = pil::kFlagRelative;
  f.position[0] = 0.05f, f.position[1] = 0.0f, f.position[2] = 0.0f;
  TaskCommand<double> c = prepare_frame_command(g, max, 1, params::kControlHz, f);
  EXPECT_EQ(c.verb, MotionVerb::kMoveTo);
  EXPECT_EQ(c.id, f.id);
  EXPECT_EQ(c.refusal, MotionReason::kNone);
  EXPECT_NEAR((c.move.end().p - Vec3<double>(0.55, 0.1, 0.3)).norm(), 0, 1e-7);
  // Limits above the configured maxima: prepare_move's over_limit, not bad_command.
  f.flags = pil::kFlagHasLimits;
  f.limits[0] = static_cast<float>(2 * max.linear.v);
  EXPECT_EQ(prepare_frame_command(g, max, 1, params::kControlHz, f).refusal, MotionReason::kOverLimit);
  // A bad frame: refused while preparing, its id and verb kept for the answer.
  f.limits[0] = 0;
  c = prepare_frame_command(g, max, 1, params::kControlHz, f);
  EXPECT_EQ(c.refusal, MotionReason::kBadCommand);
  EXPECT_EQ(c.verb, MotionVerb::kMoveTo);
  EXPECT_EQ(c.id, f.id);
  // Another verb: no plan.
  pil::CommandFrame s;
  s.id = 9;
  s.verb = static_cast<std::uint8_t>(MotionVerb::kStop);
  c = prepare_frame_command(g, max, 1, params::kControlHz, s);
  EXPECT_EQ(c.verb, MotionVerb::kStop);
  EXPECT_EQ(c.refusal, MotionReason::kNone);
}

TEST(CommandFrames, AnswerDueAndStopCategories) {
  EXPECT_FALSE(answer_due(MotionReport{}));
  MotionReport r;
  r.outcome = CommandOutcome::kAccepted;
  EXPECT_TRUE(answer_due(r));
  r = {};
  r.done_id = 1;
  EXPECT_TRUE(answer_due(r));
  r = {};
  r.aborted_id = 1;
  EXPECT_TRUE(answer_due(r));
  r = {};
  r.abort = MotionReason::kLimitReached;
  EXPECT_TRUE(answer_due(r));
  r = {};
  r.completion = MotionCompletion::kFinished;
  EXPECT_TRUE(answer_due(r));
  r = {};
  r.id = 5;  // an id alone (no outcome) is nothing to answer
  EXPECT_FALSE(answer_due(r));
  EXPECT_EQ(stop_category_of(MotionState::kDisabled), StopCategory::kNone);
  EXPECT_EQ(stop_category_of(MotionState::kHolding), StopCategory::kNone);
  EXPECT_EQ(stop_category_of(MotionState::kMoving), StopCategory::kNone);
  EXPECT_EQ(stop_category_of(MotionState::kStopping), StopCategory::kCategory2);
  EXPECT_EQ(stop_category_of(MotionState::kFault), StopCategory::kCategory0);
}

// ---------------------------------------------------------------- a running task

struct FakeBoard {
  static void link_write(const std::uint8_t*, int) {}
  static std::uint32_t cycles() { return 0; }
  static std::uint32_t stack_used() { return 0; }
  static void burn(std::uint32_t) {}
  static void fault_output(bool) {}
};
using Node = PilNode<double, FakeBoard>;

struct TaskFrames : ::testing::Test {
  std::unique_ptr<Node> node = std::make_unique<Node>();
  std::uint32_t seq = 0;
  void SetUp() override {
    node->init(joint_vector<double>(robot::kQStart), FrictionMode::kAdaptive, 0);  // the paper's motion, from tick 0
  }
  /// One lockstep tick with the arm at the start pose (encoders dithering by a count).
  void tick() {
    pil::SensorFrame s;
    for (std::int32_t& c : s.counts) c = static_cast<std::int32_t>(seq & 1u);
    s.seq = seq++;
    std::uint8_t buf[pil::kMaxFrame];
    const int n = pil::encode(s, buf);
    int ends = 0;
    for (int i = 0; i < n; ++i) ends += node->on_byte(buf[i]);
    ASSERT_EQ(ends, 1);
    node->tick();
  }
  /// A command frame arriving before the next tick (as the wiring will put it in the mailbox).
  void arrive(const pil::CommandFrame& f) {
    ControlTask<double>& t = node->task;
    t.pending = prepare_frame_command(t.gen, t.limits, t.tick, params::kControlHz, f);
  }
};

TEST_F(TaskFrames, StateFrameOfATask) {
  const pil::StateFrame s0 = state_frame_from_task(node->task);
  EXPECT_EQ(s0.tick, 0xFFFFFFFFu);  // no tick yet
  EXPECT_EQ(s0.state, static_cast<std::uint8_t>(MotionState::kMoving));
  EXPECT_EQ(s0.stop, static_cast<std::uint8_t>(StopCategory::kNone));
  for (int i = 0; i < 6; ++i) EXPECT_EQ(s0.x_d[i], s0.x[i]) << i;  // the pose held at the start
  for (int k = 0; k < 20; ++k) tick();
  const pil::StateFrame s = state_frame_from_task(node->task);
  EXPECT_EQ(s.tick, 19u);
  EXPECT_EQ(s.faults, 0u);
  EXPECT_EQ(s.queued, 0);
  // The arm stands at the start pose (counts 0 or 1), the paper's motion barely started. The start
  // pose's pitch is 90 deg, where roll and yaw are not unique (their difference is): compared as
  // rotations.
  auto rotation = [](const float* x) { return rpy_rotation<double>(Vec3<double>(x[3], x[4], x[5])); };
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(std::isfinite(s.x[i]) && std::isfinite(s.x_d[i])) << i;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(s.x[i], s0.x[i], 1e-4) << i;
    EXPECT_NEAR(s.x_d[i], s0.x[i], 1e-4) << i;
  }
  EXPECT_LT((rotation(s.x) - rotation(s0.x)).norm(), 1e-3);
  EXPECT_LT((rotation(s.x_d) - rotation(s0.x)).norm(), 1e-3);
  // The measured pose is the forward kinematics', the orientation as a move_to's absolute rpy: a
  // move_to to it is a move to where the arm is.
  const ControlTask<double>& t = node->task;
  EXPECT_NEAR((Vec3<double>(s.x[0], s.x[1], s.x[2]) - t.state.data.o[kDof]).norm(), 0, 1e-6);
  MoveRequest<double> req;
  req.position = Vec3<double>(s.x[0], s.x[1], s.x[2]);
  req.rpy = Vec3<double>(s.x[3], s.x[4], s.x[5]);
  req.has_rpy = true;
  const Pose<double> from{t.state.data.o[kDof], t.state.data.R[kDof]};
  const Pose<double> to = move_target(from, req);
  EXPECT_LT((to.R - from.R).norm(), 1e-6);
  EXPECT_LT((to.p - from.p).norm(), 1e-6);
}

TEST_F(TaskFrames, ACommandIsAnsweredInTheTickAfterItArrives) {
  for (int k = 0; k < 5; ++k) {
    tick();
    EXPECT_FALSE(answer_due(node->task.report));  // the paper's motion runs, nothing to say
  }
  pil::CommandFrame stop;
  stop.id = 41;
  stop.verb = static_cast<std::uint8_t>(MotionVerb::kStop);
  arrive(stop);
  const std::uint64_t n = node->task.tick;
  tick();
  ASSERT_TRUE(answer_due(node->task.report));
  pil::AnswerFrame a = decoded<pil::AnswerFrame>(parsed(bytes_of(answer_frame(node->task))));
  EXPECT_EQ(a.tick, static_cast<std::uint32_t>(n));  // the tick after its arrival answered it
  EXPECT_EQ(a.id, 41u);
  EXPECT_EQ(a.verb, static_cast<std::uint8_t>(MotionVerb::kStop));
  EXPECT_EQ(a.outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  EXPECT_EQ(a.abort, static_cast<std::uint8_t>(MotionReason::kStopCommand));
  EXPECT_EQ(a.state, static_cast<std::uint8_t>(MotionState::kStopping));
  EXPECT_EQ(a.stop, static_cast<std::uint8_t>(StopCategory::kCategory2));
  // A move while stopping: refused by the machine; a bad frame: refused while decoding.
  pil::CommandFrame move;
  move.id = 42;
  move.verb = static_cast<std::uint8_t>(MotionVerb::kMoveTo);
  move.flags = pil::kFlagRelative;
  move.position[0] = 0.01f;
  arrive(move);
  tick();
  a = answer_frame(node->task);
  EXPECT_EQ(a.id, 42u);
  EXPECT_EQ(a.outcome, static_cast<std::uint8_t>(CommandOutcome::kRefused));
  EXPECT_EQ(a.refusal, static_cast<std::uint8_t>(MotionReason::kStopping));
  move.id = 43;
  move.position[0] = kNaN;
  arrive(move);
  tick();
  a = answer_frame(node->task);
  EXPECT_EQ(a.id, 43u);
  EXPECT_EQ(a.verb, static_cast<std::uint8_t>(MotionVerb::kMoveTo));
  EXPECT_EQ(a.outcome, static_cast<std::uint8_t>(CommandOutcome::kRefused));
  EXPECT_EQ(a.refusal, static_cast<std::uint8_t>(MotionReason::kBadCommand));
  EXPECT_EQ(a.tick, static_cast<std::uint32_t>(node->task.tick - 1));
  const pil::StateFrame s = state_frame_from_task(node->task);
  EXPECT_EQ(s.state, static_cast<std::uint8_t>(MotionState::kStopping));
  EXPECT_EQ(s.stop, static_cast<std::uint8_t>(StopCategory::kCategory2));
}

}  // namespace

namespace {

template <class S>
pil::StateFrame start_state() {
  auto t = std::make_unique<ControlTask<S>>();
  t->init(Model<S>::of(robot::kArm), Gains<S>::paper(), FrictionMode::kAdaptive, joint_vector<S>(robot::kQStart));
  return state_frame_from_task(*t);
}

TEST(CommandFrames, StateFrameInEveryScalar) {
  const pil::StateFrame d = start_state<double>(), f = start_state<float>(), q = start_state<Fixed>();
  EXPECT_EQ(f.state, d.state);
  EXPECT_EQ(q.state, d.state);
  // The start pose's rotation (pitch 90 deg) through each scalar.
  auto rotation = [](const float* x) { return rpy_rotation<double>(Vec3<double>(x[3], x[4], x[5])); };
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(f.x[i], d.x[i], 1e-5) << i;
    EXPECT_NEAR(q.x[i], d.x[i], 1e-4) << i;
  }
  EXPECT_LT((rotation(f.x) - rotation(d.x)).norm(), 1e-3);
  EXPECT_LT((rotation(q.x_d) - rotation(d.x_d)).norm(), 1e-2);
}

}  // namespace

// ---------------------------------------------------------------- the command port in the node

namespace {

/// A board that records what the node writes, frame by frame (any other byte is counted bad).
struct RecordingBoard {
  static inline pil::Parser rx;
  static inline std::vector<pil::FrameType> types;
  static inline std::vector<pil::ActuatorFrame> actuators;
  static inline std::vector<pil::AnswerFrame> answers;
  static inline std::vector<pil::StateFrame> states;
  static inline std::vector<pil::TraceFrame> traces;
  static inline int bad = 0;
  static void reset() {
    rx.reset();
    types.clear(), actuators.clear(), answers.clear(), states.clear(), traces.clear();
    bad = 0;
  }
  static void link_write(const std::uint8_t* p, int n) {
    for (int i = 0; i < n; ++i)
      for (pil::Parser::Result r = rx.feed(p[i]); r != pil::Parser::kPending; r = rx.next()) take(r);
  }
  static void take(pil::Parser::Result r) {
    if (r != pil::Parser::kFrame) {
      ++bad;
      return;
    }
    types.push_back(rx.type());
    pil::ActuatorFrame act;
    pil::AnswerFrame ans;
    pil::StateFrame st;
    pil::TraceFrame tr;
    if (rx.decode(act)) actuators.push_back(act);
    if (rx.decode(ans)) answers.push_back(ans);
    if (rx.decode(st)) states.push_back(st);
    if (rx.decode(tr)) traces.push_back(tr);
  }
  static std::uint32_t cycles() { return 0; }
  static std::uint32_t stack_used() { return 0; }
  static void burn(std::uint32_t) {}
  static void fault_output(bool) {}
};
using RecordingNode = PilNode<double, RecordingBoard>;

/// The node over its link, lockstep: frames arrive byte by byte, a tick whenever on_byte says so.
struct NodeFrames : ::testing::Test {
  std::unique_ptr<RecordingNode> node = std::make_unique<RecordingNode>();
  std::uint32_t seq = 0;
  std::int32_t counts[kDof] = {};

  void SetUp() override {
    RecordingBoard::reset();
    node->init(joint_vector<double>(robot::kQStart), FrictionMode::kAdaptive, 0);
  }
  void TearDown() override { EXPECT_EQ(RecordingBoard::bad, 0); }
  /// A frame's bytes into the node; the ticks they make due (each run).
  template <class F>
  int arrive(const F& f) {
    int ticks = 0;
    for (std::uint8_t b : bytes_of(f)) node->on_byte(b, [&] { ++ticks, node->tick(); });
    return ticks;
  }
  /// One tick: the next sensor frame (the arm at the start pose, its encoders dithering by a count).
  void tick(std::uint8_t inject = 0) {
    pil::SensorFrame s;
    for (int i = 0; i < kDof; ++i) s.counts[i] = counts[i] + static_cast<std::int32_t>(seq & 1u);
    s.seq = seq++;
    s.inject = inject;
    ASSERT_EQ(arrive(s), 1);
  }
  static pil::CommandFrame command(std::uint32_t id, MotionVerb v) {
    pil::CommandFrame f;
    f.id = id;
    f.verb = static_cast<std::uint8_t>(v);
    return f;
  }
  /// Started disabled, enabled (command 1) and past the torque ramp (the arm stays put: the counts are 0).
  void enable() {
    tick(pil::kConfigStartDisabled);
    arrive(command(1, MotionVerb::kEnable));
    for (int k = 0; k < 60; ++k) tick();
  }
  /// A command frame, then the tick that takes it from the mailbox (and answers it).
  void take(const pil::CommandFrame& f) {
    arrive(f);
    tick();
  }
  /// The moves ids[0..n) queued, each accepted in its tick.
  void queue(const std::vector<std::uint32_t>& ids) {
    for (std::uint32_t id : ids) {
      take(small_move(id, id % 2 ? -0.01 : 0.01));
      ASSERT_EQ(RecordingBoard::answers.back().id, id);
      ASSERT_EQ(RecordingBoard::answers.back().outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted)) << id;
    }
  }
  /// Ticks until a motion comes to rest (an answer with a completion), at most n.
  void until_rest(int n = 3000) {
    for (int k = 0; k < n; ++k) {
      tick();
      if (RecordingBoard::answers.back().completion != static_cast<std::uint8_t>(MotionCompletion::kNone)) return;
    }
    FAIL() << "no completion within " << n << " ticks";
  }
};

TEST_F(NodeFrames, ACommandIsNeitherATickNorALinkErrorAndIsAnsweredAfterTheActuatorFrame) {
  tick(pil::kConfigStartDisabled);
  EXPECT_EQ(arrive(command(1, MotionVerb::kEnable)), 0);  // no tick
  EXPECT_EQ(node->task.pending.verb, MotionVerb::kEnable);
  tick();
  EXPECT_EQ(node->link_counters().total(), 0u);
  ASSERT_EQ(RecordingBoard::answers.size(), 1u);
  EXPECT_EQ(RecordingBoard::answers[0].id, 1u);
  EXPECT_EQ(RecordingBoard::answers[0].outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  EXPECT_EQ(RecordingBoard::answers[0].state, static_cast<std::uint8_t>(MotionState::kHolding));
  EXPECT_EQ(RecordingBoard::answers[0].tick, 1u);
  // Tick 0's actuator frame, then tick 1's, then its answer.
  const std::vector<pil::FrameType> want = {pil::kActuatorFrame, pil::kActuatorFrame, pil::kAnswerFrame};
  EXPECT_EQ(RecordingBoard::types, want);
  EXPECT_EQ(RecordingBoard::actuators.back().link.total(), 0u);
  // A setpoint frame: not a tick either (no stream runs: dropped and counted).
  EXPECT_EQ(arrive(setpoint_frame<double>(9, Vec3<double>::Zero(), nullptr, false)), 0);
  EXPECT_EQ(node->task.dropped, 1u);
  // A valid frame of a type the host does not send is still a frame of the wrong type: a tick at once.
  EXPECT_EQ(arrive(pil::AnswerFrame{}), 1);
  EXPECT_EQ(RecordingBoard::actuators.back().link[pil::kErrHeader], 1u);
}

TEST_F(NodeFrames, CommandsWaitForTheMailboxInOrderAndAreAnsweredOnce) {
  tick(pil::kConfigStartDisabled);
  for (int k = 0; k < 2; ++k) tick();
  arrive(command(1, MotionVerb::kEnable));
  EXPECT_EQ(node->task.pending.verb, MotionVerb::kEnable);  // prepared at once: the mailbox was free
  arrive(command(2, MotionVerb::kStop));
  arrive(command(3, MotionVerb::kDisable));
  EXPECT_EQ(node->port.waiting(), 2);
  for (int k = 0; k < 4; ++k) tick();
  ASSERT_EQ(RecordingBoard::answers.size(), 3u);
  for (std::uint32_t i = 0; i < 3; ++i) {
    EXPECT_EQ(RecordingBoard::answers[i].id, i + 1);
    EXPECT_EQ(RecordingBoard::answers[i].outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
    EXPECT_EQ(RecordingBoard::answers[i].tick, RecordingBoard::answers[0].tick + i);  // one per tick, in order
  }
  EXPECT_EQ(RecordingBoard::answers[0].state, static_cast<std::uint8_t>(MotionState::kHolding));
  EXPECT_EQ(RecordingBoard::answers[2].state, static_cast<std::uint8_t>(MotionState::kDisabled));
  EXPECT_EQ(node->port.waiting(), 0);
}

// Issue 53, defect 3: a command sent twice (a client that resends after missing the answer) runs
// once. Waiting in the mailbox, the resend is left to the answer to come; answered, it is answered
// again with the very answer it had. A 10 mm relative move sent twice queues one 10 mm move; a
// refused one is refused again, not retried; the same id with other content is a new command.
TEST_F(NodeFrames, AResentCommandIsAnsweredAgainAndRunsOnce) {
  tick(pil::kConfigStartDisabled);
  arrive(command(1, MotionVerb::kEnable));
  for (int k = 0; k < 3; ++k) tick();
  const Vec3<double> start = node->task.gen.queue_end().p;
  const pil::CommandFrame move = small_move(2);
  arrive(move);
  arrive(move);  // in the mailbox still: left to the answer to come
  EXPECT_EQ(node->port.waiting(), 0);
  tick();
  ASSERT_EQ(RecordingBoard::answers.size(), 2u);
  const pil::AnswerFrame first = RecordingBoard::answers.back();
  EXPECT_EQ(first.id, 2u);
  EXPECT_EQ(first.outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  arrive(move);  // answered: answered again at once, the same frame
  ASSERT_EQ(RecordingBoard::answers.size(), 3u);
  EXPECT_EQ(bytes_of(RecordingBoard::answers.back()), bytes_of(first));
  EXPECT_EQ(node->task.pending.verb, MotionVerb::kNone);
  EXPECT_EQ(node->port.waiting(), 0);
  tick();
  EXPECT_EQ(node->task.gen.queued(), 1) << "one move, not two";
  EXPECT_NEAR((node->task.gen.queue_end().p - start).norm(), 0.01, 1e-9) << "10 mm, not 20";
  EXPECT_EQ(node->port.resends, 2u);
  // A refused command is refused again, the same way.
  arrive(command(3, MotionVerb::kDeclarePose));  // torque on: refused
  tick();
  const pil::AnswerFrame refused = RecordingBoard::answers.back();
  EXPECT_EQ(refused.refusal, static_cast<std::uint8_t>(MotionReason::kTorqueOn));
  arrive(command(3, MotionVerb::kDeclarePose));
  EXPECT_EQ(bytes_of(RecordingBoard::answers.back()), bytes_of(refused));
  // The same id with another frame: a new command, run.
  const std::size_t answered = RecordingBoard::answers.size();
  pil::CommandFrame other = small_move(2);
  other.position[1] = 0.01f;
  arrive(other);
  tick();
  ASSERT_EQ(RecordingBoard::answers.size(), answered + 1);
  EXPECT_EQ(RecordingBoard::answers.back().tick, node->task.tick - 1);
  EXPECT_EQ(node->task.gen.queued(), 2);
}

TEST_F(NodeFrames, FullFifoAndUnknownVerbAreRefusedAtOnce) {
  tick(pil::kConfigStartDisabled);
  for (std::uint32_t id = 1; id <= 1 + kCommandFifo; ++id) arrive(command(id, MotionVerb::kStop));
  EXPECT_TRUE(RecordingBoard::answers.empty());  // one in the mailbox, kCommandFifo waiting
  arrive(command(99, MotionVerb::kStop));
  ASSERT_EQ(RecordingBoard::answers.size(), 1u);
  EXPECT_EQ(RecordingBoard::answers[0].id, 99u);
  EXPECT_EQ(RecordingBoard::answers[0].refusal, static_cast<std::uint8_t>(MotionReason::kQueueFull));
  RecordingBoard::answers.clear();
  for (int k = 0; k < 1 + kCommandFifo; ++k) tick();
  ASSERT_EQ(RecordingBoard::answers.size(), 1u + kCommandFifo);
  for (const pil::AnswerFrame& a : RecordingBoard::answers)  // a stop while disabled
    EXPECT_EQ(a.refusal, static_cast<std::uint8_t>(MotionReason::kNotEnabled));
  RecordingBoard::answers.clear();
  pil::CommandFrame u = command(7, MotionVerb::kNone);
  u.verb = 200;
  arrive(u);
  ASSERT_EQ(RecordingBoard::answers.size(), 1u);
  EXPECT_EQ(RecordingBoard::answers[0].id, 7u);
  EXPECT_EQ(RecordingBoard::answers[0].verb, static_cast<std::uint8_t>(MotionVerb::kNone));
  EXPECT_EQ(RecordingBoard::answers[0].refusal, static_cast<std::uint8_t>(MotionReason::kBadCommand));
  EXPECT_EQ(node->task.pending.verb, MotionVerb::kNone);
}

TEST_F(NodeFrames, TheTaskStartsDisabledWhenTheFirstFrameAsksAndACommandBeforeItWaitsForIt) {
  // Without the bit: the paper's motion from the first sample.
  tick();
  EXPECT_EQ(node->task.machine.state, MotionState::kMoving);
  EXPECT_EQ(node->task.gen.source(), MotionSource::kPaper);
  // With it: disabled, zero codes; an enable sent before the first sensor frame is prepared once
  // that frame has configured the task, and answered by its tick.
  SetUp();
  seq = 0;
  arrive(command(5, MotionVerb::kEnable));
  EXPECT_EQ(node->task.pending.verb, MotionVerb::kNone);  // waiting: not configured yet
  EXPECT_EQ(node->port.waiting(), 1);
  tick(pil::kConfigStartDisabled);
  ASSERT_EQ(RecordingBoard::answers.size(), 1u);
  EXPECT_EQ(RecordingBoard::answers[0].id, 5u);
  EXPECT_EQ(RecordingBoard::answers[0].tick, 0u);
  EXPECT_EQ(RecordingBoard::answers[0].state, static_cast<std::uint8_t>(MotionState::kHolding));
  EXPECT_EQ(node->task.gen.source(), MotionSource::kHold);
  for (std::int32_t c : RecordingBoard::actuators[0].codes) EXPECT_EQ(c, 0);  // the enable's ramp starts after it
}

TEST_F(NodeFrames, StateFramesOnlyWhenTheFirstFrameAsks) {
  for (int k = 0; k < 100; ++k) tick();
  EXPECT_TRUE(RecordingBoard::states.empty());
  EXPECT_EQ(RecordingBoard::types.size(), 100u);  // actuator frames only, as before the command protocol
  SetUp();
  seq = 0;
  tick(pil::kConfigStateFrames);
  for (int k = 1; k < 100; ++k) tick();
  ASSERT_EQ(RecordingBoard::states.size(), 100u / kStatePeriod);
  for (std::size_t i = 0; i < RecordingBoard::states.size(); ++i)
    EXPECT_EQ(RecordingBoard::states[i].tick, (i + 1) * kStatePeriod - 1);
  EXPECT_EQ(RecordingBoard::types[kStatePeriod], pil::kStateFrame);  // after its tick's actuator frame
  EXPECT_EQ(RecordingBoard::types[kStatePeriod - 1], pil::kActuatorFrame);
}

TEST_F(NodeFrames, ATraceFrameEndsEveryTickWhenTheFirstFrameAsks) {
  tick(pil::kConfigTrace);
  for (int k = 1; k < 30; ++k) tick();
  ASSERT_EQ(RecordingBoard::traces.size(), 30u);
  ASSERT_EQ(RecordingBoard::types.size(), 60u);
  for (std::size_t k = 0; k < 30; ++k) {
    EXPECT_EQ(RecordingBoard::types[2 * k], pil::kActuatorFrame);
    EXPECT_EQ(RecordingBoard::types[2 * k + 1], pil::kTraceFrame);
    EXPECT_EQ(RecordingBoard::traces[k].seq, RecordingBoard::actuators[k].seq);
    EXPECT_EQ(RecordingBoard::traces[k].faults, 0u);
  }
  // The last step's desired state and the reference orientation, as the task has them.
  const pil::TraceFrame& t = RecordingBoard::traces.back();
  const ControlTask<double>& task = node->task;
  EXPECT_EQ(t.state, static_cast<std::uint8_t>(MotionState::kMoving));
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(t.x_d[i], static_cast<float>(task.desired.x(i))) << i;
    EXPECT_EQ(t.xd_d[i], static_cast<float>(task.desired.xd(i))) << i;
    EXPECT_EQ(t.xdd_d[i], static_cast<float>(task.desired.xdd(i))) << i;
  }
  for (int i = 0; i < 9; ++i) EXPECT_EQ(t.R_ref[i], static_cast<float>(task.state.R_ref(i / 3, i % 3))) << i;
  EXPECT_GT(std::abs(t.xd_d[1]) + std::abs(t.xd_d[2]), 0.0f);  // the paper's motion is on its way
  // The faults the tick detected (the actuator frame carries the latched ones).
  tick(pil::kInjectNonFinite);
  EXPECT_EQ(RecordingBoard::traces.back().faults, static_cast<std::uint32_t>(kFaultNonFinite));
  EXPECT_EQ(RecordingBoard::traces.back().state, static_cast<std::uint8_t>(MotionState::kFault));
  tick();
  EXPECT_EQ(RecordingBoard::traces.back().faults, 0u);
  EXPECT_EQ(RecordingBoard::actuators.back().faults, static_cast<std::uint32_t>(kFaultNonFinite));
}

TEST_F(NodeFrames, AHostThatNeverCommandsGetsActuatorFramesOnlyEvenWhenTheMotionAborts) {
  for (int k = 0; k < 5; ++k) tick();
  counts[0] += 5000;  // an encoder jump: the fault aborts the paper's motion
  tick();
  EXPECT_EQ(node->task.report.abort, MotionReason::kFaulted);  // something to say ...
  for (int k = 0; k < 3; ++k) tick();
  EXPECT_TRUE(RecordingBoard::answers.empty());  // ... to no one who asked
  EXPECT_EQ(RecordingBoard::types.size(), 9u);
}

TEST_F(NodeFrames, AStreamFollowsItsSetpointsAndIsStopped) {
  enable();
  pil::CommandFrame st = command(2, MotionVerb::kStream);
  st.flags = pil::kFlagRelative;
  st.period = 10;
  arrive(st);
  tick();
  ASSERT_EQ(RecordingBoard::answers.back().id, 2u);
  ASSERT_EQ(RecordingBoard::answers.back().outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  EXPECT_EQ(node->task.gen.running_id(), 2u);
  const Vec3<double> p0 = node->task.gen.hold_pose().p;
  // 2 mm along y at 100 Hz (the encoders stay at 0 here: no plant, so briefly), then a stop.
  for (int n = 1; n <= 10; ++n) {
    EXPECT_EQ(arrive(setpoint_frame<double>(2, Vec3<double>(0, 0.002 * n / 10.0, 0), nullptr, false)), 0);
    for (int k = 0; k < 10; ++k) tick();
  }
  EXPECT_EQ(node->task.dropped, 0u);
  EXPECT_EQ(node->task.machine.state, MotionState::kMoving);
  const Vec3<double> d = node->task.desired.x.head<3>() - p0;
  EXPECT_GT(d(1), 1e-4);  // on its way along +y, one period behind and lagging
  EXPECT_LT(d(1), 0.002);
  EXPECT_NEAR(d(0), 0, 1e-9);
  EXPECT_NEAR(d(2), 0, 1e-9);
  // A setpoint of another stream: dropped.
  arrive(setpoint_frame<double>(3, Vec3<double>::Zero(), nullptr, false));
  EXPECT_EQ(node->task.dropped, 1u);
  arrive(command(4, MotionVerb::kStop));
  tick();
  EXPECT_EQ(RecordingBoard::answers.back().abort, static_cast<std::uint8_t>(MotionReason::kStopCommand));
  EXPECT_EQ(RecordingBoard::answers.back().aborted_id, 2u);
  EXPECT_EQ(node->task.machine.state, MotionState::kStopping);
  EXPECT_EQ(node->link_counters().total(), 0u);
}

TEST_F(NodeFrames, AStreamTakesSetpointsWithVelocity) {
  enable();
  pil::CommandFrame st = command(2, MotionVerb::kStream);
  st.flags = pil::kFlagRelative;
  st.period = 10;
  arrive(st);
  tick();
  ASSERT_EQ(RecordingBoard::answers.back().outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  const Vec3<double> p0 = node->task.gen.hold_pose().p;
  // 20 mm/s along y at 100 Hz, each setpoint with that velocity: the reference leads the plain
  // stream's by the period's delay (0.2 mm at this speed).
  Vec6<double> v = Vec6<double>::Zero();
  v(1) = 0.02;
  for (int n = 1; n <= 10; ++n) {
    EXPECT_EQ(arrive(setpoint_velocity_frame<double>(2, Vec3<double>(0, 0.0002 * n, 0), nullptr, v, false)), 0);
    for (int k = 0; k < 10; ++k) tick();
  }
  EXPECT_EQ(node->task.dropped, 0u);
  EXPECT_EQ(node->task.machine.state, MotionState::kMoving);
  const Vec3<double> d = node->task.desired.x.head<3>() - p0;
  EXPECT_GT(d(1), 1e-4);
  EXPECT_GT(node->task.desired.xd(1), 0.0);
  EXPECT_NEAR(d(0), 0, 1e-9);
  EXPECT_EQ(node->link_counters().total(), 0u);
}

// ---------------------------------------------------------------- every accepted motion ends once

/// Ids first, first + 1, ... (n of them).
std::vector<std::uint32_t> ids_from(std::uint32_t first, int n) {
  std::vector<std::uint32_t> ids;
  for (int k = 0; k < n; ++k) ids.push_back(first + static_cast<std::uint32_t>(k));
  return ids;
}

/// The answer frames of the tick that answered command `id` from its answer on: the tick's own,
/// then one per move the tick dropped.
std::vector<pil::AnswerFrame> tick_answers(std::uint32_t id) {
  const std::vector<pil::AnswerFrame>& all = RecordingBoard::answers;
  std::size_t i = 0;
  while (i < all.size() && !(all[i].id == id && all[i].outcome != 0)) ++i;
  std::vector<pil::AnswerFrame> t;
  for (std::size_t k = i; k < all.size() && all[k].tick == all[i].tick; ++k) t.push_back(all[k]);
  return t;
}

/// The answer frames after the tick's own that name the moves it dropped, in queue order: each
/// aborted `dropped`, the tick's number, state and queue.
void expect_dropped(const std::vector<pil::AnswerFrame>& tick, const std::vector<std::uint32_t>& dropped) {
  ASSERT_EQ(tick.size(), 1 + dropped.size());
  for (std::size_t k = 0; k < dropped.size(); ++k) {
    const pil::AnswerFrame& a = tick[1 + k];
    EXPECT_EQ(a.aborted_id, dropped[k]) << k;
    EXPECT_STREQ(motion_name(static_cast<MotionReason>(a.abort)), "dropped") << k;
    EXPECT_EQ(a.id, 0u);
    EXPECT_EQ(a.outcome, static_cast<std::uint8_t>(CommandOutcome::kNone));
    EXPECT_EQ(a.done_id, 0u);
    EXPECT_EQ(a.tick, tick[0].tick);
    EXPECT_EQ(a.state, tick[0].state);
    EXPECT_EQ(a.queued, tick[0].queued);
  }
}

/// Every move of ids ended exactly once in the answers so far.
void expect_each_ended_once(const std::vector<std::uint32_t>& ids) {
  for (std::uint32_t id : ids) EXPECT_EQ(endings(RecordingBoard::answers, id).size(), 1u) << "move " << id;
}

TEST_F(NodeFrames, AStopNamesEveryMoveItDropsFromAFullQueueInItsTick) {
  enable();
  const std::vector<std::uint32_t> ids = ids_from(10, MotionGenerator<double>::kQueueLength + 1);
  queue(ids);  // the running move and sixteen waiting
  take(small_move(99));
  EXPECT_EQ(RecordingBoard::answers.back().refusal, static_cast<std::uint8_t>(MotionReason::kQueueFull));
  EXPECT_EQ(RecordingBoard::answers.back().queued, ids.size());
  take(command(100, MotionVerb::kStop));
  const std::vector<pil::AnswerFrame> t = tick_answers(100);
  ASSERT_FALSE(t.empty());
  EXPECT_EQ(t[0].aborted_id, ids[0]);
  EXPECT_EQ(t[0].abort, static_cast<std::uint8_t>(MotionReason::kStopCommand));
  EXPECT_EQ(t[0].state, static_cast<std::uint8_t>(MotionState::kStopping));
  EXPECT_EQ(t[0].queued, 1);  // the move braking
  expect_dropped(t, std::vector<std::uint32_t>(ids.begin() + 1, ids.end()));
  until_rest();
  expect_each_ended_once(ids);
  const pil::StateFrame s = state_frame_from_task(node->task);
  EXPECT_EQ(s.state, static_cast<std::uint8_t>(MotionState::kHolding));
  EXPECT_EQ(s.queued, 0);
  EXPECT_EQ(s.running_id, 0u);
}

TEST_F(NodeFrames, ADisableDropsTheQueueAndTheArmDisabledAtRestHasNone) {
  enable();
  const std::vector<std::uint32_t> ids = ids_from(10, 3);
  queue(ids);
  take(command(20, MotionVerb::kDisable));
  const std::vector<pil::AnswerFrame> t = tick_answers(20);
  ASSERT_FALSE(t.empty());
  EXPECT_EQ(t[0].aborted_id, ids[0]);
  EXPECT_EQ(t[0].abort, static_cast<std::uint8_t>(MotionReason::kDisableCommand));
  expect_dropped(t, {ids[1], ids[2]});
  until_rest();
  EXPECT_EQ(RecordingBoard::answers.back().state, static_cast<std::uint8_t>(MotionState::kDisabled));
  expect_each_ended_once(ids);
  const pil::StateFrame s = state_frame_from_task(node->task);
  EXPECT_EQ(s.queued, 0);
  EXPECT_EQ(s.running_id, 0u);
}

TEST_F(NodeFrames, AFaultAbortsTheMoveAndDropsTheQueueInItsTickAndTheStateFrameSaysSoThroughClear) {
  enable();
  const std::vector<std::uint32_t> ids = ids_from(10, 4);
  queue(ids);
  EXPECT_EQ(state_frame_from_task(node->task).queued, 4);
  EXPECT_EQ(state_frame_from_task(node->task).running_id, ids[0]);
  const std::size_t before = RecordingBoard::answers.size();
  tick(pil::kInjectNonFinite);
  const std::vector<pil::AnswerFrame> t(RecordingBoard::answers.begin() + static_cast<std::ptrdiff_t>(before),
                                        RecordingBoard::answers.end());
  ASSERT_FALSE(t.empty());
  EXPECT_EQ(t[0].aborted_id, ids[0]);
  EXPECT_EQ(t[0].abort, static_cast<std::uint8_t>(MotionReason::kFaulted));
  EXPECT_EQ(t[0].state, static_cast<std::uint8_t>(MotionState::kFault));
  EXPECT_EQ(t[0].queued, 0);
  expect_dropped(t, {ids[1], ids[2], ids[3]});
  expect_each_ended_once(ids);
  // From the fault's tick on, through the clear: nothing runs, nothing is queued.
  const auto expect_nothing_queued = [this](MotionState state) {
    const pil::StateFrame s = state_frame_from_task(node->task);
    EXPECT_EQ(s.state, static_cast<std::uint8_t>(state));
    EXPECT_EQ(s.queued, 0);
    EXPECT_EQ(s.running_id, 0u);
  };
  expect_nothing_queued(MotionState::kFault);
  tick();
  expect_nothing_queued(MotionState::kFault);
  // The machine's refusals, not busy: no motion is left in the generator.
  take(command(19, MotionVerb::kPaper));
  EXPECT_EQ(RecordingBoard::answers.back().refusal, static_cast<std::uint8_t>(MotionReason::kFaulted));
  take(command(20, MotionVerb::kClear));
  EXPECT_EQ(RecordingBoard::answers.back().outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  expect_nothing_queued(MotionState::kDisabled);
  for (MotionVerb v : {MotionVerb::kPaper, MotionVerb::kStream}) {
    pil::CommandFrame f = command(21, v);
    f.period = 10;
    take(f);
    EXPECT_EQ(RecordingBoard::answers.back().refusal, static_cast<std::uint8_t>(MotionReason::kNotEnabled));
  }
  expect_each_ended_once(ids);
}

// One latch of fault bits (the supervisor's, which the motion machine reads): the actuator frame, the
// state frame and a refusal's cause report the same bits after a fault, and none after the clear;
// a second fault after it is latched again, alone.
TEST_F(NodeFrames, OneLatchTheFramesAndARefusalReportTheSameFaultsThroughAClear) {
  enable();
  tick(pil::kInjectNonFinite);
  const std::uint32_t latched = node->task.sup.latched;
  EXPECT_EQ(latched, static_cast<std::uint32_t>(kFaultNonFinite));
  EXPECT_EQ(node->task.machine.state, MotionState::kFault);
  EXPECT_EQ(RecordingBoard::actuators.back().faults, latched);
  EXPECT_EQ(state_frame_from_task(node->task).faults, latched);
  take(command(19, MotionVerb::kEnable));
  EXPECT_EQ(RecordingBoard::answers.back().refusal, static_cast<std::uint8_t>(MotionReason::kFaulted));
  EXPECT_EQ(RecordingBoard::answers.back().cause, latched);
  EXPECT_EQ(RecordingBoard::actuators.back().faults, latched);
  EXPECT_EQ(state_frame_from_task(node->task).faults, latched);
  take(command(20, MotionVerb::kClear));
  EXPECT_EQ(RecordingBoard::answers.back().outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  EXPECT_EQ(node->task.machine.state, MotionState::kDisabled);
  EXPECT_EQ(node->task.sup.latched, 0u);
  EXPECT_EQ(state_frame_from_task(node->task).faults, 0u);
  tick();
  EXPECT_EQ(RecordingBoard::actuators.back().faults, 0u);
  arrive(command(21, MotionVerb::kEnable));
  for (int k = 0; k < 5; ++k) tick();
  ASSERT_EQ(node->task.machine.state, MotionState::kHolding);
  tick(pil::kInjectNonFinite);
  EXPECT_EQ(node->task.sup.latched, static_cast<std::uint32_t>(kFaultNonFinite));
  EXPECT_EQ(state_frame_from_task(node->task).faults, node->task.sup.latched);
  EXPECT_EQ(RecordingBoard::actuators.back().faults, node->task.sup.latched);
}

TEST_F(NodeFrames, AReplaceDropsTheQueueAndAReplaceDuringItsBrakeDropsTheMoveBeforeIt) {
  enable();
  const std::vector<std::uint32_t> ids = ids_from(10, 3);
  queue(ids);
  take(small_move(13, 0.01, true));
  std::vector<pil::AnswerFrame> t = tick_answers(13);
  ASSERT_FALSE(t.empty());
  EXPECT_EQ(t[0].outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  EXPECT_EQ(t[0].aborted_id, ids[0]);
  EXPECT_EQ(t[0].abort, static_cast<std::uint8_t>(MotionReason::kSuperseded));
  EXPECT_EQ(t[0].queued, 2);  // the move braking, then the new one
  expect_dropped(t, {ids[1], ids[2]});
  // Another re-target while the first brakes: the move braking was aborted already; the one that
  // waited for it is dropped, and the new one waits in its place.
  take(small_move(14, 0.01, true));
  t = tick_answers(14);
  ASSERT_FALSE(t.empty());
  EXPECT_EQ(t[0].outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  EXPECT_EQ(t[0].aborted_id, 0u);
  EXPECT_EQ(t[0].abort, static_cast<std::uint8_t>(MotionReason::kNone));
  EXPECT_EQ(t[0].queued, 2);
  expect_dropped(t, {13});
  expect_each_ended_once({10, 11, 12, 13});
  EXPECT_TRUE(endings(RecordingBoard::answers, 14).empty());  // it runs next
  EXPECT_EQ(node->task.gen.queued(), 2);
}

/// The paper's motion (from the first tick, no id): the first move brakes it (aborted superseded),
/// the next waits behind its slow-down too, a re-target drops both, and a stop drops the
/// re-target's (the slow-down's abort was reported: the stop's names none).
TEST_F(NodeFrames, MovesWaitBehindThePapersSlowDownAndAReplaceThenAStopDropThem) {
  for (int k = 0; k < 20; ++k) tick();
  take(small_move(10));
  std::vector<pil::AnswerFrame> t = tick_answers(10);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].abort, static_cast<std::uint8_t>(MotionReason::kSuperseded));
  take(small_move(11));  // queued, not a second brake
  t = tick_answers(11);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  EXPECT_EQ(t[0].abort, static_cast<std::uint8_t>(MotionReason::kNone));
  EXPECT_EQ(t[0].queued, 2);
  take(small_move(12, 0.01, true));
  t = tick_answers(12);
  EXPECT_EQ(t[0].abort, static_cast<std::uint8_t>(MotionReason::kNone));
  expect_dropped(t, {10, 11});
  take(command(13, MotionVerb::kStop));
  t = tick_answers(13);
  EXPECT_EQ(t[0].abort, static_cast<std::uint8_t>(MotionReason::kStopCommand));
  EXPECT_EQ(t[0].aborted_id, 0u);
  EXPECT_EQ(t[0].queued, 0);
  expect_dropped(t, {12});
  expect_each_ended_once({10, 11, 12});
}

/// A collision to yield to and a stop (or a disable) in the same tick: the machine passes through
/// yielding (the motion aborted collision) and leaves it at once; the moves end with it, none runs.
TEST_F(NodeFrames, AYieldLeftInItsOwnTickEndsTheMotionAndItsQueue) {
  for (MotionVerb v : {MotionVerb::kStop, MotionVerb::kDisable}) {
    SetUp();
    seq = 0;
    enable();
    queue({10, 11, 12});
    ControlTask<double>& task = node->task;
    arrive(command(20, v));
    motion_update(task, 0, true, task.state.adapt.q_prev, MotionEvents{}, MotionReason::kNone, true);
    const MotionReport& rep = task.report;
    EXPECT_EQ(rep.outcome, CommandOutcome::kAccepted);
    EXPECT_EQ(rep.abort, MotionReason::kCollision);
    EXPECT_EQ(rep.aborted_id, 10u);
    ASSERT_EQ(rep.dropped_moves, 2);
    EXPECT_EQ(task.dropped_move_ids[0], 11u);
    EXPECT_EQ(task.dropped_move_ids[1], 12u);
    EXPECT_EQ(task.machine.state, v == MotionVerb::kStop ? MotionState::kHolding : MotionState::kDisabled);
    EXPECT_EQ(task.gen.source(), MotionSource::kHold);
    EXPECT_EQ(task.gen.queued(), 0);
  }
}

TEST(CommandFrames, AnAnswerFrameReadsBackAsTheReport) {
  MotionReport r;
  r.id = 12;
  r.verb = MotionVerb::kMoveTo;
  r.outcome = CommandOutcome::kRefused;
  r.refusal = MotionReason::kNearSingular;
  r.cause = kFaultSingular;
  r.done_id = 3;
  r.aborted_id = 4;
  r.abort = MotionReason::kSuperseded;
  r.completion = MotionCompletion::kStopped;
  const MotionReport b = report_from_frame(frame_from_report(r, MotionState::kStopping, 2, 77));
  EXPECT_EQ(b.id, r.id);
  EXPECT_EQ(b.verb, r.verb);
  EXPECT_EQ(b.outcome, r.outcome);
  EXPECT_EQ(b.refusal, r.refusal);
  EXPECT_EQ(b.cause, r.cause);
  EXPECT_EQ(b.done_id, r.done_id);
  EXPECT_EQ(b.aborted_id, r.aborted_id);
  EXPECT_EQ(b.abort, r.abort);
  EXPECT_EQ(b.completion, r.completion);
  pil::AnswerFrame bad;
  bad.verb = 200, bad.outcome = 9, bad.refusal = 99, bad.abort = 99, bad.completion = 7;
  const MotionReport n = report_from_frame(bad);
  EXPECT_EQ(n.verb, MotionVerb::kNone);
  EXPECT_EQ(n.outcome, CommandOutcome::kNone);
  EXPECT_EQ(n.refusal, MotionReason::kNone);
  EXPECT_EQ(n.abort, MotionReason::kNone);
  EXPECT_EQ(n.completion, MotionCompletion::kNone);
}

TEST(CommandFrames, LimitsAreSentAsTheF32AtMostThem) {
  MoveRequest<double> req;
  req.has_limits = true;
  req.limits = CartesianLimits<double>::defaults();  // 0.1 m/s: above its nearest f32
  const pil::CommandFrame f = frame_from_command(1, MotionVerb::kMoveTo, req);
  EXPECT_LE(static_cast<double>(f.limits[0]), 0.1);
  EXPECT_EQ(f.limits[0], std::nextafter(0.1f, 0.0f));
  EXPECT_EQ(f.limits[1], 0.25f);  // exact ones stay
  // A move at the configured maxima is within them in double too (not over_limit).
  auto task = std::make_unique<ControlTask<double>>();
  task->init(Model<double>::of(robot::kArm), Gains<double>::paper(), FrictionMode::kAdaptive,
             joint_vector<double>(robot::kQStart), 0, TaskStart::kDisabled);
  pil::CommandFrame m = f;
  m.flags = pil::kFlagRelative | pil::kFlagHasLimits;
  m.position[2] = 0.01f;
  const TaskCommand<double> c = prepare_frame_command(task->gen, task->limits, 0, params::kControlHz, m);
  EXPECT_EQ(c.refusal, MotionReason::kNone);
}

}  // namespace

// ---------------------------------------------------------------- a timer-paced board's poll

namespace {

/// poll_paced() against a task whose ticks the test stands in for: `masked` runs its work and
/// notes that it did (and may let ticks pass first: late), `wait` lets one tick pass.
struct PacedRig {
  std::unique_ptr<ControlTask<double>> task = std::make_unique<ControlTask<double>>();
  CommandPort<double> port;
  std::unique_ptr<CommandPort<double>::PacedInputs> in = std::make_unique<CommandPort<double>::PacedInputs>();
  std::vector<Bytes> written;
  bool inside = false, wrote_outside = false;
  int masked_calls = 0, waits = 0;
  std::uint64_t late_by = 0;  // ticks that pass before the hand-over (the second masked call)
  explicit PacedRig(TaskStart start) {
    task->init(Model<double>::of(robot::kArm), Gains<double>::paper(), FrictionMode::kAdaptive,
               joint_vector<double>(robot::kQStart), 0, start);
  }
  void receive(const pil::CommandFrame& f) {
    ASSERT_TRUE(port.receive(*task, parsed(bytes_of(f)), [&](const std::uint8_t* b, int n) { note(b, n); }));
  }
  void poll() {
    port.poll_paced(
        *task, *in, [&](const std::uint8_t* b, int n) { note(b, n); },
        [&](auto&& work) {
          if (++masked_calls == 2) task->tick += late_by;
          inside = true;
          work();
          inside = false;
        },
        [&] {
          ++waits;
          ++task->tick;
        });
  }
  void note(const std::uint8_t* b, int n) {
    wrote_outside |= !inside;
    written.emplace_back(b, b + n);
  }
};

TEST(CommandPortPaced, AMoveThatBrakesTheMotionGoesInJustBeforeItsPlannedTick) {
  PacedRig r(TaskStart::kPaper);  // the paper's motion runs: a move_to brakes it
  const std::uint64_t t0 = r.task->tick;
  r.receive(small_move(5));
  r.poll();
  EXPECT_EQ(r.task->pending.verb, MotionVerb::kMoveTo);
  EXPECT_TRUE(r.task->pending.brake);
  EXPECT_EQ(r.task->pending.refusal, MotionReason::kNone);
  EXPECT_EQ(r.task->pending.id, 5u);
  EXPECT_EQ(r.task->tick, t0 + kPacedLeadTicks) << "handed over before the tick it was planned for";
  EXPECT_EQ(r.waits, static_cast<int>(kPacedLeadTicks));
  EXPECT_TRUE(r.written.empty());
  EXPECT_EQ(r.port.waiting(), 0);
}

TEST(CommandPortPaced, ABrakedMoveWhoseCheckOutlastedItsLeadIsSuperseded) {
  PacedRig r(TaskStart::kPaper);
  r.late_by = kPacedLeadTicks + 1;  // the path check took longer than the lead
  r.receive(small_move(6));
  r.poll();
  EXPECT_EQ(r.task->pending.verb, MotionVerb::kMoveTo);
  EXPECT_EQ(r.task->pending.refusal, MotionReason::kSuperseded) << "the tick that takes it refuses it";
  EXPECT_EQ(r.waits, 0);
}

TEST(CommandPortPaced, AQueuedCommandGoesInAtOnceAndTheNextWaitsForTheMailbox) {
  PacedRig r(TaskStart::kDisabled);
  r.receive(frame_from_command<double>(1, MotionVerb::kEnable));
  r.receive(small_move(2));
  r.poll();
  EXPECT_EQ(r.task->pending.verb, MotionVerb::kEnable);
  EXPECT_EQ(r.waits, 0);
  EXPECT_EQ(r.port.waiting(), 1) << "the mailbox is taken until a tick takes the enable";
  r.task->pending = {};  // the tick took it
  r.poll();
  EXPECT_EQ(r.task->pending.verb, MotionVerb::kMoveTo);
  EXPECT_FALSE(r.task->pending.brake);
  EXPECT_EQ(r.task->pending.refusal, MotionReason::kNone);
  EXPECT_EQ(r.masked_calls, 6) << "each poll: inputs taken, handed over, then the mailbox taken or the FIFO empty";
}

TEST(CommandPortPaced, ABadVerbIsRefusedAtOnceInsideTheMask) {
  PacedRig r(TaskStart::kDisabled);
  pil::CommandFrame f = frame_from_command<double>(9, MotionVerb::kEnable);
  f.verb = 200;
  r.receive(f);
  r.poll();
  EXPECT_EQ(r.task->pending.verb, MotionVerb::kNone);
  ASSERT_EQ(r.written.size(), 1u);
  EXPECT_FALSE(r.wrote_outside);
  const pil::AnswerFrame a = decoded<pil::AnswerFrame>(parsed(r.written[0]));
  EXPECT_EQ(a.id, 9u);
  EXPECT_EQ(a.refusal, static_cast<std::uint8_t>(MotionReason::kBadCommand));
}

}  // namespace
