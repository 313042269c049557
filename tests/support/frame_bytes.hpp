// Frames as bytes for the tests of the link's frames and commands (tests/firmware/link/, node_frames.hpp):
// a frame's encoding, a fresh parser fed it, its decoding as every type, and the command frames the tests
// send (a small relative move, a move_to with every field set).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <vector>

#include "osc/link/commands.hpp"

namespace osc::test {

using Bytes = std::vector<std::uint8_t>;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

template <class F>
Bytes bytes_of(const F& f) {
  Bytes b(pil::kMaxFrame);
  b.resize(static_cast<std::size_t>(pil::encode(f, b.data())));
  return b;
}

/// Feeds a frame's bytes to a fresh parser: kPending until the last byte, kFrame there.
inline pil::Parser parsed(const Bytes& b) {
  pil::Parser p;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const pil::Parser::Result r = p.feed(b[i]);
    EXPECT_EQ(r, i + 1 < b.size() ? pil::Parser::kPending : pil::Parser::kFrame) << "byte " << i;
  }
  return p;
}

/// Decodes a parsed frame as every type: only its own succeeds; returns that decoding.
template <class F>
F decoded(const pil::Parser& p) {
  pil::SensorFrame s;
  pil::ActuatorFrame a;
  pil::CommandFrame c;
  pil::AnswerFrame n;
  pil::StateFrame t;
  pil::SetpointFrame sp;
  pil::TraceFrame tr;
  pil::SetpointVelocityFrame sv;
  pil::ParamFrame pf;
  pil::ParamAnswerFrame pa;
  pil::IdentifyFrame id;
  pil::CaptureFrame cf;
  pil::CaptureDataFrame cd;
  pil::IdentifyPayloadFrame ip;
  pil::IdentifyOffsetFrame io;
  const int ok = p.decode(s) + p.decode(a) + p.decode(c) + p.decode(n) + p.decode(t) + p.decode(sp) + p.decode(tr) +
                 p.decode(sv) + p.decode(pf) + p.decode(pa) + p.decode(id) + p.decode(cf) + p.decode(cd) +
                 p.decode(ip) + p.decode(io);
  EXPECT_EQ(ok, 1);
  F f;
  EXPECT_TRUE(p.decode(f));
  return f;
}

/// A move_to of dz along z from where the queue ends (1 cm: half a second at the configured limits),
/// with `replace` a re-target.
inline pil::CommandFrame small_move(std::uint32_t id, double dz = 0.01, bool replace = false) {
  MoveRequest<double> req;
  req.relative = true;
  req.replace = replace;
  req.position(2) = dz;
  return frame_from_command(id, MotionVerb::kMoveTo, req);
}

/// The answers that end command `id` (answer_ends: done, or aborted with a reason).
inline std::vector<pil::AnswerFrame> endings(const std::vector<pil::AnswerFrame>& answers, std::uint32_t id) {
  std::vector<pil::AnswerFrame> e;
  for (const pil::AnswerFrame& a : answers)
    if (answer_ends(a, id)) e.push_back(a);
  return e;
}

inline pil::CommandFrame move_frame() {
  pil::CommandFrame f;
  f.id = 0x01020304;
  f.verb = static_cast<std::uint8_t>(MotionVerb::kMoveTo);
  f.flags = pil::kFlagHasRpy | pil::kFlagHasLimits;
  const float p[3] = {0.45f, -0.125f, 0.3f}, r[3] = {0.25f, -0.5f, 3.0f};
  const float l[6] = {0.05f, 0.2f, 2.0f, 0.4f, 0.75f, 8.0f};
  for (int i = 0; i < 3; ++i) f.position[i] = p[i], f.rpy[i] = r[i];
  for (int i = 0; i < 6; ++i) f.limits[i] = l[i];
  return f;
}

}  // namespace osc::test
