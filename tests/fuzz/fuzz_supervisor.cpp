// Fuzz target: the supervisor (osc/runtime/supervisor.hpp), supervisor_next() over fuzzed
// sequences of (fault bits, ready) inputs from the initial state {kInit, 0}. Two bytes a step: a
// flags byte (bit 7: ready; bits 0-1: no fault, one fault bit chosen by the second byte, or any
// 32-bit word read from the input) and the second byte.
//
// Invariants, every step:
//  - once kFault, never another state; latched bits only grow, and they are exactly the fault bits
//    seen so far;
//  - any nonzero fault input gives kFault in the same step; kFault always names at least one
//    latched bit;
//  - torque_enabled() only in kRun; kInit goes to kRun only when ready; kRun never goes back to
//    kInit.
#include <cstdint>

#include "fuzz_util.hpp"
#include "osc/runtime/supervisor.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using osc::SupervisorState;
  fuzz::Input in(data, size);
  osc::Supervisor s{SupervisorState::kInit, 0};
  std::uint32_t seen = 0;
  while (!in.empty()) {
    const std::uint8_t flags = in.u8();
    const std::uint8_t arg = in.u8();
    std::uint32_t faults = 0;
    switch (flags & 3) {
      case 0:
        break;
      case 1:
        faults = 1u << (arg & 31);
        break;
      case 2:
        faults = static_cast<std::uint32_t>(arg) << ((flags >> 2) & 31);
        break;
      case 3:
        faults = in.u32();
        break;
    }
    const osc::SupervisorInput input{faults, (flags & 0x80) != 0};
    const osc::Supervisor n = osc::supervisor_next(s, input);
    seen |= faults;

    FUZZ_CHECK(n.state == SupervisorState::kInit || n.state == SupervisorState::kRun ||
               n.state == SupervisorState::kFault);
    if (s.state == SupervisorState::kFault) FUZZ_CHECK(n.state == SupervisorState::kFault);
    FUZZ_CHECK((n.latched & s.latched) == s.latched);
    FUZZ_CHECK(n.latched == seen);
    if (faults != 0) FUZZ_CHECK(n.state == SupervisorState::kFault);
    FUZZ_CHECK((n.state == SupervisorState::kFault) == (n.latched != 0));
    FUZZ_CHECK(osc::torque_enabled(n) == (n.state == SupervisorState::kRun));
    if (s.state == SupervisorState::kInit && n.state == SupervisorState::kRun) FUZZ_CHECK(input.ready);
    if (s.state == SupervisorState::kRun) FUZZ_CHECK(n.state != SupervisorState::kInit);
    s = n;
  }
  return 0;
}
