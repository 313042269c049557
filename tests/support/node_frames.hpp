// The PIL node over its link, lockstep, on a board that records every frame the node writes (NodeFrames):
// the fixture of the tests of the node's command protocol (tests/firmware/link/test_node.cpp,
// test_command_port.cpp) and of the motion stage driven through it (tests/firmware/runtime/
// test_motion_stage.cpp).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "frame_bytes.hpp"
#include "osc/link/node.hpp"
#include "osc/robot.hpp"

namespace osc::test {

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
  /// The next sensor frame (the arm at the start pose, its encoders dithering by a count; no current
  /// readings, no fault line).
  pil::SensorFrame sensor(std::uint8_t inject = 0) {
    pil::SensorFrame s;
    for (int i = 0; i < kDof; ++i) s.counts[i] = counts[i] + static_cast<std::int32_t>(seq & 1u);
    s.seq = seq++;
    s.inject = inject;
    return s;
  }
  /// One tick: the next sensor frame.
  void tick(std::uint8_t inject = 0) { ASSERT_EQ(arrive(sensor(inject)), 1); }
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

}  // namespace osc::test
