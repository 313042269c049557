// The elementary functions of the fixed-point scalar Q<F> (osc/math/q.hpp): sin, cos, exp, sqrt,
// atan2, asin, abs and the classification functions, and the integer quotients of the I/O boundary.
// Each computes in Q30 / Q61 integers and rounds once into Q<F>; its maximum error against double
// over the whole input range is stated at each and tested in tests/firmware/math/test_q_functions.cpp.
#pragma once

#include <cstdint>

#include "osc/math/q.hpp"

namespace osc::fixed {

namespace detail {
/// Q30 constants of the elementary functions.
constexpr std::int64_t kOneQ30 = std::int64_t{1} << 30;
constexpr std::int32_t q30(double v) { return static_cast<std::int32_t>(v * 1073741824.0 + (v >= 0 ? 0.5 : -0.5)); }
/// pi/2 and ln 2 in Q61 (mpmath, 200 bits), split for exact range reduction: the top part in Q30,
/// the rest in Q61.
constexpr std::int64_t kPio2Q61 = 3622009729038561421LL;
constexpr std::int64_t kLn2Q61 = 1598288580650331957LL;
constexpr std::int64_t kPio2Q30 = 1686629713LL;    // round(pi/2 2^30)
constexpr std::int64_t kPiQ30 = 3373259426LL;      // round(pi 2^30)
constexpr std::int32_t kTwoOverPiQ30 = 683565276;  // round(2/pi 2^30)
constexpr std::int32_t kInvLn2Q30 = 1549082005;    // round(2^30 / ln 2)
/// atan(i / 8) in Q30, i = 0..8 (mpmath, 200 bits; tests/firmware/math/test_q_functions.cpp checks each).
constexpr std::int32_t kAtanEighthsQ30[9] = {0,         133525159, 263043837, 385227074, 497837829,
                                             599791448, 690954054, 771837835, 843314857};

/// Q30 product, rounded.
inline std::int32_t mul30(std::int32_t a, std::int32_t b) {
  return static_cast<std::int32_t>(shift_round(static_cast<std::int64_t>(a) * b, 30));
}

/// r - k c for a Q61 constant c = c_hi 2^31 + c_lo, in Q30 (x in Q30, |k| < 2^31).
inline std::int64_t reduce_q30(std::int64_t x, std::int64_t k, std::int64_t c_q61) {
  const std::int64_t hi = c_q61 >> 31, lo = c_q61 & 0x7FFFFFFF;
  return x - k * hi - shift_round(k * lo, 31);
}

/// sin r, cos r for |r| <= pi/4 (+ a little), in Q30. Taylor polynomials: the truncation error
/// is below 2e-9 at pi/4 (sin: r^11/11!, cos: r^12/12!), the Q30 rounding a few 2^-30.
inline std::int32_t sin_q30(std::int32_t r) {
  const std::int32_t z = mul30(r, r);
  std::int32_t p = q30(1.0 / 362880);
  p = q30(-1.0 / 5040) + mul30(z, p);
  p = q30(1.0 / 120) + mul30(z, p);
  p = q30(-1.0 / 6) + mul30(z, p);
  return r + mul30(r, mul30(z, p));
}
inline std::int32_t cos_q30(std::int32_t r) {
  const std::int32_t z = mul30(r, r);
  std::int32_t p = q30(-1.0 / 3628800);
  p = q30(1.0 / 40320) + mul30(z, p);
  p = q30(-1.0 / 720) + mul30(z, p);
  p = q30(1.0 / 24) + mul30(z, p);
  p = q30(-0.5) + mul30(z, p);
  return static_cast<std::int32_t>(kOneQ30 + mul30(z, p));
}

/// atan z for 0 <= z <= 1 in Q30: atan z = atan c + atan t, c = i/8 the nearest eighth,
/// t = (z - c) / (1 + z c), |t| <= 1/16, atan t = t - t^3/3 + t^5/5 - t^7/7 (truncation 2e-12).
inline std::int64_t atan01_q30(std::uint32_t z) {
  const std::uint32_t i = (z + (1u << 26)) >> 27;  // nearest eighth
  const std::int64_t c = static_cast<std::int64_t>(i) << 27;
  const std::int64_t num = static_cast<std::int64_t>(z) - c;
  const std::uint32_t den = static_cast<std::uint32_t>(kOneQ30 + ((static_cast<std::int64_t>(z) * c) >> 30));
  const std::uint64_t an = static_cast<std::uint64_t>(num < 0 ? -num : num) << 30;
  const std::uint32_t tq = udiv64_32(an + (den >> 1), den);
  const std::int32_t t = num < 0 ? -static_cast<std::int32_t>(tq) : static_cast<std::int32_t>(tq);
  const std::int32_t t2 = mul30(t, t);
  std::int32_t p = q30(-1.0 / 7);
  p = q30(1.0 / 5) + mul30(t2, p);
  p = q30(-1.0 / 3) + mul30(t2, p);
  return kAtanEighthsQ30[i] + t + mul30(t, mul30(t2, p));
}

/// atan2(y, x) in Q30 (int64) for two nonnegative magnitudes in any common scale, not both 0.
inline std::int64_t atan2_abs_q30(std::uint64_t ay, std::uint64_t ax) {
  const bool swap = ay > ax;
  const std::uint64_t num = swap ? ax : ay, den = swap ? ay : ax;
  // Scale to 32 bits keeping the ratio (den < 2^62 here).
  int s = 0;
  while ((den >> s) > 0xFFFFFFFFull) ++s;
  const std::uint32_t d = static_cast<std::uint32_t>(den >> s);
  const std::uint64_t n = (num >> s) << 30;
  const std::uint32_t z = d == 0 ? 0u : udiv64_32(n + (d >> 1), d);
  const std::int64_t a = atan01_q30(z > (1u << 30) ? (1u << 30) : z);
  return swap ? kPio2Q30 - a : a;
}

}  // namespace detail

// ---------------------------------------------------------------- elementary functions
// Errors are against double evaluated at the same (quantised) argument, over the whole input
// range, in units of the result's last bit (LSB = 2^-F); tests/firmware/math/test_q_functions.cpp measures them.

template <int F>
[[gnu::always_inline]] inline Q<F> abs(Q<F> v) {
  return v.raw() < 0 ? -v : v;
}
template <int F>
constexpr bool isfinite(Q<F>) {
  return true;
}
template <int F>
constexpr bool isnan(Q<F>) {
  return false;
}
template <int F>
constexpr bool isinf(Q<F>) {
  return false;
}

namespace detail {
/// A Q30 value (int64) rounded into Q<F>.
template <int F>
Q<F> from_q30(std::int64_t v) {
  if constexpr (F < 30)
    return Q<F>::from_raw(narrow(shift_round(v, 30 - F)));
  else
    return Q<F>::from_raw(narrow(v));
}
/// sin and cos of a Q<F> angle: x = k pi/2 + r with |r| <= pi/4, r exact to 2^-30 (pi/2 to 61 bits).
template <int F>
void sincos_q30(Q<F> x, std::int32_t* s, std::int32_t* c) {
  const std::int64_t k = shift_round(static_cast<std::int64_t>(x.raw()) * kTwoOverPiQ30, F + 30);
  const std::int64_t xq30 = static_cast<std::int64_t>(x.raw()) * (std::int64_t{1} << (30 - F));
  const std::int32_t r = static_cast<std::int32_t>(reduce_q30(xq30, k, kPio2Q61));
  const unsigned quadrant = static_cast<unsigned>(k) & 3u;
  if (s) {
    const std::int32_t v = (quadrant & 1u) ? cos_q30(r) : sin_q30(r);
    *s = (quadrant & 2u) ? -v : v;
  }
  if (c) {
    const std::int32_t v = (quadrant & 1u) ? sin_q30(r) : cos_q30(r);
    *c = ((quadrant + 1u) & 2u) ? -v : v;
  }
}
}  // namespace detail

/// sin x, |error| <= 0.51 LSB for every x in the range of Q<F>.
template <int F>
Q<F> sin(Q<F> x) {
  std::int32_t s;
  detail::sincos_q30(x, &s, nullptr);
  return detail::from_q30<F>(s);
}
/// cos x, |error| <= 0.51 LSB for every x in the range of Q<F>.
template <int F>
Q<F> cos(Q<F> x) {
  std::int32_t c;
  detail::sincos_q30(x, nullptr, &c);
  return detail::from_q30<F>(c);
}

/// sin x and cos x with one argument reduction; each as sin and cos above.
template <int F>
void sincos(Q<F> x, Q<F>& s, Q<F>& c) {
  std::int32_t sr, cr;
  detail::sincos_q30(x, &sr, &cr);
  s = detail::from_q30<F>(sr);
  c = detail::from_q30<F>(cr);
}

/// e^x: x = k ln 2 + r, |r| <= ln 2 / 2, Taylor to r^8 in Q30 (truncation 2e-10), scaled by 2^k.
/// |error| <= 0.51 LSB + 4e-9 e^x; e^x beyond the range saturates (kOverflow), far below it is 0.
template <int F>
Q<F> exp(Q<F> x) {
  using namespace detail;
  // e^x beyond the range: x > (31 - F) ln 2 less a margin of two LSB.
  constexpr std::int32_t kMaxArg = static_cast<std::int32_t>(0.6931471805599453 * (31 - F) * (1 << F)) - 2;
  if (x.raw() > kMaxArg) return Q<F>::from_raw(narrow(INT64_MAX));
  const std::int64_t k = shift_round(static_cast<std::int64_t>(x.raw()) * kInvLn2Q30, F + 30);
  if (k < -(F + 2)) return Q<F>::from_raw(0);  // e^x < 2^-(F+1.5): rounds to 0
  const std::int64_t xq30 = static_cast<std::int64_t>(x.raw()) * (std::int64_t{1} << (30 - F));
  const std::int32_t r = static_cast<std::int32_t>(reduce_q30(xq30, k, kLn2Q61));
  std::int32_t p = q30(1.0 / 40320);
  p = q30(1.0 / 5040) + mul30(r, p);
  p = q30(1.0 / 720) + mul30(r, p);
  p = q30(1.0 / 120) + mul30(r, p);
  p = q30(1.0 / 24) + mul30(r, p);
  p = q30(1.0 / 6) + mul30(r, p);
  p = q30(0.5) + mul30(r, p);
  const std::int64_t e = kOneQ30 + r + mul30(r, mul30(r, p));  // e^r in Q30, 0.70..1.42
  const int shift = static_cast<int>(k) + F - 30;              // e^x = e 2^k, in Q<F>
  if (shift >= 0) return Q<F>::from_raw(narrow(e << shift));
  return Q<F>::from_raw(narrow(shift_round(e, -shift)));
}

/// sqrt x for x >= 0, correctly rounded (|error| <= 0.5 LSB). x < 0: 0 and kDomain.
template <int F>
Q<F> sqrt(Q<F> x) {
  if (x.raw() < 0) {
    detail::raise_flag(kDomain);
    return Q<F>::from_raw(0);
  }
  return Q<F>::from_raw(static_cast<std::int32_t>(detail::isqrt64_round(static_cast<std::uint64_t>(x.raw()) << F)));
}

/// atan2(y, x) in (-pi, pi], atan2(0, 0) = 0; |error| <= 0.51 LSB everywhere.
template <int F>
Q<F> atan2(Q<F> y, Q<F> x) {
  const std::int64_t yr = y.raw(), xr = x.raw();
  if (yr == 0 && xr == 0) return Q<F>::from_raw(0);
  std::int64_t a = detail::atan2_abs_q30(static_cast<std::uint64_t>(yr < 0 ? -yr : yr),
                                         static_cast<std::uint64_t>(xr < 0 ? -xr : xr));
  if (xr < 0) a = detail::kPiQ30 - a;
  if (yr < 0) a = -a;
  return detail::from_q30<F>(a);
}

/// asin x = atan2(x, sqrt(1 - x^2)) with 1 - x^2 exact and its root to 2^-30; |error| <= 0.51 LSB
/// on [-1, 1]. Beyond [-1, 1]: +-pi/2 and kDomain.
template <int F>
Q<F> asin(Q<F> x) {
  const std::int64_t one = std::int64_t{1} << F;
  std::int64_t xr = x.raw();
  if (xr > one || xr < -one) {
    detail::raise_flag(kDomain);
    xr = xr > 0 ? one : -one;
  }
  const std::uint64_t ax = static_cast<std::uint64_t>(xr < 0 ? -xr : xr);
  const std::uint64_t c2 = (static_cast<std::uint64_t>(one) << F) - ax * ax;  // 1 - x^2 in Q(2F)
  const std::uint64_t c = detail::isqrt64_round(c2 << (60 - 2 * F));          // Q30
  const std::int64_t a = detail::atan2_abs_q30(ax << (30 - F), c);
  return detail::from_q30<F>(xr < 0 ? -a : a);
}

/// a / b for an integer a (encoder counts) and a scale b in another format, in Q<F>: exact to the
/// rounding of the result.
template <int F, int G>
Q<F> quotient(std::int64_t a, Q<G> b) {
  return Q<F>::from_raw(detail::div_shifted(a, F + G, b.raw()));
}

/// n / d of two integers (sample counts to seconds), rounded.
template <int F>
Q<F> ratio(std::int64_t n, std::int64_t d) {
  return Q<F>::from_raw(detail::div_shifted(n, F, static_cast<std::int32_t>(d)));
}

}  // namespace osc::fixed
