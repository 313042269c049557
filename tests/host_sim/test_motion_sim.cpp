// Commanded motion in closed loop (host_sim/motion_sim.hpp: the control task over the simulated
// PUMA 560): enable from random poses holds the arm (the tip moves at most 0.5 mm); a move is
// tracked within 1 mm and ends done; a stop and a disable decelerate along the path and hold or
// cut the torque; every refusal reason the runtime decides is produced; the paper's motion by
// command; a fault and its clear. Each in double, and the move in float and fixed point.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "motion_sim.hpp"

using namespace osc;
using sim::MotionSim;
using V3 = sim::Vec3;
using V6 = sim::Vec6;

namespace {

V6 start_pose() {
  V6 q;
  for (int i = 0; i < 6; ++i) q(i) = robot::kQStart[i];
  return q;
}

/// What a run of ticks saw.
struct Trace {
  int ticks = 0;
  std::uint32_t faults = 0;
  double tracking = 0;                // largest |reference position - true tip| while torque was on [m]
  double tip_moved = 0;               // largest |tip - tip at the start of the run| [m]
  std::vector<MotionReport> reports;  // every tick's report with something in it
  bool ended = false;                 // the predicate became true
};

template <class S, class Pred>
Trace run_until(MotionSim<S>& sim, Pred done, int max_ticks) {
  Trace r;
  const V3 tip0 = sim.tip();
  for (int k = 0; k < max_ticks; ++k) {
    r.faults |= sim.tick();
    ++r.ticks;
    const MotionReport& rep = sim.task().report;
    if (rep.outcome != CommandOutcome::kNone || rep.completion != MotionCompletion::kNone ||
        rep.abort != MotionReason::kNone || rep.done_id != 0)
      r.reports.push_back(rep);
    if (motion_powered(sim.task().machine.state))
      r.tracking = std::max(r.tracking, (sim.reference().template head<3>() - sim.tip()).norm());
    r.tip_moved = std::max(r.tip_moved, (sim.tip() - tip0).norm());
    if (done(sim)) {
      r.ended = true;
      break;
    }
  }
  return r;
}

template <class S>
Trace run_ticks(MotionSim<S>& sim, int n) {
  return run_until(
      sim, [](const MotionSim<S>&) { return false; }, n);
}

/// Sends a command and runs the tick that answers it; returns that tick's report.
template <class S>
MotionReport answer(MotionSim<S>& sim, MotionVerb verb, std::uint32_t id) {
  sim.command(verb, id);
  sim.tick();
  return sim.task().report;
}
template <class S>
MotionReport answer_move(MotionSim<S>& sim, const MoveRequest<S>& req, std::uint32_t id) {
  sim.move_to(req, id);
  sim.tick();
  return sim.task().report;
}

template <class S>
MoveRequest<S> relative(double dx, double dy, double dz) {
  MoveRequest<S> r;
  r.relative = true;
  r.position = Vec3<S>(static_cast<S>(dx), static_cast<S>(dy), static_cast<S>(dz));
  return r;
}

template <class S>
bool state_is(const MotionSim<S>& sim, MotionState s) {
  return sim.task().machine.state == s;
}

TEST(MotionSim, EnableAtRandomPosesHoldsTheArmWithinHalfAMillimetre) {
  std::mt19937 rng(2026);
  double worst = 0;
  int poses = 0;
  while (poses < 20) {
    V6 q;
    for (int i = 0; i < 6; ++i) {
      std::uniform_real_distribution<double> u(robot::kArm.q_min[i] + 0.2, robot::kArm.q_max[i] - 0.2);
      q(i) = u(rng);
    }
    // A reachable pose the controller can act at: away from the wrist and elbow singularities.
    Model<double> model = Model<double>::of(robot::kArm);
    Data<double> data;
    OpSpace<double> os;
    opspace_update(model, data, os, q, Mat3<double>(Mat3<double>::Identity()));
    if (os.Jf.rcond < 10 * params::kPathMinRcond) continue;
    MotionSim<double> sim(q);
    const MotionReport rep = answer(sim, MotionVerb::kEnable, 1);
    EXPECT_EQ(rep.outcome, CommandOutcome::kAccepted);
    const Trace r = run_ticks(sim, 2000);
    EXPECT_EQ(r.faults, 0u) << q.transpose();
    EXPECT_TRUE(state_is(sim, MotionState::kHolding));
    EXPECT_LE(r.tip_moved, 0.5e-3) << q.transpose();
    worst = std::max(worst, r.tip_moved);
    ++poses;
  }
  RecordProperty("worst_tip_motion_mm", std::to_string(worst * 1e3));
  std::printf("enable at 20 random poses: the tip moved at most %.4f mm\n", worst * 1e3);
}

/// Enable, then (warm) the paper's motion for 10 s so that the friction estimates have been
/// learnt, a stop; then a move with a rotation, tracked within tol, ending done at its target.
template <class S>
double move_and_finish(bool warm, double tol) {
  MotionSim<S> sim(start_pose());
  EXPECT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 300);
  if (warm) {
    EXPECT_EQ(answer(sim, MotionVerb::kPaper, 2).outcome, CommandOutcome::kAccepted);
    run_ticks(sim, 10000);
    EXPECT_EQ(answer(sim, MotionVerb::kStop, 3).outcome, CommandOutcome::kAccepted);
    run_until(
        sim, [](const MotionSim<S>& s) { return state_is(s, MotionState::kHolding); }, 10000);
  }
  MoveRequest<S> req = relative<S>(0.10, -0.08, 0.05);
  req.has_rpy = true;
  req.rpy = Vec3<S>(S(0), S(0), static_cast<S>(0.3));
  EXPECT_EQ(answer_move(sim, req, 7).outcome, CommandOutcome::kAccepted);
  EXPECT_TRUE(state_is(sim, MotionState::kMoving));
  const V3 target = sim.task().gen.queue_end().p.template cast<double>();
  const Trace r = run_until(
      sim, [](const MotionSim<S>& s) { return s.task().report.done_id != 0; }, 20000);
  EXPECT_TRUE(r.ended);
  EXPECT_EQ(r.faults, 0u);
  EXPECT_EQ(sim.task().report.done_id, 7u);
  EXPECT_EQ(sim.task().report.completion, MotionCompletion::kFinished);
  EXPECT_TRUE(state_is(sim, MotionState::kHolding));
  EXPECT_LE(r.tracking, tol);
  // Held at the target: within the tracking tolerance after a settling second.
  run_ticks(sim, 1000);
  EXPECT_LE((sim.tip() - target).norm(), tol);
  std::printf("move_to (%s, %s): tracking %.4f mm, end error %.4f mm\n", typeid(S).name(), warm ? "warm" : "cold",
              r.tracking * 1e3, (sim.tip() - target).norm() * 1e3);
  return r.tracking;
}

TEST(MotionSim, MoveIsTrackedWithinOneMillimetreAndEndsDone) { move_and_finish<double>(true, 1e-3); }
TEST(MotionSim, MoveInFloat) { move_and_finish<float>(true, 1e-3); }
TEST(MotionSim, MoveInFixedPoint) { move_and_finish<Fixed>(true, 1e-3); }
// From a cold start (theta^ = 0: no friction learnt yet) the first move's break-away from static
// friction costs more: 1.5 mm measured (issue 26 speeds up the identification; issue 27 keeps
// theta^ across power cycles).
TEST(MotionSim, ColdStartMoveIsTrackedWithinTwoMillimetres) { EXPECT_GT(move_and_finish<double>(false, 2e-3), 1e-3); }

TEST(MotionSim, StopDeceleratesThenHolds) {
  MotionSim<double> sim(start_pose());
  answer(sim, MotionVerb::kEnable, 1);
  run_ticks(sim, 100);
  ASSERT_EQ(answer_move(sim, relative<double>(0.2, 0, 0), 2).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 1500);
  const MotionReport stop = answer(sim, MotionVerb::kStop, 3);
  EXPECT_EQ(stop.outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(stop.abort, MotionReason::kStopCommand);
  EXPECT_EQ(stop.aborted_id, 2u);
  EXPECT_TRUE(state_is(sim, MotionState::kStopping));
  const Trace r = run_until(
      sim, [](const MotionSim<double>& s) { return s.task().report.completion != MotionCompletion::kNone; }, 10000);
  ASSERT_TRUE(r.ended);
  EXPECT_EQ(sim.task().report.completion, MotionCompletion::kStopped);
  EXPECT_EQ(sim.task().report.done_id, 0u);  // the move did not reach its target
  EXPECT_TRUE(state_is(sim, MotionState::kHolding));
  EXPECT_EQ(r.faults, 0u);
  EXPECT_LE(r.tracking, 1e-3);
  // It stopped short of the target, along the line (y, z unchanged to the tracking error).
  const V3 rest = sim.task().gen.hold_pose().p;
  const V3 start = rest - V3(rest.x() - sim.tip().x(), 0, 0);
  EXPECT_LT((rest - start).norm(), 0.2);
}

TEST(MotionSim, DisableWhileMovingStopsThenCutsTheTorque) {
  MotionSim<double> sim(start_pose());
  answer(sim, MotionVerb::kEnable, 1);
  answer_move(sim, relative<double>(0, 0.15, 0), 2);
  run_ticks(sim, 1000);
  const MotionReport rep = answer(sim, MotionVerb::kDisable, 3);
  EXPECT_EQ(rep.outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(rep.abort, MotionReason::kDisableCommand);
  EXPECT_TRUE(state_is(sim, MotionState::kStopping));
  const Trace r = run_until(
      sim, [](const MotionSim<double>& s) { return state_is(s, MotionState::kDisabled); }, 10000);
  ASSERT_TRUE(r.ended);
  EXPECT_EQ(sim.task().report.completion, MotionCompletion::kStopped);
  EXPECT_EQ(r.faults, 0u);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(sim.task().codes[i], 0);
  EXPECT_TRUE(sim.plant().brakes());
}

TEST(MotionSim, EveryRuntimeRefusalIsNamed) {
  MotionSim<double> sim(start_pose());
  // not_enabled: a move and a stop while disabled.
  EXPECT_EQ(answer_move(sim, relative<double>(0.05, 0, 0), 1).refusal, MotionReason::kNotEnabled);
  EXPECT_EQ(answer(sim, MotionVerb::kStop, 2).refusal, MotionReason::kNotEnabled);
  answer(sim, MotionVerb::kEnable, 3);
  // over_limit: a limit above the configured maximum.
  MoveRequest<double> fast = relative<double>(0.05, 0, 0);
  fast.has_limits = true;
  fast.limits = CartesianLimits<double>::defaults();
  fast.limits.linear.v *= 2;
  EXPECT_EQ(answer_move(sim, fast, 4).refusal, MotionReason::kOverLimit);
  // ... and a rotation beyond 170 degrees.
  MoveRequest<double> spin = relative<double>(0, 0, 0);
  spin.has_rpy = true;
  spin.rpy = V3(0, 0, 3.0);
  EXPECT_EQ(answer_move(sim, spin, 5).refusal, MotionReason::kOverLimit);
  // queue_full: the running move and sixteen waiting, then one more.
  int accepted = 0;
  MotionReport rep;
  for (int i = 0; i < 30; ++i) {
    rep = answer_move(sim, relative<double>(i % 2 ? -0.01 : 0.01, 0, 0), 10 + i);
    if (rep.outcome != CommandOutcome::kAccepted) break;
    ++accepted;
  }
  EXPECT_EQ(accepted, params::kMoveQueueLength + 1);
  EXPECT_EQ(rep.refusal, MotionReason::kQueueFull);
  // busy: the paper's motion while moves run.
  EXPECT_EQ(answer(sim, MotionVerb::kPaper, 50).refusal, MotionReason::kBusy);
  // stopping: a move during a stop.
  answer(sim, MotionVerb::kStop, 52);
  EXPECT_EQ(answer_move(sim, relative<double>(0.01, 0, 0), 53).refusal, MotionReason::kStopping);
  run_until(
      sim, [](const MotionSim<double>& s) { return state_is(s, MotionState::kHolding); }, 10000);
  // superseded: the queue changed between the plan and its tick (here: a new hold).
  sim.move_to(relative<double>(0, 0.01, 0), 51);
  sim.task().gen.hold(sim.task().gen.hold_pose(), sim.task().gen.reference_orientation());
  sim.tick();
  EXPECT_EQ(sim.task().report.refusal, MotionReason::kSuperseded);
  // faulted: every command but clear while in fault; clear leads to disabled.
  sim.task().inject_nonfinite();
  run_ticks(sim, 2);
  EXPECT_TRUE(state_is(sim, MotionState::kFault));
  const MotionReport f = answer(sim, MotionVerb::kEnable, 54);
  EXPECT_EQ(f.refusal, MotionReason::kFaulted);
  EXPECT_NE(f.cause, 0u);
  EXPECT_EQ(answer(sim, MotionVerb::kClear, 55).outcome, CommandOutcome::kAccepted);
  EXPECT_TRUE(state_is(sim, MotionState::kDisabled));
  run_ticks(sim, 2);
  EXPECT_EQ(answer(sim, MotionVerb::kEnable, 56).outcome, CommandOutcome::kAccepted);
  const Trace r = run_ticks(sim, 500);
  EXPECT_EQ(r.faults, 0u);
  EXPECT_TRUE(state_is(sim, MotionState::kHolding));
}

TEST(MotionSim, ClearIsRefusedWhileTheCauseIsPresent) {
  sim::Injection inj;
  inj.enabled = true;
  inj.kind = sim::InjectionKind::kEstop;
  inj.at = 0.5;
  MotionSim<double> sim(start_pose(), inj);
  answer(sim, MotionVerb::kEnable, 1);
  run_ticks(sim, 600);
  EXPECT_TRUE(state_is(sim, MotionState::kFault));
  const MotionReport rep = answer(sim, MotionVerb::kClear, 2);
  EXPECT_EQ(rep.refusal, MotionReason::kFaulted);
  EXPECT_EQ(rep.cause, static_cast<std::uint32_t>(kFaultEstop));
}

TEST(MotionSim, PaperMotionByCommandThenAStopAlongItsPath) {
  MotionSim<double> sim(start_pose());
  answer(sim, MotionVerb::kEnable, 1);
  run_ticks(sim, 200);
  EXPECT_EQ(answer(sim, MotionVerb::kPaper, 2).outcome, CommandOutcome::kAccepted);
  const Trace moving = run_ticks(sim, 8000);
  EXPECT_EQ(moving.faults, 0u);
  EXPECT_GT(moving.tip_moved, 0.03);
  // The first seconds from a cold start, as in the paper's experiment (0.68 / 0.83 / 0.81 mm per axis).
  EXPECT_LE(moving.tracking, 1.5e-3);
  const MotionReport stop = answer(sim, MotionVerb::kStop, 3);
  EXPECT_EQ(stop.aborted_id, 2u);
  const Trace r = run_until(
      sim, [](const MotionSim<double>& s) { return s.task().report.completion != MotionCompletion::kNone; }, 10000);
  ASSERT_TRUE(r.ended);
  EXPECT_EQ(r.faults, 0u);
  EXPECT_TRUE(state_is(sim, MotionState::kHolding));
}

/// A move to the pose of joint angles q (absolute position and orientation).
MoveRequest<double> to_joint_pose(const V6& q) {
  Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  forward_kinematics(model, data, q);
  MoveRequest<double> r;
  r.position = data.o[kDof];
  r.has_rpy = true;
  r.rpy = orientation_coordinates<double>(data.R[kDof], Mat3<double>::Identity());
  return r;
}

/// The arm enabled with joint 1 at 0.05 rad from its limit of 160 deg, and a move a quarter turn
/// further about the base axis (same radius and height): past that limit.
MoveRequest<double> quarter_turn_near_the_limit(std::unique_ptr<MotionSim<double>>& sim) {
  V6 q = start_pose();
  q(0) = robot::kArm.q_max[0] - 0.05;
  sim = std::make_unique<MotionSim<double>>(q);
  answer(*sim, MotionVerb::kEnable, 1);
  run_ticks(*sim, 100);
  const V3 p = sim->task().gen.hold_pose().p;
  MoveRequest<double> turn;
  turn.position = V3(-p.y(), p.x(), p.z());
  return turn;
}

TEST(MotionSim, PathChecksRefuseLeavingTheWorkspaceAndPassingASingularity) {
  MotionSim<double> sim(start_pose());
  answer(sim, MotionVerb::kEnable, 1);
  run_ticks(sim, 100);
  // Beyond the arm's reach.
  EXPECT_EQ(answer_move(sim, relative<double>(2.0, 0, 0), 2).refusal, MotionReason::kOutOfWorkspace);
  // Joint 5 from +45 deg through 0 to -20 deg: the wrist singularity on the way.
  V6 q = start_pose();
  q(4) = -0.35;
  EXPECT_EQ(answer_move(sim, to_joint_pose(q), 3).refusal, MotionReason::kNearSingular);
  // Joint 1 turned 90 degrees from 150 deg: past its limit of 160 deg.
  std::unique_ptr<MotionSim<double>> near;
  const MoveRequest<double> turn = quarter_turn_near_the_limit(near);
  EXPECT_EQ(answer_move(*near, turn, 2).refusal, MotionReason::kOutOfWorkspace);
  // A reachable move is accepted and ends done.
  q = start_pose();
  q(4) = 0.5, q(0) = 0.2;
  EXPECT_EQ(answer_move(sim, to_joint_pose(q), 4).outcome, CommandOutcome::kAccepted);
  const Trace r = run_until(
      sim, [](const MotionSim<double>& s) { return s.task().report.done_id == 4; }, 20000);
  EXPECT_TRUE(r.ended);
  EXPECT_EQ(r.faults, 0u);
}

TEST(MotionSim, AReachedJointLimitStopsTheMotion) {
  // Joint 1 near its limit (160 deg); a move that turns it past the limit, prepared without the path
  // check (which would refuse it): the tick's check stops it, category 2.
  std::unique_ptr<MotionSim<double>> owner;
  const MoveRequest<double> req = quarter_turn_near_the_limit(owner);
  MotionSim<double>& sim = *owner;
  sim.task().pending = prepare_move(sim.task().gen, sim.task().limits, sim.task().tick, params::kControlHz, req, 2);
  sim.tick();
  ASSERT_EQ(sim.task().report.outcome, CommandOutcome::kAccepted);
  const Trace r = run_until(
      sim, [](const MotionSim<double>& s) { return s.task().report.abort != MotionReason::kNone; }, 20000);
  ASSERT_TRUE(r.ended);
  EXPECT_EQ(sim.task().report.abort, MotionReason::kLimitReached);
  const Trace rest = run_until(
      sim, [](const MotionSim<double>& s) { return state_is(s, MotionState::kHolding); }, 10000);
  EXPECT_TRUE(rest.ended);
  EXPECT_EQ(r.faults | rest.faults, 0u);
}

}  // namespace
