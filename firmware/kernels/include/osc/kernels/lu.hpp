// The 6x6 Jacobian of any arm factored as P J = L U (partial pivoting), with its reciprocal condition
// number in the 1-norm.
//
// What: PivotedLuJacobianFactor has the interface of SphericalWristJacobianFactor (opspace.hpp):
// compute(J), solve(b) = J^{-1} b, solve_transpose(b) = J^{-T} b and rcond, so that the kernels take
// either. Why: the block factor needs J block lower-triangular, which holds only for an arm with a
// spherical wrist at the operational point (has_spherical_wrist(), osc/robots/arm.hpp); an arm without
// one (a UR5e: offset wrist axes) has a full J, and this factor is its Jacobian factor. An arm with a
// spherical wrist keeps the block factor: two 3x3 inverses are cheaper and its rcond exact.
//
// How: Crout's ordering of Gaussian elimination (Golub & Van Loan 3.2.9): column k of L and row k of
// U each entry as one dot product of the entries already computed, so that fixed point rounds every
// entry once (one-rounding dot products, osc/math/q_eigen.hpp); the pivot of column k is its largest
// entry in magnitude on or below the diagonal (|L| <= 1, the growth of U at most 2^5 |J|). The
// reciprocals of the pivots are kept: a factorisation divides 6 times (and once more for rcond), a
// solve never. A pivot below min_pivot() (in float and double the least normal number, in fixed point
// the least whose reciprocal is half the range) counts as singular: its reciprocal
// is stored as 0, nothing divides by it, the solves stay finite and rcond is 0. A J with a non-finite
// entry is singular too (rcond 0, every solve 0).
//
// rcond = 1 / (||J||_1 ||J^{-1}||_1), exact (like the block factor's), not estimated: ||J^{-1}||_1 is
// the largest 1-norm of the six columns U^{-1} L^{-1} P e_j, each reduced to its norm as the factors'
// substitutions produce it, and kept (inverse, for the residual monitor's velocity noise, which needs
// J^{-1}'s columns). The control step takes them by halves, three columns a step, the other three
// one period old (compute(J, half); rcond_by_halves()), while the pivots' order holds. At n = 6
// that is six back substitutions and six sparse forward ones, 160 multiply-adds at a fixed cost:
// about what Hager's estimator (Higham's form, LAPACK's xLACN2) spends, 4 to 11 solves of 36 (4.7
// on average), and that estimate falls short
// of ||J^{-1}||_1 by more than a factor 3 on about 0.2 % of random 6x6 matrices (by up to 10;
// test_lu.cpp measures it). In fixed point a norm beyond the range (rcond below about
// 1 / (4096 ||J||_1)) gives rcond 0, and its saturations are not the caller's: the flags are taken
// and restored around it.
//
// Cost (M4F, float): the factorisation 70 multiply-adds and 6 divisions, rcond 160 multiply-adds
// and one division; each solve 30 multiply-adds and 6 products, no division. Measured by the kernels
// image (tests/boards/mps2/kernels_image.cpp, "PivotedLuJacobianFactor::compute").
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "osc/kernels/model.hpp"

namespace osc {

/// P J = L U of a 6x6 Jacobian with partial pivoting, and its 1-norm reciprocal condition number.
/// For arms without a spherical wrist (SphericalWristJacobianFactor, opspace.hpp, for those with one).
template <class S>
struct PivotedLuJacobianFactor {
  static constexpr int kN = kDof;

  Mat6<S> lu;                           // strictly lower part: L (unit diagonal, not stored); the rest: U
  Vec6<S> u_inv;                        // 1 / U(k, k); 0 where the pivot is singular
  std::array<std::uint8_t, kN> perm{};  // row k of L U is row perm[k] of J
  Mat6<S> inverse = Mat6<S>::Zero();    // J^{-1}, column by column as rcond's pass computes them
  // rcond by halves (compute(J, half)):
  S half_norm[2] = {S(0), S(0)};  // the largest 1-norm of each half's columns, as last computed
  bool halves_known = false;      // both half_norm from finite, regular factors
  bool by_halves = false;         // compute(J) by halves (rcond_by_halves())
  int next_half = 0;              // ... the half the next compute(J) takes
  /// Reciprocal condition number (1-norm, exact: see the file comment); 0 when J is singular or
  /// not finite. Callers refuse to act when it falls below their threshold.
  S rcond = S(0);

  /// rcond exact, or by halves in turn once rcond_by_halves() set the control step's mode.
  void compute(const Mat6<S>& J) {
    if (!by_halves) return compute(J, -1);
    compute(J, next_half);
    next_half ^= 1;
  }
  /// The control step's mode (the controller's observer start): compute(J) takes rcond by halves in turn,
  /// from the next call on, which is exact (nothing known yet).
  void rcond_by_halves() {
    by_halves = true;
    halves_known = false;
    next_half = 0;
  }

  /// As compute(J), with ||J^{-1}||_1 by halves (the control step's: opspace_update): the largest
  /// 1-norm of half `half` (0 or 1, kHalf) of J^{-1}'s columns from this J, of the other half the one
  /// the call before found (so at most one period old, as the alternate model rate's terms; a control
  /// step takes the halves in turn). half = -1, or the other half not known (the first call, or one
  /// after a singular J): both, exactly. Each half is about 60 of the 160 multiply-adds.
  void compute(const Mat6<S>& J, int half) {
    const Vec6<S> col_sums = J.cwiseAbs().colwise().sum().transpose();
    if (!math::isfinite(S(col_sums.sum()))) {  // a NaN or an infinity in J (float and double)
      set_singular();
      return;
    }
    lu = J;
    const std::array<std::uint8_t, kN> perm_before = perm;
    if (!factor()) {
      rcond = S(0);
      halves_known = false;
      return;
    }
    // A half is its columns K of L U, that is J^{-1}'s columns perm[K]: the same ones only while the
    // pivots' order holds.
    rcond = reciprocal_condition(col_sums.maxCoeff(), halves_known && perm == perm_before ? half : -1);
  }

  /// Column a of J^{-1}, as the last compute() found it (by halves: at most one period old); a view of the factor's.
  auto inverse_column(int a) const { return inverse.col(a); }

  /// J^{-1} b: L y = P b, then U x = y.
  Vec6<S> solve(const Vec6In<S>& b) const {
    Vec6<S> x;
    for_each_index<kN>([&]<int I>(std::integral_constant<int, I>) {
      if constexpr (I == 0)
        x(0) = b(perm[0]);
      else
        x(I) = b(perm[I]) - lu.row(I).template head<I>().dot(x.template head<I>());
    });
    back_substitute(x);
    return x;
  }

  /// J^{-T} b: U^T z = b, then L^T w = z, x = P^T w.
  Vec6<S> solve_transpose(const Vec6In<S>& b) const {
    Vec6<S> z;
    for_each_index<kN>([&]<int I>(std::integral_constant<int, I>) {
      if constexpr (I == 0)
        z(0) = b(0) * u_inv(0);
      else
        z(I) = (b(I) - lu.col(I).template head<I>().dot(z.template head<I>())) * u_inv(I);
    });
    for_each_index<kN>([&]<int K>(std::integral_constant<int, K>) {
      constexpr int I = kN - 1 - K;  // rows 5 .. 0, each with the K entries of L below its diagonal
      if constexpr (K > 0) z(I) -= lu.col(I).template tail<K>().dot(z.template tail<K>());
    });
    Vec6<S> x;
    for (int i = 0; i < kN; ++i) x(perm[i]) = z(i);
    return x;
  }

  /// Whether det J = sign(P) prod U(k, k) is positive (false when J is singular): the side of a
  /// singularity J is on (a path that crosses one turns it).
  bool det_positive() const {
    bool positive = true;
    for (int k = 0; k < kN; ++k) {
      if (u_inv(k) == S(0)) return false;
      if (u_inv(k) < S(0)) positive = !positive;
    }
    // The permutation's sign: each cycle of length m is m - 1 transpositions.
    std::array<bool, kN> seen{};
    for (int k = 0; k < kN; ++k) {
      if (seen[k]) continue;
      for (int i = k; !seen[i]; i = perm[i]) {
        seen[i] = true;
        if (i != k) positive = !positive;
      }
    }
    return positive;
  }

  /// ||J^{-1}||_1 from the factors, exactly: the largest 1-norm of a column of J^{-1} = U^{-1} L^{-1} P.
  /// Column perm[K] is U^{-1} y with L y = e_K, whose first K entries are 0 (the forward substitution
  /// starts at K); each column is reduced to its 1-norm as it is computed and kept in `inverse`.
  /// Half (0 or 1): the largest of the columns K of that half (kHalf) only; -1: of all.
  template <int Half = -1>
  S inverse_norm1() {
    S largest = S(0);
    for_each_index<kN>([&]<int K>(std::integral_constant<int, K>) {
      if constexpr (Half >= 0 && kHalf[K] != Half) return;
      Vec6<S> x = Vec6<S>::Unit(K);
      for_each_index<kN>([&]<int I>(std::integral_constant<int, I>) {
        if constexpr (I > K) x(I) = -lu.row(I).template segment<I - K>(K).dot(x.template segment<I - K>(K));
      });
      back_substitute(x);
      inverse.col(perm[K]) = x;
      const S n = norm1(x);
      if (n > largest) largest = n;
    });
    return largest;
  }

 private:
  /// The least pivot in magnitude that is not singular: the least normal number in float and double
  /// (its reciprocal is finite), in fixed point the one whose reciprocal is half the range.
  static constexpr S min_pivot() {
    if constexpr (fixed::is_q_v<S>) {
      constexpr int kShift = 2 * S::kFractionBits - 30;  // 2^(1 - integer bits) in LSB
      return S::from_raw(kShift > 0 ? std::int32_t{1} << kShift : 1);
    } else {
      return std::numeric_limits<S>::min();
    }
  }

  /// Factors lu (holding J) in place; false when a pivot is singular (the factorisation completes,
  /// with that pivot's reciprocal and multipliers 0).
  bool factor() {
    bool regular = true;
    for (int i = 0; i < kN; ++i) perm[i] = static_cast<std::uint8_t>(i);
    for_each_index<kN>([&]<int K>(std::integral_constant<int, K>) {
      // Column K of L U on and below the diagonal, each entry one dot product.
      if constexpr (K > 0)
        for (int i = K; i < kN; ++i) lu(i, K) -= lu.row(i).template head<K>().dot(lu.col(K).template head<K>());
      int p = K;
      S big = math::abs(lu(K, K));
      for (int i = K + 1; i < kN; ++i) {
        const S a = math::abs(lu(i, K));
        if (a > big) big = a, p = i;
      }
      if (p != K) {
        lu.row(K).swap(lu.row(p));
        std::swap(perm[K], perm[p]);
      }
      const bool ok = big >= min_pivot();
      regular = regular && ok;
      const S inv = ok ? S(S(1) / lu(K, K)) : S(0);
      u_inv(K) = inv;
      for (int i = K + 1; i < kN; ++i) lu(i, K) *= inv;
      // Row K of U right of the diagonal.
      if constexpr (K > 0)
        for (int j = K + 1; j < kN; ++j) lu(K, j) -= lu.row(K).template head<K>().dot(lu.col(j).template head<K>());
    });
    return regular;
  }

  /// U x = y in place (the solve's back substitution, by the pivots' reciprocals).
  void back_substitute(Vec6<S>& x) const {
    for_each_index<kN>([&]<int K>(std::integral_constant<int, K>) {
      constexpr int I = kN - 1 - K;  // rows 5 .. 0, each with the K entries of U right of its diagonal
      if constexpr (K == 0)
        x(I) = x(I) * u_inv(I);
      else
        x(I) = (x(I) - lu.row(I).template tail<K>().dot(x.template tail<K>())) * u_inv(I);
    });
  }

  /// 1 / (||J||_1 ||J^{-1}||_1), ||J^{-1}||_1 by half `half` (inverse_norm1<half>; -1: both); 0 when
  /// ||J^{-1}||_1 is not finite (float, double) or saturates (fixed point, whose flags it leaves as it
  /// found them).
  S reciprocal_condition(S norm_j, int half) {
    const std::uint32_t saved = math::take_arithmetic_flags<S>();
    if (half != 1) half_norm[0] = inverse_norm1<0>();
    if (half != 0) half_norm[1] = inverse_norm1<1>();
    halves_known = !math::take_arithmetic_fault<S>();
    const S denom = norm_j * (half_norm[0] > half_norm[1] ? half_norm[0] : half_norm[1]);  // >= 1: ||J J^{-1}||_1
    const bool saturated = math::take_arithmetic_fault<S>();
    math::restore_arithmetic_flags<S>(saved);
    if (!halves_known || saturated || !math::isfinite(denom) || !(denom >= lit<S>(0.5))) {
      halves_known = false;
      return S(0);
    }
    return S(1) / denom;
  }

  void set_singular() {
    lu.setZero();
    u_inv.setZero();
    for (int i = 0; i < kN; ++i) perm[i] = static_cast<std::uint8_t>(i);
    rcond = S(0);
    halves_known = false;
  }

  /// The half of J^{-1}'s columns K is in: the forward substitutions' multiply-adds (15, 10, 6, 3, 1,
  /// 0 for K = 0..5) split 18 and 17.
  static constexpr std::array<std::uint8_t, kN> kHalf = {0, 1, 1, 0, 1, 0};

  static S norm1(const Vec6<S>& v) { return v.cwiseAbs().sum(); }
};

}  // namespace osc
