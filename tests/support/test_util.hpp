// Shared helpers for the host tests.
#pragma once

#include <Eigen/Core>
#include <random>

#include "osc/control/arm_opspace.hpp"
#include "osc/control/params.hpp"
#include "osc/kernels/kinematics.hpp"
#include "osc/kernels/model.hpp"
#include "osc/robot.hpp"
#include "puma560_published.hpp"

namespace osc::test {

/// Skips the rest of a test in a build for another arm: a test of the PUMA 560's own figures (its
/// published vectors, presets, coupled wrist, pots, index pulses, the docs' tables of it) inside an
/// executable whose other tests run on any arm (a whole executable of them: osc_add_test's PUMA).
#define OSC_PUMA_ONLY()                                                                             \
  do {                                                                                              \
    if (!::osc::test::kPumaBuild) GTEST_SKIP() << "the PUMA 560's own figures (OSC_ROBOT=puma560)"; \
  } while (0)

/// Skips the rest of a test in a build for another arm: a test whose fixture (poses, forces, gains,
/// durations) was tuned on the PUMA 560 and has not been derived for any arm yet; `why` says what
/// (docs/arms.md lists them).
#define OSC_PUMA_TUNED(why)                                                                              \
  do {                                                                                                   \
    if (!::osc::test::kPumaBuild) GTEST_SKIP() << "tuned on the PUMA 560, not yet for any arm: " << why; \
  } while (0)

/// Arms Eigen's runtime no-malloc check for its lifetime (EIGEN_RUNTIME_NO_MALLOC is defined
/// for every test target): any heap allocation inside Eigen aborts the test.
struct NoMalloc {
  NoMalloc() { Eigen::internal::set_is_malloc_allowed(false); }
  ~NoMalloc() { Eigen::internal::set_is_malloc_allowed(true); }
};

/// J's reciprocal condition at q, by the arm's factor (ArmJacobianFactor: the block factor with a spherical wrist,
/// else the pivoted LU's exact 1-norm rcond), as the controller and the path check see it (the analytic Jacobian
/// is J where the orientation coordinates are 0).
inline double jacobian_rcond(const Vec6<double>& q) {
  static const Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  forward_kinematics(model, data, q);
  geometric_jacobian(data);
  ArmJacobianFactor<double> f;
  f.compute(data.J);
  return static_cast<double>(f.rcond);
}

/// Deterministic random states for property tests.
struct RandomStates {
  std::mt19937_64 rng{12345};
  std::uniform_real_distribution<double> u{-1.0, 1.0};

  Vec6<double> vec(double scale) {
    Vec6<double> v;
    for (int i = 0; i < kDof; ++i) v(i) = scale * u(rng);
    return v;
  }
  /// Joint angles within the arm's limits, away from its singularities. A spherical wrist (the
  /// PUMA's): away from the wrist (|sin q5| >= 0.2) and the elbow (stretched/folded,
  /// |cos(q3 + 0.047)| >= 0.2); any other arm: J's reciprocal condition (PivotedLuJacobianFactor's
  /// exact 1-norm rcond, jacobian_rcond) at least kNonsingularRcond, twice the path check's kPathMinRcond (the UR5e:
  /// about half of the poses within its limits; its median is 0.021, its 99th percentile 0.076).
  static constexpr double kNonsingularRcond = 2 * params::kPathMinRcond;
  Vec6<double> q_nonsingular() {
    for (;;) {
      Vec6<double> q;
      for (int i = 0; i < kDof; ++i) {
        const double lo = robot::kArm.q_min[i], hi = robot::kArm.q_max[i];
        q(i) = lo + (hi - lo) * 0.5 * (u(rng) + 1.0);
      }
      if constexpr (has_spherical_wrist(robot::kArm)) {
        if (std::abs(std::sin(q(4))) < 0.2) continue;          // wrist
        if (std::abs(std::cos(q(2) + 0.047)) < 0.2) continue;  // elbow (stretched/folded)
      } else if (jacobian_rcond(q) < kNonsingularRcond) {
        continue;
      }
      return q;
    }
  }
};

inline Vec6<double> from_array(const double (&a)[kDof]) { return joint_vector<double>(a); }

}  // namespace osc::test
