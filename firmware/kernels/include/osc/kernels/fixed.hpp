// Q-format fixed-point scalars: the kernels' arithmetic on cores without an FPU
// (docs/fixed_point.md has the formats, the headroom analysis and the measured errors).
//
// Q<F> is a signed 32-bit integer r that stands for r / 2^F: 31 - F integer bits, F fraction bits.
// Products and quotients go through 64-bit intermediates and are rounded to nearest. A result that
// does not fit saturates at the end of the range and raises a sticky flag, never silently:
//   kOverflow  a sum, product, negation or conversion beyond the range;
//   kDivision  a division by zero, or by a number so near zero that the quotient does not fit;
//   kDomain    a function outside its domain (sqrt of a negative, asin beyond [-1, 1], NaN input).
// The control task reads and clears the flags once per tick (math::take_arithmetic_fault) and the
// supervisor latches them as the fault `overflow`, with zero torque in the same tick.
//
// The family of formats, by quantity:
//   Fixed   = Q<19> (Q12.19, range +-4096, resolution 1.9e-6): every kernel and control-law quantity
//             (angles, positions, velocities, forces, torques, inertias, gains, time).
//   FixedIo = Q<12> (Q19.12, range +-524288, resolution 2.4e-4): hardware units at the I/O boundary
//             (encoder counts, counts per radian, DAC codes): math::io_scalar_t<Fixed>.
//   Q1.30 in 32 bits and Q30 / Q61 in 64 bits: inside the elementary functions only.
// The elementary functions (sin, cos, exp, atan2, asin, sqrt) take and return Q<F>; their maximum
// errors against double over the whole input range are stated at each and tested in
// tests/test_fixed.cpp.
#pragma once

#include <Eigen/Core>
#include <bit>
#include <climits>
#include <concepts>
#include <cstdint>
#include <type_traits>
#include <utility>

namespace osc::fixed {

/// Sticky arithmetic flags (bits of flags()).
enum Flag : std::uint32_t {
  kOverflow = 1u << 0,  ///< a result beyond the format's range (saturated)
  kDivision = 1u << 1,  ///< a division by zero or by a near-zero (saturated)
  kDomain = 1u << 2,    ///< a function outside its domain
};

namespace detail {
// One word of flags per thread of execution: on the bare-metal targets the control interrupt is
// the only one that computes in fixed point; on the host the experiment runs controllers in threads.
#if defined(__arm__) && !defined(__linux__)
inline std::uint32_t g_flags = 0;
#else
inline thread_local std::uint32_t g_flags = 0;
#endif

inline void raise_flag(std::uint32_t f) { g_flags |= f; }
/// A literal that does not fit: a compile-time error where a constant is required.
inline void literal_out_of_range() {}

constexpr std::int32_t kRawMax = INT32_MAX;
constexpr std::int32_t kRawMin = INT32_MIN;

/// v saturated to 32 bits; a saturation raises `why`.
constexpr std::int32_t narrow(std::int64_t v, std::uint32_t why = kOverflow) {
  if (v > kRawMax) {
    if (!std::is_constant_evaluated()) raise_flag(why);
    return kRawMax;
  }
  if (v < kRawMin) {
    if (!std::is_constant_evaluated()) raise_flag(why);
    return kRawMin;
  }
  return static_cast<std::int32_t>(v);
}

/// The end of the range in the direction of `positive`, with the flag `why` raised: the slow path
/// of every operation, out of line so that the fast path stays a few instructions.
[[gnu::cold, gnu::noinline]] inline std::int32_t saturated(bool positive, std::uint32_t why) {
  raise_flag(why);
  return positive ? kRawMax : kRawMin;
}

/// a + b, a - b, -a, saturating.
[[gnu::always_inline]] inline std::int32_t add(std::int32_t a, std::int32_t b) {
  std::int32_t r;
  if (__builtin_add_overflow(a, b, &r)) [[unlikely]]
    return saturated(a >= 0, kOverflow);  // both of a's sign
  return r;
}
[[gnu::always_inline]] inline std::int32_t sub(std::int32_t a, std::int32_t b) {
  std::int32_t r;
  if (__builtin_sub_overflow(a, b, &r)) [[unlikely]]
    return saturated(a >= 0, kOverflow);  // a and -b of one sign
  return r;
}
[[gnu::always_inline]] inline std::int32_t neg(std::int32_t a) {
  if (a == kRawMin) [[unlikely]]
    return saturated(true, kOverflow);
  return -a;
}
/// round(v / 2^S) (half up), saturating: the rounding constant, a range check on the high word (the
/// result fits when it lies in [-2^(S-1), 2^(S-1))), and the middle 32 bits. The constant is added
/// modulo 2^64 (a v within 2^(S-1) of the top of the 64-bit range wraps to a negative high word,
/// which is out of range too); the direction of a saturation is v's sign.
template <int S>
[[gnu::always_inline]] inline std::int32_t round_shift(std::int64_t v) {
  const std::int64_t p = static_cast<std::int64_t>(static_cast<std::uint64_t>(v) + (std::uint64_t{1} << (S - 1)));
  const std::int32_t hi = static_cast<std::int32_t>(p >> 32);
  if (static_cast<std::uint32_t>(hi) + (1u << (S - 1)) >= (1u << S)) [[unlikely]]
    return saturated(v >= 0, kOverflow);
  return static_cast<std::int32_t>((static_cast<std::uint32_t>(p) >> S) | (static_cast<std::uint32_t>(hi) << (32 - S)));
}
/// round(a b / 2^S), saturating: one 32x32 -> 64-bit multiply, then round_shift.
template <int S>
[[gnu::always_inline]] inline std::int32_t mul_shift(std::int32_t a, std::int32_t b) {
  return round_shift<S>(static_cast<std::int64_t>(a) * static_cast<std::int64_t>(b));
}

/// A sum of products a_k b_k of Q<S> numbers, held exactly in 64 bits (Q<2S>) and rounded once at
/// the end: a dot product in fixed point has the error of one rounding, not one per product, and a
/// term costs a multiply-accumulate (SMLAL) instead of a rounded, range-checked product and a
/// saturating sum.
///
/// Why no term needs its own overflow check: each product is at most 2^62 in magnitude. A sum of up
/// to three of them that wraps around the 64-bit range lands at least 2^64 - 3 2^62 = 2^62 away
/// from zero, far beyond the 2^(31+S) that the final rounding accepts, so the rounding saturates
/// and raises kOverflow. From then on the running sum is checked after every second term to stay
/// below 2^62 (checkpoint(): a sum that passed cannot have wrapped, and two more terms cannot wrap
/// it unnoticed); a partial sum beyond 2^62, i.e. 2^(62-2S) in real units (2^24 for Q12.19),
/// raises kOverflow too. Nothing wraps silently.
template <int S>
struct ProductSum {
  std::int64_t acc = 0;
  /// acc + a b modulo 2^64 (the argument above says when that is exact).
  [[gnu::always_inline]] void mac(std::int32_t a, std::int32_t b) {
    acc = static_cast<std::int64_t>(static_cast<std::uint64_t>(acc) +
                                    static_cast<std::uint64_t>(static_cast<std::int64_t>(a) * b));
  }
  /// The term with index k (0, 1, 2, ...; a constant where the sum is unrolled): a checkpoint after
  /// terms 3, 5, 7, ...
  [[gnu::always_inline]] void add(int k, std::int32_t a, std::int32_t b) {
    mac(a, b);
    after_term(k);
  }
  /// The same with - a b.
  [[gnu::always_inline]] void sub(int k, std::int32_t a, std::int32_t b) {
    acc = static_cast<std::int64_t>(static_cast<std::uint64_t>(acc) -
                                    static_cast<std::uint64_t>(static_cast<std::int64_t>(a) * b));
    after_term(k);
  }
  /// The checkpoint schedule: after terms 3, 5, 7, ... (index k = 2, 4, 6, ...).
  [[gnu::always_inline]] void after_term(int k) {
    if (k >= 2 && (k & 1) == 0) checkpoint();
  }
  /// |acc| < 2^62, or kOverflow and acc held at 2^62 of its sign.
  [[gnu::always_inline]] void checkpoint() {
    const std::int32_t hi = static_cast<std::int32_t>(acc >> 32);
    if (static_cast<std::uint32_t>(hi) + (1u << 30) >= (1u << 31)) [[unlikely]]
      acc = overflowed(hi >= 0);
  }
  /// round(sum / 2^S), saturated (kOverflow) when it does not fit.
  [[gnu::always_inline]] std::int32_t rounded() const { return round_shift<S>(acc); }

 private:
  [[gnu::cold, gnu::noinline]] static std::int64_t overflowed(bool positive) {
    raise_flag(kOverflow);
    return positive ? (std::int64_t{1} << 62) : -(std::int64_t{1} << 62);
  }
};

/// a0 b0 + a1 b1 (+ a2 b2 ...) of Q<S> raw values with one rounding.
template <int S, class... P>
[[gnu::always_inline]] inline std::int32_t dot_raw(P... ab) {
  static_assert(sizeof...(P) % 2 == 0);
  ProductSum<S> s;
  const std::int32_t v[] = {ab...};
  [&]<int... K>(std::integer_sequence<int, K...>) { (s.add(K, v[2 * K], v[2 * K + 1]), ...); }
  (std::make_integer_sequence<int, sizeof...(P) / 2>{});
  return s.rounded();
}

/// Rounding arithmetic right shift by s >= 1 (round half up).
constexpr std::int64_t shift_round(std::int64_t v, int s) { return (v + (std::int64_t{1} << (s - 1))) >> s; }

/// Number of leading zero bits of a nonzero word.
inline int clz32(std::uint32_t v) { return __builtin_clz(v); }

/// floor(n / d) for a quotient that fits in 32 bits (n < 2^32 d): long division in two 16-bit
/// digits, each estimated by a 32-bit hardware division and corrected (Knuth, TAOCP vol. 2, 4.3.1,
/// algorithm D). Cortex-M3/M4 divide 32 by 32 bits in one instruction, 64 by 32 only in a slow
/// library routine; the host uses its native division. Both give the exact quotient.
inline std::uint32_t udiv64_32_digits(std::uint64_t n, std::uint32_t d) {
  const int s = clz32(d);
  d <<= s;  // normalised: top bit set, so each digit estimate is at most 2 too large
  const std::uint64_t ns = n << s;
  const std::uint32_t un1 = static_cast<std::uint32_t>(ns >> 32);
  const std::uint32_t un0 = static_cast<std::uint32_t>(ns);
  const std::uint32_t dh = d >> 16, dl = d & 0xFFFFu;
  const std::uint32_t n1 = un0 >> 16, n0 = un0 & 0xFFFFu;
  // High digit: (un1 : n1) / d.
  std::uint32_t q1 = un1 / dh, r = un1 - q1 * dh;
  while (q1 > 0xFFFFu || q1 * dl > ((r << 16) | n1)) {
    --q1;
    r += dh;
    if (r > 0xFFFFu) break;
  }
  const std::uint32_t rem = ((un1 << 16) | n1) - q1 * d;  // < d: exact modulo 2^32
  // Low digit: (rem : n0) / d.
  std::uint32_t q0 = rem / dh;
  r = rem - q0 * dh;
  while (q0 > 0xFFFFu || q0 * dl > ((r << 16) | n0)) {
    --q0;
    r += dh;
    if (r > 0xFFFFu) break;
  }
  return (q1 << 16) | q0;
}

inline std::uint32_t udiv64_32(std::uint64_t n, std::uint32_t d) {
#if defined(__arm__)
  if ((n >> 32) == 0) return static_cast<std::uint32_t>(n) / d;
  return udiv64_32_digits(n, d);
#else
  return static_cast<std::uint32_t>(n / d);
#endif
}

/// floor(sqrt(n)) for a 64-bit n, digit by digit.
inline std::uint64_t isqrt64(std::uint64_t n) {
  std::uint64_t res = 0, bit = std::uint64_t{1} << 62;
  while (bit > n) bit >>= 2;
  while (bit != 0) {
    if (n >= res + bit) {
      n -= res + bit;
      res = (res >> 1) + bit;
    } else {
      res >>= 1;
    }
    bit >>= 2;
  }
  return res;
}

/// round(sqrt(n)): floor, plus one when n - floor^2 > floor (then sqrt(n) > floor + 1/2).
inline std::uint64_t isqrt64_round(std::uint64_t n) {
  const std::uint64_t r = isqrt64(n);
  return n - r * r > r ? r + 1 : r;
}

/// Signed quotient a * 2^s / b, rounded half away from zero, saturated (kDivision) when it does
/// not fit in 32 bits or b == 0.
inline std::int32_t div_shifted(std::int64_t a, int s, std::int32_t b) {
  const bool neg = (a < 0) != (b < 0);
  if (b == 0) {
    raise_flag(kDivision);
    return a == 0 ? 0 : (neg ? kRawMin : kRawMax);
  }
  const std::uint64_t ua = a < 0 ? 0u - static_cast<std::uint64_t>(a) : static_cast<std::uint64_t>(a);
  const std::uint32_t d = b < 0 ? 0u - static_cast<std::uint32_t>(b) : static_cast<std::uint32_t>(b);
  const std::uint64_t n = (ua >> (62 - s)) != 0 ? ~std::uint64_t{0} : ua << s;  // < 2^62, or too big
  const std::uint64_t nr = n + (d >> 1);
  // The quotient floor(nr / d) must not exceed 2^31 - 1 (2^31 when negative).
  const std::uint64_t bound = (static_cast<std::uint64_t>(d) << 31) + (neg ? d : 0u);
  if (n == ~std::uint64_t{0} || nr >= bound) {
    raise_flag(kDivision);
    return neg ? kRawMin : kRawMax;
  }
  const std::uint32_t q = udiv64_32(nr, d);
  return neg ? static_cast<std::int32_t>(0u - q) : static_cast<std::int32_t>(q);
}

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
/// atan(i / 8) in Q30, i = 0..8 (mpmath, 200 bits; tests/test_fixed.cpp checks each).
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

/// Sticky flags raised since the last take_flags() (bits of Flag).
inline std::uint32_t flags() { return detail::g_flags; }
/// Returns the flags and clears them.
inline std::uint32_t take_flags() {
  const std::uint32_t f = detail::g_flags;
  detail::g_flags = 0;
  return f;
}

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

// ---------------------------------------------------------------- elementary functions
// Errors are against double evaluated at the same (quantised) argument, over the whole input
// range, in units of the result's last bit (LSB = 2^-F); tests/test_fixed.cpp measures them.

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

namespace osc {
/// The kernels' fixed-point scalar: Q12.19.
using Fixed = fixed::Q<19>;
/// Hardware units at the I/O boundary of a fixed-point controller: Q19.12.
using FixedIo = fixed::Q<12>;
}  // namespace osc

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
