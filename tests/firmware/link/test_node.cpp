// The PIL node's side of the command protocol (osc/link/node.hpp; NodeFrames, node_frames.hpp): a command
// frame is neither a tick nor a link error and is answered after the tick's actuator frame; the first
// sensor frame's configuration bits (start disabled, state frames, a trace frame ending every tick). The
// node as the task's hal::CurrentHal: the sensor frame's currents when its drive byte says they are a
// reading, its fault lines, each what the drive check sees. The node's link supervision: test_link.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "node_frames.hpp"
#include "osc/link/node.hpp"

using namespace osc;
using namespace osc::test;

namespace {

// ---------------------------------------------------------------- the command port in the node

TEST_F(NodeFrames, ACommandIsNeitherATickNorALinkErrorAndIsAnsweredAfterTheActuatorFrame) {
  tick(pil::kConfigStartDisabled);
  EXPECT_EQ(arrive(command(1, MotionVerb::kEnable)), 0);  // no tick
  EXPECT_EQ(node->task.pending.verb, MotionVerb::kEnable);
  tick();
  EXPECT_EQ(node->link_counters().total(), 0u);
  ASSERT_EQ(RecordingBoard::answers.size(), 1u);
  EXPECT_EQ(RecordingBoard::answers[0].id, 1u);
  EXPECT_EQ(RecordingBoard::answers[0].outcome, static_cast<std::uint8_t>(CommandOutcome::kAccepted));
  EXPECT_EQ(RecordingBoard::answers[0].state, static_cast<std::uint8_t>(MotionState::kHolding));
  EXPECT_EQ(RecordingBoard::answers[0].tick, 1u);
  // Tick 0's actuator frame, then tick 1's, then its answer.
  const std::vector<pil::FrameType> want = {pil::kActuatorFrame, pil::kActuatorFrame, pil::kAnswerFrame};
  EXPECT_EQ(RecordingBoard::types, want);
  EXPECT_EQ(RecordingBoard::actuators.back().link.total(), 0u);
  // A setpoint frame: not a tick either (no stream runs: dropped and counted).
  EXPECT_EQ(arrive(setpoint_frame<double>(9, Vec3<double>::Zero(), nullptr, false)), 0);
  EXPECT_EQ(node->task.dropped, 1u);
  // A valid frame of a type the host does not send is still a frame of the wrong type: a tick at once.
  EXPECT_EQ(arrive(pil::AnswerFrame{}), 1);
  EXPECT_EQ(RecordingBoard::actuators.back().link[pil::kErrHeader], 1u);
}

TEST_F(NodeFrames, TheTaskStartsDisabledWhenTheFirstFrameAsksAndACommandBeforeItWaitsForIt) {
  // Without the bit: the paper's motion from the first sample.
  tick();
  EXPECT_EQ(node->task.machine.state, MotionState::kMoving);
  EXPECT_EQ(node->task.gen.source(), MotionSource::kPaper);
  // With it: disabled, zero codes; an enable sent before the first sensor frame is prepared once
  // that frame has configured the task, and answered by its tick.
  SetUp();
  seq = 0;
  arrive(command(5, MotionVerb::kEnable));
  EXPECT_EQ(node->task.pending.verb, MotionVerb::kNone);  // waiting: not configured yet
  EXPECT_EQ(node->port.waiting(), 1);
  tick(pil::kConfigStartDisabled);
  ASSERT_EQ(RecordingBoard::answers.size(), 1u);
  EXPECT_EQ(RecordingBoard::answers[0].id, 5u);
  EXPECT_EQ(RecordingBoard::answers[0].tick, 0u);
  EXPECT_EQ(RecordingBoard::answers[0].state, static_cast<std::uint8_t>(MotionState::kHolding));
  EXPECT_EQ(node->task.gen.source(), MotionSource::kHold);
  for (std::int32_t c : RecordingBoard::actuators[0].codes) EXPECT_EQ(c, 0);  // the enable's ramp starts after it
}

TEST_F(NodeFrames, StateFramesOnlyWhenTheFirstFrameAsks) {
  for (int k = 0; k < 100; ++k) tick();
  EXPECT_TRUE(RecordingBoard::states.empty());
  EXPECT_EQ(RecordingBoard::types.size(), 100u);  // actuator frames only, as before the command protocol
  SetUp();
  seq = 0;
  tick(pil::kConfigStateFrames);
  for (int k = 1; k < 100; ++k) tick();
  ASSERT_EQ(RecordingBoard::states.size(), 100u / kStatePeriod);
  for (std::size_t i = 0; i < RecordingBoard::states.size(); ++i)
    EXPECT_EQ(RecordingBoard::states[i].tick, (i + 1) * kStatePeriod - 1);
  EXPECT_EQ(RecordingBoard::types[kStatePeriod], pil::kStateFrame);  // after its tick's actuator frame
  EXPECT_EQ(RecordingBoard::types[kStatePeriod - 1], pil::kActuatorFrame);
}

TEST_F(NodeFrames, ATraceFrameEndsEveryTickWhenTheFirstFrameAsks) {
  tick(pil::kConfigTrace);
  for (int k = 1; k < 30; ++k) tick();
  ASSERT_EQ(RecordingBoard::traces.size(), 30u);
  ASSERT_EQ(RecordingBoard::types.size(), 60u);
  for (std::size_t k = 0; k < 30; ++k) {
    EXPECT_EQ(RecordingBoard::types[2 * k], pil::kActuatorFrame);
    EXPECT_EQ(RecordingBoard::types[2 * k + 1], pil::kTraceFrame);
    EXPECT_EQ(RecordingBoard::traces[k].seq, RecordingBoard::actuators[k].seq);
    EXPECT_EQ(RecordingBoard::traces[k].faults, 0u);
  }
  // The last step's desired state and the reference orientation, as the task has them.
  const pil::TraceFrame& t = RecordingBoard::traces.back();
  const ControlTask<double>& task = node->task;
  EXPECT_EQ(t.state, static_cast<std::uint8_t>(MotionState::kMoving));
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(t.x_d[i], static_cast<float>(task.desired.x(i))) << i;
    EXPECT_EQ(t.xd_d[i], static_cast<float>(task.desired.xd(i))) << i;
    EXPECT_EQ(t.xdd_d[i], static_cast<float>(task.desired.xdd(i))) << i;
  }
  for (int i = 0; i < 9; ++i) EXPECT_EQ(t.R_ref[i], static_cast<float>(task.state.R_ref(i / 3, i % 3))) << i;
  EXPECT_GT(std::abs(t.xd_d[1]) + std::abs(t.xd_d[2]), 0.0f);  // the paper's motion is on its way
  // The faults the tick detected (the actuator frame carries the latched ones).
  tick(pil::kInjectNonFinite);
  EXPECT_EQ(RecordingBoard::traces.back().faults, static_cast<std::uint32_t>(kFaultNonFinite));
  EXPECT_EQ(RecordingBoard::traces.back().state, static_cast<std::uint8_t>(MotionState::kFault));
  tick();
  EXPECT_EQ(RecordingBoard::traces.back().faults, 0u);
  EXPECT_EQ(RecordingBoard::actuators.back().faults, static_cast<std::uint32_t>(kFaultNonFinite));
}

// ---------------------------------------------------------------- the amplifiers (hal::CurrentHal)

static_assert(pil::drive_byte(0x3F, true) == 0xBF && pil::drive_byte(1u << 6, false) == 0,
              "six fault lines in bits 0-5, the valid bit 7");

TEST_F(NodeFrames, TheSensorFramesCurrentsAreTheNodesReadingsWhenItsDriveByteSaysSo) {
  std::int16_t got[kDof] = {1, 1, 1, 1, 1, 1};
  EXPECT_FALSE(node->read_currents(got));  // no frame yet
  EXPECT_EQ(node->amp_faults(), 0u);
  tick(pil::kConfigStartDisabled | pil::kConfigTrace);
  tick();
  EXPECT_FALSE(node->read_currents(got));  // frames without readings (drive 0)
  // Currents that are not a reading (the valid bit clear): none, whatever they hold; the drive check
  // sees none (a reading at the end of the ADC's span would be current_sense).
  const std::int16_t reading[kDof] = {3, -5, static_cast<std::int16_t>(kDriveCheck.adc_max), 0, 7, -1};
  pil::SensorFrame s = sensor();
  for (int i = 0; i < kDof; ++i) s.currents[i] = reading[i];
  ASSERT_EQ(arrive(s), 1);
  EXPECT_FALSE(node->read_currents(got));
  EXPECT_EQ(RecordingBoard::traces.back().faults, 0u);
  // The same currents with the valid bit: the node's reading, which the drive check takes.
  s = sensor();
  for (int i = 0; i < kDof; ++i) s.currents[i] = reading[i];
  s.drive = pil::drive_byte(0, true);
  ASSERT_EQ(arrive(s), 1);
  ASSERT_TRUE(node->read_currents(got));
  for (int i = 0; i < kDof; ++i) EXPECT_EQ(got[i], reading[i]) << i;
  EXPECT_EQ(node->amp_faults(), 0u);
  if (node->task.drive_check) {  // the arm states current monitors (robot::kDriveTrain.current)
    EXPECT_EQ(RecordingBoard::traces.back().faults, static_cast<std::uint32_t>(kFaultCurrentSense));
    EXPECT_EQ(node->task.drive.channel, 2);
  }
  // A tick without a sample (the next frame's CRC broken): no reading, though the last valid frame had one.
  Bytes bad = bytes_of(sensor());
  bad[10] ^= 0x40;
  int ticks = 0;
  for (std::uint8_t b : bad) node->on_byte(b, [&] { ++ticks, node->tick(); });
  ASSERT_EQ(ticks, 1);
  EXPECT_EQ(RecordingBoard::actuators.back().link[pil::kErrCrc], 1u);
  EXPECT_FALSE(node->read_currents(got));
}

TEST_F(NodeFrames, TheDriveBytesFaultLinesAreTheAmplifiersFaults) {
  tick(pil::kConfigStartDisabled | pil::kConfigTrace);
  tick();
  pil::SensorFrame s = sensor();
  s.drive = pil::drive_byte((1u << 4) | (1u << 9), false);  // amplifier 5's line; bit 9 is no amplifier's
  EXPECT_EQ(s.drive, 0x10);
  ASSERT_EQ(arrive(s), 1);
  EXPECT_EQ(node->amp_faults(), 0x10u);
  std::int16_t got[kDof];
  EXPECT_FALSE(node->read_currents(got));  // the fault lines without readings
  if (node->task.drive_check) {
    EXPECT_EQ(RecordingBoard::traces.back().faults, static_cast<std::uint32_t>(kFaultDriveFault));
    EXPECT_EQ(node->task.drive.channel, 4);
  }
  // The lines are the latest valid frame's: the next frame's, none.
  tick();
  EXPECT_EQ(node->amp_faults(), 0u);
  EXPECT_EQ(RecordingBoard::traces.back().faults, 0u);
}

}  // namespace
