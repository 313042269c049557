// Fuzz target: the firmware's PIL node (osc/link/node.hpp), osc::PilNode<double, FakeBoard>, driven
// by fuzzed link traffic: raw bytes, well-formed sensor frames with fuzzed encoder counts, amplifier
// currents and drive bytes (fault lines: a drive_fault; readings: the drive check), sequence numbers and
// fault-injection bits, and link timeouts. FakeBoard captures what the node writes.
//
// Invariants:
//  - hello() writes one actuator frame: sequence kHelloSeq, zero codes, state kInit;
//  - on_byte() and on_timeout() ask for a tick exactly when a frame ends (valid but for the command
//    protocol's, or bad, or cut short), as an independent parser fed the same bytes sees it, and in
//    the same order (several in one byte after a resynchronisation); every tick writes exactly one
//    actuator frame, nothing else, and it parses with a valid checksum;
//  - every code written is within [-kDacMaxCode, kDacMaxCode]; the frame's state and fault bits are
//    the node's supervisor's; whenever that state is not kRun every code is 0, and the board's fault
//    line is on exactly in kFault;
//  - a corrupt header, length or checksum, a frame of the wrong type, a sequence gap, junk after a
//    valid frame or a link timeout gives zero codes in the very next actuator frame (repeated errors
//    latch a link fault: tests/firmware/link/test_link.cpp); once in kFault the node never leaves it;
//  - the actuator frame answering a valid sensor frame carries its sequence number.
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "fuzz_util.hpp"
#include "osc/link/node.hpp"
#include "osc/robot.hpp"

namespace {

struct FakeBoard {
  static inline std::vector<std::uint8_t> out;
  static inline std::uint32_t clock = 0;
  static inline bool fault_line = false;
  static void link_write(const std::uint8_t* p, int n) { out.insert(out.end(), p, p + n); }
  static std::uint32_t cycles() { return clock += 1000; }
  static std::uint32_t stack_used() { return 0; }
  static void burn(std::uint32_t c) { clock += c; }
  static void fault_output(bool active) { fault_line = active; }
};
static_assert(osc::PilBoard<FakeBoard>);

using Node = osc::PilNode<double, FakeBoard>;
constexpr std::uint32_t kPeriod = 1000000;
constexpr int kMaxTicks = 100;

/// The frames the board received since the last call: valid frames only; the actuator frame first
/// and once when `tick` (then the command protocol's answer, state and trace frames, docs/protocol.md
/// "On the PIL link"), none when not (an answer the node gives at once: a command refused before
/// any tick). Returns the actuator frame.
bool g_cleared = false;  // the frames taken last held an accepted clear's answer
pil::ActuatorFrame take_frames(bool tick) {
  pil::Parser p;
  pil::ActuatorFrame a;
  g_cleared = false;
  int frames = 0, actuators = 0;
  for (std::uint8_t b : FakeBoard::out) {
    const pil::Parser::Result r = p.feed(b);
    FUZZ_CHECK(r == pil::Parser::kPending || r == pil::Parser::kFrame);
    if (r != pil::Parser::kFrame) continue;
    const bool actuator = p.decode(a);
    FUZZ_CHECK(actuator == (tick && frames == 0));  // the tick's actuator frame comes first
    FUZZ_CHECK(actuator || p.type() == pil::kAnswerFrame || p.type() == pil::kStateFrame ||
               p.type() == pil::kTraceFrame);
    pil::AnswerFrame ans;
    if (p.decode(ans) && ans.verb == static_cast<std::uint8_t>(osc::MotionVerb::kClear) &&
        ans.outcome == static_cast<std::uint8_t>(osc::CommandOutcome::kAccepted))
      g_cleared = true;
    actuators += actuator;
    ++frames;
  }
  FUZZ_CHECK(actuators == (tick ? 1 : 0));
  FUZZ_CHECK(!p.in_frame());
  FakeBoard::out.clear();
  return a;
}
pil::ActuatorFrame take_frame() { return take_frames(true); }

struct Driver {
  explicit Driver(Node& n) : node(n) {}
  Node& node;
  pil::Parser shadow;              // the specification's view of the byte stream
  std::uint32_t expected_seq = 0;  // the sequence number the node expects next
  std::uint32_t last_seq = 0;      // sequence number of the latest valid sensor frame
  bool link_fault_due = false;     // a link fault the next actuator frame must show
  bool faulted = false;            // kFault seen
  bool synced = false;             // the last thing parsed was a valid sensor frame
  bool seq_tracked = true;         // expected_seq is known (a timeout may or may not use one up)
  bool seq_check = false;          // the next answer must carry last_seq
  int ticks = 0;

  void check_tick() {
    const pil::ActuatorFrame a = take_frame();
    const osc::Supervisor& sup = node.task.sup;
    FUZZ_CHECK(a.state == static_cast<std::uint8_t>(sup.state));
    FUZZ_CHECK(a.faults == sup.latched);
    if (seq_check) FUZZ_CHECK(a.seq == last_seq);  // the answer to a valid frame carries its number
    seq_check = false;
    for (std::int32_t c : a.codes) FUZZ_CHECK(c >= -osc::kDacMaxCode && c <= osc::kDacMaxCode);
    if (sup.state != osc::SupervisorState::kRun)
      for (std::int32_t c : a.codes) FUZZ_CHECK(c == 0);
    FUZZ_CHECK(FakeBoard::fault_line == (sup.state == osc::SupervisorState::kFault));
    // Sticky, but for a clear accepted in this tick (its causes gone: the supervisor starts again).
    if (faulted && !g_cleared) FUZZ_CHECK(sup.state == osc::SupervisorState::kFault);
    if (link_fault_due) {
      for (std::int32_t c : a.codes) FUZZ_CHECK(c == 0);
      link_fault_due = false;
    }
    faulted = sup.state == osc::SupervisorState::kFault;
    ++ticks;
  }

  /// One shadow event, as the node must see it: whether it makes a tick due, and its bookkeeping.
  struct Event {
    pil::Parser::Result r;
    pil::FrameType type;
    bool sensor;  // a valid sensor frame (f)
    pil::SensorFrame f;
  };
  static bool command_protocol(pil::FrameType t) {
    return t == pil::kCommandFrame || t == pil::kSetpointFrame || t == pil::kSetpointVelocityFrame ||
           t == pil::kParamFrame || t == pil::kCaptureFrame;
  }
  /// Any frame that ends, valid or not, is answered at once, but a command protocol's (the port's:
  /// no tick, no link error); so is a header found bad and a frame cut short.
  static bool due_of(const Event& e) {
    return e.r != pil::Parser::kJunk && !(e.r == pil::Parser::kFrame && command_protocol(e.type));
  }
  std::vector<Event> drain(pil::Parser::Result r) {
    std::vector<Event> ev;
    for (; r != pil::Parser::kPending; r = shadow.next()) {
      Event e{r, shadow.type(), false, {}};
      if (r == pil::Parser::kFrame) e.sensor = shadow.decode(e.f);
      ev.push_back(e);
    }
    return ev;
  }
  /// An event's bookkeeping (the node's expectations after it).
  void note(const Event& e) {
    if (e.r == pil::Parser::kFrame && command_protocol(e.type)) {
      take_frames(false);  // the node may answer a command at once: a refusal no tick gives
      synced = true;
      return;
    }
    FUZZ_CHECK(FakeBoard::out.empty());
    if (e.r == pil::Parser::kJunk) {
      if (synced) link_fault_due = true;  // junk after a valid frame is an error of its own
      synced = false;
      return;
    }
    if (e.r != pil::Parser::kFrame || !e.sensor) {  // lost: bad, cut short, or a frame of the wrong type
      link_fault_due = true;
      synced = false;
      ++expected_seq;  // a lost frame uses up its sequence number
      return;
    }
    if (seq_tracked && e.f.seq != expected_seq) link_fault_due = true;
    expected_seq = e.f.seq + 1;
    last_seq = e.f.seq;
    seq_tracked = synced = seq_check = true;
  }
  /// The node's ticks interleaved with the shadow's events: each due() the node calls is the next
  /// event that makes a tick due (the events before it noted first); none is left over.
  template <class Run>
  void run(const std::vector<Event>& ev, Run&& node_run) {
    std::size_t next = 0;
    node_run([&] {
      while (next < ev.size() && !due_of(ev[next])) note(ev[next++]);
      FUZZ_CHECK(next < ev.size());  // a tick the shadow does not expect
      note(ev[next++]);
      node.tick();
      check_tick();
    });
    for (; next < ev.size(); ++next) {
      FUZZ_CHECK(!due_of(ev[next]));  // a tick the node did not ask for
      note(ev[next]);
    }
  }

  void byte(std::uint8_t b) {
    run(drain(shadow.feed(b)), [&](auto&& due) { node.on_byte(b, due); });
  }

  void timeout() {
    if (shadow.in_frame()) {
      run(drain(shadow.expire()), [&](auto&& due) { node.on_timeout(due); });
      return;
    }
    node.on_timeout();  // junk then nothing (a lost frame), or a silence: one tick either way
    if (!synced) ++expected_seq;
    seq_tracked = false;  // a silence uses no number, a lost frame one: unknown here
    link_fault_due = true;
    synced = false;
    node.tick();
    check_tick();
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  FakeBoard::out.clear();
  FakeBoard::clock = 0;
  FakeBoard::fault_line = false;
  auto node = std::make_unique<Node>();
  node->init(osc::joint_vector<double>(osc::robot::kQStart), osc::FrictionMode::kAdaptive, kPeriod);
  node->hello();
  {
    const pil::ActuatorFrame h = take_frame();
    FUZZ_CHECK(h.seq == pil::kHelloSeq);
    FUZZ_CHECK(h.state == static_cast<std::uint8_t>(osc::SupervisorState::kInit));
    for (std::int32_t c : h.codes) FUZZ_CHECK(c == 0);
  }
  Driver d(*node);
  std::int32_t counts[osc::kDof] = {};
  while (!in.empty() && d.ticks < kMaxTicks) {
    const std::uint8_t op = in.u8();
    switch (op & 3) {
      case 0: {  // raw bytes
        for (int k = in.u8() & 63; k > 0; --k) d.byte(in.u8());
        break;
      }
      case 1:
      case 2: {  // a well-formed sensor frame: small encoder steps, or (op & 4) any counts; (op & 32) currents
        pil::SensorFrame f;
        f.seq = (op & 8) ? in.u32() : d.expected_seq;
        for (int i = 0; i < osc::kDof; ++i)
          counts[i] = (op & 4) ? in.i32() : fuzz::wrap_add(counts[i], static_cast<std::int8_t>(in.u8()) / 4);
        for (int i = 0; i < osc::kDof; ++i) f.counts[i] = counts[i];
        if (op & 32) {  // the amplifiers' currents and drive byte (fault lines, valid bit) from the input
          for (std::int16_t& c : f.currents) c = static_cast<std::int16_t>(in.u16());
          f.drive = in.u8();
        }
        f.inject = (op & 16) ? in.u8() : 0;
        std::uint8_t buf[pil::kMaxFrame];
        const int n = pil::encode(f, buf);
        for (int i = 0; i < n; ++i) d.byte(buf[i]);
        break;
      }
      case 3:  // no complete frame within the link timeout
        d.timeout();
        break;
    }
  }
  return 0;
}
