// The tick's monitors (osc/runtime/monitors.hpp), each alone against its rule written out from
// docs/safety.md and params::, in double, float and fixed point; and the tick's stage timing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <utility>

#include "osc/runtime/control_task.hpp"

using namespace osc;

namespace {

template <class S>
class Monitors : public ::testing::Test {};
using Scalars = ::testing::Types<double, float, Fixed>;
TYPED_TEST_SUITE(Monitors, Scalars);

TEST(EncoderRange, LimitsPlusTheMarginRoundedOutwards) {
  EncoderRangeMonitor m;
  const double c = 1000;  // counts per radian
  for (int i = 0; i < kDof; ++i) m.set(i, 0.25, c);
  for (int i = 0; i < kDof; ++i) {
    // The rule: (q_min - margin - q0) c, truncated, less one; likewise above.
    const double lo = (robot::kArm.q_min[i] - params::kJointLimitMargin - 0.25) * c;
    const double hi = (robot::kArm.q_max[i] + params::kJointLimitMargin - 0.25) * c;
    EXPECT_LE(m.min_counts[i], std::floor(lo));
    EXPECT_GE(m.min_counts[i], std::floor(lo) - 2);
    EXPECT_GE(m.max_counts[i], std::ceil(hi));
    EXPECT_LE(m.max_counts[i], std::ceil(hi) + 2);
  }
  std::int32_t counts[kDof] = {};
  EXPECT_EQ(m.check(counts), 0u);
  for (int i = 0; i < kDof; ++i) {
    std::int32_t at[kDof] = {};
    at[i] = static_cast<std::int32_t>(m.max_counts[i]);
    EXPECT_EQ(m.check(at), 0u) << i;
    at[i] += 1;
    EXPECT_EQ(m.check(at), kFaultEncoderRange) << i;
    at[i] = static_cast<std::int32_t>(m.min_counts[i]);
    EXPECT_EQ(m.check(at), 0u) << i;
    at[i] -= 1;
    EXPECT_EQ(m.check(at), kFaultEncoderRange) << i;
  }
}

TEST(EncoderJump, TheSpeedLimitOverTheTicksSinceTheLastSample) {
  EncoderJumpMonitor m;
  m.reset();
  for (int i = 0; i < kDof; ++i) m.set(i, counts_per_rad(i));
  for (int i = 0; i < kDof; ++i)  // speed limit x 1 ms x counts/rad, + 1
    EXPECT_EQ(m.max_step[i],
              static_cast<std::int32_t>(robot::kDrives.max_joint_speed[i] * 1e-3 * counts_per_rad(i)) + 1);
  std::int32_t c[kDof] = {100, -100, 5, 0, 7, 1 << 30};
  bool moved[kDof] = {};
  m.tick();
  EXPECT_EQ(m.check(c, moved), 0u);  // the first sample: anything within range is fine
  EXPECT_TRUE(m.have_counts);
  for (bool b : moved) EXPECT_TRUE(b);  // the monitors start here
  m.tick();
  c[1] += m.max_step[1];
  EXPECT_EQ(m.check(c, moved), 0u);
  EXPECT_TRUE(moved[1]);
  EXPECT_FALSE(moved[0]);
  // Two ticks, one of them without a sample: twice the step is plausible, one count more is not.
  m.tick();
  m.tick();
  EXPECT_EQ(m.age, 2u);
  c[2] -= 2 * m.max_step[2];
  EXPECT_EQ(m.check(c, moved), 0u);
  m.tick();
  c[2] -= m.max_step[2] + 1;
  EXPECT_EQ(m.check(c, moved), kFaultEncoderJump);
  EXPECT_EQ(m.age, 0u);
  // A wrap of the 32-bit count is a jump, not a small step.
  m.tick();
  c[5] = std::numeric_limits<std::int32_t>::min();
  std::int32_t before[kDof];
  std::copy(c, c + kDof, before);
  m.tick();
  before[5] = std::numeric_limits<std::int32_t>::max();
  EXPECT_EQ(m.check(before, moved), kFaultEncoderJump);
  EXPECT_EQ(m.check(c, moved), kFaultEncoderJump);
}

TEST(Saturation, ConsecutiveClippedTicks) {
  SaturationMonitor m;
  m.reset();
  for (int k = 1; k < params::kSaturationTicks; ++k) ASSERT_EQ(m.check(3, true), 0u) << k;
  EXPECT_EQ(m.check(3, false), 0u);  // one unclipped tick starts the count again
  for (int k = 1; k < params::kSaturationTicks; ++k) ASSERT_EQ(m.check(3, true), 0u) << k;
  EXPECT_EQ(m.check(3, true), kFaultSaturation);
  EXPECT_EQ(m.check(2, true), 0u);  // per joint
}

TYPED_TEST(Monitors, TrackingLimits) {
  using S = TypeParam;
  const double lp = params::kTrackingLimitPosition, lo = params::kTrackingLimitOrientation;
  auto check = [](double x, double y, double z, double a, double b, double c) {
    Vec6<S> e;
    e << lit<S>(x), lit<S>(y), lit<S>(z), lit<S>(a), lit<S>(b), lit<S>(c);
    return TrackingMonitor<S>::check(e);
  };
  EXPECT_EQ(check(0, 0, 0, 0, 0, 0), 0u);
  // The translation's norm: 0.99 lp along a diagonal is in, 1.01 lp out.
  const double d = 1 / std::sqrt(3.0);
  EXPECT_EQ(check(0.99 * lp * d, -0.99 * lp * d, 0.99 * lp * d, 0, 0, 0), 0u);
  EXPECT_EQ(check(1.01 * lp * d, -1.01 * lp * d, 1.01 * lp * d, 0, 0, 0), kFaultTracking);
  // Each orientation component alone.
  for (int i = 3; i < 6; ++i) {
    double v[6] = {0, 0, 0, 0, 0, 0};
    v[i] = -0.99 * lo;
    EXPECT_EQ(check(v[0], v[1], v[2], v[3], v[4], v[5]), 0u) << i;
    v[i] = -1.01 * lo;
    EXPECT_EQ(check(v[0], v[1], v[2], v[3], v[4], v[5]), kFaultTracking) << i;
  }
}

TYPED_TEST(Monitors, ThetaBand) {
  using S = TypeParam;
  using Theta = decltype(Gains<S>::paper().theta_max);
  const Theta mx = Gains<S>::paper().theta_max;
  const double band = params::kThetaFaultBand;
  Theta th = mx;
  EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), 0u);
  for (int i : {0, 7, 17}) {
    th = mx;
    th(i) = lit<S>((1 + band) * params::kThetaMax[i] * 0.99);
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), 0u) << i;
    th(i) = lit<S>((1 + band) * params::kThetaMax[i] * 1.01);
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), kFaultThetaBounds) << i;
    th(i) = lit<S>(-band * params::kThetaMax[i] * 0.99);
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), 0u) << i;
    th(i) = lit<S>(-band * params::kThetaMax[i] * 1.01);
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), kFaultThetaBounds) << i;
    // The control task's check a part at a time: the coefficient's own part finds it, no other.
    for (int p = 0; p < ThetaBandMonitor<S>::kParts; ++p)
      EXPECT_EQ(ThetaBandMonitor<S>::check_part(th, mx, p),
                p == i / ThetaBandMonitor<S>::kPart ? static_cast<std::uint32_t>(kFaultThetaBounds) : 0u)
          << i << " part " << p;
  }
  if constexpr (std::numeric_limits<S>::has_quiet_NaN) {
    th = mx;
    th(4) = std::numeric_limits<S>::quiet_NaN();
    EXPECT_EQ(ThetaBandMonitor<S>::check(th, mx), kFaultThetaBounds);
  }
}

/// The stuck-encoder monitor fed a step output by hand: joint `j` driven at `qd` rad/s with torque
/// `tau` while its encoder stands still from tick 1 on.
template <class S>
struct StuckRig {
  StuckEncoderMonitor<S> m;
  Vec6<math::io_scalar_t<S>> cpr;
  StepOutput<S> out{};
  Vec6<S> qd_ref;  // the joint rates the reference commands
  std::int32_t counts[kDof] = {};
  std::uint64_t tick = 0;
  StuckRig() {
    m.reset();
    for (int i = 0; i < kDof; ++i) cpr(i) = lit<math::io_scalar_t<S>>(counts_per_rad(i));
    out.tau.setZero();
    qd_ref.setZero();
  }
  /// One tick; `moved_all`: every encoder counted, by `way` counts.
  std::uint32_t step(bool moved_all, std::int32_t way = 1) {
    bool moved[kDof];
    for (int i = 0; i < kDof; ++i) moved[i] = moved_all, counts[i] += moved_all ? way : 0;
    return m.check(out.tau, qd_ref, counts, moved, tick++, lit<S>(params::kDt), cpr);
  }
};

TYPED_TEST(Monitors, StuckEncoderTorqueChangeWhileStill) {
  using S = TypeParam;
  for (int j = 0; j < kDof; ++j) {
    StuckRig<S> r;
    r.tick = 1000;  // the first count 1000 ticks after the start: a slow joint
    r.out.tau(j) = lit<S>(5);
    EXPECT_EQ(r.step(true), 0u);  // counted at a torque of 5 N m
    // Still, but the torque within 5 +- 0.95 kStuckTorque: fine for a while (the silent checks
    // wait kStuckIntervals of its 1000-tick interval).
    r.out.tau(j) = lit<S>(5 - 0.95 * params::kStuckTorque[j]);
    for (int k = 0; k < 100; ++k) ASSERT_EQ(r.step(false), 0u) << j << " " << k;
    // Beyond it: a fault once it has held for kStuckQualifyTicks ticks in a row. A tick back
    // within it starts the count again.
    r.out.tau(j) = lit<S>(5 + 1.05 * params::kStuckTorque[j]);
    for (int k = 1; k < params::kStuckQualifyTicks; ++k) ASSERT_EQ(r.step(false), 0u) << j << " " << k;
    r.out.tau(j) = lit<S>(5);
    ASSERT_EQ(r.step(false), 0u) << j;
    r.out.tau(j) = lit<S>(5 + 1.05 * params::kStuckTorque[j]);
    for (int k = 1; k < params::kStuckQualifyTicks; ++k) ASSERT_EQ(r.step(false), 0u) << j << " " << k;
    EXPECT_EQ(r.step(false), kFaultEncoderStuck) << j;
    EXPECT_GE(static_cast<double>(r.m.dtau_peak(j)), 1.04 * params::kStuckTorque[j]);
  }
}

TYPED_TEST(Monitors, StuckEncoderSilentWhileTheReferenceMoves) {
  using S = TypeParam;
  const int j = 1;
  StuckRig<S> r;
  // Counting every tick: the recent interval is 1 tick.
  for (int k = 0; k < 5; ++k) ASSERT_EQ(r.step(true), 0u);
  // Then silent, with the reference moving the joint by v counts a tick: the monitor waits out
  // kStuckIntervals intervals, then faults once the motion passes kStuckMotionCounts.
  const double v = 2.0;  // counts per tick
  r.qd_ref(j) = lit<S>(v / (params::kDt * counts_per_rad(j)));
  const int expect = static_cast<int>(std::ceil(params::kStuckMotionCounts / v));
  int fault_tick = -1;
  for (int k = 1; k <= 2 * expect && fault_tick < 0; ++k)
    if (r.step(false) & kFaultEncoderStuck) fault_tick = k;
  EXPECT_NEAR(fault_tick, expect + 1, 2);
  // A joint that was counting fast also faults on the smaller silent torque change: at once when
  // the silence is long enough, the change having lasted since (qualified); ...
  StuckRig<S> t;
  for (int k = 0; k < 5; ++k) ASSERT_EQ(t.step(true), 0u);
  t.out.tau(j) = lit<S>(1.05 * params::kStuckTorqueSilent[j]);
  int first = -1;
  for (int k = 1; k <= 3 * params::kStuckIntervals && first < 0; ++k)
    if (t.step(false) & kFaultEncoderStuck) first = k;
  EXPECT_EQ(first, params::kStuckIntervals + 1);
  // ... or once it has lasted kStuckQualifyTicks ticks, a change that came after the silence did.
  StuckRig<S> u;
  for (int k = 0; k < 5; ++k) ASSERT_EQ(u.step(true), 0u);
  first = -1;
  for (int k = 1; k <= 3 * params::kStuckIntervals && first < 0; ++k) {
    u.out.tau(j) = lit<S>(k > params::kStuckIntervals ? 1.05 * params::kStuckTorqueSilent[j] : 0.0);
    if (u.step(false) & kFaultEncoderStuck) first = k;
  }
  EXPECT_EQ(first, params::kStuckIntervals + params::kStuckQualifyTicks);
}

TYPED_TEST(Monitors, StuckEncoderDitherIsNoMovingJoint) {
  using S = TypeParam;
  // An encoder dithering by a count every tick, both ways, as an edge under the sensor does at rest:
  // its interval is 1 tick, but it was not counting one way. Then silent, with a torque change above
  // the moving joint's silent threshold and below the still joint's: no fault (the compensation's
  // sign flips at rest by twice the Coulomb + Stribeck level, 18 N m on J2).
  for (int j = 0; j < kDof; ++j) {
    StuckRig<S> r;
    for (int k = 0; k < 6; ++k) ASSERT_EQ(r.step(true, k % 2 ? -1 : 1), 0u);
    const double between = (params::kStuckTorqueSilent[j] + params::kStuckTorque[j]) / 2;
    r.out.tau(j) = lit<S>(between);
    for (int k = 0; k < 4 * params::kStuckIntervals; ++k) ASSERT_EQ(r.step(false), 0u) << j << " " << k;
    EXPECT_EQ(static_cast<double>(r.m.dtau_gated_peak(j)), 0.0) << j;
    // The same torque after counting one way: the silent criterion trips.
    StuckRig<S> t;
    for (int k = 0; k < 6; ++k) ASSERT_EQ(t.step(true, -1), 0u);
    t.out.tau(j) = lit<S>(between);
    int first = -1;
    for (int k = 1; k <= 4 * params::kStuckIntervals && first < 0; ++k)
      if (t.step(false) & kFaultEncoderStuck) first = k;
    EXPECT_EQ(first, params::kStuckIntervals + 1) << j;
  }
}

/// Cycles advance by a different amount at each call, so each stage has its own length.
struct StagedHal {
  std::uint32_t clock = 0, calls = 0;
  std::int32_t written[kDof] = {};
  bool fault_line = false;
  void fault_output(bool a) { fault_line = a; }
  bool read_encoders(std::int32_t c[kDof]) {
    for (int i = 0; i < kDof; ++i) c[i] = 0;
    return true;
  }
  void write_dacs(const std::int32_t c[kDof]) { std::copy(c, c + kDof, written); }
  std::uint32_t cycles() { return clock += ++calls; }
  std::uint32_t io_faults() { return 0; }
};
static_assert(hal::ControlHal<StagedHal>);

TEST(TickStages, EveryStageTimedAndTheyAddUpToTheTick) {
  auto task = std::make_unique<ControlTask<double>>();
  task->init(Model<double>::of(robot::kArm), Gains<double>::paper(), FrictionMode::kAdaptive,
             joint_vector<double>(robot::kQStart));
  StagedHal hal;
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t calls_before = hal.calls;
    ASSERT_EQ(control_tick(*task, hal), 0u);
    std::uint32_t sum = 0;
    for (const StepTiming& s : task->stages.stage) {
      EXPECT_EQ(s.count, static_cast<std::uint32_t>(k + 1));
      EXPECT_GT(s.last, 0u);
      sum += s.last;
    }
    EXPECT_EQ(sum, task->timing.last);
    // Marks at calls n+1 .. n+10 (and the overrun check's read in the codes stage): the clock advances by the
    // sum of the call numbers in between, the codes stage two; the step's own time is its stage's.
    const std::uint32_t n = calls_before;
    EXPECT_EQ(task->stages.stage[kStageRead].last, n + 2);
    EXPECT_EQ(task->stages.stage[kStageChecks].last, n + 3);
    EXPECT_EQ(task->stages.stage[kStageReference].last, n + 4);
    EXPECT_EQ(task->stages.stage[kStageStep].last, n + 5);
    EXPECT_EQ(task->stages.stage[kStageMonitors].last, n + 6);
    EXPECT_EQ(task->stages.stage[kStageCodes].last, (n + 7) + (n + 8));
    EXPECT_EQ(task->stages.stage[kStageDecide].last, n + 9);
    EXPECT_EQ(task->stages.stage[kStageOutput].last, n + 10);
    EXPECT_EQ(task->step_timing.last, task->stages.stage[kStageStep].last);
    EXPECT_EQ(task->step_timing.count, static_cast<std::uint32_t>(k + 1));
  }
  EXPECT_STREQ(kTickStageNames[kStageStep], "step");
  EXPECT_EQ(static_cast<int>(kTickStages), 8);
}

// ---- The residual monitor (docs/safety.md, "The residual monitor")

/// A rigid arm frozen at the start pose's inertia, gravity torques and no friction, simulated
/// exactly in double: A qdd = tau + tau_ext - g. The monitor gets the true velocity as its q^dot, so
/// the residual is the external torque through the first-order filter alone:
/// r_n = tau_ext (1 - (1 - K dt)^n), exactly.
template <class S>
struct ResidualRig {
  Mat6<double> A;
  Vec6<double> g, qd = Vec6<double>::Zero(), tau = Vec6<double>::Zero();
  std::int32_t counts[kDof] = {};
  ResidualMonitor<S> m;
  IoMap<S> io = IoMap<S>::of(robot::kEncodersUniform);
  std::uint64_t tick = 0;
  double dt = params::kDt;
  const FrictionBounds<S>* proven = nullptr;  // the identification's friction (the travel check's)

  ResidualRig() {
    Model<double> model = Model<double>::of(robot::kArm);
    Data<double> data;
    forward_kinematics(model, data, joint_vector<double>(robot::kQStart));
    joint_inertia(model, data);
    A = data.A;
    g << 0, 40, 10, 0.1, 0.5, 0.01;
    tau = g;  // holds the arm
    Vec6<S> quantum;
    for (int i = 0; i < kDof; ++i) quantum(i) = lit<S>(1 / counts_per_rad(i));
    m.reset();
    m.set(quantum, Gains<S>::paper().k, io.inverse);
  }
  /// One tick: the encoders of `counting` joints advance one count (every tick: moving steadily),
  /// the others stand still. Free: the arm moves under tau + tau_ext. Held: it stays at rest under
  /// tau = g while the monitor is told tau - tau_ext was commanded (drives that do not deliver what
  /// was asked of them, or a contact that holds the arm against the difference).
  std::uint32_t step(const Vec6<double>& tau_ext, const bool counting[kDof], bool free = true) {
    bool moved[kDof];
    for (int i = 0; i < kDof; ++i) {
      moved[i] = counting[i] || tick == 0;
      if (counting[i]) ++counts[i];
    }
    const Mat6<S> As = A.cast<S>();
    const Vec6<S> gs = g.cast<S>(), zero = Vec6<S>::Zero(), qds = qd.cast<S>();
    Vec6<S> decay = Vec6<S>::Ones();
    const ResidualInput<S> in{As, gs, gs, zero, qds, decay, nullptr, proven};
    const std::uint32_t f = m.check(in, io, counts, moved, tick, tick % params::kResidualTurnEvery == 0);
    m.applied(free ? Vec6<S>(tau.cast<S>()) : Vec6<S>((tau - tau_ext).cast<S>()));
    if (free) qd += dt * A.ldlt().solve(tau + tau_ext - g);
    ++tick;
    return f;
  }
};

/// The external torque of the residual's closed-form tests [N m], and each scalar's tolerance.
Vec6<double> closed_form_torque() {
  Vec6<double> ext;
  ext << 3, -5, 2, 0.5, -0.3, 0.2;
  return ext;
}
template <class S>
constexpr double kClosedFormTol = std::is_same_v<S, double>  ? 1e-9
                                  : std::is_same_v<S, float> ? 2e-3
                                                             : 0.05;
/// Joint i's residual n checks after a constant torque `ext` began (the check after the prime is
/// n = 1): the arm moves from the prime on, so the first period's torque shows in the next check.
double closed_form_residual(double ext, int i, int n) {
  return ext * (1 - std::pow(1 - params::kResidualGain[i] * params::kDt, n - 1));
}

TYPED_TEST(Monitors, ResidualIsTheExternalTorqueThroughAFirstOrderFilter) {
  using S = TypeParam;
  ResidualRig<S> rig;
  const bool still[kDof] = {};
  const Vec6<double> ext = closed_form_torque();
  const double tol = kClosedFormTol<S>;
  rig.step(Vec6<double>::Zero(), still);  // primes it
  for (int n = 1; n <= 100; ++n) {
    rig.step(ext, still);
    for (int i = 0; i < kDof; ++i) {
      const double expect = closed_form_residual(ext(i), i, n);
      ASSERT_NEAR(static_cast<double>(rig.m.r(i)), expect, tol + 1e-6 * std::abs(expect)) << "J" << i + 1 << " n " << n;
    }
  }
}

// The change channel: d = r - r_slow every step, r_slow the residual through the slow filter
// (params::kResidualSlowGain) on the monitor's turns (every kResidualTurnEvery steps: the prime's and every
// other one), fed r's mean over the turn; on the same external torque, r in closed form, r_slow by its recursion.
TYPED_TEST(Monitors, TheChangeResidualIsTheResidualLessItsSlowPart) {
  using S = TypeParam;
  static_assert(params::kResidualTurnEvery == 2);
  ResidualRig<S> rig;
  const bool still[kDof] = {};
  const Vec6<double> ext = closed_form_torque();
  const double tol = kClosedFormTol<S>;
  const double Ks = params::kResidualSlowGain * params::kDt * params::kResidualTurnEvery;
  Vec6<double> slow = Vec6<double>::Zero();
  rig.step(Vec6<double>::Zero(), still);
  for (int n = 1; n <= 400; ++n) {
    rig.step(ext, still);
    for (int i = 0; i < kDof; ++i) {
      const double r = closed_form_residual(ext(i), i, n);
      if (n % 2 == 0) slow(i) += Ks * (0.5 * (r + closed_form_residual(ext(i), i, n - 1)) - slow(i));
      ASSERT_NEAR(static_cast<double>(rig.m.d(i)), r - slow(i), tol + 1e-6 * std::abs(r)) << "J" << i + 1 << " n " << n;
    }
  }
  // A constant torque leaves it: after 400 ms, about e^(-2) K / (K - K_slow) of the step is left.
  for (int i = 0; i < kDof; ++i) EXPECT_LT(std::abs(static_cast<double>(rig.m.d(i))), 0.2 * std::abs(ext(i)));
}

/// A rig whose joints all move steadily at 0.5 rad/s (their encoders count every tick), held (the
/// torque that drives the arm is what was commanded less `ext`), for 2 s: long enough for the
/// static band to leave the change channel.
template <class S>
ResidualRig<S> moving_rig(const FrictionBounds<S>* proven = nullptr) {
  ResidualRig<S> rig;
  rig.proven = proven;
  rig.m.armed = true;
  rig.qd.setConstant(0.5);
  const bool all[kDof] = {true, true, true, true, true, true};
  for (int n = 0; n < 2000; ++n) {
    const std::uint32_t f = rig.step(Vec6<double>::Zero(), all, false);
    EXPECT_EQ(f, 0u) << n << " " << rig.m.r.template cast<double>().transpose() << " | "
                     << rig.m.threshold.template cast<double>().transpose() << " | "
                     << rig.m.d.template cast<double>().transpose() << " | "
                     << rig.m.change_threshold.template cast<double>().transpose();
    if (f) break;
  }
  return rig;
}

// A model error that grows slowly is little change: a ramp of slope a reaches the change residual
// as a / K_slow (the high-pass of a ramp); a step well below the absolute threshold but beyond the
// change threshold is a fault in a few ticks.
TYPED_TEST(Monitors, TheChangeChannelIgnoresASlowDriftAndCatchesAStep) {
  using S = TypeParam;
  const bool all[kDof] = {true, true, true, true, true, true};
  {
    ResidualRig<S> rig = moving_rig<S>();
    Vec6<double> slope;  // [N m/s]: d settles at a tenth of the change threshold
    for (int i = 0; i < kDof; ++i)
      slope(i) = 0.1 * static_cast<double>(rig.m.change_threshold(i)) * params::kResidualSlowGain;
    for (int n = 0; n < 2000; ++n) ASSERT_EQ(rig.step(slope * (n * params::kDt), all, false), 0u) << n;
    for (int i = 0; i < kDof; ++i) {
      // Less the filter's lag: the residual trails the ramp by 1 / K.
      const double expect = slope(i) / params::kResidualSlowGain;
      EXPECT_NEAR(static_cast<double>(rig.m.d(i)), expect, 0.05 * expect + 1e-3) << i;
      EXPECT_LT(rig.m.peak_ratio(i), lit<S>(0.2)) << i;
    }
  }
  {
    ResidualRig<S> rig = moving_rig<S>();
    const double cth = static_cast<double>(rig.m.change_threshold(1)), th = static_cast<double>(rig.m.threshold(1));
    EXPECT_LT(cth, 0.5 * th) << "a moving joint's change threshold leaves the static band out";
    Vec6<double> ext = Vec6<double>::Zero();
    ext(1) = 3 * cth;
    int n = 0;
    std::uint32_t kind = 0;
    for (; n < 100 && kind == 0; ++n) kind = rig.step(ext, all, false);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultDriveFault));
    // The step's share in d crosses 1/3 within 9 ticks (0.55 at 17 ms), then 3 ticks qualify it.
    EXPECT_LE(n, 14);
  }
}

// A joint that counts slowly one way may be creeping in stick-slip, its friction anywhere within
// the static band however steady its velocity estimate: it keeps that band in both channels
// (params::kResidualSlideInterval). The same friction flipping on a joint that counts every tick,
// sliding, is a fault: its change threshold has left the static band out.
TYPED_TEST(Monitors, ACreepingJointKeepsItsStaticBand) {
  using S = TypeParam;
  constexpr int kJ = 3;  // J4
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  const double band = b.friction_hi.cou[kJ] + b.friction_hi.sti[kJ];
  // After 1 s of steady motion, an unexplained torque of +-half the band, flipping every 80 ms.
  const auto run = [&](int interval) {
    ResidualRig<S> rig;
    rig.m.armed = true;
    rig.qd(kJ) = 1 / (counts_per_rad(kJ) * interval * params::kDt);  // a count every `interval` ticks
    std::uint32_t kind = 0;
    for (int n = 0; n < 3000 && kind == 0; ++n) {
      bool counting[kDof] = {};
      counting[kJ] = n % interval == 0;
      Vec6<double> ext = Vec6<double>::Zero();
      if (n >= 1000) ext(kJ) = ((n / 80) % 2 ? 0.5 : -0.5) * band;
      kind = rig.step(ext, counting, false);
    }
    return std::make_pair(kind, static_cast<double>(rig.m.peak_ratio(kJ)));
  };
  // J4's creep in the sweep: a count every 10 ticks (0.008 rad/s at its quantum on the real arm).
  const auto [creep_kind, creep_ratio] = run(10);
  EXPECT_EQ(creep_kind, 0u);
  EXPECT_LT(creep_ratio, 0.5);
  const auto [slide_kind, slide_ratio] = run(params::kResidualSlideInterval);
  EXPECT_EQ(slide_kind, static_cast<std::uint32_t>(kFaultDriveFault)) << slide_ratio;
}

// A still joint is judged against its whole static-friction band (Coulomb plus Stribeck at the
// band's top, robot::kModelErrorBounds), which every friction preset of the arm lies within.
TEST(Residual, AStillJointsThresholdCoversTheStaticFrictionOfEveryPreset) {
  ResidualRig<double> rig;
  const bool still[kDof] = {};
  rig.step(Vec6<double>::Zero(), still);
  for (int i = 0; i < kDof; ++i) {
    for (const FrictionCoefficients* p : {&robot::kFrictionPaper, &robot::kFrictionCorke})
      EXPECT_GT(rig.m.threshold(i), params::kResidualPeakFactor[i] * (p->cou[i] + p->sti[i]) * 1.3) << i;
    EXPECT_GE(rig.m.threshold(i), params::kResidualPeakFactor[i] * (robot::kModelErrorBounds.friction_hi.cou[i] +
                                                                    robot::kModelErrorBounds.friction_hi.sti[i]))
        << i;
  }
  // The band is the presets' range widened by the drift: Corke's J1 Coulomb is the largest.
  EXPECT_NEAR(robot::kModelErrorBounds.friction_hi.cou[0], robot::kFrictionCorke.cou[0] * 1.3, 1e-12);
  EXPECT_NEAR(robot::kModelErrorBounds.friction_lo.cou[0], robot::kFrictionPaper.cou[0] * 0.7, 1e-12);
}

/// Ticks until the monitor reports a fault under a constant external torque (-1: none in 200).
template <class S>
int ticks_to_fault(ResidualRig<S>& rig, const Vec6<double>& ext, const bool counting[kDof], std::uint32_t& kind) {
  kind = 0;
  for (int n = 0; n < 200; ++n)
    if ((kind = rig.step(n == 0 ? Vec6<double>::Zero() : ext, counting, false)) != 0) return n;
  return -1;
}

TYPED_TEST(Monitors, ResidualIsolatesDriveCollisionAndStuckEncoder) {
  using S = TypeParam;
  const bool all[kDof] = {true, true, true, true, true, true};
  {  // Three times the threshold on J2 alone, every encoder counting: a drive that does not deliver.
    ResidualRig<S> rig;
    rig.m.armed = true;
    rig.step(Vec6<double>::Zero(), all);
    Vec6<double> ext = Vec6<double>::Zero();
    ext(1) = 3 * static_cast<double>(rig.m.threshold(1));
    std::uint32_t kind = 0;
    const int n = ticks_to_fault(rig, ext, all, kind);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultDriveFault));
    // Beyond the threshold once 1 - (1 - K dt)^n > 1/3 (n >= 9 at 50 /s), then for 3 ticks.
    EXPECT_GE(n, params::kResidualQualifyTicks + 5);
    EXPECT_LE(n, 15);
    EXPECT_EQ(rig.m.joint, 1);
  }
  {  // The same on J1, J2 and J3 together: a contact.
    ResidualRig<S> rig;
    rig.m.armed = true;
    rig.step(Vec6<double>::Zero(), all);
    Vec6<double> ext = Vec6<double>::Zero();
    for (int i = 0; i < 3; ++i) ext(i) = (i == 1 ? -3 : 3) * static_cast<double>(rig.m.threshold(i));
    std::uint32_t kind = 0;
    EXPECT_GT(ticks_to_fault(rig, ext, all, kind), 0);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultCollision));
  }
  {  // J2's encoder counts every tick, then stops while its joint is pushed on: a stuck encoder.
    ResidualRig<S> rig;
    rig.m.armed = true;
    for (int n = 0; n < 20; ++n) rig.step(Vec6<double>::Zero(), all);
    bool j2_silent[kDof] = {true, true, true, true, true, true};
    j2_silent[1] = false;
    Vec6<double> ext = Vec6<double>::Zero();
    ext(1) = 3 * static_cast<double>(rig.m.threshold(1));
    std::uint32_t kind = 0;
    EXPECT_GT(ticks_to_fault(rig, ext, j2_silent, kind), params::kStuckIntervals);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultEncoderStuck));
  }
  {  // Not armed: the detection is recorded, never returned.
    ResidualRig<S> rig;
    rig.m.armed = false;
    rig.step(Vec6<double>::Zero(), all);
    Vec6<double> ext = Vec6<double>::Zero();
    ext(1) = 3 * static_cast<double>(rig.m.threshold(1));
    std::uint32_t kind = 0;
    EXPECT_EQ(ticks_to_fault(rig, ext, all, kind), -1);
    EXPECT_EQ(rig.m.detected, static_cast<std::uint32_t>(kFaultDriveFault));
    EXPECT_EQ(rig.m.joint, 1);
  }
}

// Below its threshold nothing is reported, however long it lasts.
TYPED_TEST(Monitors, ResidualBelowItsThresholdNeverFaults) {
  using S = TypeParam;
  ResidualRig<S> rig;
  rig.m.armed = true;
  // These torques hold the still joints beyond their static friction, which the travel check
  // rightly calls a fault (TravelCheck* below): the residual's channels alone here.
  rig.m.travel_limit.setZero();
  const bool still[kDof] = {};
  rig.step(Vec6<double>::Zero(), still);
  Vec6<double> ext;
  for (int i = 0; i < kDof; ++i) ext(i) = (i % 2 ? -0.8 : 0.8) * static_cast<double>(rig.m.threshold(i));
  for (int n = 0; n < 1000; ++n) ASSERT_EQ(rig.step(ext, still, false), 0u) << n;
  EXPECT_EQ(rig.m.detected, 0u);
  // Close to 0.8: the thresholds grew a little with the torque commanded (the amplifiers' share).
  for (int i = 0; i < kDof; ++i) EXPECT_GT(rig.m.peak_ratio(i), lit<S>(0.6)) << i;
}

/// The travel check's rig: joint j creeps forward, a count every 10 ticks, for 100 ticks, the arm
/// held (its velocity estimate 0); then its encoder stands while the drive is told to give
/// g_j + push(n) at the n-th tick. Returns the ticks from the last count to the first fault (-1:
/// none in `ticks`).
template <class S, class Push>
int travel_ticks(ResidualRig<S>& rig, int j, Push push, int ticks, std::uint32_t& kind) {
  rig.m.armed = true;
  bool creep[kDof] = {};
  const bool none[kDof] = {};
  for (int n = 0; n <= 100; ++n) {
    creep[j] = n % 10 == 0;
    EXPECT_EQ(rig.step(Vec6<double>::Zero(), creep, false), 0u) << n;
  }
  Vec6<double> ext = Vec6<double>::Zero();
  kind = 0;
  for (int n = 1; n <= ticks; ++n) {
    ext(j) = -push(n);  // held: the monitor is told tau - ext = g + push was applied
    if ((kind = rig.step(ext, none, false)) != 0) return n;
  }
  return -1;
}
/// ... under a constant push.
template <class S>
int travel_ticks(ResidualRig<S>& rig, int j, double push, int ticks, std::uint32_t& kind) {
  return travel_ticks(
      rig, j, [push](int) { return push; }, ticks, kind);
}
/// The least and the most of the torque joint j's travel check leaves to accelerate it [N m]:
/// push less (more) the static band (`band`, or the band's top), the link inertia's share of
/// gravity, the amplifier's gain, ripple and offset on the torque applied.
double travel_force(int j, double g, double push, bool least, double band = -1) {
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  if (band < 0) band = b.friction_hi.cou[j] + b.friction_hi.sti[j];
  const double error = b.link_inertia * std::abs(g) + (b.amp_gain + b.ripple) * std::abs(g + push) +
                       b.amp_offset * robot::kDrives.torque_limit[j];
  return least ? push - band - error : push;
}

/// The least and the most of joint j's diagonal inertia the travel check takes [kg m^2]: the link
/// inertia's 10 % and the other motor-inertia set's armature either way.
std::pair<double, double> travel_inertia(const Mat6<double>& A, int j) {
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  const double G = std::abs(robot::kArm.links[j].gear_ratio);
  const double arm = std::abs(robot::kDriveTrain.motor_inertia_alt.jm[j] - robot::kArm.links[j].motor_inertia) * G * G;
  return {A(j, j) * (1 - b.link_inertia) - arm, A(j, j) * (1 + b.link_inertia) + arm};
}

// A joint whose encoder stands while the torque applied is beyond what static friction and every
// stated model error can hold must have moved: the travel check calls it encoder_stuck once its
// least travel under the least net torque passes kResidualTravelCounts counts, t = sqrt(2 L A / F)
// from rest; with the amplifier's lag and the largest inertia it takes at most 1.5 times that, and a
// step of the check.
TYPED_TEST(Monitors, TravelCheckCatchesAnEncoderThatStandsUnderATorqueBeyondStaticFriction) {
  using S = TypeParam;
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  for (int j : {0, 2, 4}) {
    ResidualRig<S> rig;
    const double band = b.friction_hi.cou[j] + b.friction_hi.sti[j];
    const double push = 3 * band + 2 * b.link_inertia * std::abs(rig.g(j));
    const double limit = params::kResidualTravelCounts / counts_per_rad(j);
    const auto [a_min, a_max] = travel_inertia(rig.A, j);
    const double fastest = std::sqrt(2 * limit * a_min / travel_force(j, rig.g(j), push, false)) / params::kDt;
    const double slowest = std::sqrt(2 * limit * a_max / travel_force(j, rig.g(j), push, true)) / params::kDt;
    std::uint32_t kind = 0;
    const int n = travel_ticks(rig, j, push, 200, kind);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultEncoderStuck)) << "J" << j + 1;
    EXPECT_GE(n, static_cast<int>(fastest)) << "J" << j + 1;
    // ... and up to two steps of the check more: the step in which the push arrives takes the least
    // torque of its ticks, the one before the push (TravelCheckTakesTheLeastTorqueOfItsStep), which
    // shifts the travel a step later, and the crossing shows at the next turn.
    EXPECT_LE(n, static_cast<int>(1.5 * slowest) + 2 + 2 * params::kResidualTurnEvery)
        << "J" << j + 1 << " (" << slowest << " ticks)";
    EXPECT_EQ(rig.m.joint, j);
  }
}

// The same joint held by a torque within its static friction's weakest breakaway stays where it
// is, as far as the check can tell: no fault in 10 s, its least travel nowhere near its limit.
TYPED_TEST(Monitors, TravelCheckLeavesAJointThatStaticFrictionHolds) {
  using S = TypeParam;
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  for (int j : {0, 2, 4}) {
    const double weakest = (b.friction_lo.cou[j] + b.friction_lo.sti[j]) / params::kResidualMargin;
    for (double sign : {1.0, -1.0}) {  // onward, and back against its last count
      ResidualRig<S> held;
      std::uint32_t kind = 0;
      EXPECT_EQ(travel_ticks(held, j, sign * 0.5 * weakest, 10000, kind), -1)
          << "J" << j + 1 << " " << sign << ": " << fault_name(kind);
      EXPECT_LT(static_cast<double>(held.m.travel_peak(j)), 0.5 * static_cast<double>(held.m.travel_limit(j)))
          << "J" << j + 1 << " " << sign;
    }
  }
}

// A joint that hunts about rest under the friction compensation's sign term: the torque commanded
// alternates tick by tick between beyond the static band (twice it, which held for the check's
// step would be a fault: TravelCheckCatches... above) and as far the other way, its mean 0. The
// check's step lasts kResidualTurnEvery ticks and takes the least torque of them, whichever tick
// it falls on; it took only its last before, and with the wrong parity the pushes that way alone
// (found on the realistic plant: J4 in Q12.19 at exactly its limit, docs/experiment.md).
TYPED_TEST(Monitors, TravelCheckTakesTheLeastTorqueOfItsStep) {
  using S = TypeParam;
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  for (int j : {0, 2, 4}) {
    for (int phase : {0, 1}) {
      ResidualRig<S> rig;
      const double push = 2 * (b.friction_hi.cou[j] + b.friction_hi.sti[j]) + 2 * b.link_inertia * std::abs(rig.g(j));
      const auto alternating = [&](int n) { return (n + phase) % 2 ? push : -push; };
      std::uint32_t kind = 0;
      EXPECT_EQ(travel_ticks(rig, j, alternating, 2000, kind), -1) << "J" << j + 1 << " phase " << phase;
      EXPECT_EQ(kind, 0u) << "J" << j + 1 << " phase " << phase << ": " << fault_name(kind);
      EXPECT_LT(static_cast<double>(rig.m.travel_peak(j)), 0.5 * static_cast<double>(rig.m.travel_limit(j)))
          << "J" << j + 1 << " phase " << phase;
    }
  }
}

// A joint that reverses: it crept forward (a count every 10 ticks), then its encoder stands while
// the torque pushes it back beyond its static friction and every model error. It must cross the
// edge it last crossed, back: the check's second way catches it. Its speed forward at the count is
// at most the count's pace (the edges' largest spacing in 9 ticks) plus the most the band lets it change over 11
// ticks; the push first takes that away, at the least net torque and the largest inertia, then moves
// it the travel limit from rest (the check clamps the travel back at minus the limit while the bound
// is negative: twice the limit), each within 1.5 times and a step of the check as onward.
TYPED_TEST(Monitors, TravelCheckCatchesAJointThatReversesUnderATorqueBeyondStaticFriction) {
  using S = TypeParam;
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  for (int j : {0, 2, 4}) {
    ResidualRig<S> rig;
    const double band = b.friction_hi.cou[j] + b.friction_hi.sti[j];
    const double push = 3 * band + 2 * b.link_inertia * std::abs(rig.g(j));
    const double limit = params::kResidualTravelCounts / counts_per_rad(j), quantum = 1 / counts_per_rad(j);
    const auto [a_min, a_max] = travel_inertia(rig.A, j);
    const double error = -travel_force(j, rig.g(j), 0, true, 0);
    const double spacing = quantum * (1 + 2 * b.encoder_edge);  // the edges' largest spacing
    const double ahead = spacing / (9 * params::kDt) + (error + band) / a_min * 11 * params::kDt;
    const double least = travel_force(j, rig.g(j), push, true);
    const double fastest = std::sqrt(2 * limit * a_min / push) / params::kDt;
    const double slowest = (ahead * a_max / least + std::sqrt(4 * limit * a_max / least)) / params::kDt;
    std::uint32_t kind = 0;
    const int n = travel_ticks(rig, j, -push, 400, kind);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultEncoderStuck)) << "J" << j + 1;
    EXPECT_GE(n, static_cast<int>(fastest)) << "J" << j + 1;
    EXPECT_LE(n, static_cast<int>(1.5 * slowest) + 2 + 2 * params::kResidualTurnEvery)
        << "J" << j + 1 << " (" << slowest << " ticks)";
    EXPECT_EQ(rig.m.joint, j);
  }
}

// The identified band (FrictionIdentifier::proven; docs/safety.md): with each joint's breakaway
// proven at 1.1 times the paper's (J1 9.9 N m against the band's top of 39), a push of twice the
// paper's breakaway, which the band's top holds without a fault, is caught both ways; one that the
// paper's own breakaway holds (0.8 of it, less the model's error) is not, either way.
TYPED_TEST(Monitors, TravelCheckTakesTheIdentifiedBand) {
  using S = TypeParam;
  const FrictionCoefficients& paper = robot::kFrictionPaper;
  FrictionBounds<S> proven;
  for (int i = 0; i < kDof; ++i) {
    proven.vis(i) = lit<S>(1.1 * paper.vis[i]);
    proven.breakaway(i) = lit<S>(1.1 * (paper.cou[i] + paper.sti[i]));
  }
  for (int j : {0, 2}) {
    const double breakaway = paper.cou[j] + paper.sti[j];
    for (double sign : {1.0, -1.0}) {
      std::uint32_t kind = 0;
      ResidualRig<S> top;
      EXPECT_EQ(travel_ticks(top, j, sign * 2 * breakaway, 2000, kind), -1) << "J" << j + 1 << " " << sign;
      ResidualRig<S> identified;
      identified.proven = &proven;
      EXPECT_GT(travel_ticks(identified, j, sign * 2 * breakaway, 2000, kind), 0) << "J" << j + 1 << " " << sign;
      EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultEncoderStuck)) << "J" << j + 1 << " " << sign;
      ResidualRig<S> held;
      held.proven = &proven;
      const double error = -travel_force(j, held.g(j), 0, true, 0);
      const double hold = 0.8 * breakaway - error;
      EXPECT_EQ(travel_ticks(held, j, sign * hold, 2000, kind), -1)
          << "J" << j + 1 << " " << sign << ": " << fault_name(kind);
    }
  }
}

// The identified band narrows a still joint's thresholds too (docs/safety.md, "The identified band"):
// static friction anywhere within the proven breakaway instead of the band's top, so each threshold
// shrinks by exactly kResidualMargin times the peak factor times what the band's top exceeds the
// proven breakaway by. A joint held still for 0.3 s, then under an unexplained torque midway between
// the two thresholds, is a drive fault, where the band's top holds it without a fault (the residual
// alone: the travel check, which would name a joint held under a torque beyond its breakaway first,
// waits as it does against a contact the task reacted to).
TYPED_TEST(Monitors, AStillJointsThresholdsTakeTheIdentifiedBand) {
  using S = TypeParam;
  const FrictionCoefficients &paper = robot::kFrictionPaper, &hi = robot::kModelErrorBounds.friction_hi;
  FrictionBounds<S> proven;
  for (int i = 0; i < kDof; ++i) {
    proven.vis(i) = lit<S>(hi.vis[i]);  // the viscous band's top: only the breakaway narrows
    proven.breakaway(i) = lit<S>(1.1 * (paper.cou[i] + paper.sti[i]));
  }
  const bool still[kDof] = {};
  ResidualRig<S> top, identified;
  identified.proven = &proven;
  top.step(Vec6<double>::Zero(), still);
  identified.step(Vec6<double>::Zero(), still);
  for (int i = 0; i < kDof; ++i) {
    const double narrower = params::kResidualMargin * params::kResidualPeakFactor[i] *
                            (hi.cou[i] + hi.sti[i] - static_cast<double>(proven.breakaway(i)));
    const double t_top = static_cast<double>(top.m.threshold(i));
    EXPECT_NEAR(t_top - static_cast<double>(identified.m.threshold(i)), narrower, 1e-3 * t_top + kClosedFormTol<S>)
        << "J" << i + 1;
  }
  // Held still for 0.3 s, then pushed by `ext`: the ticks to the fault (-1: none), its kind and joint.
  const auto held_ticks = [&](const FrictionBounds<S>* band, const Vec6<double>& ext, std::uint32_t& kind, int& joint) {
    ResidualRig<S> held;
    held.proven = band;
    held.m.armed = held.m.contact = true;
    for (int n = 0; n < 300; ++n) held.step(Vec6<double>::Zero(), still);
    const int ticks = ticks_to_fault(held, ext, still, kind);
    joint = held.m.joint;
    return ticks;
  };
  for (int j : {0, 2}) {
    Vec6<double> ext = Vec6<double>::Zero();
    ext(j) = 0.5 * static_cast<double>(top.m.threshold(j) + identified.m.threshold(j));
    std::uint32_t kind = 0;
    int joint = -1;
    EXPECT_EQ(held_ticks(nullptr, ext, kind, joint), -1) << "J" << j + 1 << ": " << fault_name(kind);
    EXPECT_GT(held_ticks(&proven, ext, kind, joint), params::kResidualQualifyTicks) << "J" << j + 1;
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultDriveFault)) << "J" << j + 1 << ": " << fault_name(kind);
    EXPECT_EQ(joint, j);
  }
}

// The wrist's velocity noise (ResidualMonitor::wrist_noise; docs/safety.md): the observer's estimate
// carries the encoders' quantisation e as J^-1 diag(k) J e. Against that matrix, solved by Eigen's LU at
// random poses (q5 from 0.06 rad to pi - 0.06), the monitor's noise bound covers every joint's worst
// case sum_j |(J^-1 diag(k) J)_ij| delta_j / 2; on J4 and J6, where |sin q5| < 0.3 and the mixing
// dominates, within kLoose times it (the bound takes the worst direction of the arm's rotation, which
// at some poses lies along z5, where it is not amplified).
TEST(Residual, TheWristsVelocityNoiseCoversTheObserversMixing) {
  ResidualRig<double> rig;
  const Vec6<double> k = Gains<double>::paper().k;
  Mat6<double> Dk = k.asDiagonal();
  std::mt19937 rng(7);
  Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  double widest = 0, loosest = 0;
  constexpr double kLoose = 10;  // measured 8.9: the bound takes the worst direction of J_21 e_arm
  for (int n = 0; n < 200; ++n) {
    Vec6<double> q;
    for (int i = 0; i < kDof; ++i)
      q(i) = std::uniform_real_distribution<double>(robot::kArm.q_min[i], robot::kArm.q_max[i])(rng);
    const double s5 = std::abs(std::sin(q(4)));
    if (s5 < std::sin(0.06)) continue;
    forward_kinematics(model, data, q);
    geometric_jacobian(data);
    const Mat6<double> M = data.J.partialPivLu().solve(Dk * data.J);
    rig.m.wrist_noise(data.J);
    for (int i = 0; i < kDof; ++i) {
      double exact = 0;
      for (int j = 0; j < kDof; ++j) exact += std::abs(M(i, j)) * 0.5 / counts_per_rad(j);
      EXPECT_GE(rig.m.velocity_noise(i), exact * (1 - 1e-9)) << "J" << i + 1 << " q5 " << q(4);
      if (i == 3 || i == 5) {
        if (s5 < 0.3) {
          loosest = std::max(loosest, rig.m.velocity_noise(i) / exact);
          EXPECT_LE(rig.m.velocity_noise(i), kLoose * exact) << "J" << i + 1 << " q5 " << q(4);
        }
        widest = std::max(widest, rig.m.velocity_noise(i) / rig.m.noise_base(i));
      }
    }
  }
  EXPECT_GT(widest, 10) << "some pose near the wrist singularity, where the mixing dominates";
  std::printf("wrist noise bound / exact, |sin q5| < 0.3: at most %.2f\n", loosest);
}

// The identified band narrows a sliding joint's Coulomb interval (docs/safety.md, "The identified
// band"): its Coulomb level is within the band and at most the proven breakaway less the Stribeck
// band's least, so with theta^ = 0 each absolute threshold shrinks by kResidualMargin times the peak
// factor times what the Coulomb band's top exceeds that by. An unexplained torque that ramps over
// 10 s (too slowly for the change channel) to midway between the two thresholds is a drive fault
// with the proven band, and nothing with the band's top.
TYPED_TEST(Monitors, ASlidingJointsThresholdsTakeTheIdentifiedBand) {
  using S = TypeParam;
  const FrictionCoefficients &paper = robot::kFrictionPaper, &lo = robot::kModelErrorBounds.friction_lo,
                             &hi = robot::kModelErrorBounds.friction_hi;
  static FrictionBounds<S> proven;
  for (int i = 0; i < kDof; ++i) {
    proven.vis(i) = lit<S>(hi.vis[i]);
    proven.breakaway(i) = lit<S>(1.1 * (paper.cou[i] + paper.sti[i]));
  }
  const ResidualRig<S> top = moving_rig<S>(), identified = moving_rig<S>(&proven);
  for (int j : {0, 2}) {
    const double cou_top = std::min(hi.cou[j], static_cast<double>(proven.breakaway(j)) - lo.sti[j]);
    const double narrower = params::kResidualMargin * params::kResidualPeakFactor[j] * (hi.cou[j] - cou_top);
    ASSERT_GT(narrower, 1.0) << "J" << j + 1;
    const double t_top = static_cast<double>(top.m.threshold(j));
    EXPECT_NEAR(t_top - static_cast<double>(identified.m.threshold(j)), narrower, 1e-3 * t_top + kClosedFormTol<S>)
        << "J" << j + 1;
    // The ramp to midway, then 0.5 s held there.
    const double mid = 0.5 * (t_top + static_cast<double>(identified.m.threshold(j)));
    const auto ramp_fault = [&](ResidualRig<S> rig) {
      const bool all[kDof] = {true, true, true, true, true, true};
      std::uint32_t kind = 0;
      for (int n = 0; n < 10500 && kind == 0; ++n) {
        Vec6<double> ext = Vec6<double>::Zero();
        ext(j) = mid * std::min(1.0, n / 10000.0);
        kind = rig.step(ext, all, false);
      }
      return std::make_pair(kind, static_cast<int>(rig.m.joint));
    };
    EXPECT_EQ(ramp_fault(top).first, 0u) << "J" << j + 1;
    const auto [kind, joint] = ramp_fault(identified);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultDriveFault)) << "J" << j + 1 << ": " << fault_name(kind);
    EXPECT_EQ(joint, j);
  }
}

// A contact the task reacted to (ResidualMonitor::note_contact): the push stays in r while the arm
// yields or holds against it. When the contact begins, the monitor notes it, so that the same push
// raises nothing, however long it lasts, while a change of the push by several change thresholds
// after it still does. When the contact ends, the floors drop back and a push still there is found
// again.
TYPED_TEST(Monitors, AContactsPushIsNotedAndWhatChangesAfterItJudged) {
  using S = TypeParam;
  const bool still[kDof] = {};
  ResidualRig<S> rig;
  rig.m.armed = true;
  for (int n = 0; n < 300; ++n) ASSERT_EQ(rig.step(Vec6<double>::Zero(), still, false), 0u) << n;
  // A push on J2 and J3 at twice their thresholds: a collision.
  Vec6<double> ext = Vec6<double>::Zero();
  ext(1) = 2 * static_cast<double>(rig.m.threshold(1));
  ext(2) = 2 * static_cast<double>(rig.m.threshold(2));
  std::uint32_t kind = 0;
  for (int n = 0; n < 200 && kind == 0; ++n) kind = rig.step(ext, still, false);
  ASSERT_EQ(kind, static_cast<std::uint32_t>(kFaultCollision)) << fault_name(kind);
  // The task reacts (yield, or a category-2 stop): contact. The push lasts 1 s, and is let be.
  rig.m.contact = true;
  for (int n = 0; n < 1000; ++n) ASSERT_EQ(rig.step(ext, still, false), 0u) << n;
  EXPECT_NEAR(static_cast<double>(rig.m.r(1)), ext(1), 0.02 * ext(1)) << "the push is still in r";
  EXPECT_LT(rig.m.peak_ratio(1), lit<S>(2.5));
  EXPECT_LT(rig.m.ratio_of(1), lit<S>(0.8));
  // J3's push grows by three of its change thresholds: found, within 50 ms.
  ResidualRig<S> grown = rig;
  Vec6<double> more = ext;
  more(2) += 3 * static_cast<double>(grown.m.change_threshold(2));
  const int ticks = ticks_to_fault(grown, more, still, kind);
  EXPECT_GT(ticks, 0);
  EXPECT_LE(ticks, 50);
  EXPECT_NE(kind, 0u);
  // The contact ends with the push still there: found again once the bound has decayed.
  rig.m.contact = false;
  EXPECT_GT(ticks_to_fault(rig, ext, still, kind), 0);
  EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultCollision)) << fault_name(kind);
}

}  // namespace

// ------------------------------------------------------------------ the position cross-check

/// A potentiometer code of joint i at angle q (the plant's pot_scale, rounded and clamped).
std::uint16_t pot_code(int i, double q, double offset_codes = 0) {
  const auto& d = robot::kDriveTrain;
  const double full = (1 << d.pot_bits) - 1;
  const double x = std::round((q - d.pot_min[i]) / (d.pot_max[i] - d.pot_min[i]) * full + offset_codes);
  return static_cast<std::uint16_t>(x < 0 ? 0 : x > full ? full : x);
}

TYPED_TEST(Monitors, PotentiometerAngleIsTheSpanOverTheCodes) {
  using S = TypeParam;
  const auto& d = robot::kDriveTrain;
  for (int i = 0; i < kDof; ++i)
    for (int code : {0, 1, 1000, 2048, 4094, 4095}) {
      const double want = d.pot_min[i] + code * (d.pot_max[i] - d.pot_min[i]) / 4095.0;
      const double got = static_cast<double>(PositionCrossCheck<S>::pot_angle(i, static_cast<std::uint16_t>(code)));
      EXPECT_NEAR(got, want, 4e-6) << "joint " << i + 1 << " code " << code;  // a few Q12.19 resolutions
    }
}

/// Healthy: the pots follow the joints (with an offset and a noise of 4 codes rms, the band's design
/// value) while every joint sweeps its range back and forth: no fault, and the filtered difference
/// stays within three quarters of its band (measured 0.62 on J5, the narrowest: the noise term is
/// about 6 sigma of the filtered difference, the worst of 1 300 correlated updates about 3.5 sigma). Stuck: joint j's
/// encoder freezes mid-sweep at 0.2 rad/s: the fault comes once the joint has moved about its band past the filter's
/// lag, and only joint j's ratio grows.
TYPED_TEST(Monitors, PositionCrossCheckIgnoresNoiseAndCatchesAStuckEncoder) {
  using S = TypeParam;
  constexpr double kOffset[kDof] = {12, -8, 15, -20, 6, -10};
  const Vec6<double> q0 = joint_vector<double>(robot::kQStart);
  const double speed = 0.2;  // rad/s
  for (int stuck = -1; stuck < kDof; ++stuck) {
    PositionCrossCheck<S> m;
    m.reset();
    std::mt19937 rng(7 + stuck);
    std::normal_distribution<double> noise(0, 4);
    double worst = 0;
    int fault_tick = -1;
    const int t_stuck = 1000;
    Vec6<double> q_stuck = q0;
    for (int t = 0; t < 4000 && fault_tick < 0; ++t) {
      Vec6<double> q;
      for (int i = 0; i < kDof; ++i) q(i) = q0(i) + 0.3 * std::sin(speed / 0.3 * t * 1e-3 + i);  // peak 0.2 rad/s
      if (t == t_stuck) q_stuck = q;
      Vec6<double> q_enc = q;
      if (stuck >= 0 && t >= t_stuck) q_enc(stuck) = q_stuck(stuck);
      std::uint16_t codes[kDof];
      for (int i = 0; i < kDof; ++i) codes[i] = pot_code(i, q(i), kOffset[i] + noise(rng));
      if (m.check(codes, true, q_enc.cast<S>()) & kFaultPositionMismatch) fault_tick = t;
      for (int i = 0; i < kDof; ++i)
        if (i != stuck) worst = std::max(worst, static_cast<double>(m.ratio(i)));
    }
    EXPECT_LT(worst, 0.75) << "healthy joints' filtered difference, a fraction of the band (stuck " << stuck << ")";
    if (stuck < 0) {
      EXPECT_EQ(fault_tick, -1);
      continue;
    }
    ASSERT_GE(fault_tick, t_stuck) << "joint " << stuck + 1 << " not detected";
    // Detected once the joint moved its band (through the filter's lag and the qualifying updates).
    double moved = 0;
    for (int t = t_stuck; t <= fault_tick; ++t)
      moved = std::max(moved, std::fabs(0.3 * std::sin(speed / 0.3 * t * 1e-3 + stuck) - (q_stuck(stuck) - q0(stuck))));
    EXPECT_GT(moved, params::kPositionBand[stuck]) << "joint " << stuck + 1;
    EXPECT_LT(moved, params::kPositionBand[stuck] + 0.2 * 0.12) << "joint " << stuck + 1 << ": within 120 ms of lag";
  }
}

/// A pot sample that is not valid (no complete conversion) is skipped, and a reset learns the
/// reference again (a cleared fault).
TYPED_TEST(Monitors, PositionCrossCheckSkipsInvalidSamplesAndRelearnsAfterAReset) {
  using S = TypeParam;
  const Vec6<double> q0 = joint_vector<double>(robot::kQStart);
  PositionCrossCheck<S> m;
  m.reset();
  std::uint16_t codes[kDof];
  for (int i = 0; i < kDof; ++i) codes[i] = pot_code(i, q0(i));
  for (int t = 0; t < 3000; ++t) EXPECT_EQ(m.check(codes, true, q0.cast<S>()), 0u);
  // The encoders now 0.1 rad off on every joint: a fault, unless the samples are invalid.
  Vec6<double> off = q0;
  off.array() += 0.1;
  for (int t = 0; t < 3000; ++t) EXPECT_EQ(m.check(codes, false, off.cast<S>()), 0u);
  std::uint32_t f = 0;
  for (int t = 0; t < 300; ++t) f |= m.check(codes, true, off.cast<S>());
  EXPECT_NE(f & kFaultPositionMismatch, 0u);
  m.reset();
  f = 0;
  for (int t = 0; t < 3000; ++t) f |= m.check(codes, true, off.cast<S>());
  EXPECT_EQ(f, 0u) << "after a reset the new difference is the reference";
}

/// The band of each joint is its derivation (params.hpp): 6 codes of its pot, twice the elastic
/// deflection at full-scale torque for a 15 Hz locked-motor resonance at the start pose on J1-J3, and
/// 1 mrad of backlash, rounded up to 0.1 mrad.
TEST(PositionCrossCheck, TheBandIsItsDerivation) {
  const auto model = Model<double>::of(robot::kArm);
  auto data = std::make_unique<Data<double>>();
  forward_kinematics(model, *data, joint_vector<double>(robot::kQStart));
  joint_inertia(model, *data);
  const auto& d = robot::kDriveTrain;
  for (int i = 0; i < kDof; ++i) {
    const double code = (d.pot_max[i] - d.pot_min[i]) / ((1 << d.pot_bits) - 1);
    const double k = std::pow(2 * kPi * params::kPositionElasticHz, 2) * data->A(i, i);
    const double elastic = i < 3 ? 2 * robot::kDrives.torque_limit[i] / k : 0;
    const double band = params::kPositionBandCodes * code + elastic + params::kPositionBacklash;
    EXPECT_GE(params::kPositionBand[i], band) << "joint " << i + 1;
    EXPECT_LT(params::kPositionBand[i], band + 1e-4) << "joint " << i + 1;
  }
}
