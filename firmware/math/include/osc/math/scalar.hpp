// The one place the kernels touch elementary functions and literals.
// double and float forward to <cmath>; the fixed-point scalars (osc/math/fixed.hpp) bring their
// own overloads of these functions into osc::math (the kernels call them qualified) and a
// constructor from double for literals (lit<S>).
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "osc/math/fixed.hpp"

namespace osc {

/// Literal of the kernel's scalar type (evaluated at compile time for float/double).
template <class S>
constexpr S lit(double v) {
  return static_cast<S>(v);
}

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
namespace detail {
/// v rounded to the nearest integer (half away from zero), for the range reductions below.
[[gnu::always_inline]] inline int round_to_int(float v) { return static_cast<int>(v >= 0.0f ? v + 0.5f : v - 0.5f); }

/// sin v and cos v in float, for the FPU targets (newlib's sinf and cosf each reduce the argument
/// again and take several times as many instructions). v = k pi/2 + r, |r| <= pi/4, with pi/2 split
/// into three floats whose first two have 12 significant bits, so that k times them is exact for
/// |k| < 2^12 (|v| < 6400); the rounding of r is kept as r_lo (TwoSum), and the one of 1 - r^2/2
/// too (as fdlibm's cosine kernel does). Taylor polynomials of sin to r^9 and of cos to r^10
/// (truncation below 2e-9 at pi/4), each result rounded once from r or 1 - r^2/2 and a small sum.
/// |error| <= 6e-8 (one float ulp of 1) for |v| <= 6400, tested
/// against double (tests/firmware/kernels/test_properties.cpp, FloatFunctions).
[[gnu::always_inline]] inline void sincos_float(float v, float& s, float& c) {
  const int k = round_to_int(v * 0.636619772f);
  const float fk = static_cast<float>(k);
  const float a = v - fk * 1.57080078125f;                                        // exact
  const float b = fk * -4.453584551811218e-06f;                                   // exact
  const float r = a - b, bv = r - a;                                              // TwoSum: r + e = a - b exactly
  const float r_lo = ((a - (r - bv)) - (b + bv)) - fk * -8.705516307827565e-10f;  // r + r_lo = v - k pi/2
  const float z = r * r;
  const float sr_lo = r * z * (-1.66666667e-1f + z * (8.33333333e-3f + z * (-1.98412698e-4f + z * 2.75573192e-6f)));
  const float sr = r + sr_lo;
  const float hz = 0.5f * z, w = 1.0f - hz;
  const float cr_lo =
      ((1.0f - w) - hz) + z * z * (4.16666667e-2f + z * (-1.38888889e-3f + z * (2.48015873e-5f + z * -2.75573192e-7f)));
  const float cr = w + cr_lo;
  // sin(r + r_lo) = sin r + r_lo cos r, cos(r + r_lo) = cos r - r_lo sin r (r_lo^2 is below 2^-40).
  const float ps = r + (sr_lo + r_lo * cr);
  const float pc = w + (cr_lo - r_lo * sr);
  switch (static_cast<unsigned>(k) & 3u) {
    case 0:
      s = ps, c = pc;
      break;
    case 1:
      s = pc, c = -ps;
      break;
    case 2:
      s = -ps, c = -pc;
      break;
    default:
      s = -pc, c = ps;
      break;
  }
}
/// e^v in float: v = k ln 2 + r, |r| <= ln 2 / 2 (ln 2 in two floats, the first with 12 significant
/// bits), Taylor polynomial to r^7 (truncation below 6e-9 relative), times 2^k from the exponent bits.
/// Relative error <= 2.4e-7 (two float ulps) where e^v is a normal float; 0 below, +inf above.
/// NonPositive: the caller's v is <= 0 or NaN (a decay), whose checks above 0 are left out; the same result.
template <bool NonPositive = false>
[[gnu::always_inline]] inline float exp_float(float v) {
  if (!(v >= -87.3f)) return v != v ? v : 0.0f;  // NaN stays NaN; e^v below the normal range: 0
  if (!NonPositive && v > 88.5f) return HUGE_VALF;
  const int k = round_to_int(v * 1.44269502f);
  const float fk = static_cast<float>(k);
  const float r = (v - fk * 0.693115234375f) - fk * 3.194618329871446e-05f;
  const float p =
      1.0f +
      r * (1.0f +
           r * (0.5f + r * (1.66666667e-1f +
                            r * (4.16666667e-2f + r * (8.33333333e-3f + r * (1.38888889e-3f + r * 1.98412698e-4f))))));
  // 2^k, k >= -126 (v >= -87.3): one factor below 128; p 2^k rounds once either way (to a subnormal at most).
  // k = 128 (only just below 88.72) as two factors, each a normal float.
  if (NonPositive || k < 128) return p * std::bit_cast<float>(static_cast<std::uint32_t>(k + 127) << 23);
  const int k1 = k / 2, k2 = k - k1;
  const float s1 = std::bit_cast<float>(static_cast<std::uint32_t>(k1 + 127) << 23);
  const float s2 = std::bit_cast<float>(static_cast<std::uint32_t>(k2 + 127) << 23);
  return p * s1 * s2;
}
/// atan2(y, x) in float, the same instructions on every target (the C libraries' atan2f differ, and
/// so would a float controller on the host and on the M4F). a = min(|x|, |y|) / max(|x|, |y|) in
/// [0, 1]; above tan(pi/12), atan a = pi/6 + atan t with t = (a sqrt3 - 1) / (a + sqrt3), so
/// |t| <= tan(pi/12) = 0.268; atan t = p by its Taylor polynomial to t^13 (truncation below 3e-9).
/// The octant (pi/2 - r where |y| > |x|, pi - r where x < 0 or -0) and the shift make the result
/// k pi/6 +- p, k in 0..6, with k pi/6 as a float and its rest: one rounding of the sum. |error|
/// <= 2e-7 (under one float ulp of pi), tested against double (test_properties, FloatFunctions).
/// IEEE's zeros (atan2(+-0, -0) = +-pi) and NaNs; both infinite gives the diagonal's angle.
[[gnu::always_inline]] inline float atan2_float(float y, float x) {
  constexpr float kHi[7] = {
      0.0f, 5.235987902e-01f, 1.047197580e+00f, 1.570796371e+00f, 2.094395161e+00f, 2.617993832e+00f, 3.141592741e+00f};
  constexpr float kLo[7] = {0.0f,
                            -1.457046339e-08f,
                            -2.914092678e-08f,
                            -4.371139006e-08f,
                            -5.828185357e-08f,
                            4.635697293e-08f,
                            -8.742278013e-08f};
  if (x != x || y != y) return x + y;
  const float ax = std::fabs(x), ay = std::fabs(y);
  const bool steep = ay > ax, negative_x = std::signbit(x);
  const float mn = steep ? ax : ay, mx = steep ? ay : ax;
  const float a = mx > 0.0f ? (mn == mx ? 1.0f : mn / mx) : 0.0f;
  const bool shifted = a > 2.679491937e-01f;
  const float t = shifted ? (a * 1.732050776f - 1.0f) / (a + 1.732050776f) : a;
  const float z = t * t;
  const float p =
      t +
      t * z *
          (-3.33333333e-1f +
           z * (2.0e-1f + z * (-1.42857143e-1f + z * (1.11111111e-1f + z * (-9.09090909e-2f + z * 7.69230769e-2f)))));
  // The angle: base + s (shift + p), base 0, pi/2 (steep) or pi (x < 0; pi/2 when both), s = -1
  // where one of steep and x < 0 reflects r.
  const bool minus = steep != negative_x;
  const int base = negative_x ? (steep ? 3 : 6) : (steep ? 3 : 0);
  const int k = base + (shifted ? (minus ? -1 : 1) : 0);
  const float r = kHi[k] + ((minus ? -p : p) + kLo[k]);
  return std::signbit(y) ? -r : r;
}
}  // namespace detail

inline float sin(float v) {
  float s, c;
  detail::sincos_float(v, s, c);
  return s;
}
inline float cos(float v) {
  float s, c;
  detail::sincos_float(v, s, c);
  return c;
}
inline float sqrt(float v) { return std::sqrt(v); }
inline float exp(float v) { return detail::exp_float(v); }
/// e^v for v <= 0 (a decay): exp(v), in float without its checks for v > 0.
inline float exp_decay(float v) { return detail::exp_float<true>(v); }
inline float abs(float v) { return std::fabs(v); }
inline float atan2(float y, float x) { return detail::atan2_float(y, x); }
/// asin v = atan2(v, sqrt((1 - v)(1 + v))) (NaN outside [-1, 1]).
inline float asin(float v) {
  if (!(std::fabs(v) <= 1.0f)) return v != v ? v : std::numeric_limits<float>::quiet_NaN();
  return detail::atan2_float(v, std::sqrt((1.0f - v) * (1.0f + v)));
}
inline bool isfinite(float v) { return std::isfinite(v); }
inline double sin(double v) { return std::sin(v); }
inline double cos(double v) { return std::cos(v); }
inline double sqrt(double v) { return std::sqrt(v); }
inline double exp(double v) { return std::exp(v); }
inline double exp_decay(double v) { return std::exp(v); }
inline double abs(double v) { return std::fabs(v); }
inline double atan2(double y, double x) { return std::atan2(y, x); }
inline double asin(double v) { return std::asin(v); }
inline bool isfinite(double v) { return std::isfinite(v); }
/// a b + c rounded once (IEEE 754's fusedMultiplyAdd): one instruction on the M4F's FPU (vfma.f32)
/// and the C library's fma on the host, the same bits on both. The build's -ffp-contract=off keeps
/// the compiler from fusing a b + c where the source does not ask for it; this asks. In fixed point,
/// a b + c.
inline float mul_add(float a, float b, float c) { return std::fma(a, b, c); }
inline double mul_add(double a, double b, double c) { return std::fma(a, b, c); }
template <class S>
inline S mul_add(S a, S b, S c) {
  return a * b + c;
}
/// sin v and cos v together (one argument reduction in fixed point).
inline void sincos(float v, float& s, float& c) { detail::sincos_float(v, s, c); }
inline void sincos(double v, double& s, double& c) { s = std::sin(v), c = std::cos(v); }
using fixed::abs;
using fixed::asin;
using fixed::atan2;
using fixed::cos;
using fixed::exp;
using fixed::isfinite;
/// e^v for v <= 0, fixed point: exp(v).
template <class S>
requires fixed::is_q_v<S>
inline S exp_decay(S v) { return exp(v); }
using fixed::sin;
using fixed::sincos;
using fixed::sqrt;

/// a0 b0 + a1 b1 + ...: a dot product written out (a plane rotation, an entry of an inertia). Fixed
/// point rounds it once (the exact products summed in 64 bits, fixed::detail::ProductSum), not once
/// per product and sum.
template <class S, class... R>
[[gnu::always_inline]] inline S sum_of_products(S a, S b, R... rest) {
  if constexpr (fixed::is_q_v<S>)
    return S::from_raw(fixed::detail::dot_raw<S::kFractionBits>(a.raw(), b.raw(), rest.raw()...));
  else if constexpr (sizeof...(R) == 0)
    return a * b;
  else
    return a * b + sum_of_products(rest...);
}
/// a b - c d, likewise (the component of a cross product).
template <class S>
[[gnu::always_inline]] inline S dot2_minus(S a, S b, S c, S d) {
  if constexpr (fixed::is_q_v<S>) {
    fixed::detail::ProductSum<S::kFractionBits> sum;
    sum.add(0, a.raw(), b.raw());
    sum.sub(1, c.raw(), d.raw());
    return S::from_raw(sum.rounded());
  } else {
    return a * b - c * d;
  }
}

/// sgn with sgn(0) = 0, eq. (3).
template <class S>
S sgn(S v) {
  return v > S(0) ? S(1) : (v < S(0) ? S(-1) : S(0));
}

/// True when every coefficient of an Eigen expression is finite. In float and double without a
/// branch per coefficient: v - v is 0 for a finite v and NaN for an infinite or NaN one (IEEE 754;
/// the build has no -ffast-math, so the compiler may not fold it), and a NaN in the sum stays NaN.
template <class Derived>
bool all_finite(const Derived& m) {
  using S = typename Derived::Scalar;
  if constexpr (std::is_floating_point_v<S>) {
    S sum = S(0);
    for (int j = 0; j < m.cols(); ++j)
      for (int i = 0; i < m.rows(); ++i) {
        const S v = m(i, j);
        sum += v - v;  // NOLINT(misc-redundant-expression): 0 for a finite v, NaN otherwise
      }
    return sum == S(0);
  } else {
    for (int j = 0; j < m.cols(); ++j)
      for (int i = 0; i < m.rows(); ++i)
        if (!isfinite(m(i, j))) return false;
    return true;
  }
}

/// Reads and clears the scalar's sticky arithmetic flags (fixed point: a saturated overflow, a
/// division by a near-zero, a function outside its domain). Always false for float and double,
/// whose overflows show as non-finite values instead.
template <class S>
bool take_arithmetic_fault() {
  if constexpr (fixed::is_q_v<S>)
    return fixed::take_flags() != 0;
  else
    return false;
}

/// The sticky arithmetic flags, taken (cleared) and put back: a computation outside the control
/// tick (a command's planning) keeps its saturations apart from the tick's,
///   const std::uint32_t saved = take_arithmetic_flags<S>();  ...;  bool bad = take_arithmetic_fault<S>();
///   restore_arithmetic_flags<S>(saved);
/// 0 and nothing for float and double.
template <class S>
std::uint32_t take_arithmetic_flags() {
  if constexpr (fixed::is_q_v<S>)
    return fixed::take_flags();
  else
    return 0;
}
template <class S>
void restore_arithmetic_flags(std::uint32_t f) {
  if constexpr (fixed::is_q_v<S>) fixed::restore_flags(f);
}

/// The scalar of hardware units at the I/O boundary (encoder counts, counts per radian, DAC
/// codes), whose magnitudes reach 10^5: the scalar itself for float and double, FixedIo for the
/// fixed-point kernels.
template <class S>
struct IoScalar {
  using type = S;
};
template <int F>
struct IoScalar<fixed::Q<F>> {
  using type = FixedIo;
};
template <class S>
using io_scalar_t = typename IoScalar<S>::type;

/// n / d of two integers (sample counts to seconds): n (1/d) for float and double (the same bits
/// as n times a sample time 1/d), rounded once in fixed point.
template <class S>
S ratio(std::uint64_t n, std::uint32_t d) {
  if constexpr (fixed::is_q_v<S>)
    return fixed::ratio<S::kFractionBits>(static_cast<std::int64_t>(n), d);
  else
    // n below 2^32 converts as a 32-bit integer (the same value: one instruction on the M4F, where
    // a 64-bit one is a library call).
    return (n >> 32 == 0 ? static_cast<S>(static_cast<std::uint32_t>(n)) : static_cast<S>(n)) *
           (S(1) / static_cast<S>(d));
}

/// An integer n (encoder counts) divided by a scale of the I/O scalar (counts per radian).
template <class S>
S quotient(std::int32_t n, io_scalar_t<S> d) {
  if constexpr (fixed::is_q_v<S>)
    return fixed::quotient<S::kFractionBits>(n, d);
  else
    return static_cast<S>(n) / d;
}
}  // namespace math
}  // namespace osc
