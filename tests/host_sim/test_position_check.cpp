// The position cross-check (osc/runtime/monitors.hpp, PositionCrossCheck) on the simulated arm:
// in closed loop, a motion that moves every joint raises no position_mismatch; then a stuck encoder
// on each channel, at several instants of that motion, is found by the cross-check alone, replayed on
// the recorded motion (the channel's counts frozen from the instant on, the potentiometers following
// the arm with the realistic plant's offsets and a noise of 2 codes rms). The replay keeps the arm on
// its healthy path: a real stuck encoder makes the controller drive its joint on, faster, so these
// are upper bounds of the detection time, on travel the joint would have made anyway.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "motion_sim.hpp"
#include "osc/robot.hpp"
#include "test_util.hpp"

namespace {

using namespace osc;

struct Sample {
  std::int32_t counts[kDof];
  sim::Vec6 q;  // the plant's joint angles
};

/// A motion that moves every joint: translations of the wrist centre and rotations about each axis.
std::vector<Sample> record(std::uint32_t& faults) {
  const sim::Vec6 q0 = joint_vector<double>(robot::kQStart);
  auto s = std::make_unique<sim::MotionSim<double>>(q0);
  std::vector<Sample> rec;
  faults = 0;
  const auto run = [&](int ticks) {
    for (int k = 0; k < ticks; ++k) {
      faults |= s->tick();
      Sample x;
      for (int i = 0; i < kDof; ++i) x.q(i) = s->plant().q()(i);
      s->hal().read_encoders(x.counts);  // the counts of the sample just taken (no jitter: the same)
      rec.push_back(x);
    }
  };
  s->command(MotionVerb::kEnable, 1);
  run(500);
  const double kDeg = kPi / 180;
  const double moves[][6] = {{0.10, -0.08, 0.05, 0, 0, 25}, {-0.10, 0.08, -0.05, 0, 0, -25},
                             {0, 0, 0, 25, 0, 0},           {0, 0, 0, -25, 0, 0},
                             {0, 0, 0, 0, 20, 0},           {0, 0, 0, 0, -20, 0},
                             {0.0, 0.12, 0.10, 0, 0, 0},    {0.0, -0.12, -0.10, 0, 0, 0}};
  std::uint32_t id = 2;
  for (const auto& m : moves) {
    MoveRequest<double> r;
    r.position = Vec3<double>(m[0], m[1], m[2]);
    r.rpy = Vec3<double>(m[3], m[4], m[5]) * kDeg;
    r.has_rpy = true;
    r.relative = true;
    s->move_to(r, id++);
    run(1);
    EXPECT_EQ(s->task().report.outcome, CommandOutcome::kAccepted) << "move " << id - 1;
    while (s->task().machine.state == MotionState::kMoving && rec.size() < 200000) run(1);
    run(200);
  }
  return rec;
}

TEST(PositionCheck, NoMismatchInClosedLoopAndAStuckEncoderOnEachJointIsFound) {
  OSC_PUMA_ONLY();  // the pots' cross-check (an arm without pots has none)
  std::uint32_t faults = 0;
  const std::vector<Sample> rec = record(faults);
  EXPECT_EQ(faults, 0u) << fault_name(faults);
  ASSERT_GT(rec.size(), 5000u);
  const Vec6<double> q_start = joint_vector<double>(robot::kQStart);
  const IoMap<double> io = IoMap<double>::of(robot::kEncodersUniform);
  const auto& d = robot::kDriveTrain;
  const double full = (1 << d.pot_bits) - 1;
  constexpr double kOffset[kDof] = {12, -8, 15, -20, 6, -10};  // the realistic plant's
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 2);
  std::vector<std::array<std::uint16_t, kDof>> pots(rec.size());
  for (std::size_t t = 0; t < rec.size(); ++t)
    for (int i = 0; i < kDof; ++i) {
      const double x =
          std::round((rec[t].q(i) - d.pot_min[i]) / (d.pot_max[i] - d.pot_min[i]) * full + kOffset[i] + noise(rng));
      pots[t][i] = static_cast<std::uint16_t>(std::clamp(x, 0.0, full));
    }
  // The healthy run through the monitor: no fault, and its largest ratio per joint.
  PositionCrossCheck<double> healthy;
  healthy.reset();
  std::vector<PositionCrossCheck<double>> at(rec.size());
  double peak[kDof] = {};
  for (std::size_t t = 0; t < rec.size(); ++t) {
    at[t] = healthy;
    EXPECT_EQ(healthy.check(pots[t].data(), true, angles_from_counts(q_start, io, rec[t].counts)), 0u) << t;
    for (int i = 0; i < kDof; ++i) peak[i] = std::max(peak[i], healthy.ratio(i));
  }
  std::printf("healthy peak |d - d_ref| / band: %.2f %.2f %.2f %.2f %.2f %.2f\n", peak[0], peak[1], peak[2], peak[3],
              peak[4], peak[5]);
  for (double p : peak) EXPECT_LT(p, 0.5);
  // Stuck encoders: each channel frozen at instants while its joint moves at 0.05 rad/s or more.
  for (int c = 0; c < kDof; ++c) {
    int cases = 0, found = 0;
    double worst_ms = 0, worst_travel = 0, worst_excess = -1;
    for (std::size_t t0 = 1000; t0 + 3000 < rec.size(); t0 += 250) {
      const double v = std::fabs(rec[t0 + 1].q(c) - rec[t0 - 1].q(c)) / 2e-3;
      if (v < 0.05) continue;
      // Only where the joint goes on to travel twice its band within 1.5 s (else no sensor can tell).
      double reach = 0;
      for (std::size_t t = t0; t < t0 + 1500; ++t) reach = std::max(reach, std::fabs(rec[t].q(c) - rec[t0].q(c)));
      if (reach < 2 * params::kPositionBand[c]) continue;
      ++cases;
      PositionCrossCheck<double> m = at[t0];
      std::int32_t frozen[kDof];
      for (std::size_t t = t0; t < t0 + 3000; ++t) {
        std::int32_t counts[kDof];
        for (int i = 0; i < kDof; ++i) counts[i] = rec[t].counts[i];
        if (t == t0)
          for (int i = 0; i < kDof; ++i) frozen[i] = counts[i];
        counts[c] = frozen[c];
        if (m.check(pots[t].data(), true, angles_from_counts(q_start, io, counts)) & kFaultPositionMismatch) {
          ++found;
          const double travel = std::fabs(rec[t].q(c) - rec[t0].q(c));
          worst_ms = std::max(worst_ms, static_cast<double>(t - t0));
          worst_travel = std::max(worst_travel, travel);
          // A first-order filter behind a ramp lags by its time constant times the speed: found once the
          // joint has moved its band, plus that lag at its fastest since t0, plus the qualifying updates.
          double v_max = 0;
          for (std::size_t k = t0 + 1; k <= t; ++k)
            v_max = std::max(v_max, std::fabs(rec[k].q(c) - rec[k - 1].q(c)) / 1e-3);
          const double lag = params::kPositionFilter + (params::kPositionQualify + 1) * 3e-3;
          worst_excess = std::max(worst_excess, travel - (params::kPositionBand[c] + v_max * lag));
          break;
        }
      }
    }
    std::printf(
        "J%d: %d stuck-encoder cases in motion, %d found; worst %.0f ms, joint travel %.1f mrad (band %.1f; beyond "
        "band + speed x lag: %.1f mrad)\n",
        c + 1, cases, found, worst_ms, 1e3 * worst_travel, 1e3 * params::kPositionBand[c], 1e3 * worst_excess);
    EXPECT_GT(cases, 0) << "J" << c + 1 << ": the motion does not move it enough";
    EXPECT_EQ(found, cases) << "J" << c + 1;
    EXPECT_LT(worst_excess, 0.002) << "J" << c + 1 << ": found later than its band and the filter's lag";
  }
}

}  // namespace
