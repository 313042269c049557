// The residual monitor's healthy sweep (issue 25; docs/safety.md, "The residual monitor"): armed,
// on random streams of noisy setpoints and random point-to-point moves at up to the configured
// limits, the worst residual of either channel stays within its derived bound (at most
// 1 / params::kResidualMargin of its threshold) and nothing faults. The moves and streams come from
// a seed the test prints; OSC_SWEEP_SEED=N replays one, OSC_SWEEP_MOVES=N sets how many moves
// (default: 12 here, 200 in the long sweep), a third as many streams follow them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <random>
#include <string>

#include "motion_sim.hpp"

using namespace osc;
using sim::MotionSim;
using V6 = sim::Vec6;

namespace {

unsigned env_or(const char* name, unsigned fallback) {
  const char* v = std::getenv(name);
  return v ? static_cast<unsigned>(std::strtoul(v, nullptr, 10)) : fallback;
}

struct SweepResult {
  double worst[kDof] = {};
  double travel[kDof] = {};  // the travel check's largest least travel / its limit
  std::string detail;        // who raised a fault
  std::uint32_t faults = 0;
  int moves = 0, refused = 0, streams = 0, streams_cut = 0;
};

/// Runs `sim` until its report names `id` done, a fault, or `max_ticks`.
template <class S>
std::uint32_t run_to_done(MotionSim<S>& sim, std::uint32_t id, int max_ticks) {
  std::uint32_t f = 0;
  for (int k = 0; k < max_ticks && f == 0; ++k) {
    f = sim.tick();
    if (sim.task().report.done_id == id) break;
  }
  return f;
}

/// A random move from where the arm is: up to 15 cm along each axis, up to 0.3 rad about z, at a
/// random share (30-100 %) of the configured linear limits.
template <class S>
MoveRequest<S> random_move(std::mt19937& rng) {
  std::uniform_real_distribution<double> d(-0.15, 0.15), a(-0.3, 0.3), share(0.3, 1.0);
  MoveRequest<S> r;
  r.relative = true;
  r.position = Vec3<S>(static_cast<S>(d(rng)), static_cast<S>(d(rng)), static_cast<S>(d(rng)));
  r.has_rpy = true;
  r.rpy = Vec3<S>(S(0), S(0), static_cast<S>(a(rng)));
  r.has_limits = true;
  r.limits = CartesianLimits<S>::defaults();
  const double k = share(rng);
  r.limits.linear.v = static_cast<S>(params::kMoveLinear[0] * k);
  r.limits.linear.a = static_cast<S>(params::kMoveLinear[1] * k);
  return r;
}

/// A random stream from where the arm is: a cosine-timed path of 1.5-3 s to up to 8 cm along each
/// axis and 0.2 rad about z, sampled at 10, 50, 100 or 1000 Hz, each setpoint with Gaussian noise
/// (0.2 mm a coordinate, 2 mrad of yaw: a hand-held device's); the last ends the stream. Runs until
/// the arm holds after it. Returns whether the stream ran to its end (else it was cut: refused or
/// stopped by the generator, counted and not a failure).
template <class S>
bool random_stream(MotionSim<S>& sim, std::uint32_t id, std::mt19937& rng, std::uint32_t& faults,
                   MoveRequest<S>& back) {
  std::uniform_real_distribution<double> d(-0.08, 0.08), a(-0.2, 0.2), dur(1.5, 3.0);
  std::normal_distribution<double> noise_p(0, 2e-4), noise_a(0, 2e-3);
  const int periods[] = {100, 20, 10, 1};
  const int period = periods[std::uniform_int_distribution<int>(0, 3)(rng)];
  const Vec3<double> target(d(rng), d(rng), d(rng));
  const double yaw = a(rng), T = dur(rng);
  back.relative = true;  // the move that undoes the stream's offset
  back.position = (-target).cast<S>();
  back.has_rpy = true;
  back.rpy = Vec3<S>(S(0), S(0), static_cast<S>(-yaw));
  MoveRequest<S> req;
  req.relative = true;
  req.period = static_cast<std::uint32_t>(period);
  sim.stream(req, id);
  faults |= sim.tick();
  if (sim.task().report.outcome != CommandOutcome::kAccepted) return false;
  bool done = false, aborted = false;
  for (int k = 0; k < 20000 && faults == 0; ++k) {
    const double t = k * 1e-3;
    if (k % period == 0 && t <= T + 1e-9) {
      const bool end = t + period * 1e-3 > T;
      const double s = end ? 1.0 : 0.5 - 0.5 * std::cos(kPi * t / T);
      const Vec3<double> p = s * target + Vec3<double>(noise_p(rng), noise_p(rng), noise_p(rng));
      const Vec3<double> rpy(0, 0, s * yaw + (end ? 0 : noise_a(rng)));
      sim.setpoint(id, p, &rpy, end);
    }
    faults |= sim.tick();
    const MotionReport& rep = sim.task().report;
    done |= rep.done_id == id;
    aborted |= rep.abort != MotionReason::kNone;
    if ((done || aborted) && sim.task().machine.state == MotionState::kHolding) break;
  }
  for (int k = 0; k < 200 && faults == 0; ++k) faults |= sim.tick();  // hold a little
  return done && !aborted;
}

template <class S>
SweepResult sweep(unsigned seed, int moves, int streams, const sim::PlantConfig& plant, FrictionMode mode) {
  std::mt19937 rng(seed);
  SweepResult out;
  V6 q0;
  for (int i = 0; i < kDof; ++i) q0(i) = robot::kQStart[i];
  MotionSim<S> sim(q0, {}, plant, mode);
  sim.task().residual.armed = true;
  sim.command(MotionVerb::kEnable, 1);
  for (int k = 0; k < 500; ++k) out.faults |= sim.tick();
  // The streams first, each followed by a move that undoes its offset (the offsets would otherwise
  // add up to a joint limit, where the generator stops a stream: limit_reached).
  for (std::uint32_t id = 10000; out.streams + out.streams_cut < streams && out.faults == 0; id += 2) {
    MoveRequest<S> back;
    ++(random_stream(sim, id, rng, out.faults, back) ? out.streams : out.streams_cut);
    sim.move_to(back, id + 1);
    out.faults |= run_to_done(sim, id + 1, 20000);
  }
  for (std::uint32_t id = 2; out.moves + out.refused < moves && out.faults == 0; ++id) {
    sim.move_to(random_move<S>(rng), id);
    out.faults |= sim.tick();
    if (sim.task().report.outcome != CommandOutcome::kAccepted) {
      ++out.refused;  // out of the workspace or near a singular pose: the path check's refusal
      continue;
    }
    ++out.moves;
    out.faults |= run_to_done(sim, id, 20000);
    for (int k = 0; k < 200 && out.faults == 0; ++k) out.faults |= sim.tick();  // hold a little
  }
  const auto& m = sim.task().residual;
  for (int i = 0; i < kDof; ++i) {
    out.worst[i] = static_cast<double>(m.peak_ratio(i));
    const double limit = static_cast<double>(m.travel_limit(i));
    out.travel[i] = limit > 0 ? static_cast<double>(m.travel_peak(i)) / limit : 0;
  }
  char buf[200];
  std::snprintf(buf, sizeof buf, "residual: %s J%d", m.detected ? fault_name(m.detected) : "none", m.joint + 1);
  out.detail = buf;
  return out;
}

/// check_sweep: no fault, and every joint's worst ratio at most 1 / kResidualMargin (the derived bound
/// holds). Before the wrist's velocity noise took the observer's mixing (docs/safety.md, "The wrist's
/// velocity noise"), J4 and J6 reached 0.91 and 0.82 near a wrist singularity (q5 = 0.08 rad, the
/// 200-move sweep) and J4 0.51 here, J5 0.59 and J6 0.93 uncompensated with Corke's friction; measured
/// since (seed 25, 12 / 60 / 200 moves): at most 0.37 compensated in every scalar, 0.42 (J2) uncompensated.
template <class S>
void check_sweep(const char* label, const osc::FrictionCoefficients& friction, FrictionMode mode, int moves,
                 bool streams = true, double link_scale = 1.0) {
  const unsigned seed = env_or("OSC_SWEEP_SEED", 25);
  sim::PlantConfig plant;
  plant.friction = friction;
  plant.link_scale = link_scale;
  const SweepResult r = sweep<S>(seed, moves, streams ? moves / 3 : 0, plant, mode);
  std::printf(
      "residual sweep %s, %s, links x%.2f, seed %u (OSC_SWEEP_SEED=%u replays it): %d moves (%d refused), %d noisy "
      "streams (%d cut), worst ratio",
      robot::kArm.name, label, link_scale, seed, seed, r.moves, r.refused, r.streams, r.streams_cut);
  for (double w : r.worst) std::printf(" %.3f", w);
  std::printf(", travel check's worst share");
  for (double w : r.travel) std::printf(" %.3f", w);
  std::printf("\n");
  EXPECT_EQ(r.faults, 0u) << fault_name(r.faults) << " (seed " << seed << "): " << r.detail;
  EXPECT_GE(r.moves, moves / 2) << "most random moves are accepted";
  EXPECT_GE(r.streams, r.streams_cut) << "most random streams run to their end";
  for (int i = 0; i < kDof; ++i)
    EXPECT_LE(r.worst[i], 1 / params::kResidualMargin) << "J" << i + 1 << " (seed " << seed << ")";
  // The travel check: a healthy joint's least travel without a count stays within the one count the
  // geometry allows, half its limit.
  for (int i = 0; i < kDof; ++i)
    EXPECT_LE(r.travel[i], 1 / params::kResidualTravelCounts) << "J" << i + 1 << " (seed " << seed << ")";
}

const int kMoves = static_cast<int>(env_or("OSC_SWEEP_MOVES", 12));

// The arm's friction presets (the sheet's): the first (the PUMA's paper values, the UR5e's estimate), and the
// last of its band (the PUMA's Corke values, the UR5e's estimate again); and the band's top, every coefficient at
// its highest (the presets' largest with the sheet's drift: the PUMA's +30 %, the UR5e's estimate +50 %).
const osc::FrictionCoefficients& first_preset() { return *robot::kFrictionPresets[0]; }
const osc::FrictionCoefficients& band_preset() {
  return *robot::kFrictionBandPresets[std::size(robot::kFrictionBandPresets) - 1];
}

TEST(ResidualSweep, RandomMovesPaperFrictionCompensated) {
  check_sweep<double>("double, first preset, compensated", first_preset(), FrictionMode::kAdaptive, kMoves);
}
TEST(ResidualSweep, RandomMovesFrictionBandsTopCompensated) {
  check_sweep<double>("double, the friction band's top, compensated", robot::kModelErrorBounds.friction_hi,
                      FrictionMode::kAdaptive, kMoves);
}
// No streams: without compensation, Corke's friction (26 N m of static friction on J1) holds the arm
// 15 mm behind a fast stream, and the tracking bound faults (seed 25, measured): the controller's
// limit, not the monitor's. Nor, on either arm, more than some tens of moves (OSC_SWEEP_MOVES): the PUMA's 53rd
// move, the UR5e's 35th end the same way (the UR5e's J2 held by its static friction while the error grows to
// 15 mm; docs/safety.md, "The sweep").
TEST(ResidualSweep, RandomMovesCorkeFrictionUncompensated) {
  check_sweep<double>("double, band's last preset, none", band_preset(), FrictionMode::kNone, kMoves, false);
}
TEST(ResidualSweep, RandomMovesInFloat) {
  check_sweep<float>("float, first preset, compensated", first_preset(), FrictionMode::kAdaptive, kMoves);
}
TEST(ResidualSweep, RandomMovesInFixedPoint) {
  check_sweep<Fixed>("fixed, first preset, compensated", first_preset(), FrictionMode::kAdaptive, kMoves);
}
// The model's error: every link's mass and inertia 10 % off the model's (within the sheet's link_inertia bound,
// which the thresholds are derived from: the PUMA's +-10 %, the UR5e's +-20 %).
TEST(ResidualSweep, RandomMovesWithLinksTenPercentHeavier) {
  check_sweep<double>("double, first preset, compensated", first_preset(), FrictionMode::kAdaptive, kMoves, true, 1.1);
}
TEST(ResidualSweep, RandomMovesWithLinksTenPercentLighter) {
  check_sweep<double>("double, first preset, compensated", first_preset(), FrictionMode::kAdaptive, kMoves, true, 0.9);
}

}  // namespace
