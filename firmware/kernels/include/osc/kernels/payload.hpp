// A rigid payload fixed to frame 6 (the flange) and its regressor: the joint torques it needs are linear in
// its ten inertial parameters (issue 57; shared/reference/drives-and-identification.md section 7.5; Atkeson,
// An and Hollerbach 1986),
//   tau_payload(q, qd, qdd) = Y(q, qd, qdd) pi,
//   pi = [m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz],
// h = m c the first moment (c the payload's centre of mass in frame 6) and I the inertia tensor about the
// frame-6 origin in frame-6 axes (its entries, not the products of inertia with their minus sign: the
// convention of LinkParams::inertia and of KDL). Parameters about the origin, not the COM, make the torque
// linear in them; PayloadParams converts to and from the datasheet's form (osc::Payload of
// osc/robots/arm.hpp: mass, COM, inertia about the COM, the runtime parameters payload_*) by the
// parallel-axis theorem.
//
// Y in three steps, each the textbook's equation:
//  1. The motion of frame 6 by the forward recursion of the Newton-Euler pass (rnea's, the base accelerating
//     at +g up so that gravity is in a): its angular velocity w, angular acceleration wd and the linear
//     acceleration a of its origin, then in frame-6 axes, where pi is constant.
//  2. The wrench the payload needs at the frame-6 origin, linear in pi (wrench_regressor, frame-6 axes):
//       f = m a + wd x h + w x (w x h),      n = I wd + w x (I w) + h x a.
//  3. The joint torques that hold that wrench, tau = J^T [f; n], J the geometric Jacobian of the frame-6
//     origin (data.J) with its rows turned into frame-6 axes: Y = (diag(R6^T, R6^T) J)^T A(w, wd, a). The
//     6 x 10 wrench regressor is formed once and mapped once.
// Cost: a forward recursion (no link forces), three rotations, the 6 x 10 wrench regressor and a 6 x 6 by
// 6 x 10 product: about 700 multiply-adds. An identification samples it at 100 Hz at most, outside the
// control tick. Allocation-free; templated on the scalar (double, float, osc::Fixed).
#pragma once

#include "osc/kernels/kinematics.hpp"

namespace osc {

/// The payload's parameter vector pi (the file comment's order) and its regressors.
template <class S>
using PayloadVector = Eigen::Matrix<S, 10, 1>;
template <class S>
using PayloadRegressor = Eigen::Matrix<S, kDof, 10>;  // joint torques = Y pi
template <class S>
using WrenchRegressor = Eigen::Matrix<S, 6, 10>;  // [f; n] at the frame-6 origin, frame-6 axes = A pi

/// The payload's inertial parameters pi in the scalar.
template <class S>
struct PayloadParams {
  S mass = S(0);                      ///< m [kg]
  Vec3<S> moment = Vec3<S>::Zero();   ///< h = m c [kg m], frame 6
  Vec6<S> inertia = Vec6<S>::Zero();  ///< about the frame-6 origin: Ixx, Ixy, Ixz, Iyy, Iyz, Izz [kg m^2]

  PayloadVector<S> vector() const {
    PayloadVector<S> pi;
    pi << mass, moment, inertia;
    return pi;
  }
  static PayloadParams of(const PayloadVector<S>& pi) {
    return {pi(0), pi.template segment<3>(1), pi.template segment<6>(4)};
  }

  /// From a datasheet's payload, in double: I_O = I_C + m (|c|^2 E - c c^T) (parallel axes).
  static PayloadParams from(const Payload& b) {
    const double m = b.mass, *c = b.com, *I = b.inertia, c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    PayloadParams p;
    p.mass = lit<S>(m);
    p.moment = Vec3<S>(lit<S>(m * c[0]), lit<S>(m * c[1]), lit<S>(m * c[2]));
    const double io[6] = {I[0] + m * (c2 - c[0] * c[0]), I[3] - m * c[0] * c[1], I[4] - m * c[0] * c[2],
                          I[1] + m * (c2 - c[1] * c[1]), I[5] - m * c[1] * c[2], I[2] + m * (c2 - c[2] * c[2])};
    for (int k = 0; k < 6; ++k) p.inertia(k) = lit<S>(io[k]);
    return p;
  }

  /// Back to a datasheet's form, in double: c = h / m and I_C = I_O - (|h|^2 E - h h^T) / m. A payload
  /// without mass (m <= 0: none, or an estimate below zero) has no centre of mass: c = 0, I_C = I_O.
  Payload body() const {
    const double m = static_cast<double>(mass);
    const double h[3] = {static_cast<double>(moment(0)), static_cast<double>(moment(1)),
                         static_cast<double>(moment(2))};
    double io[6];
    for (int k = 0; k < 6; ++k) io[k] = static_cast<double>(inertia(k));
    const double s = m > 0 ? 1 / m : 0, h2 = h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
    return {m,
            {h[0] * s, h[1] * s, h[2] * s},
            {io[0] - s * (h2 - h[0] * h[0]), io[3] - s * (h2 - h[1] * h[1]), io[5] - s * (h2 - h[2] * h[2]),
             io[1] + s * h[0] * h[1], io[2] + s * h[0] * h[2], io[4] + s * h[1] * h[2]}};
  }
};

/// The motion of frame 6 in base axes: angular velocity w, angular acceleration wd, and the linear
/// acceleration a of its origin, gravity included (the base accelerating at +g along z).
template <class S>
struct FlangeMotion {
  Vec3<S> w, wd, a;
};

/// The forward recursion of rnea (osc/kernels/dynamics.hpp) along the frame origins only, without the
/// links' COMs and forces. data: forward_kinematics at q.
template <class S>
FlangeMotion<S> flange_motion(const Model<S>& model, const Data<S>& data, const Vec6In<S>& qd, const Vec6In<S>& qdd) {
  FlangeMotion<S> m{Vec3<S>::Zero(), Vec3<S>::Zero(), Vec3<S>(S(0), S(0), model.gravity)};
  for (int i = 1; i <= kDof; ++i) {
    const Vec3<S> z = data.R[i - 1].col(2), zqd = z * qd(i - 1);
    m.wd += z * qdd(i - 1) + cross(m.w, zqd);
    m.w += zqd;
    const Vec3<S> r = data.o[i] - data.o[i - 1];
    m.a += cross(m.wd, r) + cross(m.w, cross(m.w, r));
  }
  return m;
}

/// [v]x, the matrix of v x.
template <class S>
Mat3<S> skew(const Vec3<S>& v) {
  Mat3<S> K;
  K << S(0), -v(2), v(1), v(2), S(0), -v(0), -v(1), v(0), S(0);
  return K;
}

/// The wrench regressor A(w, wd, a): [f; n] = A pi with the file comment's f and n, every vector in frame-6
/// axes. With I v = L(v) (Ixx, Ixy, Ixz, Iyy, Iyz, Izz):
///   f = a m + ([wd]x + [w]x [w]x) h,   [w]x [w]x = w w^T - |w|^2 E;
///   n = -[a]x h + (L(wd) + [w]x L(w)) (Ixx, ..., Izz).
template <class S>
WrenchRegressor<S> wrench_regressor(const Vec3<S>& w, const Vec3<S>& wd, const Vec3<S>& a) {
  const auto L = [](const Vec3<S>& v) {
    Eigen::Matrix<S, 3, 6> m;
    m << v(0), v(1), v(2), S(0), S(0), S(0),  //
        S(0), v(0), S(0), v(1), v(2), S(0),   //
        S(0), S(0), v(0), S(0), v(1), v(2);
    return m;
  };
  const Mat3<S> W = skew(w);
  WrenchRegressor<S> A = WrenchRegressor<S>::Zero();
  A.template block<3, 1>(0, 0) = a;
  A.template block<3, 3>(0, 1) = skew(wd) + w * w.transpose() - Mat3<S>(w.squaredNorm() * Mat3<S>::Identity());
  A.template block<3, 3>(3, 1) = -skew(a);
  A.template block<3, 6>(3, 4) = L(wd) + W * L(w);
  return A;
}

/// The payload's regressor Y (joint torques = Y pi, gravity included) at (q, qd, qdd). data:
/// forward_kinematics and geometric_jacobian at q (data.R, data.o and data.J are read).
template <class S>
PayloadRegressor<S> payload_regressor(const Model<S>& model, const Data<S>& data, const Vec6In<S>& qd,
                                      const Vec6In<S>& qdd) {
  const FlangeMotion<S> m = flange_motion(model, data, qd, qdd);
  const Mat3<S> Rt = data.R[kDof].transpose();
  // J's rows in frame-6 axes: the wrench's axes.
  Mat6<S> J6;
  J6.template topRows<3>() = Rt * data.J.template topRows<3>();
  J6.template bottomRows<3>() = Rt * data.J.template bottomRows<3>();
  return J6.transpose() * wrench_regressor<S>(Rt * m.w, Rt * m.wd, Rt * m.a);
}

}  // namespace osc
