// Commands to the task from outside the tick (osc/runtime/command_prep.hpp): a path check's status as a
// refusal; a move_to prepared in full, whose end angles put the wrist centre at its target within the
// path check's tolerance (forward kinematics: another path than the check's Newton steps), and one out of
// the arm's reach refused; a stream's setpoint taken only by its own stream, one not yet taken replaced
// and counted.
#include <gtest/gtest.h>

#include "osc/kernels/kinematics.hpp"
#include "osc/runtime/command_prep.hpp"
#include "task_util.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST(CommandPrep, APathChecksStatusIsItsRefusal) {
  EXPECT_EQ(path_refusal(PathStatus::kOk), MotionReason::kNone);
  EXPECT_EQ(path_refusal(PathStatus::kNearSingular), MotionReason::kNearSingular);
  EXPECT_EQ(path_refusal(PathStatus::kOutOfWorkspace), MotionReason::kOutOfWorkspace);
  EXPECT_EQ(path_refusal(PathStatus::kUnreachable), MotionReason::kOutOfWorkspace);  // beyond its reach
}

TEST(CommandPrep, APreparedMoveEndsAtItsTargetAndOneOutOfReachIsRefused) {
  auto task = disabled_task<double>();
  Data<double> start;
  forward_kinematics(task->model, start, task->q_start);
  MoveRequest<double> req;
  req.relative = true;
  req.position = Vec3<double>(0.02, -0.01, 0.03);
  const TaskCommand<double> c = prepare_checked_move(*task, req, 7);
  ASSERT_EQ(c.refusal, MotionReason::kNone) << motion_name(c.refusal);
  EXPECT_EQ(c.verb, MotionVerb::kMoveTo);
  EXPECT_EQ(c.id, 7u);
  Data<double> end;
  forward_kinematics(task->model, end, c.q_end);
  EXPECT_LT((end.o[kDof] - (start.o[kDof] + req.position)).norm(), 1e-4);  // kPositionTolerance
  EXPECT_LT((end.R[kDof] - start.R[kDof]).norm(), 2e-3);                   // no rpy: the orientation kept
  req.position = Vec3<double>(3, 0, 0);  // 3 m along x: beyond the wrist centre's reach from the shoulder
  EXPECT_EQ(prepare_checked_move(*task, req, 8).refusal, MotionReason::kOutOfWorkspace);
}

TEST(CommandPrep, ASetpointIsTakenByItsOwnStreamAndOneNotYetTakenIsReplaced) {
  auto task = disabled_task<double>();
  const Vec3<double> p(0.001, 0, 0), rpy = Vec3<double>::Zero();
  EXPECT_FALSE(offer_setpoint(*task, 3, p, rpy, false, false));  // no stream runs
  EXPECT_EQ(task->dropped, 1u);
  task->gen.start_stream(10, true, CartesianLimits<double>::defaults(), 3);
  EXPECT_FALSE(offer_setpoint(*task, 4, p, rpy, false, false));  // another stream's
  EXPECT_EQ(task->dropped, 2u);
  EXPECT_FALSE(task->sample.valid);
  ASSERT_TRUE(offer_setpoint(*task, 3, p, rpy, false, false));
  EXPECT_TRUE(task->sample.valid);
  EXPECT_EQ(task->dropped, 2u);
  // Relative to where the stream started: its hold pose plus the offset.
  EXPECT_LT((task->sample.x.head<3>() - (task->gen.hold_pose().p + p)).norm(), 1e-15);
  ASSERT_TRUE(offer_setpoint(*task, 3, Vec3<double>(2 * p), rpy, false, true));  // before a tick took the first
  EXPECT_EQ(task->dropped, 3u);
  EXPECT_TRUE(task->sample.end);
  EXPECT_LT((task->sample.x.head<3>() - (task->gen.hold_pose().p + 2 * p)).norm(), 1e-15);
}

}  // namespace
