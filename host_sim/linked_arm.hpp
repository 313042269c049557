// The controller of a PIL image (the firmware in QEMU, or any PIL peer) over the link, the simulated
// arm here: one lockstep exchange per tick, the command protocol's frames between them. The scripted
// motions' remote controller (motion_script.cpp, puma_experiment --motion --qemu) and the virtual
// board's (sim_board.cpp, osc_sim --pty --qemu).
//
// The first sensor frame asks the node to start disabled and to trace every tick (its desired state
// and reference orientation, its faults and motion state; with more configuration bits, e.g. state
// frames); the commands and the setpoints go before the sensor frame of the tick that is to take
// them, as the in-process controller's go into its mailbox before its tick. The arm's brakes follow
// the traced state.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "experiment.hpp"
#include "osc/runtime/motion_commands.hpp"
#include "pil_client.hpp"
#include "plant_hal.hpp"

namespace sim {

/// What one tick shows of the controller, the same from either kind (in process, over the link).
struct TickView {
  std::vector<osc::MotionReport> reports;  ///< the answers since the tick before, in order (the tick's own last)
  osc::MotionState state = osc::MotionState::kDisabled;  ///< the motion state after the tick
  std::uint32_t faults = 0;                              ///< the fault bits the tick detected
  /// The desired state of the last control step, in the controller's coordinates.
  Vec6 x_d = Vec6::Zero(), xd_d = Vec6::Zero(), xdd_d = Vec6::Zero();
  Vec6 pose = Vec6::Zero();   ///< the arm's true pose after the tick's sample, in the same coordinates
  bool has_theta = false;     ///< theta_hat is set (in process only)
  double theta_hat[18] = {};  ///< the friction estimates after the tick
};

/// The host's end of a lockstep PIL session over the simulated hardware (the paper's experiment's
/// remote controller, experiment.cpp, and LinkedArm): each tick a sensor frame of the encoders, the
/// amplifiers' currents and their fault lines (hal::CurrentHal; the session's first frame with the
/// configuration bits), the answer's codes to the amplifiers; zero codes on a link error (counted, the
/// first kept), and a lost link (no answer in time, the peer gone) ends it.
class PilSession {
 public:
  PilSession(double timeout_s, std::uint8_t config) : timeout_(timeout_s), config_(config) {}
  /// Starts the peer (PilClient::start).
  bool start(const std::vector<std::string>& command, std::string& err) { return link_.start(command, err); }
  /// One exchange; false when the link was lost (err: why).
  bool exchange(PlantHal& hal, std::string& err);
  PilClient& link() { return link_; }
  /// The last answer (its telemetry).
  const pil::ActuatorFrame& last() const { return last_; }
  /// The sequence number of the last sensor frame sent.
  std::uint32_t seq() const { return seq_ - 1; }
  LinkReport link_report() const {
    return LinkReport::of(last_, link_.link_counters(), link_.code_range_errors(), zeroed_ticks_, first_zeroed_);
  }

 private:
  PilClient link_;
  double timeout_;
  std::uint8_t config_;
  std::uint32_t seq_ = 0;
  pil::ActuatorFrame last_;
  std::uint32_t zeroed_ticks_ = 0;
  std::string first_zeroed_;
};

class LinkedArm {
 public:
  /// Starts cfg.pil_command (waits for its hello frame: ok() says whether it came), the arm at rest at
  /// q0 with its brakes on, its sensors cfg's (cfg.sensor_config(): e.g. plant.current_monitor). config: configuration
  /// bits for the first sensor frame besides start_disabled, trace and cfg's friction mode and adaptation law (e.g.
  /// pil::kConfigStateFrames).
  LinkedArm(const Vec6& q0, const ExperimentConfig& cfg, std::uint8_t config = 0);
  LinkedArm(const LinkedArm&) = delete;
  LinkedArm& operator=(const LinkedArm&) = delete;

  /// Whether the controller started; err says why not.
  bool ok(std::string& err) const { return ok_ || (err = start_error_, false); }
  /// A command or a setpoint frame, for the next tick.
  bool command(const pil::CommandFrame& f, std::string& err) { return session_.link().send(f, err); }
  bool setpoint(const pil::SetpointFrame& f, std::string& err) { return session_.link().send(f, err); }
  bool setpoint(const pil::SetpointVelocityFrame& f, std::string& err) { return session_.link().send(f, err); }
  /// A param frame, for the next tick (answered before its actuator frame: replies().params).
  bool param(const pil::ParamFrame& f, std::string& err) { return session_.link().send(f, err); }
  /// A capture frame, the same (replies().captures).
  bool capture(const pil::CaptureFrame& f, std::string& err) { return session_.link().send(f, err); }
  /// One tick: the sensor frame, the answer's codes to the amplifiers, the plant over the sample.
  /// False when the link was lost (err: the tick and why).
  bool tick(TickView& v, std::string& err);
  /// The command protocol's frames of the last tick: its answers, its state frame, its trace.
  const PilReplies& replies() const { return replies_; }
  /// The link's health so far.
  LinkReport link_report() const { return session_.link_report(); }
  /// The program that runs the controller (cfg.pil_command's first word).
  const std::string& program() const { return command_; }
  /// Stops the controller's process.
  void stop() { session_.link().stop(); }
  /// The simulated arm.
  const Plant& plant() const { return plant_; }

 private:
  Vec6 q0_;
  Plant plant_;
  PlantHal hal_;
  PilSession session_;
  bool ok_ = false;
  std::string start_error_, command_;
  PilReplies replies_;
  Vec6 tau_before_ = Vec6::Zero();
  const osc::Model<double> model_ = osc::Model<double>::of(osc::robot::kArm);
  osc::Data<double> data_;
};

/// A PIL firmware image for QEMU (--qemu --elf): the command line that runs it over `link`
/// (PilClient::qemu_command) and the scalar it computes in, float on the M4F (mps2-an386), fixed
/// point on the M3 (mps2-an385). False with err for a missing file or one that is no MPS2 image.
bool pil_image(const std::string& elf, PilLink link, std::vector<std::string>& command, Scalar& scalar,
               std::string& err);

}  // namespace sim
