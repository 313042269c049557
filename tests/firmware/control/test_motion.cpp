// The motion generator (osc/control/motion.hpp) and its point-to-point move
// (osc/control/cartesian_move.hpp): the reference a move produces, sampled every millisecond, against
// its limits (speed, acceleration and jerk of the translation and of the rotation, the rotation's
// from E(phi) phi_dot, not from the profile), the straight line and the single axis, its end, the
// orientation coordinates' rates against finite differences; a stop along the path; the queue; the
// re-target; the paper's motion and its slow-down; float and Q12.19 against double.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "osc/control/motion.hpp"
#include "osc/math/fixed.hpp"

using namespace osc;

namespace {

constexpr std::uint32_t kHz = params::kControlHz;

Pose<double> pose(double x, double y, double z, const Vec3<double>& rpy) {
  return {Vec3<double>(x, y, z), rpy_rotation<double>(rpy)};
}

/// The base angular velocity and acceleration of a reference in orientation coordinates:
/// w = E(phi) phi_dot (E^{-1} inverted numerically: an independent path from the one at() takes).
Vec3<double> angular_velocity(const Desired<double>& d) {
  const Mat3<double> Einv = angular_to_phi_rate<double>(d.x.tail<3>());
  return Einv.inverse() * d.xd.tail<3>();
}

/// What a reference did over a run of ticks.
struct Trace {
  double v = 0, a = 0, j = 0, w = 0, wd = 0;  // peak linear speed, acceleration, jerk; angular speed, acceleration
  double jump = 0;                            // largest change of x, xd, xdd in one tick beyond what the limits allow
  double off_line = 0;                        // largest distance from the line p0 -> p1
  double derivative = 0;                      // largest mismatch of x, xd with the trapezoidal integrals of xd, xdd
  int finished = 0, stopped = 0;              // events
  std::vector<std::uint32_t> done;            // the ids of the moves done, in order
  int ticks = 0;
  Desired<double> last{};
};

/// Runs the generator from tick t0 for n ticks (or until an event when until_event), recording the
/// reference's peaks; jerk from the difference of accelerations.
template <class S>
Trace run(MotionGenerator<S>& g, std::uint64_t t0, int n, bool until_event, const Vec3<double>* line = nullptr) {
  Trace tr;
  Desired<double> prev{Vec6<double>::Zero(), Vec6<double>::Zero(), Vec6<double>::Zero()};
  Vec3<double> w_prev = Vec3<double>::Zero();
  for (int i = 0; i < n; ++i) {
    MotionEvents ev;
    const Desired<S> ds = g.at_tick(t0 + i, kHz, ev);
    Desired<double> d{ds.x.template cast<double>(), ds.xd.template cast<double>(), ds.xdd.template cast<double>()};
    tr.v = std::max(tr.v, d.xd.head<3>().norm());
    tr.a = std::max(tr.a, d.xdd.head<3>().norm());
    const Vec3<double> w = angular_velocity(d);
    tr.w = std::max(tr.w, w.norm());
    if (i > 0) {
      tr.j = std::max(tr.j, (d.xdd.head<3>() - prev.xdd.head<3>()).norm() * kHz);
      tr.wd = std::max(tr.wd, (w - w_prev).norm() * kHz);
      // Continuity: the position moves by at most v dt, the velocity by at most a dt (plus slack).
      tr.jump = std::max(tr.jump, (d.x.head<3>() - prev.x.head<3>()).norm() - 1.01 * params::kMoveLinear[0] / kHz);
      tr.jump = std::max(tr.jump, (d.xd.head<3>() - prev.xd.head<3>()).norm() - 1.01 * params::kMoveLinear[1] / kHz);
      // xd and xdd are the derivatives of x and xd: the trapezoidal rule over one tick errs by at most
      // j dt / 8 where the jerk switches inside it (3e-4 at 2.5 m/s^3, 1.25e-3 at 10 rad/s^3).
      tr.derivative = std::max(tr.derivative, ((d.x - prev.x) * kHz - (d.xd + prev.xd) / 2).cwiseAbs().maxCoeff());
      tr.derivative = std::max(tr.derivative, ((d.xd - prev.xd) * kHz - (d.xdd + prev.xdd) / 2).cwiseAbs().maxCoeff());
    }
    if (line) {
      const Vec3<double> r = d.x.head<3>() - line[0], u = (line[1] - line[0]).normalized();
      tr.off_line = std::max(tr.off_line, (r - u * r.dot(u)).norm());
    }
    tr.finished += ev.finished, tr.stopped += ev.stopped;
    if (ev.done_id != 0) tr.done.push_back(ev.done_id);
    prev = d, w_prev = w;
    tr.last = d;
    ++tr.ticks;
    if (until_event && (ev.finished || ev.stopped)) break;
  }
  return tr;
}

const CartesianLimits<double> kLim = CartesianLimits<double>::defaults();

void expect_within_limits(const Trace& tr, double slack = 1e-9) {
  EXPECT_LE(tr.v, params::kMoveLinear[0] * (1 + slack));
  EXPECT_LE(tr.a, params::kMoveLinear[1] * (1 + slack));
  EXPECT_LE(tr.j, params::kMoveLinear[2] * (1 + 1e-6));  // a difference quotient of a piecewise-linear a
  EXPECT_LE(tr.w, params::kMoveAngular[0] * (1 + 1e-6));
  EXPECT_LE(tr.wd, params::kMoveAngular[1] * (1 + 1e-3));
  EXPECT_LE(tr.jump, 0.0);
  EXPECT_LE(tr.derivative, 0.25 * params::kMoveAngular[2] / kHz);
}

TEST(CartesianMove, StraightLineAboutOneAxisWithinItsLimitsEndingAtTheTarget) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose<double> a =
        pose(0.4 + 0.1 * U(rng), 0.1 * U(rng), 0.3 + 0.1 * U(rng), {0.3 * U(rng), 0.3 * U(rng), U(rng)});
    const Pose<double> b =
        pose(0.4 + 0.2 * U(rng), 0.2 * U(rng), 0.3 + 0.2 * U(rng), {0.3 * U(rng), 0.3 * U(rng), U(rng)});
    const Mat3<double> R_ref = rpy_rotation<double>({0.1, -0.2, 0.3});
    CartesianMove<double> m;
    ASSERT_EQ(m.plan(a, b, kLim, R_ref), ProfileStatus::kOk);
    // Synchronised: both profiles last the move's duration (or are empty).
    for (double dur : {m.linear().duration(), m.angular().duration()}) {
      if (dur > 0) {
        EXPECT_NEAR(dur, m.duration(), 1e-9);
      }
    }
    MotionGenerator<double> g;
    g.hold(a, R_ref);
    ASSERT_TRUE(g.push(m));
    g.start_moves(100);
    const Vec3<double> line[2] = {a.p, b.p};
    const Trace tr = run(g, 100, 20000, true, line);
    expect_within_limits(tr);
    EXPECT_LE(tr.off_line, 1e-12);
    EXPECT_EQ(tr.finished, 1);
    EXPECT_NEAR(tr.ticks - 1, m.duration() * kHz, 1.0);
    // It ends holding the target: position and orientation coordinates of b.
    EXPECT_LE((tr.last.x.head<3>() - b.p).norm(), 1e-12);
    EXPECT_LE((tr.last.x.tail<3>() - orientation_coordinates<double>(b.R, R_ref)).norm(), 1e-9);
    EXPECT_EQ(tr.last.xd.norm(), 0.0);
  }
}

TEST(CartesianMove, OrientationRatesAreTheDerivativesOfItsCoordinates) {
  const Mat3<double> R_ref = rpy_rotation<double>({0.2, 0.1, -0.4});
  CartesianMove<double> m;
  ASSERT_EQ(m.plan(pose(0.5, 0, 0.3, {0, 0, 0}), pose(0.5, 0.05, 0.3, {0.5, -0.4, 0.9}), kLim, R_ref),
            ProfileStatus::kOk);
  const double h = 1e-6;
  double worst_v = 0, worst_a = 0;
  for (double t = 0.01; t < m.duration(); t += 0.037) {
    const Desired<double> d = m.at(t), dp = m.at(t + h), dm = m.at(t - h);
    worst_v = std::max(worst_v, ((dp.x - dm.x) / (2 * h) - d.xd).norm());
    worst_a = std::max(worst_a, ((dp.xd - dm.xd) / (2 * h) - d.xdd).norm());
    // The orientation is the rotation about the one axis: R(t) R0^T = Rot(k, psi(t)).
    const Mat3<double> R = rpy_rotation<double>(d.x.tail<3>()) * R_ref;
    const Mat3<double> Rd = R * rpy_rotation<double>({0, 0, 0}).transpose();
    Vec3<double> k;
    double angle;
    rotation_axis_angle<double>(Rd, k, angle);
    EXPECT_NEAR(std::abs(k.dot(m.axis())), 1.0, 1e-9) << t;
    EXPECT_NEAR(angle, m.angular().at(t).p, 1e-9) << t;
  }
  EXPECT_LE(worst_v, 1e-6);
  EXPECT_LE(worst_a, 1e-4);
}

TEST(CartesianMove, RefusesRotationsBeyondTheLimitAndNonFiniteTargets) {
  CartesianMove<double> m;
  const Pose<double> a = pose(0.5, 0, 0.3, {0, 0, 0});
  EXPECT_EQ(m.plan(a, pose(0.5, 0, 0.3, {0, 0, 3.0}), kLim, a.R), ProfileStatus::kBadTarget);
  EXPECT_EQ(m.plan(a, pose(NAN, 0, 0.3, {0, 0, 0}), kLim, a.R), ProfileStatus::kBadTarget);
  CartesianLimits<double> bad = kLim;
  bad.linear.v = 0;
  EXPECT_EQ(m.plan(a, pose(0.6, 0, 0.3, {0, 0, 0}), bad, a.R), ProfileStatus::kBadLimits);
  EXPECT_FALSE(bad.within(kLim));
  bad = kLim;
  bad.angular.j *= 1.01;
  EXPECT_FALSE(bad.within(kLim));
  EXPECT_TRUE(kLim.within(kLim));
}

TEST(MotionGenerator, StopDeceleratesAlongThePathWithinTheLimits) {
  const Pose<double> a = pose(0.5, -0.2, 0.3, {0, 0, 0}), b = pose(0.5, 0.3, 0.2, {0, 0, 1.2});
  for (int at : {50, 400, 1500, 3000}) {
    MotionGenerator<double> g;
    g.hold(a, a.R);
    CartesianMove<double> m;
    ASSERT_EQ(m.plan(a, b, kLim, a.R), ProfileStatus::kOk);
    ASSERT_TRUE(g.push(m));
    g.start_moves(0);
    const Vec3<double> line[2] = {a.p, b.p};
    Trace before = run(g, 0, at, false, line);
    g.stop(at, kHz, kLim);
    EXPECT_TRUE(g.stopping());
    const Trace after = run(g, at, 20000, true, line);
    expect_within_limits(before);
    expect_within_limits(after);
    EXPECT_LE(after.off_line, 1e-12);
    EXPECT_EQ(after.stopped, 1) << at;
    EXPECT_EQ(after.finished, 0);
    // It came to rest short of the target, sooner than the move would have ended.
    EXPECT_LT(at + after.ticks, m.duration() * kHz + 1) << at;
    EXPECT_EQ(g.source(), MotionSource::kHold);
    // Continuity across the stop: the first tick after it continues the last before.
    EXPECT_LE((after.last.xd).norm(), 0.0);
  }
}

TEST(MotionGenerator, QueueHoldsSixteenWaitingMovesAndRunsThemInOrder) {
  const Pose<double> a = pose(0.5, 0, 0.3, {0, 0, 0});
  MotionGenerator<double> g;
  g.hold(a, a.R);
  int pushed = 0;
  for (int i = 0; i < 30; ++i) {
    const Pose<double> from = g.queue_end();
    const Pose<double> to = pose(0.5 + 0.02 * ((i % 2) ? -1 : 1), 0.01 * i, 0.3, {0, 0, 0.05 * (i % 3)});
    CartesianMove<double> m;
    ASSERT_EQ(m.plan(from, to, kLim, a.R), ProfileStatus::kOk);
    if (!g.push(m)) break;
    ++pushed;
  }
  EXPECT_EQ(pushed, params::kMoveQueueLength + 1);  // the one that runs and sixteen waiting
  EXPECT_TRUE(g.queue_full());
  const Pose<double> last = g.queue_end();
  g.start_moves(0);
  const Trace tr = run(g, 0, 200000, true);
  expect_within_limits(tr);
  EXPECT_EQ(tr.finished, 1);
  EXPECT_LE((tr.last.x.head<3>() - last.p).norm(), 1e-12);
  EXPECT_EQ(g.queued(), 0);
}

TEST(MotionGenerator, RetargetBrakesAlongThePathThenMovesToTheNewTarget) {
  const Pose<double> a = pose(0.5, -0.2, 0.3, {0, 0, 0}), b = pose(0.5, 0.3, 0.3, {0, 0, 0}),
                     c = pose(0.4, 0.0, 0.45, {0, 0, 0.5});
  MotionGenerator<double> g;
  g.hold(a, a.R);
  CartesianMove<double> m;
  ASSERT_EQ(m.plan(a, b, kLim, a.R), ProfileStatus::kOk);
  g.push(m);
  g.push(m);  // a waiting move that the re-target drops
  g.start_moves(0);
  const Trace before = run(g, 0, 1200, false);
  g.brake(1200, kHz, kLim);
  CartesianMove<double> r;
  ASSERT_EQ(r.plan(g.queue_end(), c, kLim, a.R), ProfileStatus::kOk);
  ASSERT_TRUE(g.push(r));
  EXPECT_EQ(g.queued(), 2);
  const Trace after = run(g, 1200, 100000, true);
  expect_within_limits(before);
  expect_within_limits(after);
  EXPECT_EQ(after.finished, 1);
  EXPECT_EQ(after.stopped, 0);
  EXPECT_LE((after.last.x.head<3>() - c.p).norm(), 1e-12);
}

/// The ids of the moves waiting in g.
std::vector<std::uint32_t> waiting(const MotionGenerator<double>& g) {
  std::uint32_t ids[MotionGenerator<double>::kMaxWaiting];
  return {ids, ids + g.waiting_ids(ids, MotionGenerator<double>::kMaxWaiting)};
}

/// A re-target while the running move brakes for one before: the move that waited for that brake is
/// dropped (named first by waiting_ids), the brake goes on, and the new move starts where it ends.
TEST(MotionGenerator, ABrakeWhileBrakingDropsTheMovesWaitingAndTheBrakesEndStays) {
  const Pose<double> a = pose(0.5, -0.2, 0.3, {0, 0, 0}), b = pose(0.5, 0.3, 0.3, {0, 0, 0}),
                     c = pose(0.4, 0.0, 0.45, {0, 0, 0.5});
  MotionGenerator<double> g;
  g.hold(a, a.R);
  CartesianMove<double> m;
  ASSERT_EQ(m.plan(a, b, kLim, a.R), ProfileStatus::kOk);
  for (std::uint32_t id : {1u, 2u, 3u}) ASSERT_TRUE(g.push(m, id));
  g.start_moves(0);
  EXPECT_EQ(waiting(g), (std::vector<std::uint32_t>{2, 3}));
  run(g, 0, 1200, false);
  g.brake(1200, kHz, kLim);
  EXPECT_EQ(g.queued(), 1);
  EXPECT_TRUE(waiting(g).empty());
  const Pose<double> rest = g.brake_end(1250, kHz, kLim);  // braking already: where it comes to rest
  EXPECT_EQ(rest.p, g.queue_end().p);
  CartesianMove<double> r;
  ASSERT_EQ(r.plan(rest, b, kLim, a.R), ProfileStatus::kOk);
  ASSERT_TRUE(g.push(r, 4));
  EXPECT_EQ(waiting(g), (std::vector<std::uint32_t>{4}));
  const std::uint32_t epoch = g.epoch();
  g.brake(1250, kHz, kLim);  // the second re-target
  EXPECT_EQ(g.epoch(), epoch + 1);
  EXPECT_EQ(g.queued(), 1);
  EXPECT_TRUE(waiting(g).empty());
  EXPECT_EQ(g.running_id(), 1u);  // still braking
  EXPECT_EQ(g.brake_end(1300, kHz, kLim).p, rest.p);
  ASSERT_EQ(r.plan(rest, c, kLim, a.R), ProfileStatus::kOk);
  ASSERT_TRUE(g.push(r, 5));
  const Trace after = run(g, 1250, 100000, true);
  expect_within_limits(after);
  EXPECT_EQ(after.finished, 1);
  EXPECT_LE((after.last.x.head<3>() - c.p).norm(), 1e-12);
  EXPECT_EQ(after.done, (std::vector<std::uint32_t>{5}));  // the braked move is never done
}

TEST(MotionGenerator, AHaltDropsEveryMotionAtOnce) {
  const Pose<double> a = pose(0.5, -0.2, 0.3, {0, 0, 0}), b = pose(0.5, 0.3, 0.3, {0, 0, 0});
  MotionGenerator<double> g;
  g.hold(a, a.R);
  CartesianMove<double> m;
  ASSERT_EQ(m.plan(a, b, kLim, a.R), ProfileStatus::kOk);
  for (std::uint32_t id : {1u, 2u, 3u}) ASSERT_TRUE(g.push(m, id));
  g.start_moves(0);
  run(g, 0, 500, false);
  EXPECT_EQ(waiting(g), (std::vector<std::uint32_t>{2, 3}));
  const std::uint32_t epoch = g.epoch();
  g.halt();
  EXPECT_EQ(g.epoch(), epoch + 1);
  EXPECT_EQ(g.source(), MotionSource::kHold);
  EXPECT_EQ(g.queued(), 0);
  EXPECT_EQ(g.running_id(), 0u);
  EXPECT_TRUE(waiting(g).empty());
  const Trace after = run(g, 500, 10, false);  // the pose held last, at rest, no event
  EXPECT_EQ(after.last.x.head<3>(), a.p);
  EXPECT_EQ(after.v, 0.0);
  EXPECT_EQ(after.finished + after.stopped, 0);
  EXPECT_TRUE(after.done.empty());
}

/// Moves pushed while the paper's motion slows down wait behind it, all of them (none has started).
TEST(MotionGenerator, MovesBehindThePapersSlowDownAllWaitAndABrakeDropsThem) {
  const Pose<double> a = pose(0.5, 0, 0.3, {0, 0, 0});
  MotionGenerator<double> g;
  g.hold(a, a.R);
  g.start_paper(TrajectorySpec<double>::paper(), 0, 7);
  run(g, 0, 3000, false);
  g.brake(3000, kHz, kLim);
  int pushed = 0;
  for (std::uint32_t id = 10;; ++id) {
    CartesianMove<double> m;
    ASSERT_EQ(m.plan(g.queue_end(), pose(0.45, 0.01 * pushed, 0.35, {0, 0, 0}), kLim, a.R), ProfileStatus::kOk);
    if (!g.push(m, id)) break;
    ++pushed;
  }
  EXPECT_EQ(pushed, MotionGenerator<double>::kMaxWaiting);
  EXPECT_EQ(waiting(g).size(), static_cast<std::size_t>(pushed));
  EXPECT_EQ(waiting(g).front(), 10u);
  EXPECT_EQ(g.running_id(), 7u);
  const Pose<double> rest = g.brake_end(3100, kHz, kLim);  // the slow-down's end, not the last move's
  g.brake(3100, kHz, kLim);
  EXPECT_EQ(g.queued(), 0);
  EXPECT_EQ(g.queue_end().p, rest.p);
  const Trace after = run(g, 3100, 100000, true);
  EXPECT_EQ(after.finished, 1);
  EXPECT_LE((after.last.x.head<3>() - rest.p).norm(), 1e-12);
}

TEST(MotionGenerator, PaperMotionSlowsDownAlongItsPathAndMayBeFollowedByMoves) {
  const Pose<double> a = pose(0.5, 0, 0.3, {0, 0, 0});
  const TrajectorySpec<double> spec = TrajectorySpec<double>::paper();
  for (bool then_move : {false, true}) {
    MotionGenerator<double> g;
    g.hold(a, a.R);
    g.start_paper(spec, 10);
    MotionEvents ev;
    // The same reference as the paper's motion started at tick 10 (bit for bit).
    const PaperMotion<double> ref{spec, a.p, 10};
    for (std::uint64_t t = 10; t < 30000; t += 997) EXPECT_EQ(g.at_tick(t, kHz, ev).x, ref.at_tick(t, kHz).x);
    const Trace before = run(g, 30000, 1, false);
    if (then_move) {
      g.brake(30001, kHz, kLim);
      CartesianMove<double> m;
      ASSERT_EQ(m.plan(g.queue_end(), pose(0.45, 0.05, 0.35, {0, 0, 0}), kLim, a.R), ProfileStatus::kOk);
      ASSERT_TRUE(g.push(m));
    } else {
      g.stop(30001, kHz, kLim);
    }
    const Trace after = run(g, 30001, 100000, true);
    EXPECT_LE((after.last.xd).norm(), 0.0);
    EXPECT_EQ(after.stopped, then_move ? 0 : 1);
    EXPECT_EQ(after.finished, then_move ? 1 : 0);
    // The slow-down's acceleration: at most (68)'s plus its speed times kPaperStopRate, per axis.
    const double bound =
        std::sqrt(3.0) * (spec.amplitude * spec.omega * spec.omega + spec.amplitude * spec.omega * kPaperStopRate);
    EXPECT_LE(after.a, std::max(bound, params::kMoveLinear[1]) * (1 + 1e-9));
    EXPECT_LE(after.jump, 0.0);
    EXPECT_LE(after.derivative, 0.25 * params::kMoveAngular[2] / kHz);
    EXPECT_GT(before.v, 0.0);
  }
}

/// The same queue of moves in float and Q12.19 against double: the references agree to the
/// scalar's resolution, and each stays within the limits.
template <class S>
void compare_scalar(double tol_pos, double tol_vel) {
  const Pose<double> a = pose(0.5, -0.1, 0.3, {0.1, 0, 0}), b = pose(0.45, 0.15, 0.35, {0.1, 0.2, 0.6});
  const auto cast_pose = [](const Pose<double>& p) { return Pose<S>{p.p.cast<S>(), p.R.cast<S>()}; };
  MotionGenerator<double> gd;
  MotionGenerator<S> gs;
  gd.hold(a, a.R);
  gs.hold(cast_pose(a), a.R.cast<S>());
  CartesianMove<double> md;
  CartesianMove<S> ms;
  // The double plan at the limits the S plan uses (less its rounding margin, rounding_margin()).
  const CartesianLimits<S> ls = CartesianLimits<S>::defaults();
  const auto margin = [](const JerkLimits<S>& l) {
    const JerkLimits<S> m = rounding_margin(l);
    return JerkLimits<double>{static_cast<double>(m.v), static_cast<double>(m.a), static_cast<double>(m.j)};
  };
  ASSERT_EQ(md.plan(a, b, {margin(ls.linear), margin(ls.angular)}, a.R), ProfileStatus::kOk);
  ASSERT_EQ(ms.plan(cast_pose(a), cast_pose(b), CartesianLimits<S>::defaults(), a.R.cast<S>()), ProfileStatus::kOk);
  gd.push(md), gs.push(ms);
  gd.start_moves(0), gs.start_moves(0);
  double ep = 0, ev = 0;
  for (std::uint64_t t = 0; t < 5000; ++t) {
    MotionEvents e1, e2;
    const Desired<double> d = gd.at_tick(t, kHz, e1);
    const Desired<S> s = gs.at_tick(t, kHz, e2);
    ep = std::max(ep, (s.x.template cast<double>() - d.x).norm());
    ev = std::max(ev, (s.xd.template cast<double>() - d.xd).norm());
  }
  EXPECT_LE(ep, tol_pos);
  EXPECT_LE(ev, tol_vel);
  const Trace tr = run(gs, 5000, 1, false);
  EXPECT_EQ(tr.v, 0.0);  // at rest at the end
}

TEST(MotionGenerator, FloatAgreesWithDouble) { compare_scalar<float>(2e-6, 2e-5); }
TEST(MotionGenerator, FixedAgreesWithDouble) { compare_scalar<Fixed>(2e-4, 2e-3); }

}  // namespace
