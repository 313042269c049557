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
    wd = wd + z * qdd(i - 1) + cross(w_prev, z * qd(i - 1));
    const Vec3<S> r = data.o[i] - data.o[i - 1];
    a = a + cross(wd, r) + cross(w, cross(w, r));
    const Vec3<S> rc = data.com[i] - data.o[i];
    const Vec3<S> ac = a + cross(wd, rc) + cross(w, cross(w, rc));
    f[i] = model.link[i - 1].mass * ac;
    n[i] = data.Ic[i] * wd + cross(w, data.Ic[i] * w);
  }
  RneaOut<S> out;
  out.acc6 = a;
  out.alpha6 = wd;
  out.w6 = w;
  // Backward pass: force F and moment N about the base origin of links i..6, which joint i
  // transmits. Its torque is z_{i-1} . (N - o_{i-1} x F) = z_{i-1} . N + vO_{i-1} . F: no moment arm
  // changes from link to link.
  Vec3<S> F = Vec3<S>::Zero(), N = Vec3<S>::Zero();
  for (int i = kDof; i >= 1; --i) {
    N = n[i] + N + cross(data.com[i], f[i]);
    F = f[i] + F;
    out.tau(i - 1) = dot_sum(Vec3<S>(data.R[i - 1].col(2)), N, data.vO[i - 1], F) + model.armature(i - 1) * qdd(i - 1);
  }
  return out;
}

/// Joint-space inertia A(q) with armature, by the composite-rigid-body algorithm:
/// A_ij = z_{i-1} . (moment about o_{i-1} of the momentum of composite body j under unit qd_j).
/// Composite spatial inertias are accumulated about the base origin: mass m, first moment h = m c,
/// rotational inertia I_O.
template <class S>
void joint_inertia(const Model<S>& model, Data<S>& data) {
  // Unit rotation about axis z_i through o_{i-1}: angular velocity z_i, base-origin velocity
  // vO_i = o_{i-1} x z_i (data.vO). A_ij = z_i . (L_j - o_{i-1} x p_j) = z_i . L_j + vO_i . p_j.
  const Vec3<S>* vO = data.vO;
  S m = S(0);
  Vec3<S> h = Vec3<S>::Zero();
  // I_O's six entries (symmetric), the first body's its own (adding it to zeros changes at most the sign of a zero).
  S io00 = S(0), io11 = S(0), io22 = S(0), io01 = S(0), io02 = S(0), io12 = S(0);
  for (int j = kDof; j >= 1; --j) {
    const S mj = model.link[j - 1].mass;
    const Vec3<S>& c = data.com[j];
    const Vec3<S> mc = mj * c;
    m += mj;
    h += mc;
    // I_O += Ic + mj (|c|^2 I - c c^T): the diagonal entry r is sum_{k != r} mc_k c_k, an off-diagonal
    // one -mc_r c_s.
    const Mat3<S>& Ic = data.Ic[j];
    const S d0 = Ic(0, 0) + math::sum_of_products(mc(1), c(1), mc(2), c(2));
    const S d1 = Ic(1, 1) + math::sum_of_products(mc(0), c(0), mc(2), c(2));
    const S d2 = Ic(2, 2) + math::sum_of_products(mc(0), c(0), mc(1), c(1));
    const S o01 = Ic(0, 1) - mc(0) * c(1), o02 = Ic(0, 2) - mc(0) * c(2), o12 = Ic(1, 2) - mc(1) * c(2);
    if (j == kDof) {
      io00 = d0, io11 = d1, io22 = d2, io01 = o01, io02 = o02, io12 = o12;
    } else {
      io00 += d0, io11 += d1, io22 += d2, io01 += o01, io02 += o02, io12 += o12;
    }
    const Vec3<S> z = data.R[j - 1].col(2);
    const Vec3<S> p = m * vO[j - 1] + cross(z, h);  // linear momentum
    Mat3<S> IO;
    IO << io00, io01, io02, io01, io11, io12, io02, io12, io22;
    const Vec3<S> L = IO * z + cross(h, vO[j - 1]);  // angular momentum about the base origin
    for (int i = 1; i <= j; ++i) {
      data.A(i - 1, j - 1) = dot_sum(Vec3<S>(data.R[i - 1].col(2)), L, vO[i - 1], p);
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

/// The velocity products of one velocity y and their symmetric bilinear form with a second velocity
/// v, in one pass: quad = c(q, y) = B(q, y) y with the geometric Jdot y of the frame-6 origin, and
/// bilinear = B(q, y) v (property 2: = B(q, v) y) with the bilinear form of Jdot, i.e. the
/// polarisation (c(y + v) - c(y - v)) / 4 without its two passes. Every product that is quadratic in
/// the velocity in rnea (w x (z qd), w x (w x r), w x (I w)) becomes half the sum of its two
/// mixed products; the linear parts (the angular velocities of y and v) are shared.
template <class S>
struct VelocityProductPair {
  VelocityProducts<S> quad;      // c(q, y), Jdot y, w6(y)
  VelocityProducts<S> bilinear;  // B(q, y) v, bilinear Jdot, w6(v)
};

template <class S>
VelocityProductPair<S> velocity_product_pair(const Model<S>& model, const Data<S>& data, const Vec6In<S>& y,
                                             const Vec6In<S>& v) {
  // The bilinear quantities (wdb, ab, fb, nb, Fb, Nb) are carried doubled: each mixed product is
  // then a plain sum of its two halves, and the one factor 1/2 is applied to the outputs.
  Vec3<S> wy = Vec3<S>::Zero(), wv = Vec3<S>::Zero();
  Vec3<S> wdq = Vec3<S>::Zero(), wdb = Vec3<S>::Zero(), aq = Vec3<S>::Zero(), ab = Vec3<S>::Zero();
  Vec3<S> fq[kDof + 1], nq[kDof + 1], fb[kDof + 1], nb[kDof + 1];
  // Link 1: the base is at rest (w = wd = 0 before it), so the products with the base's wdq, wdb and w are exact
  // zeros and left out (adding them changes no sum but, at most, the sign of a zero one).
  for (int i = 1; i <= kDof; ++i) {
    const bool first = i == 1;
    const Vec3<S> z = data.R[i - 1].col(2);
    const Vec3<S> zy = z * y(i - 1), zv = z * v(i - 1);
    if (!first) {
      wdq += cross(wy, zy);
      wdb += cross(wy, zv) + cross(wv, zy);
    }
    wy += zy;
    wv += zv;
    const Vec3<S> r = data.o[i] - data.o[i - 1], rc = data.com[i] - data.o[i];
    const Vec3<S> wyr = cross(wy, r), wvr = cross(wv, r), wyrc = cross(wy, rc), wvrc = cross(wv, rc);
    const S m = model.link[i - 1].mass;
    const Vec3<S> Iwy = data.Ic[i] * wy, Iwv = data.Ic[i] * wv;
    if (first) {
      aq += cross(wy, wyr);
      ab += cross(wy, wvr) + cross(wv, wyr);
      fq[i] = m * (aq + cross(wy, wyrc));
      fb[i] = m * (ab + cross(wy, wvrc) + cross(wv, wyrc));
      nq[i] = cross(wy, Iwy);
      nb[i] = cross(wy, Iwv) + cross(wv, Iwy);
    } else {
      aq += cross(wdq, r) + cross(wy, wyr);
      ab += cross(wdb, r) + cross(wy, wvr) + cross(wv, wyr);
      fq[i] = m * (aq + cross(wdq, rc) + cross(wy, wyrc));
      fb[i] = m * (ab + cross(wdb, rc) + cross(wy, wvrc) + cross(wv, wyrc));
      nq[i] = data.Ic[i] * wdq + cross(wy, Iwy);
      nb[i] = data.Ic[i] * wdb + cross(wy, Iwv) + cross(wv, Iwy);
    }
  }
  const S h = lit<S>(0.5);
  VelocityProductPair<S> out;
  out.quad.jdot_qd.template head<3>() = aq;
  out.quad.jdot_qd.template tail<3>() = wdq;
  out.quad.w6 = wy;
  out.bilinear.jdot_qd.template head<3>() = h * ab;
  out.bilinear.jdot_qd.template tail<3>() = h * wdb;
  out.bilinear.w6 = wv;
  // Forces and moments about the base origin, as in rnea.
  Vec3<S> Fq = Vec3<S>::Zero(), Nq = Vec3<S>::Zero(), Fb = Vec3<S>::Zero(), Nb = Vec3<S>::Zero();
  for (int i = kDof; i >= 1; --i) {
    Nq = nq[i] + Nq + cross(data.com[i], fq[i]);
    Nb = nb[i] + Nb + cross(data.com[i], fb[i]);
    Fq += fq[i];
    Fb += fb[i];
    const Vec3<S> z = data.R[i - 1].col(2);
    out.quad.c(i - 1) = dot_sum(z, Nq, data.vO[i - 1], Fq);
    out.bilinear.c(i - 1) = h * dot_sum(z, Nb, data.vO[i - 1], Fb);
  }
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
