// The control task the 1 kHz timer interrupt runs: read encoders -> angles -> control step
// (observer, controller, adaptation) -> torques -> DAC codes -> write. Bound to a HAL at compile
// time; the same code runs against the simulated plant on the host and on the targets.
#pragma once

#include <cstdint>

#include "hal/hal.hpp"
#include "osc/controller.hpp"
#include "osc/io.hpp"

namespace osc {

template <class S>
struct ControlTask {
  Model<S> model;
  Gains<S> gains;
  FrictionMode mode;
  Vec6<S> q_start;           // joint angles at which the encoders read zero
  std::uint32_t tick;        // samples since start
  ControllerState<S> state;
  StepOutput<S> last;        // the most recent step, for telemetry
  std::int32_t codes[kDof];  // the most recent DAC codes
  std::uint32_t saturated;   // bit i: joint i's torque was clipped at the DAC range this tick

  void init(const Model<S>& m, const Gains<S>& g, FrictionMode fm, const Vec6In<S>& q0) {
    model = m;
    gains = g;
    mode = fm;
    q_start = q0;
    tick = 0;
    controller_init(model, state, q0);
    for (int i = 0; i < kDof; ++i) codes[i] = 0;
    saturated = 0;
  }
};

/// Encoder counts to joint angles.
template <class S>
Vec6<S> angles_from_counts(const Vec6<S>& q_start, const std::int32_t counts[kDof]) {
  Vec6<S> q;
  for (int i = 0; i < kDof; ++i) q(i) = counts_to_angle<S>(i, counts[i], q_start(i));
  return q;
}

/// One tick. On any step fault every DAC gets code 0 in this same tick.
template <class S, class Hal>
const StepOutput<S>& control_tick(ControlTask<S>& task, Hal& hal) {
  std::int32_t counts[kDof];
  hal.read_encoders(counts);
  const Vec6<S> q = angles_from_counts(task.q_start, counts);
  const S t = static_cast<S>(task.tick) * task.gains.dt;
  task.last = control_step(task.model, task.gains, task.mode, task.state, q, t);
  task.saturated = 0;
  for (int i = 0; i < kDof; ++i) {
    if (torque_to_code(i, task.last.tau(i), task.codes[i])) task.saturated |= 1u << i;
    if (task.last.status != kStepOk) task.codes[i] = 0;
  }
  hal.write_dacs(task.codes);
  ++task.tick;
  return task.last;
}

}  // namespace osc
