// The motion generator (osc/control/motion.hpp): a stop along the path; the queue; the re-target; the
// paper's motion and its slow-down; float and Q12.19 against double. Each reference sampled every
// millisecond against its limits (motion_fixtures.hpp). The move itself: test_cartesian_move.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "motion_fixtures.hpp"
#include "osc/control/motion.hpp"
#include "osc/math/fixed.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST(MotionGenerator, StopDeceleratesAlongThePathWithinTheLimits) {
  const Pose<double> a = pose(0.5, -0.2, 0.3, {0, 0, 0}), b = pose(0.5, 0.3, 0.2, {0, 0, 1.2});
  // Stopped while speeding up, at the middle and at three quarters of the move (cruising at the arm's maxima,
  // before its deceleration: a stop there must come to rest sooner than the move would have ended).
  CartesianMove<double> planned;
  ASSERT_EQ(planned.plan(a, b, kLim, a.R), ProfileStatus::kOk);
  const int ticks = static_cast<int>(planned.duration() * kHz);
  for (int at : {50, 400, ticks / 2, 3 * ticks / 4}) {
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
