// Constant robot model and its preallocated workspace (the Model/Data split).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "osc/robots/arm.hpp"
#include "osc/kernels/scalar.hpp"

namespace osc {

template <class S> using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S> using Vec6 = Eigen::Matrix<S, 6, 1>;
template <class S> using Vec18 = Eigen::Matrix<S, 18, 1>;
template <class S> using Mat3 = Eigen::Matrix<S, 3, 3>;
template <class S> using Mat6 = Eigen::Matrix<S, 6, 6>;

/// Vector argument whose scalar is deduced from another parameter (a Model or workspace), so that
/// Eigen expressions can be passed directly.
template <class T> struct NonDeduced { using type = T; };
template <class S> using Vec6In = typename NonDeduced<Vec6<S>>::type;

/// A joint vector of a robot table (angles, limits, poses) in the kernel's scalar.
template <class S>
Vec6<S> joint_vector(const double (&a)[kDof]) {
  Vec6<S> v;
  for (int i = 0; i < kDof; ++i) v(i) = lit<S>(a[i]);
  return v;
}

/// Constant parameters of a 6-joint standard-DH arm, in the kernel's scalar.
template <class S>
struct Model {
  struct Link {
    S a, d, cos_alpha, sin_alpha;
    S mass;
    Vec3<S> com;          // COM in frame i
    Vec3<S> inertia;      // principal moments about the COM, axes of frame i
  };
  Link link[kDof];
  Vec6<S> armature;       // G^2 * Jm, added to the diagonal of A(q)
  S gravity;              // along -z0

  /// The model of an arm from its description (osc/robots/arm.hpp), with every link mass and
  /// inertia scaled by (1 + mass_inertia_error) (used to test robustness to model error).
  static Model of(const ArmDescription& arm, double mass_inertia_error = 0.0) {
    Model m{};
    const double s = 1.0 + mass_inertia_error;
    for (int i = 0; i < kDof; ++i) {
      const LinkParams& p = arm.links[i];
      Link& l = m.link[i];
      l.a = lit<S>(p.a);
      l.d = lit<S>(p.d);
      l.cos_alpha = lit<S>(std::cos(p.alpha));
      l.sin_alpha = lit<S>(std::sin(p.alpha));
      // Snap cos/sin of +-pi/2 to exact zeros so the DH structure is exact.
      if (std::fabs(std::cos(p.alpha)) < 1e-12) l.cos_alpha = S(0);
      l.mass = lit<S>(p.mass * s);
      l.com = Vec3<S>(lit<S>(p.com[0]), lit<S>(p.com[1]), lit<S>(p.com[2]));
      l.inertia = Vec3<S>(lit<S>(p.inertia[0] * s), lit<S>(p.inertia[1] * s), lit<S>(p.inertia[2] * s));
      m.armature(i) = lit<S>(p.gear_ratio * p.gear_ratio * p.motor_inertia);
    }
    m.gravity = lit<S>(arm.gravity);
    return m;
  }
};

/// Preallocated workspace. Index 0 is the base frame, index i the distal frame of link i.
template <class S>
struct Data {
  Mat3<S> R[kDof + 1];
  Vec3<S> o[kDof + 1];
  Vec3<S> com[kDof + 1];   // COM of link i in the base frame (index 0 unused)
  Mat3<S> Ic[kDof + 1];    // inertia of link i about its COM, base axes
  Mat6<S> J;               // geometric Jacobian [v; w] of the frame-6 origin, base frame
  Mat6<S> A;               // joint-space inertia, armature included
};

}  // namespace osc
