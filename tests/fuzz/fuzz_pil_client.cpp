// Fuzz target: the host side of the PIL link, the parsing of PilClient::receive()
// (host_sim/pil_client.cpp, sim::parse_actuator_bytes) on whatever the firmware sends. The byte
// stream is either raw (first byte even) or built from the input as garbage and well-formed
// actuator and sensor frames, some with one bit flipped (first byte odd). It is parsed twice: as
// one buffer, and as the client receives it, in reads of fuzzed sizes (1..512 bytes, its buffer)
// with the unparsed rest of a read kept for the next call.
//
// Invariants:
//  - the client's results do not depend on how the stream is split into reads: the same sequence
//    of frames (bit for bit) and errors (same messages) either way;
//  - a call consumes bytes only up to the end of its buffer and returns kNeedMore only there;
//  - a kFrame is the actuator frame whose encoding are the bytes at the parser's offset (the last
//    consumed, or, found after an error, earlier ones: the parser's resynchronisation); a kError
//    comes with one of the client's four messages (unexpected frame type, checksum, header type,
//    header length) and is counted once by its kind;
//  - every well-formed actuator frame that starts while the parser is idle is received intact, and
//    a sensor frame in its place is reported as an unexpected frame type.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "fuzz_util.hpp"
#include "pil_client.hpp"

namespace {

struct Event {
  sim::RxResult r;
  std::string err;
  std::uint8_t frame[pil::kMaxFrame];
  std::size_t end;    // stream offset just past the last byte consumed
  std::size_t start;  // stream offset of the frame (or the failed frame) the event is about

  bool operator==(const Event& o) const {
    return r == o.r && err == o.err && end == o.end && start == o.start &&
           (r != sim::RxResult::kFrame || std::memcmp(frame, o.frame, sizeof frame) == 0);
  }
};

const char* const kErrors[] = {
    "unexpected frame type from the firmware", "corrupted actuator frame (checksum mismatch)",
    "corrupted actuator frame (bad header: unknown type)", "corrupted actuator frame (bad header: wrong length)"};

/// One call of the client's parsing on buf[pos..len), checked; appends its event unless kNeedMore.
sim::RxResult step(pil::Parser& parser, const std::uint8_t* buf, int len, int& pos, std::size_t base,
                   const std::vector<std::uint8_t>& stream, std::vector<Event>& events) {
  const int pos0 = pos;
  pil::ActuatorFrame f;
  std::string err;
  pil::LinkCounters counters;
  const sim::RxResult r = sim::parse_actuator_bytes(parser, buf, len, pos, f, counters, err);
  // An error is counted once, by its kind; a frame counts nothing but the junk before it.
  if (r == sim::RxResult::kError) FUZZ_CHECK(counters.total() - counters[pil::kErrJunk] == 1);
  if (r == sim::RxResult::kFrame) FUZZ_CHECK(counters.total() == counters[pil::kErrJunk]);
  FUZZ_CHECK(pos >= pos0 && pos <= len);
  if (r == sim::RxResult::kNeedMore) {
    FUZZ_CHECK(pos == len);
    return r;
  }
  // An event of bytes received before (a frame found after an error) consumes nothing new.
  Event e{r, err, {}, base + static_cast<std::size_t>(pos), parser.offset()};
  FUZZ_CHECK(e.start < e.end);
  if (r == sim::RxResult::kFrame) {
    const int n = pil::encode(f, e.frame);
    FUZZ_CHECK(n == pil::kActuatorPayload + pil::kOverhead);
    FUZZ_CHECK(e.start + static_cast<std::size_t>(n) <= e.end);
    FUZZ_CHECK(std::memcmp(e.frame, stream.data() + e.start, static_cast<std::size_t>(n)) == 0);
  } else {
    FUZZ_CHECK(std::find(std::begin(kErrors), std::end(kErrors), err) != std::end(kErrors));
  }
  events.push_back(e);
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  const std::uint8_t mode = in.u8();
  std::uint8_t reads[8];
  for (auto& r : reads) r = in.u8();

  // The stream, and where the well-formed frames that must come through are.
  std::vector<std::uint8_t> stream;
  struct Expect {
    std::size_t start;
    bool actuator;
  };
  std::vector<Expect> expect;
  if ((mode & 1) == 0) {
    std::size_t n;
    const std::uint8_t* p = in.rest(n);
    stream.assign(p, p + n);
  } else {
    pil::Parser idle;  // tracks whether a frame starting here starts from idle
    auto push = [&](std::uint8_t b) {
      stream.push_back(b);
      for (pil::Parser::Result r = idle.feed(b); r != pil::Parser::kPending; r = idle.next()) {
      }
    };
    while (!in.empty()) {
      const std::uint8_t op = in.u8();
      for (int k = op & 7; k > 0; --k) push(in.u8());
      std::uint8_t buf[pil::kMaxFrame];
      const bool actuator = (op & 8) == 0;
      const int len = fuzz::build_frame(in, actuator, buf);
      const bool flip = (op & 0x30) == 0x30;
      if (flip) buf[4 + in.u8() % (len - 4)] ^= static_cast<std::uint8_t>(1u << (in.u8() & 7));
      const bool from_idle = !idle.in_frame();
      const std::size_t start = stream.size();
      for (int i = 0; i < len; ++i) push(buf[i]);
      if (from_idle && !flip) expect.push_back({start, actuator});
    }
  }

  // Parsed as one buffer.
  std::vector<Event> whole;
  {
    pil::Parser parser;
    int pos = 0;
    const int len = static_cast<int>(stream.size());
    while (step(parser, stream.data(), len, pos, 0, stream, whole) != sim::RxResult::kNeedMore) {
    }
  }
  // Parsed as the client receives it: reads of up to 512 bytes into its buffer, the rest of a read
  // parsed by the next call before anything new is read.
  std::vector<Event> chunked;
  {
    pil::Parser parser;
    std::uint8_t rx[512];
    std::size_t off = 0;
    for (int k = 0; off < stream.size(); ++k) {
      const std::size_t want = 1 + (reads[k % 8] * 2 + static_cast<std::size_t>(k)) % 512;
      const int n = static_cast<int>(std::min(want, stream.size() - off));
      std::memcpy(rx, stream.data() + off, static_cast<std::size_t>(n));
      int pos = 0;
      while (step(parser, rx, n, pos, off, stream, chunked) != sim::RxResult::kNeedMore) {
      }
      off += static_cast<std::size_t>(n);
    }
  }
  FUZZ_CHECK(whole == chunked);

  // Every well-formed frame that started from idle came through as itself.
  for (const Expect& x : expect) {
    const auto it = std::find_if(whole.begin(), whole.end(), [&](const Event& e) { return e.start == x.start; });
    FUZZ_CHECK(it != whole.end());
    if (x.actuator)
      FUZZ_CHECK(it->r == sim::RxResult::kFrame);
    else
      FUZZ_CHECK(it->r == sim::RxResult::kError && it->err == kErrors[0]);
  }
  return 0;
}
