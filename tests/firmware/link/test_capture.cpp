// The on-board capture (osc/link/capture.hpp) through the command port, as a client drives it: arm,
// trigger by hand, by a fault, by a command, by a level; the pre-trigger and the samples after it; the
// divider; every refusal; and every signal's elements read from the task's own fields. The task is set
// by hand between ticks (the values are the tick numbers), so each held sample names its tick.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "osc/link/command_port.hpp"
#include "task_util.hpp"

namespace {

using namespace osc;
using osc::test::disabled_task;

struct Capture : ::testing::Test {
  std::unique_ptr<ControlTask<double>> task = disabled_task<double>();
  CommandPort<double> port;
  std::vector<float> ring = std::vector<float>(pil::kCaptureValues);
  std::vector<pil::CaptureDataFrame> answers;

  Capture() { port.capture.attach(ring.data(), pil::kCaptureValues); }

  /// A capture frame through the port's receive(): its answer.
  pil::CaptureDataFrame ask(const pil::CaptureFrame& f) {
    std::uint8_t buf[pil::kMaxFrame];
    const int n = pil::encode(f, buf);
    pil::Parser parser;
    const std::size_t before = answers.size();
    const auto sink = [this](const std::uint8_t* b, int len) {
      pil::Parser p;
      for (int j = 0; j < len; ++j)
        if (p.feed(b[j]) == pil::Parser::kFrame) {
          pil::CaptureDataFrame a;
          if (p.decode(a)) answers.push_back(a);
        }
    };
    for (int k = 0; k < n; ++k) {
      if (parser.feed(buf[k]) == pil::Parser::kFrame) {
        EXPECT_TRUE(port.receive(*task, parser, sink));
      }
    }
    EXPECT_EQ(answers.size(), before + 1);
    return answers.empty() ? pil::CaptureDataFrame{} : answers.back();
  }
  static pil::CaptureFrame arm_frame(std::initializer_list<std::pair<int, int>> channels, int trigger, int pre,
                                     int divider = 1) {
    pil::CaptureFrame f;
    f.id = 7;
    f.op = pil::kCaptureOpArm;
    f.channels = static_cast<std::uint8_t>(channels.size());
    int c = 0;
    for (const auto& [signal, element] : channels) {
      f.signal[c] = static_cast<std::uint8_t>(signal);
      f.element[c++] = static_cast<std::uint8_t>(element);
    }
    f.trigger = static_cast<std::uint8_t>(trigger);
    f.pre = static_cast<std::uint32_t>(pre);
    f.divider = static_cast<std::uint8_t>(divider);
    return f;
  }
  pil::CaptureDataFrame op(std::uint8_t o, std::uint32_t offset = 0) {
    pil::CaptureFrame f;
    f.id = 9;
    f.op = o;
    f.offset = offset;
    return ask(f);
  }
  /// One tick as the port sees it: the task's values set to the tick's number (error[1] = n, tau[2] = -n),
  /// then the port's after_tick (the tick count already past it, as control_tick leaves it).
  void tick() {
    const auto n = static_cast<double>(task->tick);
    task->last.e(1) = n;
    task->last.tau(2) = -n;
    ++task->tick;
    port.after_tick(*task, [](const std::uint8_t*, int) {});
    task->report = {};
  }
  void ticks(int n) {
    for (int k = 0; k < n; ++k) tick();
  }
  /// Every value of a done capture, read in chunks.
  std::vector<float> read_all() {
    std::vector<float> v;
    for (;;) {
      const pil::CaptureDataFrame a = op(pil::kCaptureOpRead, static_cast<std::uint32_t>(v.size()));
      EXPECT_EQ(a.status, pil::kCaptureStatusOk);
      EXPECT_EQ(a.offset, v.size());
      if (a.status != pil::kCaptureStatusOk || a.count == 0) return v;
      v.insert(v.end(), a.values, a.values + a.count);
    }
  }
};

constexpr int kE = pil::kCaptureSignalError, kTau = pil::kCaptureSignalTorque;

TEST_F(Capture, ByHandHoldsPreSamplesBeforeTheTriggersTickAndTheRestAfter) {
  const pil::CaptureDataFrame armed = ask(arm_frame({{kE, 1}, {kTau, 2}}, pil::kCaptureTriggerManual, 100));
  EXPECT_EQ(armed.status, pil::kCaptureStatusOk);
  EXPECT_EQ(armed.state, pil::kCaptureStateArmed);
  ticks(500);
  EXPECT_EQ(op(pil::kCaptureOpStatus).state, pil::kCaptureStateArmed);
  EXPECT_EQ(op(pil::kCaptureOpRead).status, pil::kCaptureStatusNotDone);
  EXPECT_EQ(op(pil::kCaptureOpTrigger).status, pil::kCaptureStatusOk);
  tick();  // the trigger's sample: tick 500
  const int depth = pil::kCaptureValues / 2;
  EXPECT_EQ(op(pil::kCaptureOpStatus).state, pil::kCaptureStateTriggered);
  ticks(depth - 100 - 2);
  EXPECT_EQ(op(pil::kCaptureOpStatus).state, pil::kCaptureStateTriggered);
  tick();
  const pil::CaptureDataFrame done = op(pil::kCaptureOpStatus);
  EXPECT_EQ(done.state, pil::kCaptureStateDone);
  EXPECT_EQ(done.trigger_tick, 500u);
  EXPECT_EQ(done.pre, 100u);
  EXPECT_EQ(done.first_tick, 400u);
  EXPECT_EQ(done.depth, static_cast<std::uint32_t>(depth));
  EXPECT_EQ(done.channels, 2);
  ticks(50);  // done: nothing more is recorded
  const std::vector<float> v = read_all();
  ASSERT_EQ(v.size(), static_cast<std::size_t>(2 * depth));
  for (int s = 0; s < depth; ++s) {
    EXPECT_EQ(v[2 * s], static_cast<float>(400 + s)) << s;
    EXPECT_EQ(v[2 * s + 1], -static_cast<float>(400 + s)) << s;
  }
  EXPECT_EQ(op(pil::kCaptureOpRead, static_cast<std::uint32_t>(v.size())).count, 0);
  EXPECT_EQ(op(pil::kCaptureOpRead, static_cast<std::uint32_t>(v.size()) + 1).status, pil::kCaptureStatusBadOffset);
}

TEST_F(Capture, AFaultTriggersInTheTickThatLatchesIt) {
  task->sup.latched = kFaultTracking;  // latched before the arm: no trigger
  ask(arm_frame({{kE, 1}}, pil::kCaptureTriggerFault, 300));
  ticks(1000);
  EXPECT_EQ(op(pil::kCaptureOpStatus).state, pil::kCaptureStateArmed);
  task->sup.latched |= kFaultEncoderJump;
  ticks(pil::kCaptureValues);
  const pil::CaptureDataFrame done = op(pil::kCaptureOpStatus);
  ASSERT_EQ(done.state, pil::kCaptureStateDone);
  EXPECT_EQ(done.trigger_tick, 1000u);
  EXPECT_EQ(done.pre, 300u);
  const std::vector<float> v = read_all();
  ASSERT_EQ(v.size(), static_cast<std::size_t>(pil::kCaptureValues));
  EXPECT_EQ(v[0], 700.0f);
  EXPECT_EQ(v[300], 1000.0f);
  EXPECT_EQ(v.back(), static_cast<float>(700 + pil::kCaptureValues - 1));
}

TEST_F(Capture, AnEarlyTriggerHoldsTheSamplesThereWere) {
  ask(arm_frame({{kE, 1}}, pil::kCaptureTriggerCommand, 300));
  ticks(20);
  task->report.outcome = CommandOutcome::kRefused;  // a refusal is no trigger
  tick();
  EXPECT_EQ(op(pil::kCaptureOpStatus).state, pil::kCaptureStateArmed);
  task->report.outcome = CommandOutcome::kAccepted;
  tick();
  ticks(pil::kCaptureValues);
  const pil::CaptureDataFrame done = op(pil::kCaptureOpStatus);
  ASSERT_EQ(done.state, pil::kCaptureStateDone);
  EXPECT_EQ(done.trigger_tick, 21u);
  EXPECT_EQ(done.pre, 21u);
  EXPECT_EQ(done.first_tick, 0u);
  EXPECT_EQ(done.depth, static_cast<std::uint32_t>(21 + pil::kCaptureValues - 300));
  const std::vector<float> v = read_all();
  ASSERT_EQ(v.size(), done.depth);
  for (std::size_t s = 0; s < v.size(); ++s) EXPECT_EQ(v[s], static_cast<float>(s)) << s;
}

TEST_F(Capture, ALevelTriggersOnItsCrossingInItsDirectionOnly) {
  // tau[2] = -tick falls through -250 at tick 250: a rising trigger never fires, a falling one there.
  pil::CaptureFrame f = arm_frame({{kE, 1}, {kTau, 2}}, pil::kCaptureTriggerRising, 10);
  f.level_channel = 1;
  f.level = -250.0f;
  ask(f);
  ticks(400);
  EXPECT_EQ(op(pil::kCaptureOpStatus).state, pil::kCaptureStateArmed);
  f.trigger = pil::kCaptureTriggerFalling;
  ask(f);
  task->tick = 0;
  ticks(pil::kCaptureValues);
  const pil::CaptureDataFrame done = op(pil::kCaptureOpStatus);
  ASSERT_EQ(done.state, pil::kCaptureStateDone);
  EXPECT_EQ(done.trigger_tick, 250u);
  // A level the first sample is already beyond: no crossing seen, no trigger.
  f.level = 5.0f;
  f.trigger = pil::kCaptureTriggerRising;
  f.level_channel = 0;
  ask(f);
  task->tick = 10;
  ticks(100);
  EXPECT_EQ(op(pil::kCaptureOpStatus).state, pil::kCaptureStateArmed);
}

TEST_F(Capture, TheDividerTakesEveryNthTick) {
  ask(arm_frame({{kE, 1}}, pil::kCaptureTriggerFault, 50, 4));
  ticks(1001);                        // samples at ticks 0, 4, ..., 1000
  task->sup.latched = kFaultOverrun;  // in tick 1001: the trigger's sample is tick 1004's
  ticks(4 * pil::kCaptureValues);
  const pil::CaptureDataFrame done = op(pil::kCaptureOpStatus);
  ASSERT_EQ(done.state, pil::kCaptureStateDone);
  EXPECT_EQ(done.divider, 4);
  EXPECT_EQ(done.trigger_tick, 1004u);
  EXPECT_EQ(done.first_tick, 1004u - 4 * 50);
  const std::vector<float> v = read_all();
  ASSERT_EQ(v.size(), static_cast<std::size_t>(pil::kCaptureValues));
  for (std::size_t s = 0; s < v.size(); ++s) ASSERT_EQ(v[s], static_cast<float>(done.first_tick + 4 * s)) << s;
}

TEST_F(Capture, EachBadRequestIsRefusedByNameAndLeavesItIdle) {
  const auto status = [this](const pil::CaptureFrame& f) { return ask(f).status; };
  pil::CaptureFrame f = arm_frame({{kE, 0}}, pil::kCaptureTriggerManual, 0);
  f.op = pil::kCaptureOpCount;
  EXPECT_EQ(status(f), pil::kCaptureStatusBadOp);
  EXPECT_EQ(status(arm_frame({}, pil::kCaptureTriggerManual, 0)), pil::kCaptureStatusBadChannel);
  f = arm_frame({{kE, 0}}, pil::kCaptureTriggerManual, 0);
  f.channels = pil::kCaptureChannels + 1;
  EXPECT_EQ(status(f), pil::kCaptureStatusBadChannel);
  EXPECT_EQ(status(arm_frame({{pil::kCaptureSignalCount, 0}}, 0, 0)), pil::kCaptureStatusBadChannel);
  EXPECT_EQ(status(arm_frame({{kE, 6}}, 0, 0)), pil::kCaptureStatusBadChannel);
  EXPECT_EQ(status(arm_frame({{pil::kCaptureSignalThetaHat, 3 * kDof}}, 0, 0)), pil::kCaptureStatusBadChannel);
  EXPECT_EQ(status(arm_frame({{kE, 0}}, pil::kCaptureTriggerCount, 0)), pil::kCaptureStatusBadTrigger);
  f = arm_frame({{kE, 0}, {kE, 1}}, pil::kCaptureTriggerRising, 0);
  f.level_channel = 2;
  EXPECT_EQ(status(f), pil::kCaptureStatusBadTrigger);
  f.level_channel = 1;
  f.level = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(status(f), pil::kCaptureStatusBadTrigger);
  EXPECT_EQ(status(arm_frame({{kE, 0}, {kE, 1}}, 0, pil::kCaptureValues / 2)), pil::kCaptureStatusBadSpan);
  EXPECT_EQ(status(arm_frame({{kE, 0}}, 0, 0, 0)), pil::kCaptureStatusBadSpan);
  EXPECT_EQ(op(pil::kCaptureOpStatus).state, pil::kCaptureStateIdle);
  EXPECT_EQ(op(pil::kCaptureOpTrigger).status, pil::kCaptureStatusNotArmed);
  EXPECT_EQ(op(pil::kCaptureOpRead).status, pil::kCaptureStatusNotDone);
  // An armed capture aborted is idle; a board without a buffer refuses every arm.
  EXPECT_EQ(status(arm_frame({{kE, 0}}, 0, 0)), pil::kCaptureStatusOk);
  EXPECT_EQ(op(pil::kCaptureOpAbort).state, pil::kCaptureStateIdle);
  port.capture.attach(nullptr, 0);
  EXPECT_EQ(status(arm_frame({{kE, 0}}, 0, 0)), pil::kCaptureStatusNoBuffer);
}

TEST_F(Capture, IdleOrDoneItWritesNothing) {
  std::fill(ring.begin(), ring.end(), 123.0f);
  ticks(100);
  for (float x : ring) ASSERT_EQ(x, 123.0f);
  ask(arm_frame({{kE, 1}}, pil::kCaptureTriggerManual, 0));
  op(pil::kCaptureOpTrigger);
  ticks(pil::kCaptureValues);
  ASSERT_EQ(op(pil::kCaptureOpStatus).state, pil::kCaptureStateDone);
  const std::vector<float> before = ring;
  ticks(100);
  EXPECT_EQ(ring, before);
}

// Every element of every signal reads the task's field the document names (each set to a distinct value).
TEST_F(Capture, EverySignalReadsItsField) {
  ControlTask<double>& t = *task;
  const auto v = [](int signal, int k) { return 1000.0 * signal + k + 0.5; };
  for (int k = 0; k < 6; ++k) {
    t.last.e(k) = v(pil::kCaptureSignalError, k);
    t.last.x_tilde(k) = v(pil::kCaptureSignalObserverError, k);
    t.last.xd_hat(k) = v(pil::kCaptureSignalVelocity, k);
  }
  for (int k = 0; k < kDof; ++k) {
    t.last.tau(k) = v(pil::kCaptureSignalTorque, k);
    t.last.tau_f_hat(k) = v(pil::kCaptureSignalFrictionTorque, k);
    t.residual.r(k) = v(pil::kCaptureSignalResidual, k);
    t.residual.threshold(k) = v(pil::kCaptureSignalResidualThreshold, k);
    t.codes[k] = static_cast<std::int32_t>(v(pil::kCaptureSignalCodes, k));
    t.drive.threshold[k] = static_cast<std::int32_t>(v(pil::kCaptureSignalDriveMargin, k)) + 7;
    t.drive.distance[k] = 7;
  }
  for (int k = 0; k < 3 * kDof; ++k) t.state.adapt.theta_hat(k) = v(pil::kCaptureSignalThetaHat, k);
  for (int k = 0; k < kTickStages; ++k)
    t.stages.stage[k].last = static_cast<std::uint32_t>(v(pil::kCaptureSignalStageCycles, k));
  for (int s = 0; s < pil::kCaptureSignalCount; ++s) {
    ASSERT_GT(pil::kCaptureSignals[s].elements, 0);
    for (int k = 0; k < pil::kCaptureSignals[s].elements; ++k) {
      const bool integral =
          s == pil::kCaptureSignalCodes || s == pil::kCaptureSignalDriveMargin || s == pil::kCaptureSignalStageCycles;
      const double want = integral ? std::floor(v(s, k)) : v(s, k);
      EXPECT_EQ(capture_value(t, static_cast<std::uint8_t>(s), k), static_cast<float>(want))
          << pil::kCaptureSignals[s].name << "[" << k << "]";
    }
  }
}

}  // namespace

namespace {

// The level trigger's integer order (no float comparison on the tick of an FPU-less core) is the floats' order.
TEST(CaptureOrder, OrdersAsTheFloatsDo) {
  const float inf = std::numeric_limits<float>::infinity();
  const float v[] = {-inf, -3e38f, -1.0f, -1e-30f, -1e-45f, 0.0f, 1e-45f, 1e-30f, 0.5f, 1.0f, 2.0f, 3e38f, inf};
  for (float a : v)
    for (float b : v) {
      EXPECT_EQ(osc::capture_order(a) < osc::capture_order(b), a < b) << a << " " << b;
      EXPECT_EQ(osc::capture_order(a) == osc::capture_order(b), a == b) << a << " " << b;
    }
  EXPECT_EQ(osc::capture_order(-0.0f), osc::capture_order(0.0f));
}

}  // namespace
