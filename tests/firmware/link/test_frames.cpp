// The link's frame parser (osc/link/frames.hpp, pil::Parser) and its resynchronisation: a frame that
// fails (cut short, a bad CRC, an unknown type or length) gives up only its first byte, and a good
// frame among the bytes received after it is found, at once or when the in-frame timeout expires.
// Checked: every cut point of every frame type followed by a good frame; a frame inside a failed
// candidate; junk coalesced; every byte accounted for exactly once; a seeded random stream of frames,
// cut frames and junk in which every intact frame is found.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "osc/link/frames.hpp"

namespace {

using Bytes = std::vector<std::uint8_t>;

struct Event {
  pil::Parser::Result r;
  std::uint32_t offset;
  int bytes;  ///< what it accounts for: a frame's length, a junk run's, 1 for a failed frame's first byte
  Bytes frame;
};

/// The bytes a parser event accounts for.
int accounted(const pil::Parser& p, pil::Parser::Result r) {
  if (r == pil::Parser::kJunk) return p.junk();
  if (r == pil::Parser::kFrame) return pil::payload_length(p.type()) + pil::kOverhead;
  return 1;
}

/// Every event of a result and of the bytes already received after it.
void drain(pil::Parser& p, pil::Parser::Result r, std::vector<Event>& out, const Bytes& stream) {
  for (; r != pil::Parser::kPending; r = p.next()) {
    Event e{r, p.offset(), accounted(p, r), {}};
    if (r == pil::Parser::kFrame)
      e.frame.assign(stream.begin() + e.offset, stream.begin() + e.offset + static_cast<std::uint32_t>(e.bytes));
    out.push_back(e);
  }
}

/// Feeds bytes, draining every event; with `expire`, the in-frame timeout at the end.
std::vector<Event> parse(pil::Parser& p, const Bytes& stream, std::size_t from = 0, bool expire = true) {
  std::vector<Event> ev;
  for (std::size_t i = from; i < stream.size(); ++i) drain(p, p.feed(stream[i]), ev, stream);
  // The timeout until nothing is in progress (a scan after one may start another candidate).
  while (expire && p.in_frame()) drain(p, p.expire(), ev, stream);
  return ev;
}
std::vector<Event> parse(const Bytes& stream) {
  pil::Parser p;
  return parse(p, stream);
}

int frames_in(const std::vector<Event>& ev) {
  int n = 0;
  for (const Event& e : ev) n += e.r == pil::Parser::kFrame;
  return n;
}
int total_bytes(const std::vector<Event>& ev) {
  int n = 0;
  for (const Event& e : ev) n += e.bytes;
  return n;
}

/// A frame of each type, its fields from a seed (the CRC valid).
Bytes frame_of(int type_index, std::uint32_t seed) {
  const pil::FrameInfo& info = pil::kFrames[type_index];
  Bytes b(static_cast<std::size_t>(info.payload + pil::kOverhead));
  b[0] = pil::kSync0, b[1] = pil::kSync1, b[2] = info.type, b[3] = static_cast<std::uint8_t>(info.payload);
  std::mt19937 rng(seed);
  for (int i = 0; i < info.payload; ++i) b[static_cast<std::size_t>(4 + i)] = static_cast<std::uint8_t>(rng());
  const std::uint16_t crc = pil::crc16(b.data() + 2, info.payload + 2);
  b[b.size() - 2] = static_cast<std::uint8_t>(crc & 0xFF);
  b[b.size() - 1] = static_cast<std::uint8_t>(crc >> 8);
  return b;
}

Bytes clear_command(std::uint32_t id) {
  pil::CommandFrame c;
  c.id = id;
  c.verb = 6;  // clear
  Bytes b(pil::kMaxFrame);
  b.resize(static_cast<std::size_t>(pil::encode(c, b.data())));
  return b;
}

Bytes cat(const Bytes& a, const Bytes& b) {
  Bytes r = a;
  r.insert(r.end(), b.begin(), b.end());
  return r;
}

}  // namespace

// A clean frame: pending on every byte but the last, which is the frame; nothing else.
TEST(Parser, ACleanFrameEndsOnItsLastByte) {
  const Bytes f = clear_command(7);
  pil::Parser p;
  for (std::size_t i = 0; i + 1 < f.size(); ++i) ASSERT_EQ(p.feed(f[i]), pil::Parser::kPending);
  ASSERT_EQ(p.feed(f.back()), pil::Parser::kFrame);
  pil::CommandFrame c;
  ASSERT_TRUE(p.decode(c));
  EXPECT_EQ(c.id, 7u);
  EXPECT_EQ(p.offset(), 0u);
  EXPECT_EQ(p.next(), pil::Parser::kPending);
  EXPECT_FALSE(p.decode(c));  // the frame has left the buffer
}

// Issue 53, defect 3: half a frame, then a good command at once (no timeout between: the cut frame's
// length takes the command's first bytes) or after the in-frame timeout: the command is found either
// way, at every cut point of every frame type, and every byte is accounted for once.
TEST(Parser, AFrameCutShortAtAnyPointLosesNotTheNextFrame) {
  const Bytes next = clear_command(42);
  for (int t = 0; t < pil::kFrameTypes; ++t) {
    const Bytes cut_from = frame_of(t, 1000u + static_cast<std::uint32_t>(t));
    for (std::size_t k = 1; k < cut_from.size(); ++k) {
      const Bytes stream = cat(Bytes(cut_from.begin(), cut_from.begin() + static_cast<std::ptrdiff_t>(k)), next);
      // Back to back: the command is found when the cut frame's length is reached or it expires.
      const std::vector<Event> ev = parse(stream);
      ASSERT_EQ(frames_in(ev), 1) << pil::kFrames[t].name << " cut after " << k;
      EXPECT_EQ(ev.back().r, pil::Parser::kFrame) << pil::kFrames[t].name << " cut after " << k;
      EXPECT_EQ(ev.back().frame, next);
      EXPECT_EQ(ev.back().offset, k);
      EXPECT_EQ(total_bytes(ev), static_cast<int>(stream.size()));
      // With the in-frame timeout between them: the cut frame is a short frame (or junk: a cut sync
      // pair), the command found as it ends.
      pil::Parser p;
      std::vector<Event> before = parse(p, Bytes(stream.begin(), stream.begin() + static_cast<std::ptrdiff_t>(k)));
      const std::vector<Event> after = parse(p, stream, k);
      ASSERT_EQ(frames_in(before), 0);
      EXPECT_EQ(before.front().r, pil::Parser::kShortFrame) << k;
      ASSERT_EQ(frames_in(after), 1) << pil::kFrames[t].name << " cut after " << k;
      EXPECT_EQ(after.back().frame, next);
      EXPECT_EQ(total_bytes(before) + total_bytes(after), static_cast<int>(stream.size()));
    }
  }
}

// A long frame's header whose length swallows a whole short frame: the short one is found once the
// long one fails (its CRC, with the bytes after it) or expires (nothing after it).
TEST(Parser, AFrameInsideAFailedCandidateIsFound) {
  const Bytes actuator = frame_of(1, 5);  // 223 bytes
  const Bytes inner = clear_command(9);
  const Bytes head(actuator.begin(), actuator.begin() + 10);
  // Nothing after: found at the timeout.
  std::vector<Event> ev = parse(cat(head, inner));
  ASSERT_EQ(frames_in(ev), 1);
  EXPECT_EQ(ev.front().r, pil::Parser::kShortFrame);
  EXPECT_EQ(ev.back().frame, inner);
  // More frames after it: the candidate completes with a bad CRC, and both are found in order.
  const Bytes after = frame_of(1, 6);
  ev = parse(cat(cat(cat(head, inner), after), after));
  std::vector<Bytes> found;
  for (const Event& e : ev)
    if (e.r == pil::Parser::kFrame) found.push_back(e.frame);
  ASSERT_EQ(found.size(), 3u);
  EXPECT_EQ(found[0], inner);
  EXPECT_EQ(found[1], after);
  EXPECT_EQ(found[2], after);
  EXPECT_EQ(ev.front().r, pil::Parser::kBadChecksum);
}

// A corrupted frame gives up one byte; the rest is junk unless a frame starts in it, and a run of
// junk scanned at once is one event; junk fed byte by byte is reported as it comes.
TEST(Parser, JunkRunsAreOneEventAndBadFramesOneByte) {
  Bytes junk(100, 0x11);
  std::vector<Event> ev = parse(junk);
  ASSERT_EQ(ev.size(), 100u);
  for (const Event& e : ev) EXPECT_EQ(e.r, pil::Parser::kJunk);
  EXPECT_EQ(total_bytes(ev), 100);
  Bytes bad = clear_command(3);
  bad[10] ^= 0x40;
  ev = parse(cat(bad, clear_command(4)));
  ASSERT_GE(ev.size(), 3u);
  EXPECT_EQ(ev[0].r, pil::Parser::kBadChecksum);
  EXPECT_EQ(ev[0].bytes, 1);
  EXPECT_EQ(ev[1].r, pil::Parser::kJunk);
  EXPECT_EQ(ev[1].bytes, static_cast<int>(bad.size()) - 1);
  EXPECT_EQ(ev[2].r, pil::Parser::kFrame);
  EXPECT_EQ(ev[2].frame, clear_command(4));
  // An unknown type and a wrong length: the same, at the fourth byte.
  for (std::uint8_t type_len : {std::uint8_t{2}, std::uint8_t{3}}) {
    Bytes h = clear_command(5);
    h[type_len] = 0xEE;
    ev = parse(cat(h, clear_command(6)));
    EXPECT_EQ(ev[0].r, type_len == 2 ? pil::Parser::kBadHeader : pil::Parser::kBadLength);
    EXPECT_EQ(frames_in(ev), 1);
    EXPECT_EQ(ev.back().frame, clear_command(6));
  }
}

// A seeded random stream: intact frames of every type, frames cut short, corrupted frames and junk,
// fed in one go. Every intact frame that no found frame overlaps is found, in order; nothing else
// is a frame but by a CRC match; every byte is accounted for once.
TEST(Parser, ARandomStreamLosesNoIntactFrame) {
  std::mt19937 rng(53);
  for (int run = 0; run < 200; ++run) {
    Bytes stream;
    std::vector<std::pair<std::size_t, Bytes>> intact;
    for (int piece = 0; piece < 30; ++piece) {
      const Bytes f = frame_of(static_cast<int>(rng() % pil::kFrameTypes), rng());
      switch (rng() % 4) {
        case 0:
          intact.emplace_back(stream.size(), f);
          stream.insert(stream.end(), f.begin(), f.end());
          break;
        case 1:  // cut short
          stream.insert(stream.end(), f.begin(), f.begin() + 1 + static_cast<std::ptrdiff_t>(rng() % (f.size() - 1)));
          break;
        case 2: {  // one bit flipped
          Bytes g = f;
          g[rng() % g.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
          stream.insert(stream.end(), g.begin(), g.end());
          break;
        }
        default:
          for (int j = static_cast<int>(rng() % 20); j > 0; --j)
            stream.push_back(rng() % 3 == 0 ? pil::kSync0 : static_cast<std::uint8_t>(rng()));
      }
    }
    const std::vector<Event> ev = parse(stream);
    ASSERT_EQ(total_bytes(ev), static_cast<int>(stream.size())) << "run " << run;
    std::vector<std::pair<std::size_t, std::size_t>> found;
    for (const Event& e : ev) {
      if (e.r != pil::Parser::kFrame) continue;
      found.emplace_back(e.offset, e.offset + static_cast<std::size_t>(e.bytes));
      const std::uint16_t crc = static_cast<std::uint16_t>(e.frame[e.frame.size() - 2] | (e.frame.back() << 8));
      ASSERT_EQ(pil::crc16(e.frame.data() + 2, static_cast<int>(e.frame.size()) - 4), crc);
    }
    for (const auto& [at, f] : intact) {
      bool hit = false, overlapped = false;
      for (const auto& [b, e] : found) {
        hit |= b == at && e == at + f.size();
        overlapped |= b < at + f.size() && at < e;
      }
      EXPECT_TRUE(hit || overlapped) << "run " << run << ": the intact frame at " << at << " was lost";
    }
  }
}
