// The identification run's estimate in closed loop (issue 57): the identify command over the simulated arm,
// the tick's sampler (osc/runtime/identify_run.hpp) and the main loop's estimate, against the plant's own
// friction and payload (the truth, which the controller never reads).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "motion_sim.hpp"
#include "motion_sim_util.hpp"
#include "experiment.hpp"
#include "injection.hpp"
#include "plant_preset.hpp"
#include "osc/runtime/parameters.hpp"
#include "osc/runtime/identify_run.hpp"
#include "test_util.hpp"

using namespace osc;
using sim::MotionSim;
using test::answer;
using test::run_ticks;
using test::start_pose;
using test::state_is;

namespace {

using V6 = sim::Vec6;

/// An identify run from enable to done, the estimate taken in the main loop's place after every tick; the arm held
/// `hold` ticks after the enable first.
template <class S>
IdentifyReport run_identify(MotionSim<S>& sim, std::uint16_t payload, std::uint32_t& taken, std::uint32_t& lost,
                            int hold = 500) {
  EXPECT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  const auto tr = run_ticks(sim, hold);
  EXPECT_EQ(tr.faults, 0u) << fault_name(tr.faults);
  IdentifyRun<S> run;
  run.start(5, payload, sim.task().model, sim.task().without_payload(), &sim.task().io);
  sim.identify(5);
  sim.tick();
  EXPECT_EQ(sim.task().report.outcome, CommandOutcome::kAccepted) << motion_name(sim.task().report.refusal);
  std::uint32_t faults = 0;
  for (std::uint64_t k = 0; k < excitation::kTicks + 100 && sim.task().report.done_id != 5; ++k) {
    faults |= sim.tick();
    run.poll(sim.task().identify);
  }
  EXPECT_EQ(faults, 0u) << fault_name(faults);
  EXPECT_EQ(sim.task().report.done_id, 5u);
  taken = run.taken();
  lost = run.lost();
  return run.finish();
}

/// How far a run's friction is from the plant's: the largest error over issue 57's bar (10 % of the coefficient, or
/// 0.05 in its unit where that is more), over the reported sigma, and of a Coulomb + Stribeck sum relative to it; and
/// the largest reported sigma over the bar for it (2.5 % of the coefficient, with the same floor, 0.05).
/// `except`: the coefficient kinds (bit c: 0 vis, 1 cou, 2 sti) left out of `bar` and `sd`.
struct FrictionErrors {
  double bar = 0, sigmas = 0, sum = 0, sd = 0;
};

/// Prints each coefficient against the plant's, with its sigma; returns the errors.
FrictionErrors report_friction(const IdentifyReport& r, const FrictionCoefficients& truth, const char* what,
                               unsigned except = 0) {
  const double* t[3] = {truth.vis, truth.cou, truth.sti};
  const char* names[3] = {"vis", "cou", "sti"};
  FrictionErrors e;
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < kDof; ++i) {
      const int k = c * kDof + i;
      const double error = std::fabs(r.friction(k) - t[c][i]);
      std::printf("  %s J%d: %8.4f (plant %8.4f), sd %.4f (%.1f %%), error %.1f sd\n", names[c], i + 1, r.friction(k),
                  t[c][i], r.friction_sd(k), 100 * r.friction_sd(k) / t[c][i], error / r.friction_sd(k));
      e.sigmas = std::max(e.sigmas, error / r.friction_sd(k));
      if (except >> c & 1u) continue;
      e.bar = std::max(e.bar, error / std::max(0.1 * t[c][i], 0.05));
      e.sd = std::max(e.sd, r.friction_sd(k) / std::max(0.025 * t[c][i], 0.05));
    }
  for (int i = 0; i < kDof; ++i) {
    const double sum = r.friction(kDof + i) + r.friction(2 * kDof + i), plant = truth.cou[i] + truth.sti[i];
    e.sum = std::max(e.sum, std::fabs(sum - plant) / plant);
  }
  std::printf(
      "%s: condition %.0f; prediction error %.3f (J%d); status %d; worst error %.2f of the bar, %.1f sd; the "
      "sums within %.2f %%; the largest sd %.2f of its bar\n",
      what, r.condition, r.worst_prediction_error, r.worst_joint + 1, static_cast<int>(r.status), e.bar, e.sigmas,
      100 * e.sum, e.sd);
  return e;
}

/// A run on the ideal plant with the realistic plant's drive train: the published encoders and the wrist's coupling,
/// each motor with its own friction at its own rate (the plant's C^-T f(C^-1 q')). The estimate is the drives' (the
/// regression in the drives' space: osc/runtime/identify_run.hpp); each coefficient printed against the plant's.
std::unique_ptr<MotionSim<double>> coupled_sim() {
  sim::ExperimentConfig cfg;
  cfg.published_encoders = true;
  cfg.plant.coupling = true;
  auto sim = std::make_unique<MotionSim<double>>(test::identify_pose(), sim::Injection{}, cfg.plant,
                                                 FrictionMode::kAdaptive, Gains<double>::paper(), cfg.sensor_config());
  EXPECT_TRUE(sim->task().io.coupled());
  return sim;
}
IdentifyReport coupled_run() {
  const auto sim = coupled_sim();
  std::uint32_t taken = 0, lost = 0;
  return run_identify(*sim, payload_mask::kNone, taken, lost);
}

/// One run on the ideal plant with the friction preset `preset` from the runs' pose (0.656 of the design) in scalar S:
/// every sample taken, the run's estimate ok, every coefficient within 3 of its reported sigma, and each joint's
/// Coulomb + Stribeck sum, the friction at the onset of motion, within 1 %. The errors over issue 57's bars are the
/// caller's to judge (`except` as report_friction's).
template <class S>
FrictionErrors ideal_plant_run(const char* what, int preset = 0, unsigned except = 0) {
  sim::PlantConfig pc;
  pc.friction = *robot::kFrictionPresets[preset];
  MotionSim<S> sim(test::identify_pose(), {}, pc);
  std::uint32_t taken = 0, lost = 0;
  const IdentifyReport r = run_identify(sim, payload_mask::kNone, taken, lost);
  EXPECT_EQ(r.status, IdentifyStatus::kOk) << what;
  EXPECT_EQ(lost, 0u) << what;
  EXPECT_GE(taken, 15900u) << what;  // 80 000 ticks, one sample in kRunSampleTicks
  const FrictionErrors e = report_friction(r, *robot::kFrictionPresets[preset], what, except);
  EXPECT_LE(e.sigmas, 3.0) << what;
  EXPECT_LE(e.sum, 0.01) << what;
  return e;
}

}  // namespace

// The paper's friction: every coefficient within issue 57's bar, and its sigma within the 2.5 % with the bar's
// floor (0.05 in its unit). Measured (docs/adaptation.md, section 6): MEASURED_PAPER.
TEST(IdentifySim, TheFrictionOfTheIdealPlantFromOneRunInEveryScalar) {
  for (const FrictionErrors& e :
       {ideal_plant_run<double>("double"), ideal_plant_run<float>("float"), ideal_plant_run<fixed::Q<19>>("Q12.19")}) {
    EXPECT_LE(e.bar, 1.0);
    if (test::kPumaBuild) {
      EXPECT_LE(e.sd, 1.0);  // the UR5e's sigma at its start pose: not measured yet
    }
  }
}

// Corke's friction (no Stribeck term; J1's Coulomb level 26 N m): the viscous and Coulomb coefficients within the bar
// and their sigma within 2.5 %, or 0.05 in the unit. Not the Stribeck levels, all 0: the bar is the floor, 0.05 N m,
// and J1's split is known to MEASURED_CORKE (J1's residual noise is 0.13 N m, twice the paper
// preset's), which the report says: its estimate is within 3 of its sigma.
TEST(IdentifySim, TheCorkeFrictionOfTheIdealPlantFromOneRun) {
  if (!test::kPumaBuild) GTEST_SKIP() << "the PUMA's presets";
  const FrictionErrors e = ideal_plant_run<double>("double, corke", 1, 1u << 2);
  EXPECT_LE(e.bar, 1.0);
  EXPECT_LE(e.sd, 1.0);
}

// The wrist's coupling (the PUMA's q6 = e6 + 0.013 e4 - 0.18 e5) and the published encoders: in the joints' space J5's
// torque-prediction error was 23 % and the run failed (prediction_error); in the drives' space it is ok. Every
// coefficient within issue 57's bar and its sigma within its own since the friction law is the drives' too (measured
// 0.84 of the bar, the largest sigma 0.94 of its bar, prediction error 1.1 %, J5): with model (2) the joints' (the
// law's tau_f^ = W(q^dot^) theta^ against the plant's C^-T W(C^-1 q^dot) theta) the observer's rates carried its error,
// J6 4.4 times the bar and J3's Stribeck term 2.2 times (docs/adaptation.md, "The friction law on a coupled arm").
TEST(IdentifySim, TheWristsCoupledDrivesAreIdentifiedInTheDrivesSpace) {
  if (!test::kPumaBuild) GTEST_SKIP() << "the PUMA's coupled wrist";
  const IdentifyReport r = coupled_run();
  EXPECT_EQ(r.status, IdentifyStatus::kOk);
  EXPECT_LE(r.worst_prediction_error, 0.05);
  const FrictionErrors e = report_friction(r, *robot::kFrictionPresets[0], "the wrist coupled");
  EXPECT_LE(e.bar, 1.0);
  EXPECT_LE(e.sd, 1.0);
}

// The regression's model of a coupled drive train (osc/runtime/identify_run.hpp, "The rotors"), apart from the
// observer: the same run on the coupled ideal plant, with a second sampler fed the plant's own angles and motor rates
// (C^-1 of its joint rates) each tick, in the firmware's pairing (the angle at the tick's start, the torque of the tick
// before). Every coefficient within issue 57's bar and the torque-prediction error within 1 %: measured 0.61 of the
// bar and 0.6 % (J6); with the model's diagonal armature in the regression instead of each motor's rotor it was 1.66
// of the bar and J5's prediction error 1.7 %.
TEST(IdentifySim, TheDrivesRegressionIsExactOnThePlantsOwnSignals) {
  if (!test::kPumaBuild) GTEST_SKIP() << "the PUMA's coupled wrist";
  const auto owned = coupled_sim();
  MotionSim<double>& sim = *owned;
  ASSERT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 500);
  IdentifyRun<double> run;
  run.start(5, payload_mask::kNone, sim.task().model, sim.task().without_payload(), &sim.task().io);
  auto own = std::make_unique<IdentifySampler<double>>();  // 64 ticks of three vectors: off the stack
  own->reset();
  sim.identify(5);
  std::uint32_t faults = 0;
  for (std::uint64_t k = 0; k < excitation::kTicks + 100 && sim.task().report.done_id != 5; ++k) {
    const Vec6<double> q = sim.plant().q(), e_rate = motor_rates(sim.task().io, Vec6<double>(sim.plant().qd()));
    faults |= sim.tick();
    if (sim.task().gen.source() == MotionSource::kExcitation && !sim.task().gen.braking())
      own->tick(5, q, sim.task().last.tau, e_rate, sim.task().gains.tau_dec);
    run.poll(*own);
  }
  EXPECT_EQ(faults, 0u) << fault_name(faults);
  EXPECT_GE(run.taken(), 15900u);
  const IdentifyReport r = run.finish();
  const FrictionErrors e = report_friction(r, *robot::kFrictionPresets[0], "the plant's own signals");
  EXPECT_EQ(r.status, IdentifyStatus::kOk);
  EXPECT_LE(r.worst_prediction_error, 0.01);
  EXPECT_LE(e.bar, 1.0);
}

// The reported sigma over 20 seeds (issue 57's coverage bar): each seed draws every friction coefficient within +-20 %
// of the preset's, the start pose within +-2 encoder counts per joint (the encoders' phase along the run) and the
// encoders' edge jitter (0.1 count) from its own seed. Over the 20 x 18 coefficients the truth is within 2 sigma of
// the estimate in at least 85 % of cases and within 3 sigma in all.
TEST(IdentifySim, TheReportedSigmaCoversThePlantsFrictionOver20Seeds) {
  int within2 = 0, within3 = 0, total = 0;
  double largest = 0;
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> band(-0.2, 0.2), count(-2, 2);
    FrictionCoefficients truth = *robot::kFrictionPresets[0];
    for (int i = 0; i < kDof; ++i) {
      truth.vis[i] *= 1 + band(rng);
      truth.cou[i] *= 1 + band(rng);
      truth.sti[i] *= 1 + band(rng);
    }
    sim::PlantConfig pc;
    pc.friction = truth;
    sim::SensorConfig sensors;
    sensors.encoder_jitter = 0.1;
    sensors.seed = seed;
    V6 q0 = test::identify_pose();
    for (int i = 0; i < kDof; ++i) q0(i) += count(rng) / robot::kEncodersUniform.counts_per_rad[i];
    MotionSim<double> sim(q0, {}, pc, FrictionMode::kAdaptive, Gains<double>::paper(), sensors);
    std::uint32_t taken = 0, lost = 0;
    const IdentifyReport r = run_identify(sim, payload_mask::kNone, taken, lost);
    ASSERT_EQ(r.status, IdentifyStatus::kOk) << seed;
    const double* t[3] = {truth.vis, truth.cou, truth.sti};
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < kDof; ++i) {
        const double z = std::fabs(r.friction(c * kDof + i) - t[c][i]) / r.friction_sd(c * kDof + i);
        within2 += z <= 2, within3 += z <= 3, ++total;
        largest = std::max(largest, z);
      }
  }
  std::printf("20 seeds: %.1f %% within 2 sigma, %.1f %% within 3, the largest %.2f sigma\n", 100.0 * within2 / total,
              100.0 * within3 / total, largest);
  EXPECT_GE(within2, 0.85 * total);
  EXPECT_EQ(within3, total);
}

/// Sets a payload as a client would, through the parameters (param_set: payload_mass, payload_com, then
/// payload_inertia, its diagonal before its products); an inertia the parameters refuse (not_physical: an estimate's
/// noise about a point mass) is left at zero. Returns whether the inertia was set.
bool set_payload_params(ControlTask<double>& task, const Payload& p) {
  const int mass = param_index("payload_mass"), com = param_index("payload_com"),
            inertia = param_index("payload_inertia");
  EXPECT_EQ(param_set(task, mass, 0, p.mass), ParamStatus::kOk);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(param_set(task, com, k, p.com[k]), ParamStatus::kOk) << k;
  for (int k = 0; k < 6; ++k)
    if (param_set(task, inertia, k, p.inertia[k]) != ParamStatus::kOk) {
      for (int m = k - 1; m >= 0; --m) EXPECT_EQ(param_set(task, inertia, m, 0.0), ParamStatus::kOk);
      return false;
    }
  return true;
}

/// What the paper's motion and 50 random moves gave with a payload on the arm and `model` in the model.
struct PayloadRun {
  double paper = 0;  ///< the paper's 120 s: the largest |reference - tip| from 5 s [m]
  test::RandomMoves moves;
  std::uint32_t faults = 0;
  bool inertia = false;  ///< the model's payload inertia set (else left at zero: the parameters refused it)
};

PayloadRun run_with_payload(const sim::PlantConfig& plant, const Payload& model) {
  MotionSim<double> sim(test::start_pose(), {}, plant);
  PayloadRun out;
  out.inertia = set_payload_params(sim.task(), model);
  EXPECT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  out.faults |= run_ticks(sim, 300).faults;
  EXPECT_EQ(answer(sim, MotionVerb::kPaper, 2).outcome, CommandOutcome::kAccepted);
  out.faults |= run_ticks(sim, 5000).faults;
  const test::Trace paper = run_ticks(sim, 115000);
  out.paper = paper.tracking, out.faults |= paper.faults;
  EXPECT_EQ(answer(sim, MotionVerb::kStop, 3).outcome, CommandOutcome::kAccepted);
  out.faults |= test::run_until(
                    sim, [](const MotionSim<double>& s) { return test::state_is(s, MotionState::kHolding); }, 10000)
                    .faults;
  out.moves = test::random_moves(sim, 55, 50);
  out.faults |= out.moves.faults;
  return out;
}

// The payload bars of issue 57: 0.5, 1.5 and 2.5 kg at three offsets up to 0.1 m from frame 6's origin. Each is
// re-identified from a rough setting (a datasheet's, 10 % light and its centre of mass 10 % short: the model carries
// it, so the monitors see little unmodelled weight), the run estimating the whole payload (all ten parameters) with
// the arm's own model (IdentifyRun's bare model): mass within 3 %, centre of mass within 5 mm. Then the identified
// payload is set (through the parameters, as `identify --apply` does) on an arm carrying the true one: the paper's
// 120 s and 50 random moves run with no fault, the paper's largest tracking error from 5 s and the moves' mean of
// each move's largest within 10 % of the same runs without a payload. (The largest of all 50 moves, printed, is one
// move's: a move accepted or refused by a hair changes the sequence after it, and a payload estimate 0.1 g and
// 0.01 mm apart moved it from -30 % to +12 %.) At 20 % light the 2.5 kg case's unmodelled 0.5 kg at 0.1 m raised
// encoder_stuck during the run (its samples before it gave 2.4993 kg, 0.14 mm). One line per case (docs_tables.py:
// table payload_identified).
TEST(IdentifySim, PayloadsFromARoughSettingAreIdentifiedAndTrackWhenSet) {
  const PayloadRun bare = run_with_payload({}, Payload{});
  ASSERT_EQ(bare.faults, 0u) << fault_name(bare.faults);
  std::printf("payload none: paper %.4f mm, 50 moves %.4f mm, largest %.4f mm (%d refused)\n", bare.paper * 1e3,
              bare.moves.mean_tracking() * 1e3, bare.moves.tracking * 1e3, bare.moves.refused);
  const double offsets[3][3] = {{0.1, 0, 0}, {0, 0.05, 0.08}, {0.03, -0.03, 0.09}};
  for (const double mass : {0.5, 1.5, 2.5})
    for (const auto& c : offsets) {
      sim::PlantConfig pc;
      pc.payload.mass = mass;
      Payload guess;
      guess.mass = 0.9 * mass;
      for (int k = 0; k < 3; ++k) pc.payload.com[k] = c[k], guess.com[k] = 0.9 * c[k];
      MotionSim<double> sim(test::identify_pose(), {}, pc);
      sim.task().set_payload(guess);
      std::uint32_t taken = 0, lost = 0;
      const IdentifyReport r = run_identify(sim, payload_mask::kAll, taken, lost);
      const Payload found = PayloadParams<double>::of(r.payload).body();
      const Vec3<double> com(found.com[0], found.com[1], found.com[2]), truth(c[0], c[1], c[2]);
      EXPECT_EQ(r.status, IdentifyStatus::kOk) << mass;
      EXPECT_NEAR(found.mass, mass, 0.03 * mass);
      EXPECT_LT((com - truth).norm(), 5e-3) << mass;
      const PayloadRun set = run_with_payload(pc, found);
      std::printf(
          "payload %.1f kg at (%.2f, %.2f, %.2f) m: %.4f kg (%+.2f %%), centre of mass %.2f mm off, condition %.0f; "
          "set (inertia %s): paper %.4f mm (%+.1f %%), 50 moves %.4f mm (%+.1f %%), largest %.4f mm, faults %s\n",
          mass, c[0], c[1], c[2], found.mass, 100 * (found.mass / mass - 1), 1e3 * (com - truth).norm(), r.condition,
          set.inertia ? "too" : "left at zero", set.paper * 1e3, 100 * (set.paper / bare.paper - 1),
          set.moves.mean_tracking() * 1e3, 100 * (set.moves.mean_tracking() / bare.moves.mean_tracking() - 1),
          set.moves.tracking * 1e3, set.faults ? fault_name(set.faults) : "none");
      EXPECT_EQ(set.faults, 0u) << fault_name(set.faults) << ", move " << set.moves.failed_id;
      EXPECT_EQ(set.moves.failed_id, 0u);
      EXPECT_LE(set.paper, 1.1 * bare.paper) << mass;
      EXPECT_LE(set.moves.mean_tracking(), 1.1 * bare.moves.mean_tracking()) << mass;
    }
}

// A payload not yet identified (docs/safety.md, "A payload not yet identified"): none in the model, 0.5, 1.5 and
// 2.5 kg at (0.03, -0.03, 0.09) m on the arm, the parameter payload_allowance at the payload's own mass (a
// datasheet's) and at the rating. The arm holds 1.5 s after the enable and the identify run estimates the payload with
// no fault: its mass within 3 %, its centre of mass within 5 mm (issue 57's bars); the residual monitor's largest ratio
// is printed. Without the allowance the same enable stops within the second (payload_mismatch: the held-pose rule)
// for 1.5 and 2.5 kg.
TEST(IdentifySim, APayloadNotYetIdentifiedIsIdentifiedWithTheAllowance) {
  const int allowance = param_index("payload_allowance");
  for (const double mass : {0.5, 1.5, 2.5}) {
    sim::PlantConfig pc;
    pc.payload.mass = mass;
    pc.payload.com[0] = 0.03, pc.payload.com[1] = -0.03, pc.payload.com[2] = 0.09;
    const double allowances[2] = {mass, robot::kPayloadRating.mass};
    for (int a = 0; a < (mass < robot::kPayloadRating.mass ? 2 : 1); ++a) {
      const double allowed = allowances[a];
      MotionSim<double> sim(test::identify_pose(), {}, pc);
      ASSERT_EQ(param_set(sim.task(), allowance, 0, allowed), ParamStatus::kOk);
      std::uint32_t taken = 0, lost = 0;
      const IdentifyReport r = run_identify(sim, payload_mask::kAll, taken, lost, 1500);
      const Payload found = PayloadParams<double>::of(r.payload).body();
      const Vec3<double> com(found.com[0], found.com[1], found.com[2]), truth(0.03, -0.03, 0.09);
      double ratio = 0;
      for (int i = 0; i < kDof; ++i) ratio = std::max(ratio, sim.task().residual.peak_ratio(i));
      std::printf(
          "%.1f kg not yet identified, the allowance %.1f kg: %.4f kg (%+.2f %%), centre of mass %.2f mm off, the "
          "residual monitor's largest ratio %.2f\n",
          mass, allowed, found.mass, 100 * (found.mass / mass - 1), 1e3 * (com - truth).norm(), ratio);
      EXPECT_EQ(r.status, IdentifyStatus::kOk) << mass << ", " << allowed;
      EXPECT_EQ(lost, 0u) << mass;
      EXPECT_NEAR(found.mass, mass, 0.03 * mass) << allowed;
      EXPECT_LT((com - truth).norm(), 5e-3) << mass << ", " << allowed;
    }
    if (mass < 1) continue;
    MotionSim<double> without(test::identify_pose(), {}, pc);
    EXPECT_EQ(answer(without, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
    EXPECT_EQ(run_ticks(without, 1500).faults, kFaultPayloadMismatch) << mass;
  }
}

/// The mean over [t0, t1] of the realistic plant's friction scale, 1 + d sin(2 pi t / P) (PlantConfig's drift).
static double mean_drift(const sim::PlantConfig& pc, double t0, double t1) {
  if (pc.friction_drift == 0) return 1;
  const double w = 2 * kPi / pc.friction_drift_period;
  return 1 + pc.friction_drift * (std::cos(w * t0) - std::cos(w * t1)) / (w * (t1 - t0));
}

/// The plant's friction preset scaled by its drift's mean over the run that ended now and lasted `seconds`.
static FrictionCoefficients drifted(const sim::PlantConfig& pc, double now, double seconds) {
  FrictionCoefficients f = pc.friction;
  const double s = mean_drift(pc, now - seconds, now);
  for (int i = 0; i < kDof; ++i) f.vis[i] *= s, f.cou[i] *= s, f.sti[i] *= s;
  return f;
}

// The realistic plant (every feature at its mid value: the AKB86 motors, the wrist coupled, the published encoders,
// the amplifiers' lag, gains and offsets, ripple, backlash, elastic joints, the friction's drift, the current check's
// dither). The first run finds the drives' armature (the AKB86 motors' 0.36 / 2.43 / 0.29 kg m^2 more on J1-J3), set
// with the parameter armature_correction before a second run, which reuses the command id (every sample taken). The
// truth is the plant's preset times its drift's mean over the run. Measured: the armatures 0.332 / 2.507 / 0.333 (J3
// 16 % off); the second run's J1, J5 and J6 within the bar (J6 since the friction law is the drives' on a coupled arm,
// J5 since each drive's offset is estimated: they were 6.4 and 8.7 times it), J4's viscous term 1.4 times it, J3's
// Stribeck 2.1, J2 4.5 (docs/adaptation.md, "The drives' armature in the model").
// With the coupled rotors' inertia C^-T J_m C^-1 in the model (commit 27fcb2d, taken back: docs/adaptation.md) the
// armatures came out within 7.6 % and every coefficient of J1-J4 within the bar (0.98 of it at worst).
TEST(IdentifySim, TheRealisticPlantsFrictionWithItsArmatureSet) {
  if (!test::kPumaBuild) GTEST_SKIP() << "the PUMA's realistic plant";
  sim::ExperimentConfig cfg;
  ASSERT_TRUE(sim::apply_plant_preset("realistic", cfg));
  MotionSim<double> sim(test::identify_pose(), {}, cfg.plant, FrictionMode::kAdaptive, Gains<double>::paper(),
                        cfg.sensor_config());
  std::uint32_t taken = 0, lost = 0;
  const double run_seconds = excitation::kTicks / params::kControlHz;
  const IdentifyReport first = run_identify(sim, payload_mask::kNone, taken, lost);
  report_friction(first, drifted(cfg.plant, sim.plant().time(), run_seconds), "realistic, the first run");
  const int a = param_index("armature_correction");
  for (int i = 0; i < kDof; ++i) {
    const LinkParams& l = robot::kArm.links[i];
    const double truth = l.gear_ratio * l.gear_ratio * (robot::kDriveTrain.motor_inertia_alt.jm[i] - l.motor_inertia);
    std::printf("  armature J%d: %.4f (plant %.4f), sd %.4f\n", i + 1, first.armature(i), truth, first.armature_sd(i));
    if (i < 2) {
      EXPECT_NEAR(first.armature(i), truth, 0.1 * truth) << "J" << i + 1;
    }
  }
  EXPECT_EQ(answer(sim, MotionVerb::kDisable, 2).outcome, CommandOutcome::kAccepted);
  for (int i = 0; i < kDof; ++i) ASSERT_EQ(param_set(sim.task(), a, i, first.armature(i)), ParamStatus::kOk) << i;
  const IdentifyReport second = run_identify(sim, payload_mask::kNone, taken, lost);
  const FrictionCoefficients truth = drifted(cfg.plant, sim.plant().time(), run_seconds);
  report_friction(second, truth, "realistic, the armature set");
  EXPECT_EQ(second.status, IdentifyStatus::kOk);
  EXPECT_EQ(lost, 0u);
  const double* t[3] = {truth.vis, truth.cou, truth.sti};
  for (int c = 0; c < 3; ++c)
    for (int i : {0, 4, 5})  // J1's, J5's and J6's three coefficients
      EXPECT_LE(std::fabs(second.friction(c * kDof + i) - t[c][i]), std::max(0.1 * t[c][i], 0.05))
          << c << " J" << i + 1;
}

/// test_motion_sim's warm and cold move (0.10, -0.08, 0.05 m with 0.3 rad of yaw, at the move maxima) from the start
/// pose on a freshly built arm (a power-on) that first applies `record`, as a board's boot applies its stored one:
/// the move's tracking error [m].
static double first_move_after(const ParamRecord* record) {
  MotionSim<double> sim(start_pose());
  if (record) {
    EXPECT_EQ(param_apply(sim.task(), *record), ParamStatus::kOk);
  }
  EXPECT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  run_ticks(sim, 300);
  MoveRequest<double> req = test::relative<double>(0.10, -0.08, 0.05);
  req.has_rpy = true;
  req.rpy = Vec3<double>(0, 0, 0.3);
  EXPECT_EQ(test::answer_move(sim, req, 7).outcome, CommandOutcome::kAccepted);
  const test::Trace r = test::run_until(
      sim, [](const MotionSim<double>& s) { return s.task().report.done_id != 0; }, 20000);
  EXPECT_EQ(r.faults, 0u) << fault_name(r.faults);
  EXPECT_EQ(sim.task().report.done_id, 7u);
  return r.tracking;
}

// Issue 57's persistence, in process: what the friction law learnt (10 s of the paper's motion), or an identify run's
// friction set with param set, kept in a parameter record (f32, as a store keeps it) and applied at the next
// power-on. The first move then tracks within 0.5 mm; from a cold start (theta^ = 0) it is over 1 mm (2.32 mm:
// test_motion_sim). The virtual board's and the QEMU image's restart are not yet in this test.
TEST(IdentifySim, AFirstMoveFromSavedFrictionIsNotAColdStart) {
  MotionSim<double> a(start_pose());
  EXPECT_EQ(answer(a, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(answer(a, MotionVerb::kPaper, 2).outcome, CommandOutcome::kAccepted);
  run_ticks(a, 10000);
  EXPECT_EQ(answer(a, MotionVerb::kStop, 3).outcome, CommandOutcome::kAccepted);
  test::run_until(
      a, [](const MotionSim<double>& s) { return state_is(s, MotionState::kHolding); }, 10000);
  EXPECT_EQ(answer(a, MotionVerb::kDisable, 4).outcome, CommandOutcome::kAccepted);
  const ParamRecord learnt = param_capture(a.task());
  MotionSim<double> b(test::identify_pose());
  std::uint32_t taken = 0, lost = 0;
  const IdentifyReport r = run_identify(b, payload_mask::kNone, taken, lost);
  ASSERT_EQ(r.status, IdentifyStatus::kOk);
  EXPECT_EQ(answer(b, MotionVerb::kDisable, 6).outcome, CommandOutcome::kAccepted);
  const int vis = param_index("friction_vis");
  for (int k = 0; k < 3 * kDof; ++k)
    ASSERT_EQ(param_set(b.task(), vis + k / kDof, k % kDof, std::clamp(r.friction(k), 0.0, params::kThetaMax[k])),
              ParamStatus::kOk)
        << k;
  const ParamRecord identified = param_capture(b.task());
  const double cold = first_move_after(nullptr), warm = first_move_after(&learnt),
               known = first_move_after(&identified);
  std::printf("the first move after a power-on: cold %.3f mm, the learnt friction %.3f mm, the identified %.3f mm\n",
              cold * 1e3, warm * 1e3, known * 1e3);
  EXPECT_GT(cold, 1e-3);
  EXPECT_LE(warm, 0.5e-3);
  EXPECT_LE(known, 0.5e-3);
}

/// Issue 57's stale saved friction in closed loop: an arm built afresh (a power-on) on `plant` applies the friction
/// `saved` (as a board's boot applies its stored record) and runs the paper's motion for `seconds`. Returns each
/// joint's verdict (the state frame's friction_checked and friction_stale, FrictionIdentifier::checked and stale)
/// and the time of its first check [s] (-1 none).
struct FitVerdict {
  std::uint8_t checked = 0, stale = 0;
  double at[kDof] = {-1, -1, -1, -1, -1, -1};
};
static FitVerdict fit_after_power_on(const sim::PlantConfig& plant, const FrictionCoefficients& saved, double seconds,
                                     const sim::SensorConfig& sensors = {}) {
  MotionSim<double> sim(start_pose(), {}, plant, FrictionMode::kAdaptive, Gains<double>::paper(), sensors);
  const char* names[3] = {"friction_vis", "friction_cou", "friction_sti"};
  const double* values[3] = {saved.vis, saved.cou, saved.sti};
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < kDof; ++i)
      EXPECT_EQ(param_set(sim.task(), param_index(names[c]), i, values[c][i]), ParamStatus::kOk) << names[c] << i;
  EXPECT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(answer(sim, MotionVerb::kPaper, 2).outcome, CommandOutcome::kAccepted);
  FitVerdict v;
  std::uint32_t faults = 0;
  const auto& id = sim.task().state.adapt.identifier;
  for (long k = 0; k < static_cast<long>(seconds * params::kControlHz); ++k) {
    faults |= sim.tick();
    for (int i = 0; i < kDof; ++i)
      if (v.at[i] < 0 && (id.fit.checked() >> i & 1u)) v.at[i] = sim.plant().time();
  }
  EXPECT_EQ(faults, 0u) << fault_name(faults);
  v.checked = id.fit.checked();
  v.stale = id.fit.stale;
  for (int i = 0; i < kDof; ++i)
    std::printf("  J%d: %s at %.1f s; breakaway set %.3f, now %.3f N m\n", i + 1,
                !(v.checked >> i & 1u) ? "not checked"
                : (v.stale >> i & 1u)  ? "stale"
                                       : "fits",
                v.at[i], saved.cou[i] + saved.sti[i],
                sim.task().state.adapt.theta_hat(kDof + i) + sim.task().state.adapt.theta_hat(2 * kDof + i));
  return v;
}

// A saved friction that fits is checked and found to fit; one that no longer fits the arm (the arm's J2 friction 40 %
// above it, J1's 40 % below) is reported stale on those joints within the paper's motion, and the others still fit;
// one 10 % off, within params::kSavedFitFraction, fits. The saved friction is the plant's (an identification that was
// exact); the ideal plant with the paper's friction.
TEST(IdentifySim, ASavedFrictionThatNoLongerFitsTheArmIsReportedStale) {
  const sim::PlantConfig plant;
  const FrictionCoefficients saved = plant.friction;
  std::printf("the plant's friction, saved:\n");
  const FitVerdict same = fit_after_power_on(plant, saved, 120);
  sim::PlantConfig changed = plant;
  for (auto [i, f] : {std::pair{0, 0.6}, std::pair{1, 1.4}})
    changed.friction.vis[i] *= f, changed.friction.cou[i] *= f, changed.friction.sti[i] *= f;
  std::printf("J1's friction 40 %% below the saved, J2's 40 %% above:\n");
  const FitVerdict stale = fit_after_power_on(changed, saved, 120);
  sim::PlantConfig near = plant;
  for (int i = 0; i < kDof; ++i) near.friction.vis[i] *= 1.1, near.friction.cou[i] *= 1.1, near.friction.sti[i] *= 1.1;
  std::printf("every joint's friction 10 %% above the saved:\n");
  const FitVerdict within = fit_after_power_on(near, saved, 120);
  // Every joint is checked on the paper's motion, within 30 s (J1, the slowest; measured 29.7-29.8 s).
  for (const FitVerdict* v : {&same, &stale, &within}) {
    EXPECT_EQ(v->checked, 0x3Fu);
    for (int i = 0; i < kDof; ++i) EXPECT_LE(v->at[i], 35.0) << i;
  }
  EXPECT_EQ(same.stale, 0u);
  EXPECT_EQ(stale.stale, 0x3u);
  EXPECT_EQ(within.stale, 0u);
}

// The same on the realistic plant (every feature at its mid value, the friction drifting +-30 % an hour), the saved
// friction what the law learnt there in the paper's 120 s (param_capture, as param save keeps it): after a power-on
// the same arm's is found to fit, and with J2's friction 40 % above it, stale.
TEST(IdentifySim, OnTheRealisticPlantWhatTheLawLearntFitsAfterAPowerOn) {
  if (!test::kPumaBuild) GTEST_SKIP() << "the PUMA's realistic plant";
  sim::ExperimentConfig cfg;
  ASSERT_TRUE(sim::apply_plant_preset("realistic", cfg));
  MotionSim<double> a(start_pose(), {}, cfg.plant, FrictionMode::kAdaptive, Gains<double>::paper(),
                      cfg.sensor_config());
  EXPECT_EQ(answer(a, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(answer(a, MotionVerb::kPaper, 2).outcome, CommandOutcome::kAccepted);
  const auto tr = run_ticks(a, 120000);
  EXPECT_EQ(tr.faults, 0u) << fault_name(tr.faults);
  FrictionCoefficients learnt{};
  for (int i = 0; i < kDof; ++i) {
    const Vec18<double>& th = a.task().state.adapt.theta_hat;
    learnt.vis[i] = static_cast<float>(th(i)), learnt.cou[i] = static_cast<float>(th(kDof + i));
    learnt.sti[i] = static_cast<float>(th(2 * kDof + i));
  }
  std::printf("realistic, what the law learnt, saved:\n");
  const FitVerdict same = fit_after_power_on(cfg.plant, learnt, 120, cfg.sensor_config());
  sim::PlantConfig changed = cfg.plant;
  changed.friction.vis[1] *= 1.4, changed.friction.cou[1] *= 1.4, changed.friction.sti[1] *= 1.4;
  std::printf("realistic, J2's friction 40 %% above:\n");
  const FitVerdict stale = fit_after_power_on(changed, learnt, 120, cfg.sensor_config());
  EXPECT_EQ(same.stale, 0u);
  EXPECT_EQ(stale.stale & 0x2u, 0x2u);
  EXPECT_EQ(same.checked, 0x3Fu);
}

// A payload the model has wrong, enabled and holding at the runs' pose (docs/safety.md, "A payload the model has
// wrong"): 1.5 and 2.5 kg at (0.03, -0.03, 0.09) m on the arm and none in the model, and the same set in the model
// and none on the arm. Each is a category-0 stop within the first second after the enable, named payload_mismatch
// (before the held-pose rule: encoder_stuck, the travel check's), the sign of the mass it records the case's.
// Static friction holds part of the weight, so that the residual is less than it and no clean weight.
TEST(IdentifySim, APayloadTheModelHasWrongIsNamedAtTheEnable) {
  Payload p;
  p.com[0] = 0.03, p.com[1] = -0.03, p.com[2] = 0.09;
  for (const double mass : {1.5, 2.5})
    for (const bool on_arm : {true, false}) {
      p.mass = mass;
      sim::PlantConfig pc;
      if (on_arm) pc.payload = p;
      MotionSim<double> sim(test::identify_pose(), {}, pc);
      if (!on_arm) sim.task().set_payload(p);
      EXPECT_EQ(answer(sim, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
      const std::uint32_t faults = run_ticks(sim, 1000).faults;
      const ResidualMonitor<double>& m = sim.task().residual;
      std::printf(
          "%.1f kg %s: %s at %.3f s after the enable; the residual as a weight %.3f kg, %.1f mm off, misfit "
          "%.4f\n",
          mass, on_arm ? "on the arm, not set" : "set, not on the arm", fault_name(faults),
          static_cast<double>(m.detected_tick - m.primed_at) / params::kControlHz, m.flange.mass, 1e3 * m.flange.offset,
          m.flange.misfit);
      EXPECT_EQ(faults, kFaultPayloadMismatch) << mass << on_arm;
      EXPECT_EQ(m.flange.mass < 0, on_arm) << mass;
      EXPECT_LT(std::fabs(m.flange.mass), mass) << mass;
    }
}

// A payload set and not on the arm when a motion starts at the enable (docs/safety.md, "A payload the model has
// wrong"; docs/adaptation.md, table payload_stale): the paper's experiment with 1.5 and 2.5 kg at (0.03, -0.03, 0.09) m
// in the model and none on the arm. J5 counts away from its reference, which has all but not moved (4 and 12 counts
// by 0.108 and 0.082 s), what a stuck encoder cannot show (ResidualMonitor::off_reference): payload_mismatch on J5
// (before the rule: encoder_stuck), the mass recorded positive (the model's beyond the arm's). An encoder that sticks
// at the same motion's start (each joint's at 0.05 s, no payload) is not: encoder_stuck or the potentiometer's
// position_mismatch, never payload_mismatch or drive_fault.
TEST(IdentifySim, AStalePayloadAtAMotionsStartIsNamedAndAStuckEncoderThereIsNot) {
  const double com[3] = {0.03, -0.03, 0.09};
  for (const double mass : {1.5, 2.5}) {
    sim::ExperimentConfig c;
    c.duration = 0.5;
    c.params[param_slot(param_index("payload_mass"))] = mass;
    for (int k = 0; k < 3; ++k) c.params[param_slot(param_index("payload_com")) + k] = com[k];
    const sim::ExperimentResult r = sim::run_experiment(c);
    std::printf("%.1f kg set, none on the arm: %s at %.3f s on J%d, the residual as a weight %.3f kg\n", mass,
                fault_name(r.status), r.fault_time, r.residual_joint + 1, r.residual_weight_kg);
    EXPECT_EQ(r.status, kFaultPayloadMismatch) << mass;
    EXPECT_LE(r.fault_time, 0.15) << mass;
    EXPECT_EQ(r.residual_joint, 4) << mass;
    EXPECT_GT(r.residual_weight_kg, 0) << mass;
  }
  for (int j = 1; j <= kDof; ++j) {
    sim::ExperimentConfig c;
    c.duration = 2;
    const std::string spec = "encoder-stuck:" + std::to_string(j) + "@0.05";
    std::string err;
    ASSERT_TRUE(sim::parse_injection(spec.c_str(), c.injection, err)) << err;
    const sim::ExperimentResult r = sim::run_experiment(c);
    std::printf("J%d's encoder stuck at 0.05 s: %s at %.3f s\n", j, fault_name(r.status), r.fault_time);
    EXPECT_NE(r.status, 0u) << j;
    EXPECT_EQ(r.status & (kFaultPayloadMismatch | kFaultDriveFault), 0u) << j;
  }
}

// The held-pose rule's other side: an encoder that sticks while the arm holds its pose with the model right shows
// nothing, and one that sticks while the arm moves, within the first second after the enable too, is encoder_stuck,
// never payload_mismatch. Each joint's encoder stuck 0.2 s after the enable; a move from 0.1 s (each joint's own:
// the start pose with that joint 0.3 rad further, the other joints where they are). Measured: held, nothing but
// J5's position_mismatch (the potentiometer's cross-check); moving, encoder_stuck on the joint 0.21-0.31 s after
// the enable.
TEST(IdentifySim, AStuckEncoderIsNoPayloadWhetherTheArmHoldsOrMoves) {
  const V6 q0 = test::identify_pose();
  for (int j = 0; j < kDof; ++j) {
    sim::Injection inj;
    inj.enabled = true, inj.kind = sim::InjectionKind::kEncoderStuck, inj.joint = j, inj.at = 0.2;
    MotionSim<double> held(q0, inj);
    EXPECT_EQ(answer(held, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
    const std::uint32_t at_rest = run_ticks(held, 2000).faults;
    MotionSim<double> moving(q0, inj);
    EXPECT_EQ(answer(moving, MotionVerb::kEnable, 1).outcome, CommandOutcome::kAccepted);
    run_ticks(moving, 100);
    V6 q = q0;
    q(j) += 0.3;
    moving.move_to(test::to_joint_pose(q), 2);
    const std::uint32_t faults = run_ticks(moving, 2000).faults;
    const ResidualMonitor<double>& m = moving.task().residual;
    std::printf("J%d's encoder stuck at 0.2 s: holding, %s; moving, %s at %.3f s after the enable (J%d)\n", j + 1,
                fault_name(at_rest), fault_name(faults),
                static_cast<double>(m.detected_tick - m.primed_at) / params::kControlHz, m.joint + 1);
    EXPECT_EQ(at_rest & kFaultPayloadMismatch, 0u) << j;
    EXPECT_EQ(m.detected, kFaultEncoderStuck) << j;  // the residual monitor's first finding
    EXPECT_NE(faults & kFaultEncoderStuck, 0u) << j;
    EXPECT_EQ(faults & kFaultPayloadMismatch, 0u) << j;
  }
}

// The drives' torque offsets (identify_estimate.hpp's b_i): the coupled run with the realistic plant's amplifier
// offsets (0.1 % of each channel's range, signs mixed). Every coefficient within issue 57's bar and its sigma within
// its own, and each offset within 3 sigma and 6 mN m of the plant's (measured: within 2 mN m but J3's, 5 mN m and 5
// sigma off, as J3's armature correction is on the ideal plant: a bias of the run its sigma does not cover). Without
// the offsets' column 0.1 % of J5's range (0.04 N m) moved its Coulomb / Stribeck split by 0.43 N m (8.5 times the bar,
// J5's Stribeck at -0.03 against 0.40; the sum unchanged); the amplifiers' gain errors alone leave every coefficient
// within 0.26 of the bar.
TEST(IdentifySim, TheDrivesOffsetsAreEstimatedApartFromTheirFriction) {
  if (!test::kPumaBuild) GTEST_SKIP() << "the PUMA's coupled wrist";
  sim::ExperimentConfig cfg, real;
  ASSERT_TRUE(sim::apply_plant_preset("realistic", real));
  cfg.published_encoders = true;
  cfg.plant.coupling = true;
  for (int i = 0; i < kDof; ++i) cfg.plant.amp_offset[i] = real.plant.amp_offset[i];
  MotionSim<double> sim(test::identify_pose(), {}, cfg.plant, FrictionMode::kAdaptive, Gains<double>::paper(),
                        cfg.sensor_config());
  std::uint32_t taken = 0, lost = 0;
  const IdentifyReport r = run_identify(sim, payload_mask::kNone, taken, lost);
  const FrictionErrors e = report_friction(r, *robot::kFrictionPresets[0], "the amplifiers' offsets");
  EXPECT_EQ(r.status, IdentifyStatus::kOk);
  EXPECT_LE(e.bar, 1.0);
  EXPECT_LE(e.sd, 1.0);
  for (int i = 0; i < kDof; ++i) {
    std::printf("  offset J%d: %.4f (plant %.4f), sd %.4f\n", i + 1, r.offset(i), cfg.plant.amp_offset[i],
                r.offset_sd(i));
    EXPECT_NEAR(r.offset(i), cfg.plant.amp_offset[i], 3 * r.offset_sd(i) + 0.006) << "J" << i + 1;
  }
}
