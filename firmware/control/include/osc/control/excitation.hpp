// The excitation motion of an identification run (issue 57): a periodic Fourier series per joint
// (Swevers et al. 1997), planned on the board about the pose the arm rests at, and checked in full
// before it starts, so that a motion that does not fit is refused by name, not stopped halfway.
// Joint space; allocation-free; templated on the scalar (double, float, osc::Fixed).
//
// The series. With w = 2 pi / T (T = params::kExcitationPeriod) and k = 1 .. N (kExcitationHarmonics),
// joint i's reference is
//   q_i(t)    = q0_i + sum_k (a_ik / (k w)) sin(k w t) - (b_ik / (k w)) cos(k w t)
//   qd_i(t)   =        sum_k  a_ik cos(k w t) + b_ik sin(k w t)
//   qdd_i(t)  =        sum_k  k w (b_ik cos(k w t) - a_ik sin(k w t))
//   qddd_i(t) =       -sum_k  (k w)^2 (a_ik cos(k w t) + b_ik sin(k w t))
// each the exact derivative of the one before (the sampler evaluates the first three). At t = 0, and
// at every whole period,
//   q - q0 = -sum_k b_ik / (k w),   qd = sum_k a_ik,   qdd = w sum_k k b_ik,   qddd = -w^2 sum_k k^2 a_ik,
// so the four constraints on each joint's coefficients
//   sum_k a_ik = 0,   sum_k k^2 a_ik = 0,   sum_k b_ik / k = 0,   sum_k k b_ik = 0               (C)
// make the motion start at rest at q0 and, after a whole number of periods, end there at rest
// (q = q0, qd = qdd = 0), without a step in the jerk either, so that the torque rises smoothly from
// the holding torque. No offset term and no window: q0 is the series' mean, and every period is the
// same motion (Swevers' reason for a periodic excitation). (C) leaves three of five coefficients free.
//
// The design (params::kExcitationCos, kExcitationSin; declared once, checked against (C) below).
// Joints 1, 3, 5 move with cosines only (their velocities even in t), joints 2, 4, 6 with sines only
// (odd): over a period a cosine joint's velocity is orthogonal to a sine joint's, whatever the
// coefficients. Within each group the three rows are small-integer solutions of (C) chosen for little
// travel per speed (a swing each way of at most 0.49 rad per rad/s of peak speed: 0.65 rad at
// 1.31 rad/s) and little correlation between them: the six velocities' correlations are at most 0.60,
// their Gram matrix's eigenvalues 0.36 to 2.1 (test_excitation.cpp). The two aims pull apart: the
// least travel per speed puts the power on the 4th and 5th harmonics, where joints become alike. Each
// joint has its own spectrum, so no two move in phase. The rows are shapes: the plan scales each.
//
// Fitting the design (ExcitationMotion::plan). Joint i's row is scaled by the largest gain g_i that
// keeps its peak speed within kExcitationPlanFill of its speed bound and its swing each way within that
// fill of the room between q0 and its limits less kExcitationPositionMargin (the row's peaks over a
// period's samples at the control rate, in the scalar itself). A joint that starts within the margin,
// or whose room cuts its gain below kExcitationMinScale of the speed's, refuses the motion (out of
// workspace). The torque and the singularities are the check's: prepare_excitation plans and checks at the
// largest scale of every gain, of 1, s, s^2, ... (s = kExcitationScaleStep, while at least kExcitationMinScale),
// that passes: full scale, then the rest by halving their range (a smaller swing passes where a larger one does:
// its speeds, torques and room; where the loop's or the singularity test does not, a smaller scale that passed is
// kept, and every run is checked in full at its scale). None: refused with the last check's (the smallest's) reason.
//
// The check (check_excitation) samples every tick the controller would be given: tick n of the motion
// is tick n mod P of its period (P = T params::kControlHz, ExcitationMotion::at_tick), so the ticks
// 0 .. P (the last, the next period's first) are every tick of the run, bit for bit. At each, in order:
//   kOutOfWorkspace  a joint outside its limits less kExcitationPositionMargin;
//   kOverLimit       a joint's |qd| above its speed bound (kExcitationMaxSpeed or the drive's, whichever
//                    is lower, less kExcitationSpeedMargin);
//   kNearSingular    path_check's test (near_singular): the analytic Jacobian's reciprocal condition in
//                    the controller's orientation coordinates relative to R_ref below kPathMinRcond, or a
//                    singularity crossed since the sample before (the controller acts through J^-1
//                    whatever the motion's coordinates: a joint-space motion needs it as a move does);
//   kUnstableLoop    with the task's gains given, path_check's sampled-loop test (unstable_loop);
//   kOverLimit       a joint's |tau| + |tau_f| above kExcitationTorqueFraction of its torque limit:
//                    tau = A qdd + c + g (rnea, armature included), tau_f the friction (2) at the band's
//                    top without decay, the strongest the arm may have; the other 20 % is the controller's.
// The refusals are a move's (osc/runtime/motion_states.hpp: out_of_workspace, over_limit, near_singular,
// unstable_loop). Cost: per tick of the check (P + 1 = 10 001) a forward kinematics, the Jacobians'
// factors and a Newton-Euler pass (and the loop's test), at most four checks (the seven scales of 0.9: 1 and
// three halvings); when the command is
// prepared, outside the tick. In fixed point the flags raised before it are kept, its own discarded.
#pragma once

#include <array>
#include <cstdint>

#include "osc/control/params.hpp"
#include "osc/control/path_check.hpp"
#include "osc/kernels/dynamics.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/robot.hpp"

namespace osc {

/// Why a motion was refused (kOk: it fits): the first failure met.
enum class ExcitationStatus : std::uint8_t {
  kOk = 0,
  kOutOfWorkspace,  ///< a joint within kExcitationPositionMargin of a limit, or too close to one to swing
  kNearSingular,    ///< the Jacobian's reciprocal condition below kPathMinRcond, or a singularity crossed
  kOverLimit,       ///< a joint's speed or torque over its bound
  kUnstableLoop     ///< the sampled closed loop at the task's gains not stable at a sample (path_check's test)
};

namespace excitation {
constexpr int kHarmonics = params::kExcitationHarmonics;
/// The series' basis: sin(k w t), then cos(k w t), k = 1 .. N.
constexpr int kBasis = 2 * kHarmonics;
/// One period in control ticks, and the whole run.
constexpr std::uint32_t kPeriodTicks = static_cast<std::uint32_t>(params::kExcitationPeriod * params::kControlHz);
constexpr std::uint64_t kTicks = std::uint64_t{kPeriodTicks} * params::kExcitationPeriods;
/// The base angular frequency w [rad/s].
constexpr double kOmega = 2 * kPi / params::kExcitationPeriod;
static_assert(abs_of(kPeriodTicks - params::kExcitationPeriod * params::kControlHz) < 1e-9,
              "a period is a whole number of ticks");
static_assert(params::kExcitationPeriods * params::kExcitationPeriod <= params::kExcitationMaxDuration,
              "the run within its longest");
static_assert(params::kExcitationPositionMargin >= params::kWorkspaceMargin, "within a move's margin at least");
static_assert(params::kExcitationMinScale > 0 && params::kExcitationMinScale <= 1 && params::kExcitationScaleStep > 0 &&
                  params::kExcitationScaleStep < 1,
              "the bounded cut");

/// The check's tries: scale factors 1, step, step^2, ... while at least kExcitationMinScale.
constexpr int attempts() {
  int n = 0;
  for (double s = 1; s >= params::kExcitationMinScale; s *= params::kExcitationScaleStep) ++n;
  return n;
}
constexpr int kAttempts = attempts();
/// The scale of try k: kExcitationScaleStep^k, multiplied out in S (the same rounding at every call).
template <class S>
S scale_of(int k) {
  S scale(1);
  for (int i = 0; i < k; ++i) scale *= lit<S>(params::kExcitationScaleStep);
  return scale;
}

/// Whether every row of the design solves (C) and moves (its sums exact: small integers).
constexpr bool design_valid() {
  for (int i = 0; i < kDof; ++i) {
    double a0 = 0, a2 = 0, b_1 = 0, b1 = 0, power = 0;
    for (int k = 1; k <= kHarmonics; ++k) {
      const double a = params::kExcitationCos[i][k - 1], b = params::kExcitationSin[i][k - 1];
      a0 += a, a2 += k * k * a, b_1 += b / k, b1 += k * b, power += a * a + b * b;
    }
    if (!(a0 == 0 && a2 == 0 && abs_of(b_1) < 1e-12 && b1 == 0 && power > 0)) return false;
  }
  return true;
}
static_assert(design_valid(), "every joint's row solves (C): at rest at q0 at every whole period, and moves");

template <class S>
using Basis = Eigen::Matrix<S, kBasis, 1>;
template <class S>
using Coefficients = Eigen::Matrix<S, kDof, kBasis>;

/// [sin(k theta); cos(k theta)], k = 1 .. N: one sincos, then the angle sums
/// sin((k + 1) theta) = sin(k theta) cos theta + cos(k theta) sin theta (and its cosine), each rounded
/// once in fixed point.
template <class S>
Basis<S> basis(S theta) {
  constexpr int N = kHarmonics;
  S s1, c1;
  math::sincos(theta, s1, c1);
  Basis<S> h;
  h(0) = s1, h(N) = c1;
  for (int k = 1; k < N; ++k) {
    h(k) = math::sum_of_products(h(k - 1), c1, h(N + k - 1), s1);
    h(N + k) = math::dot2_minus(h(N + k - 1), c1, h(k - 1), s1);
  }
  return h;
}

/// The basis at tick n of a period (n < P): theta = 2 pi n / P from the integer count.
template <class S>
Basis<S> basis_at_tick(std::uint32_t n) {
  return basis<S>(lit<S>(2 * kPi) * math::ratio<S>(n, kPeriodTicks));
}

/// The design's rows with every gain 1 on the basis, in double at compile time: position (rad), velocity
/// (rad/s) and acceleration (rad/s^2) coefficients, row i the joint's, k w the harmonic's angular frequency:
///   p: a_k / (k w) on sin, -b_k / (k w) on cos;  v: b_k on sin, a_k on cos;  a: -k w a_k on sin, k w b_k on cos.
struct UnitSeries {
  double p[kDof * kBasis], v[kDof * kBasis], a[kDof * kBasis];
};
constexpr UnitSeries unit_series() {
  UnitSeries u{};
  for (int i = 0; i < kDof; ++i)
    for (int k = 1; k <= kHarmonics; ++k) {
      const double ca = params::kExcitationCos[i][k - 1], cb = params::kExcitationSin[i][k - 1], kw = k * kOmega;
      const int sn = i * kBasis + k - 1, cs = sn + kHarmonics;  // the entries on sin(k w t) and cos(k w t)
      u.p[sn] = ca / kw, u.p[cs] = -cb / kw;
      u.v[sn] = cb, u.v[cs] = ca;
      u.a[sn] = -ca * kw, u.a[cs] = cb * kw;
    }
  return u;
}
constexpr UnitSeries kUnit = unit_series();
/// ... in the scalar (converted at compile time, as every table the firmware indexes at run time).
template <class S>
constexpr std::array<S, kDof * kBasis> kUnitP = lit_array<S>(kUnit.p);
template <class S>
constexpr std::array<S, kDof * kBasis> kUnitV = lit_array<S>(kUnit.v);
template <class S>
constexpr std::array<S, kDof * kBasis> kUnitA = lit_array<S>(kUnit.a);

/// The design's rows, each times its joint's gain.
template <class S>
struct Series {
  using Rows = Eigen::Map<const Eigen::Matrix<S, kDof, kBasis, Eigen::RowMajor>>;
  Coefficients<S> p = Coefficients<S>::Zero(), v = Coefficients<S>::Zero(), a = Coefficients<S>::Zero();

  static Series of(const Vec6<S>& gain) {
    return {gain.asDiagonal() * Rows(kUnitP<S>.data()), gain.asDiagonal() * Rows(kUnitV<S>.data()),
            gain.asDiagonal() * Rows(kUnitA<S>.data())};
  }
};

/// The configured limits in double at compile time (ExcitationLimits::defaults, which says what each is).
struct LimitTable {
  double q_min[kDof], q_max[kDof], speed[kDof], torque[kDof], vis[kDof], breakaway[kDof];
};
constexpr LimitTable limit_table() {
  LimitTable t{};
  for (int i = 0; i < kDof; ++i) {
    const double v = robot::kDrives.max_joint_speed[i];
    t.q_min[i] = robot::kArm.q_min[i] + params::kExcitationPositionMargin;
    t.q_max[i] = robot::kArm.q_max[i] - params::kExcitationPositionMargin;
    t.speed[i] = (v < params::kExcitationMaxSpeed ? v : params::kExcitationMaxSpeed) - params::kExcitationSpeedMargin;
    t.torque[i] = params::kExcitationTorqueFraction * robot::kDrives.torque_limit[i];
    t.vis[i] = robot::kModelErrorBounds.friction_hi.vis[i];
    t.breakaway[i] = robot::kModelErrorBounds.friction_hi.cou[i] + robot::kModelErrorBounds.friction_hi.sti[i];
  }
  return t;
}
constexpr LimitTable kLimits = limit_table();

/// The design's peaks over a period (gains 1): each joint's largest |qd|, and its swing up and down
/// from q0 (both >= 0).
template <class S>
struct Peaks {
  Vec6<S> speed = Vec6<S>::Zero(), up = Vec6<S>::Zero(), down = Vec6<S>::Zero();
};

template <class S>
Peaks<S> design_peaks() {
  const Series<S> unit = Series<S>::of(Vec6<S>::Ones());
  Peaks<S> pk;
  for (std::uint32_t n = 0; n < kPeriodTicks; ++n) {
    const Basis<S> h = basis_at_tick<S>(n);
    const Vec6<S> dq = unit.p * h, qd = unit.v * h;
    for (int i = 0; i < kDof; ++i) {
      if (math::abs(qd(i)) > pk.speed(i)) pk.speed(i) = math::abs(qd(i));
      if (dq(i) > pk.up(i)) pk.up(i) = dq(i);
      if (-dq(i) > pk.down(i)) pk.down(i) = -dq(i);
    }
  }
  return pk;
}
}  // namespace excitation

/// A joint-space reference: angles [rad], velocities [rad/s], accelerations [rad/s^2].
template <class S>
struct JointSample {
  Vec6<S> q, qd, qdd;
};

/// What the motion must keep to: the reference's joint angles within [q_min, q_max], its speeds within
/// speed, and |tau| + |tau_f(qd)| within torque (friction: the strongest friction the arm may have). The
/// configured ones: the joint limits less kExcitationPositionMargin; kExcitationMaxSpeed or the drive's
/// plausible speed, whichever is lower, less kExcitationSpeedMargin; kExcitationTorqueFraction of the
/// drive's torque limit; the model-error band's top, its Coulomb and Stribeck levels summed (no decay).
template <class S>
struct ExcitationLimits {
  Vec6<S> q_min, q_max, speed, torque;
  FrictionParams<S> friction;

  static ExcitationLimits defaults() {
    using excitation::kLimits;
    static constexpr std::array<S, kDof> kQMin = lit_array<S>(kLimits.q_min), kQMax = lit_array<S>(kLimits.q_max);
    static constexpr std::array<S, kDof> kSpeed = lit_array<S>(kLimits.speed), kTorque = lit_array<S>(kLimits.torque);
    static constexpr std::array<S, kDof> kVis = lit_array<S>(kLimits.vis), kBreak = lit_array<S>(kLimits.breakaway);
    ExcitationLimits l;
    for (int i = 0; i < kDof; ++i) {
      l.q_min(i) = kQMin[i], l.q_max(i) = kQMax[i], l.speed(i) = kSpeed[i], l.torque(i) = kTorque[i];
      l.friction.vis(i) = kVis[i], l.friction.cou(i) = kBreak[i], l.friction.sti(i) = S(0), l.friction.dec(i) = S(0);
    }
    return l;
  }
};

/// The planned motion: the design fitted about q0, sampled by tick or by time.
template <class S>
class ExcitationMotion {
 public:
  /// Fits the design about q0, the arm at rest there, under lim (the file comment's "Fitting the
  /// design"); the gains at full scale (set_scale). kOutOfWorkspace names its joint in refused_joint().
  ExcitationStatus plan(const Vec6<S>& q0, const ExcitationLimits<S>& lim) {
    using namespace excitation;
    const Peaks<S> pk = design_peaks<S>();
    const S fill = lit<S>(params::kExcitationPlanFill), least = lit<S>(params::kExcitationMinScale);
    q0_ = q0;
    refused_ = -1;
    for (int i = 0; i < kDof; ++i) {
      const S up = lim.q_max(i) - q0(i), down = q0(i) - lim.q_min(i);
      speed_gain_(i) = fill * lim.speed(i) / pk.speed(i);
      S g = speed_gain_(i);
      if (pk.up(i) > S(0) && fill * up < g * pk.up(i)) g = fill * up / pk.up(i);
      if (pk.down(i) > S(0) && fill * down < g * pk.down(i)) g = fill * down / pk.down(i);
      fit_gain_(i) = g;
      if (refused_ < 0 && !(up >= S(0) && down >= S(0) && g >= least * speed_gain_(i))) refused_ = i;
    }
    set_scale(S(1));
    return refused_ < 0 ? ExcitationStatus::kOk : ExcitationStatus::kOutOfWorkspace;
  }

  /// Every joint's gain at `scale` times the fitted one (prepare_excitation's retries).
  void set_scale(S scale) {
    scale_ = scale;
    series_ = excitation::Series<S>::of(Vec6<S>(fit_gain_ * scale));
  }

  /// The reference at tick n since the start: n mod P of the period (exactly q0 at rest at every
  /// whole period), and q0 at rest from the end (ticks()) on.
  JointSample<S> at_tick(std::uint64_t n) const {
    const std::uint32_t phase = static_cast<std::uint32_t>(n % excitation::kPeriodTicks);
    if (n >= excitation::kTicks || phase == 0) return rest();
    return sample(excitation::basis_at_tick<S>(phase));
  }
  /// The reference at time t [s] since the start (t reduced to its period by whole periods, exact in
  /// every scalar; q0 at rest before the start, at every whole period and from the end on).
  JointSample<S> at(S t) const {
    const S period = lit<S>(params::kExcitationPeriod);
    if (!(t > S(0) && t < duration())) return rest();
    while (t >= period) t -= period;
    if (!(t > S(0))) return rest();
    return sample(excitation::basis<S>(lit<S>(excitation::kOmega) * t));
  }

  std::uint64_t ticks() const { return excitation::kTicks; }
  S duration() const { return lit<S>(params::kExcitationPeriods * params::kExcitationPeriod); }
  const Vec6<S>& start() const { return q0_; }
  /// Each joint's gain on its design row: at its speed bound (less the fill), after its travel, as
  /// sampled (after the scale).
  const Vec6<S>& speed_gain() const { return speed_gain_; }
  const Vec6<S>& fit_gain() const { return fit_gain_; }
  S scale() const { return scale_; }
  /// The first joint plan() refused (-1: none).
  int refused_joint() const { return refused_; }

 private:
  JointSample<S> rest() const { return {q0_, Vec6<S>::Zero(), Vec6<S>::Zero()}; }
  JointSample<S> sample(const excitation::Basis<S>& h) const {
    return {q0_ + series_.p * h, series_.v * h, series_.a * h};
  }

  Vec6<S> q0_ = Vec6<S>::Zero(), speed_gain_ = Vec6<S>::Zero(), fit_gain_ = Vec6<S>::Zero();
  S scale_ = S(1);
  excitation::Series<S> series_;
  int refused_ = -1;
};

}  // namespace osc

// The check and the preparation (check_excitation, prepare_excitation), in their own header.
#include "osc/control/excitation_check.hpp"
