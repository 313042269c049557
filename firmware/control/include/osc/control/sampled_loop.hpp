// The gains' discrete-time feasibility at the sample rate (issue 53, defect 4): whether the observer
// and the controller, sampled at dt and driving the arm, form a stable loop. A set of a gain that
// fails it is refused (osc/runtime/parameters.hpp); a gain that passes it runs.
//
// One operational axis, linearised at rest (the model exact, the friction estimate held, J and
// Lambda^-1 constant over a sample), with x_d fixed and the observer's and controller's own
// discretisation (observer.hpp, controller.hpp). Let lambda be the axis's inverse mass (an
// eigenvalue of Lambda^-1) and, in the sample's units,
//   kappa = k dt,  sigma = k_s dt,  a = lambda (k_s + k_nd) dt,  b = lambda k_i dt^2.
// Per sample n (xdh = y + k x~, x~ = x - x^, e = -x, all forces' model terms cancelling):
//   dt^2 u_cmd = -sigma dt xdh - a (sigma x + dt xdh)        the force (32), (35) over Lambda
//   dt^2 u     = dt^2 u_cmd - b x~                             the arm's acceleration: (32)'s -k_i x~
//   y'  = y + dt u_cmd,  x^' = x^ + dt (y' + k x~)             the observer update (22)
// The DAC takes u a delay phi dt after the sample (params::kActuationDelay): the arm moves with the
// previous sample's u for phi dt, then with u. The state (x, v dt, x^, y dt, u_prev dt^2) then maps
// linearly. Its eigenvalues z lie inside the unit circle when the roots s = (z - 1) / (z + 1) of
// q(s) = (1 - s)^5 p((1 + s) / (1 - s)), p the map's characteristic polynomial, lie in the left half
// plane (Routh-Hurwitz). q's coefficients are polynomials in the gains' terms without cancellation:
//   q_k = sum over the terms t of (a b sigma, a b, a kappa sigma, a kappa, a sigma, a, b sigma, b,
//         kappa sigma, kappa, sigma, 1) of t * P_kt(phi),
// P_kt the integer polynomials of kLoopTerms below (derived symbolically from the map above and
// checked against the map's eigenvalues in tests/firmware/control/test_sampled_loop.cpp). So slow
// poles (small gains put z within 1e-6 of 1) are judged as exactly as fast ones, which the
// Schur-Cohn-Jury recursion on p itself is not.
//
// The axes couple through Lambda^-1 and the gains differ per axis, so no exact per-axis split
// exists. Axis i is judged over every inverse mass it can see: its terms a and b at the bound of
// their row (Gershgorin, with the gains' square roots: a_i = dt sum_j |Lambda^-1_ij| sqrt(g_i g_j),
// g = k_s + k_nd; b_i the same with k_i and dt^2), and at that bound times 2^-1 ... 2^-8 (lighter
// axes; below 2^-8 the loop's poles approach 1 from inside). The tests check the judgement against
// the full coupled 30-state linearisation, and an accepted gain against the simulated arm.
//
// Header-only, allocation-free, in double; for a parameter set, outside the control interrupt.
#pragma once

#include <array>
#include <cmath>

#include "osc/control/gains.hpp"
#include "osc/kernels/model.hpp"
#include "osc/kernels/opspace.hpp"

namespace osc::loop {

/// One axis of the sampled loop, in the sample time's units.
struct Axis {
  double kappa;  ///< k dt
  double sigma;  ///< k_s dt
  double a;      ///< lambda (k_s + k_nd) dt
  double b;      ///< lambda k_i dt^2
};

constexpr int kTerms = 12;
/// q_k = sum_t term_t * (P[k][t][0] + P[k][t][1] phi + P[k][t][2] phi^2), the terms in the order
/// a b sigma, a b, a kappa sigma, a kappa, a sigma, a, b sigma, b, kappa sigma, kappa, sigma, 1.
constexpr int kLoopTerms[6][kTerms][3] = {
    {{1, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0},  // q0 = a b sigma
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0}},
    {{0, -2, 0},
     {2, 0, 0},
     {2, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0},  // q1
     {2, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0}},
    {{-2, 0, 2},
     {-2, -4, 0},
     {-2, -4, 0},
     {4, 0, 0},
     {4, 0, 0},
     {0, 0, 0},  // q2
     {-2, -4, 0},
     {4, 0, 0},
     {4, 0, 0},
     {0, 0, 0},
     {0, 0, 0},
     {0, 0, 0}},
    {{0, 4, -2},
     {-2, 4, 4},
     {-2, 4, 4},
     {-8, -8, 0},
     {0, -8, 0},
     {8, 0, 0},  // q3
     {-2, 4, 4},
     {0, -8, 0},
     {-8, -8, 0},
     {8, 0, 0},
     {8, 0, 0},
     {0, 0, 0}},
    {{1, 0, -2},
     {2, 4, -8},
     {2, 4, -8},
     {-4, 0, 8},
     {-4, 0, 8},
     {0, 0, 0},  // q4
     {2, 4, -8},
     {-4, 0, 8},
     {-4, 0, 8},
     {0, 0, 0},
     {0, 0, 0},
     {16, 0, 0}},
    {{0, -2, 2},
     {0, -4, 4},
     {0, -4, 4},
     {8, 8, -8},
     {0, 8, -8},
     {-8, 0, 0},  // q5
     {0, -4, 4},
     {0, 8, -8},
     {8, 8, -8},
     {-8, 0, 0},
     {-8, 0, 0},
     {16, 0, 0}},
};

/// q_0 ... q_5 of the axis's loop with the DAC delay phi (of dt).
inline std::array<double, 6> polynomial(const Axis& x, double phi) {
  const double t[kTerms] = {x.a * x.b * x.sigma, x.a * x.b, x.a * x.kappa * x.sigma, x.a * x.kappa, x.a * x.sigma, x.a,
                            x.b * x.sigma,       x.b,       x.kappa * x.sigma,       x.kappa,       x.sigma,       1.0};
  std::array<double, 6> q{};
  for (int k = 0; k < 6; ++k) {
    double v = 0;
    for (int j = 0; j < kTerms; ++j) {
      const int* p = kLoopTerms[k][j];
      v += t[j] * (p[0] + phi * (p[1] + phi * p[2]));
    }
    q[static_cast<std::size_t>(k)] = v;
  }
  return q;
}

/// Whether every root of q_5 s^5 + ... + q_0 lies in the open left half plane: the first column of
/// the Routh array, q_5, q_4, r_1, r_2, r_3, q_0, all positive.
inline bool hurwitz_stable(const std::array<double, 6>& q) {
  for (const double c : q)
    if (!(c > 0)) return false;
  const double r1 = q[3] - q[5] * q[2] / q[4];  // the s^3 row: r1, r1b
  const double r1b = q[1] - q[5] * q[0] / q[4];
  if (!(r1 > 0)) return false;
  const double r2 = q[2] - q[4] * r1b / r1;  // the s^2 row: r2, q0
  if (!(r2 > 0)) return false;
  const double r3 = r1b - r1 * q[0] / r2;  // the s^1 row
  return r3 > 0;
}

/// Whether one axis's loop is stable at the delay phi.
inline bool axis_stable(const Axis& x, double phi) { return hurwitz_stable(polynomial(x, phi)); }

/// The fractions of an axis's bound at which its loop is judged: 1, 1/2, ..., 1/256.
constexpr int kMassSteps = 9;

/// Whether the loop of every axis is stable with the gains scaled by s, every inverse mass from
/// each axis's bound (a_max, b_max: of lambda = its row's bound) down.
inline bool stable(const Gains<double>& g, const Vec6<double>& a_max, const Vec6<double>& b_max, double phi,
                   double s = 1) {
  for (int i = 0; i < kDof; ++i)
    for (int m = 0; m < kMassSteps; ++m) {
      const double f = s * std::ldexp(1.0, -m);
      if (!axis_stable({s * g.k(i) * g.dt, s * g.ks(i) * g.dt, f * a_max(i), f * b_max(i)}, phi)) return false;
    }
  return true;
}

/// Each axis's bounds a_i and b_i (the header's comment) at Lambda^-1.
inline void axis_bounds(const Gains<double>& g, const Mat6<double>& lambda_inv, Vec6<double>& a_max,
                        Vec6<double>& b_max) {
  for (int i = 0; i < kDof; ++i) {
    double a = 0, b = 0;
    for (int j = 0; j < kDof; ++j) {
      const double l = std::fabs(lambda_inv(i, j));
      a += l * std::sqrt((g.ks(i) + g.knd(i)) * (g.ks(j) + g.knd(j)));
      b += l * std::sqrt(g.ki(i) * g.ki(j));
    }
    a_max(i) = a * g.dt;
    b_max(i) = b * g.dt * g.dt;
  }
}

/// The loop's gain margin: the factor by which the gains k, k_s, k_nd, k_i together may grow before
/// the loop is unstable, to about 1 %, within 2^-8 ... 2^8. At least 1 exactly when the loop is
/// stable as they are; below 1 it is not, and the figure is the factor below which scaling them all
/// down would restore it (0: not even at 2^-8; a low k loses the loop too, so shrinking is not always
/// the way back).
inline double gain_margin(const Gains<double>& g, const Mat6<double>& lambda_inv, double phi) {
  Vec6<double> a_max, b_max;
  axis_bounds(g, lambda_inv, a_max, b_max);
  double lo = -8, hi = 8;  // log2 of the factor
  const bool now = stable(g, a_max, b_max, phi);
  if (now ? stable(g, a_max, b_max, phi, std::exp2(hi)) : !stable(g, a_max, b_max, phi, std::exp2(lo)))
    return now ? std::exp2(hi) : 0.0;
  (now ? lo : hi) = 0;
  while (hi - lo > 0.015) {
    const double mid = (lo + hi) / 2;
    (stable(g, a_max, b_max, phi, std::exp2(mid)) ? lo : hi) = mid;
  }
  return std::exp2(lo);
}

}  // namespace osc::loop

namespace osc {

/// The observer's discrete-time stability and the paper's condition (37) for a set of gains, as
/// margins (above 1: met). From osc/control/observer.hpp: per operational axis the linearised error
/// map has determinant 1 - k dt and is stable for b dt^2 < 4 - 2 k dt, b an eigenvalue of
/// Lambda^-1 k_i. b is bounded above by the largest row sum of |K_i^1/2 Lambda^-1 K_i^1/2| (which
/// has the same eigenvalues; Gershgorin), at the pose the controller last computed:
///   observer = min_axes (4 - 2 k dt) / (b_max dt^2)   (needs k dt < 2 too: else 0).
/// (37) asks k_s > 1/k_n + zeta_e with k_n, zeta_e of the proof, not of the experiment; (33) gives
/// k_nd >= 2 k_n, so (37) can hold only if k_s > 2 / k_nd: condition37 = min_axes k_s k_nd / 2. It is
/// only sufficient (below 1 a warning, never a refusal). loop: the sampled closed loop's gain margin
/// (loop::gain_margin; above 1: stable).
struct GainMargins {
  double observer = 0;
  double b_max = 0;  ///< the bound on b [1/s^2]
  double condition37 = 0;
  double loop = 0;
};

/// Lambda^-1 = J A^-1 J^T at a pose, from the controller's A and analytic Jacobian (double), by the
/// kernels' L D L^T solves column by column (Eigen's decompositions would link the heap in).
inline Mat6<double> lambda_inverse(const Mat6<double>& A, const Mat6<double>& Ja) {
  LdltFactor<double, kDof> ldlt;
  ldlt.compute(A);
  Mat6<double> X;  // A^-1 J^T
  for (int k = 0; k < kDof; ++k) X.col(k) = ldlt.solve(Vec6<double>(Ja.row(k).transpose()));
  return Ja.lazyProduct(X);
}

inline GainMargins gain_margins(const Gains<double>& g, const Mat6<double>& lambda_inv) {
  GainMargins m;
  for (int i = 0; i < kDof; ++i) {
    double row = 0;
    for (int j = 0; j < kDof; ++j) row += std::fabs(std::sqrt(g.ki(i) * g.ki(j)) * lambda_inv(i, j));
    if (row > m.b_max) m.b_max = row;
  }
  const double dt = g.dt;
  m.observer = 1e300;
  m.condition37 = 1e300;
  for (int i = 0; i < kDof; ++i) {
    const double room = 4 - 2 * g.k(i) * dt;
    const double obs = g.k(i) * dt >= 2 || room <= 0 ? 0 : room / (m.b_max * dt * dt);
    if (obs < m.observer) m.observer = obs;
    const double c = g.ks(i) * g.knd(i) / 2;
    if (c < m.condition37) m.condition37 = c;
  }
  m.loop = loop::gain_margin(g, lambda_inv, params::kActuationDelay / g.dt);
  return m;
}

}  // namespace osc
