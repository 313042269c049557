// The saturating Q-format scalar Q<F> (a signed 32-bit integer r standing for r / 2^F) and the
// formats of the firmware: Fixed = Q12.19 for every kernel quantity, FixedIo = Q19.12 for hardware
// units. Its arithmetic is osc/math/saturating_int.hpp; its elementary functions
// osc/math/q_functions.hpp; Eigen's view of it osc/math/q_eigen.hpp; osc/math/fixed.hpp has them all.
#pragma once

#include <bit>
#include <climits>
#include <compare>
#include <concepts>
#include <cstdint>
#include <type_traits>

#include "osc/math/saturating_int.hpp"

namespace osc::fixed {

template <int F>
class Q {
  static_assert(F >= 1 && F <= 30, "Q<F>: 1 to 30 fraction bits in 32-bit storage");

 public:
  using Raw = std::int32_t;
  static constexpr int kFractionBits = F;
  static constexpr int kIntegerBits = 31 - F;

#if defined(__arm__) && !defined(__linux__)
  /// Uninitialised, like float: Eigen's fixed-size temporaries stay free.
  Q() = default;
#else
  /// Zero on the host: Eigen's condition estimator compares a vector that it assigns only in an
  /// earlier loop iteration, which the host compiler cannot follow (-Wmaybe-uninitialized, an error
  /// here). On the target the same code compiles without it, and zeroing every temporary would cost
  /// memsets in the control step. No kernel reads a default-constructed value before writing it.
  constexpr Q() : r_(0) {}
#endif

  /// From an integer: implicit, as for float (Eigen's generic code writes `return 0;`).
  template <std::integral I>
  constexpr Q(I v) : r_(from_integer(v)) {}  // NOLINT(google-explicit-constructor)
  constexpr explicit Q(double v) : r_(from_double(v)) {}
  constexpr explicit Q(float v) : r_(from_double(static_cast<double>(v))) {}
  /// From another format: rounded when it has more fraction bits, saturated when out of range.
  template <int G>
  requires(G != F) constexpr explicit Q(Q<G> o) : r_(convert<G>(o.raw())) {}

  static constexpr Q from_raw(Raw r) {
    Q q;
    q.r_ = r;
    return q;
  }
  constexpr Raw raw() const { return r_; }
  static constexpr Q max() { return from_raw(detail::kRawMax); }
  static constexpr Q min() { return from_raw(detail::kRawMin); }
  static constexpr Q lsb() { return from_raw(1); }

  explicit constexpr operator double() const {
    return static_cast<double>(r_) / static_cast<double>(std::int64_t{1} << F);
  }
  /// Correctly rounded (to nearest, ties to even), assembled from the integer's bits: no floating-point
  /// operation, so a core without an FPU converts without a soft-float routine (telemetry frames).
  explicit constexpr operator float() const {
    if (r_ == 0) return 0.0f;
    const std::uint32_t sign = r_ < 0 ? 0x80000000u : 0u;
    std::uint32_t m = r_ < 0 ? 0u - static_cast<std::uint32_t>(r_) : static_cast<std::uint32_t>(r_);
    int top = 31 - std::countl_zero(m);  // value = m 2^-F = 1.f 2^(top - F)
    if (top > 23) {                      // keep 24 significant bits, rounded to nearest even
      const int sh = top - 23;
      const std::uint32_t rest = m & ((1u << sh) - 1u), half = 1u << (sh - 1);
      m >>= sh;
      if (rest > half || (rest == half && (m & 1u))) ++m;
      if (m == (1u << 24)) {
        m >>= 1;
        ++top;
      }
    } else {
      m <<= 23 - top;
    }
    const std::uint32_t exponent = static_cast<std::uint32_t>(top - F + 127);  // a normal float for F <= 30
    return std::bit_cast<float>(sign | (exponent << 23) | (m & 0x7FFFFFu));
  }
  /// Truncated towards zero, as a float converts.
  explicit constexpr operator std::int32_t() const {
    return r_ >= 0 ? (r_ >> F) : -static_cast<std::int32_t>((-static_cast<std::int64_t>(r_)) >> F);
  }

  friend constexpr bool operator==(Q a, Q b) { return a.r_ == b.r_; }
  friend constexpr auto operator<=>(Q a, Q b) { return a.r_ <=> b.r_; }

  [[gnu::always_inline]] friend Q operator+(Q a, Q b) { return from_raw(detail::add(a.r_, b.r_)); }
  [[gnu::always_inline]] friend Q operator-(Q a, Q b) { return from_raw(detail::sub(a.r_, b.r_)); }
  [[gnu::always_inline]] friend Q operator-(Q a) { return from_raw(detail::neg(a.r_)); }
  friend constexpr Q operator+(Q a) { return a; }
  /// Rounded to nearest (half up).
  [[gnu::always_inline]] friend Q operator*(Q a, Q b) { return from_raw(detail::mul_shift<F>(a.r_, b.r_)); }
  /// Rounded to nearest (half away from zero); b == 0 or a quotient beyond the range saturates.
  friend Q operator/(Q a, Q b) { return from_raw(detail::div_shifted(a.r_, F, b.r_)); }
  /// A product with another format, in this one (e.g. a quantity times a hardware scale).
  template <int G>
  requires(G != F) [[gnu::always_inline]] friend Q operator*(Q a, Q<G> b) {
    return from_raw(detail::mul_shift<G>(a.r_, b.raw()));
  }
  template <std::integral I>
  friend constexpr Q operator*(I i, Q a) {
    return from_raw(detail::narrow(static_cast<std::int64_t>(i) * a.r_));
  }
  template <std::integral I>
  friend constexpr Q operator*(Q a, I i) {
    return i * a;
  }

  [[gnu::always_inline]] Q& operator+=(Q b) { return *this = *this + b; }
  [[gnu::always_inline]] Q& operator-=(Q b) { return *this = *this - b; }
  [[gnu::always_inline]] Q& operator*=(Q b) { return *this = *this * b; }
  Q& operator/=(Q b) { return *this = *this / b; }

 private:
  template <class I>
  static constexpr Raw from_integer(I v) {
    if constexpr (std::is_signed_v<I>) {
      const std::int64_t w = static_cast<std::int64_t>(v);
      if (w > (detail::kRawMax >> F)) return detail::narrow(INT64_MAX);
      if (w < (detail::kRawMin >> F)) return detail::narrow(INT64_MIN);
      return static_cast<Raw>(w * (std::int64_t{1} << F));
    } else {
      const std::uint64_t w = static_cast<std::uint64_t>(v);
      if (w > static_cast<std::uint64_t>(detail::kRawMax >> F)) return detail::narrow(INT64_MAX);
      return static_cast<Raw>(static_cast<std::int64_t>(w) << F);
    }
  }
  static constexpr Raw from_double(double v) {
    const double s = v * static_cast<double>(std::int64_t{1} << F);
    if (!(s == s)) {  // NaN
      if (std::is_constant_evaluated())
        detail::literal_out_of_range();
      else
        detail::raise_flag(kDomain);
      return 0;
    }
    if (s >= 2147483647.5 || s < -2147483648.5) {
      if (std::is_constant_evaluated()) detail::literal_out_of_range();
      return detail::narrow(s > 0 ? INT64_MAX : INT64_MIN);
    }
    return static_cast<Raw>(static_cast<std::int64_t>(s >= 0 ? s + 0.5 : s - 0.5));
  }
  template <int G>
  static constexpr Raw convert(std::int32_t r) {
    if constexpr (G > F) {
      return static_cast<Raw>(detail::shift_round(r, G - F));
    } else {
      return detail::narrow(static_cast<std::int64_t>(r) * (std::int64_t{1} << (F - G)));
    }
  }

  Raw r_;
};

template <class T>
struct IsQ : std::false_type {};
template <int F>
struct IsQ<Q<F>> : std::true_type {};
template <class T>
inline constexpr bool is_q_v = IsQ<T>::value;

}  // namespace osc::fixed

namespace osc {
/// The kernels' fixed-point scalar: Q12.19.
using Fixed = fixed::Q<19>;
/// Hardware units at the I/O boundary of a fixed-point controller: Q19.12.
using FixedIo = fixed::Q<12>;
}  // namespace osc
