#include "experiment.hpp"

#include <chrono>
#include <cmath>
#include <memory>

#include "osc/control_task.hpp"
#include "plant_hal.hpp"

namespace sim {

const double kPaperTable1[6] = {0.38, 0.44, 0.28, 0.06, 0.04, 0.06};
const double kPaperTable3[6] = {1.84, 1.58, 1.30, 0.11, 0.09, 0.19};

namespace {

constexpr double kRadToDeg = 180.0 / osc::puma560::kPi;

template <class S>
ExperimentResult run(const ExperimentConfig& cfg) {
  const auto wall0 = std::chrono::steady_clock::now();
  ExperimentResult res;
  res.mode = cfg.mode == osc::FrictionMode::kAdaptive ? "adaptive" : "none";
  res.duration = cfg.duration;
  res.friction_preset = cfg.plant.friction.name;

  Vec6 q0;
  for (int i = 0; i < 6; ++i) q0(i) = osc::params::kQStart[i];
  Plant plant(cfg.plant);
  plant.reset(q0);
  PlantHal hal(plant, q0);

  // The firmware's control task, in the chosen scalar, with the (possibly perturbed) model.
  auto task_ptr = std::make_unique<osc::ControlTask<S>>();  // large: keep off the stack
  osc::ControlTask<S>& task = *task_ptr;
  task.init(osc::Model<S>::puma560(cfg.model_error), osc::Gains<S>::paper(), cfg.mode, q0.cast<S>());
  // Optional observer start error, with y(0) = -k x~(0) as (21) prescribes.
  for (int i = 0; i < 6; ++i) {
    task.state.x_hat(i) += static_cast<S>(cfg.observer_offset[i]);
    task.state.y(i) += task.gains.k(i) * static_cast<S>(cfg.observer_offset[i]);
  }

  // Ground truth for the error statistics: the plant's own state through double kinematics.
  const osc::Model<double> truth = osc::Model<double>::puma560();
  osc::Data<double> tdata;
  osc::forward_kinematics(truth, tdata, q0);
  const Vec3 p0 = tdata.o[6];
  const Mat3 R_ref = tdata.R[6];

  for (int i = 0; i < 6; ++i) {
    res.theta_true[i] = cfg.plant.friction.vis[i];
    res.theta_true[6 + i] = cfg.plant.friction.cou[i];
    res.theta_true[12 + i] = cfg.plant.friction.sti[i];
  }

  const double dt = osc::params::kDt;
  const long n = std::lround(cfg.duration / dt);
  const long log_every = std::max(1L, std::lround(cfg.log_period / dt));
  const double t_final = cfg.duration - cfg.final_window;
  double fr_err2 = 0, fr2 = 0;
  long fr_n = 0;
  Vec6 tau_old = Vec6::Zero();
  const long progress_every = std::max(1L, n / 100);
  for (long k = 0; k < n; ++k) {
    const double t = k * dt;
    // Errors of the true plant at the sample instant.
    osc::forward_kinematics(truth, tdata, plant.q());
    const osc::Desired<double> d = osc::trajectory(p0, t);
    const Vec3 phi = osc::orientation_coordinates(tdata.R[6], R_ref);
    double e[6];
    for (int i = 0; i < 3; ++i) e[i] = (d.x(i) - tdata.o[6](i)) * 1e3;
    for (int i = 0; i < 3; ++i) e[3 + i] = -phi(i) * kRadToDeg;

    // The control task: encoders -> control step -> DAC codes.
    const std::uint32_t faults = osc::control_tick(task, hal);
    const osc::StepOutput<S>& out = task.last;
    if (faults != 0 && res.status == 0) res.status = faults;
    const Vec6 tau_new = hal.torque();

    for (int i = 0; i < 6; ++i) {
      res.max_error[i] = std::max(res.max_error[i], std::abs(e[i]));
      if (t >= t_final) {
        res.final_max_error[i] = std::max(res.final_max_error[i], std::abs(e[i]));
        const double xt = static_cast<double>(out.x_tilde(i)) * (i < 3 ? 1e3 : kRadToDeg);
        res.max_observer_error[i] = std::max(res.max_observer_error[i], std::abs(xt));
      }
    }
    const Vec6 tau_f = plant.friction(plant.qd());
    if (t >= t_final) {
      for (int i = 0; i < 6; ++i) {
        const double df = static_cast<double>(out.tau_f_hat(i)) - tau_f(i);
        fr_err2 += df * df;
        fr2 += tau_f(i) * tau_f(i);
      }
      ++fr_n;
    }
    if (k % log_every == 0) {
      LogRow r;
      r.t = t;
      for (int i = 0; i < 6; ++i) {
        r.e[i] = e[i];
        r.x_tilde[i] = static_cast<double>(out.x_tilde(i)) * (i < 3 ? 1e3 : kRadToDeg);
        r.tau_f[i] = tau_f(i);
        r.tau_f_hat[i] = static_cast<double>(out.tau_f_hat(i));
      }
      for (int i = 0; i < 18; ++i) r.theta_hat[i] = static_cast<double>(task.state.theta_hat(i));
      res.log.push_back(r);
    }
    plant.advance_sample(tau_old, tau_new, dt);
    tau_old = tau_new;
    if (cfg.progress && k % progress_every == 0) cfg.progress(static_cast<double>(k) / n);
  }
  for (int i = 0; i < 18; ++i) res.theta_hat[i] = static_cast<double>(task.state.theta_hat(i));
  if (fr_n > 0) {
    res.friction_rms_error = std::sqrt(fr_err2 / (6.0 * fr_n));
    res.friction_rms = std::sqrt(fr2 / (6.0 * fr_n));
  }
  if (cfg.progress) cfg.progress(1.0);
  res.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return res;
}

}  // namespace

ExperimentResult run_experiment(const ExperimentConfig& cfg) {
  return cfg.scalar == Scalar::kFloat ? run<float>(cfg) : run<double>(cfg);
}

}  // namespace sim
