// A control task for the tests that drive one by hand (tests/firmware/runtime/, tests/firmware/link/).
#pragma once

#include <memory>

#include "osc/robot.hpp"
#include "osc/runtime/control_task.hpp"

namespace osc::test {

template <class S>
std::unique_ptr<ControlTask<S>> disabled_task() {
  auto t = std::make_unique<ControlTask<S>>();
  t->init(Model<S>::of(robot::kArm), Gains<S>::paper(), FrictionMode::kAdaptive, joint_vector<S>(robot::kQStart), 0,
          TaskStart::kDisabled);
  return t;
}

}  // namespace osc::test
