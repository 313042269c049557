// The motion sources: where each control step's desired state d = (x_d, x_d dot, x_d ddot) comes
// from. control_step() tracks whatever d it is given; a source computes d for the tick. So far one
// source: the built-in "paper" motion, trajectory (68) about the position at which it starts.
#pragma once

#include <cstdint>

#include "osc/control/trajectory.hpp"

namespace osc {

/// The paper's motion (68) about p0, the tip position when it started (the measured pose: the
/// motion starts where the arm is), its time counted from the sample it started at.
template <class S>
struct PaperMotion {
  TrajectorySpec<S> spec;
  Vec3<S> p0;                    ///< the centre of (68): the tip position at the start [m]
  std::uint64_t start_tick = 0;  ///< the sample the motion started at

  /// d at time t [s] since the start.
  Desired<S> at_time(S t) const { return trajectory(spec, p0, t); }
  /// d at sample `tick` of a clock of rate_hz samples per second: its time from the integer sample
  /// count since the start (trajectory_time: exact over any uptime).
  Desired<S> at_tick(std::uint64_t tick, std::uint32_t rate_hz) const {
    return at_time(trajectory_time<S>(spec, tick - start_tick, rate_hz));
  }
};

}  // namespace osc
