// Saturating integer arithmetic under the fixed-point scalar (osc/math/q.hpp): the sticky
// arithmetic flags, saturation to 32 bits, rounding shifts and products, exact sums of products in
// 64 bits, 64-by-32-bit division and integer square roots. Every routine here works on raw integers;
// a result that does not fit saturates and raises a flag, never wraps silently.
#pragma once

#include <climits>
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

/// ceil(sqrt((i + 1) 2^26)) for i = 16 .. 63: at least the root of any 32-bit word whose top six
/// bits are i, within 2^10 + 1 of it (isqrt_top's first estimate).
struct SqrtTop {
  std::uint32_t v[48]{};
  constexpr SqrtTop() {
    for (int i = 16; i < 64; ++i) {
      const std::uint64_t n = static_cast<std::uint64_t>(i + 1) << 26;
      std::uint64_t lo = 0, hi = std::uint64_t{1} << 17;  // the least s with s^2 >= n, by bisection
      while (lo < hi) {
        const std::uint64_t mid = (lo + hi) / 2;
        if (mid * mid >= n)
          hi = mid;
        else
          lo = mid + 1;
      }
      v[i - 16] = static_cast<std::uint32_t>(lo);
    }
  }
};
inline constexpr SqrtTop kSqrtTop{};

/// floor(sqrt(h)) for h in [2^30, 2^32): the table's estimate (above the root by at most 2^10 + 1),
/// two Newton steps from above in 32 bits (the error e becomes at most e^2 / 2^16 + 1: 17, then 1),
/// and one correction. Each step is one hardware division on the targets. Exact for every h: checked
/// for all 2^32 words once, and in test_saturating_int around every square and table cell.
inline std::uint32_t isqrt_top(std::uint32_t h) {
  std::uint32_t s = kSqrtTop.v[(h >> 26) - 16];
  s = (s + h / s) >> 1;
  s = (s + h / s) >> 1;
  return static_cast<std::uint64_t>(s) * s > h ? s - 1 : s;
}

/// floor(sqrt(n)) for a 64-bit n. With m = n 4^k normalised (its top word in [2^30, 2^32)),
/// floor(sqrt(n)) = floor(sqrt(m)) >> k. The top word's root s1 (isqrt_top) gives
/// x0 = (s1 + 1) 2^16, at most 2^16 above sqrt(m) >= 2^31; one Newton step from above,
/// x1 = floor((x0 + floor(m / x0)) / 2), is then at least floor(sqrt(m)) (as every such step) and
/// at most sqrt(m) + (x0 - sqrt(m))^2 / (2 x0) <= sqrt(m) + 1, so one correction ends it. One
/// 64-by-32-bit division instead of the 31 steps of 64-bit arithmetic of the digit-by-digit root
/// (on the Cortex-M3 about 370 instructions, a sixth of the stream follower's tick).
inline std::uint64_t isqrt64(std::uint64_t n) {
  const std::uint32_t top = static_cast<std::uint32_t>(n >> 32);
  if (top == 0) {
    const std::uint32_t lo = static_cast<std::uint32_t>(n);
    if (lo == 0) return 0;
    const int k = clz32(lo) / 2;
    return isqrt_top(lo << (2 * k)) >> k;
  }
  const int k = clz32(top) / 2;
  const std::uint64_t m = n << (2 * k);
  const std::uint32_t s1 = isqrt_top(static_cast<std::uint32_t>(m >> 32));
  // (s1 + 1) 2^16 = 2^32 does not fit: 2^32 - 1 is then above sqrt(m), but for the m whose root is
  // itself 2^32 - 1.
  constexpr std::uint64_t kTopSquare = 0xFFFFFFFE00000001u;  // (2^32 - 1)^2
  if (s1 == 0xFFFFu && m >= kTopSquare) return std::uint64_t{0xFFFFFFFFu} >> k;
  const std::uint32_t x0 = s1 == 0xFFFFu ? 0xFFFFFFFFu : (s1 + 1) << 16;
  const std::uint32_t q = udiv64_32(m, x0);  // <= sqrt(m) < 2^32: fits
  std::uint32_t x = (x0 >> 1) + (q >> 1) + (x0 & q & 1u);
  if (static_cast<std::uint64_t>(x) * x > m) --x;
  return x >> k;
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
}  // namespace detail

/// Sticky flags raised since the last take_flags() (bits of Flag).
inline std::uint32_t flags() { return detail::g_flags; }
/// Returns the flags and clears them.
inline std::uint32_t take_flags() {
  const std::uint32_t f = detail::g_flags;
  detail::g_flags = 0;
  return f;
}
/// Sets the flags back to f (what take_flags() returned before a computation whose own flags were
/// taken apart: a command's planning outside the control tick, whose saturations are its refusal,
/// not the tick's fault).
inline void restore_flags(std::uint32_t f) { detail::g_flags = f; }

}  // namespace osc::fixed
