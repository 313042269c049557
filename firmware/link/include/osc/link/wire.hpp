// The link's bytes, below the frames (osc/link/frames.hpp): the kinds of link error a receiver
// counts, the wire form of a field's type, the frames' CRC-16/CCITT-FALSE, and the little-endian
// writer and reader that encode and decode every payload.
#pragma once

#include <cstdint>
#include <cstring>

#include "osc/control/faults.hpp"  // OSC_X_NAME, OSC_X_DOC, OSC_X_ENUMERATOR

namespace pil {

/// The kinds of link error a receiver tells apart, each counted (LinkCounters) in telemetry.
// X(Name, "name", meaning), in counter order.
#define OSC_LINK_ERROR_LIST(X)                                                                        \
  X(Crc, "bad_crc", "a complete frame whose CRC does not match")                                      \
  X(Header, "bad_header", "the sync pair, then an unknown frame type (or a frame of the wrong type)") \
  X(Length, "bad_length", "the sync pair and a known type, with the wrong length")                    \
  X(Junk, "junk_bytes", "bytes discarded while hunting for the sync pair (junk, lost sync)")          \
  X(ShortFrame, "short_frames", "a frame that started and was cut short (silence before its end)")    \
  X(Seq, "seq_errors", "a valid frame with an unexpected sequence number")                            \
  X(Silence, "timeouts", "no frame within the silence limit")

#define OSC_X_PREFIX kErr
enum LinkError : std::uint8_t { OSC_LINK_ERROR_LIST(OSC_X_ENUMERATOR) kLinkErrorKinds };
#undef OSC_X_PREFIX
/// Names in telemetry (JSON, logs), in LinkError order.
constexpr const char* kLinkErrorNames[kLinkErrorKinds] = {OSC_LINK_ERROR_LIST(OSC_X_NAME)};
/// What each kind means, in LinkError order.
constexpr const char* kLinkErrorDocs[kLinkErrorKinds] = {OSC_LINK_ERROR_LIST(OSC_X_DOC)};

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

namespace detail {
/// The wire form of a field's C++ type: element type name, element size and count.
template <class T>
struct Wire;
template <>
struct Wire<std::uint8_t> {
  static constexpr const char* type_name = "u8";
  static constexpr int size = 1, count = 1;
};
template <>
struct Wire<std::uint32_t> {
  static constexpr const char* type_name = "u32";
  static constexpr int size = 4, count = 1;
};
template <>
struct Wire<std::int16_t> {
  static constexpr const char* type_name = "i16";
  static constexpr int size = 2, count = 1;
};
template <>
struct Wire<std::int32_t> {
  static constexpr const char* type_name = "i32";
  static constexpr int size = 4, count = 1;
};
template <>
struct Wire<float> {
  static constexpr const char* type_name = "f32";
  static constexpr int size = 4, count = 1;
};
static_assert(sizeof(float) == 4, "f32 is IEEE 754 binary32");
template <class T, int N>
struct Wire<T[N]> {
  static constexpr const char* type_name = Wire<T>::type_name;
  static constexpr int size = Wire<T>::size, count = N * Wire<T>::count;
};
template <>
struct Wire<LinkCounters> : Wire<std::uint32_t[kLinkErrorKinds]> {};
template <class T>
constexpr int kWireBytes = Wire<T>::size* Wire<T>::count;
}  // namespace detail

/// CRC-16/CCITT-FALSE (polynomial 0x1021, initial 0xFFFF), one bit at a time: the definition,
/// which makes the table below and the tests' reference.
constexpr std::uint16_t crc16_bitwise(const std::uint8_t* p, int n, std::uint16_t crc = 0xFFFF) {
  for (int i = 0; i < n; ++i) {
    crc = static_cast<std::uint16_t>(crc ^ (static_cast<std::uint16_t>(p[i]) << 8));
    for (int b = 0; b < 8; ++b) crc = static_cast<std::uint16_t>((crc & 0x8000) ? (crc << 1) ^ 0x1021 : (crc << 1));
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
/// Writes fields in their wire form, little-endian.
struct Writer {
  std::uint8_t* p;
  void put(std::uint8_t v) { *p++ = v; }
  void put(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) *p++ = static_cast<std::uint8_t>(v >> (8 * i));
  }
  void put(std::int32_t v) { put(static_cast<std::uint32_t>(v)); }
  void put(std::int16_t v) {
    const auto u = static_cast<std::uint16_t>(v);
    *p++ = static_cast<std::uint8_t>(u & 0xFF);
    *p++ = static_cast<std::uint8_t>(u >> 8);
  }
  void put(float v) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    put(u);
  }
  template <class T, int N>
  void put(const T (&a)[N]) {
    for (const T& v : a) put(v);
  }
  void put(const LinkCounters& c) { put(c.count); }
};
/// Reads them back.
struct Reader {
  const std::uint8_t* p;
  void get(std::uint8_t& v) { v = *p++; }
  void get(std::uint32_t& v) {
    v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(*p++) << (8 * i);
  }
  void get(std::int32_t& v) {
    std::uint32_t u;
    get(u);
    v = static_cast<std::int32_t>(u);
  }
  void get(std::int16_t& v) {
    const auto u = static_cast<std::uint16_t>(p[0] | (p[1] << 8));
    p += 2;
    v = static_cast<std::int16_t>(u);
  }
  void get(float& v) {
    std::uint32_t u;
    get(u);
    std::memcpy(&v, &u, 4);
  }
  template <class T, int N>
  void get(T (&a)[N]) {
    for (T& v : a) get(v);
  }
  void get(LinkCounters& c) { get(c.count); }
};
}  // namespace detail

}  // namespace pil
