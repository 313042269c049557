// A tick's telemetry as an actuator frame (osc/link/frames.hpp): the frame the PIL link answers each
// sensor frame with (osc/link/node.hpp), and what a board streams over its telemetry UART
// (boards/stm32f4), so one host-side parser (pil::Parser) reads both.
#pragma once

#include <cstdint>

#include "osc/link/frames.hpp"
#include "osc/runtime/control_task.hpp"

namespace osc {

/// The codes written this tick, the supervisor's state and latched faults, the step timing, the
/// stack high-water mark and the friction estimates. The link counters and receive gaps are the
/// link node's (left zero here).
template <class S>
pil::ActuatorFrame telemetry_frame(const ControlTask<S>& task, const std::int32_t codes[kDof], std::uint32_t seq,
                                   std::uint32_t stack_used) {
  pil::ActuatorFrame a;
  a.seq = seq;
  for (int i = 0; i < kDof; ++i) a.codes[i] = codes[i];
  a.faults = task.sup.latched;
  a.state = static_cast<std::uint8_t>(task.sup.state);
  a.step_cycles = task.step_timing.last;
  a.max_cycles = task.step_timing.max;
  a.mean_cycles = task.step_timing.mean();
  a.tick_max_cycles = task.timing.max;
  for (int s = 0; s < kTickStages; ++s) a.stage_cycles[s] = task.stages.stage[s].last;
  a.stack_used = stack_used;
  for (int i = 0; i < 3 * kDof; ++i) a.theta_hat[i] = static_cast<float>(task.state.adapt.theta_hat(i));
  for (int i = 0; i < kDof; ++i) a.tau_f_hat[i] = static_cast<float>(task.last.tau_f_hat(i));
  return a;
}

}  // namespace osc
