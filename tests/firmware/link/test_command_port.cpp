// The controller's end of the command protocol (osc/link/command_port.hpp) in the PIL node (NodeFrames,
// node_frames.hpp): commands waiting for the mailbox in order and answered once, a resend answered again
// and run once, the FIFO full and a verb outside the list refused at once, no answers to a host that
// never commands, streams and their setpoints; every accepted motion ending once, each move a tick drops
// named in its tick; and a timer-paced board's poll (poll_paced).
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "node_frames.hpp"
#include "osc/link/command_port.hpp"
#include "test_util.hpp"

using namespace osc;
using namespace osc::test;

namespace {

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
  OSC_PUMA_TUNED("its refused command is a home, which an absolute arm answers not_needed");
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

// ---------------------------------------------------------------- a timer-paced board's poll

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
