// The identification run's state-variable filter (issue 57): every signal of the run through one low pass,
//   F(s) = w^2 / (s + w)^2,   w = params::kIdentifyFilterOmega,
// critically damped, whose two states give the filtered signal and its first and second derivatives. The joint
// angles come out as q_f = F q; the commanded torque and the friction regressor's 18 columns
// (osc/kernels/friction.hpp's friction_regressor_diagonals, at the velocity estimate qd^ the caller passes) come out
// as F tau and F W. Filtering the torque and the regressor through the same F keeps them in phase: the
// filtered-regressor method (Gautier),
//   F tau = (F W) theta + [the rigid-body model at (q_f, qd_f, qdd_f)] + ...,
// whose error is the model's nonlinearity seen through F, small where F is flat over the torque's harmonics
// (params::kIdentifyFilterOmega says why 10 Hz).
//
// The rates. qd_f = F qd^ and qdd_f = s F qd^, the velocity estimate's (its channel is the viscous column's), not
// the angles' s F q and s^2 F q: s^2 F passes the encoder's quantum at w^2, and s F the estimate's error at w. On the
// PUMA's run at 10 Hz (the ideal plant, tests/host_sim/test_identify_sim.cpp) the rigid-body torque's error at the
// filtered states is 0.41 N m rms on J1 from the angles (its quantum 1e-4 rad) and 0.07 N m from the estimate, 0.006
// N m from the plant's true angles: the estimate's standard deviations shrink about as much.
//
// The states. F = [w / (s + w)]^2 as two first-order lags, x1 = w / (s + w) u and x2 = w / (s + w) x1, so
//   y = x2,   yd = w (x1 - x2),   ydd = w^2 ((u - x1) - (x1 - x2)).
// The discretisation is exact for an input linear between ticks (the first-order hold): over a tick with u
// going from u0 to u1 = u0 + d, a = w dt,
//   x1 += k (u0 - x1) + g1 d,
//   x2 += k (x1 - x2) + c (u0 - x1) + g2 d          (x1 before its update)
//   k = 1 - e^-a,  c = 1 - e^-a (1 + a),  g1 = 1 - k / a,  g2 = 2 - k - 2 k / a
// (the state transition e^(A dt) and its input integrals, in closed form). The outputs at a tick are then those
// of the continuous F driven by the samples joined by straight lines: no half-tick delay, as a zero-order hold
// would add. For a sinusoid of angular frequency W the line scales it by 1 - (W dt)^2 / 12 (8e-7 at the
// excitation's highest harmonic, 0.5 Hz), and its corners add images above the Nyquist rate, which F removes from
// y and s F from yd, but s^2 F passes at w^2: qdd_f carries (W dt)^2 w^2 / 12 of the sinusoid's amplitude, 1e-3
// rad/s^2 for 0.3 rad at 0.5 Hz, against its 3 rad/s^2.
// Each update is a difference times a coefficient added to the state, so a constant input is a fixed point in
// every scalar (the DC gain is exactly 1) and a primed filter holds a resting arm's signals without drift.
//
// The scalars. float and double: states and coefficients in S. A float state is rounded to 24 bits: in motion
// about an ulp (qdd_f's share 2e-3 rad/s^2 at 2 rad), and a state stops moving once its update is below half an
// ulp, up to 1 / (2 k) = 8 ulps short of a held input (2e-6 rad, qdd_f 1.5e-2 rad/s^2 at 2 rad): where a joint
// stops, not along the excitation; a primed filter at rest is exact. Fixed point: the coefficients (6.4e-4 to
// 0.061) in Q1.30, where Q12.19 would round g2 by 0.15 % of itself; the states in the format the channel's range
// allows, each update rounded to it, its range twice the input's (the differences u1 - u0 and u0 - x1 fit): Q5.26
// for the angles (within +-16 rad), Q6.25 for the regressor's columns (speeds within +-32 rad/s, sgn), Q9.22 for
// the torques (within +-256 N m: the DACs' full scale, where osc/runtime/control_task.hpp's applied_torque clips
// them); the arm's table is checked against them below. A fixed-point state stops up to 8 LSB short of a held
// input too: 1.2e-7 rad in Q5.26 (qdd_f 1e-3 rad/s^2), where Q12.19's would be 1.5e-5 rad and 0.12 rad/s^2. F's
// impulse response is positive (critically damped): every state lies within the input's range, so the formats fit
// whatever the signal. The outputs are rounded to S once; qdd_f = w^2 times the lags' curvature must fit S's range:
// a motion's is a few rad/s^2, a reversal at 8 rad/s gives 16 w / e = 370, a step of 1 rad in an angle would
// overflow Q12.19 (flagged).
//
// Cost per tick: 30 channels of two updates (5 products each), six exponentials (the Stribeck column); the
// outputs only where a sample is taken. Allocation-free.
#pragma once

#include <array>
#include <cstdint>

#include "osc/control/params.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/robot.hpp"

namespace osc {
namespace identify {

/// e^-x for x >= 0 in double at compile time: halved to x <= 1/2, Taylor to x^20, squared back.
constexpr double exp_neg(double x) {
  int halvings = 0;
  while (x > 0.5) x *= 0.5, ++halvings;
  double term = 1, sum = 1;
  for (int n = 1; n <= 20; ++n) term *= -x / n, sum += term;
  while (halvings-- > 0) sum *= sum;
  return sum;
}

/// The discrete filter's coefficients for a tick of dt (the file comment's), and w, w^2 for the derivatives.
struct SvfCoefficients {
  double w, w2, k, c, g1, g2;
};
constexpr SvfCoefficients svf_coefficients(double w, double dt) {
  const double a = w * dt, e = exp_neg(a);
  double k = 0, term = -1;  // 1 - e^-a by its series (no cancellation)
  for (int n = 1; n <= 20; ++n) term *= -a / n, k += term;
  return {w, w * w, k, k - a * e, 1 - k / a, 2 - k - 2 * k / a};
}
constexpr SvfCoefficients kSvf = svf_coefficients(params::kIdentifyFilterOmega, params::kDt);
static_assert(kSvf.k > 0 && kSvf.k < 0.5 && kSvf.c > 0 && kSvf.g1 > 0 && kSvf.g2 > 0, "a low pass well below 1 kHz");

/// The variance factor of a least-squares estimate from samples taken every `every` ticks of a signal whose noise
/// is white before F (identify_estimate.hpp's correlation factor): F makes neighbouring samples' noise alike, its
/// autocorrelation rho(t) = e^-w|t| (1 + w|t|), and over regressors that change slowly against it (the
/// excitation's 0.5 Hz against F's 10 Hz) the estimate's variance grows by the sum of rho over the sampled lags,
///   kappa = 1 + 2 sum_{n >= 1} rho(n b / w) = 1 + 2 [r / (1 - r) + b r / (1 - r)^2],  b = w dt every, r = e^-b:
/// 4 / b for dense samples (one independent sample per 4 / w = 64 ms), 1 for sparse ones. Noise that is not
/// white before F (a model error at the motion's own frequencies) is correlated longer: kappa is then a floor.
constexpr double noise_correlation_factor(unsigned every) {
  const double b = kSvf.w * params::kDt * every, r = exp_neg(b);
  return 1 + 2 * (r / (1 - r) + b * r / ((1 - r) * (1 - r)));
}

/// The rows of a sample the estimate takes (IdentifyEstimate::add): bit i for joint i when its filtered rate qd_f is
/// at least params::kIdentifyMinRowSpeed in magnitude (about its reversals it is left out).
template <class S>
std::uint8_t moving_rows(const Vec6<S>& qd_f) {
  static constexpr S kMin = lit<S>(params::kIdentifyMinRowSpeed);
  std::uint8_t rows = 0;
  for (int i = 0; i < kDof; ++i)
    if (qd_f(i) >= kMin || qd_f(i) <= -kMin) rows = static_cast<std::uint8_t>(rows | 1u << i);
  return rows;
}

/// The states' integer bits in fixed point (the file comment's formats), checked against the arm's table: every
/// input within half the format's range, so that the difference of two fits.
constexpr int kAngleBits = 5;      // Q5.26: states within +-32, angles within +-16 rad
constexpr int kRegressorBits = 6;  // Q6.25: states within +-64, speeds within +-32 rad/s
constexpr int kTorqueBits = 9;     // Q9.22: states within +-512, torques within +-256 N m
constexpr bool within(const double (&a)[kDof], double bound) {
  for (const double v : a)
    if (!(v < bound && v > -bound)) return false;
  return true;
}
static_assert(within(robot::kArm.q_min, 16 - params::kJointLimitMargin) &&
                  within(robot::kArm.q_max, 16 - params::kJointLimitMargin) &&
                  within(robot::kDrives.max_joint_speed, 32) && within(robot::kDrives.torque_limit, 256),
              "the filter's fixed-point states hold the arm's angles, speeds and torques, and their differences");

/// The scalar of a channel's states and of the coefficients: S itself, or in fixed point the Q format with
/// IntegerBits integer bits, and Q1.30.
template <class S, int IntegerBits>
struct Formats {
  using State = S;
  using Coefficient = S;
};
template <int F, int IntegerBits>
struct Formats<fixed::Q<F>, IntegerBits> {
  using State = fixed::Q<31 - IntegerBits>;
  using Coefficient = fixed::Q<30>;
};

/// N channels of F, their states in the format IntegerBits allows (Formats).
template <class S, int N, int IntegerBits>
class StateVariableFilter {
  using X = typename Formats<S, IntegerBits>::State;
  using C = typename Formats<S, IntegerBits>::Coefficient;
  static constexpr C kK = lit<C>(kSvf.k), kC = lit<C>(kSvf.c), kG1 = lit<C>(kSvf.g1), kG2 = lit<C>(kSvf.g2);

 public:
  using Vec = Eigen::Matrix<S, N, 1>;

  /// The steady state of a constant input u (held for ever).
  void prime(const Vec& u) {
    for (int j = 0; j < N; ++j) x1_[j] = x2_[j] = u_[j] = X(u(j));
  }
  /// One tick: u is this tick's sample, the input a line from the last one to it.
  void step(const Vec& u) {
    for (int j = 0; j < N; ++j) {
      const X u1 = X(u(j)), e = u_[j] - x1_[j], d = u1 - u_[j];
      x2_[j] += (x1_[j] - x2_[j]) * kK + e * kC + d * kG2;
      x1_[j] += e * kK + d * kG1;
      u_[j] = u1;
    }
  }
  /// F u, s F u and s^2 F u at the last tick.
  Vec value() const {
    Vec y;
    for (int j = 0; j < N; ++j) y(j) = S(x2_[j]);
    return y;
  }
  Vec rate() const {
    static constexpr S kW = lit<S>(kSvf.w);
    Vec y;
    for (int j = 0; j < N; ++j) y(j) = kW * (x1_[j] - x2_[j]);
    return y;
  }
  Vec acceleration() const {
    static constexpr S kW2 = lit<S>(kSvf.w2);
    Vec y;
    for (int j = 0; j < N; ++j) y(j) = kW2 * ((u_[j] - x1_[j]) - (x1_[j] - x2_[j]));
    return y;
  }

 private:
  std::array<X, N> x1_{}, x2_{}, u_{};  // the two lags' states and the last input
};

}  // namespace identify

/// The run's signals through F at a tick: the joint angles, the velocity estimate and its rate, the commanded torque,
/// and the friction regressor's columns (RegressorDiagonals: its vis, cou and sti columns, a joint per entry).
template <class S>
struct IdentifySignals {
  Vec6<S> q, qd, qdd;  ///< F q, F qd^, s F qd^ [rad, rad/s, rad/s^2]
  Vec6<S> tau;         ///< F tau [N m]
  RegressorDiagonals<S> w;
};

/// The filters of an identification run: prime() at the run's start, update() every control tick, signals()
/// where a sample is taken.
template <class S>
class IdentifyFilter {
 public:
  /// Starts every filter at the steady state of the arm held at q with torque tau and velocity estimate qd (at
  /// rest: 0), so that a run that starts at rest has no transient; dec: the Stribeck decays (FrictionParams::dec).
  void prime(const Vec6<S>& q, const Vec6<S>& tau, const Vec6<S>& qd, const Vec6<S>& dec) {
    dec_ = dec;
    q_.prime(q);
    tau_.prime(tau);
    w_.prime(regressor(qd));
  }
  /// One control tick: the measured angles, the commanded torque, the velocity estimate.
  void update(const Vec6<S>& q, const Vec6<S>& tau, const Vec6<S>& qd) {
    q_.step(q);
    tau_.step(tau);
    w_.step(regressor(qd));
  }
  /// The rates and accelerations are the velocity estimate's through F (the viscous column is qd itself), F qd and
  /// s F qd, not s F q and s^2 F q (the file comment's "The rates").
  IdentifySignals<S> signals() const {
    const Vec18<S> w = w_.value();
    const Vec6<S> vis = w.template segment<kDof>(0);
    return {q_.value(),
            vis,
            w_.rate().template segment<kDof>(0),
            tau_.value(),
            {vis, w.template segment<kDof>(kDof), w.template segment<kDof>(2 * kDof)}};
  }

 private:
  /// The friction regressor's columns at qd, stacked as theta: [vis; cou; sti] (the kernel's friction model).
  Vec18<S> regressor(const Vec6<S>& qd) const {
    const RegressorDiagonals<S> d = friction_regressor_diagonals(qd, dec_);
    Vec18<S> w;
    w << d.vis, d.cou, d.sti;
    return w;
  }

  identify::StateVariableFilter<S, kDof, identify::kAngleBits> q_;
  identify::StateVariableFilter<S, kDof, identify::kTorqueBits> tau_;
  identify::StateVariableFilter<S, 3 * kDof, identify::kRegressorBits> w_;
  Vec6<S> dec_ = Vec6<S>::Zero();
};

}  // namespace osc
