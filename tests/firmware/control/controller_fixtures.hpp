// What the tests of the control step's stages share (test_controller.cpp, test_observer.cpp,
// test_trajectory.cpp): the start pose, the paper's trajectory, and the Stages fixture, a state off the
// task where each stage is checked against an independent evaluation of its equations.
#pragma once

#include <gtest/gtest.h>

#include "osc/control/controller.hpp"

namespace osc::test {

inline Vec6<double> q_start() { return joint_vector<double>(robot::kQStart); }

constexpr TrajectorySpec<double> kPaperTrajectory = TrajectorySpec<double>::paper();

// ---------------------------------------------------------------- the stages, one at a time
// Each stage of control_step against an independent evaluation of its equations (dense solves with
// Lambda and the analytic Jacobian, Psi by the other polarisation), at an off-task state.
struct Stages : ::testing::Test {
  Model<double> model = Model<double>::of(robot::kArm);
  Gains<double> G = Gains<double>::paper();
  Data<double> data{};
  ArmOpSpace<double> os{};
  Vec6<double> q = q_start();
  void SetUp() override {
    forward_kinematics(model, data, q);
    const Mat3<double> R_ref = data.R[kDof];
    q << q(0) + 0.05, q(1) - 0.04, q(2) + 0.03, q(3) + 0.1, q(4) - 0.05, q(5) + 0.2;  // phi != 0
    opspace_update(model, data, os, q, R_ref);
  }
  static Vec6<double> v6(double a, double b, double c, double d, double e, double f) {
    Vec6<double> v;
    v << a, b, c, d, e, f;
    return v;
  }
};

}  // namespace osc::test
