#include "experiment.hpp"

#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <memory>

#include "osc/runtime/control_task.hpp"
#include "pil_client.hpp"
#include "plant_hal.hpp"

namespace sim {

const double kPaperTable1[6] = {0.38, 0.44, 0.28, 0.06, 0.04, 0.06};
const double kPaperTable3[6] = {1.84, 1.58, 1.30, 0.11, 0.09, 0.19};

namespace {

constexpr double kRadToDeg = 180.0 / osc::kPi;

/// What the controller reports back each tick.
struct TickReport {
  std::uint32_t faults = 0;
  bool has_observer = false;  // x_tilde is available (in-process controller only)
  double x_tilde[6] = {};
  double xd_hat[6] = {};  // the observer's velocity estimate: m/s, rad/s (in-process only)
  double tau_f_hat[6] = {};
  double theta_hat[18] = {};
};

/// The host-built controller: the firmware's control task, in process.
template <class S>
class LocalController {
 public:
  explicit LocalController(const ExperimentConfig& cfg, const Vec6& q0) : task_(new osc::ControlTask<S>) {
    task_->init(osc::Model<S>::of(osc::robot::kArm, cfg.model_error), cfg.gains.template cast<S>(), cfg.mode,
                q0.cast<S>(), PlantHal::kPeriodNs);
    task_->set_encoder_resolution(cfg.encoder_counts_per_motor_rev);
    // Optional observer start error, with y(0) = -k x~(0) as (21) prescribes.
    for (int i = 0; i < 6; ++i) {
      task_->state.obs.x_hat(i) += static_cast<S>(cfg.observer_offset[i]);
      task_->state.obs.y(i) += task_->gains.k(i) * static_cast<S>(cfg.observer_offset[i]);
    }
  }
  bool tick(PlantHal& hal, TickReport& r, std::string&) {
    r.faults = osc::control_tick(*task_, hal);
    const osc::StepOutput<S>& out = task_->last;
    r.has_observer = true;
    for (int i = 0; i < 6; ++i) {
      r.x_tilde[i] = static_cast<double>(out.x_tilde(i));
      r.xd_hat[i] = static_cast<double>(out.xd_hat(i));
      r.tau_f_hat[i] = static_cast<double>(out.tau_f_hat(i));
    }
    for (int i = 0; i < 18; ++i) r.theta_hat[i] = static_cast<double>(task_->state.adapt.theta_hat(i));
    return true;
  }
  void skip_ticks(std::uint64_t n) { task_->tick += n; }
  void finish(ExperimentResult& res) {
    for (int i = 0; i < 6; ++i) res.stuck_peak[i] = static_cast<double>(task_->stuck.peak(i));
    for (int i = 0; i < 6; ++i) res.stuck_dtau_peak[i] = static_cast<double>(task_->stuck.dtau_peak(i));
    for (int i = 0; i < 6; ++i) res.stuck_dtau_silent_peak[i] = static_cast<double>(task_->stuck.dtau_gated_peak(i));
  }

 private:
  std::unique_ptr<osc::ControlTask<S>> task_;  // large: keep off the stack
};

/// The firmware image (or any PIL peer) over the link, one exchange per tick.
class RemoteController {
 public:
  RemoteController(const ExperimentConfig& cfg, std::string& err)
      : timeout_(cfg.pil_timeout),
        config_(static_cast<std::uint8_t>((cfg.mode == osc::FrictionMode::kNone ? pil::kConfigNoCompensation : 0) |
                                          pil::config_adaptation(cfg.gains.adaptation))) {
    ok_ = link_.start(cfg.pil_command, err);
  }
  bool ok() const { return ok_; }
  /// One exchange. The simulated amplifiers apply the codes of a valid, in-range answer to this
  /// tick's sensor frame, and zero on anything else (counted, the first such error kept); a lost
  /// link (no answer in time, the peer gone) also ends the run.
  bool tick(PlantHal& hal, TickReport& r, std::string& err) {
    pil::SensorFrame s;
    s.seq = seq_++;
    hal.read_encoders(s.counts);
    if (s.seq == 0) s.inject = config_;
    pil::ActuatorFrame a = last_;
    std::string why;
    const PilClient::Exchange x = link_.exchange(s, a, timeout_, why);
    hal.write_dacs(a.codes);
    if (x == PilClient::Exchange::kLost) return err = why, false;
    if (x == PilClient::Exchange::kZeroed) {
      ++zeroed_ticks_;
      if (first_zeroed_.empty()) first_zeroed_ = "tick " + std::to_string(s.seq) + ": " + why;
    }
    last_ = a;
    r.faults = a.faults;
    for (int i = 0; i < 6; ++i) r.tau_f_hat[i] = a.tau_f_hat[i];
    for (int i = 0; i < 18; ++i) r.theta_hat[i] = a.theta_hat[i];
    return true;
  }
  void finish(ExperimentResult& res) {
    res.max_step_cycles = last_.max_cycles;
    res.mean_step_cycles = last_.mean_cycles;
    res.max_tick_cycles = last_.tick_max_cycles;
    res.stack_used = last_.stack_used;
    res.link.firmware = last_.link;
    res.link.host = link_.link_counters();
    res.link.host_code_range = link_.code_range_errors();
    res.link.zeroed_ticks = zeroed_ticks_;
    res.link.first_zeroed = first_zeroed_;
    res.link.rx_gap_max = last_.rx_gap_max;
    res.link.rx_long_gaps = last_.rx_long_gaps;
    link_.stop();
  }

 private:
  PilClient link_;
  double timeout_;
  std::uint8_t config_;  // configuration bits of the first sensor frame
  bool ok_ = false;
  std::uint32_t seq_ = 0;
  pil::ActuatorFrame last_;
  std::uint32_t zeroed_ticks_ = 0;
  std::string first_zeroed_;
};

template <class Controller>
void run(const ExperimentConfig& cfg, const Vec6& q0, Controller& ctrl, ExperimentResult& res) {
  Plant plant(cfg.plant);
  plant.reset(q0);
  PlantHal hal(plant, q0, cfg.encoder_counts_per_motor_rev, cfg.injection);
  InjectionResult& ir = res.injection;
  ir.injection = cfg.injection;

  // Ground truth for the error statistics: the plant's own state through double kinematics.
  const osc::Model<double> truth = osc::Model<double>::of(osc::robot::kArm);
  osc::Data<double> tdata;
  osc::forward_kinematics(truth, tdata, q0);
  const Vec3 p0 = tdata.o[6];
  const Mat3 R_ref = tdata.R[6];

  const double dt = osc::params::kDt;
  const long n = std::lround(cfg.duration / dt);
  const long log_every = std::max(1L, std::lround(cfg.log_period / dt));
  const double t_final = cfg.duration - cfg.final_window;
  double fr_err2 = 0, fr2 = 0;
  long fr_n = 0;
  Vec6 tau_old = Vec6::Zero();
  const long progress_every = std::max(1L, n / 100);
  const long jump_tick = cfg.jump_at >= 0 ? std::lround(cfg.jump_at / dt) : -1;
  const long window_ticks = std::max(1L, std::lround(cfg.window / dt));
  res.window = cfg.window;
  res.final_window = std::min(cfg.final_window, cfg.duration);
  TickReport rep;
  for (long k = 0; k < n; ++k) {
    const double t = k * dt;
    const osc::TrajectorySpec<double>& spec = cfg.gains.trajectory;
    const double t_ref = osc::trajectory_time<double>(spec, static_cast<std::uint64_t>(k),
                                                      osc::params::kControlHz);  // as the controller
    // Errors of the true plant at the sample instant.
    osc::forward_kinematics(truth, tdata, plant.q());
    const osc::Desired<double> d = osc::trajectory(spec, p0, t_ref);
    const Vec3 phi = osc::orientation_coordinates(tdata.R[6], R_ref);
    double e[6];
    for (int i = 0; i < 3; ++i) e[i] = (d.x(i) - tdata.o[6](i)) * 1e3;
    for (int i = 0; i < 3; ++i) e[3 + i] = -phi(i) * kRadToDeg;

    if constexpr (requires { ctrl.skip_ticks(std::uint64_t{0}); }) {
      if (k == jump_tick) ctrl.skip_ticks(cfg.jump_ticks);
    }
    // The controller: encoders -> control step -> DAC codes.
    hal.begin_sample(t);
    if (!ctrl.tick(hal, rep, res.error)) {
      res.error = "tick " + std::to_string(k) + ": " + res.error;
      break;
    }
    if (rep.faults != 0 && res.status == 0) {
      res.status = rep.faults, res.fault_time = t;
      FaultState& fs = res.fault;
      fs.tick = k, fs.t = t, fs.faults = rep.faults;
      for (int i = 0; i < 6; ++i)
        fs.q[i] = plant.q()(i), fs.qd[i] = plant.qd()(i), fs.tau[i] = tau_old(i), fs.e[i] = e[i];
      for (int i = 0; i < 18; ++i) fs.theta_hat[i] = rep.theta_hat[i];
    }
    // Statistics stop at a fault: after it the amplifiers are off and the robot falls.
    const bool counting = res.status == 0;
    if (counting) res.stats_until = t + dt;
    const Vec6 tau_new = hal.torque();
    if (hal.injection_active()) {
      if (rep.faults != 0 && ir.detected < 0) ir.detected = t, ir.faults = rep.faults;
      if (ir.zero_torque < 0) {
        ir.excursion_mm = std::max(ir.excursion_mm, std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]));
        if ((tau_new.array() == 0.0).all()) ir.zero_torque = t;
      }
      if (ir.detected >= 0)
        for (int i = 0; i < 6; ++i)
          if (std::abs(tau_new(i)) > ir.max_torque_after)
            ir.max_torque_after = std::abs(tau_new(i)), ir.max_torque_joint = i;
    }

    double xt[6], xdt[6];
    // The observer's errors are known only for the in-process controller; over the link they are
    // not sent, and the time series leaves their columns out rather than showing zeros.
    res.has_observer = rep.has_observer;
    if (rep.has_observer) {
      // The true operational velocity: the analytic Jacobian of the plant's pose times its joint speeds.
      osc::geometric_jacobian(tdata);
      const Mat6 Ja = osc::analytic_jacobian(tdata.J, phi);
      const Vec6 xd_true = Ja * plant.qd();
      for (int i = 0; i < 6; ++i) {
        const double scale = i < 3 ? 1e3 : kRadToDeg;
        xt[i] = rep.x_tilde[i] * scale;
        xdt[i] = (rep.xd_hat[i] - xd_true(i)) * scale;
      }
    } else {
      for (int i = 0; i < 6; ++i) xt[i] = xdt[i] = std::numeric_limits<double>::quiet_NaN();
    }
    if (!counting) {
      // Only the time series goes on after a fault (the figures show what the robot did).
    } else if (k % window_ticks == 0) {
      res.window_max.push_back({0, 0, 0, 0, 0, 0});
      res.window_theta_range.push_back({rep.theta_hat[0], rep.theta_hat[0]});
    }
    if (counting) {
      auto& wmax = res.window_max.back();
      auto& wth = res.window_theta_range.back();
      for (int i = 0; i < 18; ++i) {
        wth[0] = std::min(wth[0], rep.theta_hat[i]);
        wth[1] = std::max(wth[1], rep.theta_hat[i]);
        res.theta_min_seen[i] = k == 0 ? rep.theta_hat[i] : std::min(res.theta_min_seen[i], rep.theta_hat[i]);
        res.theta_max_seen[i] = k == 0 ? rep.theta_hat[i] : std::max(res.theta_max_seen[i], rep.theta_hat[i]);
      }
      for (int i = 0; i < 6; ++i) {
        wmax[i] = std::max(wmax[i], std::abs(e[i]));
        res.max_error[i] = std::max(res.max_error[i], std::abs(e[i]));
        if (t >= t_final) {
          res.final_max_error[i] = std::max(res.final_max_error[i], std::abs(e[i]));
          if (rep.has_observer) {
            res.max_observer_error[i] = std::max(res.max_observer_error[i], std::abs(xt[i]));
            res.max_observer_velocity_error[i] = std::max(res.max_observer_velocity_error[i], std::abs(xdt[i]));
          }
        }
      }
    }
    const Vec6 tau_f = plant.friction(plant.qd());
    if (counting && t >= t_final) {
      for (int i = 0; i < 6; ++i) {
        const double df = rep.tau_f_hat[i] - tau_f(i);
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
        r.x_tilde[i] = xt[i];
        r.xd_tilde[i] = xdt[i];
        r.tau[i] = tau_new(i);
        r.tau_f[i] = tau_f(i);
        r.tau_f_hat[i] = rep.tau_f_hat[i];
      }
      for (int i = 0; i < 18; ++i) r.theta_hat[i] = rep.theta_hat[i];
      res.log.push_back(r);
    }
    plant.advance_sample(tau_old, tau_new, dt);
    res.plant_evaluations = plant.evaluations();
    tau_old = tau_new;
    if (cfg.progress && k % progress_every == 0) cfg.progress(static_cast<double>(k) / n);
  }
  for (int i = 0; i < 18; ++i) res.theta_hat[i] = res.status ? res.fault.theta_hat[i] : rep.theta_hat[i];
  if (fr_n > 0) {
    res.friction_rms_error = std::sqrt(fr_err2 / (6.0 * fr_n));
    res.friction_rms = std::sqrt(fr2 / (6.0 * fr_n));
  }
  ctrl.finish(res);
  if (cfg.progress) cfg.progress(1.0);
}

}  // namespace

ExperimentResult run_experiment(const ExperimentConfig& cfg) {
  const auto wall0 = std::chrono::steady_clock::now();
  timespec cpu0{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu0);
  ExperimentResult res;
  res.mode = mode_name(cfg.mode);
  res.duration = cfg.duration;
  res.adaptation = osc::adaptation_law_name(cfg.gains.adaptation);
  res.friction_preset = cfg.plant.friction.name;
  for (int i = 0; i < 6; ++i) {
    res.theta_true[i] = cfg.plant.friction.vis[i];
    res.theta_true[6 + i] = cfg.plant.friction.cou[i];
    res.theta_true[12 + i] = cfg.plant.friction.sti[i];
  }
  const Vec6 q0 = cfg.q_start;
  if (!cfg.pil_command.empty()) {
    RemoteController ctrl(cfg, res.error);
    if (ctrl.ok()) run(cfg, q0, ctrl, res);
  } else if (cfg.scalar == Scalar::kFloat) {
    LocalController<float> ctrl(cfg, q0);
    run(cfg, q0, ctrl, res);
  } else if (cfg.scalar == Scalar::kFixed) {
    LocalController<osc::Fixed> ctrl(cfg, q0);
    run(cfg, q0, ctrl, res);
  } else {
    LocalController<double> ctrl(cfg, q0);
    run(cfg, q0, ctrl, res);
  }
  res.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  timespec cpu1{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu1);
  res.cpu_seconds =
      static_cast<double>(cpu1.tv_sec - cpu0.tv_sec) + 1e-9 * static_cast<double>(cpu1.tv_nsec - cpu0.tv_nsec);
  return res;
}

}  // namespace sim
