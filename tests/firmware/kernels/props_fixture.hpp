// What the kernels' property tests share (test_dynamics.cpp, test_kinematics.cpp, test_opspace.cpp,
// test_friction.cpp, test_properties.cpp): the Props fixture, the kernels on random non-singular
// states (deterministic seed), every kernel call with Eigen's malloc check armed (test::NoMalloc;
// guards are never nested: the inner guard's destructor would re-enable allocation).
//
// Finite differences: central, step h = 1e-6 (rad, or s along q(t) = q + t qd with |qd_i| <= 1).
// Truncation error ~ h^2 |f'''| ~ 1e-12 and round-off ~ eps |f| / h ~ 1e-10 relative, amplified
// by the conditioning of Lambda (two solves with Ja); the tolerances leave >= 10x margin over the
// worst value seen (printed).
#pragma once

#include <gtest/gtest.h>

#include "osc/control/arm_opspace.hpp"
#include "test_util.hpp"

namespace osc::test {

constexpr int kStates = 300;
constexpr double kH = 1e-6;

struct Props : ::testing::Test {
  Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data{};
  ArmOpSpace<double> os{};
  test::RandomStates rs;

  /// x(q) = [p; phi] with orientation relative to R_ref.
  Vec6<double> x_of(const Vec6<double>& q, const Mat3<double>& R_ref) {
    NoMalloc guard;
    forward_kinematics(model, data, q);
    return operational_coordinates(data, R_ref);
  }
  /// opspace_update at q: fills data (frames, J, A) and os (x, Ja, Jf, A_ldlt, Lambda, g).
  void update(const Vec6<double>& q, const Mat3<double>& R_ref) {
    NoMalloc guard;
    opspace_update(model, data, os, q, R_ref);
  }
  /// End-effector orientation R_6(q).
  Mat3<double> orientation(const Vec6<double>& q) {
    NoMalloc guard;
    forward_kinematics(model, data, q);
    return data.R[kDof];
  }
  /// Reference orientation for state k: even k its own orientation (phi = 0 at q), odd k the
  /// orientation at a nearby perturbed configuration (|dq_i| <= 0.2 rad, phi != 0).
  Mat3<double> reference_for(int k, const Vec6<double>& q) {
    return orientation(k % 2 == 0 ? q : Vec6<double>(q + rs.vec(0.2)));
  }
};

}  // namespace osc::test
