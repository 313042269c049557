// Shared helpers for the host tests.
#pragma once

#include <Eigen/Core>
#include <random>

#include "osc/kernels/model.hpp"
#include "osc/robot.hpp"

namespace osc::test {

/// Arms Eigen's runtime no-malloc check for its lifetime (EIGEN_RUNTIME_NO_MALLOC is defined
/// for every test target): any heap allocation inside Eigen aborts the test.
struct NoMalloc {
  NoMalloc() { Eigen::internal::set_is_malloc_allowed(false); }
  ~NoMalloc() { Eigen::internal::set_is_malloc_allowed(true); }
};

/// Deterministic random states for property tests.
struct RandomStates {
  std::mt19937_64 rng{12345};
  std::uniform_real_distribution<double> u{-1.0, 1.0};

  Vec6<double> vec(double scale) {
    Vec6<double> v;
    for (int i = 0; i < kDof; ++i) v(i) = scale * u(rng);
    return v;
  }
  /// Joint angles within the WC91 limits, away from the wrist (q5 = 0) and elbow singularities.
  Vec6<double> q_nonsingular() {
    for (;;) {
      Vec6<double> q;
      for (int i = 0; i < kDof; ++i) {
        const double lo = robot::kArm.q_min[i], hi = robot::kArm.q_max[i];
        q(i) = lo + (hi - lo) * 0.5 * (u(rng) + 1.0);
      }
      if (std::abs(std::sin(q(4))) < 0.2) continue;          // wrist
      if (std::abs(std::cos(q(2) + 0.047)) < 0.2) continue;  // elbow (stretched/folded)
      return q;
    }
  }
};

inline Vec6<double> from_array(const double (&a)[kDof]) { return joint_vector<double>(a); }

}  // namespace osc::test
