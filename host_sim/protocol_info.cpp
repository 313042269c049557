// osc_protocol: the link protocol's facts as JSON, read from the firmware's own declarations (the
// frame types and field lists and the constants of osc/link/frames.hpp and command_frames.hpp, the
// fault catalogue, the supervisor's states, the motion state machine's and the commands' names, the
// robot's drives, the move limits) and its own encoder (the example frames). scripts/docs_tables.py
// --kind protocol writes docs/protocol.md's tables from it; ctest docs_tables_protocol fails when
// they differ. With --client: what a client of the command protocol needs (the frames' layouts, the
// flags, the names of every code, the limits), which clients/python/osc_protocol.json holds
// (scripts/client_protocol.py writes it; ctest client_protocol_json_current fails when it differs).
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <span>
#include <string>

#include <nlohmann/json.hpp>

#include "osc/control/gains.hpp"
#include "osc/control/params.hpp"
#include "osc/link/command_port.hpp"
#include "osc/link/commands.hpp"
#include "osc/link/frames.hpp"
#include "osc/link/param_frames.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/io.hpp"
#include "osc/runtime/supervisor.hpp"
#include "osc/runtime/timing.hpp"

namespace {

using nlohmann::json;

json fields(const pil::FieldInfo* list, int n) {
  json out = json::array();
  int offset = 0;
  for (const pil::FieldInfo& f : std::span(list, static_cast<std::size_t>(n))) {
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
/// paper's adaptation law), a later one (with the amplifiers' currents and a fault line), and an actuator
/// frame that answers it.
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
  const std::int16_t currents[pil::kJoints] = {310, -1200, 45, 0, -7, 2};
  for (int i = 0; i < pil::kJoints; ++i) later.counts[i] = counts[i], later.currents[i] = currents[i];
  later.drive = pil::drive_byte(1u << 2, true);
  out.push_back({{"what",
                  "sensor frame 1234: counts 1500, -2750, 40, -3, 0, 12; currents 310, -1200, 45, 0, -7, 2, a "
                  "reading (currents_valid), amplifier 3's fault line active"},
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

/// The command protocol's examples: a move_to and the answer of the tick that accepted it.
json command_examples() {
  json out = json::array();
  std::uint8_t buf[pil::kMaxFrame];
  osc::MoveRequest<double> req;
  req.position = osc::Vec3<double>(0.05, 0.0, -0.02);
  req.relative = true;
  out.push_back(
      {{"what", "command 7: move_to, relative, by (0.05, 0, -0.02) m, orientation kept, the configured limits"},
       {"frame", "command"},
       {"bytes", bytes_of(buf, osc::encode_command(7, osc::MotionVerb::kMoveTo, req, buf))}});
  osc::MotionReport r;
  r.id = 7;
  r.verb = osc::MotionVerb::kMoveTo;
  r.outcome = osc::CommandOutcome::kAccepted;
  out.push_back(
      {{"what", "its answer: command 7 (move_to) accepted in tick 1234, state moving, one move queued"},
       {"frame", "answer"},
       {"bytes", bytes_of(buf, pil::encode(osc::frame_from_report(r, osc::MotionState::kMoving, 1, 1234), buf))}});
  return out;
}

/// The names, codes and meanings of one of the motion state machine's enumerations.
template <class E>
json motion_names() {
  json out = json::array();
  for (int i = 0; i < osc::MotionNames<E>::kCount; ++i)
    out.push_back({{"code", i}, {"name", osc::MotionNames<E>::kNames[i]}, {"doc", osc::MotionNames<E>::kDocs[i]}});
  return out;
}

/// The names, codes and meanings of a list given as two arrays.
json coded(const char* const* names, const char* const* docs, int n) {
  json out = json::array();
  for (int i = 0; i < n; ++i) out.push_back({{"code", i}, {"name", names[i]}, {"doc", docs[i]}});
  return out;
}

/// The on-board capture's lists and sizes (osc/link/capture_frames.hpp): with `docs` (the document's), codes and
/// meanings too; a client's has the lists' names in code order.
json capture(bool docs) {
  json j;
  j["channels"] = pil::kCaptureChannels;
  j["values"] = pil::kCaptureValues;
  j["chunk"] = pil::kCaptureChunk;
  j["signals"] = json::array();
  for (int i = 0; i < pil::kCaptureSignalCount; ++i) {
    const pil::CaptureSignalInfo& s = pil::kCaptureSignals[i];
    json e = {{"name", s.name}, {"elements", s.elements}, {"unit", s.unit}};
    if (docs) e["code"] = i, e["doc"] = s.doc;
    j["signals"].push_back(e);
  }
  const auto list = [docs](const char* const* names, const char* const* meanings, int n) {
    if (docs) return coded(names, meanings, n);
    json out = json::array();
    for (int i = 0; i < n; ++i) out.push_back(names[i]);
    return out;
  };
  j["ops"] = list(pil::kCaptureOpNames, pil::kCaptureOpDocs, pil::kCaptureOpCount);
  j["triggers"] = list(pil::kCaptureTriggerNames, pil::kCaptureTriggerDocs, pil::kCaptureTriggerCount);
  j["states"] = list(pil::kCaptureStateNames, pil::kCaptureStateDocs, pil::kCaptureStateCount);
  j["statuses"] = list(pil::kCaptureStatusNames, pil::kCaptureStatusDocs, pil::kCaptureStatusCount);
  return j;
}

/// The parameter table (osc/runtime/parameters.hpp): each parameter with its index, elements, unit,
/// range and default per element, access, persistence and meaning; the operations, statuses, flags.
json parameters(bool with_docs) {
  json j;
  j["layout"] = osc::kParamLayout;
  j["table"] = json::array();
  for (int i = 0; i < osc::kParamCount; ++i) {
    const osc::ParamInfo& p = osc::kParams[i];
    json lo = json::array(), hi = json::array(), def = json::array();
    for (int e = 0; e < p.count; ++e)
      lo.push_back(p.lo_of(e)), hi.push_back(p.hi_of(e)), def.push_back(osc::param_default(i, e));
    json row = {{"index", i},
                {"name", p.name},
                {"count", p.count},
                {"unit", p.unit},
                {"lo", lo},
                {"hi", hi},
                {"default", def},
                {"access", osc::kParamAccessNames[static_cast<int>(p.access)]},
                {"persists", p.persists}};
    if (with_docs) row["doc"] = p.doc;
    j["table"].push_back(row);
  }
  if (with_docs) {
    j["ops"] = coded(pil::kParamOpNames, pil::kParamOpDocs, pil::kParamOpCount);
    j["statuses"] = coded(osc::kParamStatusNames, osc::kParamStatusDocs, osc::kParamStatusCount);
    j["access"] = coded(osc::kParamAccessNames, osc::kParamAccessDocs, 2);
    j["flags"] = json::array();
    for (int i = 0; i < pil::kParamFlagCount; ++i)
      j["flags"].push_back(
          {{"bit", i}, {"mask", 1 << i}, {"name", pil::kParamFlagNames[i]}, {"doc", pil::kParamFlagDocs[i]}});
  } else {
    j["ops"] = json::array();
    for (const char* n : pil::kParamOpNames) j["ops"].push_back(n);
    j["statuses"] = json::array();
    for (const char* n : osc::kParamStatusNames) j["statuses"].push_back(n);
    j["flags"] = json::array();
    for (const char* n : pil::kParamFlagNames) j["flags"].push_back(n);
  }
  return j;
}

/// The command protocol: flags, bounds, the move limits, the names of the codes, examples.
json command_protocol() {
  json j;
  j["flags"] = json::array();
  for (int i = 0; i < pil::kCommandFlagCount; ++i)
    j["flags"].push_back(
        {{"bit", i}, {"mask", 1 << i}, {"name", pil::kCommandFlagNames[i]}, {"doc", pil::kCommandFlagDocs[i]}});
  j["setpoint_flags"] = json::array();
  for (int i = 0; i < pil::kSetpointFlagCount; ++i)
    j["setpoint_flags"].push_back(
        {{"bit", i}, {"mask", 1 << i}, {"name", pil::kSetpointFlagNames[i]}, {"doc", pil::kSetpointFlagDocs[i]}});
  j["stream_max_period"] = pil::kStreamMaxPeriod;
  j["state_period"] = osc::kStatePeriod;
  j["command_fifo"] = osc::kCommandFifo;
  j["max_position"] = pil::kCommandMaxPosition;
  j["max_angle"] = pil::kCommandMaxAngle;
  j["max_velocity"] = pil::kCommandMaxVelocity;
  const auto lim = osc::CartesianLimits<double>::defaults();
  j["limits"] = {{"linear", {lim.linear.v, lim.linear.a, lim.linear.j}},
                 {"angular", {lim.angular.v, lim.angular.a, lim.angular.j}}};
  j["queue_length"] = osc::params::kMoveQueueLength;
  j["max_move_rotation"] = osc::kMaxMoveRotation;
  j["verbs"] = motion_names<osc::MotionVerb>();
  j["motion_states"] = motion_names<osc::MotionState>();
  j["reasons"] = motion_names<osc::MotionReason>();
  j["outcomes"] = motion_names<osc::CommandOutcome>();
  j["stop_categories"] = motion_names<osc::StopCategory>();
  j["completions"] = motion_names<osc::MotionCompletion>();
  j["identify_statuses"] = coded(osc::kIdentifyStatusNames, osc::kIdentifyStatusDocs, osc::kIdentifyStatusCount);
  j["poses"] = json::array();
  for (int i = 0; i < osc::robot::kNamedPoseCount; ++i) {
    const osc::NamedPose& p = osc::robot::kNamedPoses[i];
    json deg = json::array();
    for (double q : p.q) deg.push_back(std::round(q * 180 / osc::kPi * 1e6) / 1e6);
    j["poses"].push_back({{"code", i}, {"name", p.name}, {"q_deg", deg}, {"doc", p.doc}});
  }
  j["examples"] = command_examples();
  j["parameters"] = parameters(true);
  j["capture"] = capture(true);
  return j;
}

template <class E>
json names() {
  json out = json::array();
  for (int i = 0; i < osc::MotionNames<E>::kCount; ++i) out.push_back(osc::MotionNames<E>::kNames[i]);
  return out;
}

/// A frame's fields as a client lays them out: name, wire type, count (wire order, no padding), and the unit as
/// declared ("m, rad": the elements in equal runs, the first half in m, the second in rad; "" for codes and counts).
json client_fields(const pil::FrameInfo& f) {
  json out = json::array();
  for (const pil::FieldInfo& x : std::span(f.fields, static_cast<std::size_t>(f.field_count)))
    out.push_back({{"name", x.name}, {"type", x.type}, {"count", x.count}, {"unit", x.unit}});
  return out;
}

/// What a client of the command protocol needs, and nothing it does not (no documentation text: the
/// file changes only when the protocol does).
json client_protocol() {
  json j;
  j["generated_by"] = "osc_protocol --client (scripts/client_protocol.py); do not edit";
  j["sync"] = {pil::kSync0, pil::kSync1};
  j["crc"] = {{"poly", 0x1021}, {"init", 0xFFFF}};
  j["control_hz"] = osc::params::kControlHz;
  j["types"] = json::array();
  j["fields"] = json::object();
  for (const pil::FrameInfo& f : pil::kFrames) {
    j["types"].push_back({{"name", f.name}, {"code", f.type}, {"payload", f.payload}});
    j["fields"][f.name] = client_fields(f);
  }
  j["command_flags"] = json::array();
  for (const char* n : pil::kCommandFlagNames) j["command_flags"].push_back(n);
  j["setpoint_flags"] = json::array();
  for (const char* n : pil::kSetpointFlagNames) j["setpoint_flags"].push_back(n);
  j["stream_max_period"] = pil::kStreamMaxPeriod;
  const auto lim = osc::CartesianLimits<double>::defaults();
  j["limits"] = {{"linear", {lim.linear.v, lim.linear.a, lim.linear.j}},
                 {"angular", {lim.angular.v, lim.angular.a, lim.angular.j}}};
  j["verbs"] = names<osc::MotionVerb>();
  j["motion_states"] = names<osc::MotionState>();
  j["reasons"] = names<osc::MotionReason>();
  j["outcomes"] = names<osc::CommandOutcome>();
  j["stop_categories"] = names<osc::StopCategory>();
  j["completions"] = names<osc::MotionCompletion>();
  j["identify_statuses"] = json::array();
  for (const char* n : osc::kIdentifyStatusNames) j["identify_statuses"].push_back(n);
  j["poses"] = json::array();
  for (int i = 0; i < osc::robot::kNamedPoseCount; ++i) j["poses"].push_back(osc::robot::kNamedPoses[i].name);
  j["faults"] = json::array();
  for (int i = 0; i < osc::kFaultCount; ++i) j["faults"].push_back(osc::kFaultNames[i]);
  j["parameters"] = parameters(false);
  j["capture"] = capture(false);
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  const bool client = argc == 2 && std::string(argv[1]) == "--client";
  if (argc > 1 && !client) {
    std::fprintf(stderr,
                 "usage: %s [--client]  (prints the link protocol's facts as JSON; --client: what a client of the "
                 "command protocol needs)\n",
                 argv[0]);
    return 2;
  }
  if (client) {
    std::cout << client_protocol().dump(1) << "\n";
    return 0;
  }
  json j;
  j["sync"] = {pil::kSync0, pil::kSync1};
  j["overhead"] = pil::kOverhead;
  j["max_frame"] = pil::kMaxFrame;
  j["types"] = json::array();
  for (const pil::FrameInfo& f : pil::kFrames) {
    const std::string from = f.from;
    j["types"].push_back({{"name", f.name},
                          {"code", f.type},
                          {"payload", f.payload},
                          {"from", from},
                          {"to", from == "host" ? "firmware" : "host"},
                          {"when", f.when}});
    j[std::string(f.name) + "_fields"] = fields(f.fields, f.field_count);
  }
  j["hello_seq"] = pil::kHelloSeq;
  const char check[] = "123456789";
  j["crc"] = {
      {"poly", 0x1021}, {"init", 0xFFFF}, {"check", pil::crc16(reinterpret_cast<const std::uint8_t*>(check), 9)}};
  j["inject"] = {{"non_finite", pil::kInjectNonFinite},
                 {"overrun", pil::kInjectOverrun},
                 {"trace", pil::kConfigTrace},
                 {"state_frames", pil::kConfigStateFrames},
                 {"start_disabled", pil::kConfigStartDisabled},
                 {"adaptation_shift", pil::kConfigAdaptationShift},
                 {"adaptation_mask", pil::kConfigAdaptationMask},
                 {"no_compensation", pil::kConfigNoCompensation}};
  const osc::CurrentMonitor& monitor = osc::robot::kDriveTrain.current;
  j["drive"] = {{"fault_lines", pil::kDriveFaultLines},
                {"currents_valid", pil::kDriveCurrentsValid},
                {"adc_bits", monitor.bits},
                {"range", monitor.range}};
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
  j["command"] = command_protocol();
  std::cout << j.dump(1) << "\n";
  return 0;
}
