// The experiment's configuration file and its outputs (host_sim/config.hpp, summary.hpp): defaults
// from the firmware headers, round trip through --print-config, errors that name the key, values
// that reach the run, and a summary JSON that nlohmann-json reads back.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "config.hpp"
#include "experiment_cli.hpp"
#include "summary.hpp"

namespace {

using sim::Settings;

bool apply(Settings& s, const std::string& yaml, std::string& err) {
  return sim::apply_config(yaml, "test.yaml", s, err);
}

TEST(Config, DefaultsAreTheFirmwareHeadersValues) {
  const Settings s;
  const auto j = sim::config_json(s);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(j["controller"]["knd"][i].get<double>(), osc::params::kKnd[i]);
    EXPECT_EQ(j["controller"]["k"][i].get<double>(), osc::params::kK[i]);
    EXPECT_EQ(j["controller"]["ks"][i].get<double>(), osc::params::kKs[i]);
    EXPECT_EQ(j["controller"]["ki"][i].get<double>(), osc::params::kKi[i]);
    EXPECT_NEAR(j["start_pose"][i].get<double>(), osc::robot::kQStart[i] * 180 / osc::kPi, 1e-12);
  }
  EXPECT_EQ(j["controller"]["k_ad"].get<double>(), osc::params::kKad);
  EXPECT_EQ(j["trajectory"]["amplitude"].get<double>(), osc::params::kAmplitude);
  EXPECT_EQ(j["trajectory"]["period"].get<double>(), 5.0);
  EXPECT_EQ(j["plant"]["friction"]["preset"].get<std::string>(), "paper");
  EXPECT_EQ(j["plant"]["encoder_cpr"].get<double>(), osc::robot::kDrives.encoder_counts_per_motor_rev);
  EXPECT_TRUE(sim::differences_from_paper(s).empty());
}

TEST(Config, PrintedConfigurationReadsBackToTheSameSettings) {
  Settings s;
  std::string err;
  ASSERT_TRUE(apply(s,
                    "trajectory: {amplitude: 0.03, period: 2.5}\nplant:\n  friction: {preset: corke}\n"
                    "  delay: 0.0005\nrun: {modes: adaptive, scalar: float}\nstart_pose: [10, 40, -170, 5, 50, -5]\n",
                    err))
      << err;
  const std::string text = sim::config_yaml(s);
  Settings back;
  ASSERT_TRUE(apply(back, text, err)) << err << "\n" << text;
  EXPECT_EQ(sim::config_yaml(back), text);
  EXPECT_EQ(back.base.gains.trajectory.amplitude, 0.03);
  EXPECT_EQ(back.base.gains.trajectory.period_ticks, 2500u);
  EXPECT_STREQ(back.base.plant.friction.name, "corke");
  EXPECT_EQ(back.base.plant.compute_delay, 0.0005);
  EXPECT_TRUE(back.run_adaptive);
  EXPECT_FALSE(back.run_none);
  EXPECT_EQ(back.base.scalar, sim::Scalar::kFloat);
  EXPECT_NEAR(back.base.q_start(2), -170 * osc::kPi / 180, 1e-15);
  // The printed defaults read back as the headers' values exactly (degrees to radians included).
  Settings d;
  ASSERT_TRUE(apply(d, sim::config_yaml(Settings{}), err)) << err;
  for (int i = 0; i < 6; ++i) EXPECT_EQ(d.base.q_start(i), osc::robot::kQStart[i]);
  EXPECT_EQ(d.base.gains.trajectory.omega, osc::params::kOmega);
  EXPECT_TRUE(sim::differences_from_paper(d).empty());
}

TEST(Config, BadKeysAndValuesAreErrorsThatNameTheKey) {
  struct Case {
    const char* yaml;
    const char* expect;  // in the message
  } cases[] = {
      {"trajectory: {amplitud: 0.1}", "unknown key 'trajectory.amplitud'"},
      {"trajectorie: {amplitude: 0.1}", "unknown key 'trajectorie'"},
      {"trajectory: {amplitude: 0.5}", "trajectory.amplitude: 0.5 is out of range [0, 0.2]"},
      {"trajectory: {amplitude: fast}", "trajectory.amplitude: expected a number, got 'fast'"},
      {"trajectory: {period: 5.0005}", "trajectory.period: 5.0005 s is not a whole number of samples"},
      {"run: {duration: .nan}", "run.duration: expected a number"},
      {"run: {duration: 0}", "run.duration: 0 is out of range [1, 86400]"},
      {"run: {modes: sideways}", "run.modes: expected both, adaptive or none, got 'sideways'"},
      {"controller: {knd: [1, 2, 3]}", "controller.knd: expected a list of 6 numbers"},
      {"controller: {ki: [1, 2, 3, 4, 5, -6]}", "controller.ki[6]: -6 is out of range"},
      {"start_pose: [0, 45, -180, 0, 120, 0]", "start_pose[5]: 120 is out of range [-100, 100]"},
      {"plant: {friction: heavy}", "unknown key 'plant.friction'"},
      {"[1, 2]", "expected a mapping"},
      {"run: {duration: 30", "not valid YAML"},
  };
  for (const Case& c : cases) {
    Settings s;
    std::string err;
    EXPECT_FALSE(apply(s, c.yaml, err)) << c.yaml;
    EXPECT_NE(err.find(c.expect), std::string::npos) << c.yaml << " -> " << err;
    EXPECT_EQ(err.rfind("test.yaml: ", 0), 0u) << err;  // the file is named
  }
}

TEST(Config, SettingACoefficientMakesTheFrictionCustomAndAPresetResetsIt) {
  Settings s;
  std::string err;
  ASSERT_TRUE(sim::apply_setting("plant.friction.vis=[1, 2, 3, 0.1, 0.2, 0.3]", s, err)) << err;
  EXPECT_STREQ(s.base.plant.friction.name, "custom");
  EXPECT_EQ(s.base.plant.friction.vis[1], 2.0);
  EXPECT_EQ(s.base.plant.friction.cou[0], osc::robot::kFrictionPaper.cou[0]);  // the rest kept
  // Custom coefficients are printed, and read back.
  const std::string text = sim::config_yaml(s);
  EXPECT_NE(text.find("vis: [1, 2, 3, 0.1, 0.2, 0.3]"), std::string::npos) << text;
  Settings back;
  ASSERT_TRUE(apply(back, text, err)) << err;
  EXPECT_EQ(sim::config_yaml(back), text);
  ASSERT_TRUE(sim::apply_setting("plant.friction.preset=none", s, err)) << err;
  EXPECT_STREQ(s.base.plant.friction.name, "none");
  EXPECT_EQ(s.base.plant.friction.vis[1], 0.0);
}

TEST(Config, DifferencesFromThePaperListTheSetUpKeysOnly) {
  Settings s;
  std::string err;
  ASSERT_TRUE(sim::apply_setting("run.scalar=float", s, err));
  ASSERT_TRUE(sim::apply_setting("run.modes=adaptive", s, err));
  EXPECT_TRUE(sim::differences_from_paper(s).empty());  // arithmetic and modes are not the set-up
  ASSERT_TRUE(sim::apply_setting("trajectory.amplitude=0.1", s, err));
  ASSERT_TRUE(sim::apply_setting("controller.k_ad=250", s, err));
  const auto d = sim::differences_from_paper(s);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0], "controller.k_ad");
  EXPECT_EQ(d[1], "trajectory.amplitude");
}

TEST(Config, EveryScalarIsANameOfRunScalarAndReadsBack) {
  for (int i = 0; i < static_cast<int>(std::size(sim::kScalarNames)); ++i) {
    Settings s;
    std::string err;
    ASSERT_TRUE(sim::apply_setting(std::string("run.scalar=") + sim::kScalarNames[i], s, err)) << err;
    EXPECT_EQ(static_cast<int>(s.base.scalar), i);
    EXPECT_NE(sim::config_yaml(s).find(std::string("scalar: ") + sim::kScalarNames[i]), std::string::npos);
  }
  Settings s;
  std::string err;
  EXPECT_FALSE(sim::apply_setting("run.scalar=q15", s, err));
  EXPECT_NE(err.find("fixed"), std::string::npos) << err;  // the message lists the names
}

TEST(Config, CommandLineAppliesFileThenOptionsThenSet) {
  char prog[] = "puma_experiment", a1[] = "--duration=30", a2[] = "--set", a3[] = "run.duration=40", a4[] = "--mode",
       a5[] = "none";
  char* argv[] = {prog, a1, a2, a3, a4, a5};
  sim::ExperimentOptions o;
  std::string err;
  ASSERT_TRUE(sim::parse_experiment_args(6, argv, o, err)) << err;
  EXPECT_EQ(o.base.duration, 40.0);
  EXPECT_FALSE(o.run_adaptive);
  char b1[] = "--duration", b2[] = "0";
  char* bad[] = {prog, b1, b2};
  sim::ExperimentOptions o2;
  EXPECT_FALSE(sim::parse_experiment_args(3, bad, o2, err));
  EXPECT_EQ(err, "--duration: 0 is out of range [1, 86400] (run.duration)");
  // The firmware image compiles in its gains and trajectory: --qemu refuses to pretend otherwise.
  char c1[] = "--qemu", c2[] = "--set", c3[] = "trajectory.amplitude=0.1";
  char* q[] = {prog, c1, c2, c3};
  sim::ExperimentOptions o3;
  EXPECT_FALSE(sim::parse_experiment_args(4, q, o3, err));
  EXPECT_NE(err.find("trajectory.amplitude applies to the host-built controller only"), std::string::npos) << err;
}

// The plant's preset sets every feature; a feature set after it is a difference from the preset,
// named in the outputs; the printed configuration reads back to the same plant.
TEST(Config, PlantPresetSetsEveryFeatureAndDifferencesAreNamed) {
  Settings s;
  std::string err;
  EXPECT_EQ(sim::config_json(s)["plant"]["preset"].get<std::string>(), "ideal");
  EXPECT_TRUE(sim::differences_from_preset(s).empty());
  ASSERT_TRUE(sim::apply_setting("plant.preset=realistic", s, err)) << err;
  EXPECT_TRUE(s.base.published_encoders);
  EXPECT_TRUE(s.base.plant.coupling);
  ASSERT_NE(s.base.plant.motor_inertia, nullptr);
  EXPECT_STREQ(s.base.plant.motor_inertia->name, "akb86");
  EXPECT_GT(s.base.plant.amp_lag, 0.2e-3);
  EXPECT_LT(s.base.plant.amp_lag, 0.5e-3);
  EXPECT_GE(s.base.plant.elastic_hz, 15);
  EXPECT_LE(s.base.plant.elastic_hz, 25);
  EXPECT_GE(s.base.plant.backlash, 0.1e-3);
  EXPECT_LE(s.base.plant.backlash, 1e-3);
  EXPECT_GT(s.base.sensors.pot_noise, 0);
  EXPECT_TRUE(sim::differences_from_preset(s).empty());
  // The plant models the paper's robot: it leaves the paper's set-up (and its tables) comparable.
  EXPECT_TRUE(sim::differences_from_paper(s).empty());
  // The encoders of plant and controller: the arm's own, coupled.
  const osc::EncoderMap m = s.base.encoder_map();
  EXPECT_EQ(m.coupling_terms, 3);
  EXPECT_EQ(m.counts_per_rad[1], osc::robot::kDriveTrain.encoders.counts_per_rad[1]);
  // One feature changed: named as a difference from the preset.
  ASSERT_TRUE(sim::apply_setting("plant.elastic_hz=12", s, err)) << err;
  EXPECT_EQ(sim::differences_from_preset(s), std::vector<std::string>{"plant.elastic_hz"});
  const std::string text = sim::config_yaml(s);
  Settings back;
  ASSERT_TRUE(sim::apply_config(text, "printed", back, err)) << err;
  EXPECT_EQ(sim::config_yaml(back), text);
  EXPECT_EQ(back.base.plant.elastic_hz, 12);
  EXPECT_EQ(sim::differences_from_preset(back), std::vector<std::string>{"plant.elastic_hz"});
  // Back to ideal: every feature off again, the paper's plant bit for bit.
  ASSERT_TRUE(sim::apply_setting("plant.preset=ideal", s, err)) << err;
  EXPECT_EQ(sim::config_yaml(s), sim::config_yaml(Settings{}));
  // A bad preset or feature value is an error naming the key.
  EXPECT_FALSE(sim::apply_setting("plant.preset=real", s, err));
  EXPECT_NE(err.find("plant.preset: expected ideal or realistic"), std::string::npos) << err;
  EXPECT_FALSE(sim::apply_setting("plant.dac_bits=12.5", s, err));
  EXPECT_NE(err.find("plant.dac_bits: 12.5 is not a whole number"), std::string::npos) << err;
  EXPECT_FALSE(sim::apply_setting("plant.coupling=yes", s, err));
  EXPECT_NE(err.find("plant.coupling: expected off or on"), std::string::npos) << err;
}

TEST(Config, PlantOptionsOnTheCommandLine) {
  char prog[] = "puma_experiment", a1[] = "--plant", a2[] = "realistic", a3[] = "--plant-set", a4[] = "backlash=0",
       a5[] = "--plant-set", a6[] = "coupling=off";
  char* argv[] = {prog, a1, a2, a3, a4, a5, a6};
  sim::ExperimentOptions o;
  std::string err;
  ASSERT_TRUE(sim::parse_experiment_args(7, argv, o, err)) << err;
  EXPECT_EQ(o.plant_preset, "realistic");
  EXPECT_EQ(o.base.plant.backlash, 0.0);
  EXPECT_FALSE(o.base.plant.coupling);
  EXPECT_EQ(sim::differences_from_preset(o), (std::vector<std::string>{"plant.coupling", "plant.backlash"}));
  char b1[] = "--plant-set", b2[] = "nothing=1";
  char* bad[] = {prog, b1, b2};
  sim::ExperimentOptions o2;
  EXPECT_FALSE(sim::parse_experiment_args(3, bad, o2, err));
  EXPECT_EQ(err, "--plant-set: unknown key 'plant.nothing' (--print-config lists the keys)");
  // The image in QEMU reads its encoders as uniform and uncoupled: the arm's own are refused.
  char c1[] = "--qemu";
  char* q[] = {prog, c1, a1, a2};
  sim::ExperimentOptions o3;
  EXPECT_FALSE(sim::parse_experiment_args(4, q, o3, err));
  EXPECT_NE(err.find("plant.coupling applies to the host-built controller only"), std::string::npos) << err;
}

// --pil-link names the transport to the image in QEMU; semihosting unless it says uart.
TEST(Config, PilLinkIsSemihostingOrUartAndNeedsQemu) {
  char prog[] = "puma_experiment", q[] = "--qemu", l[] = "--pil-link", uart[] = "uart", spi[] = "spi";
  std::string err;
  sim::ExperimentOptions o;
  char* plain[] = {prog, q};
  ASSERT_TRUE(sim::parse_experiment_args(2, plain, o, err)) << err;
  EXPECT_EQ(o.pil_link, sim::PilLink::kSemihosting);
  sim::ExperimentOptions o2;
  char* by_uart[] = {prog, q, l, uart};
  ASSERT_TRUE(sim::parse_experiment_args(4, by_uart, o2, err)) << err;
  EXPECT_EQ(o2.pil_link, sim::PilLink::kUart);
  sim::ExperimentOptions o3;
  char* unknown[] = {prog, q, l, spi};
  EXPECT_FALSE(sim::parse_experiment_args(4, unknown, o3, err));
  EXPECT_EQ(err, "--pil-link: 'spi' is not a link: semihosting | uart");
  sim::ExperimentOptions o4;
  char* without_qemu[] = {prog, l, uart};
  EXPECT_FALSE(sim::parse_experiment_args(3, without_qemu, o4, err));
  EXPECT_EQ(err, "--pil-link applies with --qemu only");
}

TEST(Config, StartPoseAtASingularityIsRefused) {
  Settings s;
  std::string err;
  ASSERT_TRUE(sim::apply_setting("start_pose=[0, 45, -180, 0, 0, 0]", s, err)) << err;  // q5 = 0: wrist singular
  EXPECT_FALSE(sim::validate_settings(s, err));
  EXPECT_NE(err.find("start_pose: too close to a singularity"), std::string::npos) << err;
}

// Gains each within its range that together lose the sampled loop (issue 53, defect 4): refused
// before the run, by name, as the board's param set refuses them.
TEST(Config, GainsThatLoseTheSampledLoopAreRefused) {
  Settings s;
  std::string err;
  ASSERT_TRUE(sim::apply_setting("controller.knd=[120, 120, 120, 100, 100, 100]", s, err)) << err;
  EXPECT_TRUE(sim::validate_settings(s, err)) << err;
  ASSERT_TRUE(sim::apply_setting("controller.ks=[97, 97, 97, 100, 100, 100]", s, err)) << err;
  EXPECT_FALSE(sim::validate_settings(s, err));
  EXPECT_NE(err.find("controller: the gains would make the sampled loop unstable at the start pose"), std::string::npos)
      << err;
}

// The configured values reach the run: the trajectory's amplitude and the start pose change what
// the robot does, not only what is printed.
TEST(Config, ConfiguredTrajectoryAndStartPoseReachTheRun) {
  auto run = [](const std::string& set) {
    Settings s;
    std::string err;
    if (!set.empty()) {
      EXPECT_TRUE(sim::apply_setting(set, s, err)) << err;
    }
    sim::ExperimentConfig c = s.base;
    c.duration = 6;                     // the envelope has risen to 1 - exp(-10.8)
    c.mode = osc::FrictionMode::kNone;  // paper friction, uncompensated: errors grow with the motion
    return sim::run_experiment(c);
  };
  const sim::ExperimentResult paper = run("");
  const sim::ExperimentResult still = run("trajectory.amplitude=0");
  const sim::ExperimentResult big = run("trajectory.amplitude=0.1");
  EXPECT_EQ(paper.status, 0u);
  EXPECT_EQ(still.status, 0u);
  EXPECT_EQ(big.status, 0u);
  // Holding still at the start pose: static friction and the encoder quantisation only.
  EXPECT_LT(still.max_error[0], 0.2 * paper.max_error[0]);
  EXPECT_GT(big.max_error[0], 1.05 * paper.max_error[0]);  // twice as fast: more viscous friction
  const sim::ExperimentResult moved = run("start_pose=[20, 40, -170, 10, 50, 10]");
  EXPECT_EQ(moved.status, 0u);
  EXPECT_NE(moved.max_error[0], paper.max_error[0]);
}

TEST(Summary, JsonWrittenByTheRunnerReadsBackWithEveryRunOnceAndTheFault) {
  Settings s;
  std::string err;
  ASSERT_TRUE(sim::apply_setting("trajectory.amplitude=0.1", s, err));
  sim::ExperimentConfig c = s.base;
  c.duration = 2;
  c.injection.enabled = true;
  c.injection.kind = sim::InjectionKind::kEncoderGarbage;
  c.injection.joint = 2;
  c.injection.at = 1.0;
  std::vector<sim::ExperimentResult> runs{sim::run_experiment(c)};
  sim::Provenance prov;
  prov.revision = sim::git_revision();
  prov.config_text = sim::config_yaml(s);
  prov.config_hash = sim::text_hash(prov.config_text);
  prov.differs = sim::differences_from_paper(s);
  const std::string text = sim::summary_json(runs, s, prov, true).dump(2);
  const sim::json j = sim::json::parse(text);
  EXPECT_EQ(j["config"]["trajectory"]["amplitude"].get<double>(), 0.1);
  EXPECT_FALSE(j["paper_setup"].get<bool>());
  EXPECT_EQ(j["differs_from_paper"][0].get<std::string>(), "trajectory.amplitude");
  EXPECT_EQ(j["config_hash"].get<std::string>().size(), 16u);
  EXPECT_FALSE(j.contains("mode"));  // the top level does not repeat a run
  ASSERT_EQ(j["runs"].size(), 1u);
  const auto& r = j["runs"][0];
  EXPECT_EQ(r["timeseries"].get<std::string>(), "timeseries_adaptive.csv");
  ASSERT_TRUE(r["fault"].is_object());
  EXPECT_EQ(r["fault"]["tick"].get<long>(), 1000);
  EXPECT_DOUBLE_EQ(r["fault"]["time_s"].get<double>(), 1.0);
  EXPECT_EQ(r["fault"]["q_rad"].size(), 6u);
  EXPECT_EQ(r["stats_until_s"].get<double>(), 1.0);
  EXPECT_EQ(r["injection"]["kind"].get<std::string>(), "encoder-garbage");
  // The CSV names its columns by joint and coefficient and carries the provenance.
  const std::string csv = sim::csv_text(runs[0], prov);
  EXPECT_EQ(csv.rfind("# puma_experiment ", 0), 0u);
  EXPECT_NE(csv.find(prov.config_hash), std::string::npos);
  EXPECT_NE(csv.find(",theta_vis_j1,"), std::string::npos);
  EXPECT_NE(csv.find(",xdt_phz_deg_s,"), std::string::npos);
}

}  // namespace
