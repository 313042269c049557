// The identification run's motion in closed loop (issue 57; docs/adaptation.md, "The identify command"):
// the identify command over the simulated arm (host_sim/motion_sim.hpp) runs the excitation motion
// (osc/control/excitation.hpp) about the held joint angles for its 80 s, with the true joint angles,
// speeds and torques within the limits its check used, and ends done, holding where it started; a stop
// brakes it along its path and holds; what cannot run is refused by name before it starts. The true
// state is the plant's, not the controller's estimate of it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "motion_sim.hpp"
#include "osc/link/commands.hpp"
#include "motion_sim_util.hpp"
#include "test_util.hpp"

using namespace osc;
using sim::MotionSim;
using test::answer;
using test::run_ticks;
using test::run_until;
using test::start_pose;
using test::state_is;

namespace {

using V6 = sim::Vec6;

/// The true joint state against the run's limits (ExcitationLimits::defaults, the check's), per tick.
struct Envelope {
  double room = 1e9;    // least distance of a joint to its limit less the margin [rad] (< 0: beyond)
  double speed = 0;     // largest |qd_i| / speed bound_i
  double torque = 0;    // largest |tau_i| / torque bound_i (the commanded torque)
  double tracking = 0;  // largest |q_i - q_ref_i| [rad] (the reference from the generator)
  int room_joint = -1, speed_joint = -1, torque_joint = -1;

  template <class S>
  void add(MotionSim<S>& sim, const ExcitationLimits<double>& lim) {
    const V6& q = sim.plant().q();
    const V6& qd = sim.plant().qd();
    const V6 tau = sim.hal().torque();
    for (int i = 0; i < kDof; ++i) {
      const double r = std::min(q(i) - lim.q_min(i), lim.q_max(i) - q(i));
      if (r < room) room = r, room_joint = i;
      if (std::fabs(qd(i)) / lim.speed(i) > speed) speed = std::fabs(qd(i)) / lim.speed(i), speed_joint = i;
      if (std::fabs(tau(i)) / lim.torque(i) > torque) torque = std::fabs(tau(i)) / lim.torque(i), torque_joint = i;
    }
  }
};

/// Enable at the start pose and settle.
template <class S>
void enable_and_settle(MotionSim<S>& sim) {
  ASSERT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 500);
  ASSERT_TRUE(state_is(sim, MotionState::kHolding));
}

/// Sends an identify and runs the tick that answers it.
template <class S>
MotionReport answer_identify(MotionSim<S>& sim, std::uint32_t id, ExcitationCheck<S>* check = nullptr) {
  sim.identify(id, check);
  sim.tick();
  return sim.task().report;
}

/// The whole run in scalar S on an arm that holds: accepted, within its limits every tick, done after its 80 s,
/// holding where it started. Returns the envelope.
template <class S>
Envelope run_to_its_end(MotionSim<S>& sim) {
  const sim::Vec3 tip0 = sim.tip();
  const V6 q0 = sim.plant().q();
  ExcitationCheck<S> check;
  const MotionReport rep = answer_identify(sim, 5, &check);
  EXPECT_EQ(rep.outcome, CommandOutcome::kAccepted) << motion_name(rep.refusal);
  EXPECT_TRUE(state_is(sim, MotionState::kMoving));
  const ExcitationLimits<double> lim = ExcitationLimits<double>::defaults();
  Envelope env;
  std::uint32_t faults = 0;
  std::uint64_t ticks = 0;
  const std::uint64_t run = excitation::kTicks;
  while (sim.task().report.done_id != 5 && ticks < run + 100) {
    faults |= sim.tick();
    ++ticks;
    env.add(sim, lim);
    if (sim.task().gen.source() == MotionSource::kExcitation) {
      const JointSample<S> r = sim.task().gen.excitation_at(sim.task().tick, params::kControlHz).ref;
      env.tracking = std::max(env.tracking, (sim.plant().q() - r.q.template cast<double>()).cwiseAbs().maxCoeff());
    }
  }
  EXPECT_EQ(faults, 0u) << fault_name(faults);
  EXPECT_EQ(sim.task().report.done_id, 5u);
  EXPECT_EQ(sim.task().report.completion, MotionCompletion::kFinished);
  // Done one tick after its last reference (the tick that takes the command starts it at the next).
  EXPECT_NEAR(static_cast<double>(ticks), static_cast<double>(run), 2.0);
  run_ticks(sim, 1000);
  EXPECT_TRUE(state_is(sim, MotionState::kHolding));
  EXPECT_LT((sim.tip() - tip0).norm(), 0.5e-3);
  EXPECT_LT((sim.plant().q() - q0).cwiseAbs().maxCoeff(), 2e-3);
  // Within what the check passed (its limits less their margins), the true state: the reference's
  // peaks are at most the speed bound less 1 % (kExcitationPlanFill); the tracking error adds to them.
  EXPECT_GT(env.room, 0.0) << "joint " << env.room_joint + 1;
  EXPECT_LT(env.speed, 1.0) << "joint " << env.speed_joint + 1;
  EXPECT_LT(env.torque, 1.0) << "joint " << env.torque_joint + 1;
  EXPECT_LT(env.tracking, 0.01);
  std::printf(
      "identify run (%s, scale %.3f): %llu ticks; least room to a limit %.3f rad (J%d), speed %.3f of its bound "
      "(J%d), commanded torque %.3f of its bound (J%d), joint tracking at most %.2e rad; back within %.3f mm\n",
      typeid(S).name(), static_cast<double>(check.scale), static_cast<unsigned long long>(ticks), env.room,
      env.room_joint + 1, env.speed, env.speed_joint + 1, env.torque, env.torque_joint + 1, env.tracking,
      (sim.tip() - tip0).norm() * 1e3);
  return env;
}

/// The same from the runs' pose, enabled there.
template <class S>
Envelope whole_run() {
  MotionSim<S> sim(test::identify_pose());
  enable_and_settle(sim);
  return run_to_its_end(sim);
}

TEST(IdentifyCommand, RunsItsExcitationWithinItsLimitsAndEndsDoneWhereItStarted) { whole_run<double>(); }
TEST(IdentifyCommand, RunsInFloat) { whole_run<float>(); }
TEST(IdentifyCommand, RunsInFixedPoint) { whole_run<Fixed>(); }

// A stop brakes the run along its path (its time slowed to rest) and holds; the run is aborted
// stop_command; every tick stays within the limits.
// An identify after a move that turned the wrist by 30 degrees (from the start pose, enabled there, q5 from 45 to 74.5
// degrees: further than the QEMU power cycle's move to the runs' pose, 68.75). The run takes its orientation
// coordinates where it starts (prepare_identify_at; the tick's controller_rereference), so it runs as from an enable
// there: before, the coordinates of the enable's pose, 30 degrees away, made its loop check refuse it unstable_loop,
// and a disable and an enable at the runs' pose were needed. The reference pose the state frame reports does not move
// at the accept.
TEST(IdentifyCommand, RunsAfterAMoveThatTurnedTheWristWithoutAnEnableThere) {
  if (!test::kPumaBuild) GTEST_SKIP() << "the PUMA's poses";
  MotionSim<double> sim(start_pose());
  enable_and_settle(sim);
  MoveRequest<double> req;
  req.position = Vec3<double>(0.5963, -0.1500, -0.0144);
  req.has_rpy = true;
  req.rpy = Vec3<double>(0, 60.52 * M_PI / 180, 0);
  ASSERT_EQ(test::answer_move(sim, req, 3).outcome, CommandOutcome::kAccepted);
  run_until(
      sim, [](const MotionSim<double>& s) { return s.task().report.done_id == 3; }, 20000);
  run_ticks(sim, 500);
  ASSERT_TRUE(state_is(sim, MotionState::kHolding));
  EXPECT_NEAR(sim.plant().q()(4), 1.3, 2e-3);
  const pil::StateFrame before = state_frame_from_task(sim.task());
  const Mat3<double> R_enable = sim.task().state.R_ref;
  {  // in the enable's coordinates, as before, the check refuses the run
    ControlTask<double>& t = sim.task();
    const loop::PathLoop loop = loop::path_loop(t.gains, params::kPathLoopMargin);
    ExcitationMotion<double> motion;
    const ExcitationCheck<double> old =
        prepare_excitation(t.model, t.check_data, Vec6<double>(t.state.adapt.q_prev), R_enable,
                           ExcitationLimits<double>::defaults(), motion, &loop);
    EXPECT_EQ(old.status, ExcitationStatus::kUnstableLoop);
  }
  const Envelope env = run_to_its_end(sim);
  EXPECT_GT(env.room, 0.0);
  // The controller was re-referenced at the run's start: 30 degrees from the enable's orientation.
  const double turned = Eigen::AngleAxisd(sim.task().state.R_ref * R_enable.transpose()).angle();
  EXPECT_NEAR(turned * 180 / M_PI, 29.5, 1.0);
  const pil::StateFrame after = state_frame_from_task(sim.task());
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(after.x_d[i], before.x_d[i], 0.5e-3) << i;
  const auto R_of = [](const float* x) { return rpy_rotation<double>(Vec3<double>(x[3], x[4], x[5])); };
  EXPECT_LT((R_of(after.x_d) - R_of(before.x_d)).norm(), 2e-3);
}

TEST(IdentifyCommand, AStopBrakesItAlongItsPathAndHolds) {
  MotionSim<double> sim(test::identify_pose());
  enable_and_settle(sim);
  ASSERT_EQ(answer_identify(sim, 5).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 23500);  // at speed: a joint near its peak
  double speed0 = sim.plant().qd().cwiseAbs().maxCoeff();
  EXPECT_GT(speed0, 0.3);
  const MotionReport stop = answer(sim, MotionVerb::kStop, 6);
  ASSERT_EQ(stop.outcome, CommandOutcome::kAccepted);
  EXPECT_TRUE(state_is(sim, MotionState::kStopping));
  EXPECT_EQ(stop.aborted_id, 5u);
  EXPECT_EQ(stop.abort, MotionReason::kStopCommand);
  const ExcitationLimits<double> lim = ExcitationLimits<double>::defaults();
  Envelope env;
  std::uint32_t faults = 0;
  bool stopped = false;
  int ticks = 0;
  for (; ticks < 6000 && !state_is(sim, MotionState::kHolding); ++ticks) {
    faults |= sim.tick();
    env.add(sim, lim);
    stopped |= sim.task().report.completion == MotionCompletion::kStopped;
  }
  EXPECT_EQ(faults, 0u);
  EXPECT_TRUE(stopped);
  EXPECT_TRUE(state_is(sim, MotionState::kHolding));
  EXPECT_GT(env.room, 0.0);
  EXPECT_LT(env.speed, 1.0);
  EXPECT_LT(env.torque, 1.0);
  run_ticks(sim, 500);
  EXPECT_LT(sim.plant().qd().cwiseAbs().maxCoeff(), 0.01);
  std::printf("identify stopped at %.2f rad/s: at rest in %.2f s\n", speed0, ticks * 1e-3);
}

// What cannot run is refused by name before it starts, the arm as it was.
TEST(IdentifyCommand, WhatCannotRunIsRefusedByName) {
  {  // disabled: not_enabled
    MotionSim<double> sim(start_pose());
    const MotionReport rep = answer_identify(sim, 5);
    EXPECT_EQ(rep.outcome, CommandOutcome::kRefused);
    EXPECT_EQ(rep.refusal, MotionReason::kNotEnabled);
  }
  {  // a motion running: busy; a move_to during the run: busy
    MotionSim<double> sim(start_pose());
    enable_and_settle(sim);
    ASSERT_EQ(answer(sim, MotionVerb::kPaper, 2).outcome, CommandOutcome::kAccepted);
    run_ticks(sim, 100);
    EXPECT_EQ(answer_identify(sim, 5).refusal, MotionReason::kBusy);
    ASSERT_EQ(answer(sim, MotionVerb::kStop, 3).outcome, CommandOutcome::kAccepted);
    run_until(
        sim, [](const MotionSim<double>& s) { return state_is(s, MotionState::kHolding); }, 10000);
    run_ticks(sim, 1000);
    if (test::kPumaBuild) {  // the start pose itself: q5 = pi/4
      EXPECT_EQ(answer_identify(sim, 8).refusal, MotionReason::kUnstableLoop);
    }
  }
  {
    MotionSim<double> sim(test::identify_pose());
    enable_and_settle(sim);
    ASSERT_EQ(answer_identify(sim, 6).outcome, CommandOutcome::kAccepted);
    run_ticks(sim, 100);
    MoveRequest<double> req;
    req.relative = true;
    req.position = Vec3<double>(0, 0, 0.01);
    sim.move_to(req, 7);
    sim.tick();
    EXPECT_EQ(sim.task().report.refusal, MotionReason::kBusy);
    EXPECT_EQ(sim.task().gen.source(), MotionSource::kExcitation);
  }
  {  // an identify that was not prepared (a bare command): bad_command, in any state (the tick's flag)
    MotionSim<double> sim(start_pose());
    EXPECT_EQ(answer(sim, MotionVerb::kIdentify, 4).refusal, MotionReason::kBadCommand);
    enable_and_settle(sim);
    EXPECT_EQ(answer(sim, MotionVerb::kIdentify, 5).refusal, MotionReason::kBadCommand);
    EXPECT_TRUE(state_is(sim, MotionState::kHolding));
  }
  if (!test::kPumaBuild) return;  // the poses below are the PUMA's
  {                               // a joint within the margin of its limit: out_of_workspace
    V6 q = start_pose();
    q(0) = robot::kArm.q_max[0] - 0.02;
    MotionSim<double> sim(q);
    enable_and_settle(sim);
    EXPECT_EQ(answer_identify(sim, 5).refusal, MotionReason::kOutOfWorkspace);
    EXPECT_TRUE(state_is(sim, MotionState::kHolding));
  }
  {  // the wrist at its singularity (q5 = 0.02 rad: rcond 0.004 at the first tick, under 0.01): near_singular
    V6 q = start_pose();
    q(4) = 0.02;
    MotionSim<double> sim(q);
    enable_and_settle(sim);
    EXPECT_EQ(answer_identify(sim, 5).refusal, MotionReason::kNearSingular);
    EXPECT_TRUE(state_is(sim, MotionState::kHolding));
  }
}

}  // namespace
