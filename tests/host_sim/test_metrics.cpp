// The run's metrics (host_sim/metrics.hpp), each fed known samples: window maxima, the final window,
// the friction rms, the fault snapshot, the frozen estimates, the injection's detection, the JSON.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "experiment.hpp"

namespace {

using sim::ExperimentConfig;
using sim::Sample;

constexpr double kDt = osc::params::kDt;

/// Sample k with e = (err, -err, 0, 0, 0, 0) and every theta^ = theta; the last window from sample `last`.
Sample sample(long k, double err, double theta = 0, long last = 0) {
  Sample s;
  s.k = k;
  s.t = k * kDt;
  s.last = k >= last;
  s.e[0] = err;
  s.e[1] = -err;
  for (double& th : s.rep.theta_hat) th = theta;
  return s;
}

TEST(Metrics, WindowMaximaStartAWindowEveryWindowTicks) {
  ExperimentConfig cfg;
  cfg.window = 3 * kDt;  // windows [0, 3), [3, 6), [6, 7) in samples
  sim::WindowMaxima m;
  m.begin(cfg);
  const double err[7] = {1, 5, 2, 3, -7, 0, 4};
  for (long k = 0; k < 7; ++k) m.observe(sample(k, err[k], 0.1 * k));
  ASSERT_EQ(m.window_max.size(), 3u);
  EXPECT_EQ(m.window_max[0][0], 5);
  EXPECT_EQ(m.window_max[1][0], 7);  // |e|
  EXPECT_EQ(m.window_max[1][1], 7);
  EXPECT_EQ(m.window_max[2][0], 4);
  EXPECT_EQ(m.window_max[2][3], 0);
  ASSERT_EQ(m.window_theta_range.size(), 3u);
  EXPECT_DOUBLE_EQ(m.window_theta_range[1][0], 0.3);
  EXPECT_DOUBLE_EQ(m.window_theta_range[1][1], 0.5);
}

TEST(Metrics, TrackingMaximaCountTheLastWindowAloneAndNothingAfterAFault) {
  ExperimentConfig cfg;
  cfg.duration = 10 * kDt;
  cfg.final_window = 4 * kDt;
  sim::TrackingMaxima m;
  m.begin(cfg);
  EXPECT_DOUBLE_EQ(m.final_window, 4 * kDt);
  for (long k = 0; k < 10; ++k) {
    Sample s = sample(k, k < 6 ? 9.5 : 1.0 + k, 0, 6);  // large before the last window, 7..10 in it
    s.counting = k < 9;                                 // a fault at sample 9: its 10 is not counted
    m.observe(s);
  }
  EXPECT_EQ(m.max_error[0], 9.5);
  EXPECT_EQ(m.final_max_error[0], 9);  // samples 6, 7, 8: 7, 8, 9
  EXPECT_EQ(m.final_max_error[1], 9);
  EXPECT_EQ(m.final_max_error[2], 0);
  // A final window longer than the run is the whole run.
  cfg.final_window = 1.0;
  m.begin(cfg);
  EXPECT_DOUBLE_EQ(m.final_window, cfg.duration);
}

TEST(Metrics, ObserverMaximaCountTheLastWindowOfAnObservedRun) {
  sim::ObserverMaxima m;
  for (long k = 0; k < 4; ++k) {
    Sample s = sample(k, 0, 0, 2);
    s.rep.has_observer = true;
    s.x_tilde[2] = k < 2 ? -50.0 : -1.0 * k;  // |x~_z| 50 before the last window, 2 and 3 in it
    s.xd_tilde[5] = 0.5 * k;
    m.observe(s);
  }
  EXPECT_TRUE(m.has_observer);
  EXPECT_EQ(m.max_observer_error[2], 3);
  EXPECT_EQ(m.max_observer_velocity_error[5], 1.5);
  sim::ObserverMaxima remote;  // over the link: NaN errors, not counted
  Sample s = sample(0, 0, 0, 0);
  s.x_tilde[0] = std::nan("");
  remote.observe(s);
  EXPECT_FALSE(remote.has_observer);
  EXPECT_EQ(remote.max_observer_error[0], 0);
}

TEST(Metrics, FrictionRmsIsTheRmsOverTheLastWindowsJointSamples) {
  sim::FrictionRms m;
  for (long k = 0; k < 3; ++k) {
    Sample s = sample(k, 0, 0, 1);                  // the last window: samples 1 and 2
    s.tau_f.setConstant(k == 0 ? 100.0 : 2.0 * k);  // sample 0 is outside the window
    s.rep.tau_f_hat[0] = 3.0;                       // error 3 - 2k on joint 1, -2k on the others
    m.observe(s);
  }
  m.end();
  // Errors: sample 1: 1, -2 x5; sample 2: -1, -4 x5. Friction: 2 x6, 4 x6.
  const double err2 = (1 + 5 * 4) + (1 + 5 * 16), fr2 = 6 * 4 + 6 * 16;
  EXPECT_NEAR(m.friction_rms_error, std::sqrt(err2 / 12), 1e-12);
  EXPECT_NEAR(m.friction_rms, std::sqrt(fr2 / 12), 1e-12);
}

TEST(Metrics, FaultSnapshotKeepsTheFirstFaultOnly) {
  sim::FaultSnapshot m;
  for (long k = 0; k < 6; ++k) {
    Sample s = sample(k, 0.5 * k);
    s.rep.faults = k < 2 ? 0u : k == 2 ? std::uint32_t{osc::kFaultTracking} : std::uint32_t{osc::kFaultEncoderRange};
    s.counting = k < 2;
    s.tau_before.setConstant(10.0 * k);
    s.q.setConstant(k);
    m.observe(s);
  }
  EXPECT_EQ(m.status, osc::kFaultTracking);
  EXPECT_DOUBLE_EQ(m.fault_time, 2 * kDt);
  EXPECT_EQ(m.fault.tick, 2);
  EXPECT_EQ(m.fault.faults, osc::kFaultTracking);
  EXPECT_EQ(m.fault.q[3], 2);
  EXPECT_EQ(m.fault.tau[0], 20);  // the torque of the sample before
  EXPECT_EQ(m.fault.e[0], 1.0);
  EXPECT_DOUBLE_EQ(m.stats_until, 2 * kDt);  // samples 0 and 1
}

TEST(Metrics, FrictionEstimatesStopAtTheFaultsTick) {
  ExperimentConfig cfg;
  sim::FrictionEstimates m;
  m.begin(cfg);
  EXPECT_EQ(m.theta_true[6], cfg.plant.friction.cou[0]);
  const double theta[5] = {2, 1, 3, 7, 8};  // the fault at sample 3
  for (long k = 0; k < 5; ++k) {
    Sample s = sample(k, 0, theta[k]);
    s.counting = k < 3;
    m.observe(s);
  }
  EXPECT_EQ(m.theta_hat[17], 7);  // the estimate of the fault's tick
  EXPECT_EQ(m.theta_min_seen[0], 1);
  EXPECT_EQ(m.theta_max_seen[0], 3);  // counted before the fault only
}

TEST(Metrics, InjectionTrackingTimesDetectionAndZeroTorque) {
  ExperimentConfig cfg;
  cfg.injection.enabled = true;
  sim::InjectionTracking m;
  m.begin(cfg);
  for (long k = 0; k < 6; ++k) {
    Sample s = sample(k, 3.0);  // |p - p_d| = 3 sqrt(2) mm
    s.injection_active = k >= 1;
    s.rep.faults = k >= 2 ? std::uint32_t{osc::kFaultEncoderStuck} : 0u;
    s.tau.setConstant(k >= 4 ? 0.0 : 1.0 + k);
    s.tau(4) = k == 3 ? -9.0 : s.tau(4);
    m.observe(s);
  }
  const sim::InjectionResult& r = m.injection;
  EXPECT_DOUBLE_EQ(r.detected, 2 * kDt);
  EXPECT_EQ(r.faults, osc::kFaultEncoderStuck);
  EXPECT_DOUBLE_EQ(r.zero_torque, 4 * kDt);
  EXPECT_DOUBLE_EQ(r.excursion_mm, 3 * std::sqrt(2.0));
  EXPECT_EQ(r.max_torque_after, 9);
  EXPECT_EQ(r.max_torque_joint, 4);
}

TEST(Metrics, ResultWritesItsMetricsJsonInTheListsOrder) {
  sim::ExperimentResult r;
  r.max_error[4] = 0.25;
  r.window_max.push_back({1, 2, 3, 4, 5, 6});
  sim::Json j;
  r.each([&j](const auto& metric) {
    if constexpr (requires { metric.to_json(j); }) metric.to_json(j);
  });
  std::vector<std::string> keys;
  for (const auto& kv : j.items()) keys.push_back(kv.key());
  ASSERT_GE(keys.size(), 4u);
  EXPECT_EQ(keys[0], "stats_until_s");  // FaultSnapshot first
  EXPECT_EQ(keys.back(), "plant_evaluations");
  EXPECT_EQ(j["max_error_deg"][1], 0.25);
  EXPECT_EQ(j["window_max_error"][0][5], 6);
  EXPECT_FALSE(j.contains("injection"));  // none injected
  EXPECT_FALSE(j.contains("link"));       // not a PIL run
}

}  // namespace
