// The one place the kernels touch elementary functions and literals.
// double and float forward to <cmath>; the fixed-point scalars (osc/kernels/fixed.hpp) bring their
// own overloads of these functions into osc::math (the kernels call them qualified) and a
// constructor from double for literals (lit<S>).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "osc/kernels/fixed.hpp"

namespace osc {

/// Literal of the kernel's scalar type (evaluated at compile time for float/double).
template <class S>
constexpr S lit(double v) { return static_cast<S>(v); }

/// A table of literals (per-joint limits) in the kernel's scalar. Bound to a constexpr variable it is
/// converted at compile time: indexing it at run time then costs no conversion from double (on a
/// core without a double-precision FPU, each would be a library call).
template <class S, std::size_t N>
constexpr std::array<S, N> lit_array(const double (&a)[N]) {
  std::array<S, N> r{};
  for (std::size_t i = 0; i < N; ++i) r[i] = lit<S>(a[i]);
  return r;
}

namespace math {
inline float sin(float v) { return std::sin(v); }
inline float cos(float v) { return std::cos(v); }
inline float sqrt(float v) { return std::sqrt(v); }
inline float exp(float v) { return std::exp(v); }
inline float abs(float v) { return std::fabs(v); }
inline float atan2(float y, float x) { return std::atan2(y, x); }
inline float asin(float v) { return std::asin(v); }
inline bool isfinite(float v) { return std::isfinite(v); }
inline double sin(double v) { return std::sin(v); }
inline double cos(double v) { return std::cos(v); }
inline double sqrt(double v) { return std::sqrt(v); }
inline double exp(double v) { return std::exp(v); }
inline double abs(double v) { return std::fabs(v); }
inline double atan2(double y, double x) { return std::atan2(y, x); }
inline double asin(double v) { return std::asin(v); }
inline bool isfinite(double v) { return std::isfinite(v); }
/// sin v and cos v together (one argument reduction in fixed point).
inline void sincos(float v, float& s, float& c) { s = std::sin(v), c = std::cos(v); }
inline void sincos(double v, double& s, double& c) { s = std::sin(v), c = std::cos(v); }
using fixed::sin;
using fixed::cos;
using fixed::sincos;
using fixed::sqrt;
using fixed::exp;
using fixed::abs;
using fixed::atan2;
using fixed::asin;
using fixed::isfinite;

/// sgn with sgn(0) = 0, eq. (3).
template <class S>
S sgn(S v) { return v > S(0) ? S(1) : (v < S(0) ? S(-1) : S(0)); }

/// True when every coefficient of an Eigen expression is finite.
template <class Derived>
bool all_finite(const Derived& m) {
  for (int j = 0; j < m.cols(); ++j)
    for (int i = 0; i < m.rows(); ++i)
      if (!isfinite(m(i, j))) return false;
  return true;
}

/// Reads and clears the scalar's sticky arithmetic flags (fixed point: a saturated overflow, a
/// division by a near-zero, a function outside its domain). Always false for float and double,
/// whose overflows show as non-finite values instead.
template <class S>
bool take_arithmetic_fault() {
  if constexpr (fixed::is_q_v<S>) return fixed::take_flags() != 0;
  else return false;
}

/// The scalar of hardware units at the I/O boundary (encoder counts, counts per radian, DAC
/// codes), whose magnitudes reach 10^5: the scalar itself for float and double, FixedIo for the
/// fixed-point kernels.
template <class S> struct IoScalar { using type = S; };
template <int F> struct IoScalar<fixed::Q<F>> { using type = FixedIo; };
template <class S> using io_scalar_t = typename IoScalar<S>::type;

/// n / d of two integers (sample counts to seconds): n (1/d) for float and double (the same bits
/// as n times a sample time 1/d), rounded once in fixed point.
template <class S>
S ratio(std::uint64_t n, std::uint32_t d) {
  if constexpr (fixed::is_q_v<S>) return fixed::ratio<S::kFractionBits>(static_cast<std::int64_t>(n), d);
  else return static_cast<S>(n) * (S(1) / static_cast<S>(d));
}

/// An integer n (encoder counts) divided by a scale of the I/O scalar (counts per radian).
template <class S>
S quotient(std::int32_t n, io_scalar_t<S> d) {
  if constexpr (fixed::is_q_v<S>) return fixed::quotient<S::kFractionBits>(n, d);
  else return static_cast<S>(n) / d;
}
}  // namespace math
}  // namespace osc
