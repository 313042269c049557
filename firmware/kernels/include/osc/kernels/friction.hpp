// Joint friction model (2) and its linear-in-the-parameters form (18)-(20).
#pragma once

#include "osc/kernels/model.hpp"

namespace osc {

template <class S>
using Regressor = Eigen::Matrix<S, kDof, 3 * kDof>;

/// Coefficients of (2). theta = [tau_vis; tau_cou; tau_sti] (20); tau_dec is known.
template <class S>
struct FrictionParams {
  Vec6<S> vis, cou, sti, dec;

  /// From a table of coefficients (osc/robots/arm.hpp) and every tau_dec = dec.
  static FrictionParams from(const FrictionCoefficients& c, double dec_all) {
    FrictionParams p;
    for (int i = 0; i < kDof; ++i) {
      p.vis(i) = lit<S>(c.vis[i]);
      p.cou(i) = lit<S>(c.cou[i]);
      p.sti(i) = lit<S>(c.sti[i]);
      p.dec(i) = lit<S>(dec_all);
    }
    return p;
  }

  Vec18<S> theta() const {
    Vec18<S> t;
    t << vis, cou, sti;
    return t;
  }
};

/// Friction torque (2): tau_f = vis qd + [cou + sti exp(-dec qd^2)] sgn(qd), per joint (10).
template <class S>
Vec6<S> friction_torque(const FrictionParams<S>& p, const Vec6In<S>& qd) {
  Vec6<S> tau;
  for (int i = 0; i < kDof; ++i)
    tau(i) = p.vis(i) * qd(i) + (p.cou(i) + p.sti(i) * math::exp(-p.dec(i) * qd(i) * qd(i))) * math::sgn(qd(i));
  return tau;
}

/// The three diagonals of the regressor W_j(qd) of (19), [diag(qd), diag(sgn qd),
/// diag(sgn(qd) exp(-dec qd^2))]: all of its nonzeros. Products with W and W^T take 18 multiplications
/// this way instead of 108, with the same sums (the dense product only adds zeros).
template <class S>
struct RegressorDiagonals {
  Vec6<S> vis, cou, sti;

  /// W theta (theta = [vis; cou; sti], 18 entries).
  Vec6<S> times(const Vec18<S>& theta) const {
    return vis.cwiseProduct(theta.template segment<kDof>(0)) + cou.cwiseProduct(theta.template segment<kDof>(kDof)) +
           sti.cwiseProduct(theta.template segment<kDof>(2 * kDof));
  }
  /// W^T v.
  Vec18<S> transpose_times(const Vec6<S>& v) const {
    Vec18<S> r;
    r << vis.cwiseProduct(v), cou.cwiseProduct(v), sti.cwiseProduct(v);
    return r;
  }
};

template <class S>
RegressorDiagonals<S> friction_regressor_diagonals(const Vec6<S>& qd, const Vec6<S>& dec) {
  RegressorDiagonals<S> w;
  for (int i = 0; i < kDof; ++i) {
    const S s = math::sgn(qd(i));
    w.vis(i) = qd(i);
    w.cou(i) = s;
    w.sti(i) = s * math::exp_decay(-dec(i) * qd(i) * qd(i));
  }
  return w;
}

/// Regressor W_j(qd) of (19) as a dense 6x18 matrix.
template <class S>
Regressor<S> friction_regressor(const Vec6<S>& qd, const Vec6<S>& dec) {
  const RegressorDiagonals<S> w = friction_regressor_diagonals(qd, dec);
  Regressor<S> W = Regressor<S>::Zero();
  for (int i = 0; i < kDof; ++i) {
    W(i, i) = w.vis(i);
    W(i, kDof + i) = w.cou(i);
    W(i, 2 * kDof + i) = w.sti(i);
  }
  return W;
}

}  // namespace osc
