// Eigen's view of the fixed-point scalar Q<F> (osc/math/q.hpp): its NumTraits, and the dot
// products of Q<F> numbers rounded once (every sum of products Eigen forms).
#pragma once

#include <Eigen/Core>
#include <utility>

#include "osc/math/q.hpp"

namespace Eigen {
/// Q<F> is a real, signed, non-integer scalar to Eigen: its decompositions (LU, LLT) and condition
/// estimates run unchanged. Costs are relative to an integer add.
template <int F>
struct NumTraits<osc::fixed::Q<F>> {
  using Q = osc::fixed::Q<F>;
  using Real = Q;
  using NonInteger = Q;
  using Literal = Q;
  using Nested = Q;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 0,  // any bit pattern is a valid value; the constructor zeroes it anyway
    ReadCost = 1,
    AddCost = 2,
    MulCost = 8,
  };
  static constexpr Q epsilon() { return Q::lsb(); }
  /// The tolerance of Eigen's approximate comparisons: 2^-(F/2), about the square root of epsilon,
  /// as for float and double.
  static constexpr Q dummy_precision() { return Q::from_raw(std::int32_t{1} << ((F + 1) / 2)); }
  static constexpr Q highest() { return Q::max(); }
  static constexpr Q lowest() { return Q::min(); }
  /// No infinity nor NaN: the ends of the range stand for them (and raised kOverflow on the way).
  static constexpr Q infinity() { return Q::max(); }
  static constexpr Q quiet_NaN() { return Q::max(); }
  static constexpr int digits() { return 31; }
  static constexpr int digits10() { return (F * 30103) / 100000; }
  static constexpr int min_exponent() { return -F; }
  static constexpr int max_exponent() { return 31 - F; }
};
}  // namespace Eigen

namespace Eigen::internal {
// Dot products of Q<F> numbers with one rounding. Every sum of products that Eigen forms (a.dot(b),
// the coefficients of a fixed-size matrix product, the steps of its triangular solves and of LLT,
// squaredNorm) is a redux of scalar_sum_op over a coefficient-wise product; for Q<F> these reduxes
// accumulate the exact products in 64 bits and round once (osc::fixed::detail::ProductSum) instead
// of rounding and saturating at every product and sum. The result is the correctly rounded sum
// (when it fits), and a multiply-accumulate costs a fraction of a rounded product on a core
// without an FPU. Nothing else of Eigen changes: float and double take Eigen's own paths.
template <class Op>
struct OscQProductOp : std::false_type {};
template <int F>
struct OscQProductOp<scalar_product_op<osc::fixed::Q<F>, osc::fixed::Q<F>>> : std::true_type {};
template <int F>
struct OscQProductOp<scalar_conj_product_op<osc::fixed::Q<F>, osc::fixed::Q<F>>> : std::true_type {};

template <int F>
struct OscQDotRedux {
  /// fn(k, i, j) for every coefficient (i, j) of xpr, k counting them: unrolled with a compile-time
  /// k (std::integral_constant) at compile-time sizes (the 3- and 6-term dot products of the
  /// kernels), a loop for the run-time blocks of LLT.
  template <class Xpr, class Fn>
  [[gnu::always_inline]] static void for_each_coeff(const Xpr& xpr, Fn&& fn) {
    constexpr int R = Xpr::RowsAtCompileTime, C = Xpr::ColsAtCompileTime;
    if constexpr (R != Dynamic && C != Dynamic) {
      [&]<int... K>(std::integer_sequence<int, K...>) { (fn(std::integral_constant<int, K>{}, K % R, K / R), ...); }
      (std::make_integer_sequence<int, R * C>{});
    } else {
      int k = 0;
      for (Index j = 0; j < xpr.cols(); ++j)
        for (Index i = 0; i < xpr.rows(); ++i) fn(k++, i, j);
    }
  }
  /// sum_ij lhs(i, j) rhs(i, j) of a coefficient-wise product.
  template <class Op, class L, class R>
  static osc::fixed::Q<F> run(const CwiseBinaryOp<Op, L, R>& xpr) {
    const evaluator<L> le(xpr.lhs());
    const evaluator<R> re(xpr.rhs());
    osc::fixed::detail::ProductSum<F> s;
    for_each_coeff(xpr, [&](auto k, Index i, Index j) { s.add(k, le.coeff(i, j).raw(), re.coeff(i, j).raw()); });
    return osc::fixed::Q<F>::from_raw(s.rounded());
  }
  /// sum_ij x(i, j)^2 (squaredNorm).
  template <class X>
  static osc::fixed::Q<F> run(const CwiseUnaryOp<scalar_abs2_op<osc::fixed::Q<F>>, X>& xpr) {
    const evaluator<X> e(xpr.nestedExpression());
    osc::fixed::detail::ProductSum<F> s;
    for_each_coeff(xpr, [&](auto k, Index i, Index j) {
      const std::int32_t v = e.coeff(i, j).raw();
      s.add(k, v, v);
    });
    return osc::fixed::Q<F>::from_raw(s.rounded());
  }
};

// Eigen picks its redux by traversal and unrolling; a Q<F> scalar never vectorises
// (DefaultTraversal), and small fixed sizes unroll completely: both cases take the one-rounding sum.
#define OSC_Q_DOT_REDUX(UNROLLING)                                                                                     \
  template <int F, class Op, class L, class R>                                                                         \
  requires OscQProductOp<Op>::value struct redux_impl<scalar_sum_op<osc::fixed::Q<F>, osc::fixed::Q<F>>,               \
                                                      redux_evaluator<CwiseBinaryOp<Op, L, R>>, DefaultTraversal,      \
                                                      UNROLLING> {                                                     \
    template <class Ev, class Func, class Xpr>                                                                         \
    static osc::fixed::Q<F> run(const Ev&, const Func&, const Xpr& xpr) {                                              \
      return OscQDotRedux<F>::run(xpr);                                                                                \
    }                                                                                                                  \
  };                                                                                                                   \
  template <int F, class X>                                                                                            \
  struct redux_impl<scalar_sum_op<osc::fixed::Q<F>, osc::fixed::Q<F>>,                                                 \
                    redux_evaluator<CwiseUnaryOp<scalar_abs2_op<osc::fixed::Q<F>>, X>>, DefaultTraversal, UNROLLING> { \
    template <class Ev, class Func, class Xpr>                                                                         \
    static osc::fixed::Q<F> run(const Ev&, const Func&, const Xpr& xpr) {                                              \
      return OscQDotRedux<F>::run(xpr);                                                                                \
    }                                                                                                                  \
  };
OSC_Q_DOT_REDUX(NoUnrolling)
OSC_Q_DOT_REDUX(CompleteUnrolling)
#undef OSC_Q_DOT_REDUX
}  // namespace Eigen::internal
