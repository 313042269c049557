// The fixed-point scalar (osc/math/fixed.hpp, which includes its parts) in the control task: the overflow
// fault (zero torque in the same tick), raised in the step or between two ticks. Its parts' tests are in
// the file of each header: test_saturating_int.cpp, test_q.cpp, test_q_functions.cpp, test_q_eigen.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "osc/math/fixed.hpp"
#include "osc/runtime/control_task.hpp"

using namespace osc;

namespace {

// ---------------------------------------------------------------- the fault
struct StillHal {
  std::int32_t written[kDof] = {1, 1, 1, 1, 1, 1};
  bool read_encoders(std::int32_t c[kDof]) {
    for (int i = 0; i < kDof; ++i) c[i] = 0;
    return true;
  }
  void write_dacs(const std::int32_t c[kDof]) { std::copy(c, c + kDof, written); }
  std::uint32_t cycles() { return 0; }
  std::uint32_t io_faults() { return 0; }
  void fault_output(bool) {}
  bool all_zero() const {
    for (int c : written)
      if (c != 0) return false;
    return true;
  }
};

TEST(FixedFault, AnOverflowInTheStepLatchesTheOverflowFaultWithZeroTorqueInTheSameTick) {
  auto task = std::make_unique<ControlTask<Fixed>>();
  task->init(Model<Fixed>::of(robot::kArm), Gains<Fixed>::paper(), FrictionMode::kAdaptive,
             joint_vector<Fixed>(robot::kQStart));
  StillHal hal;
  fixed::take_flags();
  for (int k = 0; k < 5; ++k) ASSERT_EQ(control_tick(*task, hal), 0u);
  EXPECT_FALSE(hal.all_zero());  // holding the arm against gravity
  EXPECT_EQ(task->sup.state, SupervisorState::kRun);
  task->state.obs.y(2) = Fixed(4000);  // an observer state that drives F beyond the range
  const std::uint32_t f = control_tick(*task, hal);
  EXPECT_EQ(f, static_cast<std::uint32_t>(kFaultOverflow)) << fault_name(f);
  EXPECT_EQ(task->last.status, static_cast<std::uint32_t>(kFaultOverflow));
  EXPECT_TRUE(hal.all_zero());
  EXPECT_EQ(task->sup.state, SupervisorState::kFault);
  EXPECT_EQ(task->sup.latched, static_cast<std::uint32_t>(kFaultOverflow));
  EXPECT_STREQ(fault_name(task->sup.latched), "overflow");
  control_tick(*task, hal);  // latched: zero from now on
  EXPECT_TRUE(hal.all_zero());
}

TEST(FixedFault, ASaturationOutsideTheStepIsLatchedInTheSameTickToo) {
  auto task = std::make_unique<ControlTask<Fixed>>();
  task->init(Model<Fixed>::of(robot::kArm), Gains<Fixed>::paper(), FrictionMode::kAdaptive,
             joint_vector<Fixed>(robot::kQStart));
  StillHal hal;
  fixed::take_flags();
  ASSERT_EQ(control_tick(*task, hal), 0u);
  (void)(Fixed::max() + Fixed(1));  // e.g. in the I/O layer between two ticks
  EXPECT_EQ(control_tick(*task, hal), static_cast<std::uint32_t>(kFaultOverflow));
  EXPECT_TRUE(hal.all_zero());
}

}  // namespace
