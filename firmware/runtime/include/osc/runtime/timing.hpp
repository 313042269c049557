// The tick's timing, in the HAL's cycle-counter units (instructions under QEMU's -icount shift=0,
// core cycles on a board): a running record per quantity, and the stages of control_tick()
// (osc/runtime/control_task.hpp), each timed on every tick.
#pragma once

#include <cstdint>

#include "osc/control/faults.hpp"  // OSC_X_NAME, OSC_X_DOC, OSC_X_ENUMERATOR

namespace osc {

/// The last, largest and mean of a duration measured once a tick.
struct StepTiming {
  std::uint32_t last = 0, max = 0;
  std::uint64_t sum = 0;
  std::uint32_t count = 0;
  std::uint32_t mean() const { return count ? static_cast<std::uint32_t>(sum / count) : 0; }
  void add(std::uint32_t c) {
    last = c;
    if (c > max) max = c;
    sum += c;
    ++count;
  }
};

/// The stages of a tick, in the order the data flows: the block diagram of control_tick(), one call
/// (stage_<name>, osc/runtime/control_task.hpp) each. The torques become DAC codes before the
/// decision: the supervisor and the motion state machine judge every fault of the tick, the codes'
/// saturation, overflow and overrun among them; the output writes the codes the decision allows.
// X(Name, "name", what the stage does)
#define OSC_TICK_STAGE_LIST(X)                                                                               \
  X(Read, "read", "the HAL's I/O faults (E-stop, drives) and the encoder read")                              \
  X(Checks, "checks",                                                                                        \
    "the encoder monitors: range, jump (EncoderRangeMonitor, EncoderJumpMonitor); the counts of a sample "   \
    "that passed them to joint angles")                                                                      \
  X(Reference, "reference",                                                                                  \
    "the stream setpoint handed to the motion source, then the desired state: the motion source's "          \
    "(MotionGenerator::at_tick), a yielding arm's own pose")                                                 \
  X(Step, "step", "the control step: observer, controller, adaptation (control_step)")                       \
  X(Monitors, "monitors",                                                                                    \
    "every monitor of the step and the sample: stuck encoder, residual (collision, drive fault), the "       \
    "momentum law's friction identification, tracking, friction-estimate band, position cross-check; "       \
    "a collision's reaction")                                                                                \
  X(Codes, "codes",                                                                                          \
    "the enable's torque ramp, torques to DAC codes, saturation, fixed-point overflow, overrun (the cycles " \
    "since the tick's first mark)")                                                                          \
  X(Decide, "decide",                                                                                        \
    "homing's index faults, the supervisor, the tick's category-2 stop request, the motion state machine")   \
  X(Output, "output",                                                                                        \
    "the codes the supervisor and the motion state allow (0 otherwise), the residual monitor's applied "     \
    "torque, the DAC write, the fault line")

#define OSC_X_PREFIX kStage
enum TickStage : std::uint8_t { OSC_TICK_STAGE_LIST(OSC_X_ENUMERATOR) kTickStages };
#undef OSC_X_PREFIX
/// The stages' names (telemetry, reports) and meanings, in TickStage order.
constexpr const char* kTickStageNames[kTickStages] = {OSC_TICK_STAGE_LIST(OSC_X_NAME)};
constexpr const char* kTickStageDocs[kTickStages] = {OSC_TICK_STAGE_LIST(OSC_X_DOC)};

/// Each stage's timing: stage s of a tick lasted from mark s to mark s + 1.
struct TickTiming {
  StepTiming stage[kTickStages];
  /// The stages of one tick from its kTickStages + 1 cycle-counter marks.
  void add(const std::uint32_t (&marks)[kTickStages + 1]) {
    for (int s = 0; s < kTickStages; ++s) stage[s].add(marks[s + 1] - marks[s]);
  }
};

}  // namespace osc
