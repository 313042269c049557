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

constexpr double kSqrt2 = 1.4142135623730951;

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
// clang-format off
constexpr int kLoopTerms[6][kTerms][3] = {
    {{1, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0},  // q0 = a b sigma
     {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}},
    {{0, -2, 0}, {2, 0, 0}, {2, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0},  // q1
     {2, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}},
    {{-2, 0, 2}, {-2, -4, 0}, {-2, -4, 0}, {4, 0, 0}, {4, 0, 0}, {0, 0, 0},  // q2
     {-2, -4, 0}, {4, 0, 0}, {4, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}},
    {{0, 4, -2}, {-2, 4, 4}, {-2, 4, 4}, {-8, -8, 0}, {0, -8, 0}, {8, 0, 0},  // q3
     {-2, 4, 4}, {0, -8, 0}, {-8, -8, 0}, {8, 0, 0}, {8, 0, 0}, {0, 0, 0}},
    {{1, 0, -2}, {2, 4, -8}, {2, 4, -8}, {-4, 0, 8}, {-4, 0, 8}, {0, 0, 0},  // q4
     {2, 4, -8}, {-4, 0, 8}, {-4, 0, 8}, {0, 0, 0}, {0, 0, 0}, {16, 0, 0}},
    {{0, -2, 2}, {0, -4, 4}, {0, -4, 4}, {8, 8, -8}, {0, 8, -8}, {-8, 0, 0},  // q5
     {0, -4, 4}, {0, 8, -8}, {8, 8, -8}, {-8, 0, 0}, {-8, 0, 0}, {16, 0, 0}},
};
// clang-format on

/// P_kt(phi): term t's weight in q_k.
constexpr double loop_weight(int k, int t, double phi) {
  const int* p = kLoopTerms[k][t];
  return p[0] + phi * (p[1] + phi * p[2]);
}

/// q_0 ... q_5 of the axis's loop with the DAC delay phi (of dt).
inline std::array<double, 6> polynomial(const Axis& x, double phi) {
  const double t[kTerms] = {x.a * x.b * x.sigma, x.a * x.b, x.a * x.kappa * x.sigma, x.a * x.kappa, x.a * x.sigma, x.a,
                            x.b * x.sigma,       x.b,       x.kappa * x.sigma,       x.kappa,       x.sigma,       1.0};
  std::array<double, 6> q{};
  for (int k = 0; k < 6; ++k) {
    double v = 0;
    for (int j = 0; j < kTerms; ++j) v += t[j] * loop_weight(k, j, phi);
    q[static_cast<std::size_t>(k)] = v;
  }
  return q;
}

/// Whether every root of q_5 s^5 + ... + q_0 lies in the open left half plane: the first column of
/// the Routh array, q_5, q_4, r_1, r_2, r_3, q_0, all positive.
template <class T>
bool hurwitz_stable(const std::array<T, 6>& q) {
  for (const T c : q)
    if (!(c > 0)) return false;
  const T r1 = q[3] - q[5] * q[2] / q[4];  // the s^3 row: r1, r1b
  const T r1b = q[1] - q[5] * q[0] / q[4];
  if (!(r1 > 0)) return false;
  const T r2 = q[2] - q[4] * r1b / r1;  // the s^2 row: r2, q0
  if (!(r2 > 0)) return false;
  const T r3 = r1b - r1 * q[0] / r2;  // the s^1 row
  return r3 > 0;
}

/// Whether one axis's loop is stable at the delay phi (double: the reference the tests use).
inline bool axis_stable(const Axis& x, double phi) { return hurwitz_stable(polynomial(x, phi)); }

/// The check's own arithmetic: float, which the boards' FPUs compute in hardware. The check runs in
/// a board's main loop when a parameter frame comes, and a 25 MHz part's main loop must answer
/// within a few milliseconds (the PIL firmware's watchdog): in software double it would take
/// several. The bilinear form needs no more (no cancellation); the tests hold float's judgement to
/// double's and to the coupled loop's.
using Real = float;

/// kLoopTerms at the DAC delay the check assumes (params::kActuationDelay).
struct LoopWeights {
  Real w[6][kTerms];
};
constexpr LoopWeights loop_weights(double phi) {
  LoopWeights l{};
  for (int k = 0; k < 6; ++k)
    for (int t = 0; t < kTerms; ++t) l.w[k][t] = static_cast<Real>(loop_weight(k, t, phi));
  return l;
}
inline constexpr LoopWeights kLoopWeights = loop_weights(params::kActuationDelay / params::kDt);

/// One axis at that delay as a function of the fraction f of its inverse mass bound:
/// q_k(f) = A_k + f (B_k + f C_k) (the terms without a or b, with one of them, with both).
struct AxisForm {
  Real A[6], B[6], C[6];
};
inline AxisForm axis_form(Real kappa, Real sigma, Real a, Real b) {
  // kLoopTerms' order: 0 a b sigma, 1 a b, 2 a kappa sigma, 3 a kappa, 4 a sigma, 5 a, 6 b sigma,
  // 7 b, 8 kappa sigma, 9 kappa, 10 sigma, 11 1.
  AxisForm x{};
  const Real ks = kappa * sigma;
  for (int k = 0; k < 6; ++k) {
    const Real* w = kLoopWeights.w[k];
    x.A[k] = w[8] * ks + w[9] * kappa + w[10] * sigma + w[11];
    x.B[k] = a * (w[2] * ks + w[3] * kappa + w[4] * sigma + w[5]) + b * (w[6] * sigma + w[7]);
    x.C[k] = a * b * (w[0] * sigma + w[1]);
  }
  return x;
}
inline bool form_stable(const AxisForm& x, Real f) {
  std::array<Real, 6> q;
  for (int k = 0; k < 6; ++k) q[static_cast<std::size_t>(k)] = x.A[k] + f * (x.B[k] + f * x.C[k]);
  return hurwitz_stable(q);
}

/// The fractions of an axis's bound at which its loop is judged: 1, 1/2, ..., 1/256.
constexpr int kMassSteps = 9;

/// Each axis's loop at its bound: kappa, sigma, a and b (the last two at its row's bound of lambda).
struct LoopBounds {
  Real kappa[kDof], sigma[kDof], a[kDof], b[kDof];
};

/// Whether an axis's loop is stable at its bound and every fraction of it.
inline bool form_stable_below(const AxisForm& x) {
  Real f = 1;
  for (int m = 0; m < kMassSteps; ++m, f *= Real(0.5))
    if (!form_stable(x, f)) return false;
  return true;
}

/// Whether the loop of every axis is stable with the gains scaled by s, every inverse mass from
/// each axis's bound down.
inline bool stable(const LoopBounds& l, Real s = 1) {
  for (int i = 0; i < kDof; ++i)
    if (!form_stable_below(axis_form(s * l.kappa[i], s * l.sigma[i], s * l.a[i], s * l.b[i]))) return false;
  return true;
}

/// Each axis's row bounds (the header's comment) at Lambda^-1: of lambda (k_s + k_nd) and of
/// lambda k_i, Gershgorin over the gains' square roots (sqrt(g_i g_j) = sqrt(g_i) sqrt(g_j)). The
/// observer's margin reads the second too.
struct RowBounds {
  Vec6<double> g, ki;
};
inline RowBounds row_bounds(const Gains<double>& g, const Mat6<double>& lambda_inv) {
  Vec6<double> rg, rk;  // the square roots of k_s + k_nd and of k_i
  for (int i = 0; i < kDof; ++i) rg(i) = std::sqrt(g.ks(i) + g.knd(i)), rk(i) = std::sqrt(g.ki(i));
  RowBounds r;
  for (int i = 0; i < kDof; ++i) {
    double a = 0, b = 0;
    for (int j = 0; j < kDof; ++j) {
      const double l = std::fabs(lambda_inv(i, j));
      a += l * rg(j);
      b += l * rk(j);
    }
    r.g(i) = a * rg(i);
    r.ki(i) = b * rk(i);
  }
  return r;
}

/// The loop of each axis at its row bounds, in the check's arithmetic: a = bound dt, b = bound dt^2.
inline LoopBounds loop_bounds(const Gains<double>& g, const RowBounds& r) {
  LoopBounds l;
  for (int i = 0; i < kDof; ++i) {
    l.kappa[i] = static_cast<Real>(g.k(i) * g.dt), l.sigma[i] = static_cast<Real>(g.ks(i) * g.dt);
    l.a[i] = static_cast<Real>(r.g(i) * g.dt), l.b[i] = static_cast<Real>(r.ki(i) * g.dt * g.dt);
  }
  return l;
}

/// The loop's test at the samples of a path (osc/control/path_check.hpp): each axis at its row bounds
/// of Lambda^-1 there (row_bounds, loop_bounds) times `scale`, the margin the path keeps on the inverse
/// masses (not on the gains: a larger k can steady an axis that a lighter mass would not). The gains'
/// terms once per check; per sample one row sum per axis and stable(). The square roots carry dt and
/// the scale: a_i = w_i sum_j |Lambda^-1_ij| w_j with w = sqrt((k_s + k_nd) dt scale), b_i the same
/// with v = sqrt(k_i scale) dt.
struct PathLoop {
  Real kappa[kDof], sigma[kDof], w[kDof], v[kDof];
};
inline PathLoop path_loop(const Gains<double>& g, double scale) {
  PathLoop p;
  for (int i = 0; i < kDof; ++i) {
    p.kappa[i] = static_cast<Real>(g.k(i) * g.dt), p.sigma[i] = static_cast<Real>(g.ks(i) * g.dt);
    p.w[i] = static_cast<Real>(std::sqrt((g.ks(i) + g.knd(i)) * g.dt * scale));
    p.v[i] = static_cast<Real>(std::sqrt(g.ki(i) * scale) * g.dt);
  }
  return p;
}
/// Each axis's loop at Lambda^-1 (any scalar) times path_loop's scale: its terms at its row bounds.
template <class S>
LoopBounds path_bounds(const PathLoop& p, const Mat6<S>& lambda_inv) {
  LoopBounds l;
  for (int i = 0; i < kDof; ++i) {
    Real a = 0, b = 0;
    for (int j = 0; j < kDof; ++j) {
      const Real m = std::fabs(static_cast<Real>(lambda_inv(i, j)));
      a += m * p.w[j];
      b += m * p.v[j];
    }
    l.kappa[i] = p.kappa[i], l.sigma[i] = p.sigma[i], l.a[i] = a * p.w[i], l.b[i] = b * p.v[i];
  }
  return l;
}
/// Whether axis i's loop is stable at its bound and every fraction of it (stable()'s test of one axis).
inline bool axis_stable(const LoopBounds& l, int i) {
  return form_stable_below(axis_form(l.kappa[i], l.sigma[i], l.a[i], l.b[i]));
}
/// Whether the loop of every axis is stable at Lambda^-1 (any scalar) times path_loop's scale.
template <class S>
bool path_loop_stable(const PathLoop& p, const Mat6<S>& lambda_inv) {
  return stable(path_bounds(p, lambda_inv));
}

/// The steps of the loop's gain margin: factors of sqrt 2, at most kMarginSteps of them each way.
constexpr int kMarginSteps = 4;

/// The loop's gain margin: the factor by which the gains k, k_s, k_nd, k_i together may grow before
/// the loop is unstable, in steps of sqrt 2 (a lower bound: the loop is stable at it, not at the
/// next step), up to 4. At least 1 exactly when the loop is stable as they are. Below 1 it is not,
/// and the figure is the first step down (to 1/4) at which it would be (0: none; a low k loses the
/// loop too, so shrinking every gain is not always the way back). At most kMarginSteps + 1
/// evaluations of stable(), each a few thousand float operations.
inline double gain_margin(const LoopBounds& l) {
  const bool now = stable(l);
  const Real root2 = static_cast<Real>(kSqrt2);
  Real s = 1;
  for (int n = 0; n < kMarginSteps; ++n) {
    const Real next = now ? s * root2 : s / root2;
    const bool ok = stable(l, next);
    if (now && !ok) return s;
    if (!now && ok) return next;
    s = next;
  }
  return now ? s : 0.0;
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

  /// Whether gains of these margins may run: the observer's margin above 1, the loop's at least 1.
  bool observer_stable() const { return observer > 1; }
  bool loop_stable() const { return loop >= 1; }
};

/// Lambda^-1 = J A^-1 J^T at a pose, from the controller's A and analytic Jacobian (a parameter set's
/// check in double, the path check in its scalar), by the kernels' L D L^T solves column by column
/// (Eigen's decompositions would link the heap in).
template <class S>
Mat6<S> lambda_inverse(const Mat6<S>& A, const Mat6<S>& Ja) {
  LdltFactor<S, kDof> ldlt;
  ldlt.compute(A);
  Mat6<S> X;  // A^-1 J^T
  for (int k = 0; k < kDof; ++k) X.col(k) = ldlt.solve(Vec6<S>(Ja.row(k).transpose()));
  return Ja.lazyProduct(X);
}

inline GainMargins gain_margins(const Gains<double>& g, const Mat6<double>& lambda_inv) {
  GainMargins m;
  const loop::RowBounds rows = loop::row_bounds(g, lambda_inv);
  for (int i = 0; i < kDof; ++i)
    if (rows.ki(i) > m.b_max) m.b_max = rows.ki(i);
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
  m.loop = loop::gain_margin(loop::loop_bounds(g, rows));
  return m;
}

}  // namespace osc
