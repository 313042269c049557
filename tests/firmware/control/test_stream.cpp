// The follower of streamed setpoints (osc/control/stream.hpp): a smooth path streamed at 10, 50 and
// 1000 Hz followed to its end within the Euclidean limits (speed, acceleration and jerk of the
// translation from xd, xdd and the differences of xdd; the rotation's from w = E(phi) phi_dot, E
// inverted numerically), close to the path while it runs; a jump beyond the limits followed within
// them; a stream cut mid-path: stale after the stated time, then the category-2 stop to rest within
// the limits; float and Q12.19 against double.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "osc/control/stream.hpp"
#include "osc/math/fixed.hpp"

using namespace osc;

namespace {

constexpr std::uint32_t kHz = params::kControlHz;
constexpr double kDt = params::kDt;

/// The path: 0.15 m along a line and 0.2 rad of the orientation coordinates, cosine timing over
/// 3 s (peak speed pi / 2 * 0.05 = 0.079 m/s, 0.055 m/s on x, within the per-axis 0.1 / sqrt(3) =
/// 0.058 m/s; the axes' unequal shares make the per-axis followers' differences show as a distance
/// from the line).
constexpr double kPathTime = 3.0;
const Vec3<double> kP0(0.5, 0.0, 0.3), kDir = Vec3<double>(1, -0.8, 0.6).normalized();
const Vec3<double> kPhi0(0.1, -0.2, 0.3), kAxis = Vec3<double>(1, 0.5, -0.7).normalized();

Vec6<double> path(double t) {
  const double u = std::clamp(t / kPathTime, 0.0, 1.0);
  const double s = 0.5 * (1 - std::cos(kPi * u));
  Vec6<double> x;
  x << kP0 + 0.15 * s * kDir, kPhi0 + 0.2 * s * kAxis;
  return x;
}
/// Its derivative (the rates of the coordinates), analytic.
Vec6<double> path_rate(double t) {
  const double u = t / kPathTime;
  const double sd = u < 0 || u > 1 ? 0.0 : 0.5 * kPi / kPathTime * std::sin(kPi * u);
  Vec6<double> v;
  v << 0.15 * sd * kDir, 0.2 * sd * kAxis;
  return v;
}

/// The base angular velocity of a reference: w = E(phi) phi_dot, E = (E^{-1})^{-1} numerically.
Vec3<double> omega(const Desired<double>& d) {
  return angular_to_phi_rate<double>(d.x.tail<3>()).inverse() * d.xd.tail<3>();
}

/// Peaks of a reference over a run.
struct Trace {
  double v = 0, a = 0, j = 0, w = 0, wd = 0, phij = 0;
  double lag = 0, off_line = 0;  // against the path delayed by T; distance from its straight line
  double lag_now = 0;            // against the path itself (not delayed)
  int ticks = 0;
  Desired<double> last{}, prev{};
  Vec3<double> w_prev = Vec3<double>::Zero();

  void add(const Desired<double>& d) {
    v = std::max(v, d.xd.head<3>().norm());
    a = std::max(a, d.xdd.head<3>().norm());
    const Vec3<double> wn = omega(d);
    w = std::max(w, wn.norm());
    if (ticks > 0) {
      j = std::max(j, (d.xdd.head<3>() - prev.xdd.head<3>()).norm() * kHz);
      wd = std::max(wd, (wn - w_prev).norm() * kHz);
      phij = std::max(phij, (d.xdd.tail<3>() - prev.xdd.tail<3>()).norm() * kHz);
    }
    prev = last = d, w_prev = wn;
    ++ticks;
  }
};

const CartesianLimits<double> kLim = CartesianLimits<double>::defaults();

/// The Euclidean limits; the angular acceleration from differences of w with 5 % for the term
/// Edot phi_dot (stream.hpp), the jerk of phi_ddot within the angular jerk limit.
void expect_within_limits(const Trace& tr, double slack = 1e-9) {
  EXPECT_LE(tr.v, kLim.linear.v * (1 + slack));
  EXPECT_LE(tr.a, kLim.linear.a * (1 + slack));
  EXPECT_LE(tr.j, kLim.linear.j * (1 + 1e-6));
  EXPECT_LE(tr.w, kLim.angular.v * (1 + slack));
  EXPECT_LE(tr.wd, kLim.angular.a * 1.05);
  EXPECT_LE(tr.phij, kLim.angular.j * (1 + 1e-6));
}

Desired<double> to_double(const Desired<double>& d) { return d; }
template <class S>
Desired<double> to_double(const Desired<S>& d) {
  return {d.x.template cast<double>(), d.xd.template cast<double>(), d.xdd.template cast<double>()};
}

/// Streams path() at rate_hz from tick 0 (sample k at tick k P, the path's time k P dt; with
/// `velocity`, each with the path's rate), until `cut` [s] (then nothing more) or to its end and
/// then end(); runs `total` ticks.
template <class S>
Trace stream_path(StreamFollower<S>& f, std::uint32_t rate_hz, int total, double cut = 1e9, bool velocity = false) {
  const std::uint32_t P = kHz / rate_hz;
  f.start(path(0).cast<S>(), P);
  Trace tr;
  bool ended = false;
  for (int n = 0; n < total; ++n) {
    const double t = n * kDt;
    if (n % P == 0 && t < cut && !ended) {
      if (velocity)
        f.push(path(t).cast<S>(), path_rate(t).cast<S>());
      else
        f.push(path(t).cast<S>());
      if (t >= kPathTime) f.end(), ended = true;
    }
    const Desired<double> d = to_double(f.tick());
    tr.add(d);
    // The target is the path delayed by T; the reference is one tick on.
    const Vec6<double> r = path((n + 1) * kDt - P * kDt);
    tr.lag = std::max(tr.lag, (d.x.head<3>() - r.head<3>()).norm());
    tr.lag_now = std::max(tr.lag_now, (d.x.head<3>() - path((n + 1) * kDt).head<3>()).norm());
    const Vec3<double> q = d.x.head<3>() - kP0;
    tr.off_line = std::max(tr.off_line, (q - kDir * q.dot(kDir)).norm());
  }
  return tr;
}

TEST(StreamFollower, FollowsASmoothPathAtEachRateWithinTheLimits) {
  const Vec6<double> end = path(kPathTime);
  for (std::uint32_t rate : {10u, 50u, 1000u}) {
    StreamFollower<double> f;
    const Trace tr = stream_path(f, rate, 6000);
    expect_within_limits(tr);
    const double ep = (tr.last.x.head<3>() - end.head<3>()).norm();
    const double ew = (tr.last.x.tail<3>() - end.tail<3>()).norm();
    std::printf(
        "%4u Hz: end %.2e m %.2e rad, lag to the delayed path %.2f mm, off the line %.3f mm, "
        "peaks v %.4f a %.4f j %.3f w %.4f wd %.4f\n",
        rate, ep, ew, 1e3 * tr.lag, 1e3 * tr.off_line, tr.v, tr.a, tr.j, tr.w, tr.wd);
    EXPECT_LE(ep, 1e-3) << rate;
    EXPECT_LE(ew, 1e-3) << rate;
    EXPECT_LE(tr.lag, 2e-3) << rate;
    EXPECT_LE(tr.off_line, 2e-4) << rate;
  }
}

// Samples with their velocity: no delay. At 10 Hz, without velocities the reference lags the path
// by about v T = 7.9 mm (the delay); with them it is on the path to within the prediction's error
// (a T^2 / 2) and the follower's lag.
TEST(StreamFollower, SamplesWithVelocityFollowThePathWithoutTheDelay) {
  const Vec6<double> end = path(kPathTime);
  for (std::uint32_t rate : {10u, 50u, 1000u}) {
    StreamFollower<double> plain, with_v;
    const Trace tp = stream_path(plain, rate, 6000);
    const Trace tv = stream_path(with_v, rate, 6000, 1e9, true);
    expect_within_limits(tv);
    std::printf("%4u Hz: lag to the path without velocities %.2f mm, with %.2f mm; off the line %.3f mm\n", rate,
                1e3 * tp.lag_now, 1e3 * tv.lag_now, 1e3 * tv.off_line);
    EXPECT_LE((tv.last.x - end).norm(), 1e-3) << rate;
    EXPECT_LE(tv.last.xd.norm(), 1e-6) << rate;  // at rest at the end sample
    EXPECT_LE(tv.lag_now, 2e-3) << rate;
    EXPECT_LE(tv.off_line, 3e-4) << rate;
    // The delay it removes: at 10 Hz a fifth of the lag or less.
    if (rate == 10u) {
      EXPECT_GE(tp.lag_now, 5 * tv.lag_now);
    }
  }
}

// A velocity that disagrees with the samples (a client's error: the path moves, the velocities say
// still, or twice the speed): the target is continuous all the same, and the reference within the
// limits and at the end sample in the end.
TEST(StreamFollower, InconsistentVelocitiesStayWithinTheLimits) {
  for (double scale : {0.0, 2.0, -1.0}) {
    StreamFollower<double> f;
    const std::uint32_t P = 50;
    f.start(path(0), P);
    Trace tr;
    Vec6<double> prev_r = path(0), vr;
    double jump = 0;
    for (int n = 0; n < 8000; ++n) {
      const double t = n * kDt;
      if (n % P == 0 && t <= kPathTime) {
        f.push(path(t), scale * path_rate(t));
        if (t >= kPathTime) f.end();
      }
      const Vec6<double> r = f.target(vr);
      jump = std::max(jump, (r - prev_r).norm());
      prev_r = r;
      tr.add(f.tick());
    }
    expect_within_limits(tr);
    EXPECT_LE((tr.last.x - path(kPathTime)).norm(), 1e-3) << scale;
    // Continuous: a tick's step of the target is a speed times 1 ms, a tenth of the 4 mm between
    // two samples (a jump between two samples' lines would be of that order).
    EXPECT_LE(jump, 4e-4) << scale;
  }
}

TEST(StreamFollower, AJumpBeyondTheLimitsIsFollowedWithinThem) {
  for (std::uint32_t rate : {50u, 1000u}) {
    StreamFollower<double> f;
    const std::uint32_t P = kHz / rate;
    Vec6<double> x0;
    x0 << 0.5, 0.0, 0.3, 0.3, 0.6, 0.2;
    Vec6<double> x1 = x0;
    x1.head<3>() += 0.3 * Vec3<double>(1, 1, 0).normalized();
    // Every orientation rate at its limit, along E's largest singular direction (1, +-1, -1) at a
    // pitch up to 1.1 rad: |w| = sqrt(1 + 2 sin(pitch) / 3) |phi_dot| = 1.26 |phi_dot|.
    x1.tail<3>() += Vec3<double>(0.5, 0.5, -0.5);
    f.start(x0, P);
    Trace tr;
    for (int n = 0; n < 12000; ++n) {
      if (n % P == 0) f.push(n < 500 ? x0 : x1);
      tr.add(f.tick());
    }
    expect_within_limits(tr);
    EXPECT_LE((tr.last.x - x1).norm(), 1e-3) << rate;
    // The jump is taken at the speed limit.
    EXPECT_GE(tr.v, 0.9 * kLim.linear.v / std::sqrt(1.5)) << rate;
  }
}

TEST(StreamFollower, StartsFromTheHeldPoseToAFarFirstSample) {
  StreamFollower<double> f;
  Vec6<double> x0, x1;
  x0 << 0.5, 0.0, 0.3, 0, 0, 0;
  x1 << 0.4, 0.2, 0.4, 0.2, 0.1, -0.3;
  f.start(x0, 20);
  Trace tr;
  for (int n = 0; n < 12000; ++n) {
    if (n % 20 == 0) f.push(x1);
    tr.add(f.tick());
  }
  expect_within_limits(tr);
  EXPECT_LE((tr.last.x - x1).norm(), 1e-3);
}

TEST(StreamFollower, ACutStreamGoesStaleAndStopsWithinTheLimits) {
  for (std::uint32_t rate : {10u, 50u, 1000u}) {
    const std::uint32_t P = kHz / rate;
    const std::uint32_t timeout = std::max(2 * P, 20u);
    StreamFollower<double> f;
    // The last sample at 1.5 s (mid-path, near the peak speed).
    const int last = static_cast<int>(1500 / P) * static_cast<int>(P);
    const Trace before = stream_path(f, rate, last + 1, 1.5 + 1e-9);
    EXPECT_FALSE(f.stale());
    Trace gap;
    int n = last + 1;
    for (; !f.stale() && n < last + 1000; ++n) gap.add(f.tick());
    // Stale after max(2 T, 20 ms) without a sample: tick() `timeout + 1` after the sample's.
    EXPECT_EQ(n - last, static_cast<int>(timeout) + 1) << rate;
    const Vec3<double> v0 = f.tick().xd.head<3>().cast<double>();
    const Vec3<double> p0 = gap.last.x.head<3>();
    f.stop();
    Trace after;
    while (!f.stopped() && after.ticks < 5000) after.add(f.tick());
    expect_within_limits(before);
    expect_within_limits(gap);
    expect_within_limits(after);
    EXPECT_TRUE(f.stopped()) << rate;
    EXPECT_EQ(after.last.xd.norm(), 0.0);
    EXPECT_EQ(after.last.xdd.norm(), 0.0);
    // Braking from the path's peak speed at the arm's acceleration limit (less the jerk ramps): within a second.
    EXPECT_LT(after.ticks, 1000) << rate;
    // Along the direction it was moving in (within 2 degrees).
    const Vec3<double> moved = after.last.x.head<3>() - p0;
    EXPECT_GT(moved.normalized().dot(v0.normalized()), std::cos(2 * kPi / 180)) << rate;
    std::printf("%4u Hz: stale after %d ticks, stop %d ticks over %.1f mm\n", rate, n - last, after.ticks,
                1e3 * moved.norm());
  }
}

/// StreamFollower::stop_lead: the distance a stop() then covers, as a time at the velocity it starts from
/// (the fraction d / v it returns, divided here in double).
/// Checked against the stop itself (the reference's own travel until it rests), on every axis that moves,
/// at points of the path where it accelerates (0.6 s), cruises at its peak (1.5 s) and slows (2.4 s), in
/// every scalar; and at the peak against the analytic (v / a + a / j) / 2 of each group. Measured
/// (2026-12-04; double, float and Q12.19 within 0.01 of each other):
/// - the translation's axes 0.99 to 1.00 of their travel at all three points: the lead is the stop's own
///   distance (exact for a trapezoidal stop);
/// - the rotation's axes 1.33 to 1.51: the lead is the longer group's, and the rotation's stop is shorter.
/// Each stop also comes to exact rest (v = a = 0), in Q12.19 too (kStopRestSpeed): before it, a Q12.19
/// stop from 0.6 s kept 1 unit of speed and never rested.
template <class S>
void check_stop_lead(const char* scalar) {
  for (double at : {0.6, 1.5, 2.4}) {
    StreamFollower<S> f;
    const int last = static_cast<int>(at * kHz);
    stream_path(f, 1000, last + 1, at + 1e-9, true);
    const Desired<double> d = to_double(f.tick());
    const StopLead<S> fraction = f.stop_lead();
    ASSERT_GT(static_cast<double>(fraction.v), 0.0) << at;
    const double lead = static_cast<double>(fraction.d) / static_cast<double>(fraction.v);
    f.stop();
    Desired<double> e = d;
    int ticks = 0;
    while (!f.stopped() && ticks < 5000) e = to_double(f.tick()), ++ticks;
    ASSERT_TRUE(f.stopped()) << at;
    double lo = 1e9, hi = 0;
    for (int i = 0; i < 6; ++i) {
      const double v = d.xd(i), travel = e.x(i) - d.x(i);
      if (std::abs(v) < 1e-3) continue;
      const double ratio = v * lead / travel;
      lo = std::min(lo, ratio), hi = std::max(hi, ratio);
      EXPECT_GE(ratio, 0.98) << "axis " << i << " at " << at << " s: lead " << lead;
      EXPECT_LE(ratio, 1.7) << "axis " << i << " at " << at << " s: lead " << lead;
    }
    std::printf("%s at %.1f s: lead %.4f s, lead / travel %.3f to %.3f, stop %d ticks\n", scalar, at, lead, lo, hi,
                ticks);
    if (at == 1.5) {  // at the peak speed, the acceleration about 0: each group's (v / a + a / j) / 2
      double analytic = 0;
      for (int g = 0; g < 6; g += 3) {
        const double a = static_cast<double>(f.limits(g).a), j = static_cast<double>(f.limits(g).j);
        double vmax = 0;
        for (int i = g; i < g + 3; ++i) vmax = std::max(vmax, std::abs(d.xd(i)));
        analytic = std::max(analytic, 0.5 * (vmax / a + a / j));
      }
      EXPECT_NEAR(lead, analytic, 0.02 * analytic);
    }
  }
}

TEST(StreamFollower, AStopsLeadIsTheDistanceItsStopCovers) {
  check_stop_lead<double>("double");
  check_stop_lead<float>("float");
  check_stop_lead<Fixed>("Q12.19");
}

/// The same stream in S and double (double at the limits S uses, less its rounding margin), its
/// samples without and with velocities.
template <class S>
void compare_scalar(double tol_pos, double tol_vel, bool velocity) {
  const CartesianLimits<S> ls = CartesianLimits<S>::defaults();
  const auto margin = [](const JerkLimits<S>& l) {
    const JerkLimits<S> m = rounding_margin(l);
    return JerkLimits<double>{static_cast<double>(m.v), static_cast<double>(m.a), static_cast<double>(m.j)};
  };
  StreamFollower<double> fd(CartesianLimits<double>{margin(ls.linear), margin(ls.angular)});
  StreamFollower<S> fs;
  const Trace td = stream_path(fd, 50, 5000, 1e9, velocity);
  const Trace ts = stream_path(fs, 50, 5000, 1e9, velocity);
  expect_within_limits(ts);
  // Step by step.
  fd.start(path(0), 20), fs.start(path(0).cast<S>(), 20);
  double ep = 0, ev = 0;
  for (int n = 0; n < 5000; ++n) {
    const double t = n * kDt;
    if (n % 20 == 0 && velocity) fd.push(path(t), path_rate(t)), fs.push(path(t).cast<S>(), path_rate(t).cast<S>());
    if (n % 20 == 0 && !velocity) fd.push(path(t)), fs.push(path(t).cast<S>());
    const Desired<double> d = fd.tick(), s = to_double(fs.tick());
    ep = std::max(ep, (s.x - d.x).norm());
    ev = std::max(ev, (s.xd - d.xd).norm());
  }
  std::printf("against double%s: x %.2e, xd %.2e\n", velocity ? " (with velocities)" : "", ep, ev);
  EXPECT_LE(ep, tol_pos);
  EXPECT_LE(ev, tol_vel);
  EXPECT_LE((ts.last.x - td.last.x).norm(), tol_pos);
}

TEST(StreamFollower, FloatAgreesWithDouble) {
  for (bool velocity : {false, true}) compare_scalar<float>(2e-5, 1e-4, velocity);
}
TEST(StreamFollower, FixedAgreesWithDouble) {
  for (bool velocity : {false, true}) compare_scalar<Fixed>(1e-4, 1e-3, velocity);
}

/// The host time of tick() (and push() every 20 ticks) alone, per scalar: for the record only.
template <class S>
double microseconds_per_tick() {
  StreamFollower<S> f;
  f.start(path(0).cast<S>(), 20);
  Vec6<S> samples[300];
  for (int k = 0; k < 300; ++k) samples[k] = path(k * 0.02).cast<S>();
  double sink = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (int n = 0; n < 6000; ++n) {
    if (n % 20 == 0) f.push(samples[std::min(n / 20, 299)]);
    sink += static_cast<double>(f.tick().xdd(0));
  }
  const auto t1 = std::chrono::steady_clock::now();
  EXPECT_TRUE(std::isfinite(sink));
  return std::chrono::duration<double, std::micro>(t1 - t0).count() / 6000;
}

TEST(StreamFollower, CostPerTick) {
  std::printf("host, tick(): double %.3f us, float %.3f us, Q12.19 %.3f us\n", microseconds_per_tick<double>(),
              microseconds_per_tick<float>(), microseconds_per_tick<Fixed>());
}

}  // namespace
