// The identification run's state-variable filter (osc/control/identify_filter.hpp): a sum of sinusoids through it
// against F's analytic steady-state response (amplitude and phase of F, s F and s^2 F, evaluated here with
// std::complex), in double, float and Q12.19; the discretisation against a fine Runge-Kutta integration of the
// continuous F over a random input joined by straight lines (what it claims to be exact for); a step against its
// closed form; a resting arm held without drift and a stopped one settled; the fixed-point states at the range's
// ends without a flag or an overshoot; the friction columns the kernel's regressor's; the noise correlation
// factor against the filter's own impulse response.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <random>
#include <vector>

#include "osc/control/identify_filter.hpp"
#include "osc/math/fixed.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

constexpr double kW = params::kIdentifyFilterOmega;
constexpr double kT = params::kDt;

/// a sin(2 pi hz t + phase).
struct Tone {
  double amplitude, hz, phase;
};

/// s^order F(s) at s = j 2 pi hz.
std::complex<double> transfer(double hz, int order) {
  const std::complex<double> s(0, 2 * kPi * hz);
  return std::pow(s, order) * kW * kW / ((s + kW) * (s + kW));
}
/// The signal, and F's steady-state response to it (order 0: F, 1: s F, 2: s^2 F).
double signal(const std::vector<Tone>& tones, double offset, double t) {
  double u = offset;
  for (const Tone& k : tones) u += k.amplitude * std::sin(2 * kPi * k.hz * t + k.phase);
  return u;
}
double response(const std::vector<Tone>& tones, double offset, double t, int order) {
  double y = order == 0 ? offset : 0;
  for (const Tone& k : tones) {
    const std::complex<double> H = transfer(k.hz, order);
    y += k.amplitude * std::abs(H) * std::sin(2 * kPi * k.hz * t + k.phase + std::arg(H));
  }
  return y;
}
/// What the first-order hold may change in the response. The line through the samples of e^(jWt) (W = 2 pi hz) is
/// the tone times sinc^2(W dt / 2) = 1 - (W dt)^2 / 12 + ... and its images at W + 2 pi m / dt, each sin^2(W dt / 2)
/// / (pi m)^2 of it; sampled at the ticks they fold back onto W through s^order F at their own frequency, which
/// falls there for F and s F but is w^2 for s^2 F. So each component's error is within (W dt)^2 / 12 (|H(jW)| +
/// H_hi), H_hi the largest |s^order F| beyond the Nyquist rate: twice that is the bound.
double hold_bound(const std::vector<Tone>& tones, int order) {
  double b = 0;
  for (const Tone& k : tones) {
    const double images = order == 2 ? kW * kW : std::abs(transfer(0.5 / kT - k.hz, order));
    b += 2 * k.amplitude * std::pow(2 * kPi * k.hz * kT, 2) / 12 * (std::abs(transfer(k.hz, order)) + images);
  }
  return b;
}

// The inputs: the angles about 1 rad, the torque up to 180 N m, the speeds up to 1.5 rad/s, from 0.1 to 5 Hz: the
// excitation's band (to 0.5 Hz) and beyond, where F's gain falls (0.8 at 5 Hz).
const std::vector<Tone> kAngle = {
    {0.6, 0.1, 0.3}, {0.4, 0.3, -1.0}, {0.3, 0.5, 2.0}, {0.05, 2.0, 0.5}, {0.02, 5.0, 1.0}};
const std::vector<Tone> kTorque = {{90, 0.1, 0.0}, {50, 0.3, 1.0}, {25, 0.5, -2.0}, {10, 2.0, 0.2}, {5, 5.0, 0.0}};
const std::vector<Tone> kSpeed = {
    {0.7, 0.1, 1.2}, {0.5, 0.3, 0.0}, {0.2, 0.5, -0.5}, {0.05, 2.0, 0.0}, {0.02, 5.0, 2.0}};
constexpr double kAngleOffset = 1.0;

/// The worst |filter - F's response| of each output over the last 8 s of 10 (the start's transient, e^-wt (1 + wt),
/// is below 1e-50 by 2 s).
struct Errors {
  double q = 0, qd = 0, qdd = 0, tau = 0, vis = 0;
};

template <class S>
void inputs_at(double t, Vec6<S>& q, Vec6<S>& tau, Vec6<S>& qd) {
  for (int i = 0; i < kDof; ++i) {  // each joint 0.1 s behind the one before
    const double ti = t - 0.1 * i;
    q(i) = lit<S>(signal(kAngle, kAngleOffset, ti));
    tau(i) = lit<S>(signal(kTorque, 0, ti));
    qd(i) = lit<S>(signal(kSpeed, 0, ti));
  }
}

/// The filter primed with the inputs at t = 0 (into q, tau, qd), as a run starts at rest.
template <class S>
IdentifyFilter<S> primed_at_start(Vec6<S>& q, Vec6<S>& tau, Vec6<S>& qd) {
  IdentifyFilter<S> f;
  inputs_at<S>(0, q, tau, qd);
  f.prime(q, tau, qd, Vec6<S>::Constant(lit<S>(params::kTauDec)));
  return f;
}

template <class S>
Errors sinusoids_through_the_filter() {
  Vec6<S> q, tau, qd;
  IdentifyFilter<S> f = primed_at_start(q, tau, qd);
  Errors e;
  const auto worst = [](double& w, S ours, double ref) { w = std::max(w, std::abs(static_cast<double>(ours) - ref)); };
  for (int n = 1; n <= 10000; ++n) {
    const double t = n * kT;
    inputs_at<S>(t, q, tau, qd);
    IdentifySignals<S> s;
    {
      test::NoMalloc guard;
      f.update(q, tau, qd);
      s = f.signals();
    }
    if (t < 2) continue;
    for (int i = 0; i < kDof; ++i) {
      const double ti = t - 0.1 * i;
      worst(e.q, s.q(i), response(kAngle, kAngleOffset, ti, 0));
      worst(e.qd, s.qd(i), response(kSpeed, 0, ti, 0));  // the velocity estimate's, not the angles'
      worst(e.qdd, s.qdd(i), response(kSpeed, 0, ti, 1));
      worst(e.tau, s.tau(i), response(kTorque, 0, ti, 0));
      worst(e.vis, s.w.vis(i), response(kSpeed, 0, ti, 0));  // the viscous column is qd itself
    }
  }
  EXPECT_FALSE(math::take_arithmetic_fault<S>());
  return e;
}

void print(const char* what, const Errors& e) {
  std::printf(
      "%-7s |q_f - Fq| %.2e rad, |qd_f - Fqd| %.2e rad/s, |qdd_f - sFqd| %.2e rad/s^2, |tau_f - Ftau| %.2e N m, "
      "|vis_f - Fqd| %.2e rad/s\n",
      what, e.q, e.qd, e.qdd, e.tau, e.vis);
}

}  // namespace

TEST(IdentifyFilter, SinusoidsComeOutWithFsAmplitudeAndPhaseAndTheRatesAsTheVelocityEstimatesAndItsDerivative) {
  const Errors d = sinusoids_through_the_filter<double>();
  const Errors f = sinusoids_through_the_filter<float>();
  const Errors x = sinusoids_through_the_filter<Fixed>();
  const Errors hold{hold_bound(kAngle, 0), hold_bound(kSpeed, 0), hold_bound(kSpeed, 1), hold_bound(kTorque, 0),
                    hold_bound(kSpeed, 0)};
  print("hold", hold);
  print("double", d);
  print("float", f);
  print("Q12.19", x);
  // double: the hold alone (its bound computed above).
  EXPECT_LE(d.q, hold.q);
  EXPECT_LE(d.qd, hold.qd);
  EXPECT_LE(d.qdd, hold.qdd);
  EXPECT_LE(d.tau, hold.tau);
  EXPECT_LE(d.vis, hold.vis);
  // float: the hold plus the inputs' rounding and the states', about an ulp in motion (the rates' channel at speeds
  // below 1.5 rad/s: 1e-7), times w for qdd_f: measured 0.5e-6 rad, 0 rad/s, 1.4e-5 rad/s^2, 1.8e-5 N m above
  // double's. Budgets about twice that.
  EXPECT_LE(f.q, hold.q + 1e-6);
  EXPECT_LE(f.qd, hold.qd + 1e-6);
  EXPECT_LE(f.qdd, hold.qdd + 3e-5);
  EXPECT_LE(f.tau, hold.tau + 4e-5);
  EXPECT_LE(f.vis, hold.vis + 1e-6);
  // Q12.19: the hold plus the inputs' and outputs' rounding to 2^-19 (half an LSB each, 1e-6; the inputs' through
  // s F at up to w: 6e-5 rad/s^2) and the states' to Q5.26 / Q6.25 / Q9.22 (1.5e-8 / 3e-8 / 2.4e-7): measured 0.9e-6
  // rad, 0.9e-6 rad/s, 1.1e-5 rad/s^2, 0 N m above double's. Budgets about twice that.
  EXPECT_LE(x.q, hold.q + 2e-6);
  EXPECT_LE(x.qd, hold.qd + 2e-6);
  EXPECT_LE(x.qdd, hold.qdd + 2.5e-5);
  EXPECT_LE(x.tau, hold.tau + 4e-6);
  EXPECT_LE(x.vis, hold.vis + 2e-6);
}

TEST(IdentifyFilter, ItIsTheContinuousFilterDrivenByTheSamplesJoinedByStraightLines) {
  // A random input every tick (uniform in [-1, 1]: far rougher than any signal of a run), joined by lines; the
  // continuous F's states (x1 = w/(s + w) u, x2 = w/(s + w) x1) integrated by RK4 at dt / 100 (its global error
  // about (w dt / 100)^4 = 1.6e-15 of the signal). y = x2, yd = w (x1 - x2), ydd = w^2 (u - 2 x1 + x2) at every
  // tick, within 1e-13 of their sizes (1, w, w^2): measured 0.6, 0.8 and 1.0e-14.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  identify::StateVariableFilter<double, 1, identify::kAngleBits> f;
  Eigen::Matrix<double, 1, 1> in(u(rng));
  f.prime(in);
  double x1 = in(0), x2 = in(0), u0 = in(0), worst[3] = {0, 0, 0};
  for (int n = 1; n <= 5000; ++n) {
    const double u1 = u(rng);
    const auto deriv = [&](double s, double a, double b, double& da, double& db) {
      const double v = u0 + (u1 - u0) * s / kT;
      da = kW * (v - a), db = kW * (a - b);
    };
    const double h = kT / 100;
    for (int m = 0; m < 100; ++m) {
      const double s = m * h;
      double a1, b1, a2, b2, a3, b3, a4, b4;
      deriv(s, x1, x2, a1, b1);
      deriv(s + h / 2, x1 + h / 2 * a1, x2 + h / 2 * b1, a2, b2);
      deriv(s + h / 2, x1 + h / 2 * a2, x2 + h / 2 * b2, a3, b3);
      deriv(s + h, x1 + h * a3, x2 + h * b3, a4, b4);
      x1 += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4), x2 += h / 6 * (b1 + 2 * b2 + 2 * b3 + b4);
    }
    u0 = u1;
    in(0) = u1;
    f.step(in);
    worst[0] = std::max(worst[0], std::abs(f.value()(0) - x2));
    worst[1] = std::max(worst[1], std::abs(f.rate()(0) - kW * (x1 - x2)));
    worst[2] = std::max(worst[2], std::abs(f.acceleration()(0) - kW * kW * (u1 - 2 * x1 + x2)));
  }
  std::printf("against RK4 over a random line: y %.1e, yd %.1e, ydd %.1e\n", worst[0], worst[1], worst[2]);
  EXPECT_LT(worst[0], 1e-13);
  EXPECT_LT(worst[1], 1e-13 * kW);
  EXPECT_LT(worst[2], 1e-13 * kW * kW);
}

namespace {
/// F's response to a step of U taken between ticks 0 and 1 (the hold's line from 0 to U over the first tick), at t
/// since tick 0: the step response s(t) = U (1 - e^-wt (1 + wt)) averaged over [t - dt, t], its integral
/// integral(t) = U (t - (2 - e^-wt (2 + wt)) / w), so y = (integral(t) - integral(t - dt)) / dt, yd = (s(t) - s(t -
/// dt)) / dt and ydd = (s'(t) - s'(t - dt)) / dt with s'(t) = U w^2 t e^-wt.
struct StepReference {
  double U;
  double integral(double t) const { return t <= 0 ? 0 : U * (t - (2 - std::exp(-kW * t) * (2 + kW * t)) / kW); }
  double s(double t) const { return t <= 0 ? 0 : U * (1 - std::exp(-kW * t) * (1 + kW * t)); }
  double sd(double t) const { return t <= 0 ? 0 : U * kW * kW * t * std::exp(-kW * t); }
  double y(double t) const { return (integral(t) - integral(t - kT)) / kT; }
  double yd(double t) const { return (s(t) - s(t - kT)) / kT; }
  double ydd(double t) const { return (sd(t) - sd(t - kT)) / kT; }
};

template <class S>
void step_response(double U, double tolerance[3]) {
  identify::StateVariableFilter<S, 1, identify::kAngleBits> f;
  using V = Eigen::Matrix<S, 1, 1>;
  f.prime(V(S(0)));
  const StepReference ref{U};
  double worst[3] = {0, 0, 0}, previous = 0;
  for (int n = 1; n <= 1000; ++n) {
    f.step(V(lit<S>(U)));
    const double t = n * kT, y = static_cast<double>(f.value()(0));
    worst[0] = std::max(worst[0], std::abs(y - ref.y(t)));
    worst[1] = std::max(worst[1], std::abs(static_cast<double>(f.rate()(0)) - ref.yd(t)));
    worst[2] = std::max(worst[2], std::abs(static_cast<double>(f.acceleration()(0)) - ref.ydd(t)));
    EXPECT_GE(y, previous) << n;  // critically damped: rises without overshoot
    EXPECT_LE(y, U) << n;
    previous = y;
  }
  std::printf("step of %.0f: y %.1e, yd %.1e, ydd %.1e (tolerances %.0e, %.0e, %.0e)\n", U, worst[0], worst[1],
              worst[2], tolerance[0], tolerance[1], tolerance[2]);
  for (int k = 0; k < 3; ++k) EXPECT_LE(worst[k], tolerance[k]) << k;
  EXPECT_FALSE(math::take_arithmetic_fault<S>());
}
}  // namespace

TEST(IdentifyFilter, AStepIsItsClosedForm) {
  // A step of 0.5 rad in an angle's channel over 1 s (its qdd_f starts at w^2 U = 1974 rad/s^2, within Q12.19).
  // double: the closed form's own rounding (integral(t) - integral(t - dt) of values up to 0.5 over dt). float: the
  // states may stop up to 8 ulps (0.5e-6 rad at 0.5 rad) short of the held input, times w and w^2 for the derivatives;
  // Q12.19: the output's rounding (1e-6), Q5.26's 8 LSB (1.2e-7) times w and w^2. Budgets about twice the
  // measured.
  double d[3] = {1e-11, 1e-10, 1e-8}, f[3] = {2e-6, 1e-4, 1e-2}, x[3] = {2e-6, 2e-5, 2e-3};
  step_response<double>(0.5, d);
  step_response<float>(0.5, f);
  step_response<Fixed>(0.5, x);
}

/// A resting arm primed: its signals stay exactly the inputs, their derivatives exactly 0, in every scalar.
template <class S>
void holds_at_rest() {
  IdentifyFilter<S> f;
  const Vec6<S> q = test::from_array(robot::kQStart).cast<S>(),
                tau = Vec6<S>(Vec6<double>(12.5, -80, 31, 0.3, -1.2, 0.07).cast<S>()), zero = Vec6<S>::Zero();
  f.prime(q, tau, zero, Vec6<S>::Constant(lit<S>(params::kTauDec)));
  for (int n = 0; n < 10000; ++n) f.update(q, tau, zero);
  const IdentifySignals<S> s = f.signals();
  EXPECT_EQ(s.q, q);
  EXPECT_EQ(s.qd, zero);
  EXPECT_EQ(s.qdd, zero);
  EXPECT_EQ(s.tau, tau);
  EXPECT_EQ(s.w.vis, zero);
  EXPECT_EQ(s.w.cou, zero);
  EXPECT_EQ(s.w.sti, zero);
}

TEST(IdentifyFilter, APrimedFilterHoldsAnArmAtRestWithoutDriftInEveryScalar) {
  holds_at_rest<double>();
  holds_at_rest<float>();
  holds_at_rest<Fixed>();
}

/// A joint that moves for 3 s and stops: 2 s after, how far q_f is from where it stopped and what derivatives remain.
template <class S>
Errors settles_after_a_stop() {
  Vec6<S> q, tau, qd;
  IdentifyFilter<S> f = primed_at_start(q, tau, qd);
  for (int n = 1; n <= 3000; ++n) inputs_at<S>(n * kT, q, tau, qd), f.update(q, tau, qd);
  for (int n = 0; n < 2000; ++n) f.update(q, tau, qd);
  const IdentifySignals<S> s = f.signals();
  const auto worst = [](const Vec6<S>& a) { return a.template cast<double>().cwiseAbs().maxCoeff(); };
  return {worst(s.q - q), worst(s.qd - qd), worst(s.qdd), worst(s.tau - tau), worst(s.w.vis - qd)};
}

TEST(IdentifyFilter, AfterAStopTheStatesSettleWithinTheirRounding) {
  // A state moves while its update exceeds half its LSB: it may stay 1 / (2k) = 8 LSB short of a held input
  // (identify_filter.hpp), each of the two; qd_f is the rates' channel's value and qdd_f w times its lag. Q5.26:
  // 1.2e-7 rad; Q6.25: 2.4e-7 rad/s, qdd_f within 63 x 16 x 3e-8 = 3e-5 rad/s^2; float at 1-2 rad: 8 ulps of
  // 1.2e-7-2.4e-7, at the speeds below 1 rad/s 8 ulps of 6e-8, qdd_f within 63 x 1e-6 = 6e-5 rad/s^2.
  const Errors d = settles_after_a_stop<double>(), f = settles_after_a_stop<float>(), x = settles_after_a_stop<Fixed>();
  print("double", d);
  print("float", f);
  print("Q12.19", x);
  EXPECT_LT(d.q, 1e-12);
  EXPECT_LT(d.qdd, 1e-9);
  EXPECT_LT(f.q, 4e-6);
  EXPECT_LT(f.qd, 1e-6);
  EXPECT_LT(f.qdd, 6e-5);
  EXPECT_LT(x.q, 1.5e-6);
  EXPECT_LT(x.qd, 5e-7);
  EXPECT_LT(x.qdd, 3e-5);
  EXPECT_LT(x.tau, 8e-6);  // Q9.22: 2 x 8 LSB of 2.4e-7
}

TEST(IdentifyFilter, TheFixedPointStatesHoldTheRangesEndsWithoutAFlagOrAnOvershoot) {
  // The ends the formats are sized for: the angles a triangle wave between +-2 pi at 8 rad/s (the PUMA's plausible
  // speed; its corners give qdd_f = 16 w / e = 370 rad/s^2, within Q12.19), the torques square waves at the DACs'
  // full scale, the speeds square waves at the drives' plausible ones. F's impulse response is positive, so every
  // output stays within the input's range (plus the output's rounding) and no state saturates.
  IdentifyFilter<Fixed> f;
  Vec6<double> tau_max, speed;
  for (int i = 0; i < kDof; ++i)
    tau_max(i) = robot::kDrives.torque_limit[i], speed(i) = robot::kDrives.max_joint_speed[i];
  const Vec6<Fixed> zero = Vec6<Fixed>::Zero();
  f.prime(zero, zero, zero, Vec6<Fixed>::Constant(lit<Fixed>(params::kTauDec)));
  const double lsb = 1.0 / (1 << 19), ramp = 2 * kPi / 8;  // a ramp from 0 to 2 pi [s]
  double largest = 0;
  for (int n = 1; n <= 8000; ++n) {
    const double t = n * kT, phase = std::fmod(t, 4 * ramp), sign = std::fmod(t, 0.6) < 0.3 ? 1 : -1;
    const double q = phase < ramp       ? 8 * phase
                     : phase < 3 * ramp ? 2 * kPi - 8 * (phase - ramp)
                                        : -2 * kPi + 8 * (phase - 3 * ramp);
    const Vec6<Fixed> tau = (sign * tau_max).cast<Fixed>(), qd = (sign * speed).cast<Fixed>();
    f.update(Vec6<Fixed>::Constant(lit<Fixed>(q)), tau, qd);
    const IdentifySignals<Fixed> s = f.signals();
    for (int i = 0; i < kDof; ++i) {
      largest = std::max(largest, std::abs(static_cast<double>(s.q(i))));
      ASSERT_LE(std::abs(static_cast<double>(s.q(i))), 2 * kPi + lsb) << n;
      ASSERT_LE(std::abs(static_cast<double>(s.tau(i))), tau_max(i) + lsb) << n;
      ASSERT_LE(std::abs(static_cast<double>(s.w.vis(i))), speed(i) + lsb) << n;
      ASSERT_LE(std::abs(static_cast<double>(s.w.cou(i))), 1 + lsb) << n;
    }
  }
  EXPECT_GT(largest, 6.0);  // the ends reached
  EXPECT_FALSE(math::take_arithmetic_fault<Fixed>());
}

TEST(IdentifyFilter, TheFrictionColumnsAreTheKernelsRegressorThroughF) {
  // At a constant speed, after F has settled, each column is friction_regressor_diagonals' (its DC gain is 1): the
  // filter forms them with the kernel's friction model (2), not its own.
  IdentifyFilter<double> f;
  const Vec6<double> q = Vec6<double>::Zero(), tau = Vec6<double>::Zero(),
                     dec = Vec6<double>::Constant(params::kTauDec);
  const Vec6<double> qd(0.8, -0.3, 1.4, -2.0, 0.05, 0.0);
  f.prime(q, tau, Vec6<double>::Zero(), dec);
  for (int n = 0; n < 2000; ++n) f.update(q, tau, qd);
  const RegressorDiagonals<double> ref = friction_regressor_diagonals(qd, dec);
  const IdentifySignals<double> s = f.signals();
  EXPECT_LT((s.w.vis - ref.vis).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((s.w.cou - ref.cou).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((s.w.sti - ref.sti).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(s.w.sti(0), std::exp(-params::kTauDec * 0.64), 1e-12);
  EXPECT_EQ(s.w.cou(5), 0);  // sgn 0 = 0
}

TEST(IdentifyFilter, TheNoiseCorrelationFactorIsTheFiltersOwnAutocorrelationSummedOverTheSampledLags) {
  // The discrete filter's impulse response h (its value output), its autocorrelation rho(m) = sum h_n h_{n+m} /
  // sum h_n^2, summed over the lags a decimation by `every` samples: the factor the closed form gives, within the
  // continuous approximation's (w dt = 0.06): measured 0.06 %, asserted 0.5 %.
  identify::StateVariableFilter<double, 1, identify::kAngleBits> f;
  using V = Eigen::Matrix<double, 1, 1>;
  f.prime(V(0.0));
  std::vector<double> h;
  f.step(V(1.0));
  h.push_back(f.value()(0));
  for (int n = 0; n < 20000; ++n) f.step(V(0.0)), h.push_back(f.value()(0));
  const auto rho = [&](std::size_t m) {
    double a = 0, b = 0;
    for (std::size_t n = 0; n < h.size(); ++n) {
      b += h[n] * h[n];
      if (n + m < h.size()) a += h[n] * h[n + m];
    }
    return a / b;
  };
  for (const unsigned every : {1u, 5u, 10u, 50u, 200u}) {
    double kappa = 1;
    for (std::size_t k = 1; k * every < 5000; ++k) kappa += 2 * rho(k * every);
    const double closed = identify::noise_correlation_factor(every);
    std::printf("every %3u ticks: kappa %.3f from the impulse response, %.3f closed form\n", every, kappa, closed);
    EXPECT_NEAR(closed / kappa, 1, 0.005) << every;
  }
  EXPECT_NEAR(identify::noise_correlation_factor(1), 4 / (kW * kT), 0.01 * 4 / (kW * kT));
}
