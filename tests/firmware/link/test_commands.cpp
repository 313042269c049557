// The command protocol's conversions (osc/link/commands.hpp) and the frames they fill: the sensor and
// actuator frames unchanged byte for byte, round trips of every frame type through the encoder and the
// parser, a command frame decoded into a request and back, each kind of bad field refused with
// bad_command, setpoints, preparing a frame's command, the answer and state frames of a running task
// (PilNode<double> on a fake board), and a command answered in the tick after it arrives. The command
// frames' layouts: test_command_frames.cpp; the node's command port: test_command_port.cpp, test_node.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "frame_bytes.hpp"
#include "osc/link/commands.hpp"
#include "osc/link/node.hpp"
#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"

using namespace osc;
using namespace osc::test;

namespace {

// ---------------------------------------------------------------- layouts

TEST(CommandFrames, SensorAndActuatorFramesUnchangedByteForByte) {
  // docs/protocol.md's worked examples, as encoded before the command frames existed (the actuator
  // frame with the 8 tick stages of issue 54; the sensor frame with the amplifiers' currents and drive
  // byte of issue 56, its bytes from Python's struct and the CRC's definition).
  pil::SensorFrame s;
  s.seq = 1234;
  const std::int32_t counts[pil::kJoints] = {1500, -2750, 40, -3, 0, 12};
  const std::int16_t currents[pil::kJoints] = {310, -1200, 45, 0, -7, 2};
  for (int i = 0; i < pil::kJoints; ++i) s.counts[i] = counts[i], s.currents[i] = currents[i];
  s.drive = pil::drive_byte(1u << 2, true);
  const Bytes sensor = {0xA5, 0x5A, 0x01, 0x2A, 0xD2, 0x04, 0x00, 0x00, 0xDC, 0x05, 0x00, 0x00, 0x42, 0xF5, 0xFF, 0xFF,
                        0x28, 0x00, 0x00, 0x00, 0xFD, 0xFF, 0xFF, 0xFF, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x00, 0x00, 0x00,
                        0x36, 0x01, 0x50, 0xFB, 0x2D, 0x00, 0x00, 0x00, 0xF9, 0xFF, 0x02, 0x00, 0x84, 0x00, 0xE7, 0xCC};
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
        case pil::kIdentifyFrame:
          out = bytes_of(decoded<pil::IdentifyFrame>(p));
          break;
        case pil::kParamAnswerFrame:
          out = bytes_of(decoded<pil::ParamAnswerFrame>(p));
          break;
        case pil::kCaptureFrame:
          out = bytes_of(decoded<pil::CaptureFrame>(p));
          break;
        case pil::kCaptureDataFrame:
          out = bytes_of(decoded<pil::CaptureDataFrame>(p));
          break;
        case pil::kIdentifyPayloadFrame:
          out = bytes_of(decoded<pil::IdentifyPayloadFrame>(p));
          break;
        case pil::kIdentifyOffsetFrame:
          out = bytes_of(decoded<pil::IdentifyOffsetFrame>(p));
          break;
      }
      ASSERT_EQ(out, in) << info.name;
    }
  }
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

// ---------------------------------------------------------------- refusals

struct BadField {
  const char* what;
  void (*spoil)(pil::CommandFrame&);
};

const BadField kBad[] = {
    {"verb one past the list", [](pil::CommandFrame& f) { f.verb = MotionNames<MotionVerb>::kCount; }},
    {"verb 255", [](pil::CommandFrame& f) { f.verb = 255; }},
    {"flag bit 5", [](pil::CommandFrame& f) { f.flags |= 1u << 5; }},
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
  for (int i = 0; i < 6; ++i) f.limits[i] = detail::f32_at_most(lim[i]);  // as a client sends them: at most
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
  EXPECT_EQ(static_cast<int>(MotionReason::kDropped), 23);    // issue 53's, after them
  EXPECT_EQ(static_cast<int>(MotionReason::kNotNeeded), 24);  // issue 55's, after it
  EXPECT_EQ(static_cast<int>(MotionReason::kUnstableLoop), 25);
  EXPECT_STREQ(motion_name(MotionReason::kUnstableLoop), "unstable_loop");
  EXPECT_EQ(static_cast<int>(MotionReason::kUnstableLoop) + 1, MotionNames<MotionReason>::kCount);
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
  // The saved friction's check is the momentum law's (FrictionIdentifier::checked and stale): nothing set, none.
  EXPECT_EQ(s.friction_checked, 0);
  EXPECT_EQ(s.friction_stale, 0);
  FrictionIdentifier<double>& id = node->task.state.adapt.identifier;
  id.fit.judged[0] = 0x1, id.fit.judged[1] = 0x6, id.fit.stale = 0x4;
  const pil::StateFrame v = state_frame_from_task(node->task);
  EXPECT_EQ(v.friction_checked, 0x7);
  EXPECT_EQ(v.friction_stale, 0x4);
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
  req.limits = CartesianLimits<double>::defaults();  // the arm's maxima (0.1 or 0.2 m/s lie below their nearest f32)
  const pil::CommandFrame f = frame_from_command(1, MotionVerb::kMoveTo, req);
  const double lim[3] = {req.limits.linear.v, req.limits.linear.a, req.limits.linear.j};
  int rounded_down = 0;
  for (int i = 0; i < 3; ++i) {
    // The largest f32 at most the limit: an exact one stays, any other is rounded down.
    EXPECT_LE(static_cast<double>(f.limits[i]), lim[i]) << i;
    EXPECT_GT(static_cast<double>(std::nextafter(f.limits[i], HUGE_VALF)), lim[i]) << i;
    rounded_down += static_cast<double>(f.limits[i]) < lim[i];
  }
  EXPECT_GE(rounded_down, 1) << "one of the maxima is not an f32 (the case this test is for)";
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
