// Constant robot model and its preallocated workspace (the Model/Data split).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "osc/robots/arm.hpp"
#include "osc/math/scalar.hpp"

namespace osc {

template <class S>
using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S>
using Vec6 = Eigen::Matrix<S, 6, 1>;
template <class S>
using Vec18 = Eigen::Matrix<S, 18, 1>;
template <class S>
using Mat3 = Eigen::Matrix<S, 3, 3>;
template <class S>
using Mat6 = Eigen::Matrix<S, 6, 6>;

/// Vector argument whose scalar is deduced from another parameter (a Model or workspace), so that
/// Eigen expressions can be passed directly.
template <class T>
struct NonDeduced {
  using type = T;
};
template <class S>
using Vec6In = typename NonDeduced<Vec6<S>>::type;

/// A joint vector of a robot table (angles, limits, poses) in the kernel's scalar.
template <class S>
Vec6<S> joint_vector(const double (&a)[kDof]) {
  Vec6<S> v;
  for (int i = 0; i < kDof; ++i) v(i) = lit<S>(a[i]);
  return v;
}

/// f(std::integral_constant<int, I>{}) for I = 0, 1, ..., N - 1 in order: a loop whose index is a
/// compile-time constant, so that every partial row of a factorisation is a fixed-size segment.
template <int N, class Fn>
void for_each_index(Fn&& f) {
  [&]<int... I>(std::integer_sequence<int, I...>) { (f(std::integral_constant<int, I>{}), ...); }
  (std::make_integer_sequence<int, N>{});
}

/// a x b, each component a_i b_j - a_j b_i by math::dot2_minus (one rounding in fixed point).
template <class A, class B>
[[gnu::always_inline]] inline Vec3<typename A::Scalar> cross(const Eigen::MatrixBase<A>& a,
                                                             const Eigen::MatrixBase<B>& b) {
  using S = typename A::Scalar;
  if constexpr (fixed::is_q_v<S>) {
    const Vec3<S> u = a, v = b;
    return Vec3<S>(math::dot2_minus(u(1), v(2), u(2), v(1)), math::dot2_minus(u(2), v(0), u(0), v(2)),
                   math::dot2_minus(u(0), v(1), u(1), v(0)));
  } else {
    return a.cross(b);
  }
}

/// u . v + w . x of 3-vectors, rounded once in fixed point (a six-term math::sum_of_products).
template <class S>
[[gnu::always_inline]] inline S dot_sum(const Vec3<S>& u, const Vec3<S>& v, const Vec3<S>& w, const Vec3<S>& x) {
  if constexpr (fixed::is_q_v<S>)
    return math::sum_of_products(u(0), v(0), u(1), v(1), u(2), v(2), w(0), x(0), w(1), x(1), w(2), x(2));
  else
    return u.dot(v) + w.dot(x);
}

/// a u + b v of two 3-vectors, each component by math::sum_of_products (one rounding in fixed point).
template <class S, class U, class V>
[[gnu::always_inline]] inline Vec3<S> combine(S a, const Eigen::MatrixBase<U>& u, S b, const Eigen::MatrixBase<V>& v) {
  using math::sum_of_products;
  return Vec3<S>(sum_of_products(a, S(u(0)), b, S(v(0))), sum_of_products(a, S(u(1)), b, S(v(1))),
                 sum_of_products(a, S(u(2)), b, S(v(2))));
}

/// a u + b v + c w of three 3-vectors, each component by math::sum_of_products (one rounding in
/// fixed point).
template <class S>
[[gnu::always_inline]] inline Vec3<S> sum3(S a, const Vec3<S>& u, S b, const Vec3<S>& v, S c, const Vec3<S>& w) {
  using math::sum_of_products;
  return Vec3<S>(sum_of_products(a, u(0), b, v(0), c, w(0)), sum_of_products(a, u(1), b, v(1), c, w(1)),
                 sum_of_products(a, u(2), b, v(2), c, w(2)));
}

/// How a link's placement P = (R, p) places its frame, for forward_kinematics. The rotations of a
/// DH table (Rx of 0 and +-pi/2: every PUMA 560 link) move two columns, one with a sign; any other
/// rotation takes the product, exact for a signed permutation (a URDF's quarter turns: coefficients
/// 0 and +-1), which kPermutation and its column codes name. A translation (a, 0, d) in the turned
/// frame (every DH row) is a two-term sum.
enum class Rotation : unsigned char { kIdentity, kRxPlusHalfPi, kRxMinusHalfPi, kPermutation, kGeneral };

struct PlacementForm {
  Rotation rotation;
  signed char column[3];  ///< kPermutation: column k of R is sign(column[k]) e_{|column[k]| - 1}
  bool planar;            ///< p(1) == 0
};

constexpr PlacementForm placement_form(const Placement& P) {
  PlacementForm f{Rotation::kGeneral, {0, 0, 0}, P.p[1] == 0};
  if (!is_signed_permutation(P)) return f;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r)
      if (P.R[r][c] != 0) f.column[c] = static_cast<signed char>(P.R[r][c] > 0 ? r + 1 : -(r + 1));
  const auto is = [&f](int a, int b, int c) { return f.column[0] == a && f.column[1] == b && f.column[2] == c; };
  f.rotation = is(1, 2, 3)    ? Rotation::kIdentity
               : is(1, 3, -2) ? Rotation::kRxPlusHalfPi
               : is(1, -3, 2) ? Rotation::kRxMinusHalfPi
                              : Rotation::kPermutation;
  return f;
}

/// A drive train that couples the joints (q = C e, C unit lower triangular: osc/robots/arm.hpp, EncoderMap; e the
/// motors' angles referred to their joints): the terms of C^-1 below its diagonal. Each motor turns at e' = C^-1 q'
/// and carries C^T tau, so model (2)'s friction, each motor's own at its own rate, is C^-T f(C^-1 q') in the joints'
/// space (osc/control/controller.hpp). No terms: an uncoupled arm (C = I), the motors' rates the joints'.
template <class S>
struct DriveCoupling {
  static constexpr int kMaxTerms = kDof * (kDof - 1) / 2;
  int terms = 0;
  std::int8_t row[kMaxTerms]{}, col[kMaxTerms]{};
  S c[kMaxTerms]{};

  bool coupled() const { return terms != 0; }
  /// From C^-1 (set-up, in double).
  [[gnu::cold]] static DriveCoupling of(const double (&inverse)[kDof][kDof]) {
    DriveCoupling d{};
    for (int i = 0; i < kDof; ++i)
      for (int j = 0; j < i; ++j)
        if (inverse[i][j] != 0) {
          const int k = d.terms++;
          d.row[k] = static_cast<std::int8_t>(i);
          d.col[k] = static_cast<std::int8_t>(j);
          d.c[k] = lit<S>(inverse[i][j]);
        }
    return d;
  }
};

/// The motors' rates, referred to their joints, of joint rates qd: C^-1 qd.
template <class S>
Vec6<S> motor_rates(const DriveCoupling<S>& d, const Vec6<S>& qd) {
  Vec6<S> r = qd;
  for (int k = 0; k < d.terms; ++k) r(d.row[k]) += d.c[k] * qd(d.col[k]);
  return r;
}

/// The joint torques that motor torques tau_m (referred to their joints) give: C^-T tau_m.
template <class S>
Vec6<S> joint_torques_of_motors(const DriveCoupling<S>& d, const Vec6<S>& tau_m) {
  Vec6<S> t = tau_m;
  for (int k = 0; k < d.terms; ++k) t(d.col[k]) += d.c[k] * tau_m(d.row[k]);
  return t;
}

/// Constant parameters of a 6-joint revolute arm (osc/robots/arm.hpp), in the kernel's scalar.
template <class S>
struct Model {
  struct Link {
    Mat3<S> R;  // the placement P_i: frame i in the turned frame F_{i-1} Rz(q_i)
    Vec3<S> p;
    PlacementForm form;
    S mass;
    Vec3<S> com;       // COM in frame i
    Vec3<S> inertia;   // Ixx, Iyy, Izz about the COM, axes of frame i
    Vec3<S> products;  // Ixy, Ixz, Iyz
    bool diagonal;     // products all zero
  };
  Mat3<S> base_R;  // frame 0 in the base frame
  Vec3<S> base_o;
  bool base_identity;  // frame 0 is the base frame
  Link link[kDof];
  Vec6<S> armature;  // G^2 * Jm, added to the diagonal of A(q)
  S gravity;         // along -z of the base frame
  /// The drive train's coupling (none from Model::of: ControlTask::set_encoders sets the arm's), through which
  /// the friction is each motor's (DriveCoupling).
  DriveCoupling<S> drives;
  /// Of each link with products: its tensor's Cholesky factor L (I = L L^T, lower; the generator refuses a
  /// tensor that is not positive definite), its diagonal and (L_yx, L_zx, L_zy) (rotated_full_inertia). Apart
  /// from Link, whose size (the stride of link[i]) the arms without products keep.
  Vec3<S> root_diagonal[kDof], root_lower[kDof];

  /// The Cholesky factor of the tensor (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) scaled by s, in double (set-up
  /// only); a pivot that is not positive (a tensor the generator would refuse) gives 0s.
  static void cholesky_root(const double (&t)[6], double s, Vec3<S>& diagonal, Vec3<S>& lower) {
    const auto root = [](double v) { return v > 0 ? std::sqrt(v) : 0.0; };
    const double d0 = root(t[0] * s);
    const double l10 = d0 > 0 ? t[3] * s / d0 : 0, l20 = d0 > 0 ? t[4] * s / d0 : 0;
    const double d1 = root(t[1] * s - l10 * l10);
    const double l21 = d1 > 0 ? (t[5] * s - l20 * l10) / d1 : 0;
    const double d2 = root(t[2] * s - l20 * l20 - l21 * l21);
    diagonal = Vec3<S>(lit<S>(d0), lit<S>(d1), lit<S>(d2));
    lower = Vec3<S>(lit<S>(l10), lit<S>(l20), lit<S>(l21));
  }

  /// The model of an arm from its description (osc/robots/arm.hpp), with every link mass and
  /// inertia scaled by (1 + mass_inertia_error) (used to test robustness to model error), and link 6
  /// carrying `payload` (none by default: the arm's own link, bit for bit).
  static Model of(const ArmDescription& arm, double mass_inertia_error = 0.0, const Payload& payload = {}) {
    Model m{};
    const double s = 1.0 + mass_inertia_error;
    placement(arm.base, m.base_R, m.base_o);
    m.base_identity = placement_form(arm.base).rotation == Rotation::kIdentity && arm.base.p[0] == 0 &&
                      arm.base.p[1] == 0 && arm.base.p[2] == 0;
    for (int i = 0; i < kDof; ++i) {
      LinkParams p = arm.links[i];
      p.mass *= s;
      for (double& v : p.inertia) v *= s;
      if (i == kDof - 1) p = with_payload(p, payload);
      Link& l = m.link[i];
      placement(p.placement, l.R, l.p);
      l.form = placement_form(p.placement);
      m.set_inertial(i, {p.mass,
                         {p.com[0], p.com[1], p.com[2]},
                         {p.inertia[0], p.inertia[1], p.inertia[2], p.inertia[3], p.inertia[4], p.inertia[5]}});
      m.armature(i) = lit<S>(p.gear_ratio * p.gear_ratio * p.motor_inertia);
    }
    m.gravity = lit<S>(arm.gravity);
    return m;
  }

  /// Link i's mass, centre of mass and inertia (and its tensor's Cholesky factor) from a body in its
  /// frame, in double (set-up, and a payload set at run time: outside the tick).
  void set_inertial(int i, const RigidBody& b) {
    Link& l = link[i];
    l.mass = lit<S>(b.mass);
    l.com = Vec3<S>(lit<S>(b.com[0]), lit<S>(b.com[1]), lit<S>(b.com[2]));
    l.inertia = Vec3<S>(lit<S>(b.inertia[0]), lit<S>(b.inertia[1]), lit<S>(b.inertia[2]));
    l.products = Vec3<S>(lit<S>(b.inertia[3]), lit<S>(b.inertia[4]), lit<S>(b.inertia[5]));
    l.diagonal = b.inertia[3] == 0 && b.inertia[4] == 0 && b.inertia[5] == 0;
    cholesky_root(b.inertia, 1.0, root_diagonal[i], root_lower[i]);
  }

  /// Link i's body as the model has it, in double.
  RigidBody inertial(int i) const {
    const Link& l = link[i];
    const auto d = [](S v) { return static_cast<double>(v); };
    return {d(l.mass),
            {d(l.com(0)), d(l.com(1)), d(l.com(2))},
            {d(l.inertia(0)), d(l.inertia(1)), d(l.inertia(2)), d(l.products(0)), d(l.products(1)), d(l.products(2))}};
  }

 private:
  static void placement(const Placement& P, Mat3<S>& R, Vec3<S>& p) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R(r, c) = lit<S>(P.R[r][c]);
      p(r) = lit<S>(P.p[r]);
    }
  }
};

/// Preallocated workspace. Index 0 is the base frame, index i the distal frame of link i.
template <class S>
struct Data {
  Mat3<S> R[kDof + 1];
  Vec3<S> o[kDof + 1];
  Vec3<S> com[kDof + 1];  // COM of link i in the base frame (index 0 unused)
  Mat3<S> Ic[kDof + 1];   // inertia of link i about its COM, base axes (symmetric)
  Vec3<S> vO[kDof];       // o_i x z_i: velocity of the point at the base origin under a unit rate of joint i + 1
  Mat6<S> J;              // geometric Jacobian [v; w] of the frame-6 origin, base frame
  Mat6<S> A;              // joint-space inertia, armature included
};

}  // namespace osc
