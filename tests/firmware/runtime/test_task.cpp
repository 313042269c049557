// The control task's type and its set-up (osc/runtime/task.hpp): a collision reaction and thresholds
// outside their bounds are refused and change nothing. The reactions themselves on the simulated arm:
// tests/host_sim/test_collision_reaction.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "osc/robot.hpp"
#include "osc/runtime/task.hpp"

using namespace osc;

namespace {

TEST(CollisionReaction, ThresholdsOutsideTheirBoundsAreRefusedAndChangeNothing) {
  std::unique_ptr<ControlTask<double>> task(new ControlTask<double>);
  task->init(Model<double>::of(robot::kArm), Gains<double>::paper(), FrictionMode::kAdaptive,
             joint_vector<double>(robot::kQStart));
  const double ok[kDof] = {10, 10, 10, 5, 5, 5};
  ASSERT_TRUE(task->set_collision(CollisionReaction::kYield, ok));
  double bad[kDof] = {10, 10, 10, 5, 5, 5};
  for (const double v : {-1.0, std::nan(""), robot::kDrives.torque_limit[4] * 1.01}) {
    bad[4] = v;
    EXPECT_FALSE(task->set_collision(CollisionReaction::kCategory2, bad)) << v;
    EXPECT_EQ(task->collision_reaction, CollisionReaction::kYield);
    EXPECT_EQ(task->residual.collision_floor(4), 5.0);
  }
  EXPECT_FALSE(task->set_collision(static_cast<CollisionReaction>(3), ok));
}

}  // namespace
