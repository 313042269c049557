// osc_protocol: the link protocol's facts as JSON, read from the firmware's own declarations (the
// field lists and constants of osc/link/frames.hpp, the fault catalogue, the supervisor's states, the
// robot's drives) and its own encoder (the example frames). scripts/docs_tables.py --kind protocol
// writes docs/protocol.md's tables from it; ctest docs_tables_protocol fails when they differ.
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <string>

#include <nlohmann/json.hpp>

#include "osc/control/gains.hpp"
#include "osc/control/params.hpp"
#include "osc/link/frames.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/io.hpp"
#include "osc/runtime/supervisor.hpp"
#include "osc/runtime/timing.hpp"

namespace {

using nlohmann::json;

template <std::size_t N>
json fields(const pil::FieldInfo (&list)[N]) {
  json out = json::array();
  int offset = 0;
  for (const pil::FieldInfo& f : list) {
    out.push_back({{"name", f.name},
                   {"type", f.type},
                   {"count", f.count},
                   {"bytes", f.bytes},
                   {"offset", offset},
                   {"unit", f.unit},
                   {"doc", f.doc}});
    offset += f.bytes;
  }
  return out;
}

json bytes_of(const std::uint8_t* p, int n) {
  json out = json::array();
  for (int i = 0; i < n; ++i) out.push_back(p[i]);
  return out;
}

/// The examples of the document: the first sensor frame of a run (at the start pose, asking for the
/// paper's adaptation law), a later one, and an actuator frame that answers it.
json examples() {
  json out = json::array();
  std::uint8_t buf[pil::kMaxFrame];
  pil::SensorFrame first;
  first.seq = 0;
  first.inject = pil::config_adaptation(osc::AdaptationLaw::kPaper);
  out.push_back({{"what",
                  "the first sensor frame: sequence 0, every encoder at 0 (the start pose), the paper's "
                  "adaptation law requested"},
                 {"frame", "sensor"},
                 {"bytes", bytes_of(buf, pil::encode(first, buf))}});
  pil::SensorFrame later;
  later.seq = 1234;
  const std::int32_t counts[pil::kJoints] = {1500, -2750, 40, -3, 0, 12};
  for (int i = 0; i < pil::kJoints; ++i) later.counts[i] = counts[i];
  out.push_back({{"what", "sensor frame 1234: counts 1500, -2750, 40, -3, 0, 12"},
                 {"frame", "sensor"},
                 {"bytes", bytes_of(buf, pil::encode(later, buf))}});
  pil::ActuatorFrame a;
  a.seq = 1234;
  const std::int32_t codes[pil::kJoints] = {120, -9100, 2047, 0, -15, 3};
  for (int i = 0; i < pil::kJoints; ++i) a.codes[i] = codes[i];
  a.state = static_cast<std::uint8_t>(osc::SupervisorState::kRun);
  a.step_cycles = 9560;
  a.max_cycles = 9600;
  a.mean_cycles = 9500;
  a.tick_max_cycles = 13640;
  a.stack_used = 2960;
  a.theta_hat[0] = 1.5f;
  a.tau_f_hat[0] = -0.25f;
  a.link[pil::kErrSeq] = 1;
  a.rx_gap_max = 250000;
  out.push_back({{"what",
                  "actuator frame 1234: codes 120, -9100, 2047, 0, -15, 3, state run, no fault, step 9 560 "
                  "cycles (max 9 600, mean 9 500), tick max 13 640, stack 2 960 bytes, theta_hat[0] 1.5, "
                  "tau_f_hat[0] -0.25, one sequence error, longest receive gap 250 000 cycles"},
                 {"frame", "actuator"},
                 {"bytes", bytes_of(buf, pil::encode(a, buf))}});
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1) {
    std::fprintf(stderr, "usage: %s  (prints the link protocol's facts as JSON)\n", argv[0]);
    return 2;
  }
  json j;
  j["sync"] = {pil::kSync0, pil::kSync1};
  j["overhead"] = pil::kOverhead;
  j["max_frame"] = pil::kMaxFrame;
  j["types"] = {{{"name", "sensor"},
                 {"code", pil::kSensorFrame},
                 {"payload", pil::kSensorPayload},
                 {"from", "host"},
                 {"to", "firmware"}},
                {{"name", "actuator"},
                 {"code", pil::kActuatorFrame},
                 {"payload", pil::kActuatorPayload},
                 {"from", "firmware"},
                 {"to", "host"}}};
  j["hello_seq"] = pil::kHelloSeq;
  const char check[] = "123456789";
  j["crc"] = {
      {"poly", 0x1021}, {"init", 0xFFFF}, {"check", pil::crc16(reinterpret_cast<const std::uint8_t*>(check), 9)}};
  j["sensor_fields"] = fields(pil::kSensorFields);
  j["actuator_fields"] = fields(pil::kActuatorFields);
  j["inject"] = {{"non_finite", pil::kInjectNonFinite},
                 {"overrun", pil::kInjectOverrun},
                 {"adaptation_shift", pil::kConfigAdaptationShift},
                 {"adaptation_mask", pil::kConfigAdaptationMask},
                 {"no_compensation", pil::kConfigNoCompensation}};
  j["adaptation_laws"] = json::array();
  for (int i = 0; i < osc::kAdaptationLawCount; ++i) j["adaptation_laws"].push_back(osc::kAdaptationLawNames[i]);
  j["default_adaptation"] = osc::adaptation_law_name(osc::Gains<double>::paper().adaptation);
  j["link_errors"] = json::array();
  for (int i = 0; i < pil::kLinkErrorKinds; ++i)
    j["link_errors"].push_back({{"name", pil::kLinkErrorNames[i]}, {"doc", pil::kLinkErrorDocs[i]}});
  j["states"] = json::array();
  for (int i = 0; i < osc::kSupervisorStateCount; ++i) j["states"].push_back(osc::kSupervisorStateNames[i]);
  j["tick_stages"] = json::array();
  for (int i = 0; i < osc::kTickStages; ++i)
    j["tick_stages"].push_back({{"name", osc::kTickStageNames[i]}, {"doc", osc::kTickStageDocs[i]}});
  j["faults"] = json::array();
  for (int i = 0; i < osc::kFaultCount; ++i)
    j["faults"].push_back({{"name", osc::kFaultNames[i]}, {"doc", osc::kFaultDocs[i]}});
  j["dac_max_code"] = osc::kDacMaxCode;
  j["joints"] = json::array();
  for (int i = 0; i < pil::kJoints; ++i)
    j["joints"].push_back({{"counts_per_rad", osc::counts_per_rad(i)},
                           {"q_start", osc::robot::kQStart[i]},
                           {"torque_limit", osc::robot::kDrives.torque_limit[i]},
                           {"max_speed", osc::robot::kDrives.max_joint_speed[i]}});
  j["encoder_counts_per_motor_rev"] = osc::robot::kDrives.encoder_counts_per_motor_rev;
  j["control_hz"] = osc::params::kControlHz;
  j["link_timeout_s"] = osc::params::kLinkTimeout;
  j["link_silence_ticks"] = osc::params::kLinkSilenceTicks;
  j["link_error_limit"] = osc::params::kLinkErrorLimit;
  j["link_error_window"] = osc::params::kLinkErrorWindow;
  j["examples"] = examples();
  std::cout << j.dump(1) << "\n";
  return 0;
}
