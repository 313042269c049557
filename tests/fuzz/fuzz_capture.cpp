// Fuzz target: the on-board capture (osc/link/capture.hpp, through the command port's receive and
// after_tick) against a control task in float, whose fault bits and command outcomes the input sets.
// The input is a sequence of steps, byte 0 of each its kind: even, a capture frame of the next 37 bytes
// as its payload (every field raw: ops, channels, signals, elements, triggers outside their lists, any
// level's bits, any pre, divider and offset); odd, ticks (byte 1: how many, 1 to 256), with byte 2's bits
// as the latched faults' change and whether a command is accepted in the first.
//
// Invariants:
//  - every capture frame gets exactly one capture_data frame, its id and op echoed, its status and state
//    names of their lists; a refused arm leaves it idle; an accepted one armed;
//  - a read answers only a done capture, with at most kCaptureChunk values, none beyond depth x channels,
//    each finite (the task's signals are);
//  - a done capture holds at most its buffer's share per channel and at least the samples after its
//    trigger; pre is at most the pre asked; first_tick = trigger_tick - pre x divider;
//  - ASan: no access outside the ring.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "fuzz_util.hpp"
#include "osc/link/command_port.hpp"
#include "osc/robot.hpp"

namespace {

using namespace osc;
using S = float;

struct Fixture {
  std::unique_ptr<ControlTask<S>> task = std::make_unique<ControlTask<S>>();
  CommandPort<S> port;
  std::vector<float> ring = std::vector<float>(pil::kCaptureValues);
};

struct Armed {
  std::uint32_t pre = 0;
  int channels = 0;
};

void frame(Fixture& fx, fuzz::Input& in, std::uint32_t id, Armed& armed) {
  std::uint8_t payload[pil::kCapturePayload];
  for (std::uint8_t& b : payload) b = in.u8();
  std::uint8_t buf[pil::kMaxFrame];
  buf[0] = pil::kSync0, buf[1] = pil::kSync1, buf[2] = pil::kCaptureFrame, buf[3] = pil::kCapturePayload;
  std::memcpy(buf + 4, payload, sizeof payload);
  for (int i = 0; i < 4; ++i) buf[4 + i] = static_cast<std::uint8_t>(id >> (8 * i));  // the id field
  const std::uint16_t crc = pil::crc16(buf + 2, pil::kCapturePayload + 2);
  buf[4 + pil::kCapturePayload] = static_cast<std::uint8_t>(crc & 0xFF);
  buf[5 + pil::kCapturePayload] = static_cast<std::uint8_t>(crc >> 8);
  pil::Parser parser;
  pil::CaptureFrame f;
  int answers = 0;
  pil::CaptureDataFrame a{};
  for (int k = 0; k < pil::kCapturePayload + pil::kOverhead; ++k) {
    if (parser.feed(buf[k]) != pil::Parser::kFrame) continue;
    FUZZ_CHECK(parser.decode(f));
    FUZZ_CHECK(fx.port.receive(*fx.task, parser, [&](const std::uint8_t* b, int len) {
      pil::Parser p;
      for (int j = 0; j < len; ++j)
        if (p.feed(b[j]) == pil::Parser::kFrame) {
          FUZZ_CHECK(p.decode(a));
          ++answers;
        }
    }));
  }
  FUZZ_CHECK(answers == 1);
  FUZZ_CHECK(a.id == id && a.op == f.op);
  FUZZ_CHECK(a.status < pil::kCaptureStatusCount && a.state < pil::kCaptureStateCount);
  if (f.op == pil::kCaptureOpArm) {
    FUZZ_CHECK(a.state == (a.status == pil::kCaptureStatusOk ? pil::kCaptureStateArmed : pil::kCaptureStateIdle));
    if (a.status == pil::kCaptureStatusOk) armed = {f.pre, f.channels};
  }
  if (a.state == pil::kCaptureStateDone) {
    const std::uint32_t depth = pil::kCaptureValues / static_cast<std::uint32_t>(armed.channels);
    FUZZ_CHECK(a.channels == armed.channels && a.depth <= depth && a.pre <= armed.pre);
    FUZZ_CHECK(a.depth >= depth - armed.pre);  // the samples after the trigger, and the trigger's
    FUZZ_CHECK(a.first_tick == a.trigger_tick - a.pre * a.divider);
  }
  if (f.op == pil::kCaptureOpRead && a.status == pil::kCaptureStatusOk) {
    FUZZ_CHECK(a.state == pil::kCaptureStateDone && a.count <= pil::kCaptureChunk);
    FUZZ_CHECK(a.offset + a.count <= a.depth * a.channels);
    for (int v = 0; v < a.count; ++v) FUZZ_CHECK(std::isfinite(a.values[v]));
  }
}

void ticks(Fixture& fx, fuzz::Input& in) {
  const int n = in.u8() + 1;
  const std::uint8_t how = in.u8();
  ControlTask<S>& t = *fx.task;
  t.sup.latched ^= (how & 0x7Fu) << 3;  // a few fault bits set or cleared
  t.report.outcome = (how & 0x80u) ? CommandOutcome::kAccepted : CommandOutcome::kNone;
  for (int k = 0; k < n; ++k) {
    t.last.e(1) = static_cast<S>(t.tick % 1000) * S(1e-4);  // a ramp for the level triggers
    ++t.tick;
    fx.port.after_tick(t, [](const std::uint8_t*, int) {});
    t.report = {};
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Fixture* fx = [] {
    auto* f = new Fixture();
    f->task->init(Model<S>::of(robot::kArm), Gains<S>::paper(), FrictionMode::kAdaptive,
                  joint_vector<S>(robot::kQStart), 0, TaskStart::kDisabled);
    return f;
  }();
  fx->port.capture.attach(fx->ring.data(), pil::kCaptureValues);  // idle: each input starts afresh
  fx->task->tick = 0;
  fx->task->sup.latched = 0;
  fuzz::Input in(data, size);
  Armed armed;
  std::uint32_t id = 0;
  while (in.left() >= 3) {
    if (in.u8() % 2 == 0)
      frame(*fx, in, ++id, armed);
    else
      ticks(*fx, in);
  }
  return 0;
}
