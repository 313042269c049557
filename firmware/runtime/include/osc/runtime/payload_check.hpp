// What a residual on a still arm says of the load at its flange (docs/safety.md, "A payload the model has
// wrong"): the residual monitor's finding in the first params::kPayloadCheckTicks after an enable is named
// payload_mismatch, not encoder_stuck or collision, when the residual is the weight of a point mass at the
// flange (ResidualMonitor::decide, osc/runtime/residual_travel.hpp).
#pragma once

#include <cmath>

#include "osc/control/params.hpp"
#include "osc/kernels/model.hpp"
#include "osc/math/scalar.hpp"
#include "osc/robot.hpp"

namespace osc {

/// The weight that best explains a residual r = A q^dd + c + g + tau_f^ - tau at rest: what the model holds up
/// beyond the arm's load, a vertical force F at frame 6's origin with a horizontal moment N (its centre of mass off
/// that origin), tau = J_v^T F z + J_w^T N. A payload the model carries and the arm does not gives r = g_payload(q):
/// mass > 0; one on the arm that the model lacks, mass < 0.
template <class S>
struct FlangeWeight {
  S mass = S(0);    // F / g [kg]
  S offset = S(0);  // |N| / |F|: the centre of mass's horizontal distance from frame 6's origin [m]
  S misfit = S(1);  // |r - fit|^2 / |r|^2: the share of the residual no weight explains (1: none fitted)
  S spread = S(0);  // 1 - max r_i^2 / |r|^2: the share of the residual off its largest joint
  bool fitted = false;
};

/// The farthest the flange's origin is from joint i's axis, at any pose [m]: the arm's placements from joint i on
/// (the first across the axis alone, its offset along it taken out), each at its length. With the rated reach of a
/// payload's centre of mass off the flange (sqrt(3) com_reach), joint i's lever on a weight at the flange.
inline double flange_lever(int i) {
  const double* own = robot::kArm.links[i].placement.p;
  double lever = std::sqrt(own[0] * own[0] + own[1] * own[1]);
  for (int k = i + 1; k < kDof; ++k) {
    const double* p = robot::kArm.links[k].placement.p;
    lever += std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  }
  return lever + 1.7320508 * robot::kPayloadRating.com_reach;
}

/// The most a payload of `mass` [kg] can load joint i at rest [N m]: its weight at flange_lever(i). A payload not
/// yet identified, up to that mass either way (the parameter payload_allowance), adds it to the residual monitor's
/// floor of the model's error and the share of it a motion can change to its change channel
/// (ResidualMonitor::set_allowance, allowance_change; docs/safety.md, "A payload not yet identified").
inline double allowance_torque(double mass, int i) { return mass * robot::kArm.gravity * flange_lever(i); }

/// r scaled to a largest |r_i| of 1, into u: returns that largest |r_i|, or 0 where r is all but 0 (every |r_i|
/// within 1e-3 N m; u then untouched). The first pass of flange_weight and residual_spread: no product of theirs
/// leaves the fixed-point range.
template <class S>
S scaled_residual(const Vec6<S>& r, Vec6<S>& u) {
  S scale = S(0);
  for (int i = 0; i < kDof; ++i) scale = math::abs(r(i)) > scale ? math::abs(r(i)) : scale;
  if (scale <= lit<S>(1e-3)) return S(0);
  u = r / scale;
  return scale;
}

/// The share of r's square off its largest joint (FlangeWeight::spread); 0 where r is all but 0.
template <class S>
S residual_spread(const Vec6<S>& r) {
  Vec6<S> u;
  if (scaled_residual(r, u) == S(0)) return S(0);
  S all = S(0);
  for (int i = 0; i < kDof; ++i) all += u(i) * u(i);
  return S(1) - S(1) / all;  // the largest |u_i| is 1
}

/// The least-squares weight of r (J: the geometric Jacobian [v; w] of frame 6's origin, base frame, gravity
/// along -z). Its three columns are J's rows 2 (the origin's vertical rate), 3 and 4 (the horizontal components
/// of the joints' axes): a 3x3 system by its cofactors, on r scaled to a largest |r_i| of 1, so that no product
/// leaves the fixed-point range. Not fitted (misfit 1): r = 0, or columns that cannot be told apart (a
/// singular pose).
template <class S>
FlangeWeight<S> flange_weight(const Mat6<S>& J, const Vec6<S>& r) {
  FlangeWeight<S> w;
  Vec6<S> u;
  const S scale = scaled_residual(r, u);
  if (scale == S(0)) return w;
  S m[3][3], b[3];
  for (int a = 0; a < 3; ++a) {
    b[a] = J.row(2 + a).dot(u);
    for (int c = a; c < 3; ++c) m[a][c] = m[c][a] = J.row(2 + a).dot(J.row(2 + c));
  }
  // The adjugate of m (row a, column c: the cofactor of m[c][a]; cyclic indices carry the signs) and its
  // determinant.
  S adj[3][3];
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c) {
      const int c1 = (c + 1) % 3, c2 = (c + 2) % 3, a1 = (a + 1) % 3, a2 = (a + 2) % 3;
      adj[a][c] = m[c1][a1] * m[c2][a2] - m[c1][a2] * m[c2][a1];
    }
  const S det = m[0][0] * adj[0][0] + m[0][1] * adj[1][0] + m[0][2] * adj[2][0];
  const S trace = m[0][0] + m[1][1] + m[2][2];
  if (det <= lit<S>(params::kPayloadFitConditioning) * trace * trace * trace) return w;
  S x[3];
  for (int a = 0; a < 3; ++a) x[a] = (adj[a][0] * b[0] + adj[a][1] * b[1] + adj[a][2] * b[2]) / det;
  S miss = S(0), all = S(0);
  for (int i = 0; i < kDof; ++i) {
    const S e = u(i) - (J(2, i) * x[0] + J(3, i) * x[1] + J(4, i) * x[2]);
    miss += e * e;
    all += u(i) * u(i);
  }
  w.misfit = miss / all;
  w.spread = S(1) - S(1) / all;  // residual_spread(r): the largest |u_i| is 1
  w.mass = x[0] * scale / lit<S>(robot::kArm.gravity);
  const S moment = math::sqrt(x[1] * x[1] + x[2] * x[2]), force = math::abs(x[0]);
  w.offset = force > lit<S>(1e-3) * moment ? moment / force : lit<S>(1000);
  w.fitted = true;
  return w;
}

/// Whether w is a payload the model has wrong: the residual all but wholly a weight (misfit within
/// params::kPayloadFitMisfit) and not one joint's (at least params::kPayloadSpread of its square off its largest
/// joint: at a pose where a weight loads one joint all but alone, as J2 with the wrist centre above the elbow, it
/// cannot be told from that joint's drive or encoder), of at least params::kPayloadMismatchMass and at most twice the
/// arm's rating either way, its centre of mass within the rating's reach (each coordinate within +-com_reach of frame
/// 6's origin: at most sqrt(3) com_reach from it horizontally).
template <class S>
bool payload_mismatch(const FlangeWeight<S>& w) {
  static constexpr S kReach = lit<S>(1.7320508 * robot::kPayloadRating.com_reach);
  const S m = math::abs(w.mass);
  return w.fitted && w.misfit <= lit<S>(params::kPayloadFitMisfit) && w.spread >= lit<S>(params::kPayloadSpread) &&
         m >= lit<S>(params::kPayloadMismatchMass) && m <= lit<S>(2 * robot::kPayloadRating.mass) && w.offset <= kReach;
}

}  // namespace osc
