// The supervisor (osc/runtime/supervisor.hpp), exhaustively against an independent oracle. The control
// task's fault handling with a scripted HAL: test_control_task.cpp.
#include <gtest/gtest.h>

#include <random>
#include <utility>
#include <vector>

#include "osc/runtime/supervisor.hpp"

using namespace osc;

namespace {

// Independent oracle: the specification of supervisor_next written as plain rules.
Supervisor oracle(Supervisor s, SupervisorInput in) {
  Supervisor n = s;
  n.latched = s.latched | in.faults;  // every bit, named in the catalogue or not
  if (s.state == SupervisorState::kFault)
    n.state = SupervisorState::kFault;
  else if (n.latched)
    n.state = SupervisorState::kFault;
  else if (s.state == SupervisorState::kInit)
    n.state = in.ready ? SupervisorState::kRun : SupervisorState::kInit;
  else
    n.state = SupervisorState::kRun;
  return n;
}

/// Fault words to pair exhaustively with every other: none, each bit alone (an undefined one
/// included), all of them, all and the undefined bit.
std::vector<std::uint32_t> corner_words() {
  std::vector<std::uint32_t> w = {0u, kAllFaults, 2 * kAllFaults + 1};
  for (int b = 0; b <= kFaultCount; ++b) w.push_back(1u << b);
  return w;
}

// Every state and readiness against the oracle, for every fault word (an undefined bit included)
// with every corner latched word, every latched word with every corner fault word, and a million
// seeded random pairs besides. (Every pair of words, 2^33 cases since the fault list grew to 16
// bits, took minutes; the supervisor treats the bits alike, and the corners cover each alone.)
TEST(Supervisor, ExhaustiveAgainstTheSpecification) {
  int cases = 0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;  // (latched, fault word)
  for (std::uint32_t c : corner_words()) {
    for (std::uint32_t f = 0; f <= 2 * kAllFaults + 1; ++f) pairs.emplace_back(c & kAllFaults, f);
    for (std::uint32_t l = 0; l <= kAllFaults; ++l) pairs.emplace_back(l, c);
  }
  std::mt19937 rng(25);
  std::uniform_int_distribution<std::uint32_t> word(0, 2 * kAllFaults + 1);
  for (int k = 0; k < 1000000; ++k) pairs.emplace_back(word(rng) & kAllFaults, word(rng));
  for (int st = 0; st < 3; ++st)
    for (const auto& [latched, f] : pairs)
      for (int ready = 0; ready < 2; ++ready) {
        const Supervisor s{static_cast<SupervisorState>(st), st == 2 ? latched : 0u};
        if (st != 2 && latched != 0) continue;  // only kFault carries latched bits
        const SupervisorInput in{f, ready != 0};
        const Supervisor got = supervisor_next(s, in), want = oracle(s, in);
        ASSERT_EQ(got.state, want.state) << st << " " << f << " " << ready;
        ASSERT_EQ(got.latched, want.latched);
        // Properties: faults are sticky and always disable torque.
        if (f != 0) {
          ASSERT_FALSE(torque_enabled(got));
          ASSERT_FALSE(supervisor_healthy(got));  // a faulting tick never feeds the watchdog
        }
        if (st == 2) {
          ASSERT_EQ(got.state, SupervisorState::kFault);
          ASSERT_FALSE(supervisor_healthy(got));
        }
        ASSERT_EQ(supervisor_healthy(got), want.state != SupervisorState::kFault && want.latched == 0);
        ASSERT_EQ(got.latched & s.latched, s.latched);
        ++cases;
      }
  EXPECT_GT(cases, 1000);
}

// Found by tests/fuzz/fuzz_supervisor: a fault bit outside the catalogue (here from a HAL's I/O
// layer) was masked off by supervisor_next, and the torque stayed on.
TEST(Supervisor, AFaultBitOutsideTheCatalogueFaultsAndIsLatched) {
  const std::uint32_t unknown = 1u << 31;
  ASSERT_EQ(unknown & kAllFaults, 0u);
  const Supervisor s = supervisor_next({SupervisorState::kRun, 0}, {unknown, true});
  EXPECT_EQ(s.state, SupervisorState::kFault);
  EXPECT_EQ(s.latched, unknown);
  EXPECT_FALSE(torque_enabled(s));
  EXPECT_EQ(supervisor_next({SupervisorState::kInit, 0}, {unknown, true}).state, SupervisorState::kFault);
}

}  // namespace
