// Commanded motion in closed loop (host_sim/motion_sim.hpp: the control task over the simulated arm,
// the build's): enable from random poses holds the arm (the tip moves at most 0.5 mm); a move is
// tracked within 1 mm and ends done; 50 seeded random moves at the maxima, the same; a stop and a
// disable decelerate along the path and hold or cut the torque; every refusal reason the runtime
// decides is produced; the paper's motion by command; a fault and its clear. Each in double, and
// the move in float and fixed point.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "motion_sim.hpp"
#include "motion_sim_util.hpp"
#include "osc/control/sampled_loop.hpp"
#include "sampled_loop_reference.hpp"
#include "test_util.hpp"

using namespace osc;
using sim::MotionSim;
using V3 = sim::Vec3;
using V6 = sim::Vec6;
using test::answer;
using test::answer_move;
using test::relative;
using test::run_ticks;
using test::run_until;
using test::start_pose;
using test::state_is;
using test::to_joint_pose;
using test::Trace;

namespace {

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
    ArmOpSpace<double> os;
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
/// From a cold start (theta^ = 0) the first break-away costs more than a millimetre: on the PUMA 560
/// 2.32 mm at its maxima with the momentum law, which learns only from settled samples (at the first
/// maxima 2.29 mm, and 1.53 mm with the robust law, which learns from the tracking error at once;
/// docs/motion.md). The UR5e's estimated friction
/// (cou + sti 9 N m on J1-J3, a strain-wave gear's: docs/arms.md) against its lighter links costs
/// more: 2.74 mm on this move, 3.14-3.24 mm on the streams' first (measured); another arm's bound is
/// not yet derived from its sheet, so it takes the UR5e's.
constexpr double kColdStartTolerance = test::kPumaBuild ? 2.5e-3 : 3.5e-3;
/// The paper's motion from a cold start, its first seconds: on the PUMA 0.68 / 0.83 / 0.81 mm per
/// axis (as in the paper's experiment) under 1.5 mm; the UR5e's break-away 2.56 mm (measured).
constexpr double kColdStartPaperTolerance = test::kPumaBuild ? 1.5e-3 : 3e-3;
TEST(MotionSim, ColdStartMoveIsTrackedWithinTwoAndAHalfMillimetres) {
  EXPECT_GT(move_and_finish<double>(false, kColdStartTolerance), 1e-3);
}

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
  // The first seconds from a cold start, as in the paper's experiment (kColdStartPaperTolerance).
  EXPECT_LE(moving.tracking, kColdStartPaperTolerance);
  const MotionReport stop = answer(sim, MotionVerb::kStop, 3);
  EXPECT_EQ(stop.aborted_id, 2u);
  const Trace r = run_until(
      sim, [](const MotionSim<double>& s) { return s.task().report.completion != MotionCompletion::kNone; }, 10000);
  ASSERT_TRUE(r.ended);
  EXPECT_EQ(r.faults, 0u);
  EXPECT_TRUE(state_is(sim, MotionState::kHolding));
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

/// Starts a move prepared without the path check (which would refuse it), as the tick's own checks must stop it;
/// the tick that answers it runs.
void start_unchecked(MotionSim<double>& sim, const MoveRequest<double>& req, std::uint32_t id) {
  sim.task().pending = prepare_move(sim.task().gen, sim.task().limits, sim.task().tick, params::kControlHz, req, id);
  sim.tick();
}

/// The singular pose nearest the start pose along joint j's sweep (the other joints at the start pose): from
/// the start angle outward in each direction by 1 mrad, within the joint's limits less the path check's margin
/// and at most pi away, to where J's reciprocal condition first falls below the path check's kPathMinRcond and
/// then down to its least; the nearer of the two directions' (rcond 1: none on the sweep). For the wrist
/// (j = 4), the elbow (j = 2) and the shoulder (j = 1) of a 6R arm.
struct SweptSingularity {
  V6 q;
  double rcond = 1;
  int steps = 0;
};
SweptSingularity least_rcond_on_sweep(int j) {
  SweptSingularity best;
  const V6 q0 = start_pose();
  for (int dir : {-1, 1}) {
    SweptSingularity found;
    for (int k = 1; k <= 3142; ++k) {
      V6 q = q0;
      q(j) += dir * 1e-3 * k;
      if (q(j) < robot::kArm.q_min[j] + params::kWorkspaceMargin ||
          q(j) > robot::kArm.q_max[j] - params::kWorkspaceMargin)
        break;
      const double r = test::jacobian_rcond(q);
      if (r < found.rcond && (r < params::kPathMinRcond || found.steps > 0)) {
        found = {q, r, k};
      } else if (found.steps > 0) {
        break;  // past the least
      }
    }
    if (found.steps > 0 && (best.steps == 0 || found.steps < best.steps)) best = found;
  }
  return best;
}

constexpr struct {
  int joint;
  const char* name;
} kSingularities[] = {{4, "wrist"}, {2, "elbow"}, {1, "shoulder"}};

TEST(MotionSim, PathChecksRefuseLeavingTheWorkspaceAndPassingASingularity) {
  MotionSim<double> sim(start_pose());
  answer(sim, MotionVerb::kEnable, 1);
  run_ticks(sim, 100);
  // Beyond the arm's reach.
  EXPECT_EQ(answer_move(sim, relative<double>(2.0, 0, 0), 2).refusal, MotionReason::kOutOfWorkspace);
  // Into the wrist and elbow singularities (and the shoulder's, where its sweep reaches one): each refused.
  int found = 0;
  for (const auto& s : kSingularities) {
    const SweptSingularity sing = least_rcond_on_sweep(s.joint);
    if (sing.rcond >= params::kPathMinRcond) continue;  // none on this joint's sweep (the PUMA's shoulder)
    ++found;
    // near_singular, or unstable_loop where the path meets a light axis first: on the PUMA the elbow's and the
    // shoulder's (J4's axis along J1's), on the UR5e the wrist's too, where the loop is lost before J is near singular
    // (APathThroughALightAxisIsRefusedUnstableLoop).
    const MotionReason why = answer_move(sim, to_joint_pose(sing.q), 3).refusal;
    EXPECT_TRUE(why == MotionReason::kNearSingular || why == MotionReason::kUnstableLoop)
        << s.name << " at q" << s.joint + 1 << " = " << sing.q(s.joint) << ", rcond " << sing.rcond << ": "
        << motion_name(why);
  }
  EXPECT_GE(found, 2) << "the wrist's and the elbow's sweeps reach their singularities";
  // Joint 1 turned 90 degrees from near its limit: past that limit.
  std::unique_ptr<MotionSim<double>> near;
  const MoveRequest<double> turn = quarter_turn_near_the_limit(near);
  EXPECT_EQ(answer_move(*near, turn, 2).refusal, MotionReason::kOutOfWorkspace);
  // A reachable move is accepted and ends done.
  V6 q = start_pose();
  q(0) += 0.2;
  EXPECT_EQ(answer_move(sim, to_joint_pose(q), 4).outcome, CommandOutcome::kAccepted);
  const Trace r = run_until(
      sim, [](const MotionSim<double>& s) { return s.task().report.done_id == 4; }, 20000);
  EXPECT_TRUE(r.ended);
  EXPECT_EQ(r.faults, 0u);
}

/// A move into each singularity on its joint's sweep (least_rcond_on_sweep: the wrist's, the elbow's, and the
/// shoulder's where the sweep reaches one), prepared without the path check (which refuses it, above), stops by
/// name and never reaches its end:
/// - the tick's check aborts it, category 2 (limit_reached), when J's reciprocal condition falls below
///   params::kLimitMinRcond (or a joint reaches its limit on the way); the stop then either holds, or, where
///   braking carries the arm on to the controller's own threshold (kMinJacobianRcond), ends in the named fault
///   `singular` (category 0: zero torque in that tick);
/// - or, before J is near singular, the path passes a light axis of Lambda^-1 where the sampled loop is lost
///   (APathThroughALightAxisIsRefusedUnstableLoop), and the oscillation monitor stops the arm: `unstable`
///   (category 0).
/// Nothing else: no other fault, no non-finite value. The condition at the abort or the fault and the least while
/// braking, measured, are printed (the PUMA's wrist: aborted at 1.99e-3, braking reached 1.0e-3: `singular`).
TEST(MotionSim, AMoveIntoEachSingularityStopsByName) {
  int found = 0;
  for (const auto& s : kSingularities) {
    SCOPED_TRACE(s.name);
    const SweptSingularity sing = least_rcond_on_sweep(s.joint);
    if (sing.rcond >= params::kPathMinRcond) continue;  // none on this joint's sweep (the PUMA's shoulder)
    ++found;
    MotionSim<double> sim(start_pose());
    answer(sim, MotionVerb::kEnable, 1);
    run_ticks(sim, 100);
    start_unchecked(sim, to_joint_pose(sing.q), 2);
    ASSERT_EQ(sim.task().report.outcome, CommandOutcome::kAccepted);
    double least = 1;
    const Trace r = run_until(
        sim,
        [&](const MotionSim<double>& m) {
          if (motion_powered(m.task().machine.state)) least = std::min(least, static_cast<double>(m.task().last.rcond));
          return m.task().report.abort != MotionReason::kNone || state_is(m, MotionState::kFault) ||
                 m.task().report.done_id == 2;
        },
        60000);
    ASSERT_TRUE(r.ended);
    ASSERT_NE(sim.task().report.done_id, 2u) << "the move reached the singular pose";
    const double at_stop = static_cast<double>(sim.task().last.rcond);
    const char* how = "";
    if (state_is(sim, MotionState::kFault)) {
      // The loop lost on the way, before J is near singular.
      EXPECT_EQ(r.faults, static_cast<std::uint32_t>(kFaultUnstable)) << fault_name(r.faults);
      EXPECT_GE(at_stop, params::kLimitMinRcond);
      for (int i = 0; i < kDof; ++i) EXPECT_EQ(sim.task().codes[i], 0) << "zero torque in the fault's tick";
      how = "fault unstable";
    } else {
      EXPECT_EQ(sim.task().report.abort, MotionReason::kLimitReached);
      EXPECT_EQ(r.faults, 0u) << fault_name(r.faults);
      EXPECT_GE(at_stop, params::kMinJacobianRcond);
      const Trace rest = run_until(
          sim,
          [&](const MotionSim<double>& m) {
            if (motion_powered(m.task().machine.state))
              least = std::min(least, static_cast<double>(m.task().last.rcond));
            return state_is(m, MotionState::kHolding) || state_is(m, MotionState::kFault);
          },
          10000);
      ASSERT_TRUE(rest.ended);
      if (state_is(sim, MotionState::kHolding)) {
        EXPECT_EQ(rest.faults, 0u) << fault_name(rest.faults);
        how = "aborted limit_reached, held";
      } else {
        EXPECT_EQ(rest.faults, static_cast<std::uint32_t>(kFaultSingular)) << fault_name(rest.faults);
        for (int i = 0; i < kDof; ++i) EXPECT_EQ(sim.task().codes[i], 0) << "zero torque in the fault's tick";
        how = "aborted limit_reached, then fault singular";
      }
    }
    EXPECT_TRUE(std::isfinite(least) && least > 0);
    std::printf(
        "%s, %s singularity (q%d = %.3f rad, rcond %.2e there): %s; rcond %.2e at the stop, least %.2e while "
        "powered (limit %.0e, fault %.0e), after %d ticks\n",
        robot::kArm.name, s.name, s.joint + 1, sing.q(s.joint), sing.rcond, how, at_stop, least, params::kLimitMinRcond,
        params::kMinJacobianRcond, r.ticks);
  }
  EXPECT_GE(found, 2) << "the wrist's and the elbow's sweeps reach their singularities";
}

/// The first pose on the elbow's or the shoulder's sweep from the start pose (least_rcond_on_sweep's, J's reciprocal
/// condition above kPathMinRcond all the way) where the coupled sampled loop at the gains g is unstable (the
/// reference of tests/support/sampled_loop_reference.hpp, not the check's bound): an axis of Lambda^-1 so light there
/// that the damping's step lambda (k_s + k_nd) dt passes about 2; its spectral radius above rho. None: steps 0.
SweptSingularity first_unstable_on_sweep(const Mat3<double>& R_ref, const Gains<double>& g, double rho = 1) {
  SweptSingularity best;
  const V6 q0 = start_pose();
  for (const int j : {2, 1})
    for (const int dir : {-1, 1})
      for (int k = 1; k <= 3142; k += 2) {
        V6 q = q0;
        q(j) += dir * 1e-3 * k;
        if (q(j) < robot::kArm.q_min[j] + params::kWorkspaceMargin ||
            q(j) > robot::kArm.q_max[j] - params::kWorkspaceMargin || test::jacobian_rcond(q) < params::kPathMinRcond)
          break;
        if (test::coupled_spectral_radius(g, test::lambda_inverse_at(q, R_ref)) > rho) {
          if (best.steps == 0 || k < best.steps) best = {q, test::jacobian_rcond(q), k};
          break;
        }
      }
  return best;
}

/// The PUMA's false alarm of issue 55, traced: a move toward the elbow's singular pose, prepared without the path
/// check, passed q2 + q3 near -pi/2 (J4's axis along J1's), where J is well conditioned (rcond 0.16) but Lambda^-1 has
/// an eigenvalue of 34.5: the gains' sampled loop is unstable there, the torques alternated sign every tick and grew,
/// and the residual monitor stopped the arm. The path check now judges the loop at each sample (kUnstableLoop): a move
/// to the first pose where the coupled loop is unstable is refused `unstable_loop`, and so is one to where it grows
/// 2 % a tick; started without the check, the latter does not stay in control, and the oscillation monitor stops it
/// (category 0, `unstable`; before it, the PUMA's ended in `saturation` after 4 463 ticks). An arm whose sweeps reach
/// no such pose before a singularity skips, saying so.
TEST(MotionSim, APathThroughALightAxisIsRefusedUnstableLoop) {
  MotionSim<double> sim(start_pose());
  answer(sim, MotionVerb::kEnable, 1);
  run_ticks(sim, 100);
  const Mat3<double> R_ref = sim.task().gen.reference_orientation();
  const Gains<double> g = sim.task().gains.template cast<double>();
  EXPECT_GT(gain_margins(g, test::lambda_inverse_at(start_pose(), R_ref)).loop, 2) << "room at the start pose";
  const SweptSingularity light = first_unstable_on_sweep(R_ref, g);
  if (light.steps == 0)
    GTEST_SKIP() << robot::kArm.name << ": no pose on the elbow's or shoulder's sweep loses the loop";
  std::printf(
      "%s: the coupled loop is lost at q = %.3f %.3f %.3f %.3f %.3f %.3f (rcond %.3f, Lambda^-1's largest "
      "eigenvalue %.1f)\n",
      robot::kArm.name, light.q(0), light.q(1), light.q(2), light.q(3), light.q(4), light.q(5), light.rcond,
      Eigen::SelfAdjointEigenSolver<Mat6<double>>(test::lambda_inverse_at(light.q, R_ref)).eigenvalues().maxCoeff());
  EXPECT_GT(light.rcond, 5 * params::kPathMinRcond) << "not near a singularity";
  EXPECT_EQ(answer_move(sim, to_joint_pose(light.q), 2).refusal, MotionReason::kUnstableLoop);
  // Where it grows 2 % a tick, the arm started there without the check does not stay in control (below that the
  // joints' static friction can hold the oscillation: at 1 % the PUMA's arm held).
  const SweptSingularity growing = first_unstable_on_sweep(R_ref, g, 1.02);
  ASSERT_GT(growing.steps, 0);
  EXPECT_EQ(answer_move(sim, to_joint_pose(growing.q), 2).refusal, MotionReason::kUnstableLoop);
  start_unchecked(sim, to_joint_pose(growing.q), 3);
  ASSERT_EQ(sim.task().report.outcome, CommandOutcome::kAccepted);
  const Trace r = run_until(
      sim, [](const MotionSim<double>& m) { return state_is(m, MotionState::kFault); }, 30000);
  EXPECT_EQ(r.faults, static_cast<std::uint32_t>(kFaultUnstable))
      << fault_name(r.faults) << ": the oscillation monitor names it (0: the arm held the pose for 30 s)";
  EXPECT_TRUE(state_is(sim, MotionState::kFault));
  for (int i = 0; i < kDof; ++i) EXPECT_EQ(sim.task().codes[i], 0) << "zero torque after the fault";
  std::printf("started without the path check: %s after %d ticks\n", std::string(fault_name(r.faults)).c_str(),
              r.ticks);
}

/// What a stream turning the arm about the base's z axis did (stream_turn).
struct Turn {
  MotionReason abort = MotionReason::kNone;  // the first abort's reason (the report's lasts a tick)
  double rate = 0;                           // the stream's turn rate [rad/s]
  double speed = 0, q_peak = 0;              // joint 1's largest |rate| until the abort, its largest angle
  std::uint32_t faults = 0;
};

/// Streams (id) a turn of the arm about the base's z axis (joint 1's) at `share` of the follower's per-axis limits,
/// with velocities, to `to` rad (the stream ended there), until it is done or aborted and the arm holds.
template <class S>
Turn stream_turn(MotionSim<S>& sim, double share, double to, std::uint32_t id) {
  MoveRequest<S> req;
  req.relative = true;
  req.period = 10;
  sim.stream(req, id);
  sim.tick();
  EXPECT_EQ(sim.task().report.outcome, CommandOutcome::kAccepted);
  const V3 p0 = sim.tip();
  const CartesianLimits<S>& lim = sim.task().limits;
  const double radius = std::hypot(p0.x(), p0.y()), vmax = static_cast<double>(lim.linear.v),
               wmax = static_cast<double>(lim.angular.v);
  Turn r;
  r.rate = share * std::min(vmax * StreamFollower<double>::kInvSqrt3 / radius,
                            wmax * StreamFollower<double>::kInvSqrt3 / kStreamEBound);
  r.q_peak = sim.plant().q()(0);
  bool done = false;
  for (int k = 0; k < 60000 && !((done || r.abort != MotionReason::kNone) && state_is(sim, MotionState::kHolding));
       ++k) {
    const double theta = std::min(r.rate * k * 1e-3, to);
    if (r.abort == MotionReason::kNone && !done && k % req.period == 0) {
      const Eigen::AngleAxisd turn(theta, V3::UnitZ());
      const V3 dp = turn * p0 - p0, rpy(0, 0, theta);
      V6 v = V6::Zero();
      if (theta < to) v << V3::UnitZ().cross(turn * p0) * r.rate, 0, 0, r.rate;
      sim.setpoint(id, dp, &rpy, theta >= to, &v);
    }
    r.faults |= sim.tick();
    done |= sim.task().report.done_id == id;
    if (r.abort == MotionReason::kNone) {
      r.abort = sim.task().report.abort;
      r.speed = std::max(r.speed, std::abs(sim.plant().qd()(0)));
    }
    r.q_peak = std::max(r.q_peak, sim.plant().q()(0));
  }
  return r;
}

/// With joint 1 at rest at (or past) its upper limit: a move turning it further out is refused (out_of_workspace), a
/// move that leaves it where it is and one turning it back in are accepted and done (the path check lets a path
/// leave a limit, and the tick's limit check does not stop it: motion_limits_from). Ids id .. id + 2.
template <class S>
void leave_limit_of_joint1(MotionSim<S>& sim, std::uint32_t id) {
  const double q0 = sim.plant().q()(0);
  const V3 p1 = sim.tip(), out = V3::UnitZ().cross(V3(p1.x(), p1.y(), 0)).normalized() * 0.03;  // joint 1's tangent
  EXPECT_EQ(answer_move(sim, relative<S>(out.x(), out.y(), 0), id).refusal, MotionReason::kOutOfWorkspace)
      << "a move further out";
  std::uint32_t faults = 0;
  for (const V3& d : {V3(0, 0, 0.02), V3(-out)}) {
    ++id;
    ASSERT_EQ(answer_move(sim, relative<S>(d.x(), d.y(), d.z()), id).outcome, CommandOutcome::kAccepted)
        << d.transpose();
    MotionReason abort = MotionReason::kNone;
    const Trace r = run_until(
        sim,
        [&abort, id](const MotionSim<S>& m) {
          if (m.task().report.abort != MotionReason::kNone) abort = m.task().report.abort;
          return m.task().report.done_id == id;
        },
        10000);
    EXPECT_TRUE(r.ended) << d.transpose() << ": done";
    EXPECT_EQ(abort, MotionReason::kNone) << d.transpose();
    faults |= r.faults;
  }
  EXPECT_EQ(faults, 0u) << fault_name(faults);
  EXPECT_LT(sim.plant().q()(0), q0 - 0.02) << "joint 1 turned back in";
  std::printf("from %.4f rad from its limit, joint 1 moved back in to %.4f rad from it\n", q0 - robot::kArm.q_max[0],
              sim.plant().q()(0) - robot::kArm.q_max[0]);
}

/// A stream into joint 1's upper limit, stopped at it (AStreamIntoAJointLimitStopsAtIt), in the scalar S: the
/// tick's check multiplies through by the stop lead's velocity (no division), which Q12.19 rounds.
template <class S>
void stream_into_joint_limit(const char* scalar) {
  // Joint 1 half a radian from its upper limit; a stream (which no path check judges) turns the arm about the
  // base's z axis (joint 1's) at 90 % of the follower's per-axis limits, on to 0.3 rad past the limit. The tick's
  // check takes the stop's braking distance (motion_limits_reached): the arm comes to rest at the limit, not past
  // it (stopped only at the limit, a joint at 0.20 m/s braked 0.11 rad past it: beyond the encoders' margin,
  // encoder_range), and not far before it.
  V6 q = start_pose();
  q(0) = robot::kArm.q_max[0] - 0.5;
  MotionSim<S> sim(q);
  ASSERT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 200);
  const Turn t = stream_turn(sim, 0.9, 0.8, 2);
  EXPECT_EQ(t.abort, MotionReason::kLimitReached) << scalar;
  EXPECT_TRUE(state_is(sim, MotionState::kHolding)) << scalar;
  EXPECT_EQ(t.faults, 0u) << scalar << ": " << fault_name(t.faults);
  EXPECT_GT(t.speed, 0.5 * t.rate) << scalar << ": the joint turned at the stream's rate";
  EXPECT_LE(t.q_peak, robot::kArm.q_max[0] + 0.01) << scalar << ": not past the limit (the brake taken into account)";
  EXPECT_GE(sim.plant().q()(0), robot::kArm.q_max[0] - 0.05) << scalar << ": and not far before it";
  std::printf("%s: joint 1 at %.3f rad/s (stream %.3f rad/s): at rest %.4f rad from its limit, peak %.4f\n", scalar,
              t.speed, t.rate, sim.plant().q()(0) - robot::kArm.q_max[0], t.q_peak - robot::kArm.q_max[0]);
  leave_limit_of_joint1(sim, 10);
}

TEST(MotionSim, AStreamIntoAJointLimitStopsAtIt) {
  stream_into_joint_limit<double>("double");
  stream_into_joint_limit<float>("float");
  stream_into_joint_limit<Fixed>("Q12.19");
}

TEST(MotionSim, AnArmPastAJointLimitCanBeMovedBackInOnly) {
  // Joint 1 at rest 0.01 rad past its upper limit (within the encoders' margin: no fault), as a stop with any
  // overshoot would leave it. A stream turning it further out is stopped within params::kLimitStartSlack of where it
  // started; moves may take it back in, not further out (leave_limit_of_joint1).
  V6 q = start_pose();
  q(0) = robot::kArm.q_max[0] + 0.01;
  MotionSim<double> sim(q);
  ASSERT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 300);
  const double q0 = sim.plant().q()(0);
  const Turn t = stream_turn(sim, 0.9, 0.3, 2);
  EXPECT_EQ(t.abort, MotionReason::kLimitReached);
  EXPECT_EQ(t.faults, 0u) << fault_name(t.faults);
  EXPECT_LE(t.q_peak, q0 + params::kLimitStartSlack + 0.003)
      << "stopped near where it started (0.0016 beyond measured)";
  std::printf("a stream out from %.4f rad past the limit: stopped, peak %.4f rad past\n", q0 - robot::kArm.q_max[0],
              t.q_peak - robot::kArm.q_max[0]);
  leave_limit_of_joint1(sim, 10);
}

}  // namespace

// ---------------------------------------------------------------- streams

namespace {

/// A path for the streams: 60 mm along x, -40 mm along y, 20 mm up and 10 degrees of yaw, timed
/// by a cosine over 2.5 s, relative to where the stream starts; its peak rates are within the
/// follower's per-axis limits (v / sqrt(3): a path faster than those is followed slower and late).
constexpr double kPathT = 2.5;
V6 path_at(double t) {
  const double s = t >= kPathT ? 1 : 0.5 - 0.5 * std::cos(kPi * t / kPathT);
  V6 x;
  x << 0.06 * s, -0.04 * s, 0.02 * s, 0, 0, 10 * kPi / 180 * s;
  return x;
}
/// Its velocity: the rates, the angular ones as w = E(rpy) rpy_dot.
V6 path_velocity(double t) {
  const double sd = t >= kPathT ? 0 : 0.5 * kPi / kPathT * std::sin(kPi * t / kPathT);
  V6 r;
  r << 0.06 * sd, -0.04 * sd, 0.02 * sd, 0, 0, 10 * kPi / 180 * sd;
  r.tail<3>() = phi_rate_to_angular<double>(V3(path_at(t).tail<3>())) * r.tail<3>();
  return r;
}

/// What a stream run measured: the reference's own maxima (speed, acceleration, jerk from
/// differences of the acceleration; angular speed, angular acceleration), its largest distance
/// from the path's line, the tracking error, the end error of the arm, the outcome.
struct StreamRun {
  double v = 0, a = 0, j = 0, w = 0, wd = 0, off_path = 0, tracking = 0, end_error = 0, end_angle = 0;
  double lag = 0;  // the reference's distance from the path (not delayed)
  std::uint32_t faults = 0;
  bool done = false;
  MotionReason abort = MotionReason::kNone;
  int ticks = 0;
};

/// Enable, then stream path_at at rate_hz (relative; with `velocity`, each setpoint with its
/// velocity), the last setpoint ending the stream; or without setpoints after cut_s. Runs until the
/// stream is done or aborted and the arm holds.
template <class S>
StreamRun stream_path(int rate_hz, double cut_s = -1, bool velocity = false) {
  MotionSim<S> sim(start_pose());
  StreamRun out;
  EXPECT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 200);
  MoveRequest<S> req;
  req.relative = true;
  req.period = static_cast<std::uint32_t>(1000 / rate_hz);
  sim.stream(req, 2);
  sim.tick();
  EXPECT_EQ(sim.task().report.outcome, CommandOutcome::kAccepted);
  const V3 p0 = sim.tip();
  const sim::Mat3 R_ref = sim.task().state.R_ref.template cast<double>();
  const V6 x0 = sim.pose();
  Vec3<double> a_prev = Vec3<double>::Zero(), w_prev = Vec3<double>::Zero();
  const V3 line = path_at(kPathT).head<3>().normalized();
  for (int k = 0; k < 20000; ++k) {
    const double t = k * 1e-3;
    if (k % req.period == 0 && (cut_s < 0 || t <= cut_s)) {
      const bool end = t >= kPathT;
      if (t <= kPathT + 1e-9) {
        const V6 x = path_at(t), v = path_velocity(t);
        const V3 rpy = x.tail<3>();
        EXPECT_TRUE(sim.setpoint(2, x.head<3>(), &rpy, end, velocity ? &v : nullptr)) << t;
      }
    }
    out.faults |= sim.tick();
    ++out.ticks;
    const MotionReport& rep = sim.task().report;
    out.done |= rep.done_id == 2;
    if (rep.abort != MotionReason::kNone) out.abort = rep.abort;
    const Desired<S>& d = sim.task().desired;
    const Vec3<double> v = d.xd.template head<3>().template cast<double>();
    const Vec3<double> a = d.xdd.template head<3>().template cast<double>();
    const Vec3<double> phi = d.x.template tail<3>().template cast<double>();
    const Vec3<double> w = angular_to_phi_rate<double>(phi).inverse() * d.xd.template tail<3>().template cast<double>();
    out.v = std::max(out.v, v.norm());
    out.a = std::max(out.a, a.norm());
    if (k > 0) out.j = std::max(out.j, (a - a_prev).norm() * 1e3), out.wd = std::max(out.wd, (w - w_prev).norm() * 1e3);
    out.w = std::max(out.w, w.norm());
    a_prev = a, w_prev = w;
    const V3 rel = d.x.template head<3>().template cast<double>() - p0;
    out.off_path = std::max(out.off_path, (rel - rel.dot(line) * line).norm());
    out.lag = std::max(out.lag, (rel - path_at((k + 1) * 1e-3).head<3>()).norm());
    out.tracking = std::max(out.tracking, (sim.reference().template head<3>() - sim.tip()).norm());
    if ((out.done || out.abort != MotionReason::kNone) && state_is(sim, MotionState::kHolding)) break;
  }
  run_ticks(sim, 500);  // settled, holding
  const V6 end = path_at(kPathT);
  out.end_error = (sim.tip() - (p0 + end.head<3>())).norm();
  const sim::Mat3 R_end = rpy_rotation<double>(end.tail<3>()) * rpy_rotation<double>(x0.tail<3>()) * R_ref;
  const sim::Mat3 R_now = rpy_rotation<double>(V3(sim.pose().template tail<3>())) * R_ref;
  V3 axis;
  rotation_axis_angle<double>(sim::Mat3(R_now * R_end.transpose()), axis, out.end_angle);
  EXPECT_TRUE(state_is(sim, MotionState::kHolding));
  return out;
}

template <class S>
void stream_at_rates(bool velocity = false) {
  const CartesianLimits<double> lim = CartesianLimits<double>::defaults();
  for (int rate : {10, 50, 1000}) {
    const StreamRun r = stream_path<S>(rate, -1, velocity);
    const std::string at =
        std::string(typeid(S).name()) + " at " + std::to_string(rate) + " Hz" + (velocity ? " with velocities" : "");
    EXPECT_TRUE(r.done) << at;
    EXPECT_EQ(r.abort, MotionReason::kNone) << at;
    EXPECT_EQ(r.faults, 0u) << at;
    EXPECT_LE(r.end_error, 1e-3) << at;
    EXPECT_LE(r.end_angle, 1e-3) << at;
    EXPECT_LE(r.v, lim.linear.v) << at;
    EXPECT_LE(r.a, lim.linear.a) << at;
    EXPECT_LE(r.j, lim.linear.j) << at;
    EXPECT_LE(r.w, lim.angular.v) << at;
    EXPECT_LE(r.wd, lim.angular.a) << at;
    // Not distorted: the reference stays on the path's line (the follower lags along it).
    EXPECT_LE(r.off_path, 0.2e-3) << at;
    EXPECT_LE(r.tracking, kColdStartTolerance) << at;  // a cold start (theta^ = 0), as the first move's
    std::printf(
        "stream %s: end error %.4f mm %.5f rad, off the line %.4f mm, lag %.3f mm, tracking %.3f mm, v %.4f a %.4f "
        "j %.3f w %.4f wd %.4f, %d ticks\n",
        at.c_str(), r.end_error * 1e3, r.end_angle, r.off_path * 1e3, r.lag * 1e3, r.tracking * 1e3, r.v, r.a, r.j, r.w,
        r.wd, r.ticks);
  }
}

}  // namespace

TEST(MotionSim, StreamAtTenFiftyAndThousandHzEndsAtThePathsEnd) { stream_at_rates<double>(); }
TEST(MotionSim, StreamInFloat) { stream_at_rates<float>(); }
TEST(MotionSim, StreamInFixedPoint) { stream_at_rates<Fixed>(); }
TEST(MotionSim, StreamWithVelocitiesInEachScalar) {
  stream_at_rates<double>(true);
  stream_at_rates<float>(true);
  stream_at_rates<Fixed>(true);
}

// Setpoints with their velocities remove the stream's delay of one period: at 10 Hz the reference
// lags the path by v T without them (about 4.5 mm here), by a fraction of it with them.
TEST(MotionSim, StreamWithVelocitiesAtTenHzLagsAFifthOrLess) {
  const StreamRun plain = stream_path<double>(10), with_v = stream_path<double>(10, -1, true);
  std::printf("10 Hz: the reference's lag behind the path %.2f mm without velocities, %.2f mm with\n", plain.lag * 1e3,
              with_v.lag * 1e3);
  EXPECT_GE(plain.lag, 3e-3);
  EXPECT_LE(with_v.lag, plain.lag / 5);
}

/// A stream cut mid-path (its last setpoint at 1 s): stale after max(2 T, 20 ms), the category-2 stop to
/// rest, then held. In every scalar: in Q12.19 the stop once ended 1 unit of speed short of rest and the
/// arm stayed `stopping` (kStopRestSpeed).
template <class S>
void cut_stream(const char* scalar) {
  for (int rate : {10, 50, 1000}) {
    MotionSim<S> sim(start_pose());
    answer(sim, MotionVerb::kEnable, 1);
    run_ticks(sim, 200);
    MoveRequest<S> req;
    req.relative = true;
    req.period = static_cast<std::uint32_t>(1000 / rate);
    sim.stream(req, 2);
    sim.tick();
    ASSERT_EQ(sim.task().report.outcome, CommandOutcome::kAccepted);
    long last = -1, stale_at = -1;
    std::uint32_t faults = 0;
    for (long k = 0; k < 10000 && stale_at < 0; ++k) {
      if (k % req.period == 0 && k * 1e-3 <= 1.0) {
        const V6 x = path_at(k * 1e-3);
        sim.setpoint(2, x.head<3>(), nullptr, false);
        last = k;
      }
      faults |= sim.tick();
      if (sim.task().report.abort == MotionReason::kStaleStream) stale_at = k;
    }
    ASSERT_GE(stale_at, 0) << scalar << " at " << rate << " Hz";
    // Stale after max(2 T, 20 ms) without a setpoint: the tick after that.
    // Stale in the tick that completes max(2 T, 20 ms) without a setpoint after the last one's.
    const long timeout = std::max<long>(2 * req.period, 20);
    EXPECT_EQ(stale_at - last, timeout) << scalar << " at " << rate << " Hz";
    EXPECT_EQ(sim.task().report.aborted_id, 2u) << scalar;
    EXPECT_TRUE(state_is(sim, MotionState::kStopping));
    const Trace stop = run_until(
        sim, [](const MotionSim<S>& s) { return state_is(s, MotionState::kHolding); }, 10000);
    EXPECT_TRUE(stop.ended) << scalar << " at " << rate << " Hz";
    EXPECT_LT(stop.ticks, 1500) << scalar << " at " << rate << " Hz: the stop rests within 1.5 s";
    EXPECT_EQ(sim.task().report.completion, MotionCompletion::kStopped);
    // Held for 3 s after a cold start's stop: the tip's largest distance from where the stop ended. The
    // Coulomb and Stribeck compensation, sgn(q^dot^) (cou^ + sti^), learnt from a cold start in the one-second
    // stream, may exceed the plant's: then the joints hunt at rest (1e-2 rad/s at times, bounded), on both arms.
    // On the PUMA that is its wrist's and the tip stays within 0.25 mm (0.193 measured, 2026-12-04); on the UR5e
    // (J2's cou^ + sti^ 10.4 to 11.4 N m against the plant's 9.0) its shoulder's, and the tip within 1 mm (0.741
    // measured, float at 50 Hz). A saved identification (issue 57) is what would start the hold from the plant's.
    const V3 held = sim.tip();
    double settle = 0;
    std::uint32_t hold_faults = 0;
    for (int n = 0; n < 3000; ++n) {
      hold_faults |= sim.tick();
      settle = std::max(settle, (sim.tip() - held).norm());
    }
    EXPECT_EQ(faults | stop.faults | hold_faults, 0u) << scalar << " at " << rate << " Hz";
    EXPECT_LE(settle, test::kPumaBuild ? 0.25e-3 : 1e-3) << scalar << " at " << rate << " Hz";
    EXPECT_TRUE(state_is(sim, MotionState::kHolding));
    std::printf("%s, %d Hz: stale after %ld ticks, at rest after %d, then held 3 s within %.3f mm\n", scalar, rate,
                stale_at - last, stop.ticks, 1e3 * settle);
  }
}

TEST(MotionSim, CuttingAStreamStopsItAndHolds) {
  cut_stream<double>("double");
  cut_stream<float>("float");
  cut_stream<Fixed>("Q12.19");
}

TEST(MotionSim, StreamRefusalsAndAStopCommand) {
  MotionSim<double> sim(start_pose());
  MoveRequest<double> req;
  req.period = 20;
  req.relative = true;
  sim.stream(req, 1);
  sim.tick();
  EXPECT_EQ(sim.task().report.refusal, MotionReason::kNotEnabled);
  answer(sim, MotionVerb::kEnable, 2);
  MoveRequest<double> fast = req;
  fast.has_limits = true;
  fast.limits = CartesianLimits<double>::defaults();
  fast.limits.angular.j *= 1.5;
  sim.stream(fast, 3);
  sim.tick();
  EXPECT_EQ(sim.task().report.refusal, MotionReason::kOverLimit);
  sim.stream(req, 4);
  sim.tick();
  ASSERT_EQ(sim.task().report.outcome, CommandOutcome::kAccepted);
  // While it runs: another stream, the paper's motion and a move are busy.
  sim.stream(req, 5);
  sim.tick();
  EXPECT_EQ(sim.task().report.refusal, MotionReason::kBusy);
  EXPECT_EQ(answer(sim, MotionVerb::kPaper, 6).refusal, MotionReason::kBusy);
  EXPECT_EQ(answer_move(sim, relative<double>(0.01, 0, 0), 7).refusal, MotionReason::kBusy);
  // Setpoints moving at 20 mm/s along x, then a stop: aborted, decelerated, held.
  const V3 p0 = sim.tip();
  for (int k = 0; k < 500; ++k) {
    if (k % 20 == 0) sim.setpoint(4, V3(0.02 * k * 1e-3, 0, 0), nullptr, false);
    sim.tick();
  }
  const MotionReport stop = answer(sim, MotionVerb::kStop, 8);
  EXPECT_EQ(stop.abort, MotionReason::kStopCommand);
  EXPECT_EQ(stop.aborted_id, 4u);
  // A setpoint after the stop is dropped.
  const std::uint32_t dropped = sim.task().dropped;
  EXPECT_FALSE(sim.setpoint(4, V3(0.02, 0, 0), nullptr, false));
  EXPECT_EQ(sim.task().dropped, dropped + 1);
  const Trace r = run_until(
      sim, [](const MotionSim<double>& s) { return state_is(s, MotionState::kHolding); }, 5000);
  EXPECT_TRUE(r.ended);
  EXPECT_EQ(r.faults, 0u);
  const double moved = (sim.tip() - p0)(0);
  EXPECT_GT(moved, 0.005);  // it went along x, and stopped short of where the stream would have gone
  EXPECT_LT(moved, 0.02);
}

/// 50 seeded random moves from where the arm is (up to 15 cm along each axis and 0.3 rad about z, at the
/// configured maxima, params::kMoveLinear), after 10 s of the paper's motion (friction learnt): each is accepted
/// or refused by name by the path check (out of the workspace, near a singular pose, the loop lost on a light axis),
/// and an accepted one runs to
/// its end with no fault, its reference's speed and acceleration within the maxima and the tip within 1 mm of it.
/// On every arm, at the arm's maxima (its sheet's cartesian_maxima, chosen by this test: docs/arms.md, "Speed
/// limits").
TEST(MotionSim, FiftySeededRandomMovesAtTheMaximaTrackWithinOneMillimetre) {
  MotionSim<double> sim(start_pose());
  ASSERT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 300);
  ASSERT_EQ(answer(sim, MotionVerb::kPaper, 2).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 10000);
  ASSERT_EQ(answer(sim, MotionVerb::kStop, 3).outcome, CommandOutcome::kAccepted);
  run_until(
      sim, [](const MotionSim<double>& s) { return state_is(s, MotionState::kHolding); }, 10000);
  const test::RandomMoves r = test::random_moves(sim, 55, 50);
  EXPECT_EQ(r.failed_id, 0u) << "move " << r.failed_id << ": " << fault_name(r.faults) << ", refused "
                             << MotionNames<MotionReason>::kNames[static_cast<int>(r.refusal)];
  EXPECT_EQ(r.moves, 50) << "most random moves are accepted (" << r.refused << " refused)";
  EXPECT_LE(r.tracking, 1e-3);
  EXPECT_LE(r.oscillation, 0.5) << "the oscillation monitor's healthy margin";
  EXPECT_LE(r.speed, params::kMoveLinear[0] * (1 + 1e-9));
  EXPECT_LE(r.accel, params::kMoveLinear[1] * (1 + 1e-9));
  std::printf(
      "%s: 50 random moves (%d refused by the path check): tracking at most %.4f mm, reference speed at "
      "most %.4f m/s (maximum %.2f), acceleration at most %.4f m/s^2 (maximum %.2f); oscillation monitor at most "
      "%.3f of its limit\n",
      robot::kArm.name, r.refused, r.tracking * 1e3, r.speed, params::kMoveLinear[0], r.accel, params::kMoveLinear[1],
      r.oscillation);
}
