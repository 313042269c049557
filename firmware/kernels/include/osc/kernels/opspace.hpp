// Operational-space dynamics (4)-(5): Lambda(x), Psi(x,y) z, p(x), f, Gamma = J^T F.
//
// Every solve with J or J^T goes through the arm's factor of J (OpSpace's JF, JacobianFactorFor):
// - For an arm with a spherical wrist whose centre is the frame-6 origin (has_spherical_wrist(), in
//   osc/robots/arm.hpp; the PUMA 560 is one), the linear-velocity rows of J do not depend on joints
//   4-6: J = [J11 0; J21 J22] is block lower-triangular (also for the analytic Jacobian), and
//   J^{-1} = [J11^{-1} 0; -J22^{-1} J21 J11^{-1} J22^{-1}]. SphericalWristJacobianFactor keeps the
//   inverses of the two 3x3 blocks (by cofactors: one division each); every solve with J or J^T is
//   then three 3x3 products and no division, det J = det J11 det J22, and the reciprocal condition
//   numbers are exact (1-norm).
// - Any other arm (a UR5e: its wrist axes are offset) takes PivotedLuJacobianFactor (lu.hpp): P J = L U,
//   six divisions per factorisation, none per solve, its rcond exact too.
// No 6x6 matrix is ever inverted.
#pragma once

#include <type_traits>
#include <utility>

#include "osc/kernels/dynamics.hpp"
#include "osc/kernels/lu.hpp"

namespace osc {

/// Factorisation of the block lower-triangular 6x6 Jacobian of a spherical-wrist arm. Valid only
/// when has_spherical_wrist(arm) holds (the runtime checks it at compile time for the built robot).
template <class S>
struct SphericalWristJacobianFactor {
  Mat3<S> arm_inv;    // J11^{-1}: position rows, joints 1-3
  Mat3<S> wrist_inv;  // J22^{-1}: orientation rows, joints 4-6
  Mat3<S> J21;
  /// Reciprocal condition number (1-norm) of the worse of the two blocks; 0 when one is singular.
  /// Callers refuse to act when it falls below their threshold.
  S rcond = S(0);

  void compute(const Mat6<S>& J) {
    J21 = J.template bottomLeftCorner<3, 3>();
    const S r1 = invert(J.template topLeftCorner<3, 3>(), arm_inv);
    const S r2 = invert(J.template bottomRightCorner<3, 3>(), wrist_inv);
    rcond = r1 < r2 ? r1 : r2;
    if (!math::isfinite(rcond)) rcond = S(0);
  }
  /// Column a of J^{-1} (a solve; the pivoted LU keeps them).
  Vec6<S> inverse_column(int a) const { return solve(Vec6<S>::Unit(a)); }
  /// J^{-1} b.
  Vec6<S> solve(const Vec6In<S>& b) const {
    Vec6<S> x;
    x.template head<3>() = arm_inv * b.template head<3>();
    x.template tail<3>() = wrist_inv * (b.template tail<3>() - J21 * x.template head<3>());
    return x;
  }
  /// J^{-T} b.
  Vec6<S> solve_transpose(const Vec6In<S>& b) const {
    Vec6<S> x;
    x.template tail<3>() = wrist_inv.transpose() * b.template tail<3>();
    x.template head<3>() = arm_inv.transpose() * (b.template head<3>() - J21.transpose() * x.template tail<3>());
    return x;
  }

 private:
  /// M^{-1} by cofactors (its columns are cross products of M's rows, over det M) and the reciprocal
  /// condition number of M in the 1-norm; a zero inverse and 0 when M is singular.
  static S invert(const Mat3<S>& M, Mat3<S>& inv) {
    const Vec3<S> r0 = M.row(0).transpose(), r1 = M.row(1).transpose(), r2 = M.row(2).transpose();
    Mat3<S> adj;
    adj << cross(r1, r2), cross(r2, r0), cross(r0, r1);
    const S det = r0.dot(adj.col(0));
    if (det == S(0)) {
      inv.setZero();
      return S(0);
    }
    inv = (S(1) / det) * adj;
    return S(1) / (norm1(M) * norm1(inv));
  }
  static S norm1(const Mat3<S>& M) { return M.cwiseAbs().colwise().sum().maxCoeff(); }
};

/// A = L D L^T of a symmetric positive definite N x N matrix (unit lower-triangular L, diagonal D):
/// no pivoting (not needed for A(q)), no square root, and the reciprocals 1/D kept, so that a
/// factorisation takes N divisions and a solve none (Eigen's LLT takes N square roots and N(N-1)/2
/// divisions, and N divisions per triangular solve). positive is false when a pivot is not positive
/// (A not positive definite); the solve is then meaningless. A(q) with its armature is positive
/// definite by construction, so the control step does not test it (tests/firmware/kernels/test_properties.cpp does).
template <class S, int N>
struct LdltFactor {
  Eigen::Matrix<S, N, N> L;  // strictly lower part: L; the rest unused
  Eigen::Matrix<S, N, 1> d, d_inv;
  bool positive = false;

  void compute(const Eigen::Matrix<S, N, N>& A) {
    positive = true;
    Eigen::Matrix<S, N, 1> t;  // t_k = L(j, k) d_k of the current row j
    // Row j at compile time, so that every partial row is a fixed-size segment (unrolled sums).
    for_each_index<N>([&]<int J>(std::integral_constant<int, J>) {
      if constexpr (J == 0) {
        d(0) = A(0, 0);
      } else {
        t.template head<J>() = L.row(J).template head<J>().transpose().cwiseProduct(d.template head<J>());
        d(J) = A(J, J) - L.row(J).template head<J>().dot(t.template head<J>());
      }
      if (!(d(J) > S(0))) positive = false;
      d_inv(J) = S(1) / d(J);
      for (int i = J + 1; i < N; ++i) {
        if constexpr (J == 0)
          L(i, 0) = A(i, 0) * d_inv(0);
        else
          L(i, J) = (A(i, J) - L.row(i).template head<J>().dot(t.template head<J>())) * d_inv(J);
      }
    });
  }
  /// A^{-1} b: L y = b, then L^T x = D^{-1} y.
  Eigen::Matrix<S, N, 1> solve(const Eigen::Matrix<S, N, 1>& b) const {
    Eigen::Matrix<S, N, 1> x;
    x(0) = b(0);
    for_each_index<N>([&]<int I>(std::integral_constant<int, I>) {
      if constexpr (I > 0) x(I) = b(I) - L.row(I).template head<I>().dot(x.template head<I>());
    });
    x(N - 1) *= d_inv(N - 1);
    for_each_index<N>([&]<int K>(std::integral_constant<int, K>) {
      constexpr int I = N - 2 - K, M = N - 1 - I;  // rows N-2 .. 0, each with the M entries below it
      if constexpr (I >= 0) x(I) = x(I) * d_inv(I) - L.col(I).template tail<M>().dot(x.template tail<M>());
    });
    return x;
  }
};

/// The factor of J an arm takes: the block factor where it has a spherical wrist at its operational
/// point (has_spherical_wrist(), osc/robots/arm.hpp), the pivoted LU (lu.hpp) where it has not.
template <class S, bool kSphericalWrist>
using JacobianFactorFor =
    std::conditional_t<kSphericalWrist, SphericalWristJacobianFactor<S>, PivotedLuJacobianFactor<S>>;

/// Lambda = J^{-T} A J^{-1} (5), by column solves; symmetrised. The control step never forms it: it
/// needs only products Lambda u (operational_force) and solves Lambda^{-1} w (operational_acceleration).
/// JF: the factor of J (JacobianFactorFor).
template <class S, class JF>
Mat6<S> operational_inertia(const Mat6<S>& A, const JF& Jf) {
  Mat6<S> Y;  // Y = J^{-T} A
  for (int k = 0; k < kDof; ++k) Y.col(k) = Jf.solve_transpose(A.col(k));
  Mat6<S> L;  // L^T = J^{-T} Y^T
  for (int k = 0; k < kDof; ++k) L.row(k) = Jf.solve_transpose(Y.row(k).transpose()).transpose();
  return lit<S>(0.5) * (L + L.transpose());
}

/// Operational-space state of the robot at q with task reference orientation R_ref: everything
/// the observer and controller need that depends on q only. JF: the arm's factor of J
/// (JacobianFactorFor; ArmOpSpace, osc/control/controller.hpp, is the built arm's).
template <class S, class JF>
struct OpSpace {
  Vec6<S> x;                   // [p; phi]
  PhiRate<S> E;                // E^{-1}(phi) and the trig of phi
  Mat6<S> Ja;                  // analytic Jacobian
  JF Jf;                       // factorisation of Ja
  LdltFactor<S, kDof> A_ldlt;  // A = L D L^T
  Vec6<S> g;                   // joint gravity torques
};

/// Computes kinematics, Ja and its factorisation at q and, with `dynamics` (the default), A(q), its L D L^T
/// factors and g(q); without, data.A, os.A_ldlt and os.g keep the values of the last update that computed them
/// (the control step's alternate model rate, osc/control/controller.hpp).
template <class S, class JF>
void opspace_update(const Model<S>& model, Data<S>& data, OpSpace<S, JF>& os, const Vec6In<S>& q, const Mat3<S>& R_ref,
                    bool dynamics = true) {
  forward_kinematics(model, data, q);
  geometric_jacobian(data);
  os.x = operational_coordinates(data, R_ref);
  os.E = phi_rate(Vec3<S>(os.x.template tail<3>()));
  analytic_jacobian(data.J, os.E, os.Ja);
  os.Jf.compute(os.Ja);
  if (!dynamics) return;
  joint_inertia(model, data);
  os.A_ldlt.compute(data.A);
  os.g = gravity_torques(model, data);
}

/// Lambda of the current state (opspace_update must have run).
template <class S, class JF>
Mat6<S> operational_inertia(const Data<S>& data, const OpSpace<S, JF>& os) {
  return operational_inertia(data.A, os.Jf);
}

/// p(x) = J^{-T} g(q) (5).
template <class S, class JF>
Vec6<S> operational_gravity(const OpSpace<S, JF>& os) {
  return os.Jf.solve_transpose(os.g);
}

/// f = J^{-T} tau_f (5), (31).
template <class S, class JF>
Vec6<S> operational_friction(const OpSpace<S, JF>& os, const Vec6In<S>& tau_f) {
  return os.Jf.solve_transpose(tau_f);
}

/// Gamma = J^T F (5).
template <class S, class JF>
Vec6<S> joint_torques(const OpSpace<S, JF>& os, const Vec6In<S>& F) {
  return os.Ja.transpose() * F;
}

/// Lambda^{-1} w = J A^{-1} J^T w, by the L D L^T factors of A.
template <class S, class JF>
Vec6<S> lambda_solve(const OpSpace<S, JF>& os, const Vec6In<S>& w) {
  return os.Ja * os.A_ldlt.solve(Vec6<S>(os.Ja.transpose() * w));
}

/// Lambda a + J^{-T} tau = J^{-T} (A J^{-1} a + tau): the operational force that a joint torque tau
/// and an operational acceleration a call for together, with one solve with J and one with J^T
/// (Lambda = J^{-T} A J^{-1}). Every operational force of (35) is of this form: Lambda a, p = J^{-T} g,
/// f = J^{-T} tau_f and Psi(x, y) z (psi_terms).
template <class S, class JF>
Vec6<S> operational_force(const Data<S>& data, const OpSpace<S, JF>& os, const Vec6In<S>& a, const Vec6In<S>& tau) {
  return os.Jf.solve_transpose(Vec6<S>(data.A * os.Jf.solve(a) + tau));
}

/// J A^{-1} tau + a = Lambda^{-1} J^{-T} tau + a: the operational acceleration x_dd = J q_dd + Jdot q_dot
/// of the arm under joint torque tau (q_dd = A^{-1} tau), a being Jdot q_dot; the inverse of
/// operational_force: the acceleration a force F = Lambda a + J^{-T} tau gives is
/// operational_acceleration(J^T F - tau, 0) = a. Lambda^{-1} w is operational_acceleration(J^T w, 0)
/// (lambda_solve).
template <class S, class JF>
Vec6<S> operational_acceleration(const OpSpace<S, JF>& os, const Vec6In<S>& tau, const Vec6In<S>& a) {
  return os.Ja * os.A_ldlt.solve(tau) + a;
}

/// Analytic Jdot(q, qd) qd.
template <class S, class JF>
Vec6<S> analytic_jdot_qd(const Model<S>& model, const Data<S>& data, const OpSpace<S, JF>& os, const Vec6In<S>& qd) {
  const VelocityProducts<S> vp = velocity_products(model, data, qd);
  return analytic_jdot_qd(vp.jdot_qd, vp.w6, os.E);
}

/// h(v) = Psi(x, v) v = J^{-T} c(q, qd_v) - Lambda Jdot(q, qd_v) qd_v, with qd_v = J^{-1} v,
/// evaluated as J^{-T} [c - A J^{-1} Jdot qd_v] (operational_force): the bracket is a joint torque,
/// whereas Lambda times the operational acceleration Jdot qd_v has entries many times h's
/// own near the edges of the workspace (beyond the range of a fixed-point scalar first).
template <class S, class JF>
Vec6<S> psi_quadratic(const Model<S>& model, const Data<S>& data, const OpSpace<S, JF>& os, const Vec6In<S>& v) {
  const Vec6<S> qd = os.Jf.solve(v);
  const VelocityProducts<S> vp = velocity_products(model, data, qd);
  const Vec6<S> jdqd = analytic_jdot_qd(vp.jdot_qd, vp.w6, os.E);
  return operational_force(data, os, Vec6<S>(-jdqd), vp.c);
}

/// The joint-space parts of Psi(x, y) y and Psi(x, y) z (8), from one pass of velocity_product_pair:
///   J^T Psi(x, y) z = B(q, q_y) q_z - A J^{-1} Jdot_a(q_y, q_z),   q_y = J^{-1} y, q_z = J^{-1} z,
/// with Jdot_a(q_y, q_z) the symmetric bilinear form of the analytic Jdot(q, q_y) q_y (and z = y the
/// quadratic one). The control step adds them to other joint-space terms before the one solve with
/// J^T they all need (operational_force, operational_acceleration); psi_pair finishes them alone.
template <class S>
struct PsiTerms {
  Vec6<S> c_yy, jdot_yy;  // B(q, q_y) q_y and Jdot_a(q_y, q_y)
  Vec6<S> c_yz, jdot_yz;  // B(q, q_y) q_z and Jdot_a(q_y, q_z)
};

/// The same from qy = J^{-1} y, which the caller may already have (the observer's q^dot).
template <class S, class JF>
PsiTerms<S> psi_terms(const Model<S>& model, const Data<S>& data, const OpSpace<S, JF>& os, const Vec6In<S>& qy,
                      const Vec6In<S>& z) {
  const Vec6<S> qz = os.Jf.solve(z);
  const VelocityProductPair<S> vp = velocity_product_pair(model, data, qy, qz);
  const Vec3<S> pdy = phi_rates_of(os.E, vp.quad.w6), pdz = phi_rates_of(os.E, vp.bilinear.w6);  // orientation rates
  PsiTerms<S> t;
  t.c_yy = vp.quad.c;
  t.c_yz = vp.bilinear.c;
  t.jdot_yy << vp.quad.jdot_qd.template head<3>(),
      phi_rates_of(os.E, Vec3<S>(vp.quad.jdot_qd.template tail<3>() - edot_rates(os.E, pdy)));
  t.jdot_yz << vp.bilinear.jdot_qd.template head<3>(),
      phi_rates_of(os.E, Vec3<S>(vp.bilinear.jdot_qd.template tail<3>() - edot_rates(os.E, pdy, pdz)));
  return t;
}

/// Psi(x, y) y and Psi(x, y) z together (z enters linearly; Psi(x, y) z is the symmetric bilinear
/// form of (8)): one pass of velocity_product_pair.
template <class S>
struct PsiPair {
  Vec6<S> yy;  // Psi(x, y) y
  Vec6<S> yz;  // Psi(x, y) z
};

template <class S, class JF>
PsiPair<S> psi_pair(const Model<S>& model, const Data<S>& data, const OpSpace<S, JF>& os, const Vec6In<S>& y,
                    const Vec6In<S>& z) {
  const PsiTerms<S> t = psi_terms(model, data, os, Vec6<S>(os.Jf.solve(y)), z);
  PsiPair<S> out;
  out.yy = operational_force(data, os, Vec6<S>(-t.jdot_yy), t.c_yy);
  out.yz = operational_force(data, os, Vec6<S>(-t.jdot_yz), t.c_yz);
  return out;
}

/// Psi(x, y) z, the symmetric bilinear form of (8).
template <class S, class JF>
Vec6<S> psi_bilinear(const Model<S>& model, const Data<S>& data, const OpSpace<S, JF>& os, const Vec6In<S>& y,
                     const Vec6In<S>& z) {
  return psi_pair(model, data, os, y, z).yz;
}

}  // namespace osc
