// Processor-in-the-loop link protocol: framed, checksummed, little-endian, lockstep (one sensor
// frame from the host and one actuator frame back per tick). Shared by the firmware and host_sim.
// The command protocol's frames (command, answer, state, setpoint, trace: osc/link/command_frames.hpp)
// use the same framing.
//
// Frame:  0xA5 0x5A | type (1) | length (1) | payload (length bytes) | CRC-16/CCITT-FALSE (2, LE)
// The CRC covers type, length and payload. Each payload is declared once, as a field list
// (OSC_SENSOR_FIELDS, OSC_ACTUATOR_FIELDS, OSC_COMMAND_FIELDS, ...), and each frame type once, in
// OSC_FRAME_LIST: the frame structs, their encoding and decoding, the payload lengths, the parser's
// table of types and the protocol document's tables (docs/protocol.md, checked by ctest
// docs_tables_protocol) are all made from them. A field is added in its list, and nowhere else.
#pragma once

#include <cstdint>
#include <cstring>

#include "osc/control/faults.hpp"  // OSC_X_NAME, OSC_X_DOC, OSC_X_ENUMERATOR
#include "osc/control/gains.hpp"
#include "osc/link/capture_frames.hpp"
#include "osc/link/command_frames.hpp"
#include "osc/link/wire.hpp"
#include "osc/robots/arm.hpp"
#include "osc/runtime/timing.hpp"

namespace pil {

constexpr std::uint8_t kSync0 = 0xA5, kSync1 = 0x5A;
/// Sequence number of the actuator frame the firmware sends once it is ready to receive (bytes sent
/// before that may be lost). The host waits for it before its first sensor frame.
constexpr std::uint32_t kHelloSeq = 0xFFFFFFFFu;
constexpr int kJoints = osc::kDof;

/// Fault-injection requests in a sensor frame.
enum Inject : std::uint8_t {
  kInjectNone = 0,
  kInjectNonFinite = 1u << 0,  ///< poison the observer state with a NaN
  kInjectOverrun = 1u << 1,    ///< burn more than one period inside the tick
  /// Configuration, honoured in the first frame only: a trace frame after every tick (bit 2), state
  /// frames every osc::kStatePeriod ticks (bit 3), the task started disabled, waiting for an enable,
  /// instead of running the paper's motion (bit 4), the adaptation law + 1 in bits 5-6 (0: the
  /// firmware's default), and no friction compensation in bit 7.
  kConfigTrace = 1u << 2,
  kConfigStateFrames = 1u << 3,
  kConfigStartDisabled = 1u << 4,
  kConfigAdaptationShift = 5,
  kConfigAdaptationMask = 3u << 5,
  kConfigNoCompensation = 1u << 7,
};
static_assert(osc::kAdaptationLawCount <= 3, "the adaptation law fits the configuration field");

/// The drive byte of a sensor frame: the amplifiers' fault lines and whether its currents are a reading
/// (hal::CurrentHal, read by the host from its amplifiers: the PIL node's read_currents and amp_faults).
enum Drive : std::uint8_t {
  kDriveFaultLines = (1u << kJoints) - 1u,  ///< bit c: amplifier c's fault line is active (amp_faults)
  kDriveCurrentsValid = 1u << 7,            ///< currents holds a reading (read_currents gave one); 0: none
};
static_assert(kJoints <= 7, "a fault line per amplifier below the valid bit");

/// The drive byte of a reading: the fault lines (bit c: amplifier c; those of other bits dropped) and
/// whether the currents are one.
constexpr std::uint8_t drive_byte(std::uint32_t fault_lines, bool currents_valid) {
  const unsigned valid = currents_valid ? static_cast<unsigned>(kDriveCurrentsValid) : 0u;
  return static_cast<std::uint8_t>((fault_lines & kDriveFaultLines) | valid);
}

/// The configuration bits that select an adaptation law.
constexpr std::uint8_t config_adaptation(osc::AdaptationLaw law) {
  return static_cast<std::uint8_t>((static_cast<unsigned>(law) + 1u) << kConfigAdaptationShift);
}

// X(type, name, extent, unit, meaning): one payload field, in wire order. `extent` is empty for one
// value or [N] for N of them; the wire type follows the C++ type (detail::Wire): std::uint8_t u8,
// std::int16_t i16, std::uint32_t u32, std::int32_t i32, float f32 (IEEE 754 binary32), all little-endian.
#define OSC_SENSOR_FIELDS(X)                                                                                        \
  X(std::uint32_t, seq, , "", "sequence number: 0 in the first frame, one more in each next frame (wraps at 2^32)") \
  X(std::int32_t, counts, [kJoints], "count",                                                                       \
    "encoder counts of joints 1 to 6, 0 at the start pose (Encoders, DACs, the plant)")                             \
  X(std::int16_t, currents, [kJoints], "code",                                                                      \
    "each amplifier's current-monitor reading, as hal::CurrentHal::read_currents gives it: +-(2^(bits-1) - 1) at "  \
    "+-range times the DAC's full-scale current; 0 when drive says there is none (The drive byte)")                 \
  X(std::uint8_t, drive, , "", "the amplifiers' fault lines and whether currents is a reading (The drive byte)")    \
  X(std::uint8_t, inject, , "", "fault-injection requests; configuration bits in the first frame (The inject byte)")

#define OSC_ACTUATOR_FIELDS(X)                                                                                       \
  X(std::uint32_t, seq, , "", "the sequence number of the sensor frame this answers; 0xFFFFFFFF in the hello frame") \
  X(std::int32_t, codes, [kJoints], "code",                                                                          \
    "DAC codes of joints 1 to 6, within the DAC full scale (Encoders, DACs, the plant)")                             \
  X(std::uint32_t, faults, , "", "latched fault bits (Fault bits)")                                                  \
  X(std::uint8_t, state, , "", "supervisor state (Supervisor states)")                                               \
  X(std::uint32_t, step_cycles, , "cycles",                                                                          \
    "this tick's control step (observer, controller, adaptation); the last one's in a tick without one")             \
  X(std::uint32_t, max_cycles, , "cycles", "the longest control step so far")                                        \
  X(std::uint32_t, mean_cycles, , "cycles", "the mean control step so far")                                          \
  X(std::uint32_t, tick_max_cycles, , "cycles",                                                                      \
    "the longest whole tick before this one (encoders to DACs, with its frame's transmission)")                      \
  X(std::uint32_t, stage_cycles, [osc::kTickStages], "cycles", "this tick's stages, in Tick stages order")           \
  X(std::uint32_t, stack_used, , "bytes", "the main stack's high-water mark")                                        \
  X(float, theta_hat, [3 * kJoints], "N m s/rad, N m, N m",                                                          \
    "friction estimates: viscous of joints 1-6, then Coulomb 1-6, then Stribeck 1-6")                                \
  X(float, tau_f_hat, [kJoints], "N m", "the estimated friction torque of joints 1 to 6")                            \
  X(LinkCounters, link, , "", "the firmware's link errors since start, one u32 per kind (Link error counters)")      \
  X(std::uint32_t, rx_gap_max, , "cycles", "the longest gap between two received bytes")                             \
  X(std::uint32_t, rx_long_gaps, , "",                                                                               \
    "gaps longer than params::kLinkSilenceTicks control periods (a tick-based silence watchdog's view)")

// X(Name, code, "name", "sender", when it is sent, FIELDS): the frame types, in code order. Each
// makes the struct NameFrame (its fields, in wire order), kNameFrame (its type code), kNameFields
// (its fields as the document lists them), kNamePayload (its payload length), encode(),
// Parser::decode() and for_each_field().
#define OSC_FRAME_LIST(X)                                                                                              \
  X(Sensor, 1, "sensor", "host",                                                                                       \
    "one per control tick: the tick's encoder counts, amplifier currents and fault lines", OSC_SENSOR_FIELDS)          \
  X(Actuator, 2, "actuator", "firmware", "one per sensor frame: the tick's DAC codes and the telemetry",               \
    OSC_ACTUATOR_FIELDS)                                                                                               \
  X(Command, 3, "command", "host", "a client's command: answered by the tick after it arrives", OSC_COMMAND_FIELDS)    \
  X(Answer, 4, "answer", "firmware",                                                                                   \
    "after each tick that answered a command or ended a motion (done, aborted, at rest)", OSC_ANSWER_FIELDS)           \
  X(State, 5, "state", "firmware", "the motion state and the poses, on request or periodically", OSC_STATE_FIELDS)     \
  X(Setpoint, 6, "setpoint", "host", "one sample of a stream, at the stream's period", OSC_SETPOINT_FIELDS)            \
  X(Trace, 7, "trace", "firmware",                                                                                     \
    "after every tick's other frames, when the first sensor frame asked (configuration bit trace)", OSC_TRACE_FIELDS)  \
  X(SetpointVelocity, 8, "setpoint_velocity", "host",                                                                  \
    "one sample of a stream with its velocity, in place of a setpoint frame (the follower joins the sample's "         \
    "line without the setpoints' delay)",                                                                              \
    OSC_SETPOINT_VELOCITY_FIELDS)                                                                                      \
  X(Param, 9, "param", "host", "a parameter request: get, set, save, load, reset, check (answered at once)",           \
    OSC_PARAM_FIELDS)                                                                                                  \
  X(ParamAnswer, 10, "param_answer", "firmware", "the answer to each param frame, sent as it is handled",              \
    OSC_PARAM_ANSWER_FIELDS)                                                                                           \
  X(Identify, 11, "identify", "firmware",                                                                              \
    "once after an identify run's motion ends, from a board that estimates: the run's estimate, or why there is none", \
    OSC_IDENTIFY_FIELDS)                                                                                               \
  X(Capture, 12, "capture", "host", "a capture request: arm, trigger, abort, status, read (answered at once)",         \
    OSC_CAPTURE_FIELDS)                                                                                                \
  X(CaptureData, 13, "capture_data", "firmware", "the answer to each capture frame, sent as it is handled",            \
    OSC_CAPTURE_DATA_FIELDS)                                                                                           \
  X(IdentifyPayload, 14, "identify_payload", "firmware",                                                               \
    "right after the identify frame of a run asked with the flag payload: its estimate of the payload at the flange",  \
    OSC_IDENTIFY_PAYLOAD_FIELDS)                                                                                       \
  X(IdentifyOffset, 15, "identify_offset", "firmware",                                                                 \
    "right after every identify frame (before an identify_payload frame): the run's estimate of each drive's torque "  \
    "offset",                                                                                                          \
    OSC_IDENTIFY_OFFSET_FIELDS)

#define OSC_FRAME_TYPE(Name, code, name, from, when, FIELDS) k##Name##Frame = code,
enum FrameType : std::uint8_t { OSC_FRAME_LIST(OSC_FRAME_TYPE) };
#undef OSC_FRAME_TYPE

#define OSC_FRAME_MEMBER(type, name, extent, unit, doc) type name extent = {};
#define OSC_FRAME_STRUCT(Name, code, name, from, when, FIELDS) \
  struct Name##Frame {                                         \
    FIELDS(OSC_FRAME_MEMBER)                                   \
  };
OSC_FRAME_LIST(OSC_FRAME_STRUCT)
#undef OSC_FRAME_STRUCT
#undef OSC_FRAME_MEMBER

/// One field of a payload as the protocol document lists it.
struct FieldInfo {
  const char* name;
  const char* type;  ///< u8, i16, u32, i32, f32
  int count;         ///< values of that type
  int bytes;         ///< count x the type's size
  const char* unit;
  const char* doc;
};
#define OSC_FIELD_INFO(type, name, extent, unit, doc) \
  FieldInfo{#name,                                    \
            detail::Wire<type extent>::type_name,     \
            detail::Wire<type extent>::count,         \
            detail::kWireBytes<type extent>,          \
            unit,                                     \
            doc},
#define OSC_FRAME_FIELDS(Name, code, name, from, when, FIELDS) \
  constexpr FieldInfo k##Name##Fields[] = {FIELDS(OSC_FIELD_INFO)};
OSC_FRAME_LIST(OSC_FRAME_FIELDS)
#undef OSC_FRAME_FIELDS
#undef OSC_FIELD_INFO

#define OSC_FIELD_BYTES(type, name, extent, unit, doc) +detail::kWireBytes<type extent>
#define OSC_FRAME_PAYLOAD(Name, code, name, from, when, FIELDS) \
  constexpr int k##Name##Payload = 0 FIELDS(OSC_FIELD_BYTES);
OSC_FRAME_LIST(OSC_FRAME_PAYLOAD)
#undef OSC_FRAME_PAYLOAD
#undef OSC_FIELD_BYTES

/// A frame type as the protocol document lists it.
struct FrameInfo {
  const char* name;
  FrameType type;
  int payload;              ///< bytes
  const char* from;         ///< the sender: host or firmware
  const char* when;         ///< when it is sent
  const FieldInfo* fields;  ///< its fields, in wire order
  int field_count;
};
#define OSC_FRAME_INFO(Name, code, name, from, when, FIELDS) \
  FrameInfo{name,                                            \
            k##Name##Frame,                                  \
            k##Name##Payload,                                \
            from,                                            \
            when,                                            \
            k##Name##Fields,                                 \
            static_cast<int>(sizeof(k##Name##Fields) / sizeof(FieldInfo))},
constexpr FrameInfo kFrames[] = {OSC_FRAME_LIST(OSC_FRAME_INFO)};
#undef OSC_FRAME_INFO
constexpr int kFrameTypes = static_cast<int>(sizeof(kFrames) / sizeof(*kFrames));

namespace detail {
constexpr int max_payload() {
  int m = 0;
  for (const FrameInfo& f : kFrames) m = f.payload > m ? f.payload : m;
  return m;
}
/// Every type code distinct and nonzero, every length fits its byte.
constexpr bool frame_types_valid() {
  for (int i = 0; i < kFrameTypes; ++i) {
    if (kFrames[i].type == 0 || kFrames[i].payload >= 256) return false;
    for (int k = 0; k < i; ++k)
      if (kFrames[k].type == kFrames[i].type) return false;
  }
  return true;
}
}  // namespace detail
static_assert(detail::frame_types_valid(), "distinct nonzero type codes; each length fits a byte");

constexpr int kOverhead = 6;
constexpr int kMaxPayload = detail::max_payload();
constexpr int kMaxFrame = kMaxPayload + kOverhead;
static_assert(kMaxPayload == kActuatorPayload,
              "the actuator frame is the largest: the boards size their telemetry (buffer, baud rate) by kMaxFrame");

namespace detail {
#define OSC_FIELD_PUT(type, name, extent, unit, doc) w.put(f.name);
#define OSC_FIELD_GET(type, name, extent, unit, doc) r.get(f.name);
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

/// encode(frame, buf): encodes into buf (at least kMaxFrame bytes); returns the frame length.
#define OSC_FRAME_ENCODE(Name, code, name, from, when, FIELDS)    \
  inline int encode(const Name##Frame& f, std::uint8_t* buf) {    \
    detail::Writer w{buf + 4};                                    \
    FIELDS(OSC_FIELD_PUT)                                         \
    return detail::finish(buf, k##Name##Frame, k##Name##Payload); \
  }
OSC_FRAME_LIST(OSC_FRAME_ENCODE)
#undef OSC_FRAME_ENCODE

/// Payload length of a frame type, -1 for an unknown type.
constexpr int payload_length(std::uint8_t type) {
#define OSC_FRAME_CASE(Name, code, name, from, when, FIELDS) \
  case k##Name##Frame:                                       \
    return k##Name##Payload;
  switch (type) {
    OSC_FRAME_LIST(OSC_FRAME_CASE)
    default:
      return -1;
  }
#undef OSC_FRAME_CASE
}

/// Streaming frame parser with resynchronisation: nothing that arrived whole is lost. Bytes are fed
/// one at a time; feed() returns the first event the byte completes, and next() each further one
/// (a caller drains them: `for (r = p.feed(b); r != Parser::kPending; r = p.next())`). After a kFrame,
/// decode() reads its payload until the next call; after a kJunk, junk() counts its bytes. Every
/// byte is accounted for: part of a frame (kFrame), the start of a frame that failed (kBadHeader,
/// kBadLength, kBadChecksum, kShortFrame: its first sync byte), or junk (bytes discarded while
/// hunting for the sync pair, coalesced into one kJunk).
///
/// The rule on every transport (docs/protocol.md, "Framing and resynchronisation"): a frame that
/// fails (an unknown type, a wrong length, a CRC mismatch, or cut short: silence for the transport's
/// in-frame timeout before its end, expire()) gives up only its first byte; the bytes received after
/// it are scanned again from there, so that a good frame among them (the next command, sent after a
/// frame was cut short) is found, whether its end has come already or comes later. Bytes that only
/// look like a frame's start hold the frames after them at most until their length is reached or
/// the timeout expires. Allocation-free: the buffer holds one frame.
class Parser {
 public:
  enum Result : std::uint8_t { kPending, kFrame, kJunk, kBadHeader, kBadLength, kBadChecksum, kShortFrame };

  /// One received byte: the first event it completes (kPending: none); next() gives the others.
  Result feed(std::uint8_t b) {
    settle();
    if (n_ == kBuffer) compact();
    if (n_ == kBuffer) {  // events not drained: the byte cannot be kept (counted as junk)
      junk_ = 1;
      offset_ = fed_++;
      return kJunk;
    }
    buf_[n_++] = b;
    ++fed_;
    return scan();
  }
  /// The next event of the bytes already received (kPending: none left).
  Result next() {
    settle();
    return scan();
  }
  /// The transport's in-frame timeout: the frame in progress, if any, is cut short (kShortFrame;
  /// next() gives what the bytes after its first are found to hold). kPending when none was.
  Result expire() {
    settle();
    if (pos_ == 0 || s_ + pos_ < n_) return scan();  // no frame in progress, or bytes not scanned yet
    return fail(kShortFrame);
  }

  /// Bytes the last kJunk result discarded (1 or more).
  int junk() const { return junk_; }
  /// The error kind of a result other than kPending and kFrame.
  static constexpr LinkError error_of(Result r) {
    return r == kJunk         ? kErrJunk
           : r == kBadHeader  ? kErrHeader
           : r == kBadLength  ? kErrLength
           : r == kShortFrame ? kErrShortFrame
                              : kErrCrc;
  }
  /// True while a frame has started but not completed (the in-frame timeout applies).
  bool in_frame() const { return pos_ != 0 && frame_ == 0; }
  void reset() { s_ = n_ = pos_ = need_ = frame_ = junk_ = 0; }
  /// After kFrame: the frame's type.
  FrameType type() const { return static_cast<FrameType>(buf_[s_ + 2]); }
  /// After an event: the offset in the byte stream (bytes fed since construction, mod 2^32) of the
  /// frame's first byte; for kJunk, of its first byte.
  std::uint32_t offset() const { return offset_; }

  /// decode(frame): after kFrame, its payload into a frame of its type (false for another type).
#define OSC_FRAME_DECODE(Name, code, name, from, when, FIELDS) \
  bool decode(Name##Frame& f) const {                          \
    if (frame_ == 0 || type() != k##Name##Frame) return false; \
    detail::Reader r{buf_ + s_ + 4};                           \
    FIELDS(OSC_FIELD_GET)                                      \
    return true;                                               \
  }
  OSC_FRAME_LIST(OSC_FRAME_DECODE)
#undef OSC_FRAME_DECODE

 private:
  /// Room for a frame and the bytes after a candidate that failed near its end.
  static constexpr int kBuffer = 2 * kMaxFrame;

  /// The stream offset of buf_[s_].
  std::uint32_t start_offset() const { return fed_ - static_cast<std::uint32_t>(n_ - s_); }
  /// The frame the last call returned leaves the buffer.
  void settle() {
    if (frame_ == 0) return;
    s_ += frame_;
    frame_ = pos_ = 0;
    if (s_ == n_) s_ = n_ = 0;
  }

  /// Scans the bytes not yet scanned up to the next event: buf_[s_, s_ + pos_) is the candidate
  /// frame, buf_[s_ + pos_, n_) the bytes after it.
  Result scan() {
    int junk = 0;
    const std::uint32_t junk_at = start_offset();
    while (s_ + pos_ < n_) {
      const std::uint8_t b = buf_[s_ + pos_];
      if (pos_ == 0) {
        if (b != kSync0) {
          ++junk, ++s_;
          continue;
        }
        if (junk > 0) break;  // the junk before this frame first
        pos_ = 1;
      } else if (pos_ == 1) {
        if (b == kSync1) {
          pos_ = 2;
        } else {  // lost sync: the first sync byte was junk, this byte is scanned again
          ++junk, ++s_;
          pos_ = 0;
        }
      } else if (pos_ == 2) {
        pos_ = 3;
      } else if (pos_ == 3) {
        const int expect = payload_length(buf_[s_ + 2]);
        if (expect < 0 || b != expect) return fail(expect < 0 ? kBadHeader : kBadLength);
        need_ = b + kOverhead;
        pos_ = 4;
      } else if (++pos_ == need_) {
        const int len = buf_[s_ + 3];
        const std::uint16_t crc = static_cast<std::uint16_t>(buf_[s_ + 4 + len] | (buf_[s_ + 5 + len] << 8));
        if (crc16(buf_ + s_ + 2, len + 2) != crc) return fail(kBadChecksum);
        offset_ = start_offset();
        frame_ = need_;
        return kFrame;
      }
    }
    if (s_ == n_) s_ = n_ = 0;
    if (junk == 0) return kPending;
    junk_ = junk;
    offset_ = junk_at;
    return kJunk;
  }
  /// The candidate fails: its bytes after the first are scanned again by the next call.
  Result fail(Result r) {
    offset_ = start_offset();
    ++s_;
    pos_ = 0;
    return r;
  }
  void compact() {
    std::memmove(buf_, buf_ + s_, static_cast<std::size_t>(n_ - s_));
    n_ -= s_;
    s_ = 0;
  }

  std::uint8_t buf_[kBuffer] = {};
  int s_ = 0, n_ = 0, pos_ = 0, need_ = 0, frame_ = 0, junk_ = 0;
  std::uint32_t fed_ = 0, offset_ = 0;
};

#undef OSC_FIELD_PUT
#undef OSC_FIELD_GET

/// Calls visit(name, value) for each field of a frame, in wire order; value is the member itself (a
/// number, an array or LinkCounters). Host tools make their JSON keys from it (host_sim/frame_json.hpp).
#define OSC_FIELD_VISIT(type, name, extent, unit, doc) visit(#name, f.name);
#define OSC_FRAME_FOR_EACH(Name, code, name, from, when, FIELDS) \
  template <class Visit>                                         \
  void for_each_field(const Name##Frame& f, Visit&& visit) {     \
    FIELDS(OSC_FIELD_VISIT)                                      \
  }
OSC_FRAME_LIST(OSC_FRAME_FOR_EACH)
#undef OSC_FRAME_FOR_EACH
#undef OSC_FIELD_VISIT

}  // namespace pil
