// The main loop's side of an identify run on a board that estimates (osc/link/identify_port.hpp): the run followed
// from the tick that accepted it, its report sent as one identify frame after the end's answer and its drives' torque
// offsets right after it (an identify_offset frame), and an aborted run's frames. Over the simulated arm (MotionSim),
// the frames decoded from the bytes a board would send.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "motion_sim.hpp"
#include "motion_sim_util.hpp"
#include "osc/link/identify_port.hpp"
#include "osc/robot.hpp"

using namespace osc;
using sim::MotionSim;
using test::answer;
using test::run_ticks;

namespace {

/// The frames a board would send, decoded, each with the tick it came after.
struct Sent {
  std::vector<pil::IdentifyFrame> frames;
  std::vector<std::uint64_t> ticks;
  std::vector<pil::IdentifyOffsetFrame> offsets;    ///< identify_offset frames
  std::vector<pil::IdentifyPayloadFrame> payloads;  ///< identify_payload frames (a run with the flag payload)
  /// identify_offset frames not right after their identify frame, identify_payload frames not right after those
  int order_errors = 0;
  pil::FrameType last_type = pil::kActuatorFrame;  ///< the last frame's type
};

/// Runs ticks with the port after each `every`-th, until `until` holds after a tick or max ticks; the identify frames
/// sent.
template <class Until>
void run(MotionSim<double>& sim, IdentifyPort<double>& port, Sent& sent, std::uint64_t max, Until until,
         std::uint64_t every = 1) {
  pil::Parser parser;
  const auto write = [&](const std::uint8_t* b, int n) {
    for (int i = 0; i < n; ++i)
      if (parser.feed(b[i]) == pil::Parser::kFrame) {
        pil::IdentifyFrame f;
        pil::IdentifyOffsetFrame o;
        pil::IdentifyPayloadFrame p;
        if (parser.decode(o)) {
          sent.order_errors += sent.frames.empty() || sent.frames.back().id != o.id ||
                               sent.offsets.size() + 1 != sent.frames.size() || sent.last_type != pil::kIdentifyFrame;
          sent.offsets.push_back(o);
          sent.last_type = pil::kIdentifyOffsetFrame;
          continue;
        }
        if (parser.decode(p)) {
          sent.order_errors +=
              sent.frames.empty() || sent.frames.back().id != p.id || sent.last_type != pil::kIdentifyOffsetFrame;
          sent.payloads.push_back(p);
          sent.last_type = pil::kIdentifyPayloadFrame;
          continue;
        }
        ASSERT_TRUE(parser.decode(f)) << "a frame other than identify, identify_offset and identify_payload";
        sent.order_errors += !sent.frames.empty() && sent.offsets.size() != sent.frames.size();
        sent.last_type = pil::kIdentifyFrame;
        sent.frames.push_back(f);
        sent.ticks.push_back(sim.task().tick);
      }
  };
  for (std::uint64_t k = 0; k < max; ++k) {
    ASSERT_EQ(sim.tick(), 0u);
    if (sim.task().tick % every == 0) port.after_tick(sim.task(), write);
    if (until()) return;
  }
}

}  // namespace

/// The arm enabled and holding for half a second.
void enable_and_hold(MotionSim<double>& sim) {
  ASSERT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 500);
}

/// One run of command `id` with the port after every tick, to its end and 50 ticks more: its frames into `sent`, the
/// tick that reported it done into `done_tick` (0: it did not end).
void run_to_end(MotionSim<double>& sim, IdentifyPort<double>& port, Sent& sent, std::uint32_t id,
                std::uint64_t& done_tick) {
  sim.identify(id);
  done_tick = 0;
  run(sim, port, sent, excitation::kTicks + 200, [&] {
    if (sim.task().report.done_id == id) done_tick = sim.task().tick;
    return done_tick != 0 && sim.task().tick > done_tick + 50;
  });
}

// Two runs on the ideal plant, the second with the same id (a client's retry): one identify frame each, after the
// tick that reported the run done; its coefficients within issue 57's bar of the plant's (10 %, or 0.05 where that is
// more), each marked identified exactly where its standard deviation is within params::kIdentifiedFraction of it, the
// armatures' corrections near 0 (the model's armature is the plant's).
TEST(IdentifyPort, EachRunsEstimateComesAsOneFrameAfterItsEnd) {
  MotionSim<double> sim(test::identify_pose());
  IdentifyPort<double> port;
  ASSERT_NO_FATAL_FAILURE(enable_and_hold(sim));
  Sent sent;
  for (std::size_t n = 1; n <= 2; ++n) {
    std::uint64_t done_tick = 0;
    run_to_end(sim, port, sent, 9, done_tick);
    ASSERT_NE(done_tick, 0u) << "run " << n << " did not end";
    ASSERT_EQ(sent.frames.size(), n);
    EXPECT_EQ(sent.ticks.back(), done_tick);
    const pil::IdentifyFrame& f = sent.frames.back();
    EXPECT_EQ(f.id, 9u);
    ASSERT_EQ(f.status, static_cast<std::uint8_t>(IdentifyStatus::kOk));
    EXPECT_GE(f.samples, 15900u);
    EXPECT_EQ(f.lost, 0u);
    EXPECT_GT(f.condition, 1.0f);
    EXPECT_LT(f.prediction_error, static_cast<float>(params::kIdentifyMaxPredictionError));
    const FrictionCoefficients& truth = *robot::kFrictionPresets[0];
    const double* t[3] = {truth.vis, truth.cou, truth.sti};
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < kDof; ++i) {
        const int k = c * kDof + i;
        EXPECT_LE(std::fabs(f.friction[k] - t[c][i]), std::max(0.1 * t[c][i], 0.05)) << "coefficient " << k;
        const bool identified = f.friction_sd[k] <= params::kIdentifiedFraction * std::fabs(f.friction[k]);
        EXPECT_EQ(((f.identified >> k) & 1u) != 0, identified) << "coefficient " << k;
      }
    // Near 0: within 4 sigma plus 1 % of the drive's described armature (J3's comes out 0.004 kg m^2, 0.7 % of its
    // 0.58 and 5-6 sigma on the ideal plant: a bias its sigma does not cover, docs/adaptation.md).
    for (int i = 0; i < kDof; ++i)
      EXPECT_LE(std::fabs(f.armature[i]), 4 * f.armature_sd[i] + 0.01 * sim.task().armature_base[i]) << "drive " << i;
    // Right after it, each drive's torque offset: the ideal plant's amplifiers add none, so near 0 (within 3 sigma and
    // 6 mN m, test_identify_sim's bound; J3's came out 5 mN m off on the realistic plant).
    ASSERT_EQ(sent.offsets.size(), n);
    const pil::IdentifyOffsetFrame& o = sent.offsets.back();
    EXPECT_EQ(o.id, 9u);
    EXPECT_EQ(o.status, f.status);
    for (int i = 0; i < kDof; ++i) {
      EXPECT_GT(o.offset_sd[i], 0.0f) << "drive " << i;
      EXPECT_LE(std::fabs(o.offset[i]), 3 * o.offset_sd[i] + 0.006) << "drive " << i;
    }
    EXPECT_EQ(sent.order_errors, 0);
    EXPECT_EQ(port.reports(), n);
    EXPECT_FALSE(port.active());
    EXPECT_TRUE(sent.payloads.empty()) << "no identify_payload frame without the flag payload";
  }
}

// A run asked with the flag payload on an arm carrying 1.5 kg at (0, 0.05, 0.08) m, the model set roughly (10 % light,
// its centre of mass 10 % short, as a datasheet's), and amplifiers that add a constant torque to J2 and J5: its
// identify frame, its identify_offset frame with those offsets (within 3 sigma and 6 mN m), then its identify_payload
// frame, with the whole payload (the run's model is the arm's own): mass within 3 %, centre of mass within 5 mm (issue
// 57's bars); every estimated parameter with a standard deviation, the mass's verdict as its sigma says.
TEST(IdentifyPort, ARunWithThePayloadFlagSendsThePayloadRightAfterItsEstimate) {
  sim::PlantConfig pc;
  pc.payload.mass = 1.5;
  pc.payload.com[1] = 0.05, pc.payload.com[2] = 0.08;
  pc.amp_offset[1] = 0.05, pc.amp_offset[4] = -0.02;  // N m, joint-referred
  MotionSim<double> sim(test::identify_pose(), {}, pc);
  Payload guess;
  guess.mass = 0.9 * 1.5;
  guess.com[1] = 0.9 * 0.05, guess.com[2] = 0.9 * 0.08;
  sim.task().set_payload(guess);
  IdentifyPort<double> port;
  ASSERT_NO_FATAL_FAILURE(enable_and_hold(sim));
  Sent sent;
  sim.identify(4, nullptr, payload_mask::kAll);
  std::uint64_t done_tick = 0;
  run(sim, port, sent, excitation::kTicks + 200, [&] {
    if (sim.task().report.done_id == 4) done_tick = sim.task().tick;
    return done_tick != 0 && sim.task().tick > done_tick + 50;
  });
  ASSERT_NE(done_tick, 0u);
  ASSERT_EQ(sent.frames.size(), 1u);
  ASSERT_EQ(sent.offsets.size(), 1u);
  ASSERT_EQ(sent.payloads.size(), 1u);
  EXPECT_EQ(sent.order_errors, 0);
  const pil::IdentifyOffsetFrame& o = sent.offsets[0];
  ASSERT_EQ(o.status, static_cast<std::uint8_t>(IdentifyStatus::kOk));
  for (int i = 0; i < kDof; ++i) {
    std::printf("offset J%d: %.4f N m (plant %.4f), sd %.4f\n", i + 1, static_cast<double>(o.offset[i]),
                pc.amp_offset[i], static_cast<double>(o.offset_sd[i]));
    EXPECT_NEAR(o.offset[i], pc.amp_offset[i], 3 * o.offset_sd[i] + 0.006) << "drive " << i;
  }
  const pil::IdentifyPayloadFrame& p = sent.payloads[0];
  EXPECT_EQ(p.id, 4u);
  ASSERT_EQ(p.status, static_cast<std::uint8_t>(IdentifyStatus::kOk));
  EXPECT_EQ(sent.frames[0].status, p.status);
  EXPECT_NEAR(p.mass, 1.5, 0.03 * 1.5);
  const double off = std::hypot(p.com[0] - 0.0, p.com[1] - 0.05, p.com[2] - 0.08);
  EXPECT_LT(off, 5e-3);
  for (int k = 0; k < 10; ++k) EXPECT_GT(p.pi_sd[k], 0.0f) << k;
  EXPECT_EQ((p.identified & 1u) != 0, p.pi_sd[0] <= params::kIdentifiedFraction * p.mass);
  std::printf("payload over the port: %.4f kg, centre of mass %.2f mm off, mass sd %.4f kg\n",
              static_cast<double>(p.mass), 1e3 * off, static_cast<double>(p.pi_sd[0]));
}

// A run stopped at once: one frame, status aborted, no estimate in it. Another identify while the arm still brakes is
// refused (busy: the run it aborted still brakes) and sends no identify frame.
TEST(IdentifyPort, AStoppedRunIsReportedAbortedAndARefusedOneNotAtAll) {
  MotionSim<double> sim(test::identify_pose());
  IdentifyPort<double> port;
  ASSERT_NO_FATAL_FAILURE(enable_and_hold(sim));
  Sent sent;
  sim.identify(4);
  run(sim, port, sent, 20, [] { return false; });
  EXPECT_TRUE(port.active());
  sim.command(MotionVerb::kStop, 5);
  run(sim, port, sent, 5000, [&] { return sim.task().report.aborted_id == 4; });
  ASSERT_EQ(sent.frames.size(), 1u);
  const pil::IdentifyFrame& f = sent.frames.back();
  EXPECT_EQ(f.id, 4u);
  EXPECT_EQ(f.status, static_cast<std::uint8_t>(IdentifyStatus::kAborted));
  EXPECT_EQ(f.identified, 0u);
  EXPECT_TRUE(std::all_of(std::begin(f.friction), std::end(f.friction), [](float v) { return v == 0.0f; }));
  ASSERT_EQ(sent.offsets.size(), 1u);
  EXPECT_EQ(sent.offsets[0].status, f.status);
  EXPECT_TRUE(std::all_of(std::begin(sent.offsets[0].offset), std::end(sent.offsets[0].offset),
                          [](float v) { return v == 0.0f; }));
  EXPECT_EQ(sent.order_errors, 0);
  EXPECT_FALSE(port.active());
  ASSERT_TRUE(test::state_is(sim, MotionState::kStopping));
  sim.identify(6);
  run(sim, port, sent, 1, [] { return true; });
  ASSERT_EQ(sim.task().report.outcome, CommandOutcome::kRefused);
  EXPECT_EQ(sim.task().report.refusal, MotionReason::kBusy) << motion_name(sim.task().report.refusal);
  run(sim, port, sent, 3000, [&] { return test::state_is(sim, MotionState::kHolding); });
  run(sim, port, sent, 1000, [] { return false; });
  EXPECT_EQ(sent.frames.size(), 1u);
  EXPECT_FALSE(port.active());
  EXPECT_EQ(port.reports(), 1u);
}

// A main loop that runs only every 20 ticks (a timer-paced board's, busy): it misses the ticks that accepted and ended
// the run, yet follows it (the sampler's counts) and reads every tick it recorded (the ring holds 64): one frame, at
// its first call after the end, with the estimate of a port called after every tick, bit for bit.
TEST(IdentifyPort, AMainLoopThatCallsEvery20TicksGetsTheSameEstimate) {
  Sent every_tick, every_20;
  std::uint64_t end_tick[2] = {0, 0};
  for (int pass = 0; pass < 2; ++pass) {
    MotionSim<double> sim(test::identify_pose());
    IdentifyPort<double> port;
    ASSERT_NO_FATAL_FAILURE(enable_and_hold(sim));
    while (sim.task().tick % 20 != 7) ASSERT_EQ(sim.tick(), 0u);  // the accept's tick is not a call's
    sim.identify(11);
    Sent& sent = pass == 0 ? every_tick : every_20;
    std::uint64_t& done = end_tick[pass];
    run(
        sim, port, sent, excitation::kTicks + 200,
        [&] {
          if (sim.task().report.done_id == 11) done = sim.task().tick;
          return done != 0 && sim.task().tick > done + 50;
        },
        pass == 0 ? 1 : 20);
    ASSERT_NE(done, 0u);
    ASSERT_EQ(sent.frames.size(), 1u) << "pass " << pass;
    EXPECT_FALSE(port.active());
  }
  EXPECT_NE(end_tick[1] % 20, 0u);  // the end's tick was not a call's either
  EXPECT_EQ(every_20.ticks[0], (end_tick[1] / 20 + 1) * 20);
  const pil::IdentifyFrame &a = every_tick.frames[0], &b = every_20.frames[0];
  ASSERT_EQ(a.status, static_cast<std::uint8_t>(IdentifyStatus::kOk));
  EXPECT_EQ(b.status, a.status);
  EXPECT_EQ(b.samples, a.samples);
  EXPECT_EQ(b.lost, 0u);
  for (int k = 0; k < 3 * kDof; ++k) {
    EXPECT_EQ(b.friction[k], a.friction[k]) << "coefficient " << k;
    EXPECT_EQ(b.friction_sd[k], a.friction_sd[k]) << "coefficient " << k;
  }
  EXPECT_EQ(b.identified, a.identified);
  ASSERT_EQ(every_tick.offsets.size(), 1u);
  ASSERT_EQ(every_20.offsets.size(), 1u);
  for (int i = 0; i < kDof; ++i) EXPECT_EQ(every_20.offsets[0].offset[i], every_tick.offsets[0].offset[i]) << i;
}
