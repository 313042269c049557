// Fuzz target: the PIL link's streaming frame parser (osc/link/frames.hpp, pil::Parser).
//
// Invariants, checked after every byte fed:
//  - kFrame and kBadChecksum end a frame: the last length + 6 bytes fed are the sync pair, a known
//    type, that type's payload length, the payload and a CRC, which matches exactly for kFrame;
//  - a kFrame decodes as its own type only (every type of OSC_FRAME_LIST: sensor, actuator and the
//    command protocol's), and re-encoding the decoded frame gives back exactly the bytes fed;
//  - in_frame(): false after a completed frame; from idle only the first sync byte starts a frame;
//    a frame in progress stays in progress on kPending; after kBadHeader the parser is in a frame
//    only if that byte was a first sync byte (resynchronisation on A5);
//  - structured inputs (first byte odd): valid frames of every type built from the input, with
//    garbage between them, are each returned as kFrame on their last byte (never earlier) whenever
//    the parser was idle before the frame; a frame with one bit flipped in its payload or CRC ends in kBadChecksum.
#include <cstdint>
#include <cstring>
#include <vector>

#include "frame_builder.hpp"
#include "fuzz_util.hpp"
#include "osc/link/frames.hpp"

namespace {

/// The payload length of a type, from the table of frame types (not the parser's payload_length).
int payload_of(std::uint8_t type) {
  for (const pil::FrameInfo& f : pil::kFrames)
    if (f.type == type) return f.payload;
  return -1;
}

/// Decodes a completed frame as every type: exactly one, its own, succeeds; re-encodes it into out.
int decode_and_encode(const pil::Parser& p, std::uint8_t* out) {
  int decoded = 0, len = 0;
#define OSC_FUZZ_DECODE(Name, code, name, from, when, FIELDS) \
  {                                                           \
    pil::Name##Frame g;                                       \
    if (p.decode(g)) {                                        \
      ++decoded;                                              \
      FUZZ_CHECK(p.type() == pil::k##Name##Frame);            \
      len = pil::encode(g, out);                              \
    }                                                         \
  }
  OSC_FRAME_LIST(OSC_FUZZ_DECODE)
#undef OSC_FUZZ_DECODE
  FUZZ_CHECK(decoded == 1);
  return len;
}

struct Checked {
  pil::Parser p;
  std::vector<std::uint8_t> fed;

  pil::Parser::Result feed(std::uint8_t b) {
    const bool was_in = p.in_frame();
    fed.push_back(b);
    const pil::Parser::Result r = p.feed(b);
    switch (r) {
      case pil::Parser::kPending:
        if (was_in)
          FUZZ_CHECK(p.in_frame());
        else
          FUZZ_CHECK(p.in_frame() == (b == pil::kSync0));
        break;
      case pil::Parser::kJunk:  // bytes discarded while hunting for the sync pair
        FUZZ_CHECK(p.junk() == 1 || p.junk() == 2);
        break;
      case pil::Parser::kBadLength:  // a known type with another length: the frame is dropped
        FUZZ_CHECK(was_in);
        FUZZ_CHECK(!p.in_frame());
        break;
      case pil::Parser::kBadHeader:
        FUZZ_CHECK(was_in);
        if (p.in_frame()) FUZZ_CHECK(b == pil::kSync0);
        break;
      case pil::Parser::kFrame:
      case pil::Parser::kBadChecksum: {
        FUZZ_CHECK(was_in);
        FUZZ_CHECK(!p.in_frame());
        const int n = payload_of(p.type());
        FUZZ_CHECK(n > 0);
        const std::size_t total = static_cast<std::size_t>(n + pil::kOverhead);
        FUZZ_CHECK(fed.size() >= total);
        const std::uint8_t* f = fed.data() + fed.size() - total;
        FUZZ_CHECK(f[0] == pil::kSync0 && f[1] == pil::kSync1 && f[2] == p.type() && f[3] == n);
        const std::uint16_t crc = pil::crc16(f + 2, n + 2);
        const std::uint16_t got = static_cast<std::uint16_t>(f[total - 2] | (f[total - 1] << 8));
        FUZZ_CHECK((crc == got) == (r == pil::Parser::kFrame));
        if (r == pil::Parser::kFrame) {
          std::uint8_t out[pil::kMaxFrame];
          const int len = decode_and_encode(p, out);
          FUZZ_CHECK(len == static_cast<int>(total));
          FUZZ_CHECK(std::memcmp(out, f, total) == 0);
        }
        break;
      }
      default:
        FUZZ_CHECK(false);
    }
    return r;
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  Checked c;
  if ((in.u8() & 1) == 0) {
    // Raw bytes.
    while (!in.empty()) c.feed(in.u8());
    return 0;
  }
  // Structured: garbage, then a frame (maybe with one bit flipped), repeatedly. The frame's type:
  // bit 3 and bits 5-6 of op, an index into the frame types (0 sensor, 1 actuator, then the others).
  while (!in.empty()) {
    const std::uint8_t op = in.u8();
    for (int k = op & 7; k > 0; --k) c.feed(in.u8());
    std::uint8_t buf[pil::kMaxFrame];
    const int index = ((op >> 3) & 1) | (((op >> 5) & 3) << 1);
    const int len = fuzz::build_frame_of(in, pil::kFrames[index % pil::kFrameTypes].type, buf);
    int flip = -1;
    if (op & 0x10) {
      flip = 4 + in.u8() % (len - 4);  // payload or CRC
      buf[flip] ^= static_cast<std::uint8_t>(1u << (in.u8() & 7));
    }
    const bool idle = !c.p.in_frame();
    for (int i = 0; i < len; ++i) {
      const pil::Parser::Result r = c.feed(buf[i]);
      if (!idle) continue;
      if (i < len - 1)
        FUZZ_CHECK(r == pil::Parser::kPending);
      else
        FUZZ_CHECK(r == (flip < 0 ? pil::Parser::kFrame : pil::Parser::kBadChecksum));
    }
  }
  return 0;
}
