// Processor-in-the-loop link protocol: framed, checksummed, little-endian, lockstep (one sensor
// frame from the host and one actuator frame back per tick). Shared by the firmware and host_sim.
//
// Frame:  0xA5 0x5A | type (1) | length (1) | payload (length bytes) | CRC-16/CCITT-FALSE (2, LE)
// The CRC covers type, length and payload. Sensor frames carry the tick's sequence number, the six
// encoder counts and fault-injection requests (test builds); actuator frames carry the DAC codes,
// the supervisor state and fault bits, step timing, stack use, the friction estimates and the
// firmware's link error counters.
#pragma once

#include <cstdint>
#include <cstring>

#include "osc/control/gains.hpp"
#include "osc/robots/arm.hpp"

namespace pil {

constexpr std::uint8_t kSync0 = 0xA5, kSync1 = 0x5A;
/// Sequence number of the actuator frame the firmware sends once it is ready to receive (bytes sent
/// before that may be lost). The host waits for it before its first sensor frame.
constexpr std::uint32_t kHelloSeq = 0xFFFFFFFFu;
constexpr int kJoints = osc::kDof;

enum FrameType : std::uint8_t { kSensorFrame = 1, kActuatorFrame = 2 };

/// Fault-injection requests in a sensor frame.
enum Inject : std::uint8_t {
  kInjectNone = 0,
  kInjectNonFinite = 1u << 0,  ///< poison the observer state with a NaN
  kInjectOverrun = 1u << 1,    ///< burn more than one period inside the tick
  /// Configuration, honoured in the first frame only: the adaptation law + 1 in bits 5-6 (0: the
  /// firmware's default), and no friction compensation in bit 7.
  kConfigAdaptationShift = 5,
  kConfigAdaptationMask = 3u << 5,
  kConfigNoCompensation = 1u << 7,
};
static_assert(osc::kAdaptationLawCount <= 3, "the adaptation law fits the configuration field");

/// The configuration bits that select an adaptation law.
constexpr std::uint8_t config_adaptation(osc::AdaptationLaw law) {
  return static_cast<std::uint8_t>((static_cast<unsigned>(law) + 1u) << kConfigAdaptationShift);
}

struct SensorFrame {
  std::uint32_t seq = 0;
  std::int32_t counts[kJoints] = {};
  std::uint8_t inject = 0;
};

/// The kinds of link error a receiver tells apart, each counted (LinkCounters) in telemetry.
enum LinkError : std::uint8_t {
  kErrCrc,       ///< a complete frame whose CRC does not match
  kErrHeader,    ///< the sync pair, then an unknown frame type (or a frame of the wrong type)
  kErrLength,    ///< the sync pair and a known type, with the wrong length
  kErrJunk,      ///< bytes discarded while hunting for the sync pair (junk, lost sync)
  kErrShortFrame,///< a frame that started and was cut short (silence before its end)
  kErrSeq,       ///< a valid frame with an unexpected sequence number
  kErrSilence,   ///< no frame within the silence limit
  kLinkErrorKinds
};
/// Names in telemetry (JSON, logs), in LinkError order.
constexpr const char* kLinkErrorNames[kLinkErrorKinds] = {"bad_crc",      "bad_header", "bad_length", "junk_bytes",
                                                          "short_frames", "seq_errors", "timeouts"};

/// Link errors counted by kind since start (32-bit counters that wrap; compare differences).
struct LinkCounters {
  std::uint32_t count[kLinkErrorKinds] = {};
  std::uint32_t& operator[](LinkError e) { return count[e]; }
  std::uint32_t operator[](LinkError e) const { return count[e]; }
  std::uint32_t total() const {
    std::uint32_t n = 0;
    for (std::uint32_t c : count) n += c;
    return n;
  }
};

struct ActuatorFrame {
  std::uint32_t seq = 0;
  std::int32_t codes[kJoints] = {};
  std::uint32_t faults = 0;      ///< latched osc::Fault bits
  std::uint8_t state = 0;        ///< osc::SupervisorState
  /// Control step (observer + controller + adaptation) of the previous tick, its max and mean, and
  /// the max of the whole tick (encoders to DACs, with this frame's transmission), in cycles.
  std::uint32_t step_cycles = 0, max_cycles = 0, mean_cycles = 0, tick_max_cycles = 0;
  std::uint32_t stack_used = 0;  ///< bytes, high-water mark
  float theta_hat[3 * kJoints] = {};
  float tau_f_hat[kJoints] = {};
  LinkCounters link;             ///< the firmware's link errors by kind, since start
  /// The longest gap between two received bytes, in cycles, and how many gaps were longer than
  /// params::kLinkSilenceTicks control periods (what a tick-based silence watchdog would have seen).
  std::uint32_t rx_gap_max = 0, rx_long_gaps = 0;
};

constexpr int kSensorPayload = 4 + 4 * kJoints + 1;
constexpr int kActuatorPayload =
    4 + 4 * kJoints + 4 + 1 + 4 * 5 + 4 * 3 * kJoints + 4 * kJoints + 4 * kLinkErrorKinds + 4 * 2;
constexpr int kOverhead = 6;
constexpr int kMaxFrame = kActuatorPayload + kOverhead;
static_assert(kActuatorPayload < 256 && kSensorPayload < 256, "length fits a byte");
static_assert(kActuatorPayload == 185, "the actuator frame's layout (encode/decode below) changed: update the docs");

/// CRC-16/CCITT-FALSE (polynomial 0x1021, initial 0xFFFF), one bit at a time: the definition,
/// which makes the table below and the tests' reference.
constexpr std::uint16_t crc16_bitwise(const std::uint8_t* p, int n, std::uint16_t crc = 0xFFFF) {
  for (int i = 0; i < n; ++i) {
    crc = static_cast<std::uint16_t>(crc ^ (static_cast<std::uint16_t>(p[i]) << 8));
    for (int b = 0; b < 8; ++b)
      crc = static_cast<std::uint16_t>((crc & 0x8000) ? (crc << 1) ^ 0x1021 : (crc << 1));
  }
  return crc;
}

namespace detail {
/// The CRC register after one byte b with a zero register, for every b (512 bytes of flash).
struct Crc16Table {
  std::uint16_t v[256];
  constexpr Crc16Table() : v{} {
    for (int b = 0; b < 256; ++b) {
      const auto byte = static_cast<std::uint8_t>(b);
      v[b] = crc16_bitwise(&byte, 1, 0);
    }
  }
};
inline constexpr Crc16Table kCrc16Table{};
}  // namespace detail

/// The same CRC a byte at a time through the table: a frame's CRC in a few instructions per byte
/// instead of about forty (the link runs in the control interrupt).
inline std::uint16_t crc16(const std::uint8_t* p, int n, std::uint16_t crc = 0xFFFF) {
  for (int i = 0; i < n; ++i)
    crc = static_cast<std::uint16_t>((crc << 8) ^ detail::kCrc16Table.v[((crc >> 8) ^ p[i]) & 0xFF]);
  return crc;
}
static_assert(detail::kCrc16Table.v[1] == 0x1021, "the table's first power of x is the polynomial");

namespace detail {
struct Writer {
  std::uint8_t* p;
  void u8(std::uint8_t v) { *p++ = v; }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) *p++ = static_cast<std::uint8_t>(v >> (8 * i));
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f32(float v) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    u32(u);
  }
};
struct Reader {
  const std::uint8_t* p;
  std::uint8_t u8() { return *p++; }
  std::uint32_t u32() {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(*p++) << (8 * i);
    return v;
  }
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  float f32() {
    const std::uint32_t u = u32();
    float v;
    std::memcpy(&v, &u, 4);
    return v;
  }
};
inline int finish(std::uint8_t* buf, FrameType type, int payload) {
  buf[0] = kSync0;
  buf[1] = kSync1;
  buf[2] = type;
  buf[3] = static_cast<std::uint8_t>(payload);
  const std::uint16_t crc = crc16(buf + 2, payload + 2);
  buf[4 + payload] = static_cast<std::uint8_t>(crc & 0xFF);
  buf[5 + payload] = static_cast<std::uint8_t>(crc >> 8);
  return payload + kOverhead;
}
}  // namespace detail

/// Encodes into buf (at least kMaxFrame bytes); returns the frame length.
inline int encode(const SensorFrame& f, std::uint8_t* buf) {
  detail::Writer w{buf + 4};
  w.u32(f.seq);
  for (int i = 0; i < kJoints; ++i) w.i32(f.counts[i]);
  w.u8(f.inject);
  return detail::finish(buf, kSensorFrame, kSensorPayload);
}

inline int encode(const ActuatorFrame& f, std::uint8_t* buf) {
  detail::Writer w{buf + 4};
  w.u32(f.seq);
  for (int i = 0; i < kJoints; ++i) w.i32(f.codes[i]);
  w.u32(f.faults);
  w.u8(f.state);
  w.u32(f.step_cycles);
  w.u32(f.max_cycles);
  w.u32(f.mean_cycles);
  w.u32(f.tick_max_cycles);
  w.u32(f.stack_used);
  for (float v : f.theta_hat) w.f32(v);
  for (float v : f.tau_f_hat) w.f32(v);
  for (std::uint32_t c : f.link.count) w.u32(c);
  w.u32(f.rx_gap_max);
  w.u32(f.rx_long_gaps);
  return detail::finish(buf, kActuatorFrame, kActuatorPayload);
}

/// Payload length of a frame type, -1 for an unknown type.
constexpr int payload_length(std::uint8_t type) {
  return type == kSensorFrame ? kSensorPayload : type == kActuatorFrame ? kActuatorPayload : -1;
}

/// Streaming frame parser: feed bytes one at a time. Every byte is accounted for: part of a frame
/// (kPending, then kFrame, kBadChecksum, kBadHeader or kBadLength when the frame ends), or junk
/// (kJunk: junk() bytes discarded while hunting for the sync pair).
class Parser {
 public:
  enum Result : std::uint8_t { kPending, kFrame, kJunk, kBadHeader, kBadLength, kBadChecksum };

  Result feed(std::uint8_t b) {
    switch (stage_) {
      case 0:  // hunting for the first sync byte; anything else is junk
        if (b == kSync0) {
          stage_ = 1;
          return kPending;
        }
        junk_ = 1;
        return kJunk;
      case 1:
        if (b == kSync1) {
          stage_ = 2;
          return kPending;
        }
        // Lost sync: the sync byte before was junk, and so is this one unless it starts a frame.
        stage_ = b == kSync0 ? 1 : 0;
        junk_ = b == kSync0 ? 1 : 2;
        return kJunk;
      case 2:
        buf_[0] = b;
        stage_ = 3;
        return kPending;
      case 3: {
        buf_[1] = b;
        const int expect = payload_length(buf_[0]);
        if (expect < 0 || b != expect) {
          stage_ = 0;
          return expect < 0 ? kBadHeader : kBadLength;
        }
        need_ = b + 2;  // payload and CRC
        have_ = 0;
        stage_ = 4;
        return kPending;
      }
      default: {
        buf_[2 + have_++] = b;
        if (have_ < need_) return kPending;
        stage_ = 0;
        const int n = buf_[1];
        const std::uint16_t crc = static_cast<std::uint16_t>(buf_[2 + n] | (buf_[3 + n] << 8));
        return crc16(buf_, n + 2) == crc ? kFrame : kBadChecksum;
      }
    }
  }
  /// Bytes the last kJunk result discarded (1 or 2).
  int junk() const { return junk_; }
  /// The error kind of a result other than kPending and kFrame.
  static constexpr LinkError error_of(Result r) {
    return r == kJunk ? kErrJunk : r == kBadHeader ? kErrHeader : r == kBadLength ? kErrLength : kErrCrc;
  }
  /// True while a frame has started but not completed (a timeout here is a short frame).
  bool in_frame() const { return stage_ != 0; }
  void reset() { stage_ = 0; }
  FrameType type() const { return static_cast<FrameType>(buf_[0]); }

  bool decode(SensorFrame& f) const {
    if (type() != kSensorFrame) return false;
    detail::Reader r{buf_ + 2};
    f.seq = r.u32();
    for (int i = 0; i < kJoints; ++i) f.counts[i] = r.i32();
    f.inject = r.u8();
    return true;
  }
  bool decode(ActuatorFrame& f) const {
    if (type() != kActuatorFrame) return false;
    detail::Reader r{buf_ + 2};
    f.seq = r.u32();
    for (int i = 0; i < kJoints; ++i) f.codes[i] = r.i32();
    f.faults = r.u32();
    f.state = r.u8();
    f.step_cycles = r.u32();
    f.max_cycles = r.u32();
    f.mean_cycles = r.u32();
    f.tick_max_cycles = r.u32();
    f.stack_used = r.u32();
    for (float& v : f.theta_hat) v = r.f32();
    for (float& v : f.tau_f_hat) v = r.f32();
    for (std::uint32_t& c : f.link.count) c = r.u32();
    f.rx_gap_max = r.u32();
    f.rx_long_gaps = r.u32();
    return true;
  }

 private:
  std::uint8_t buf_[kMaxFrame] = {};
  int stage_ = 0, need_ = 0, have_ = 0, junk_ = 0;
};

}  // namespace pil
