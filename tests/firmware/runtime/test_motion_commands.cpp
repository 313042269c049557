// The commands a client gives the task (osc/runtime/motion_commands.hpp): each verb's command to the
// motion state machine, written out; a move_to's target from where its move starts, relative and
// absolute, against rotations written out here; what preparing a move decides: planned from where the
// queue ends, over_limit above the configured limits, queue_full, busy while a stream runs; a pose to
// declare known by its code.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <iterator>
#include <utility>

#include "osc/robot.hpp"
#include "osc/runtime/motion_commands.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

TEST(MotionCommands, EachVerbIsItsMachinesCommand) {
  using V = MotionVerb;
  using Cmd = MotionCommand;
  const std::pair<V, Cmd> table[] = {{V::kNone, Cmd::kNone},       {V::kEnable, Cmd::kEnable},
                                     {V::kDisable, Cmd::kDisable}, {V::kMoveTo, Cmd::kMove},
                                     {V::kPaper, Cmd::kMove},      {V::kStop, Cmd::kStop},
                                     {V::kClear, Cmd::kClear},     {V::kStream, Cmd::kMove},
                                     {V::kHome, Cmd::kHome},       {V::kDeclarePose, Cmd::kDeclarePose},
                                     {V::kIdentify, Cmd::kMove}};
  ASSERT_EQ(static_cast<int>(std::size(table)), MotionNames<V>::kCount);
  for (const auto& [v, c] : table) EXPECT_EQ(verb_command(v), c) << motion_name(v);
  EXPECT_EQ(verb_command(static_cast<V>(200)), Cmd::kNone);  // a code outside the list
  // An identify moves only as prepare_identify planned and checked it: a bare one is not marked checked (the tick
  // refuses it bad_command: test_identify_command.cpp).
  EXPECT_FALSE(prepare_command<double>(V::kIdentify, 4).checked);
  EXPECT_EQ(prepare_command<double>(V::kPaper, 4).refusal, MotionReason::kNone);
}

TEST(MotionCommands, AMoveTargetIsRelativeToWhereItStartsOrAbsolute) {
  Mat3<double> rx, rz;  // 90 degrees about x, about z
  rx << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  rz << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Pose<double> from{Vec3<double>(0.5, 0.1, 0.3), rx};
  MoveRequest<double> req;
  req.relative = true;
  req.position = Vec3<double>(0.01, -0.02, 0.03);
  Pose<double> to = move_target(from, req);
  EXPECT_LT((to.p - Vec3<double>(0.51, 0.08, 0.33)).norm(), 1e-15);
  EXPECT_EQ(to.R, rx);  // without rpy the orientation stays
  req.has_rpy = true;
  req.rpy = Vec3<double>(0, 0, kPi / 2);  // yaw: applied in the base frame, after the start's rotation
  to = move_target(from, req);
  EXPECT_LT((to.R - rz * rx).norm(), 1e-15);
  req.relative = false;
  to = move_target(from, req);
  EXPECT_EQ(to.p, req.position);
  EXPECT_LT((to.R - rz).norm(), 1e-15);
}

TEST(MotionCommands, PreparingAMoveDecidesWhatTheGeometryAndTheLimitsDo) {
  OSC_PUMA_TUNED("its homing and declare_pose cases need incremental encoders (an absolute arm answers not_needed)");
  const CartesianLimits<double> max = CartesianLimits<double>::defaults();
  const Pose<double> hold{Vec3<double>(0.5, 0.1, 0.3), Mat3<double>::Identity()};
  MotionGenerator<double> g;
  g.hold(hold, hold.R);
  MoveRequest<double> req;
  req.relative = true;
  req.position = Vec3<double>(0, 0, 0.01);
  // Each move planned from where the queue ends: 1 cm more each, until the queue is full.
  const int slots = params::kMoveQueueLength + 1;  // the one that runs and those waiting
  for (int n = 1; n <= slots; ++n) {
    const TaskCommand<double> c = prepare_move(g, max, 1, params::kControlHz, req, static_cast<std::uint32_t>(n));
    ASSERT_EQ(c.refusal, MotionReason::kNone) << n;
    EXPECT_FALSE(c.brake);
    EXPECT_LT((c.move.end().p - (hold.p + Vec3<double>(0, 0, 0.01 * n))).norm(), 1e-12) << n;
    ASSERT_TRUE(g.push(c.move, c.id));
  }
  EXPECT_EQ(prepare_move(g, max, 1, params::kControlHz, req, 99).refusal, MotionReason::kQueueFull);
  req.has_limits = true;
  req.limits = max;
  req.limits.angular.j *= 1.01;
  EXPECT_EQ(prepare_move(g, max, 1, params::kControlHz, req, 101).refusal, MotionReason::kOverLimit);
  MotionGenerator<double> s;
  s.hold(hold, hold.R);
  s.start_stream(10, true, max, 5);
  req.has_limits = false;
  EXPECT_EQ(prepare_move(s, max, 1, params::kControlHz, req, 102).refusal, MotionReason::kBusy);
  EXPECT_EQ(prepare_declare_pose<double>(robot::kNamedPoseCount, 103).refusal, MotionReason::kUnknownPose);
  const TaskCommand<double> d = prepare_declare_pose<double>(robot::kNamedPoseCount - 1, 104);
  EXPECT_EQ(d.refusal, MotionReason::kNone);
  EXPECT_EQ(d.pose, robot::kNamedPoseCount - 1);
  EXPECT_EQ(d.verb, MotionVerb::kDeclarePose);
}

}  // namespace
