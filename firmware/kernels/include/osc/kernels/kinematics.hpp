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

/// Ic = Rn I Rn^T for a link with products of inertia, from I's Cholesky factor L (Model::root_diagonal,
/// root_lower): Ic = B B^T with B = Rn L (18 + 18 multiply-adds; the full tensor rotated at once took 27 + 18).
/// Inline: a call per link cost the UR5e's M4F tick 37 instructions, and the PUMA's (no products) none.
template <class S>
[[gnu::always_inline]] inline void rotated_full_inertia(const Mat3<S>& Rn, const Vec3<S>& d, const Vec3<S>& l,
                                                        Mat3<S>& Ic) {
  Mat3<S> B;
  B.col(0) = sum3(d(0), Vec3<S>(Rn.col(0)), l(0), Vec3<S>(Rn.col(1)), l(1), Vec3<S>(Rn.col(2)));
  B.col(1) = combine(d(1), Vec3<S>(Rn.col(1)), l(2), Vec3<S>(Rn.col(2)));
  B.col(2) = d(2) * Rn.col(2);
  for (int r = 0; r < 3; ++r)
    for (int k = r; k < 3; ++k) Ic(r, k) = Ic(k, r) = B.row(r).dot(B.row(k));
}

/// Frames 0..6 into data.R, data.o; COM positions and base-axis inertias into data.com, data.Ic; the
/// joint axes' moments o_i x z_i into data.vO (the CRBA's and the RNEA passes' joint projections).
/// F_{i+1} = F_i Rz(q_i) P_i (osc/robots/arm.hpp): Rz turns the first two columns of R_i by q_i
/// (x, y below, z unchanged), and the placement's rotation mixes them (columns moved with a sign
/// for the DH twists 0 and +-pi/2, else a product: Model::Link::form). o_{i+1} = o_i + p_x x +
/// p_y y + p_z z (a x + d z for a DH row).
template <class S>
void forward_kinematics(const Model<S>& model, Data<S>& data, const Vec6In<S>& q) {
  if (model.base_identity) {
    data.R[0].setIdentity();
    data.o[0].setZero();
  } else {
    data.R[0] = model.base_R;
    data.o[0] = model.base_o;
  }
  // The joints' sines and cosines first: independent of each other, unlike the frames below.
  S sq[kDof], cq[kDof];
  for (int i = 0; i < kDof; ++i) math::sincos(q(i), sq[i], cq[i]);
  for (int i = 0; i < kDof; ++i) {
    const auto& l = model.link[i];
    const S s = sq[i], c = cq[i];
    const Mat3<S>& R = data.R[i];
    Mat3<S>& Rn = data.R[i + 1];
    const Vec3<S> x = combine(c, R.col(0), s, R.col(1));   // R Rz(q) e_x
    const Vec3<S> y = combine(c, R.col(1), -s, R.col(0));  // R Rz(q) e_y
    const Vec3<S> z = R.col(2);
    switch (l.form.rotation) {
      case Rotation::kIdentity:
        Rn.col(0) = x, Rn.col(1) = y, Rn.col(2) = z;
        break;
      case Rotation::kRxPlusHalfPi:
        Rn.col(0) = x, Rn.col(1) = z, Rn.col(2) = -y;
        break;
      case Rotation::kRxMinusHalfPi:
        Rn.col(0) = x, Rn.col(1) = -z, Rn.col(2) = y;
        break;
      case Rotation::kPermutation:
      case Rotation::kGeneral:
        for (int k = 0; k < 3; ++k) Rn.col(k) = sum3(l.R(0, k), x, l.R(1, k), y, l.R(2, k), z);
        break;
    }
    data.o[i + 1] = data.o[i] + combine(l.p(0), x, l.p(2), z);
    if (!l.form.planar) data.o[i + 1] += l.p(1) * y;  // off the DH plane: a URDF's offset
    data.com[i + 1] = data.o[i + 1] + Rn * l.com;
    // Ic = Rn I Rn^T, symmetric: six of its entries; of the principal part diag(Ixx, Iyy, Izz) alone where
    // the link has no products (Ixy, Ixz, Iyz), else of the full tensor.
    Mat3<S>& Ic = data.Ic[i + 1];
    if (l.diagonal) {
      const Mat3<S> M = Rn * l.inertia.asDiagonal();
      for (int r = 0; r < 3; ++r)
        for (int k = r; k < 3; ++k) Ic(r, k) = Ic(k, r) = M.row(r).dot(Rn.row(k));
    } else {
      rotated_full_inertia(Rn, model.root_diagonal[i], model.root_lower[i], Ic);
    }
  }
  for (int i = 0; i < kDof; ++i) data.vO[i] = cross(data.o[i], data.R[i].col(2));
}

/// Geometric Jacobian of the frame-6 origin, base frame: column j = [z_{j-1} x (o6 - o_{j-1}); z_{j-1}].
/// For the PUMA the upper-right 3x3 block is zero (the wrist axes meet at o6).
template <class S>
void geometric_jacobian(Data<S>& data) {
  for (int j = 0; j < kDof; ++j) {
    const Vec3<S> z = data.R[j].col(2);
    data.J.template block<3, 1>(0, j) = cross(z, data.o[kDof] - data.o[j]);
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

/// The map between the base angular velocity w and the orientation rates phi_dot at phi:
/// E(phi) phi_dot = w. Computed once per sample (opspace_update) with the sines and cosines of pitch
/// and yaw that its derivative needs too.
template <class S>
struct PhiRate {
  Mat3<S> Einv;      // E^{-1}(phi): phi_dot = E^{-1} w
  S cb, sb, cg, sg;  // cos, sin of pitch (phi_2) and yaw (phi_3)
};

template <class S>
PhiRate<S> phi_rate(const Vec3<S>& phi) {
  PhiRate<S> E;
  math::sincos(phi(1), E.sb, E.cb);
  math::sincos(phi(2), E.sg, E.cg);
  const S cg_cb = E.cg / E.cb, sg_cb = E.sg / E.cb;
  E.Einv << cg_cb, sg_cb, S(0), -E.sg, E.cg, S(0), E.sb * cg_cb, E.sb * sg_cb, S(1);
  return E;
}

/// E^{-1}(phi): maps the base angular velocity w to phi_dot (E(phi) phi_dot = w).
template <class S>
Mat3<S> angular_to_phi_rate(const Vec3<S>& phi) {
  return phi_rate(phi).Einv;
}

/// E(phi) itself: maps phi_dot to the base angular velocity, w = E(phi) phi_dot (defined at every
/// phi; a client's rates of roll, pitch, yaw as the angular velocity a setpoint carries).
template <class S>
Mat3<S> phi_rate_to_angular(const Vec3<S>& phi) {
  S sb, cb, sg, cg;
  math::sincos(phi(1), sb, cb);
  math::sincos(phi(2), sg, cg);
  Mat3<S> E;
  E << cg * cb, -sg, S(0), sg * cb, cg, S(0), -sb, S(0), S(1);
  return E;
}

/// E^{-1}(phi) w with E^{-1}'s two zeros and its one (phi_rate) skipped: each entry is the sum E.Einv * w forms,
/// p0 + (p1 + p2) with p2 = 0 or w_z (in fixed point rounded once), the same bits from 7 of its 9 products. Its
/// other six entries as values, kept in registers over a loop of such products (analytic_jacobian).
template <class S>
struct PhiRateRows {
  S e00, e01, e10, e11, e20, e21;
  explicit PhiRateRows(const PhiRate<S>& E)
      : e00(E.Einv(0, 0)),
        e01(E.Einv(0, 1)),
        e10(E.Einv(1, 0)),
        e11(E.Einv(1, 1)),
        e20(E.Einv(2, 0)),
        e21(E.Einv(2, 1)) {}
  [[gnu::always_inline]] Vec3<S> operator()(S wx, S wy, S wz) const {
    return Vec3<S>(math::sum_of_products(e00, wx, e01, wy), math::sum_of_products(e10, wx, e11, wy),
                   math::sum_of_products(e20, wx, e21, wy, S(1), wz));
  }
};
template <class S, class V>
[[gnu::always_inline]] inline Vec3<S> phi_rates_of(const PhiRate<S>& E, const Eigen::MatrixBase<V>& w) {
  const Vec3<S> v = w;
  return PhiRateRows<S>(E)(v(0), v(1), v(2));
}

/// Analytic Jacobian Ja = blockdiag(I, E^{-1}(phi)) J, so that x_dot = Ja q_dot, written into Ja (the control
/// step's, without a copy of it).
template <class S>
void analytic_jacobian(const Mat6<S>& J, const PhiRate<S>& E, Mat6<S>& Ja) {
  Ja.template topRows<3>() = J.template topRows<3>();
  const PhiRateRows<S> e(E);
  for (int c = 0; c < kDof; ++c) Ja.template block<3, 1>(3, c) = e(J(3, c), J(4, c), J(5, c));
}
template <class S>
Mat6<S> analytic_jacobian(const Mat6<S>& J, const PhiRate<S>& E) {
  Mat6<S> Ja;
  analytic_jacobian(J, E, Ja);
  return Ja;
}
template <class S>
Mat6<S> analytic_jacobian(const Mat6<S>& J, const Vec3<S>& phi) {
  return analytic_jacobian(J, phi_rate(phi));
}

/// Edot phi_dot for the products of the rates p01 = phi_dot_1 phi_dot_2, p20 = phi_dot_3 phi_dot_1,
/// p21 = phi_dot_3 phi_dot_2 (symmetrised products for the bilinear form).
template <class S>
Vec3<S> edot_products(const PhiRate<S>& E, S p01, S p20, S p21) {
  return p01 * Vec3<S>(-E.cg * E.sb, -E.sg * E.sb, -E.cb) + p20 * Vec3<S>(-E.sg * E.cb, E.cg * E.cb, S(0)) +
         p21 * Vec3<S>(-E.cg, -E.sg, S(0));
}
/// Edot(phi, phi_dot) phi_dot.
template <class S>
Vec3<S> edot_rates(const PhiRate<S>& E, const Vec3<S>& a) {
  return edot_products(E, a(0) * a(1), a(2) * a(0), a(2) * a(1));
}
/// The symmetric bilinear form of Edot(phi, phi_dot) phi_dot at the rates a and b.
template <class S>
Vec3<S> edot_rates(const PhiRate<S>& E, const Vec3<S>& a, const Vec3<S>& b) {
  const S h = lit<S>(0.5);
  return edot_products(E, h * (a(0) * b(1) + a(1) * b(0)), h * (a(2) * b(0) + a(0) * b(2)),
                       h * (a(2) * b(1) + a(1) * b(2)));
}

/// Converts the geometric Jdot*qd = [a6; alpha6] (q_ddot = 0) into the analytic one:
/// d/dt(E^{-1} w) = E^{-1} (alpha - Edot phi_dot), with w = J_w qd.
template <class S>
Vec6<S> analytic_jdot_qd(const Vec6<S>& jdot_qd_geometric, const Vec3<S>& w, const PhiRate<S>& E) {
  const Vec3<S> pd = E.Einv * w;  // (roll, pitch, yaw) rates
  Vec6<S> out;
  out << jdot_qd_geometric.template head<3>(), E.Einv * (jdot_qd_geometric.template tail<3>() - edot_rates(E, pd));
  return out;
}
template <class S>
Vec6<S> analytic_jdot_qd(const Vec6<S>& jdot_qd_geometric, const Vec3<S>& w, const Vec3<S>& phi) {
  return analytic_jdot_qd(jdot_qd_geometric, w, phi_rate(phi));
}

}  // namespace osc
