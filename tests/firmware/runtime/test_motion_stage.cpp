// The tick's motion stage (osc/runtime/motion_stage.hpp), driven through the PIL node's commands
// (NodeFrames, tests/support/node_frames.hpp): a collision to yield to and a stop or a disable in the same
// tick end the motion and its queue in that tick.
#include <gtest/gtest.h>

#include "node_frames.hpp"
#include "osc/runtime/motion_stage.hpp"

using namespace osc;
using namespace osc::test;

namespace {

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

}  // namespace
