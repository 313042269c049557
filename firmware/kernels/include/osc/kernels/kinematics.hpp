// Forward kinematics, geometric and analytic Jacobians, and Jdot*qd.
//
// Operational coordinates x = [p; phi]: p is the frame-6 origin (the wrist centre) in the
// base frame; phi = (roll, pitch, yaw) of the rotation *relative to a fixed reference
// orientation* R_ref, R(q) R_ref^T = Rz(yaw) Ry(pitch) Rx(roll), i.e. rotations about the
// base X, Y and Z axes. phi = 0 at R = R_ref, where E(phi) = I; the coordinates are singular
// only at pitch = +-90 deg relative to the reference, far from the paper's task, which holds
// the start orientation (R_ref = start orientation).  Absolute roll-pitch-yaw would be
// singular exactly at qn, where the tool axis points along base +x.
#pragma once

#include "osc/kernels/model.hpp"

namespace osc {

/// Frames 0..6 into data.R, data.o; COM positions and base-axis inertias into data.com, data.Ic.
template <class S>
void forward_kinematics(const Model<S>& model, Data<S>& data, const Vec6In<S>& q) {
  data.R[0].setIdentity();
  data.o[0].setZero();
  for (int i = 0; i < kDof; ++i) {
    const auto& l = model.link[i];
    const S c = math::cos(q(i)), s = math::sin(q(i));
    Mat3<S> Ai;  // Rz(q) Rx(alpha)
    Ai << c, -s * l.cos_alpha, s * l.sin_alpha,
          s, c * l.cos_alpha, -c * l.sin_alpha,
          S(0), l.sin_alpha, l.cos_alpha;
    data.o[i + 1] = data.o[i] + data.R[i] * Vec3<S>(l.a * c, l.a * s, l.d);
    data.R[i + 1] = data.R[i] * Ai;
    data.com[i + 1] = data.o[i + 1] + data.R[i + 1] * l.com;
    data.Ic[i + 1] = data.R[i + 1] * l.inertia.asDiagonal() * data.R[i + 1].transpose();
  }
}

/// Geometric Jacobian of the frame-6 origin, base frame: column j = [z_{j-1} x (o6 - o_{j-1}); z_{j-1}].
/// For the PUMA the upper-right 3x3 block is zero (the wrist axes meet at o6).
template <class S>
void geometric_jacobian(Data<S>& data) {
  for (int j = 0; j < kDof; ++j) {
    const Vec3<S> z = data.R[j].col(2);
    data.J.template block<3, 1>(0, j) = z.cross(data.o[kDof] - data.o[j]);
    data.J.template block<3, 1>(3, j) = z;
  }
}

/// Orientation coordinates phi of R relative to R_ref (see the file comment).
template <class S>
Vec3<S> orientation_coordinates(const Mat3<S>& R, const Mat3<S>& R_ref) {
  const Mat3<S> Rr = R * R_ref.transpose();
  S sp = -Rr(2, 0);
  if (sp > S(1)) sp = S(1);
  if (sp < S(-1)) sp = S(-1);
  return Vec3<S>(math::atan2(Rr(2, 1), Rr(2, 2)), math::asin(sp), math::atan2(Rr(1, 0), Rr(0, 0)));
}

/// x = [p; phi] of the current data (forward_kinematics must have run).
template <class S>
Vec6<S> operational_coordinates(const Data<S>& data, const Mat3<S>& R_ref) {
  Vec6<S> x;
  x << data.o[kDof], orientation_coordinates(data.R[kDof], R_ref);
  return x;
}

/// E^{-1}(phi): maps the base angular velocity w to phi_dot (E(phi) phi_dot = w).
template <class S>
Mat3<S> angular_to_phi_rate(const Vec3<S>& phi) {
  const S cb = math::cos(phi(1)), sb = math::sin(phi(1));
  const S cg = math::cos(phi(2)), sg = math::sin(phi(2));
  Mat3<S> Einv;
  Einv << cg / cb, sg / cb, S(0),
          -sg, cg, S(0),
          cg * sb / cb, sg * sb / cb, S(1);
  return Einv;
}

/// Analytic Jacobian Ja = blockdiag(I, E^{-1}(phi)) J, so that x_dot = Ja q_dot.
template <class S>
Mat6<S> analytic_jacobian(const Mat6<S>& J, const Vec3<S>& phi) {
  Mat6<S> Ja = J;
  Ja.template bottomRows<3>() = angular_to_phi_rate(phi) * J.template bottomRows<3>();
  return Ja;
}

/// Converts the geometric Jdot*qd = [a6; alpha6] (q_ddot = 0) into the analytic one:
/// d/dt(E^{-1} w) = E^{-1} (alpha - Edot phi_dot), with w = J_w qd.
template <class S>
Vec6<S> analytic_jdot_qd(const Vec6<S>& jdot_qd_geometric, const Vec3<S>& w, const Vec3<S>& phi) {
  const Mat3<S> Einv = angular_to_phi_rate(phi);
  const Vec3<S> pd = Einv * w;  // (roll, pitch, yaw) rates
  const S cb = math::cos(phi(1)), sb = math::sin(phi(1));
  const S cg = math::cos(phi(2)), sg = math::sin(phi(2));
  const Vec3<S> Edot_pd = pd(0) * pd(1) * Vec3<S>(-cg * sb, -sg * sb, -cb) +
                          pd(2) * (pd(0) * Vec3<S>(-sg * cb, cg * cb, S(0)) + pd(1) * Vec3<S>(-cg, -sg, S(0)));
  Vec6<S> out;
  out << jdot_qd_geometric.template head<3>(), Einv * (jdot_qd_geometric.template tail<3>() - Edot_pd);
  return out;
}

}  // namespace osc
