// Link supervision of the firmware's PIL node (osc/link/node.hpp), host-only: PilNode<double> on a
// fake board whose UART is a byte vector and whose clock the test runs. For every kind of link error,
// injected mid-run while the controller holds the arm against gravity (nonzero codes): the next
// actuator frame carries zero codes, the error is counted in that frame's telemetry, the fault is not
// latched, and repeated errors latch the named link fault. Both ways of pacing the ticks: lockstep
// (a tick per frame, as pil_firmware under QEMU) and timer-paced (a tick per period, whatever came).
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <vector>

#include "osc/link/node.hpp"
#include "osc/robot.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

/// The fake board: what the node writes to the UART is parsed back into actuator frames.
struct FakeBoard {
  static inline std::uint32_t clock = 0;
  static inline std::vector<pil::ActuatorFrame> sent;
  static inline pil::Parser rx;
  static inline int bad_bytes = 0;  // anything but clean frames from the node (must stay 0)
  static void reset() {
    clock = 0;
    sent.clear();
    rx.reset();
    bad_bytes = 0;
  }
  static void link_write(const std::uint8_t* p, int n) {
    for (int i = 0; i < n; ++i)
      for (pil::Parser::Result r = rx.feed(p[i]); r != pil::Parser::kPending; r = rx.next()) {
        pil::ActuatorFrame a;
        if (r == pil::Parser::kFrame && rx.decode(a))
          sent.push_back(a);
        else
          ++bad_bytes;
      }
  }
  static std::uint32_t cycles() { return clock += 100; }
  static std::uint32_t stack_used() { return 0; }
  static void burn(std::uint32_t c) { clock += c; }
  static void fault_output(bool) {}
};
static_assert(PilBoard<FakeBoard>);
static_assert(hal::ControlHal<PilNode<double, FakeBoard>>);
static_assert(hal::CurrentHal<PilNode<double, FakeBoard>>);

using Bytes = std::vector<std::uint8_t>;
using Answers = std::vector<pil::ActuatorFrame>;

bool zero(const pil::ActuatorFrame& a) {
  for (std::int32_t c : a.codes)
    if (c != 0) return false;
  return true;
}

struct LinkNode : ::testing::Test {
  std::unique_ptr<PilNode<double, FakeBoard>> node = std::make_unique<PilNode<double, FakeBoard>>();
  std::uint32_t seq = 0;

  void SetUp() override { restart(); }
  void restart() {
    seq = 0;
    FakeBoard::reset();
    node->init(joint_vector<double>(robot::kQStart), FrictionMode::kAdaptive, 1000000);
    // These frames are an arm frozen at the start pose while the controller holds it against
    // gravity: the armed residual monitor rightly calls that a drive fault. The link's tests want
    // the link's own faults, so the monitor runs as a trial here.
    node->task.residual.armed = false;
    node->hello();
    ASSERT_EQ(FakeBoard::sent.size(), 1u);
    FakeBoard::sent.clear();
  }
  void TearDown() override { EXPECT_EQ(FakeBoard::bad_bytes, 0); }

  /// The next sensor frame's bytes (the robot at the start pose, its encoders dithering by a count
  /// so that the stuck-encoder monitor sees them alive over long runs: the controller holds it
  /// against gravity with nonzero codes).
  Bytes frame() {
    pil::SensorFrame s;
    for (std::int32_t& c : s.counts) c = static_cast<std::int32_t>(seq & 1u);
    s.seq = seq++;
    Bytes b(pil::kMaxFrame);
    b.resize(static_cast<std::size_t>(pil::encode(s, b.data())));
    return b;
  }
  /// Feeds bytes as the lockstep board does (a tick whenever a frame ends); returns the answers.
  Answers lockstep(const Bytes& b) {
    const std::size_t n = FakeBoard::sent.size();
    for (std::uint8_t c : b) node->on_byte(c, [&] { node->tick(); });
    return Answers(FakeBoard::sent.begin() + static_cast<std::ptrdiff_t>(n), FakeBoard::sent.end());
  }
  /// The lockstep board's link timeout: no byte for params::kLinkTimeout.
  Answers lockstep_timeout() {
    const std::size_t n = FakeBoard::sent.size();
    node->on_timeout([&] { node->tick(); });
    return Answers(FakeBoard::sent.begin() + static_cast<std::ptrdiff_t>(n), FakeBoard::sent.end());
  }
  /// One lockstep exchange of a healthy frame; its single answer.
  pil::ActuatorFrame exchange() {
    const Answers a = lockstep(frame());
    EXPECT_EQ(a.size(), 1u);
    return a.empty() ? pil::ActuatorFrame{} : a.back();
  }
  void healthy(int n) {
    for (int k = 0; k < n; ++k) {
      const pil::ActuatorFrame a = exchange();
      ASSERT_EQ(a.faults, 0u);
      ASSERT_EQ(a.seq, seq - 1);
      ASSERT_FALSE(zero(a));
    }
  }
  /// Timer-paced: bytes arrive between ticks, the board ticks every period.
  void arrive(const Bytes& b) {
    for (std::uint8_t c : b) node->on_byte(c);
  }
  pil::ActuatorFrame timer_tick() {
    const std::size_t n = FakeBoard::sent.size();
    node->tick();
    EXPECT_EQ(FakeBoard::sent.size(), n + 1);  // one actuator frame (DAC write) per tick
    return FakeBoard::sent.back();
  }
};

// ---------------------------------------------------------------- every error kind, lockstep
struct ErrorCase {
  const char* name;
  pil::LinkError counter;  // the counter that counts it
  std::uint32_t fault;     // the fault repeated errors latch
  int error_ticks;         // ticks at zero per injection (a lost sync also costs the next frame)
  int answer_seq_offset;   // the answer's sequence number relative to the first frame used
  std::function<Answers(LinkNode&)> inject;
};

Bytes with(Bytes b, std::size_t at, std::uint8_t xor_mask) {
  b[at] ^= xor_mask;
  return b;
}

const ErrorCase kCases[] = {
    {"BadCrc", pil::kErrCrc, kFaultLinkCorrupt, 1, 0,
     [](LinkNode& t) { return t.lockstep(with(t.frame(), 10, 0x40)); }},
    {"BadHeader", pil::kErrHeader, kFaultLinkCorrupt, 1, 0,
     [](LinkNode& t) { return t.lockstep(with(t.frame(), 2, 0x1E)); }},  // type 0x1F: unknown
    {"BadLength", pil::kErrLength, kFaultLinkCorrupt, 1, 0,
     [](LinkNode& t) { return t.lockstep(with(t.frame(), 3, 0x01)); }},
    {"JunkBetweenFrames", pil::kErrJunk, kFaultLinkCorrupt, 1, 0,
     [](LinkNode& t) {
       Bytes b = {0x00, 0x13, 0xA5, 0x77, 0xFF};
       const Bytes f = t.frame();
       b.insert(b.end(), f.begin(), f.end());
       return t.lockstep(b);
     }},
    {"LostSyncMidFrame", pil::kErrCrc, kFaultLinkCorrupt, 1, 0,
     [](LinkNode& t) {
       Bytes b = t.frame();
       b.resize(12);  // cut short, and the next frame follows at once
       const Bytes f = t.frame();
       b.insert(b.end(), f.begin(), f.end());
       // The cut frame takes the next one's first bytes and fails its CRC (zero codes); the scan
       // from its second byte finds the next frame, answered with torque (pil::Parser).
       Answers a = t.lockstep(b);
       EXPECT_EQ(a.size(), 2u);
       if (a.size() == 2) {
         EXPECT_EQ(zero(a[1]), a[1].faults != 0);  // torque, unless the error before just latched
         EXPECT_EQ(a[1].seq, t.seq - 1);
       }
       a.resize(std::min<std::size_t>(a.size(), 1));
       return a;
     }},
    {"SyncByteDestroyed", pil::kErrJunk, kFaultLinkCorrupt, 1, 0,
     [](LinkNode& t) {
       Answers a = t.lockstep(with(t.frame(), 1, 0xFF));  // all junk: nothing to answer yet
       EXPECT_TRUE(a.empty());
       return t.lockstep_timeout();
     }},
    {"TruncatedFrameThenSilence", pil::kErrShortFrame, kFaultLinkCorrupt, 1, 0,
     [](LinkNode& t) {
       Bytes b = t.frame();
       b.resize(12);
       EXPECT_TRUE(t.lockstep(b).empty());
       return t.lockstep_timeout();
     }},
    {"WrongSequenceNumber", pil::kErrSeq, kFaultLinkCorrupt, 1, 1,
     [](LinkNode& t) {
       ++t.seq;  // one skipped
       return t.lockstep(t.frame());
     }},
    {"Silence", pil::kErrSilence, kFaultLinkLost, 1, -1, [](LinkNode& t) { return t.lockstep_timeout(); }},
};

struct EachLinkError : LinkNode, ::testing::WithParamInterface<ErrorCase> {};

TEST_P(EachLinkError, ZeroCodesInTheAnswerCountedNotLatched) {
  const ErrorCase& c = GetParam();
  healthy(5);
  const std::uint32_t first_seq = seq;
  const std::uint32_t before = node->link_counters()[c.counter];
  const Answers a = c.inject(*this);
  // Lockstep: exactly one answer, at once, with zero codes: the plant gets zero torque in this very
  // tick (and a timer-paced board writes the same at its next tick, see below).
  ASSERT_EQ(a.size(), 1u);
  EXPECT_TRUE(zero(a[0]));
  EXPECT_EQ(a[0].seq, first_seq + static_cast<std::uint32_t>(c.answer_seq_offset));
  EXPECT_EQ(a[0].faults, 0u);  // a single error does not latch
  EXPECT_EQ(a[0].state, static_cast<std::uint8_t>(SupervisorState::kRun));
  EXPECT_GT(a[0].link[c.counter], before);  // counted in the very frame that carries the zero codes
  // Torque again once the link is clean (after the error's ticks at zero).
  for (int k = 1; k < c.error_ticks; ++k) EXPECT_TRUE(zero(exchange()));
  healthy(3);
}

TEST_P(EachLinkError, RepeatedErrorsLatchTheNamedFault) {
  const ErrorCase& c = GetParam();
  healthy(3);
  int error_ticks = 0;
  pil::ActuatorFrame a;
  while (error_ticks < params::kLinkErrorLimit) {
    const Answers x = c.inject(*this);
    ASSERT_EQ(x.size(), 1u);
    a = x[0];
    ++error_ticks;
    for (int k = 1; k < c.error_ticks && error_ticks < params::kLinkErrorLimit; ++k, ++error_ticks) a = exchange();
    EXPECT_TRUE(zero(a));
    if (error_ticks < params::kLinkErrorLimit) {
      ASSERT_EQ(a.faults, 0u) << "latched after " << error_ticks << " error ticks";
      healthy(2);
    }
  }
  EXPECT_EQ(a.faults, c.fault) << fault_name(a.faults);
  EXPECT_EQ(a.state, static_cast<std::uint8_t>(SupervisorState::kFault));
  const pil::ActuatorFrame b = exchange();  // latched: zero with healthy frames too
  EXPECT_TRUE(zero(b));
  EXPECT_EQ(b.faults, c.fault);
}

INSTANTIATE_TEST_SUITE_P(Lockstep, EachLinkError, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<ErrorCase>& i) { return std::string(i.param.name); });

TEST_F(LinkNode, JunkAfterAnErrorBelongsToIt) {
  healthy(3);
  const Answers a = lockstep(with(frame(), 2, 0x1E));  // type 0x1F, unknown: answered at its 4th byte
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(node->link_counters()[pil::kErrHeader], 1u);
  // Its rest: the frame gives up its first byte, the bytes after it are scanned again and are junk.
  EXPECT_EQ(node->link_counters()[pil::kErrJunk], static_cast<std::uint32_t>(pil::kSensorPayload + pil::kOverhead - 1));
  healthy(1);  // not a second error
}

TEST_F(LinkNode, ErrorsFurtherApartThanTheWindowDoNotLatch) {
  OSC_PUMA_TUNED(
      "its frames freeze the arm while the paper's motion runs: the UR5e's drives saturate within the window");
  healthy(2);
  auto error = [&] {
    const Answers a = lockstep(with(frame(), 10, 0x40));
    ASSERT_EQ(a.size(), 1u);
    EXPECT_TRUE(zero(a[0]));
  };
  // Bad frames at ticks t, t + W/2 and t + W: never kLinkErrorLimit within kLinkErrorWindow ticks.
  static_assert(params::kLinkErrorLimit == 3);
  constexpr int kHalf = params::kLinkErrorWindow / 2;
  for (int i = 0; i < params::kLinkErrorLimit; ++i) {
    if (i) healthy(kHalf - 1);
    error();
  }
  EXPECT_EQ(node->task.sup.latched, 0u);
  healthy(1);
  error();  // the last three within W ticks
  EXPECT_EQ(node->task.sup.latched, static_cast<std::uint32_t>(kFaultLinkCorrupt));
  EXPECT_EQ(node->link_counters()[pil::kErrCrc], 4u);
  // Nothing else but the bad frames' bytes after their first, scanned again: junk.
  EXPECT_EQ(node->link_counters().total(), 4u + 4u * (pil::kSensorPayload + pil::kOverhead - 1));
}

// ---------------------------------------------------------------- timer-paced board
TEST_F(LinkNode, TimerPacedSilenceKeepsTheCodesTwoTicksThenZeroThenLatchesLinkLost) {
  for (int k = 0; k < 5; ++k) {
    arrive(frame());
    ASSERT_FALSE(zero(timer_tick()));
  }
  const pil::ActuatorFrame last = FakeBoard::sent.back();
  // Up to kLinkSilenceTicks ticks without a frame: the DACs keep their codes, no error.
  for (int k = 0; k < params::kLinkSilenceTicks; ++k) {
    const pil::ActuatorFrame a = timer_tick();
    EXPECT_TRUE(std::equal(a.codes, a.codes + kDof, last.codes)) << k;
    EXPECT_EQ(a.link.total(), 0u);
  }
  // Silence longer than that: zero codes at the next tick, counted.
  pil::ActuatorFrame a = timer_tick();
  EXPECT_TRUE(zero(a));
  EXPECT_EQ(a.link[pil::kErrSilence], 1u);
  EXPECT_EQ(a.faults, 0u);
  // Each further silent tick is an error tick: the kLinkErrorLimit-th latches link_lost.
  for (int k = 1; k < params::kLinkErrorLimit; ++k) a = timer_tick();
  EXPECT_TRUE(zero(a));
  EXPECT_EQ(a.faults, static_cast<std::uint32_t>(kFaultLinkLost));
  EXPECT_EQ(a.link[pil::kErrSilence], static_cast<std::uint32_t>(params::kLinkErrorLimit));
  arrive(frame());  // latched: frames again do not bring torque back
  EXPECT_TRUE(zero(timer_tick()));
}

TEST_F(LinkNode, TimerPacedFrameLateWithinTheAllowanceIsNoError) {
  for (int k = 0; k < 3; ++k) {
    arrive(frame());
    timer_tick();
  }
  for (int k = 0; k < params::kLinkSilenceTicks; ++k) timer_tick();
  arrive(frame());
  const pil::ActuatorFrame a = timer_tick();
  EXPECT_FALSE(zero(a));
  EXPECT_EQ(a.link.total(), 0u);
  EXPECT_EQ(node->task.tick, 3u + params::kLinkSilenceTicks + 1u);  // the sample clock ran on
}

TEST_F(LinkNode, TimerPacedCorruptionZeroesTheNextTick) {
  const std::function<Bytes(LinkNode&)> corrupt[] = {
      [](LinkNode& t) { return with(t.frame(), 10, 0x40); },  // bad CRC
      [](LinkNode& t) { return with(t.frame(), 2, 0x1E); },   // bad header (type 0x1F)
      [](LinkNode& t) { return with(t.frame(), 3, 0x01); },   // bad length
      [](LinkNode&) {
        return Bytes{0x01, 0x02, 0x03};
      },  // junk between frames
      [](LinkNode& t) {
        ++t.seq;
        return t.frame();
      },  // wrong sequence number
  };
  for (const auto& make : corrupt) {
    restart();
    for (int k = 0; k < 3; ++k) {
      arrive(frame());
      ASSERT_FALSE(zero(timer_tick()));
    }
    const std::uint32_t errors = node->link_counters().total();
    arrive(make(*this));
    const pil::ActuatorFrame a = timer_tick();  // the next tick: zero codes, counted
    EXPECT_TRUE(zero(a));
    EXPECT_GT(a.link.total(), errors);
    EXPECT_EQ(a.faults, 0u);
    // Torque again at the next tick with a healthy frame (after a wrong sequence number the node
    // follows the host's numbering).
    for (int k = 0; k < 2; ++k) {
      arrive(frame());
      EXPECT_FALSE(zero(timer_tick()));
    }
  }
}

TEST_F(LinkNode, TimerPacedTruncatedFrameIsAShortFrameWhenTheSilenceRuleFires) {
  arrive(frame());
  const pil::ActuatorFrame last = timer_tick();
  Bytes b = frame();
  b.resize(12);
  arrive(b);
  // A frame in transit at a tick is normal; a stalled one is told apart by the silence after it.
  for (int k = 0; k < params::kLinkSilenceTicks; ++k)
    EXPECT_TRUE(std::equal(last.codes, last.codes + kDof, timer_tick().codes));
  const pil::ActuatorFrame a = timer_tick();
  EXPECT_TRUE(zero(a));
  EXPECT_EQ(a.link[pil::kErrShortFrame], 1u);
  EXPECT_EQ(a.link[pil::kErrSilence], 0u);
  arrive(frame());  // the answer to the lost frame carried its number; the next one is in sequence
  EXPECT_FALSE(zero(timer_tick()));
}

}  // namespace
