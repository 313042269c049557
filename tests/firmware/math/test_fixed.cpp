// The fixed-point scalar (osc/kernels/fixed.hpp): rounding and saturation of every operation
// against exact integer arithmetic, the sticky flags, the elementary functions' stated maximum
// errors against double over their whole input range, Eigen's LU and LLT on 3x3 and 6x6, and the
// overflow fault through the control task (zero torque in the same tick).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "osc/runtime/control_task.hpp"
#include "test_util.hpp"

using namespace osc;
using fixed::Q;

namespace {

__extension__ using I128 = __int128;      // exact products and quotients for the reference
constexpr double kLsb = 1.0 / (1 << 19);  // of Fixed
constexpr std::int32_t kMax = INT32_MAX, kMin = INT32_MIN;

std::int32_t clamp32(I128 v) { return v > kMax ? kMax : (v < kMin ? kMin : static_cast<std::int32_t>(v)); }
/// floor(v / 2^s + 1/2): round half up, as the product rounds.
I128 round_shift(I128 v, int s) {
  const I128 d = I128(1) << s;
  I128 q = v / d;
  if (v - q * d < 0) --q;  // floor
  return (v - q * d) * 2 >= d ? q + 1 : q;
}
/// round(n / d) half away from zero.
I128 round_div(I128 n, I128 d) {
  const bool neg = (n < 0) != (d < 0);
  const I128 an = n < 0 ? -n : n, ad = d < 0 ? -d : d;
  const I128 q = (an + ad / 2) / ad;
  return neg ? -q : q;
}

struct Raws {
  std::mt19937_64 rng{20261124};
  /// A raw value of every magnitude: a random sign, bit length and mantissa.
  std::int32_t any() {
    const int bits = static_cast<int>(rng() % 32);
    std::int64_t v = static_cast<std::int64_t>(rng() & ((std::uint64_t{1} << bits) - 1));
    if (rng() & 1) v = -v;
    return static_cast<std::int32_t>(v);
  }
  std::int32_t uniform() { return static_cast<std::int32_t>(static_cast<std::uint32_t>(rng())); }
};

TEST(FixedArithmetic, EveryOperationRoundsAsExactArithmeticAndSaturatesWithTheFlag) {
  Raws r;
  for (int k = 0; k < 200000; ++k) {
    const std::int32_t a = k % 2 ? r.any() : r.uniform(), b = k % 3 ? r.any() : r.uniform();
    const Fixed x = Fixed::from_raw(a), y = Fixed::from_raw(b);
    auto check = [&](const char* op, Fixed got, I128 exact) {
      ASSERT_EQ(got.raw(), clamp32(exact)) << op << " a=" << a << " b=" << b;
    };
    fixed::take_flags();
    const Fixed s = x + y;
    const bool sat_s = (I128(a) + b) != s.raw();
    EXPECT_EQ(fixed::take_flags() != 0, sat_s);
    check("+", s, I128(a) + b);
    const Fixed d = x - y;
    EXPECT_EQ(fixed::take_flags() != 0, (I128(a) - b) != d.raw());
    check("-", d, I128(a) - b);
    const Fixed p = x * y;
    const I128 pe = round_shift(I128(a) * b, 19);
    EXPECT_EQ(fixed::take_flags() != 0, pe != p.raw());
    check("*", p, pe);
    if (b != 0) {
      const Fixed qt = x / y;
      const I128 qe = round_div(I128(a) << 19, b);
      EXPECT_EQ(fixed::take_flags() == fixed::kDivision, qe != qt.raw()) << a << " / " << b;
      check("/", qt, qe);
    }
  }
}

TEST(FixedArithmetic, EdgesOfTheRange) {
  fixed::take_flags();
  EXPECT_EQ((Fixed::max() + Fixed::lsb()).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ((-Fixed::min()).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ(fixed::abs(Fixed::min()).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ((Fixed(3000) * Fixed(2)).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  // Division by zero and by a near-zero.
  EXPECT_EQ((Fixed(1) / Fixed(0)).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kDivision);
  EXPECT_EQ((Fixed(-1) / Fixed(0)).raw(), kMin);
  EXPECT_EQ((Fixed(0) / Fixed(0)).raw(), 0);
  EXPECT_EQ(fixed::take_flags(), fixed::kDivision);
  EXPECT_EQ((Fixed(1) / Fixed::lsb()).raw(), kMax);  // 2^19 > 4096
  EXPECT_EQ(fixed::take_flags(), fixed::kDivision);
  EXPECT_EQ((Fixed(-4096) / Fixed(1)).raw(), kMin);  // exactly the bottom of the range: no flag
  EXPECT_EQ(fixed::take_flags(), 0u);
  // Conversions.
  EXPECT_EQ(Fixed(5000.0).raw(), kMax);
  EXPECT_EQ(Fixed(-1e9).raw(), kMin);
  EXPECT_EQ(Fixed(std::nan("")).raw(), 0);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow | fixed::kDomain);
  EXPECT_EQ(Fixed(5000).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ(Fixed(std::uint64_t{1} << 40).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ(FixedIo(Fixed::max()).raw(), 1 << 24);  // 4096 in Q19.12, rounded up from 4096 - 2^-19
  EXPECT_EQ(Fixed(FixedIo(5000)).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
  EXPECT_EQ(static_cast<std::int32_t>(Fixed(-2.75)), -2);  // truncation, as a float converts
  EXPECT_EQ(static_cast<std::int32_t>(Fixed(2.75)), 2);
  EXPECT_EQ(Fixed(0.5).raw(), 1 << 18);
  EXPECT_EQ(Fixed(-1.5 * kLsb).raw(), -2);  // half away from zero
  // The flag is sticky until taken.
  (void)(Fixed::max() * Fixed(2));
  (void)(Fixed(1) + Fixed(1));
  EXPECT_EQ(fixed::flags(), fixed::kOverflow);
  EXPECT_EQ(fixed::flags(), fixed::kOverflow);
  EXPECT_TRUE(math::take_arithmetic_fault<Fixed>());
  EXPECT_FALSE(math::take_arithmetic_fault<Fixed>());
  EXPECT_FALSE(math::take_arithmetic_fault<float>());
}

TEST(FixedArithmetic, ConversionsToFloatAndDoubleAreExactOrCorrectlyRounded) {
  Raws r;
  for (int k = 0; k < 100000; ++k) {
    const Fixed x = Fixed::from_raw(r.uniform());
    const double d = static_cast<double>(x);
    EXPECT_EQ(d * (1 << 19), static_cast<double>(x.raw()));
    EXPECT_EQ(static_cast<float>(x), static_cast<float>(d));
  }
  // The edges, and the ties of the rounding to 24 bits (even down, odd up), in three formats.
  for (std::int32_t raw :
       {1, -1, 2, INT32_MAX, INT32_MIN, INT32_MIN + 1, (1 << 24) - 1, 1 << 24, (1 << 24) + 1, (1 << 24) + 3,
        -((1 << 24) + 1), -((1 << 24) + 3), (1 << 30) + 64, (1 << 30) + 192, 0x7FFFFFC0, 0x7FFFFF40}) {
    EXPECT_EQ(static_cast<float>(Fixed::from_raw(raw)), static_cast<float>(static_cast<double>(Fixed::from_raw(raw))))
        << raw;
    EXPECT_EQ(static_cast<float>(FixedIo::from_raw(raw)),
              static_cast<float>(static_cast<double>(FixedIo::from_raw(raw))))
        << raw;
    EXPECT_EQ(static_cast<float>(fixed::Q<30>::from_raw(raw)),
              static_cast<float>(static_cast<double>(fixed::Q<30>::from_raw(raw))))
        << raw;
  }
  EXPECT_EQ(static_cast<float>(Fixed::from_raw(0)), 0.0f);
}

TEST(FixedArithmetic, MixedFormatProductAndIntegerQuotient) {
  Raws r;
  for (int k = 0; k < 100000; ++k) {
    const std::int32_t a = r.any(), b = r.any();
    fixed::take_flags();
    EXPECT_EQ((Fixed::from_raw(a) * FixedIo::from_raw(b)).raw(), clamp32(round_shift(I128(a) * b, 12)));
    const std::int32_t counts = static_cast<std::int32_t>(r.rng() % 400001) - 200000;
    if (b != 0) {
      const Fixed q = math::quotient<Fixed>(counts, FixedIo::from_raw(b));
      EXPECT_EQ(q.raw(), clamp32(round_div(I128(counts) << 31, b)));
    }
  }
  fixed::take_flags();
  // Sample counts to seconds: exact to the rounding, uptime-independent within the period.
  EXPECT_EQ(math::ratio<Fixed>(25000, 1000).raw(), 25 << 19);
  EXPECT_EQ(math::ratio<Fixed>(1, 1000).raw(), 524);  // 0.001 * 2^19 = 524.288
  EXPECT_EQ(math::ratio<Fixed>(2999, 1000).raw(), static_cast<std::int32_t>(std::lround(2.999 * (1 << 19))));
  EXPECT_EQ(fixed::take_flags(), 0u);
  EXPECT_EQ(math::ratio<float>(2999, 1000), 2999.0f * 1e-3f);  // as n dt for float
  EXPECT_EQ(math::ratio<double>(2999, 1000), 2999.0 * 1e-3);
}

TEST(FixedArithmetic, TargetDivisionRoutineIsExact) {
  std::mt19937_64 rng(7);
  auto check = [](std::uint64_t n, std::uint32_t d) {
    ASSERT_EQ(fixed::detail::udiv64_32_digits(n, d), static_cast<std::uint32_t>(n / d)) << n << " / " << d;
  };
  for (std::uint32_t d : {1u, 2u, 3u, 0xFFFFu, 0x10000u, 0x10001u, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFFu}) {
    check(0, d);
    check((static_cast<std::uint64_t>(d) << 32) - 1, d);  // the largest quotient
    check(static_cast<std::uint64_t>(d) << 31, d);
    check(d, d);
  }
  for (int k = 0; k < 2000000; ++k) {
    std::uint32_t d = static_cast<std::uint32_t>(rng()) >> (rng() % 32);
    if (d == 0) d = 1;
    const std::uint64_t n = rng() % (static_cast<std::uint64_t>(d) << 32);
    check(n, d);
  }
}

TEST(FixedArithmetic, TargetSquareRootIsExact) {
  // Against the digit-by-digit root and the definition r^2 <= n < (r + 1)^2 (in 128 bits).
  auto check = [](std::uint64_t n) {
    const std::uint64_t r = fixed::detail::isqrt64(n);
    ASSERT_EQ(r, fixed::detail::isqrt64_digits(n)) << n;
    const I128 r2 = static_cast<I128>(r) * static_cast<I128>(r), next = r2 + 2 * static_cast<I128>(r) + 1;
    ASSERT_TRUE(r2 <= static_cast<I128>(n) && static_cast<I128>(n) < next) << n;
  };
  // The 32-bit path: around every square (the root's steps) and every table cell, and a sweep.
  for (std::uint64_t s = 0; s <= 0x10000u; ++s)
    for (std::uint64_t n : {s * s - 1, s * s, s * s + 1})
      if (n <= 0xFFFFFFFFu) check(n);
  for (std::uint64_t cell = 16; cell <= 64; ++cell)
    for (int d = -2; d <= 2; ++d) check((cell << 26) + d);
  for (std::uint64_t n = 0; n <= 0xFFFFFFFFu; n += 997) check(n);
  // The 64-bit path: squares and their neighbours up to the top, powers of two, the words whose root
  // is 2^32 - 1, and random words of every length.
  for (std::uint64_t s = 0xFFFFFFFFu; s > 0xFFFFu; s -= 1 + s / 4096)
    for (std::uint64_t n : {s * s - 1, s * s, s * s + 1}) check(n);
  for (int e = 32; e < 64; ++e)
    for (int d = -2; d <= 2; ++d) check((std::uint64_t{1} << e) + static_cast<std::uint64_t>(d));
  for (std::uint64_t j = 0; j < 1000; ++j) check(~std::uint64_t{0} - j), check(0xFFFFFFFE00000001u - j);
  std::mt19937_64 rng(11);
  for (int k = 0; k < 1000000; ++k) check(rng() >> (rng() % 64));
}

// ---------------------------------------------------------------- elementary functions
/// Worst error in LSB of Fixed of f against g over the given raw arguments.
template <class F, class G>
double worst_lsb(const std::vector<std::int32_t>& args, F f, G g, double* where = nullptr) {
  double worst = 0;
  for (std::int32_t a : args) {
    const Fixed x = Fixed::from_raw(a);
    const double e = std::abs(static_cast<double>(f(x)) - g(static_cast<double>(x))) / kLsb;
    if (e > worst) {
      worst = e;
      if (where) *where = static_cast<double>(x);
    }
  }
  return worst;
}

/// Arguments over the whole range: uniform raws, every magnitude, and a dense sweep of [lo, hi].
std::vector<std::int32_t> arguments(double lo, double hi, int n = 400000) {
  Raws r;
  std::vector<std::int32_t> v;
  for (int k = 0; k < n; ++k) v.push_back(k % 2 ? r.uniform() : r.any());
  const std::int32_t a = Fixed(lo).raw(), b = Fixed(hi).raw();
  const std::int64_t step = std::max<std::int64_t>(1, (static_cast<std::int64_t>(b) - a) / n);
  for (std::int64_t x = a; x <= b; x += step) v.push_back(static_cast<std::int32_t>(x));
  v.push_back(kMax);
  v.push_back(kMin);
  v.push_back(0);
  return v;
}

// The stated maximum errors (docs/fixed_point.md), in LSB of Q12.19 (1.9e-6).
constexpr double kSinCosMaxLsb = 0.51;
constexpr double kSqrtMaxLsb = 0.5;
constexpr double kAtan2MaxLsb = 0.51;
constexpr double kAsinMaxLsb = 0.51;
constexpr double kExpMaxLsb = 0.51;  // plus kExpMaxRelative of the result
constexpr double kExpMaxRelative = 4e-9;

TEST(FixedFunctions, SinAndCosWithinTheirStatedErrorEverywhere) {
  const auto args = arguments(-40, 40);
  double at_s = 0, at_c = 0;
  const double es = worst_lsb(
      args, [](Fixed x) { return math::sin(x); }, [](double x) { return std::sin(x); }, &at_s);
  const double ec = worst_lsb(
      args, [](Fixed x) { return math::cos(x); }, [](double x) { return std::cos(x); }, &at_c);
  std::printf("sin: worst %.4f LSB at %.6f; cos: worst %.4f LSB at %.6f\n", es, at_s, ec, at_c);
  EXPECT_LE(es, kSinCosMaxLsb);
  EXPECT_LE(ec, kSinCosMaxLsb);
}

TEST(FixedFunctions, SqrtIsCorrectlyRounded) {
  const auto args = arguments(0, 10);
  double worst = 0;
  for (std::int32_t a : args) {
    if (a < 0) continue;
    const Fixed x = Fixed::from_raw(a);
    worst = std::max(worst, std::abs(static_cast<double>(math::sqrt(x)) - std::sqrt(static_cast<double>(x))) / kLsb);
  }
  std::printf("sqrt: worst %.4f LSB\n", worst);
  EXPECT_LE(worst, kSqrtMaxLsb);
  fixed::take_flags();
  EXPECT_EQ(math::sqrt(Fixed(-1)).raw(), 0);
  EXPECT_EQ(fixed::take_flags(), fixed::kDomain);
}

TEST(FixedFunctions, ExpWithinItsStatedErrorEverywhere) {
  const auto args = arguments(-20, 8.3);
  double worst = 0, at = 0;
  fixed::take_flags();
  for (std::int32_t a : args) {
    const Fixed x = Fixed::from_raw(a);
    const double want = std::exp(static_cast<double>(x));
    const Fixed got = math::exp(x);
    if (want >= 4096) {
      EXPECT_EQ(got.raw(), kMax) << static_cast<double>(x);
      EXPECT_EQ(fixed::take_flags(), fixed::kOverflow);
      continue;
    }
    const double e = (std::abs(static_cast<double>(got) - want) - kExpMaxRelative * want) / kLsb;
    if (e > worst) worst = e, at = static_cast<double>(x);
  }
  // e^x just below the top of the range.
  fixed::take_flags();
  EXPECT_NEAR(static_cast<double>(math::exp(Fixed(8.3))), std::exp(static_cast<double>(Fixed(8.3))),
              4e-9 * 4096 + kLsb);
  EXPECT_EQ(fixed::take_flags(), 0u);
  std::printf("exp: worst |error| - %.0e e^x = %.4f LSB at %.6f\n", kExpMaxRelative, worst, at);
  EXPECT_LE(worst, kExpMaxLsb);
}

TEST(FixedFunctions, Atan2WithinItsStatedErrorEverywhere) {
  Raws r;
  double worst = 0;
  for (int k = 0; k < 1000000; ++k) {
    const std::int32_t a = k % 3 ? r.any() : r.uniform(), b = k % 5 ? r.any() : r.uniform();
    const Fixed y = Fixed::from_raw(a), x = Fixed::from_raw(b);
    const double want = std::atan2(static_cast<double>(y), static_cast<double>(x));
    worst = std::max(worst, std::abs(static_cast<double>(math::atan2(y, x)) - want) / kLsb);
  }
  for (std::int32_t a : {0, 1, -1, kMax, kMin})
    for (std::int32_t b : {0, 1, -1, kMax, kMin}) {
      const double want = std::atan2(a * kLsb, b * kLsb);
      worst = std::max(
          worst, std::abs(static_cast<double>(math::atan2(Fixed::from_raw(a), Fixed::from_raw(b))) - want) / kLsb);
    }
  std::printf("atan2: worst %.4f LSB\n", worst);
  EXPECT_LE(worst, kAtan2MaxLsb);
  for (int i = 0; i <= 8; ++i) EXPECT_NEAR(fixed::detail::kAtanEighthsQ30[i], std::atan(i / 8.0) * (1 << 30), 0.5) << i;
}

TEST(FixedFunctions, AsinWithinItsStatedErrorOnItsWholeDomain) {
  double worst = 0, at = 0;
  for (std::int32_t a = -(1 << 19); a <= (1 << 19); ++a) {  // every argument in [-1, 1]
    const Fixed x = Fixed::from_raw(a);
    const double e = std::abs(static_cast<double>(math::asin(x)) - std::asin(static_cast<double>(x))) / kLsb;
    if (e > worst) worst = e, at = static_cast<double>(x);
  }
  std::printf("asin: worst %.4f LSB at %.7f\n", worst, at);
  EXPECT_LE(worst, kAsinMaxLsb);
  fixed::take_flags();
  EXPECT_EQ(math::asin(Fixed(1.5)), math::asin(Fixed(1)));
  EXPECT_EQ(fixed::take_flags(), fixed::kDomain);
}

// ---------------------------------------------------------------- Eigen
static_assert(Eigen::NumTraits<Fixed>::IsInteger == 0 && Eigen::NumTraits<Fixed>::IsSigned == 1);
static_assert(Eigen::NumTraits<Fixed>::epsilon() == Fixed::lsb());

TEST(FixedEigen, PartialPivLuAndLltSolveLikeDouble) {
  test::RandomStates rs;
  double worst_lu = 0, worst_llt = 0, worst_rcond = 0;
  for (int k = 0; k < 2000; ++k) {
    // 3x3 with entries in [-1, 1] and a condition number bounded by the diagonal shift.
    Mat3<double> A3 = Mat3<double>::Identity() * 1.5;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) A3(i, j) += 0.5 * rs.u(rs.rng);
    const Vec3<double> b3(rs.u(rs.rng), rs.u(rs.rng), rs.u(rs.rng));
    // 6x6 symmetric positive definite, eigenvalues in [0.1, 10] (like A(q) and Lambda).
    Mat6<double> M = Mat6<double>::Zero();
    for (int i = 0; i < 6; ++i) M.col(i) = rs.vec(1.0);
    const Mat6<double> A6 = 0.15 * M * M.transpose() + 0.1 * Mat6<double>::Identity();
    const Vec6<double> b6 = rs.vec(1.0);
    {
      test::NoMalloc guard;
      const Eigen::PartialPivLU<Mat3<Fixed>> lu(A3.cast<Fixed>());
      const Vec3<Fixed> x3 = lu.solve(b3.cast<Fixed>());
      const Vec3<Fixed> y3 = lu.transpose().solve(b3.cast<Fixed>());
      const Eigen::LLT<Mat6<Fixed>> llt(A6.cast<Fixed>());
      ASSERT_EQ(llt.info(), Eigen::Success);
      const Vec6<Fixed> x6 = llt.solve(b6.cast<Fixed>());
      const Eigen::PartialPivLU<Mat3<double>> lud(A3);
      worst_lu = std::max(worst_lu, (x3.cast<double>() - lud.solve(b3)).cwiseAbs().maxCoeff());
      worst_lu =
          std::max(worst_lu, (y3.cast<double>() - Vec3<double>(lud.transpose().solve(b3))).cwiseAbs().maxCoeff());
      worst_llt = std::max(worst_llt, (x6.cast<double>() - A6.llt().solve(b6)).cwiseAbs().maxCoeff());
      worst_rcond = std::max(worst_rcond, std::abs(static_cast<double>(lu.rcond()) - lud.rcond()));
    }
  }
  std::printf("Eigen in Q12.19: worst |x - x_double|: PartialPivLU 3x3 %.2e, LLT 6x6 %.2e; rcond %.2e\n", worst_lu,
              worst_llt, worst_rcond);
  EXPECT_LT(worst_lu, 1e-4);
  EXPECT_LT(worst_llt, 1e-3);
  EXPECT_LT(worst_rcond, 1e-4);
  EXPECT_EQ(fixed::take_flags(), 0u);
}

TEST(FixedEigen, ASingularMatrixRaisesTheFlagInsteadOfAnInfinity) {
  Mat3<Fixed> S = Mat3<Fixed>::Zero();
  S(0, 0) = Fixed(1);
  S(1, 1) = Fixed(1);
  fixed::take_flags();
  const Eigen::PartialPivLU<Mat3<Fixed>> lu(S);
  const Vec3<Fixed> x = lu.solve(Vec3<Fixed>(Fixed(1), Fixed(1), Fixed(1)));
  EXPECT_EQ(x(2).raw(), kMax);
  EXPECT_EQ(fixed::take_flags(), fixed::kDivision);
  Mat6<Fixed> N = Mat6<Fixed>::Identity();
  N(3, 3) = Fixed(-1);
  EXPECT_EQ(Eigen::LLT<Mat6<Fixed>>(N).info(), Eigen::NumericalIssue);
}

// ---------------------------------------------------------------- the fault
struct StillHal {
  std::int32_t written[kDof] = {1, 1, 1, 1, 1, 1};
  bool read_encoders(std::int32_t c[kDof]) {
    for (int i = 0; i < kDof; ++i) c[i] = 0;
    return true;
  }
  void write_dacs(const std::int32_t c[kDof]) { std::copy(c, c + kDof, written); }
  std::uint32_t cycles() { return 0; }
  std::uint32_t io_faults() { return 0; }
  void fault_output(bool) {}
  bool all_zero() const {
    for (int c : written)
      if (c != 0) return false;
    return true;
  }
};

TEST(FixedFault, AnOverflowInTheStepLatchesTheOverflowFaultWithZeroTorqueInTheSameTick) {
  auto task = std::make_unique<ControlTask<Fixed>>();
  task->init(Model<Fixed>::of(robot::kArm), Gains<Fixed>::paper(), FrictionMode::kAdaptive,
             joint_vector<Fixed>(robot::kQStart));
  StillHal hal;
  fixed::take_flags();
  for (int k = 0; k < 5; ++k) ASSERT_EQ(control_tick(*task, hal), 0u);
  EXPECT_FALSE(hal.all_zero());  // holding the arm against gravity
  EXPECT_EQ(task->sup.state, SupervisorState::kRun);
  task->state.obs.y(2) = Fixed(4000);  // an observer state that drives F beyond the range
  const std::uint32_t f = control_tick(*task, hal);
  EXPECT_EQ(f, static_cast<std::uint32_t>(kFaultOverflow)) << fault_name(f);
  EXPECT_EQ(task->last.status, static_cast<std::uint32_t>(kFaultOverflow));
  EXPECT_TRUE(hal.all_zero());
  EXPECT_EQ(task->sup.state, SupervisorState::kFault);
  EXPECT_EQ(task->sup.latched, static_cast<std::uint32_t>(kFaultOverflow));
  EXPECT_STREQ(fault_name(task->sup.latched), "overflow");
  control_tick(*task, hal);  // latched: zero from now on
  EXPECT_TRUE(hal.all_zero());
}

TEST(FixedFault, ASaturationOutsideTheStepIsLatchedInTheSameTickToo) {
  auto task = std::make_unique<ControlTask<Fixed>>();
  task->init(Model<Fixed>::of(robot::kArm), Gains<Fixed>::paper(), FrictionMode::kAdaptive,
             joint_vector<Fixed>(robot::kQStart));
  StillHal hal;
  fixed::take_flags();
  ASSERT_EQ(control_tick(*task, hal), 0u);
  (void)(Fixed::max() + Fixed(1));  // e.g. in the I/O layer between two ticks
  EXPECT_EQ(control_tick(*task, hal), static_cast<std::uint32_t>(kFaultOverflow));
  EXPECT_TRUE(hal.all_zero());
}

}  // namespace
