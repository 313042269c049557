// Fuzz target: the link's streaming frame parser (osc/link/frames.hpp, pil::Parser) and its
// resynchronisation.
//
// Invariants, checked at every event (every byte's events drained with next(); in-frame timeouts,
// expire(), where the input asks):
//  - kFrame: the bytes at offset() in the stream fed are the sync pair, a known type, that type's
//    payload length, the payload and a matching CRC; the frame decodes as its own type only, and
//    re-encoding it gives back exactly those bytes;
//  - an error (kBadHeader, kBadLength, kBadChecksum, kShortFrame): offset() is a first sync byte of
//    the stream; kBadChecksum's bytes there are a complete frame of a known type whose CRC does not
//    match; kJunk: junk() >= 1;
//  - every byte is accounted for exactly once: at the end, with the timeout until no frame is in
//    progress, frames' lengths, one byte per error and the junk add up to the bytes fed;
//  - structured inputs (first byte odd): valid frames of every type built from the input, with
//    garbage, cut frames and flipped bits between them; every intact frame is found, unless a frame
//    that was found overlaps it (a CRC that matched across them).

#include <cstdint>
#include <cstring>
#include <utility>
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
  std::vector<std::pair<std::size_t, std::size_t>> found;  // [offset, end) of each kFrame
  std::size_t accounted = 0;

  void feed(std::uint8_t b) {
    fed.push_back(b);
    drain(p.feed(b));
  }
  void expire() { drain(p.expire()); }
  /// The end of the input: the timeout until nothing is in progress.
  void finish() {
    while (p.in_frame()) expire();
    FUZZ_CHECK(accounted == fed.size());
  }

 private:
  void drain(pil::Parser::Result r) {
    for (; r != pil::Parser::kPending; r = p.next()) check(r);
  }
  void check(pil::Parser::Result r) {
    const std::size_t at = p.offset();
    FUZZ_CHECK(at < fed.size());
    if (r == pil::Parser::kJunk) {
      FUZZ_CHECK(p.junk() >= 1);
      accounted += static_cast<std::size_t>(p.junk());
      return;
    }
    FUZZ_CHECK(fed[at] == pil::kSync0);
    if (r != pil::Parser::kFrame && r != pil::Parser::kBadChecksum) {
      FUZZ_CHECK(r == pil::Parser::kBadHeader || r == pil::Parser::kBadLength || r == pil::Parser::kShortFrame);
      ++accounted;
      return;
    }
    FUZZ_CHECK(at + 4 <= fed.size());
    const int n = payload_of(fed[at + 2]);
    FUZZ_CHECK(n > 0 && fed[at + 1] == pil::kSync1 && fed[at + 3] == n);
    const std::size_t total = static_cast<std::size_t>(n + pil::kOverhead);
    FUZZ_CHECK(at + total <= fed.size());
    const std::uint8_t* f = fed.data() + at;
    const std::uint16_t crc = pil::crc16(f + 2, n + 2);
    const std::uint16_t got = static_cast<std::uint16_t>(f[total - 2] | (f[total - 1] << 8));
    FUZZ_CHECK((crc == got) == (r == pil::Parser::kFrame));
    if (r == pil::Parser::kBadChecksum) {
      ++accounted;
      return;
    }
    FUZZ_CHECK(p.type() == f[2]);
    std::uint8_t out[pil::kMaxFrame];
    const int len = decode_and_encode(p, out);
    FUZZ_CHECK(len == static_cast<int>(total));
    FUZZ_CHECK(std::memcmp(out, f, total) == 0);
    found.emplace_back(at, at + total);
    accounted += total;
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  Checked c;
  if ((in.u8() & 1) == 0) {
    // Raw bytes; a byte 0xFF followed by an odd byte is the in-frame timeout.
    while (!in.empty()) {
      const std::uint8_t b = in.u8();
      if (b == 0xFF && (in.u8() & 1)) {
        c.expire();
        continue;
      }
      c.feed(b);
    }
    c.finish();
    return 0;
  }
  // Structured: garbage, then a frame (intact, with one bit flipped, or cut short, maybe then the
  // timeout), repeatedly. The frame's type: bit 3 and bits 5-6 of op, an index into the frame types.
  std::vector<std::pair<std::size_t, std::size_t>> intact;
  while (!in.empty()) {
    const std::uint8_t op = in.u8();
    for (int k = op & 7; k > 0; --k) c.feed(in.u8());
    std::uint8_t buf[pil::kMaxFrame];
    const int index = ((op >> 3) & 1) | (((op >> 5) & 3) << 1);
    int len = fuzz::build_frame_of(in, pil::kFrames[index % pil::kFrameTypes].type, buf);
    const bool flip = (op & 0x10) != 0, cut = (op & 0x80) != 0;
    if (flip) buf[4 + in.u8() % (len - 4)] ^= static_cast<std::uint8_t>(1u << (in.u8() & 7));
    if (cut) len = 1 + in.u8() % (len - 1);
    if (!flip && !cut) intact.emplace_back(c.fed.size(), c.fed.size() + static_cast<std::size_t>(len));
    for (int i = 0; i < len; ++i) c.feed(buf[i]);
    if (cut && (in.u8() & 1)) c.expire();
  }
  c.finish();
  for (const auto& [b, e] : intact) {
    bool hit = false;
    for (const auto& [fb, fe] : c.found) hit |= (fb == b && fe == e) || (fb < e && b < fe);
    FUZZ_CHECK(hit);
  }
  return 0;
}
