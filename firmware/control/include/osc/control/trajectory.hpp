// Desired trajectory (68): +-50 mm on each axis about the start position p0, period 5 s,
// envelope 1 - exp(-0.05 t^3) so that the desired velocity and acceleration start at zero
// (the paper's shape; TrajectorySpec holds another).
// The orientation is held at its start value (phi_d = 0 relative to the start orientation).
#pragma once

#include <cstdint>

#include "osc/kernels/model.hpp"
#include "osc/control/params.hpp"

namespace osc {

/// (68) repeats every 2 pi / omega = 5 s = 5000 samples once its envelope has risen.
constexpr std::uint64_t kTrajectoryPeriodTicks = 5000;
/// After 20 s the envelope 1 - exp(-0.05 t^3) is 1 to within exp(-400): nothing but the phase changes.
constexpr std::uint64_t kEnvelopeSettledTicks = 4 * kTrajectoryPeriodTicks;
static_assert(abs_of(params::kOmega * kTrajectoryPeriodTicks * params::kDt - 2 * kPi) < 1e-12,
              "the period in samples is a whole number of the trajectory's periods");
static_assert(params::kEnvelope * 20.0 * 20.0 * 20.0 >= 400.0, "the envelope has settled by then");

/// The shape of (68): amplitude, angular frequency and envelope rate, with the two sample counts
/// that keep its phase exact over any uptime. The firmware uses paper() (params.hpp); the host's
/// experiment may configure another (host_sim/config.cpp checks it with trajectory_spec_valid).
template <class S>
struct TrajectorySpec {
  S amplitude;                  ///< [m]
  S omega;                      ///< [rad/s], 2 pi / (period_ticks dt)
  S envelope;                   ///< c in 1 - exp(-c t^3) [1/s^3]
  std::uint64_t period_ticks;   ///< one period of the sinusoids, in samples (a whole number)
  std::uint64_t settled_ticks;  ///< a whole number of periods after which c t^3 >= 400

  static constexpr TrajectorySpec paper() {
    return {lit<S>(params::kAmplitude), lit<S>(params::kOmega), lit<S>(params::kEnvelope), kTrajectoryPeriodTicks,
            kEnvelopeSettledTicks};
  }
  /// The same shape in another scalar.
  template <class T>
  TrajectorySpec<T> cast() const {
    return {static_cast<T>(amplitude), static_cast<T>(omega), static_cast<T>(envelope), period_ticks, settled_ticks};
  }
};

/// The spec of a trajectory with the given amplitude [m], period (a whole number of samples) and
/// envelope rate c [1/s^3]: settled_ticks is the first whole number of periods with c t^3 >= 400.
inline TrajectorySpec<double> trajectory_spec(double amplitude, std::uint64_t period_ticks, double envelope,
                                              double dt) {
  TrajectorySpec<double> s{amplitude, 2 * kPi / (static_cast<double>(period_ticks) * dt), envelope, period_ticks, 0};
  std::uint64_t n = 1;
  while (envelope * (n * period_ticks * dt) * (n * period_ticks * dt) * (n * period_ticks * dt) < 400.0) ++n;
  s.settled_ticks = n * period_ticks;
  return s;
}

/// The trajectory's time at sample n of a rate of rate_hz samples per second, from the integer
/// sample count: n / rate_hz while the envelope rises, then the settling time plus the phase within
/// the period. Its precision therefore does not depend on uptime (a float n dt advances in 1.5 ms
/// steps after 2.3 h and stops after 4.6 h), and a 64-bit count never wraps in service. The count
/// is divided by the integer rate, not multiplied by a rounded sample time: exact to the scalar's
/// rounding in fixed point too (math::ratio).
template <class S>
S trajectory_time(const TrajectorySpec<S>& spec, std::uint64_t n, std::uint32_t rate_hz) {
  if (n < spec.settled_ticks) return math::ratio<S>(n, rate_hz);
  return math::ratio<S>(spec.settled_ticks + (n - spec.settled_ticks) % spec.period_ticks, rate_hz);
}

template <class S>
struct Desired {
  Vec6<S> x, xd, xdd;  // x_d, x_d dot, x_d double dot
};

/// Evaluates (68) and its analytic derivatives at time t (f = 1, see docs/paper_notes.md).
template <class S>
Desired<S> trajectory(const TrajectorySpec<S>& spec, const Vec3<S>& p0, S t) {
  const S A = spec.amplitude, w = spec.omega, c = spec.envelope;
  // Envelope s(t) and its derivatives. The factor e^{-c t^3} is applied before the powers of t grow
  // (c^2 t^4 reaches 8800 at t = 25 s; c t^2 e^{-c t^3} stays below 0.4), so that no intermediate
  // leaves the range of a fixed-point scalar.
  const S ct = c * t, ct2 = ct * t;
  const S ex = math::exp(-(ct2 * t));
  const S s = S(1) - ex;
  const S ct2_ex = ct2 * ex;
  const S sd = lit<S>(3) * ct2_ex;
  const S sdd = lit<S>(6) * ct * ex - lit<S>(9) * ct2_ex * ct2;
  S sn, cs;
  math::sincos(w * t, sn, cs);
  // x: A sin(wt) s;  y, z: A cos(wt) s.
  const S px = A * sn * s, pxd = A * (w * cs * s + sn * sd),
          pxdd = A * (-w * w * sn * s + lit<S>(2) * w * cs * sd + sn * sdd);
  const S py = A * cs * s, pyd = A * (-w * sn * s + cs * sd),
          pydd = A * (-w * w * cs * s - lit<S>(2) * w * sn * sd + cs * sdd);
  Desired<S> d;
  d.x << p0(0) + px, p0(1) + py, p0(2) + py, S(0), S(0), S(0);
  d.xd << pxd, pyd, pyd, S(0), S(0), S(0);
  d.xdd << pxdd, pydd, pydd, S(0), S(0), S(0);
  return d;
}

}  // namespace osc
