// The jerk-limited profile (osc/control/jerk_profile.hpp): rest-to-rest minimum times against the
// closed forms of the four regimes, random starts (moving, overshooting, beyond what vmax allows)
// against the limits, continuity and the end state, the minimum time against an independent
// discrete-time time-optimal controller, plan_with_duration, and float and Q12.19 against double.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "osc/control/jerk_profile.hpp"

using namespace osc;

namespace {

using Lim = JerkLimits<double>;

/// What check() found over one profile.
struct Report {
  double v_excess = 0, a_excess = 0, j_excess = 0;  // relative to the limit
  double jump = 0;                                  // largest discontinuity of p, v, a at a boundary
  double end = 0;                                   // |end state - (pT, 0, 0)|
  double v_peak = 0, a_peak = 0;                    // largest |v|, |a|
};

/// Samples at every 1 ms and every segment boundary (each side) and each velocity extremum inside a
/// segment; compares with the limits (vmax raised to the start's unavoidable coast velocity).
Report check(const JerkProfile<double>& pr, double target, const Lim& lim, double v_allowed) {
  Report r;
  auto sample = [&](double t) {
    const ProfileState<double> s = pr.at(t);
    r.v_peak = std::max(r.v_peak, std::abs(s.v));
    r.a_peak = std::max(r.a_peak, std::abs(s.a));
    r.v_excess = std::max(r.v_excess, std::abs(s.v) / v_allowed - 1);
    r.a_excess = std::max(r.a_excess, std::abs(s.a) / lim.a - 1);
    r.j_excess = std::max(r.j_excess, std::abs(s.j) / lim.j - 1);
  };
  for (double t = 0; t < pr.duration(); t += 1e-3) sample(t);
  for (int i = 0; i < pr.segment_count(); ++i) {
    const JerkSegment<double>& g = pr.segment(i);
    sample(g.t0);
    sample(g.t0 + g.duration * (1 - 1e-12));
    if (g.jerk != 0 && -g.a / g.jerk > 0 && -g.a / g.jerk < g.duration) sample(g.t0 - g.a / g.jerk);  // a = 0
    // The end of segment i from its own cubic against the start of i + 1 (or the target at rest).
    const double T = g.duration;
    const double p = g.p + T * (g.v + T * (g.a / 2 + T * g.jerk / 6)), v = g.v + T * (g.a + T * g.jerk / 2),
                 a = g.a + T * g.jerk;
    if (i + 1 < pr.segment_count()) {
      const JerkSegment<double>& h = pr.segment(i + 1);
      r.jump = std::max({r.jump, std::abs(p - h.p), std::abs(v - h.v), std::abs(a - h.a), std::abs(g.t0 + T - h.t0)});
    } else {
      r.end = std::max({std::abs(p - target), std::abs(v), std::abs(a)});
    }
  }
  // at() at the end and beyond.
  const ProfileState<double> e = pr.at(pr.duration());
  r.end = std::max({r.end, std::abs(e.p - target), std::abs(e.v), std::abs(e.a)});
  return r;
}

// ---------------------------------------------------------------- rest to rest
/// The minimum time of a rest-to-rest move of length L (> 0), by regime.
double closed_form_time(double L, const Lim& l, int* regime) {
  const double v = l.v, a = l.a, j = l.j;
  if (v * j >= a * a) {  // amax is reached before vmax on the way up
    if (L >= v * (v / a + a / j)) {
      *regime = 0;  // vmax and amax reached: T = L/v + v/a + a/j
      return L / v + v / a + a / j;
    }
    if (L >= 2 * a * a * a / (j * j)) {
      *regime = 1;  // amax reached, not vmax: L = vp (vp/a + a/j), T = 2 (vp/a + a/j)
      const double vp = a / 2 * (-a / j + std::sqrt(a * a / (j * j) + 4 * L / a));
      return 2 * (vp / a + a / j);
    }
  } else {
    if (L >= 2 * v * std::sqrt(v / j)) {
      *regime = 3;  // vmax reached, not amax: T = L/v + 2 sqrt(v/j)
      return L / v + 2 * std::sqrt(v / j);
    }
  }
  *regime = 2;  // neither: four ramps of tau, L = 2 j tau^3
  return 4 * std::cbrt(L / (2 * j));
}

TEST(JerkProfile, RestToRestMinimumTimesAreTheClosedFormsOfTheirRegimes) {
  int seen[4] = {0, 0, 0, 0};
  for (const Lim& lim : {Lim{1, 5, 50}, Lim{2, 10, 100}, Lim{0.3, 2, 500}, Lim{1, 5, 10}, Lim{0.5, 1, 1}}) {
    for (double L : {1e-4, 1e-3, 0.01, 0.05, 0.1, 0.33, 0.7, 1.0, 3.0, 10.0}) {
      for (double sign : {1.0, -1.0}) {
        int regime = -1;
        const double want = closed_form_time(L, lim, &regime);
        ++seen[regime];
        JerkProfile<double> pr;
        ASSERT_EQ(pr.plan(0.2, 0, 0, 0.2 + sign * L, lim), ProfileStatus::kOk);
        EXPECT_NEAR(pr.duration(), want, 1e-12 * want) << L << " regime " << regime;
        // The limits that the regime says are reached are reached, the others are not.
        const Report r = check(pr, 0.2 + sign * L, lim, lim.v);
        EXPECT_EQ(r.v_peak > lim.v * (1 - 1e-9), regime == 0 || regime == 3) << L << " regime " << regime;
        EXPECT_EQ(r.a_peak > lim.a * (1 - 1e-9), regime == 0 || regime == 1) << L << " regime " << regime;
        EXPECT_LT(r.end, 1e-12);
      }
    }
  }
  for (int k = 0; k < 4; ++k) EXPECT_GT(seen[k], 2) << "regime " << k;
}

// ---------------------------------------------------------------- random starts
struct Case {
  double p0, v0, a0, target;
  Lim lim;
  double v_allowed;  // vmax, or the start's coast velocity where that exceeds it
};

/// Random limits of the arm's scales; starts at rest, moving, braking, overshooting and beyond
/// what vmax allows; targets near and far, on both sides.
Case random_case(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1), s(-1, 1);
  Case c;
  c.lim = {0.2 + 2 * u(rng), 1 + 10 * u(rng), 10 + 200 * u(rng)};
  c.p0 = s(rng);
  const int kind = static_cast<int>(rng() % 6);
  c.v0 = kind == 0 ? 0 : c.lim.v * s(rng);
  c.a0 = kind == 0 ? 0 : c.lim.a * s(rng);
  if (kind == 1) c.v0 = c.lim.v * (u(rng) > 0.5 ? 1 : -1);  // at the velocity limit
  if (kind == 2) c.a0 = c.lim.a * (u(rng) > 0.5 ? 1 : -1);  // at the acceleration limit
  const double vc = c.v0 + c.a0 * std::abs(c.a0) / (2 * c.lim.j);
  c.v_allowed = std::max(c.lim.v, std::abs(vc));
  // The hardest stop's distance, roughly: v |v| / (2 a) + v a / (2 j).
  const double stop = c.v0 * std::abs(c.v0) / (2 * c.lim.a);
  const double scale = std::pow(10.0, -4 + 4.5 * u(rng));
  c.target = kind == 3 ? c.p0 + stop * u(rng) : c.p0 + stop + scale * s(rng);  // 3: short of the stop
  return c;
}

TEST(JerkProfile, RandomStartsKeepTheLimitsAreContinuousAndEndAtTheTargetAtRest) {
  std::mt19937_64 rng(20240601);
  Report worst;
  int over = 0, reversing = 0, max_segments = 0;
  for (int k = 0; k < 10000; ++k) {
    const Case c = random_case(rng);
    JerkProfile<double> pr;
    ASSERT_EQ(pr.plan(c.p0, c.v0, c.a0, c.target, c.lim), ProfileStatus::kOk) << k;
    const Report r = check(pr, c.target, c.lim, c.v_allowed);
    const double tol = 1e-9;
    ASSERT_LT(r.v_excess, tol) << k;
    ASSERT_LT(r.a_excess, tol) << k;
    ASSERT_LT(r.j_excess, tol) << k;
    ASSERT_LT(r.jump, 1e-12) << k;
    ASSERT_LT(r.end, 1e-9) << k << " p0 " << c.p0 << " v0 " << c.v0 << " a0 " << c.a0 << " target " << c.target;
    ASSERT_LE(pr.segment_count(), 7) << k;
    // The start is the start.
    const ProfileState<double> s0 = pr.at(0);
    ASSERT_NEAR(s0.p, c.p0, 1e-15);
    ASSERT_NEAR(s0.v, c.v0, 1e-15);
    ASSERT_NEAR(s0.a, c.a0, 1e-15);
    worst.v_excess = std::max(worst.v_excess, r.v_excess);
    worst.a_excess = std::max(worst.a_excess, r.a_excess);
    worst.j_excess = std::max(worst.j_excess, r.j_excess);
    worst.jump = std::max(worst.jump, r.jump);
    worst.end = std::max(worst.end, r.end);
    over += c.v_allowed > c.lim.v;
    max_segments = std::max(max_segments, pr.segment_count());
    for (int i = 0; i < pr.segment_count(); ++i) reversing += pr.segment(i).v * c.v0 < 0 ? 1 : 0;
  }
  std::printf(
      "10000 random starts: worst excess v %.2e a %.2e j %.2e (relative), jump %.2e, end %.2e; %d start "
      "beyond vmax, %d segments moving against v0, at most %d segments\n",
      worst.v_excess, worst.a_excess, worst.j_excess, worst.jump, worst.end, over, reversing, max_segments);
  EXPECT_GT(over, 100);
  EXPECT_GT(reversing, 1000);
}

// ---------------------------------------------------------------- optimality
/// An independent time-optimal controller in discrete time (dt = 1 ms): each step takes the jerk
/// that moves the hardest stop's end furthest towards the target without passing it, under |a| <=
/// amax and a coast velocity within vmax. It shares no code with the planner.
struct Greedy {
  Lim l;
  double target;
  struct St {
    double p, v, a;
  };
  static St step(const St& s, double J, double t) {
    return {s.p + s.v * t + s.a * t * t / 2 + J * t * t * t / 6, s.v + s.a * t + J * t * t / 2, s.a + J * t};
  }
  /// The end of the hardest stop and its duration: a ramp at -j towards -amax, a hold, a ramp back
  /// to 0 at v = 0.
  double stop(const St& s0, double* duration = nullptr) const {
    const double vc = s0.v + s0.a * std::abs(s0.a) / (2 * l.j);
    const double d = vc >= 0 ? 1 : -1;
    const double v = d * s0.v, a = d * s0.a;
    double m = std::sqrt(std::max(0.0, a * a / 2 + l.j * v)), th = 0;
    if (m > l.a) {
      m = l.a;
      th = (v + (a * a - 2 * m * m) / (2 * l.j)) / m;
    }
    const double t1 = std::max(0.0, (a + m) / l.j), t3 = m / l.j;
    if (duration) *duration = t1 + th + t3;
    St s{0, v, a};
    s = step(s, -l.j, t1);
    s = step(s, 0, th);
    s = step(s, l.j, t3);
    return s0.p + d * s.p;
  }
  double coast(const St& s) const { return s.v + s.a * std::abs(s.a) / (2 * l.j); }
  /// Steps until the hardest stop ends at the target; returns that time plus the stop's duration
  /// (the arrival of a feasible trajectory: these steps, then the stop).
  double run(St s, double dt) const {
    for (int k = 0; k < 200000; ++k) {
      double rest = 0;
      const double ps = stop(s, &rest);
      if (std::abs(ps - target) < 1e-10) return k * dt + rest;
      const bool forward = ps <= target;
      double lo = std::max(-l.j, (-l.a - s.a) / dt), hi = std::min(l.j, (l.a - s.a) / dt);
      // forward: the largest J with stop <= target and coast <= vmax; else the smallest J with
      // stop >= target and coast >= -vmax.
      auto ok = [&](double J) {
        const St n = step(s, J, dt);
        return forward ? stop(n) <= target && coast(n) <= l.v : stop(n) >= target && coast(n) >= -l.v;
      };
      for (int i = 0; i < 60; ++i) {
        const double mid = (lo + hi) / 2;
        if (ok(mid) == forward)
          lo = mid;
        else
          hi = mid;
      }
      s = step(s, forward ? lo : hi, dt);
    }
    return 1e9;
  }
};

TEST(JerkProfile, MinimumTimeMatchesAnIndependentDiscreteTimeOptimalController) {
  std::mt19937_64 rng(777);
  double worst_slower = -1e9, worst_faster = -1e9;
  int n = 0;
  while (n < 150) {
    Case c = random_case(rng);
    if (c.v_allowed > c.lim.v) continue;  // the greedy controller assumes a start that can keep vmax
    JerkProfile<double> pr;
    ASSERT_EQ(pr.plan(c.p0, c.v0, c.a0, c.target, c.lim), ProfileStatus::kOk);
    const double tg = Greedy{c.lim, c.target}.run({c.p0, c.v0, c.a0}, 1e-3);
    // The plan is feasible, so it is no faster than the optimum; the greedy controller is within a
    // few steps of the optimum. The plan must not be slower than it.
    worst_slower = std::max(worst_slower, pr.duration() - tg);
    worst_faster = std::max(worst_faster, tg - pr.duration());
    EXPECT_LT(pr.duration(), tg + 1e-9) << n << " p0 " << c.p0 << " v0 " << c.v0 << " a0 " << c.a0 << " target "
                                        << c.target;
    EXPECT_LT(tg, pr.duration() + 3e-3) << n;
    ++n;
  }
  std::printf("plan vs discrete-time controller (dt = 1 ms): plan slower by at most %.2e s, faster by at most %.2e s\n",
              worst_slower, worst_faster);
}

// ---------------------------------------------------------------- plan_with_duration
TEST(JerkProfile, PlanWithDurationLastsExactlyTKeepsTheLimitsAndEndsAtTheTarget) {
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> u(0, 1);
  int from_rest = 0, moving = 0, unreachable = 0;
  for (int k = 0; k < 2000; ++k) {
    Case c = random_case(rng);
    if (k % 3 == 0) c.v0 = c.a0 = 0, c.v_allowed = c.lim.v;
    JerkProfile<double> fastest, pr;
    ASSERT_EQ(fastest.plan(c.p0, c.v0, c.a0, c.target, c.lim), ProfileStatus::kOk);
    const double T = fastest.duration() * (1 + 3 * u(rng) * u(rng));
    const ProfileStatus st = pr.plan_with_duration(c.p0, c.v0, c.a0, c.target, c.lim, T);
    if (st == ProfileStatus::kDurationUnreachable) {
      ++unreachable;
      continue;
    }
    ASSERT_EQ(st, ProfileStatus::kOk) << k;
    ASSERT_NEAR(pr.duration(), T, 1e-9 * T + 1e-12) << k << " v0 " << c.v0 << " a0 " << c.a0;
    const Report r = check(pr, c.target, c.lim, c.v_allowed);
    ASSERT_LT(r.v_excess, 1e-9) << k;
    ASSERT_LT(r.a_excess, 1e-9) << k;
    ASSERT_LT(r.j_excess, 1e-9) << k;
    ASSERT_LT(r.end, 1e-9) << k;
    ASSERT_LE(pr.segment_count(), 7) << k << " p0 " << c.p0 << " v0 " << c.v0 << " a0 " << c.a0 << " target "
                                     << c.target << " lim " << c.lim.v << " " << c.lim.a << " " << c.lim.j << " T "
                                     << T;
    (c.v0 == 0 && c.a0 == 0 ? from_rest : moving)++;
  }
  std::printf("plan_with_duration: %d from rest, %d moving, %d unreachable\n", from_rest, moving, unreachable);
  EXPECT_GT(moving, 1000);
  EXPECT_LT(unreachable, 20);
  // Below the minimum time: refused.
  JerkProfile<double> pr;
  ASSERT_EQ(pr.plan(0, 0.3, 1, 0.5, Lim{1, 5, 50}), ProfileStatus::kOk);
  const double tmin = pr.duration();
  EXPECT_EQ(pr.plan_with_duration(0, 0.3, 1, 0.5, Lim{1, 5, 50}, tmin * 0.999), ProfileStatus::kDurationTooShort);
  // From rest, twice as long: the same path at half the speed, a quarter of the acceleration.
  JerkProfile<double> slow;
  ASSERT_EQ(pr.plan(0, 0, 0, 0.5, Lim{1, 5, 50}), ProfileStatus::kOk);
  ASSERT_EQ(slow.plan_with_duration(0, 0, 0, 0.5, Lim{1, 5, 50}, 2 * pr.duration()), ProfileStatus::kOk);
  for (double f : {0.1, 0.35, 0.5, 0.8}) {
    const ProfileState<double> a = pr.at(f * pr.duration()), b = slow.at(f * slow.duration());
    EXPECT_NEAR(b.p, a.p, 1e-12);
    EXPECT_NEAR(b.v, a.v / 2, 1e-12);
    EXPECT_NEAR(b.a, a.a / 4, 1e-12);
  }
}

// ---------------------------------------------------------------- contract
TEST(JerkProfile, InputsOutOfContractAreRefusedAndLeaveTheProfile) {
  const double nan = std::nan("");
  JerkProfile<double> pr;
  ASSERT_EQ(pr.plan(0, 0, 0, 1, Lim{1, 5, 50}), ProfileStatus::kOk);
  const double t = pr.duration();
  EXPECT_EQ(pr.plan(0, 0, 0, 1, Lim{0, 5, 50}), ProfileStatus::kBadLimits);
  EXPECT_EQ(pr.plan(0, 0, 0, 1, Lim{1, -5, 50}), ProfileStatus::kBadLimits);
  EXPECT_EQ(pr.plan(0, 0, 0, 1, Lim{1, 5, nan}), ProfileStatus::kBadLimits);
  EXPECT_EQ(pr.plan(0, 0, 0, 1, Lim{1, 5, INFINITY}), ProfileStatus::kBadLimits);
  EXPECT_EQ(pr.plan(0, 1.01, 0, 1, Lim{1, 5, 50}), ProfileStatus::kBadStart);
  EXPECT_EQ(pr.plan(0, 0, -5.5, 1, Lim{1, 5, 50}), ProfileStatus::kBadStart);
  EXPECT_EQ(pr.plan(0, nan, 0, 1, Lim{1, 5, 50}), ProfileStatus::kBadStart);
  EXPECT_EQ(pr.plan(nan, 0, 0, 1, Lim{1, 5, 50}), ProfileStatus::kBadStart);
  EXPECT_EQ(pr.plan(0, 0, 0, nan, Lim{1, 5, 50}), ProfileStatus::kBadTarget);
  EXPECT_EQ(pr.plan_with_duration(0, 0, 0, 1, Lim{1, 5, 50}, nan), ProfileStatus::kBadTarget);
  EXPECT_EQ(pr.duration(), t);
  // A zero-length move from rest: at the target at once.
  ASSERT_EQ(pr.plan(0.25, 0, 0, 0.25, Lim{1, 5, 50}), ProfileStatus::kOk);
  EXPECT_EQ(pr.duration(), 0.0);
  EXPECT_EQ(pr.at(0).p, 0.25);
}

/// The defect behind Homing.InFloat at 0.40 m/s^2 (issue 55): a float profile evaluated at its cruise gave
/// v = 0.0399960019 against its limit 0.0399959981 (0.04 less the float rounding margin), plan_stop refused it
/// (kBadStart) and left the move's own profile, and CartesianMove::stop restarted its time at 0: the reference jumped
/// back to the move's start (77 mm) and the arm faulted `tracking`. A stop is planned from any finite state: one a
/// rounding or more beyond the speed limit only slows, an acceleration beyond the limit is taken at it; each ends
/// at rest, keeps |a| <= amax and |j| <= j, and its speed only falls. A non-finite start still fails.
TEST(JerkProfile, AStopIsPlannedFromAStateBeyondTheLimits) {
  const Lim lim{0.04, 0.4, 2.5};
  for (const double v0 : {0.04 * (1 + 1e-7), 0.06, -0.05}) {
    for (const double a0 : {0.0, 0.3, -0.45}) {
      JerkProfile<double> pr;
      ASSERT_EQ(pr.plan_stop(0.1, v0, a0, lim), ProfileStatus::kOk) << v0 << " " << a0;
      EXPECT_GT(pr.duration(), 0.0);
      double v_prev = std::abs(v0);
      for (double t = 0; t <= pr.duration() + 1e-3; t += 1e-3) {
        const ProfileState<double> st = pr.at(t);
        EXPECT_LE(std::abs(st.a), lim.a * (1 + 1e-12)) << t;
        EXPECT_LE(std::abs(st.j), lim.j * (1 + 1e-12)) << t;
        if (std::abs(a0) < lim.a && v0 * a0 <= 0) {  // already decelerating or coasting: the speed only falls
          EXPECT_LE(std::abs(st.v), v_prev + 1e-12) << v0 << " " << a0 << " " << t;
          v_prev = std::abs(st.v);
        }
      }
      const ProfileState<double> end = pr.at(pr.duration());
      EXPECT_EQ(end.v, 0.0);
      EXPECT_EQ(end.a, 0.0);
      EXPECT_NEAR(end.p, pr.target(), 1e-15);
    }
  }
  // In float, from the state its own cruise gives.
  JerkProfile<float> move, stop;
  const JerkLimits<float> lf{0.04f * 0.9999f, 0.4f * 0.9999f, 2.5f * 0.998f};
  ASSERT_EQ(move.plan(0, 0, 0, 0.2f, lf), ProfileStatus::kOk);
  int refused_before = 0;
  for (float t = 0; t < move.duration(); t += 1e-3f) {
    const ProfileState<float> st = move.at(t);
    refused_before += !(std::abs(st.v) <= lf.v);
    ASSERT_EQ(stop.plan_stop(st.p, st.v, st.a, lf), ProfileStatus::kOk) << t;
    EXPECT_EQ(stop.at(0).p, st.p);
  }
  std::printf("float cruise at 0.04 m/s: %d of %d ticks beyond the limit by rounding, each stop planned\n",
              refused_before, static_cast<int>(move.duration() * 1000));
  JerkProfile<double> pr;
  EXPECT_EQ(pr.plan_stop(0, std::nan(""), 0, lim), ProfileStatus::kBadStart);
  EXPECT_EQ(pr.plan_stop(0, 0, INFINITY, lim), ProfileStatus::kBadStart);
  EXPECT_EQ(pr.plan_stop(0, 0, 0, Lim{0.04, 0, 2.5}), ProfileStatus::kBadLimits);
}

// ---------------------------------------------------------------- float and fixed point
struct Move {
  double p0, v0, a0, target;
  Lim lim;
};
/// The arm's scales: translations up to 1 m at 1 m/s, 5 m/s^2, 50 m/s^3; rotations up to 3 rad at
/// 2 rad/s, 10 rad/s^2, 100 rad/s^3; from rest, moving, re-targeted behind, braking.
const Move kMoves[] = {
    {0.0, 0, 0, 1.0, {1, 5, 50}},       {0.4, 0, 0, 0.4005, {1, 5, 50}},  {-0.3, 0, 0, 0.25, {1, 5, 50}},
    {0.2, 0.8, 2, 0.9, {1, 5, 50}},     {0.2, 0.8, 2, 0.1, {1, 5, 50}},   {0.5, -1, 0, 0.45, {1, 5, 50}},
    {0.1, 0.9, 5, 0.5, {1, 5, 50}},     {0.0, 0.5, -4, 0.04, {1, 5, 50}}, {0.0, 0, 0, 3.0, {2, 10, 100}},
    {-1.5, 0, 0, 1.4, {2, 10, 100}},    {1.0, 2, 0, -2.0, {2, 10, 100}},  {0.3, -1.2, 6, 0.3, {2, 10, 100}},
    {2.0, 1.5, -10, 2.1, {2, 10, 100}}, {0.0, 0, 0, 0.01, {2, 10, 100}},
};

template <class S>
JerkLimits<S> to(const Lim& l) {
  return {S(l.v), S(l.a), S(l.j)};
}

/// Worst |p - p_double|, over every 1 ms of each translation (or rotation) move, of a plan in S;
/// the end reached.
template <class S>
double worst_against_double(bool with_duration, bool rotations, double* worst_end, double* worst_t) {
  double worst = 0;
  *worst_end = *worst_t = 0;
  for (const Move& m : kMoves) {
    if ((m.lim.v > 1.5) != rotations) continue;
    JerkProfile<double> ref;
    JerkProfile<S> pr;
    ProfileStatus st;
    if (with_duration) {
      ref.plan(m.p0, m.v0, m.a0, m.target, m.lim);
      const double T = 1.5 * ref.duration();
      EXPECT_EQ(ref.plan_with_duration(m.p0, m.v0, m.a0, m.target, m.lim, T), ProfileStatus::kOk);
      st = pr.plan_with_duration(S(m.p0), S(m.v0), S(m.a0), S(m.target), to<S>(m.lim), S(T));
    } else {
      EXPECT_EQ(ref.plan(m.p0, m.v0, m.a0, m.target, m.lim), ProfileStatus::kOk);
      st = pr.plan(S(m.p0), S(m.v0), S(m.a0), S(m.target), to<S>(m.lim));
    }
    EXPECT_EQ(st, ProfileStatus::kOk);
    *worst_t = std::max(*worst_t, std::abs(static_cast<double>(pr.duration()) - ref.duration()));
    const int n = static_cast<int>(ref.duration() * 1000) + 2;
    for (int k = 0; k <= n; ++k) {
      const S t = math::ratio<S>(static_cast<std::uint64_t>(k), 1000);
      const ProfileState<S> s = pr.at(t);
      worst = std::max(worst, std::abs(static_cast<double>(s.p) - ref.at(static_cast<double>(t)).p));
    }
    // The end of the last segment, by its cubic in S (at() itself returns the target beyond it).
    const JerkSegment<S>& g = pr.segment(pr.segment_count() - 1);
    const ProfileState<S> e = pr.at(g.t0 + g.duration - S(g.duration * S(1e-6)));
    *worst_end =
        std::max({*worst_end, std::abs(static_cast<double>(e.p) - m.target), std::abs(static_cast<double>(e.v))});
  }
  return worst;
}

TEST(JerkProfile, FloatAndFixedPointFollowDoubleOnTheArmsMoves) {
  // Tolerances: translations [m], rotations [rad]. Fixed point rounds each duration to 2^-19 s:
  // the profile's timing shifts by a few of them, at up to 2 m/s or rad/s. plan_with_duration's
  // bisection on the velocity limit picks a limit of the same duration to that rounding (and from rest
  // its jerk / k^3 is rounded to 2^-19): twice as loose.
  const double kFloat[2] = {2e-6, 4e-6}, kFixed[2] = {1e-5, 2e-5}, kFixedWithDuration[2] = {2e-5, 5e-5};
  for (bool with_duration : {false, true}) {
    for (bool rotations : {false, true}) {
      double end_f, end_q, dt_f, dt_q;
      const double f = worst_against_double<float>(with_duration, rotations, &end_f, &dt_f);
      fixed::take_flags();
      const double q = worst_against_double<Fixed>(with_duration, rotations, &end_q, &dt_q);
      EXPECT_EQ(fixed::take_flags(), 0u);
      std::printf(
          "%s, %s: |p - p_double| float %.2e, Q12.19 %.2e; end |p - pT|, |v| float %.2e, Q12.19 %.2e; "
          "|T - T_double| float %.2e, Q12.19 %.2e\n",
          with_duration ? "plan_with_duration (1.5 Tmin)" : "plan", rotations ? "rotations" : "translations", f, q,
          end_f, end_q, dt_f, dt_q);
      EXPECT_LT(f, kFloat[rotations]);
      EXPECT_LT(q, with_duration ? kFixedWithDuration[rotations] : kFixed[rotations]);
      EXPECT_LT(end_f, kFloat[rotations]);
      EXPECT_LT(end_q, kFixed[rotations]);
    }
  }
}

}  // namespace
