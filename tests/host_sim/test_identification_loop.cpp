// Issue 26 in the closed loop: the `momentum` law (friction identified from the residual monitor's
// momentum residual, osc/control/identification.hpp) against the robust law on the paper's 120 s
// experiment, and on a frictionless plant. About a second of CPU per run in double.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "experiment.hpp"
#include "motion_sim.hpp"
#include "osc/control/identification.hpp"

using namespace sim;

namespace {

ExperimentConfig config(osc::AdaptationLaw law, const osc::FrictionCoefficients& friction, double duration = 120) {
  ExperimentConfig c;
  c.duration = duration;
  c.mode = osc::FrictionMode::kAdaptive;
  c.plant.friction = friction;
  c.gains.adaptation = law;
  c.window = 5;  // the windows after the first are "t >= 5 s"
  return c;
}

/// The worst |e| over the windows after the first (t >= the window's length) per axis [mm, deg].
std::array<double, 6> after_first_window(const ExperimentResult& r) {
  std::array<double, 6> worst{};
  for (std::size_t w = 1; w < r.window_max.size(); ++w)
    for (int a = 0; a < 6; ++a) worst[a] = std::max(worst[a], r.window_max[w][a]);
  return worst;
}

}  // namespace

// The robust law's slowness, the issue's test: 120 s into the paper's experiment its viscous
// estimate of J1 is still below half the plant's (0.62 of 5.8); the momentum law's is within 10 %.
// The same criterion (at least half the truth) fails on one law and passes on the other.
TEST(FrictionIdentification, RobustLawIsSlowWhereTheMomentumLawIsNot) {
  const ExperimentResult robust = run_experiment(config(osc::AdaptationLaw::kRobust, osc::robot::kFrictionPaper));
  const ExperimentResult momentum = run_experiment(config(osc::AdaptationLaw::kMomentum, osc::robot::kFrictionPaper));
  const double truth = osc::robot::kFrictionPaper.vis[0];
  std::printf("theta^_vis,J1 after 120 s: robust %.2f, momentum %.2f (plant %.2f)\n", robust.theta_hat[0],
              momentum.theta_hat[0], truth);
  ASSERT_EQ(robust.status, 0u);
  ASSERT_EQ(momentum.status, 0u);
  EXPECT_LT(robust.theta_hat[0], 0.5 * truth);
  EXPECT_GE(momentum.theta_hat[0], 0.5 * truth);
  EXPECT_NEAR(momentum.theta_hat[0], truth, 0.1 * truth);
}

// The 120 s criteria of issue 26 on the default plant: tracking from t = 5 s at or below half of
// Table I, the last 20 s at or below 0.08 mm; each joint's Coulomb + Stribeck sum identified and
// within 10 % of the plant's; every coefficient the excitation monitor calls identified within 10 %.
TEST(FrictionIdentification, PaperExperimentMeetsTheIssuesCriteria) {
  const ExperimentResult r = run_experiment(config(osc::AdaptationLaw::kMomentum, osc::robot::kFrictionPaper));
  ASSERT_EQ(r.status, 0u);
  ASSERT_TRUE(r.has_identification);
  const std::array<double, 6> after = after_first_window(r);
  for (int a = 0; a < 3; ++a) {
    std::printf("axis %d: max |e| from 5 s %.3f mm (half of Table I %.3f), last 20 s %.3f mm\n", a, after[a],
                kPaperTable1[a] / 2, r.final_max_error[a]);
    EXPECT_LE(after[a], kPaperTable1[a] / 2) << "axis " << a;
    EXPECT_LE(r.final_max_error[a], 0.08) << "axis " << a;
  }
  for (int j = 0; j < 6; ++j) {
    const double sum = r.theta_hat[6 + j] + r.theta_hat[12 + j], truth = r.theta_true[6 + j] + r.theta_true[12 + j];
    EXPECT_TRUE(osc::friction_identified(sum, r.breakaway_sd[j])) << "J" << j + 1 << " sd " << r.breakaway_sd[j];
    EXPECT_NEAR(sum, truth, 0.1 * truth) << "J" << j + 1;
  }
  for (int c = 0; c < 18; ++c) {
    if (osc::friction_identified(r.theta_hat[c], r.theta_sd[c])) {
      EXPECT_NEAR(r.theta_hat[c], r.theta_true[c], 0.1 * r.theta_true[c]) << "coefficient " << c;
    }
  }
}

// A frictionless plant: the momentum law's predicted friction stays at most 0.3 N m rms (the issue's
// bound; measured about 0.02), its estimates within [0, theta_max], no joint's breakaway sum
// identified (there is none to identify: its standard deviation is not small against 0).
TEST(FrictionIdentification, FrictionlessPlantPredictsNoFriction) {
  ExperimentConfig c = config(osc::AdaptationLaw::kMomentum, osc::kFrictionNone);
  c.final_window = 60;
  const ExperimentResult r = run_experiment(c);
  ASSERT_EQ(r.status, 0u);
  std::printf("frictionless plant: predicted friction rms %.3f N m over the last 60 s\n", r.friction_rms_error);
  EXPECT_LT(r.friction_rms_error, 0.3);
  for (int i = 0; i < 18; ++i) {
    EXPECT_GE(r.theta_min_seen[i], 0.0) << i;
    EXPECT_LE(r.theta_max_seen[i], osc::params::kThetaMax[i]) << i;
  }
  for (int j = 0; j < 3; ++j) EXPECT_LT(r.final_max_error[j], 0.08) << "axis " << j;
}

// Corke's friction (a Coulomb level five times the paper's on J1, no Stribeck term): the same
// identification without retuning, each breakaway sum within 5 %.
TEST(FrictionIdentification, CorkeFrictionIsIdentifiedToo) {
  const ExperimentResult r = run_experiment(config(osc::AdaptationLaw::kMomentum, osc::robot::kFrictionCorke));
  ASSERT_EQ(r.status, 0u);
  for (int j = 0; j < 6; ++j) {
    const double sum = r.theta_hat[6 + j] + r.theta_hat[12 + j], truth = r.theta_true[6 + j] + r.theta_true[12 + j];
    EXPECT_NEAR(sum, truth, 0.05 * truth) << "J" << j + 1;
  }
  const std::array<double, 6> after = after_first_window(r);
  for (int a = 0; a < 3; ++a) EXPECT_LE(after[a], kPaperTable1[a] / 2) << "axis " << a;
}

// Issue 57's item 5, the reported sigma on the paper's 120 s run over 20 seeds: each seed draws every friction
// coefficient within +-20 % of the paper's, the start pose within +-2 encoder counts per joint (the encoders' phase
// along the motion) and the encoders' edge jitter (0.1 count) from its own seed. Over the 20 x 24 reported values
// (the 18 coefficients and the 6 Coulomb + Stribeck sums) the plant's lies within 2 sigma of the estimate in at least
// 85 % of cases and within 3 sigma in all; and every sum is claimed (identified) in every seed. One line per value
// (docs_tables.py's table sigma_coverage reads them).
TEST(FrictionIdentification, TheReportedSigmaCoversThePlantsFrictionOver20Seeds) {
  constexpr int kSeeds = 20, kValues = 24;
  int within2[kValues] = {}, within3[kValues] = {}, claimed[kValues] = {};
  double largest[kValues] = {};
  for (std::uint32_t seed = 1; seed <= kSeeds; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> band(-0.2, 0.2), count(-2, 2);
    osc::FrictionCoefficients truth = osc::robot::kFrictionPaper;
    for (int i = 0; i < 6; ++i) {
      truth.vis[i] *= 1 + band(rng);
      truth.cou[i] *= 1 + band(rng);
      truth.sti[i] *= 1 + band(rng);
    }
    ExperimentConfig c = config(osc::AdaptationLaw::kMomentum, truth);
    c.sensors.encoder_jitter = 0.1;
    c.sensors.seed = seed;
    const osc::EncoderMap enc = c.encoder_map();
    for (int i = 0; i < 6; ++i) c.q_start(i) += count(rng) / enc.counts_per_rad[i];
    const ExperimentResult r = run_experiment(c);
    ASSERT_EQ(r.status, 0u) << seed;
    ASSERT_TRUE(r.has_identification);
    for (int v = 0; v < kValues; ++v) {
      const int j = v - 18;
      const double estimate = v < 18 ? r.theta_hat[v] : r.theta_hat[6 + j] + r.theta_hat[12 + j];
      const double plant = v < 18 ? r.theta_true[v] : r.theta_true[6 + j] + r.theta_true[12 + j];
      const double sd = v < 18 ? r.theta_sd[v] : r.breakaway_sd[j];
      const double z = std::fabs(estimate - plant) / sd;
      within2[v] += z <= 2, within3[v] += z <= 3, claimed[v] += osc::friction_identified(estimate, sd);
      largest[v] = std::max(largest[v], z);
    }
  }
  int all2 = 0, all3 = 0;
  for (int v = 0; v < kValues; ++v) {
    const char* names[4] = {"vis", "cou", "sti", "cou+sti"};
    std::printf("coverage %s J%d: %d/%d within 2 sigma, %d within 3, largest %.2f sigma, claimed in %d\n", names[v / 6],
                v % 6 + 1, within2[v], kSeeds, within3[v], largest[v], claimed[v]);
    all2 += within2[v], all3 += within3[v];
    if (v >= 18) {
      EXPECT_EQ(claimed[v], kSeeds) << "the sum of J" << v - 17;
    }
  }
  std::printf("coverage: %d of %d within 2 sigma (%.1f %%), %d within 3\n", all2, kSeeds * kValues,
              100.0 * all2 / (kSeeds * kValues), all3);
  EXPECT_GE(all2, 0.85 * kSeeds * kValues);
  EXPECT_EQ(all3, kSeeds * kValues);
}

/// Enables the simulated arm, runs the paper's motion for `paper_ticks`, stops it and lets it settle
/// into holding (4 s); returns the fault bits seen.
namespace {
std::uint32_t learn_then_hold(MotionSim<double>& sim, int paper_ticks) {
  std::uint32_t faults = 0;
  auto run = [&](int ticks) {
    for (int k = 0; k < ticks; ++k) faults |= sim.tick();
  };
  sim.command(osc::MotionVerb::kEnable, 1);
  run(500);
  sim.command(osc::MotionVerb::kPaper, 2);
  run(paper_ticks);
  sim.command(osc::MotionVerb::kStop, 3);
  run(4000);
  return faults;
}
}  // namespace

// Holding still, the momentum law learns nothing: theta^ is bit for bit the one the stop ended with
// (no sample counts while a joint does not move; the robust law's leakage would pull it toward 0).
// And a clear outside a fault, accepted, changes nothing: the monitors it restarts start from the
// torque that holds the arm. (A stuck-encoder monitor restarted from zero torque took the holding
// torque for a torque change without motion: encoder_stuck on J2 after a clear, found by the
// one-hour hold of docs/adaptation.md.) With the residual monitor armed and not.
TEST(FrictionIdentification, HoldingStillLearnsNothingAndAClearChangesNothing) {
  for (const bool armed : {false, true}) {
    MotionSim<double> sim(osc::joint_vector<double>(osc::robot::kQStart));
    sim.task().gains.adaptation = osc::AdaptationLaw::kMomentum;
    sim.task().residual.armed = armed;
    std::uint32_t faults = learn_then_hold(sim, 20000);
    auto run = [&](int ticks) {
      for (int k = 0; k < ticks; ++k) faults |= sim.tick();
    };
    ASSERT_EQ(sim.task().machine.state, osc::MotionState::kHolding);
    const osc::Vec18<double> held = sim.task().state.adapt.theta_hat;
    EXPECT_GT(held(osc::kDof + 1), 1.0);  // J2's Coulomb level: learnt during the motion
    run(10000);
    EXPECT_EQ(sim.task().state.adapt.theta_hat, held) << (armed ? "armed" : "trial");
    sim.command(osc::MotionVerb::kClear, 4);
    sim.tick();
    EXPECT_EQ(sim.task().report.outcome, osc::CommandOutcome::kAccepted);
    run(3000);
    EXPECT_EQ(faults, 0u) << (armed ? "armed" : "trial");
    EXPECT_EQ(sim.task().machine.state, osc::MotionState::kHolding);
  }
}

// One short move repeated (3 cm along x and back, as scripts/repeat_move.py's hour, here for a
// minute): the move does not excite the Coulomb / Stribeck split (its decay excitation stays below
// the gate), so every joint's Stribeck level is held bit for bit while its samples still count, and
// the sums the paper's motion identified hold within 1 %.
TEST(FrictionIdentification, RepeatedShortMoveHoldsTheUnexcitedSplit) {
  MotionSim<double> sim(osc::joint_vector<double>(osc::robot::kQStart));
  sim.task().gains.adaptation = osc::AdaptationLaw::kMomentum;
  std::uint32_t faults = learn_then_hold(sim, 30000);
  ASSERT_EQ(sim.task().machine.state, osc::MotionState::kHolding);
  const osc::FrictionIdentifier<double> before = sim.task().state.adapt.identifier;
  std::uint32_t id = 4;
  double dx = 0.03;
  for (int k = 0; k < 60000; ++k) {
    if (sim.idle() && sim.task().machine.state == osc::MotionState::kHolding) {
      osc::MoveRequest<double> r;
      r.position = osc::Vec3<double>(dx, 0, 0);
      r.relative = true;
      sim.move_to(r, id++);
      dx = -dx;
    }
    faults |= sim.tick();
  }
  EXPECT_EQ(faults, 0u);
  EXPECT_GT(id, 40u);  // the moves were made
  const osc::FrictionIdentifier<double>& after = sim.task().state.adapt.identifier;
  for (int j = 1; j < 3; ++j)  // J2 and J3 carry the move (J1 hardly turns)
    EXPECT_GT(after.updates[j], before.updates[j] + 100) << "J" << j + 1 << ": the move's samples count";
  for (int j = 0; j < 3; ++j) {
    EXPECT_LT(after.decay_excitation(j), osc::params::kIdentifySplitExcitation) << "J" << j + 1;
    EXPECT_EQ(after.z[j](2), before.z[j](2)) << "J" << j + 1 << ": the Stribeck level held";
    EXPECT_EQ(after.P[j](2, 2), before.P[j](2, 2)) << "J" << j + 1;
    const double sum_before = before.z[j](1), sum_after = after.z[j](1);  // the filter's coordinate cou + sti
    EXPECT_NEAR(sum_after, sum_before, 0.01 * sum_before) << "J" << j + 1;
  }
}
