#include "experiment.hpp"

#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <memory>

#include "control_tick_sim.hpp"
#include "linked_arm.hpp"
#include "osc/runtime/control_task.hpp"
#include "plant_hal.hpp"

namespace sim {

const double kPaperTable1[6] = {0.38, 0.44, 0.28, 0.06, 0.04, 0.06};
const double kPaperTable3[6] = {1.84, 1.58, 1.30, 0.11, 0.09, 0.19};

namespace {

constexpr double kRadToDeg = 180.0 / osc::kPi;

/// The host-built controller: the firmware's control task, in process.
template <class S>
class LocalController {
 public:
  explicit LocalController(const ExperimentConfig& cfg, const Vec6& q0) : task_(new osc::ControlTask<S>) {
    task_->init(osc::Model<S>::of(osc::robot::kArm, cfg.model_error), cfg.gains.template cast<S>(), cfg.mode,
                q0.cast<S>(), PlantHal::kPeriodNs);
    configure_monitors(*task_, cfg);
    task_->set_encoders(cfg.encoder_map());
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
    r.has_identification = task_->gains.adaptation == osc::AdaptationLaw::kMomentum;
    if (r.has_identification) {
      const osc::FrictionIdentifier<S>& id = task_->state.adapt.identifier;
      for (int i = 0; i < 6; ++i) {
        for (int c = 0; c < 3; ++c) r.theta_sd[6 * c + i] = std::sqrt(std::max(0.0, id.variance(i, c)));
        r.breakaway_sd[i] = std::sqrt(std::max(0.0, id.breakaway_variance(i)));
        r.split_excitation[i] = id.decay_excitation(i);
      }
    }
    const osc::ResidualMonitor<S>& m = task_->residual;
    for (int i = 0; i < 6; ++i) {
      // The channel nearer its threshold: the residual or its change (monitors.hpp); in double,
      // so that a fixed-point division here cannot raise the controller's arithmetic flag.
      const double r_abs = std::abs(static_cast<double>(m.r(i))), th_abs = static_cast<double>(m.threshold(i));
      const double d_abs = std::abs(static_cast<double>(m.d(i))), th_d = static_cast<double>(m.change_threshold(i));
      const bool change = d_abs * th_abs > r_abs * th_d;
      const double th = change ? th_d : th_abs, ri = change ? d_abs : r_abs;
      const double ratio = th > 0 ? ri / th : 0;
      const double position = static_cast<double>(task_->position.ratio(i));
      if (position > residual_.position_peak_ratio[i]) residual_.position_peak_ratio[i] = position;
      const double oscillation = task_->oscillation.ratio(i);
      if (oscillation > residual_.oscillation_peak_ratio[i]) residual_.oscillation_peak_ratio[i] = oscillation;
      if (m.primed && th > 0 && ratio > residual_.residual_peak_ratio[i]) {
        residual_.residual_peak_ratio[i] = ratio;
        residual_.residual_peak_s[i] = static_cast<double>(task_->tick - 1) / osc::params::kControlHz;
        residual_.residual_peak_Nm[i] = ri;
        residual_.residual_threshold_Nm[i] = th;
      }
    }
    return true;
  }
  /// The counter jumps by n, as if the task had been running that much longer: the trajectory's
  /// start stays (its time grows by n, the point of the jump), while the monitors' recent history
  /// (each encoder's last change, a run over the threshold, the enable's ramp and prime) moves with the clock,
  /// as it would have in a task that had been running.
  void skip_ticks(std::uint64_t n) {
    task_->tick += n;
    task_->ramp_start += n;
    task_->residual.activity.shift(n);
    task_->stuck.activity.shift(n);
    for (std::uint64_t& t : task_->residual.over_since) t += n;
    task_->residual.primed_at += n;
  }
  void finish(ExperimentResult& res) {
    for (int i = 0; i < 6; ++i) res.stuck_peak[i] = static_cast<double>(task_->stuck.peak(i));
    for (int i = 0; i < 6; ++i) res.stuck_dtau_peak[i] = static_cast<double>(task_->stuck.dtau_peak(i));
    for (int i = 0; i < 6; ++i) res.stuck_dtau_silent_peak[i] = static_cast<double>(task_->stuck.dtau_gated_peak(i));
    for (int i = 0; i < 6; ++i) {
      res.residual_peak_ratio[i] = residual_.residual_peak_ratio[i];
      res.residual_peak_s[i] = residual_.residual_peak_s[i];
      res.residual_peak_Nm[i] = residual_.residual_peak_Nm[i];
      res.residual_threshold_Nm[i] = residual_.residual_threshold_Nm[i];
      res.position_peak_ratio[i] = residual_.position_peak_ratio[i];
      res.oscillation_peak_ratio[i] = residual_.oscillation_peak_ratio[i];
    }
    const osc::ResidualMonitor<S>& m = task_->residual;
    for (int i = 0; i < 6; ++i) {
      const double limit = static_cast<double>(m.travel_limit(i));
      res.travel_peak_ratio[i] = limit > 0 ? static_cast<double>(m.travel_peak(i)) / limit : 0;
    }
    if (m.detected != 0) {
      res.residual_detected_s = static_cast<double>(m.detected_tick) / osc::params::kControlHz;
      res.residual_fault = m.detected;
      res.residual_joint = static_cast<unsigned char>(m.joint);  // set: 0..5
      res.residual_weight = m.flange.fitted;
      res.residual_weight_kg = static_cast<double>(m.flange.mass);
      res.residual_weight_offset_m = static_cast<double>(m.flange.offset);
      res.residual_weight_misfit = static_cast<double>(m.flange.misfit);
    }
    const osc::DriveMonitor& d = task_->drive;
    for (int c = 0; c < 6; ++c) {
      res.drive_peak_ratio[c] = d.peak[c] / 1000.0;
      res.dither_peak_fade[c] = d.dither_peak[c] / 1000.0;
    }
    if (d.detected != 0) {
      res.drive_detected_s = static_cast<double>(d.detected_tick) / osc::params::kControlHz;
      res.drive_fault = d.detected;
      res.drive_channel = static_cast<unsigned char>(d.channel);  // set: 0..5
    }
  }

 private:
  std::unique_ptr<osc::ControlTask<S>> task_;  // large: keep off the stack
  StuckMonitorPeaks residual_;                 // the residual monitor's peaks so far
};

/// The firmware image (or any PIL peer) over the link, one exchange per tick.
class RemoteController {
 public:
  RemoteController(const ExperimentConfig& cfg, std::string& err)
      : session_(cfg.pil_timeout,
                 static_cast<std::uint8_t>((cfg.mode == osc::FrictionMode::kNone ? pil::kConfigNoCompensation : 0) |
                                           pil::config_adaptation(cfg.gains.adaptation))) {
    ok_ = session_.start(cfg.pil_command, err);
  }
  bool ok() const { return ok_; }
  /// One exchange (PilSession::exchange): the codes of a valid, in-range answer, else zero.
  bool tick(PlantHal& hal, TickReport& r, std::string& err) {
    if (!session_.exchange(hal, err)) return false;
    const pil::ActuatorFrame& a = session_.last();
    r.faults = a.faults;
    for (int i = 0; i < 6; ++i) r.tau_f_hat[i] = a.tau_f_hat[i];
    for (int i = 0; i < 18; ++i) r.theta_hat[i] = a.theta_hat[i];
    return true;
  }
  void finish(ExperimentResult& res) {
    const pil::ActuatorFrame& last = session_.last();
    res.max_step_cycles = last.max_cycles;
    res.mean_step_cycles = last.mean_cycles;
    res.max_tick_cycles = last.tick_max_cycles;
    res.stack_used = last.stack_used;
    res.link = session_.link_report();
    session_.link().stop();
  }

 private:
  PilSession session_;
  bool ok_ = false;
};

/// The true plant's errors, through double kinematics: the tracking error e against the task
/// (the paper's motion about the start pose, as the controller's), and the observer's errors
/// against the true operational velocity.
class GroundTruth {
 public:
  GroundTruth(const Vec6& q0, const osc::TrajectorySpec<double>& spec) {
    osc::forward_kinematics(model_, data_, q0);
    paper_ = {spec, data_.o[6], 0};
    R_ref_ = data_.R[6];
  }
  /// e of the plant at q in sample k: mm (x, y, z), deg (about X, Y, Z).
  void tracking_error(long k, const Vec6& q, double e[6]) {
    osc::forward_kinematics(model_, data_, q);
    const osc::Desired<double> d = paper_.at_tick(static_cast<std::uint64_t>(k), osc::params::kControlHz);
    phi_ = osc::orientation_coordinates(data_.R[6], R_ref_);
    for (int i = 0; i < 3; ++i) e[i] = (d.x(i) - data_.o[6](i)) * 1e3;
    for (int i = 0; i < 3; ++i) e[3 + i] = -phi_(i) * kRadToDeg;
  }
  /// The observer's errors at the pose of the last tracking_error (mm, deg; mm/s, deg/s). They are
  /// known only for the in-process controller; over the link they are not sent, and NaN here.
  void observer_errors(const TickReport& rep, const Vec6& qd, double xt[6], double xdt[6]) {
    if (!rep.has_observer) {
      for (int i = 0; i < 6; ++i) xt[i] = xdt[i] = std::numeric_limits<double>::quiet_NaN();
      return;
    }
    // The true operational velocity: the analytic Jacobian of the plant's pose times its joint speeds.
    osc::geometric_jacobian(data_);
    const Mat6 Ja = osc::analytic_jacobian(data_.J, phi_);
    const Vec6 xd_true = Ja * qd;
    for (int i = 0; i < 6; ++i) {
      const double scale = i < 3 ? 1e3 : kRadToDeg;
      xt[i] = rep.x_tilde[i] * scale;
      xdt[i] = (rep.xd_hat[i] - xd_true(i)) * scale;
    }
  }

 private:
  const osc::Model<double> model_ = osc::Model<double>::of(osc::robot::kArm);
  osc::Data<double> data_;
  osc::PaperMotion<double> paper_;
  Mat3 R_ref_;
  Vec3 phi_ = Vec3::Zero();
};

/// The closed loop, sample by sample: the true errors, the controller's tick, the metrics of the
/// result (metrics.hpp) observe the sample, the plant advances.
template <class Controller>
void run(const ExperimentConfig& cfg, const Vec6& q0, Controller& ctrl, ExperimentResult& res) {
  Plant plant(cfg.plant);
  plant.reset(q0);
  plant.set_contact(Contact::of(cfg.injection));
  PlantHal hal(plant, q0, cfg.sensor_config(), cfg.injection);
  GroundTruth truth(q0, cfg.gains.trajectory);
  const double dt = osc::params::kDt;
  const long n = std::lround(cfg.duration / dt);
  const long progress_every = std::max(1L, n / 100);
  const long jump_tick = cfg.jump_at >= 0 ? std::lround(cfg.jump_at / dt) : -1;
  const double t_final = cfg.duration - cfg.final_window;  // the "last" statistics from here
  Sample s;
  for (long k = 0; k < n; ++k) {
    s.k = k;
    s.t = k * dt;
    s.last = s.t >= t_final;
    truth.tracking_error(k, plant.q(), s.e);
    if constexpr (requires { ctrl.skip_ticks(std::uint64_t{0}); }) {
      if (k == jump_tick) ctrl.skip_ticks(cfg.jump_ticks);
    }
    // The controller: encoders -> control step -> DAC codes.
    hal.begin_sample(s.t);
    if (!ctrl.tick(hal, s.rep, res.error)) {
      res.error = "tick " + std::to_string(k) + ": " + res.error;
      break;
    }
    s.counting = s.counting && s.rep.faults == 0;
    s.q = plant.q();
    s.qd = plant.qd();
    s.tau = hal.torque();
    s.tau_f = plant.friction(plant.qd());
    s.injection_active = hal.injection_active();
    truth.observer_errors(s.rep, plant.qd(), s.x_tilde, s.xd_tilde);
    res.each([&s](auto& m) {
      if constexpr (requires { m.observe(s); }) m.observe(s);
    });
    plant.set_amplifiers(!hal.fault());
    plant.advance_sample(s.tau_before, s.tau, dt);
    s.tau_before = s.tau;
    if (cfg.progress && k % progress_every == 0) cfg.progress(static_cast<double>(k) / n);
  }
  res.plant_evaluations = plant.evaluations();
  res.injection.peak_contact_force = plant.peak_contact_force();
  res.injection.first_contact = plant.first_contact_time();
  res.injection.breakaway = hal.breakaway_before(res.injection.detected >= 0 ? res.injection.detected : cfg.duration);
  res.each([](auto& m) {
    if constexpr (requires { m.end(); }) m.end();
  });
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
  res.each([&cfg](auto& m) {
    if constexpr (requires { m.begin(cfg); }) m.begin(cfg);
  });
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
