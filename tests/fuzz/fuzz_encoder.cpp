// Fuzz target: the control task's encoder plausibility checks (osc/runtime/control_task.hpp).
// A ControlTask<double> (initialised like the tests: the PUMA 560 model, the paper's gains,
// adaptive friction compensation, the start pose) is ticked with a HAL whose encoders return
// fuzzed int32 counts: arbitrary values, small steps, one wild joint, or values at the edges of
// the plausible range and step. The encoder resolution is fuzzed too (100..1e7 counts per motor
// revolution, the command line's range).
//
// Invariants, every tick:
//  - control_tick writes the DACs exactly once, and every code is within [-kDacMaxCode, kDacMaxCode];
//  - a reading outside [min_counts, max_counts] returns and latches encoder_range; a change from
//    the previous reading (64-bit difference, from the second reading on) beyond max_count_step
//    returns and latches encoder_jump; either way every code of that very tick is 0 and the
//    supervisor is in kFault; neither bit is returned when its condition does not hold;
//  - the plausible range contains the start pose (count 0) and the plausible step is positive;
//  - codes are nonzero only in kRun; the fault line is on exactly in kFault; latched bits only grow;
//    after any fault every later code is 0.
#include <cstdint>
#include <memory>

#include "fuzz_util.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/control_task.hpp"

namespace {

struct FuzzHal {
  std::int32_t next[osc::kDof] = {};
  std::int32_t written[osc::kDof] = {};
  int writes = 0;
  bool fault_line = false;
  std::uint32_t clock = 0;
  bool read_encoders(std::int32_t c[osc::kDof]) {
    for (int i = 0; i < osc::kDof; ++i) c[i] = next[i];
    return true;  // a sample every tick (ticks without one: tests/firmware/runtime/test_control_task.cpp)
  }
  void write_dacs(const std::int32_t c[osc::kDof]) {
    for (int i = 0; i < osc::kDof; ++i) written[i] = c[i];
    ++writes;
  }
  std::uint32_t cycles() { return clock += 10; }
  std::uint32_t io_faults() { return 0; }
  void fault_output(bool active) { fault_line = active; }
};
static_assert(hal::ControlHal<FuzzHal>);

constexpr int kMaxTicks = 128;

std::int64_t abs64(std::int64_t v) { return v < 0 ? -v : v; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  auto task = std::make_unique<osc::ControlTask<double>>();
  task->init(osc::Model<double>::of(osc::robot::kArm), osc::Gains<double>::paper(), osc::FrictionMode::kAdaptive,
             osc::joint_vector<double>(osc::robot::kQStart));
  if (in.u8() & 1) task->set_encoder_resolution(100.0 + static_cast<double>(in.u32() % 9999901u));
  for (int i = 0; i < osc::kDof; ++i) {
    FUZZ_CHECK(task->range.min_counts[i] < 0 && task->range.max_counts[i] > 0);
    FUZZ_CHECK(task->jump.max_step[i] > 0);
  }

  FuzzHal hal;
  std::int32_t prev[osc::kDof] = {};
  bool have_prev = false, faulted = false;
  std::uint32_t latched = 0;
  for (int tick = 0; tick < kMaxTicks && !in.empty(); ++tick) {
    std::int32_t c[osc::kDof];
    const std::uint8_t mode = in.u8();
    for (int i = 0; i < osc::kDof; ++i) c[i] = fuzz::wrap_add(prev[i], static_cast<std::int8_t>(in.u8()) / 8);
    switch (mode & 3) {
      case 0:  // arbitrary counts on every joint
        for (auto& v : c) v = in.i32();
        break;
      case 1:  // small steps only
        break;
      case 2:  // one joint anywhere
        c[(mode >> 2) % osc::kDof] = in.i32();
        break;
      case 3: {  // one joint at an edge of the plausible range or step, give or take one count
        const int j = (mode >> 2) % osc::kDof;
        const std::int64_t off = static_cast<std::int64_t>(in.u8() % 3) - 1;
        std::int64_t v = 0;
        switch ((mode >> 5) & 3) {
          case 0:
            v = task->range.min_counts[j] + off;
            break;
          case 1:
            v = task->range.max_counts[j] + off;
            break;
          case 2:
            v = static_cast<std::int64_t>(prev[j]) + task->jump.max_step[j] + off;
            break;
          case 3:
            v = static_cast<std::int64_t>(prev[j]) - task->jump.max_step[j] + off;
            break;
        }
        c[j] = static_cast<std::int32_t>(v < INT32_MIN ? INT32_MIN : v > INT32_MAX ? INT32_MAX : v);
        break;
      }
    }
    bool range = false, jump = false;
    for (int i = 0; i < osc::kDof; ++i) {
      if (c[i] < task->range.min_counts[i] || c[i] > task->range.max_counts[i]) range = true;
      if (have_prev && abs64(static_cast<std::int64_t>(c[i]) - prev[i]) > task->jump.max_step[i]) jump = true;
      prev[i] = c[i];
      hal.next[i] = c[i];
    }
    have_prev = true;

    const int writes = hal.writes;
    const std::uint32_t f = osc::control_tick(*task, hal);
    FUZZ_CHECK(hal.writes == writes + 1);
    for (std::int32_t code : hal.written) FUZZ_CHECK(code >= -osc::kDacMaxCode && code <= osc::kDacMaxCode);
    FUZZ_CHECK(((f & osc::kFaultEncoderRange) != 0) == range);
    FUZZ_CHECK(((f & osc::kFaultEncoderJump) != 0) == jump);
    if (range) FUZZ_CHECK(task->sup.latched & osc::kFaultEncoderRange);
    if (jump) FUZZ_CHECK(task->sup.latched & osc::kFaultEncoderJump);
    FUZZ_CHECK((task->sup.latched & latched) == latched);
    latched = task->sup.latched;
    faulted = faulted || f != 0;
    if (faulted) FUZZ_CHECK(task->sup.state == osc::SupervisorState::kFault);
    if (faulted || task->sup.state != osc::SupervisorState::kRun)
      for (std::int32_t code : hal.written) FUZZ_CHECK(code == 0);
    FUZZ_CHECK(hal.fault_line == (task->sup.state == osc::SupervisorState::kFault));
  }
  return 0;
}
