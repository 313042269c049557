// Fuzz target: the command protocol's decoding (osc/link/commands.hpp) behind the link's parser
// (osc/link/frames.hpp, pil::Parser): command frames from arbitrary bytes, each checked and decoded
// (command_from_frame), then prepared as the task's mailbox would take it (prepare_frame_command:
// prepare_move for a move_to) against a MotionGenerator<double> holding a pose, running a queued
// move or running the paper's motion. Accepted moves are queued, so that later commands plan from
// where they end (and fill the queue).
//
// Input: byte 0 chooses the generator's situation (bits 1-2) and the tick the commands are prepared
// for (bits 3-7, 50 ms each); bit 0 the format of the rest:
//   0  raw bytes, fed to the parser; every command frame it completes is checked;
//   1  frames built from the input: op (bits 0-2: garbage bytes before the frame; bit 3: the numbers
//      as raw f32 bits, NaNs and infinities included, else as 16-bit integers scaled into and around
//      the bounds; bit 4: one bit of the frame flipped; bits 5-6: 1 a setpoint frame, 2 a setpoint
//      with velocity, else a command frame), id, verb, flags, the numbers.
//
// Invariants:
//  - a command frame is refused exactly when the specification (docs/protocol.md, Command checks:
//    written again here independently) says it is bad, and then with bad_command; an accepted one
//    encodes back to the same bytes (frame_from_command); every frame of another type, and every
//    frame with a flipped bit, is no command;
//  - prepare_frame_command keeps the id, the verb (none for a verb outside the list) and a refusal
//    of the reason list, bad_command exactly when decoding refused;
//  - a setpoint, with its velocity or not, is dropped exactly when the specification says it is bad
//    (Setpoint flags, the command's bounds, the velocities'); a good one for the running stream is
//    prepared into finite coordinates and rates, and the generator's next reference is finite;
//  - an accepted move's duration is finite; its reference (CartesianMove::at) is finite at a dozen
//    times over its duration and beyond, and its linear speed never exceeds the configured maximum
//    (CartesianLimits<double>::defaults().linear.v), nor the request's own limit, by more than
//    1e-9 relative; a queued move (no brake) ends at the target move_target() names.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>

#include "fuzz_util.hpp"
#include "osc/control/gains.hpp"
#include "osc/link/commands.hpp"

namespace {

using osc::MotionReason;
using osc::MotionVerb;

constexpr std::uint32_t kHz = osc::params::kControlHz;
const osc::CartesianLimits<double> kMax = osc::CartesianLimits<double>::defaults();

/// The command checks of docs/protocol.md, written from the document (not from the code).
bool valid_by_the_document(const pil::CommandFrame& f) {
  if (f.verb > 10 || (f.flags & 0xE0) != 0) return false;             // verbs 0 to 10; flags 0 to 4 (payload)
  if (f.verb == 7 && (f.period < 1 || f.period > 100)) return false;  // stream: 1 to 100 ms
  for (int i = 0; i < 3; ++i) {
    if (std::isnan(f.position[i]) || std::isinf(f.position[i]) || f.position[i] < -10.0f || f.position[i] > 10.0f)
      return false;
    const double r = f.rpy[i];
    if (std::isnan(r) || r < -2 * osc::kPi || r > 2 * osc::kPi) return false;
  }
  for (float l : f.limits) {
    if (!std::isfinite(l)) return false;
    if ((f.flags & 8) && l <= 0.0f) return false;
  }
  return true;
}

struct Checker {
  osc::MotionGenerator<double> gen;
  std::uint64_t next_tick = 1;
  int accepted = 0;

  void setup(std::uint8_t how) {
    const osc::Pose<double> start{osc::Vec3<double>(0.5, 0.1, 0.3), osc::rpy_rotation<double>({0.1, -0.2, 0.3})};
    gen.hold(start, osc::rpy_rotation<double>({0.0, 1.5707963267948966, 0.0}));  // the PUMA's R_ref at its start
    next_tick = 1 + static_cast<std::uint64_t>(how >> 3) * 50;
    switch ((how >> 1) & 3) {
      case 1: {  // a move running: a re-target brakes it
        osc::CartesianMove<double> m;
        const osc::Pose<double> to{start.p + osc::Vec3<double>(0.2, -0.1, 0.05), start.R};
        FUZZ_CHECK(m.plan(start, to, kMax, gen.reference_orientation()) == osc::ProfileStatus::kOk);
        FUZZ_CHECK(gen.push(m, 1000));
        gen.start_moves(0);
        break;
      }
      case 2:  // the paper's motion: every move brakes it first
        gen.start_paper(osc::Gains<double>::paper().trajectory, 0, 2000);
        break;
      case 3:  // a stream running (id 3000): moves are busy, its setpoints are taken
        gen.start_stream(20, (how & 0x80) != 0, kMax, 3000);
        break;
      default:
        break;
    }
  }

  void check_move(const pil::CommandFrame& f, const osc::MoveRequest<double>& req, const osc::TaskCommand<double>& c) {
    const osc::CartesianMove<double>& m = c.move;
    const double T = m.duration();
    FUZZ_CHECK(std::isfinite(T) && T >= 0);
    const double own = req.has_limits ? req.limits.linear.v : kMax.linear.v;
    for (int k = 0; k <= 12; ++k) {
      const double t = k <= 10 ? T * k / 10 : T + k - 10;  // over the move, then at rest after it
      const osc::Desired<double> d = m.at(t);
      FUZZ_CHECK(osc::math::all_finite(d.x) && osc::math::all_finite(d.xd) && osc::math::all_finite(d.xdd));
      const double v = d.xd.head<3>().norm();
      FUZZ_CHECK(v <= kMax.linear.v * (1 + 1e-9));
      FUZZ_CHECK(v <= own * (1 + 1e-9));
    }
    if (!c.brake) {  // planned from where the queue ends: it ends at the target
      const osc::Pose<double> to = osc::move_target(gen.queue_end(), req);
      FUZZ_CHECK((m.end().p - to.p).norm() <= 1e-9 * (1 + to.p.norm()));
      if (gen.push(m, f.id)) ++accepted;
    }
  }

  void command(const pil::CommandFrame& f) {
    osc::MoveRequest<double> req;
    MotionVerb verb;
    const MotionReason why = osc::command_from_frame(f, req, verb);
    FUZZ_CHECK(why == MotionReason::kNone || why == MotionReason::kBadCommand);
    FUZZ_CHECK((why == MotionReason::kNone) == valid_by_the_document(f));
    FUZZ_CHECK(verb ==
               (f.verb < osc::MotionNames<MotionVerb>::kCount ? static_cast<MotionVerb>(f.verb) : MotionVerb::kNone));
    if (why == MotionReason::kNone) {
      std::uint8_t a[pil::kMaxFrame], b[pil::kMaxFrame];
      const int n = pil::encode(f, a);
      // The request gives the frame back, but for identify's flag payload, which no request carries (a client adds
      // it: osc_client's identify(payload)).
      pil::CommandFrame g = osc::frame_from_command(f.id, verb, req);
      g.flags = static_cast<std::uint8_t>(g.flags | (f.flags & pil::kFlagPayload));
      FUZZ_CHECK(pil::encode(g, b) == n);
      FUZZ_CHECK(std::memcmp(a, b, static_cast<std::size_t>(n)) == 0);
      FUZZ_CHECK((f.flags & pil::kFlagPayload) != 0 || osc::encode_command(f.id, verb, req, b) == n);
    }
    const osc::TaskCommand<double> c = osc::prepare_frame_command(gen, kMax, next_tick, kHz, f);
    FUZZ_CHECK(c.id == f.id);
    FUZZ_CHECK(c.verb == verb);
    FUZZ_CHECK(static_cast<int>(c.refusal) < osc::MotionNames<MotionReason>::kCount);
    FUZZ_CHECK(std::strcmp(osc::motion_name(c.refusal), "?") != 0);
    FUZZ_CHECK((c.refusal == MotionReason::kBadCommand) == (why == MotionReason::kBadCommand));
    // An identify moves only as prepare_identify planned and checked it (the port calls it in this one's
    // place): a frame's own command is never marked checked, so a tick that were given it refuses it.
    FUZZ_CHECK(!c.checked);
    // declare_pose: a pose code beyond the document's Poses table (4 poses) is unknown_pose, and only it.
    const bool unknown_pose = why == MotionReason::kNone && verb == MotionVerb::kDeclarePose && f.period >= 4;
    FUZZ_CHECK((c.refusal == MotionReason::kUnknownPose) == unknown_pose);
    if (why == MotionReason::kNone && verb == MotionVerb::kMoveTo && c.refusal == MotionReason::kNone)
      check_move(f, req, c);
  }

  /// Feeds one byte; checks each completed frame among its events. Returns the first event.
  pil::Parser::Result feed(pil::Parser& p, std::uint8_t byte) {
    const pil::Parser::Result first = p.feed(byte);
    for (pil::Parser::Result r = first; r != pil::Parser::kPending; r = p.next())
      if (r == pil::Parser::kFrame) frame(p);
    return first;
  }

  /// A completed frame: a command or a setpoint checked as the document says.
  void frame(const pil::Parser& p) {
    pil::CommandFrame f;
    pil::SetpointFrame sp;
    pil::SetpointVelocityFrame sv;
    if (p.decode(f))
      command(f);
    else if (p.decode(sp))
      setpoint(sp, nullptr);
    else if (p.decode(sv))
      setpoint(sv, sv.velocity);
    else
      FUZZ_CHECK(p.type() != pil::kCommandFrame && p.type() != pil::kSetpointFrame &&
                 p.type() != pil::kSetpointVelocityFrame);
  }

  /// A setpoint, with its velocity or not: valid as the document says (flags end and has_rpy only,
  /// the bounds of a command's numbers, each velocity finite within 10), and prepared for the running
  /// stream (3000) into finite coordinates near the target and finite rates (0 with end, the angular
  /// ones 0 without has_rpy); then the generator's next tick is finite.
  template <class Frame>
  void setpoint(const Frame& f, const float* velocity) {
    bool valid = (f.flags & 0xFC) == 0;
    for (int i = 0; i < 3; ++i) {
      valid &= std::isfinite(f.position[i]) && std::fabs(f.position[i]) <= 10.0f;
      valid &= std::isfinite(f.rpy[i]) && std::fabs(static_cast<double>(f.rpy[i])) <= 2 * osc::kPi;
    }
    for (int i = 0; velocity && i < 6; ++i) valid &= std::isfinite(velocity[i]) && std::fabs(velocity[i]) <= 10.0f;
    FUZZ_CHECK(osc::detail::setpoint_valid(f) == valid);
    if (!valid) return;
    osc::StreamSample<double> out;
    const osc::Vec3<double> p(f.position[0], f.position[1], f.position[2]), rpy(f.rpy[0], f.rpy[1], f.rpy[2]);
    osc::Vec6<double> v = osc::Vec6<double>::Zero();
    for (int i = 0; velocity && i < 6; ++i) v(i) = velocity[i];
    const bool has_rpy = (f.flags & 2) != 0, end = (f.flags & 1) != 0;
    const bool taken = osc::prepare_setpoint(gen, f.id, p, rpy, has_rpy, end, out, velocity ? &v : nullptr);
    FUZZ_CHECK(taken == (gen.source() == osc::MotionSource::kStream && f.id == 3000));
    if (!taken) return;
    FUZZ_CHECK(osc::math::all_finite(out.x));
    FUZZ_CHECK(osc::math::all_finite(out.v));
    FUZZ_CHECK(out.has_velocity == (velocity != nullptr));
    if (end || !velocity) FUZZ_CHECK(out.v.norm() == 0);
    if (!has_rpy) FUZZ_CHECK(out.v.tail<3>().norm() == 0);
    const osc::Vec3<double> at = gen.stream_relative() ? osc::Vec3<double>(gen.hold_pose().p + p) : p;
    FUZZ_CHECK((out.x.head<3>() - at).norm() <= 1e-9 * (1 + at.norm()));
    gen.stream_setpoint(out.x, out.end, out.has_velocity ? &out.v : nullptr);
    osc::MotionEvents ev;
    const osc::Desired<double> d = gen.at_tick(next_tick, kHz, ev);
    FUZZ_CHECK(osc::math::all_finite(d.x) && osc::math::all_finite(d.xd) && osc::math::all_finite(d.xdd));
  }
};

/// A number of the frame from the input: raw f32 bits, or a small integer times `unit`.
float number(fuzz::Input& in, bool raw, double unit, bool is_signed = true) {
  if (raw) {
    const std::uint32_t u = in.u32();
    float v;
    std::memcpy(&v, &u, 4);
    return v;
  }
  const std::uint16_t u = in.u16();
  return static_cast<float>((is_signed ? static_cast<std::int16_t>(u) : u) * unit);
}

/// A setpoint frame from the input (for the running stream, id 3000, when bit 0 of its first byte is
/// set): positions to +-16 m, angles to +-8 rad, with velocity each to +-16 m/s or rad/s.
template <class Frame>
Frame setpoint_from(fuzz::Input& in, bool raw) {
  Frame f;
  f.id = (in.u8() & 1) ? 3000u : in.u32();
  f.flags = in.u8();
  for (float& p : f.position) p = number(in, raw, 1.0 / 2048);
  for (float& r : f.rpy) r = number(in, raw, 1.0 / 4096);
  if constexpr (std::is_same_v<Frame, pil::SetpointVelocityFrame>)
    for (float& v : f.velocity) v = number(in, raw, 1.0 / 2048);
  return f;
}

pil::CommandFrame frame_from(fuzz::Input& in, bool raw) {
  pil::CommandFrame f;
  f.id = in.u32();
  f.verb = in.u8();
  f.flags = in.u8();
  // Small integers: positions to +-16 m (bound 10), angles to +-8 rad (bound 2 pi), each limit from
  // 0 to 1.3 times its configured maximum.
  for (float& p : f.position) p = number(in, raw, 1.0 / 2048);
  for (float& r : f.rpy) r = number(in, raw, 1.0 / 4096);
  const osc::JerkLimits<double> max[2] = {kMax.linear, kMax.angular};
  for (int k = 0; k < 2; ++k) {
    f.limits[3 * k] = number(in, raw, max[k].v / 50000, false);
    f.limits[3 * k + 1] = number(in, raw, max[k].a / 50000, false);
    f.limits[3 * k + 2] = number(in, raw, max[k].j / 50000, false);
  }
  f.period = in.u8();
  return f;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  const std::uint8_t how = in.u8();
  auto c = std::make_unique<Checker>();
  c->setup(how);
  pil::Parser parser;
  if ((how & 1) == 0) {
    while (!in.empty()) c->feed(parser, in.u8());
    return 0;
  }
  while (!in.empty()) {
    const std::uint8_t op = in.u8();
    for (int k = op & 7; k > 0; --k) c->feed(parser, in.u8());
    std::uint8_t buf[pil::kMaxFrame];
    const bool raw = (op & 8) != 0;
    const int kind = (op >> 5) & 3;  // a command frame, a setpoint, a setpoint with velocity
    const int len = kind == 1   ? pil::encode(setpoint_from<pil::SetpointFrame>(in, raw), buf)
                    : kind == 2 ? pil::encode(setpoint_from<pil::SetpointVelocityFrame>(in, raw), buf)
                                : pil::encode(frame_from(in, raw), buf);
    const bool flip = (op & 0x10) != 0;
    if (flip) buf[4 + in.u8() % (len - 4)] ^= static_cast<std::uint8_t>(1u << (in.u8() & 7));
    const bool idle = !parser.in_frame();
    for (int i = 0; i < len; ++i) {
      const pil::Parser::Result r = c->feed(parser, buf[i]);
      if (idle && i == len - 1) FUZZ_CHECK(r == (flip ? pil::Parser::kBadChecksum : pil::Parser::kFrame));
    }
  }
  return 0;
}
