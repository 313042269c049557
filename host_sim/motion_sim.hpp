// The simulated arm under commanded motion: the firmware's control task (in process, any scalar)
// over the simulated PUMA 560 (PlantHal), started disabled, driven by commands as a board's main
// loop would drive it: each command is prepared (motion_commands.hpp) and put in the task's mailbox,
// which the next tick takes. The plant's brakes hold the arm while the controller is disabled or in
// fault and release when it holds torque (a PUMA's arm power and brakes).
//
// Used by the closed-loop tests of commanded motion (tests/host_sim/test_motion_sim.cpp) and the
// runner's scripted motions.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "control_tick_sim.hpp"
#include "osc/runtime/control_task.hpp"
#include "plant.hpp"
#include "plant_hal.hpp"

namespace sim {

template <class S>
class MotionSim {
 public:
  /// The arm at rest at q0, its encoders zeroed there (the task's q_start), the controller disabled.
  /// inj: a simulated hardware fault or a contact (injection.hpp), none by default. sensors: the
  /// plant's (the task reads encoders of sensors.encoders). Without power_on the arm was placed at q0,
  /// a pose the task takes as declared (homed, as the paper's procedure); with power_on, the arm
  /// powers on there (incremental encoders count from there) while the task assumes q0: not homed, motion is
  /// refused until a home or a declare_pose. Absolute encoders (osc::has_absolute_encoders) read the
  /// angle wherever it powers on: the task is homed from the start.
  static constexpr bool kAbsolute = osc::has_absolute_encoders(osc::robot::kDriveTrain);
  explicit MotionSim(const Vec6& q0, const Injection& inj = {}, const PlantConfig& pc = {},
                     osc::FrictionMode mode = osc::FrictionMode::kAdaptive,
                     const osc::Gains<double>& gains = osc::Gains<double>::paper(), const SensorConfig& sensors = {},
                     const std::optional<Vec6>& power_on = std::nullopt)
      : plant_(pc), hal_(plant_, kAbsolute ? q0 : power_on.value_or(q0), sensors, inj), task_(new osc::ControlTask<S>) {
    plant_.reset(power_on.value_or(q0));
    plant_.set_contact(Contact::of(inj));  // a collision or a wall acts in the plant, the rest in the HAL
    plant_.set_brakes(true);
    task_->init(osc::Model<S>::of(osc::robot::kArm), gains.template cast<S>(), mode, q0.cast<S>(), PlantHal::kPeriodNs,
                osc::TaskStart::kDisabled);
    task_->set_encoders(sensors.encoders);
    task_->homed = kAbsolute || !power_on.has_value();
  }
  /// A home, planned (the homing move, path-checked) from the measured angles, taken by the next tick.
  void home(std::uint32_t id) { task_->pending = osc::prepare_checked_home(*task_, id); }
  /// A declare_pose of the named pose of code `pose` (robot::kNamedPoses), taken by the next tick.
  void declare_pose(unsigned pose, std::uint32_t id) { task_->pending = osc::prepare_declare_pose<S>(pose, id); }

  /// A command without a plan (enable, disable, paper, stop, clear), taken by the next tick.
  void command(osc::MotionVerb verb, std::uint32_t id) { task_->pending = osc::prepare_command<S>(verb, id); }
  /// An identification run, planned and checked about the last measured angles (prepare_identify); the
  /// check's report into `check` when given.
  void identify(std::uint32_t id, osc::ExcitationCheck<S>* check = nullptr,
                std::uint16_t payload = osc::payload_mask::kNone) {
    task_->pending = osc::prepare_identify(*task_, id, check, payload);
  }
  /// A move_to, prepared (planned and its path checked) from where the queue will end, taken by the
  /// next tick.
  void move_to(const osc::MoveRequest<S>& req, std::uint32_t id) {
    task_->pending = osc::prepare_checked_move(*task_, req, id);
  }
  /// A stream command (req.period, req.relative, req.has_limits), taken by the next tick.
  void stream(const osc::MoveRequest<S>& req, std::uint32_t id) {
    task_->pending = osc::prepare_stream(task_->limits, req, id);
  }
  /// A setpoint of stream `id` for the next tick (rpy: null keeps the orientation; velocity: the
  /// linear and angular velocity, or none); false: dropped.
  bool setpoint(std::uint32_t id, const Vec3& position, const Vec3* rpy, bool end, const Vec6* velocity = nullptr) {
    const osc::Vec3<S> r = rpy ? osc::Vec3<S>(rpy->cast<S>()) : osc::Vec3<S>::Zero();
    const osc::Vec6<S> v = velocity ? osc::Vec6<S>(velocity->cast<S>()) : osc::Vec6<S>::Zero();
    return osc::offer_setpoint(*task_, id, osc::Vec3<S>(position.cast<S>()), r, rpy != nullptr, end,
                               velocity ? &v : nullptr);
  }
  /// Whether the mailbox is free for the next command.
  bool idle() const { return task_->pending.verb == osc::MotionVerb::kNone; }

  /// One control period: the task's tick, then the plant over one sample with the torque the
  /// amplifiers produce. Returns the tick's fault bits.
  std::uint32_t tick() {
    hal_.begin_sample(plant_.time());
    const std::uint32_t faults = osc::control_tick(*task_, hal_);
    const Vec6 tau = hal_.torque();
    plant_.set_brakes(!osc::motion_powered(task_->machine.state));
    plant_.set_amplifiers(!hal_.fault());
    plant_.advance_sample(tau_before_, tau, osc::params::kDt);
    tau_before_ = tau;
    return faults;
  }

  /// The wrist centre of the simulated arm [m] (the point the controller tracks).
  Vec3 tip() const {
    osc::forward_kinematics(model_, data_, plant_.q());
    return data_.o[osc::kDof];
  }
  /// The reference of the last step, x_d (the generator's, in the controller's coordinates).
  Vec6 reference() const { return task_->desired.x.template cast<double>(); }
  /// The true pose of the simulated arm in the controller's coordinates: the wrist centre and the
  /// orientation relative to the controller's reference orientation.
  Vec6 pose() const {
    osc::forward_kinematics(model_, data_, plant_.q());
    Vec6 x;
    x << data_.o[osc::kDof],
        osc::orientation_coordinates<double>(data_.R[osc::kDof], task_->state.R_ref.template cast<double>());
    return x;
  }

  osc::ControlTask<S>& task() { return *task_; }
  const osc::ControlTask<S>& task() const { return *task_; }
  Plant& plant() { return plant_; }
  PlantHal& hal() { return hal_; }

 private:
  Plant plant_;
  PlantHal hal_;
  std::unique_ptr<osc::ControlTask<S>> task_;  // large: keep off the stack
  Vec6 tau_before_ = Vec6::Zero();
  const osc::Model<double> model_ = osc::Model<double>::of(osc::robot::kArm);
  mutable osc::Data<double> data_;
};

}  // namespace sim
