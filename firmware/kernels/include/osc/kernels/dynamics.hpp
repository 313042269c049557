// Joint-space dynamics (1) without friction: A(q) q_dd + B(q,qd) qd + g(q) = Gamma.
// All functions read the frames that forward_kinematics left in data.
#pragma once

#include "osc/kernels/kinematics.hpp"

namespace osc {

/// Result of one recursive Newton-Euler pass.
template <class S>
struct RneaOut {
  Vec6<S> tau;     // joint torques (armature * q_dd included)
  Vec3<S> acc6;    // classical linear acceleration of the frame-6 origin
  Vec3<S> alpha6;  // angular acceleration of link 6
  Vec3<S> w6;      // angular velocity of link 6
};

/// Recursive Newton-Euler in base-frame vectors. gravity_on selects g(q).
template <class S>
RneaOut<S> rnea(const Model<S>& model, const Data<S>& data, const Vec6In<S>& qd, const Vec6In<S>& qdd,
                bool gravity_on) {
  Vec3<S> w = Vec3<S>::Zero(), wd = Vec3<S>::Zero();
  // Gravity enters as an upward acceleration of the base.
  Vec3<S> a = gravity_on ? Vec3<S>(S(0), S(0), model.gravity) : Vec3<S>::Zero();
  Vec3<S> f[kDof + 1], n[kDof + 1];
  // Forward pass: velocities and accelerations of each link.
  for (int i = 1; i <= kDof; ++i) {
    const Vec3<S> z = data.R[i - 1].col(2);
    const Vec3<S> w_prev = w;
    w = w_prev + z * qd(i - 1);
    wd = wd + z * qdd(i - 1) + w_prev.cross(z * qd(i - 1));
    const Vec3<S> r = data.o[i] - data.o[i - 1];
    a = a + wd.cross(r) + w.cross(w.cross(r));
    const Vec3<S> rc = data.com[i] - data.o[i];
    const Vec3<S> ac = a + wd.cross(rc) + w.cross(w.cross(rc));
    f[i] = model.link[i - 1].mass * ac;
    n[i] = data.Ic[i] * wd + w.cross(data.Ic[i] * w);
  }
  RneaOut<S> out;
  out.acc6 = a;
  out.alpha6 = wd;
  out.w6 = w;
  // Backward pass: force F and moment N about o_{i-1} transmitted through joint i.
  Vec3<S> F = Vec3<S>::Zero(), N = Vec3<S>::Zero();
  for (int i = kDof; i >= 1; --i) {
    N = n[i] + N + (data.com[i] - data.o[i - 1]).cross(f[i]) + (data.o[i] - data.o[i - 1]).cross(F);
    F = f[i] + F;
    out.tau(i - 1) = data.R[i - 1].col(2).dot(N) + model.armature(i - 1) * qdd(i - 1);
  }
  return out;
}

/// Joint-space inertia A(q) with armature, by the composite-rigid-body algorithm:
/// A_ij = z_{i-1} . (moment about o_{i-1} of the momentum of composite body j under unit qd_j).
/// Composite spatial inertias are accumulated about the base origin: mass m, first moment h = m c,
/// rotational inertia I_O.
template <class S>
void joint_inertia(const Model<S>& model, Data<S>& data) {
  S m = S(0);
  Vec3<S> h = Vec3<S>::Zero();
  Mat3<S> IO = Mat3<S>::Zero();
  for (int j = kDof; j >= 1; --j) {
    const S mj = model.link[j - 1].mass;
    const Vec3<S>& c = data.com[j];
    m += mj;
    h += mj * c;
    IO += data.Ic[j] + mj * (c.squaredNorm() * Mat3<S>::Identity() - c * c.transpose());
    // Unit rotation about axis z through o_{j-1}: angular velocity z, origin velocity o x z.
    const Vec3<S> z = data.R[j - 1].col(2);
    const Vec3<S> vO = data.o[j - 1].cross(z);
    const Vec3<S> p = m * vO + z.cross(h);      // linear momentum
    const Vec3<S> L = IO * z + h.cross(vO);     // angular momentum about the base origin
    for (int i = 1; i <= j; ++i) {
      const Vec3<S> zi = data.R[i - 1].col(2);
      data.A(i - 1, j - 1) = zi.dot(L - data.o[i - 1].cross(p));
      data.A(j - 1, i - 1) = data.A(i - 1, j - 1);
    }
  }
  data.A.diagonal() += model.armature;
}

/// Gravity torques g(q), from the composite bodies (what rnea with gravity and no motion gives, in
/// O(n) products instead of a full pass): joint j holds the weight of links j..6, whose mass M_j
/// and first moment h_j = sum m_i c_i the backward loop accumulates, so
/// g_j = z_{j-1} . ((h_j - M_j o_{j-1}) x (0, 0, gravity)).
template <class S>
Vec6<S> gravity_torques(const Model<S>& model, const Data<S>& data) {
  S m = S(0);
  Vec3<S> h = Vec3<S>::Zero();
  Vec6<S> g;
  for (int j = kDof; j >= 1; --j) {
    m += model.link[j - 1].mass;
    h += model.link[j - 1].mass * data.com[j];
    const Vec3<S> r = h - m * data.o[j - 1];  // first moment of links j..6 about o_{j-1}
    const Vec3<S> z = data.R[j - 1].col(2);
    g(j - 1) = model.gravity * (z(0) * r(1) - z(1) * r(0));  // z . (r x g e_z)
  }
  return g;
}

/// Velocity products c(q,qd) = B(q,qd) qd (no gravity, no acceleration), and in the same pass
/// the geometric Jdot*qd = [acc6; alpha6] of the frame-6 origin.
template <class S>
struct VelocityProducts {
  Vec6<S> c;
  Vec6<S> jdot_qd;
  Vec3<S> w6;
};

template <class S>
VelocityProducts<S> velocity_products(const Model<S>& model, const Data<S>& data, const Vec6In<S>& qd) {
  const RneaOut<S> r = rnea(model, data, qd, Vec6<S>::Zero(), false);
  VelocityProducts<S> out;
  out.c = r.tau;
  out.jdot_qd << r.acc6, r.alpha6;
  out.w6 = r.w6;
  return out;
}

/// Christoffel-form bilinear map B(q,y) z (property 2: B(q,y) z = B(q,z) y), by polarisation
/// of the quadratic form c(q, v): B(q,y) z = (c(y+z) - c(y-z)) / 4.
template <class S>
Vec6<S> coriolis_bilinear(const Model<S>& model, const Data<S>& data, const Vec6In<S>& y, const Vec6In<S>& z) {
  const Vec6<S> cp = rnea(model, data, y + z, Vec6<S>::Zero(), false).tau;
  const Vec6<S> cm = rnea(model, data, y - z, Vec6<S>::Zero(), false).tau;
  return lit<S>(0.25) * (cp - cm);
}

/// Christoffel-form matrix B(q, qd): column k = B(q, qd) e_k.
template <class S>
Mat6<S> coriolis_matrix(const Model<S>& model, const Data<S>& data, const Vec6In<S>& qd) {
  Mat6<S> B;
  for (int k = 0; k < kDof; ++k) B.col(k) = coriolis_bilinear(model, data, qd, Vec6<S>::Unit(k));
  return B;
}

}  // namespace osc
