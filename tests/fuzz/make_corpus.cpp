// Writes the seed corpora of the fuzz targets: fuzz_make_corpus DIR writes DIR/<target>/<seed>.
// The seeds are small, valid inputs in each target's input format (see the target's comment),
// chosen to start the fuzzer where the interesting code runs: well-formed frames, a controller
// running in kRun, each command-line option. Regenerate after a change of the link protocol or of
// a target's input format, and commit the result (docs/fuzzing.md).
#include <cstdint>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "osc/link/frames.hpp"
#include "osc/link/param_frames.hpp"
#include "osc/runtime/motion_commands.hpp"

namespace {

using Bytes = std::vector<std::uint8_t>;
std::filesystem::path g_root;

void put(const std::string& target, const std::string& name, const Bytes& b) {
  const auto dir = g_root / target;
  std::filesystem::create_directories(dir);
  std::ofstream f(dir / name, std::ios::binary);
  f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  if (!f) {
    std::fprintf(stderr, "cannot write %s\n", (dir / name).c_str());
    std::exit(1);
  }
}

void u32(Bytes& b, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void append(Bytes& b, const Bytes& x) { b.insert(b.end(), x.begin(), x.end()); }

Bytes sensor(std::uint32_t seq, std::int32_t c, std::uint8_t inject = 0) {
  pil::SensorFrame f;
  f.seq = seq;
  for (int i = 0; i < pil::kJoints; ++i) f.counts[i] = c * (i + 1);
  f.inject = inject;
  std::uint8_t buf[pil::kMaxFrame];
  return Bytes(buf, buf + pil::encode(f, buf));
}

Bytes actuator(std::uint32_t seq, std::uint8_t state, std::uint32_t faults) {
  pil::ActuatorFrame a;
  a.seq = seq;
  for (int i = 0; i < pil::kJoints; ++i) a.codes[i] = (i % 2 ? -1 : 1) * 100 * (i + 1);
  a.state = state;
  a.faults = faults;
  a.step_cycles = 22000;
  a.max_cycles = 23000;
  a.mean_cycles = 21000;
  a.tick_max_cycles = 30000;
  a.stack_used = 1234;
  for (int i = 0; i < 3 * pil::kJoints; ++i) a.theta_hat[i] = 0.5f * static_cast<float>(i);
  for (int i = 0; i < pil::kJoints; ++i) a.tau_f_hat[i] = -0.25f * static_cast<float>(i);
  std::uint8_t buf[pil::kMaxFrame];
  return Bytes(buf, buf + pil::encode(a, buf));
}

Bytes args(const std::vector<std::string>& a) {
  Bytes b;
  for (size_t i = 0; i < a.size(); ++i) {
    if (i) b.push_back(0);
    b.insert(b.end(), a[i].begin(), a[i].end());
  }
  return b;
}

void frames() {
  // Raw mode (first byte even): frames as they travel.
  Bytes b{0};
  append(b, sensor(0, 5));
  put("fuzz_frames", "raw_sensor", b);
  b = {0};
  append(b, actuator(7, 1, 0));
  put("fuzz_frames", "raw_actuator", b);
  b = {0, 0x12, pil::kSync0, 0x00, pil::kSync0, pil::kSync0};
  append(b, sensor(1, -3));
  Bytes bad = sensor(2, 4);
  bad[10] ^= 0x10;  // checksum mismatch
  append(b, bad);
  append(b, sensor(3, 9));
  put("fuzz_frames", "raw_garbage_between", b);
  // Structured mode (first byte odd): op, garbage, fields.
  b = {1, 0x02, 0xA5, 0x5A};  // a sensor frame after two garbage bytes, its fields
  for (int i = 0; i < pil::kSensorPayload; ++i) b.push_back(static_cast<std::uint8_t>(i));
  b.push_back(0x18);  // actuator frame, one bit flipped
  for (int i = 0; i < 137; ++i) b.push_back(static_cast<std::uint8_t>(3 * i));
  put("fuzz_frames", "structured", b);
}

void node() {
  // ops: 1 = well-formed sensor frame with the expected sequence number and six small steps,
  // 3 = link timeout, 0 = raw bytes.
  Bytes b;
  for (int t = 0; t < 30; ++t) {
    b.push_back(1);
    for (int i = 0; i < 6; ++i) b.push_back(static_cast<std::uint8_t>(t % 3 == 0 ? 4 : 0xFC));
  }
  put("fuzz_node", "steady_run", b);
  Bytes c = b;
  c.resize(7 * 5);
  c.push_back(1 | 16);  // inject field from the input: overrun
  for (int i = 0; i < 6; ++i) c.push_back(0);
  c.push_back(pil::kInjectOverrun);
  put("fuzz_node", "overrun", c);
  c.resize(7 * 5);
  c.push_back(1 | 8);  // sequence number from the input: a gap
  u32(c, 99);
  for (int i = 0; i < 6; ++i) c.push_back(0);
  put("fuzz_node", "sequence_gap", c);
  c.resize(7 * 5);
  c.push_back(3);
  put("fuzz_node", "timeout", c);
  c.resize(7 * 5);
  const Bytes raw = sensor(5, 0, static_cast<std::uint8_t>(pil::kConfigNoCompensation));
  c.push_back(0);
  c.push_back(static_cast<std::uint8_t>(raw.size()));
  append(c, raw);
  put("fuzz_node", "raw_frame", c);
  Bytes first;
  const Bytes cfg = sensor(0, 0, static_cast<std::uint8_t>(pil::config_adaptation(osc::AdaptationLaw{})));
  first.push_back(0);
  first.push_back(static_cast<std::uint8_t>(cfg.size()));
  append(first, cfg);
  append(first, b);
  put("fuzz_node", "configured_run", first);
  // op bit 5: the amplifiers' currents and drive byte from the input. Readings that follow the codes
  // loosely (the drive check's tracking and dither), then a reading off the ADC's scale; a fault line.
  Bytes d;
  for (int t = 0; t < 20; ++t) {
    d.push_back(1 | 32);
    for (int i = 0; i < 6; ++i) d.push_back(static_cast<std::uint8_t>(t % 2 ? 4 : 0xFC));
    for (int i = 0; i < 6; ++i) {
      const int reading = t == 19 && i == 2 ? 2047 : (t % 3) * (i - 2);
      d.push_back(static_cast<std::uint8_t>(reading & 0xFF));
      d.push_back(static_cast<std::uint8_t>((reading >> 8) & 0xFF));
    }
    d.push_back(pil::drive_byte(0, true));
  }
  put("fuzz_node", "drive_readings", d);
  Bytes lines = b;
  lines.resize(7 * 10);
  lines.push_back(1 | 32);
  for (int i = 0; i < 6; ++i) lines.push_back(0);
  for (int i = 0; i < 12; ++i) lines.push_back(0);
  lines.push_back(pil::drive_byte(1u << 3, false));
  put("fuzz_node", "amp_fault_line", lines);
}

void encoder() {
  // Byte 0 even: the robot's encoder resolution. Then per tick: a mode byte and six small steps
  // (mode 1), and its extra bytes for the other modes.
  Bytes b{0};
  for (int t = 0; t < 40; ++t) {
    b.push_back(1);
    for (int i = 0; i < 6; ++i) b.push_back(static_cast<std::uint8_t>(t % 2 ? 8 : 0xF8));
  }
  put("fuzz_encoder", "steady_run", b);
  Bytes c = b;
  c.resize(1 + 7 * 10);
  c.push_back(3 | (2 << 2) | (2 << 5));  // joint 3 at the plausible step + 1
  for (int i = 0; i < 6; ++i) c.push_back(0);
  c.push_back(2);
  put("fuzz_encoder", "edge_step", c);
  Bytes r{0};
  for (std::uint8_t off : {1, 2}) {  // joint 2 at the plausible maximum, then one count beyond
    r.push_back(3 | (1 << 2) | (1 << 5));
    for (int i = 0; i < 6; ++i) r.push_back(0);
    r.push_back(off);
  }
  put("fuzz_encoder", "edge_range", r);
  Bytes d{0, 2};  // INT32_MAX on joint 1 at the first sample
  for (int i = 0; i < 6; ++i) d.push_back(0);
  u32(d, 0x7FFFFFFF);
  put("fuzz_encoder", "int32_max_first", d);
  Bytes e{1};  // another resolution: 4096 counts per motor revolution
  u32(e, 4096 - 100);
  for (int t = 0; t < 20; ++t) {
    e.push_back(1);
    for (int i = 0; i < 6; ++i) e.push_back(static_cast<std::uint8_t>(t % 2 ? 16 : 0xF0));
  }
  put("fuzz_encoder", "resolution_4096", e);
}

void supervisor() {
  // Two bytes a step: flags (bit 7 ready; bits 0-1 fault form), argument.
  put("fuzz_supervisor", "init_run", {0x00, 0, 0x80, 0, 0x80, 0, 0x80, 0});
  put("fuzz_supervisor", "run_then_fault", {0x80, 0, 0x80, 0, 0x81, 3, 0x80, 0, 0x81, 5});
  put("fuzz_supervisor", "word_faults", {0x80, 0, 0x83, 0, 0x00, 0x01, 0x00, 0x80, 0x80, 0});
  // Regression: bit 20 is outside the fault catalogue; it used to be masked off (torque stayed on).
  put("fuzz_supervisor", "unknown_fault_bit", {0x80, 0, 0x80, 0, 0x81, 20, 0x80, 0});
}

void pil_client() {
  // Byte 0 even: raw stream after 8 bytes of read sizes.
  Bytes b{0, 1, 7, 30, 255, 2, 64, 9, 100};
  append(b, actuator(pil::kHelloSeq, 0, 0));
  append(b, actuator(0, 1, 0));
  append(b, actuator(1, 2, 1u << 6));
  put("fuzz_pil_client", "raw_actuators", b);
  Bytes c{0, 3, 3, 3, 3, 3, 3, 3, 3, 0x11};
  append(c, actuator(4, 1, 0));
  append(c, sensor(5, 1));
  Bytes bad = actuator(6, 1, 0);
  bad[20] ^= 1;
  append(c, bad);
  put("fuzz_pil_client", "raw_errors", c);
  // Byte 0 odd: frames built from the input (op, garbage, fields).
  Bytes d{1, 255, 255, 255, 255, 255, 255, 255, 255, 0x01, 0x5A};
  for (int i = 0; i < 137; ++i) d.push_back(static_cast<std::uint8_t>(i));
  d.push_back(0x08);  // a sensor frame, its fields
  for (int i = 0; i < pil::kSensorPayload; ++i) d.push_back(static_cast<std::uint8_t>(7 * i));
  put("fuzz_pil_client", "structured", d);
}

// fuzz_command's structured frames: op, id, verb, flags, then 12 numbers, as 16-bit integers (op bit
// 3 clear: positions in 1/2048 m, angles in 1/4096 rad, limits in 1/50000 of their maximum) or as
// raw f32 bits (op bit 3 set).
struct Command {
  std::uint32_t id;
  osc::MotionVerb verb;
  std::uint8_t flags;
  double position[3], rpy[3];
  double limits[6];  ///< fractions of the configured maxima (16-bit form), or values (raw form)
};

void u16(Bytes& b, int v) {
  b.push_back(static_cast<std::uint8_t>(v & 0xFF));
  b.push_back(static_cast<std::uint8_t>((v >> 8) & 0xFF));
}
void f32(Bytes& b, double v) {
  const float f = static_cast<float>(v);
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  u32(b, u);
}

void command_op(Bytes& b, std::uint8_t op, const Command& c) {
  b.push_back(op);
  for (int k = op & 7; k > 0; --k) b.push_back(0x5A);  // garbage before the frame
  u32(b, c.id);
  b.push_back(static_cast<std::uint8_t>(c.verb));
  b.push_back(c.flags);
  const bool raw = (op & 8) != 0;
  for (double p : c.position) raw ? f32(b, p) : u16(b, static_cast<int>(std::lround(p * 2048)));
  for (double r : c.rpy) raw ? f32(b, r) : u16(b, static_cast<int>(std::lround(r * 4096)));
  for (double l : c.limits) raw ? f32(b, l) : u16(b, static_cast<int>(std::lround(l * 50000)));
}

void command() {
  using osc::MotionVerb;
  constexpr std::uint8_t kRel = pil::kFlagRelative, kRpy = pil::kFlagHasRpy, kRep = pil::kFlagReplace,
                         kLim = pil::kFlagHasLimits;
  const Command rel{1, MotionVerb::kMoveTo, kRel, {0.05, -0.02, 0.01}, {0, 0, 0}, {}};
  const Command abs{
      2, MotionVerb::kMoveTo, kRpy | kLim, {0.55, 0.05, 0.25}, {0.2, -0.1, 0.4}, {0.5, 0.5, 0.5, 0.8, 0.8, 0.8}};
  const Command turn{3, MotionVerb::kMoveTo, kRel | kRpy, {0, 0, 0}, {0.0, 0.3, -0.2}, {}};
  const Command retarget{4, MotionVerb::kMoveTo, kRel | kRep, {-0.03, 0.04, 0.0}, {0, 0, 0}, {}};
  // Byte 0: bit 0 structured, bits 1-2 the generator (0 holding, 1 a move running, 2 the paper's
  // motion), bits 3-7 the tick in 50 ms.
  for (int how = 0; how < 3; ++how) {
    Bytes b{static_cast<std::uint8_t>(1 | (how << 1) | (4 << 3))};
    command_op(b, 0, rel);
    command_op(b, 2, abs);
    command_op(b, 0, turn);
    command_op(b, 0x10, rel);  // one bit flipped
    command_op(b, 0, retarget);
    put("fuzz_command", std::string("moves_") + "0mp"[how], b);
  }
  Bytes verbs{1};
  for (int v = 0; v <= 7; ++v) command_op(verbs, 0, {static_cast<std::uint32_t>(10 + v), MotionVerb(v), 0, {}, {}, {}});
  put("fuzz_command", "verbs", verbs);
  // Raw numbers at the edges: tiny limits over a long move, bounds, NaN, a flag outside the list.
  Bytes edges{1};
  command_op(
      edges, 8,
      {20, MotionVerb::kMoveTo, kRel | kLim, {10, -10, 10}, {0, 0, 0}, {1e-30, 1e-30, 1e-30, 1e-30, 1e-30, 1e-30}});
  command_op(edges, 8, {21, MotionVerb::kMoveTo, kRel | kLim, {10, 0, 0}, {0, 0, 0}, {0.1, 1e-20, 2.5, 0.5, 1, 10}});
  command_op(edges, 8, {22, MotionVerb::kMoveTo, kRpy, {0.5, 0.1, 0.3}, {6.2831850, -6.2831850, 0}, {}});
  command_op(edges, 8, {23, MotionVerb::kMoveTo, kRel, {std::nan(""), 0, 0}, {0, 0, 0}, {}});
  command_op(edges, 8, {24, MotionVerb::kMoveTo, 0x10, {0, 0, 0}, {0, 0, 0}, {}});
  put("fuzz_command", "edges", edges);
  Bytes queue{1};  // more moves than the queue holds
  for (int k = 0; k < 18; ++k)
    command_op(queue, 0,
               {static_cast<std::uint32_t>(100 + k), MotionVerb::kMoveTo, kRel, {0.002, 0, 0}, {0, 0, 0}, {}});
  put("fuzz_command", "queue_full", queue);
  // Raw: encoded command frames among other bytes and frames.
  Bytes raw{0, 0x00, pil::kSync0};
  for (const Command* c : {&rel, &turn, &retarget}) {
    pil::CommandFrame f;
    f.id = c->id;
    f.verb = static_cast<std::uint8_t>(c->verb);
    f.flags = c->flags;
    for (int i = 0; i < 3; ++i)
      f.position[i] = static_cast<float>(c->position[i]), f.rpy[i] = static_cast<float>(c->rpy[i]);
    std::uint8_t buf[pil::kMaxFrame];
    append(raw, Bytes(buf, buf + pil::encode(f, buf)));
    append(raw, sensor(3, 1));
  }
  put("fuzz_command", "raw_frames", raw);
  // A stream running (how 3): its setpoints (op bits 5-6: 1 plain, 2 with velocity; the selector byte's
  // bit 0: the stream's id 3000), the last with end; one with a NaN velocity, one of another stream.
  Bytes stream{static_cast<std::uint8_t>(1 | (3 << 1))};
  const auto setpoint_op = [&stream](std::uint8_t op, int n, std::uint8_t flags, bool mine) {
    stream.push_back(op);
    stream.push_back(mine ? 1 : 0);
    if (!mine) u32(stream, 77);
    stream.push_back(flags);
    const bool raw = (op & 8) != 0;
    const double pos[3] = {0.001 * n, -0.0005 * n, 0}, rpy[3] = {0, 0, 0.002 * n};
    for (double p : pos) raw ? f32(stream, p) : u16(stream, static_cast<int>(std::lround(p * 2048)));
    for (double r : rpy) raw ? f32(stream, r) : u16(stream, static_cast<int>(std::lround(r * 4096)));
    if ((op >> 5) == 2)
      for (double v : {0.02, -0.01, 0.0, 0.0, 0.0, 0.04})
        raw ? f32(stream, v) : u16(stream, static_cast<int>(std::lround(v * 2048)));
  };
  for (int n = 1; n <= 4; ++n) setpoint_op(0x20, n, pil::kSetpointHasRpy, true);
  for (int n = 5; n <= 8; ++n) setpoint_op(0x40, n, pil::kSetpointHasRpy, true);
  setpoint_op(0x40, 9, 0, false);
  stream.push_back(0x48);  // raw numbers, a NaN velocity
  stream.push_back(1);
  stream.push_back(0);
  for (int i = 0; i < 6; ++i) f32(stream, 0.0);
  for (int i = 0; i < 6; ++i) f32(stream, i == 2 ? std::nan("") : 0.0);
  setpoint_op(0x40, 10, pil::kSetpointHasRpy | pil::kSetpointEnd, true);
  put("fuzz_command", "stream_setpoints", stream);
}

void cli() {
  put("fuzz_cli", "none", {});
  put("fuzz_cli", "help", args({"--help"}));
  put("fuzz_cli", "numbers",
      args({"--duration", "30", "--model-error", "-0.1", "--encoder-cpr", "4096", "--substep", "5e-5", "--delay", "0",
            "--final-window", "60"}));
  put("fuzz_cli", "words",
      args({"--mode", "adaptive", "--friction", "corke", "--scalar", "float", "--adaptation", "paper", "--no-csv",
            "--no-progress"}));
  put("fuzz_cli", "files", args({"--qemu", "--elf", "fw.elf", "--json", "s.json", "--csv-dir", "out dir"}));
  put("fuzz_cli", "bad_value", args({"--duration", "1e999"}));
  put("fuzz_cli", "missing_value", args({"--mode"}));
}

}  // namespace

/// fuzz_param: byte 0 the scalar and the torque; then requests of op, index, element, how, value.
void param() {
  const auto request = [](Bytes& b, std::uint8_t op, int index, int element, double value) {
    b.push_back(op);
    b.push_back(static_cast<std::uint8_t>(index));
    b.push_back(static_cast<std::uint8_t>(element));
    b.push_back(1);  // raw f32 bits
    float v = static_cast<float>(value);
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    u32(b, bits);
  };
  for (int scalar = 0; scalar < 3; ++scalar) {
    // Every parameter's every element read, then set to its default; a save, a reset, a load.
    Bytes b{static_cast<std::uint8_t>(scalar)};
    for (int i = 0; i < osc::kParamCount; ++i)
      for (int e = 0; e < osc::kParams[i].count; ++e) {
        request(b, pil::kParamOpGet, i, e, 0);
        request(b, pil::kParamOpSet, i, e, osc::param_default(i, e));
      }
    for (std::uint8_t op : {pil::kParamOpSave, pil::kParamOpReset, pil::kParamOpLoad, pil::kParamOpCheck})
      request(b, op, 0, 0, 0);
    put("fuzz_param", "defaults_" + std::to_string(scalar), b);
    // Gains at the edge of the observer's stability, out of range, NaN; the torque on.
    Bytes edge{static_cast<std::uint8_t>(scalar | 4)};
    const int k = osc::param_index("k"), ki = osc::param_index("ki");
    for (double v : {1990.0, 2000.0, 2100.0, 1e5, std::nan(""), -1.0}) request(edge, pil::kParamOpSet, k, 0, v);
    for (double v : {4000.0, 5000.0, 3e5, 1e6}) request(edge, pil::kParamOpSet, ki, 3, v);
    request(edge, pil::kParamOpSet, osc::param_index("collision_threshold"), 5, 21.3);
    put("fuzz_param", "edges_" + std::to_string(scalar), edge);
    edge[0] = static_cast<std::uint8_t>(scalar);
    put("fuzz_param", "edges_off_" + std::to_string(scalar), edge);
  }
}

/// fuzz_capture: steps of a capture frame (an even byte, then its 37 payload bytes) or ticks (an odd byte, how
/// many, the faults' change).
void capture() {
  const auto request = [](Bytes& b, std::uint8_t op, std::initializer_list<int> signals, std::uint8_t trigger,
                          std::uint32_t pre, std::uint32_t offset = 0, float level = 0) {
    pil::CaptureFrame f;
    f.op = op;
    f.channels = static_cast<std::uint8_t>(signals.size());
    int c = 0;
    for (int s : signals) {
      f.signal[c] = static_cast<std::uint8_t>(s);
      f.element[c] = static_cast<std::uint8_t>(c % 6);
      ++c;
    }
    f.trigger = trigger;
    f.level = level;
    f.pre = pre;
    f.divider = 1;
    f.offset = offset;
    std::uint8_t buf[pil::kMaxFrame];
    pil::encode(f, buf);
    b.push_back(0);
    b.insert(b.end(), buf + 4, buf + 4 + pil::kCapturePayload);
  };
  const auto ticks = [](Bytes& b, int n, std::uint8_t how) {
    b.push_back(1);
    b.push_back(static_cast<std::uint8_t>(n - 1));
    b.push_back(how);
  };
  // By hand: arm two channels, a pre-trigger, the trigger, the rest, every read.
  Bytes manual;
  request(manual, pil::kCaptureOpArm, {pil::kCaptureSignalResidual, pil::kCaptureSignalTorque},
          pil::kCaptureTriggerManual, 100);
  ticks(manual, 200, 0);
  request(manual, pil::kCaptureOpTrigger, {}, 0, 0);
  for (int k = 0; k < 9; ++k) ticks(manual, 256, 0);
  for (std::uint32_t offset = 0; offset <= 4096; offset += 40 * 8)
    request(manual, pil::kCaptureOpRead, {}, 0, 0, offset);
  put("fuzz_capture", "manual", manual);
  // A fault's trigger over eight channels; a level's; refusals.
  Bytes fault;
  request(fault, pil::kCaptureOpArm, {0, 1, 2, 3, 4, 5, 6, 7}, pil::kCaptureTriggerFault, 511);
  ticks(fault, 100, 0);
  ticks(fault, 256, 1);
  ticks(fault, 256, 0);
  request(fault, pil::kCaptureOpRead, {}, 0, 0, 4000);
  request(fault, pil::kCaptureOpArm, {pil::kCaptureSignalError}, pil::kCaptureTriggerRising, 10, 0, 0.05f);
  for (int k = 0; k < 20; ++k) ticks(fault, 256, 0x80);
  request(fault, pil::kCaptureOpArm, {pil::kCaptureSignalCount}, pil::kCaptureTriggerCount, 5000);
  request(fault, pil::kCaptureOpRead, {}, 0, 0, 0);
  put("fuzz_capture", "fault_level", fault);
}

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_corpus DIR (e.g. tests/fuzz/corpus)\n");
    return 2;
  }
  g_root = argv[1];
  frames();
  node();
  encoder();
  supervisor();
  command();
  param();
  capture();
  pil_client();
  cli();
  return 0;
}
