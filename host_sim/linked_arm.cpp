#include "linked_arm.hpp"

#include <unistd.h>

#include "osc/link/commands.hpp"

namespace sim {

bool PilSession::exchange(PlantHal& hal, std::string& err) {
  pil::SensorFrame s;
  s.seq = seq_++;
  // The sample as the in-process tick reads it (control_tick: the encoders, then the drive check's
  // currents and fault lines, before the DAC write): once each, at this sample's time.
  hal.read_encoders(s.counts);
  const bool currents = hal.read_currents(s.currents);
  if (!currents)
    for (std::int16_t& c : s.currents) c = 0;
  s.drive = pil::drive_byte(hal.amp_faults(), currents);
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
  return true;
}

LinkedArm::LinkedArm(const Vec6& q0, const ExperimentConfig& cfg, std::uint8_t config)
    : q0_(q0),
      plant_(cfg.plant),
      hal_(plant_, q0_, cfg.sensor_config(), cfg.injection),
      session_(cfg.pil_timeout,
               static_cast<std::uint8_t>(config | pil::kConfigStartDisabled | pil::kConfigTrace |
                                         (cfg.mode == osc::FrictionMode::kNone ? pil::kConfigNoCompensation : 0) |
                                         pil::config_adaptation(cfg.gains.adaptation))) {
  plant_.reset(q0_);
  plant_.set_contact(Contact::of(cfg.injection));
  plant_.set_brakes(true);
  ok_ = session_.start(cfg.pil_command, start_error_);
  command_ = cfg.pil_command.empty() ? "" : cfg.pil_command.front();
}

bool LinkedArm::tick(TickView& v, std::string& err) {
  hal_.begin_sample(plant_.time());
  if (!session_.exchange(hal_, err)) return err = "tick " + std::to_string(session_.seq()) + ": " + err, false;
  const std::uint32_t seq = session_.seq();
  replies_ = session_.link().take_replies();
  if (replies_.traces.empty() || replies_.traces.back().seq != seq)
    return err = "tick " + std::to_string(seq) + ": no trace frame", false;
  const pil::TraceFrame& t = replies_.traces.back();
  v.reports.clear();
  for (const pil::AnswerFrame& f : replies_.answers) v.reports.push_back(osc::report_from_frame(f));
  v.state = static_cast<osc::MotionState>(t.state);
  v.faults = t.faults;
  Mat3 R_ref;
  for (int i = 0; i < 6; ++i) v.x_d(i) = t.x_d[i], v.xd_d(i) = t.xd_d[i], v.xdd_d(i) = t.xdd_d[i];
  for (int i = 0; i < 9; ++i) R_ref(i / 3, i % 3) = t.R_ref[i];
  // The plant over the sample, as MotionSim::tick: the amplifiers' torque, the brakes by the state.
  const Vec6 tau = hal_.torque();
  plant_.set_brakes(!osc::motion_powered(v.state));
  plant_.set_amplifiers(!hal_.fault());
  plant_.advance_sample(tau_before_, tau, osc::params::kDt);
  tau_before_ = tau;
  osc::forward_kinematics(model_, data_, plant_.q());
  v.pose << data_.o[osc::kDof], osc::orientation_coordinates<double>(data_.R[osc::kDof], R_ref);
  return true;
}

bool pil_image(const std::string& elf, PilLink link, std::vector<std::string>& command, Scalar& scalar,
               std::string& err) {
  if (access(elf.c_str(), R_OK) != 0)
    return err =
               "firmware image " + elf + " not found: build it with 'cmake --preset m4f && cmake --build --preset m4f'",
           false;
  command = PilClient::qemu_command("qemu-system-arm", elf, link, err);
  if (command.empty()) return false;
  scalar = qemu_machine(elf, err) == "mps2-an385" ? Scalar::kFixed : Scalar::kFloat;
  return true;
}

}  // namespace sim
