// The motion state machine (osc/runtime/motion_states.hpp): exhaustively against an independent
// oracle (the documented table as data), its safety properties, its names, and sequences.
#include <gtest/gtest.h>

#include <cctype>
#include <cstring>
#include <initializer_list>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "osc/runtime/motion_states.hpp"

using namespace osc;

namespace osc {  // gtest prints an enumeration by its name
std::ostream& operator<<(std::ostream& os, MotionState e) { return os << motion_name(e); }
std::ostream& operator<<(std::ostream& os, MotionCommand e) { return os << motion_name(e); }
std::ostream& operator<<(std::ostream& os, MotionReason e) { return os << motion_name(e); }
}  // namespace osc

namespace {

using S = MotionState;
using C = MotionCommand;
using R = MotionReason;

constexpr int kStates = MotionNames<S>::kCount;
constexpr int kCommands = MotionNames<C>::kCount;
constexpr int kReasons = MotionNames<R>::kCount;
static_assert(kStates == 7 && kCommands == 8 && kReasons == 26);
static_assert(MotionNames<CommandOutcome>::kCount == 3 && MotionNames<StopCategory>::kCount == 3);
static_assert(MotionNames<MotionCompletion>::kCount == 4);
static_assert(sizeof(MotionNames<S>::kDocs) == sizeof(MotionNames<S>::kNames));
static_assert(sizeof(MotionNames<R>::kDocs) == sizeof(MotionNames<R>::kNames));

constexpr std::uint32_t kUndefinedBit = 1u << 31;
static_assert((kUndefinedBit & kAllFaults) == 0);

// ---- The oracle: the table of motion_states.hpp as data, and its rows written as plain rules. ----

enum class Pending { kKeep, kSet, kCancel };
/// What a command does in a state the events left: where it goes, the refusal (kNone: accepted),
/// the abort, the pending disable, whether it enables.
struct Cell {
  S to;
  R refusal;
  R abort;
  Pending pending;
  bool enabling;
};
constexpr Cell go(S to, Pending p = Pending::kKeep) { return {to, R::kNone, R::kNone, p, false}; }
constexpr Cell refuse(S stay, R why) { return {stay, why, R::kNone, Pending::kKeep, false}; }
constexpr Cell abort_to_stopping(R why, Pending p) { return {S::kStopping, R::kNone, why, p, false}; }

// Rows: disabled, holding, moving, stopping, (fault: the fault rules decide), yielding, homing;
// columns: enable, disable, move, stop, (clear: accepted, nothing changes, outside fault), home,
// declare_pose. A move the table accepts is refused not_homed while the encoders' offsets are unknown.
constexpr Cell kClearCell = go(S::kDisabled);  // unused: clear has its own rule
constexpr Cell kTable[7][7] = {
    {{S::kHolding, R::kNone, R::kNone, Pending::kCancel, true},
     go(S::kDisabled),
     refuse(S::kDisabled, R::kNotEnabled),
     refuse(S::kDisabled, R::kNotEnabled),
     kClearCell,
     refuse(S::kDisabled, R::kNotEnabled),
     go(S::kDisabled)},
    {go(S::kHolding), go(S::kDisabled), go(S::kMoving), go(S::kHolding), kClearCell, go(S::kHoming),
     refuse(S::kHolding, R::kTorqueOn)},
    {go(S::kMoving), abort_to_stopping(R::kDisableCommand, Pending::kSet), go(S::kMoving),
     abort_to_stopping(R::kStopCommand, Pending::kKeep), kClearCell, refuse(S::kMoving, R::kBusy),
     refuse(S::kMoving, R::kTorqueOn)},
    {go(S::kStopping, Pending::kCancel), go(S::kStopping, Pending::kSet), refuse(S::kStopping, R::kStopping),
     go(S::kStopping), kClearCell, refuse(S::kStopping, R::kStopping), refuse(S::kStopping, R::kTorqueOn)},
    {refuse(S::kFault, R::kFaulted), refuse(S::kFault, R::kFaulted), refuse(S::kFault, R::kFaulted),
     refuse(S::kFault, R::kFaulted), kClearCell, refuse(S::kFault, R::kFaulted), refuse(S::kFault, R::kFaulted)},
    {go(S::kHolding), go(S::kDisabled), refuse(S::kYielding, R::kYielding), go(S::kHolding), kClearCell,
     refuse(S::kYielding, R::kYielding), refuse(S::kYielding, R::kTorqueOn)},
    {go(S::kHoming), abort_to_stopping(R::kDisableCommand, Pending::kSet), refuse(S::kHoming, R::kBusy),
     abort_to_stopping(R::kStopCommand, Pending::kKeep), kClearCell, go(S::kHoming), refuse(S::kHoming, R::kTorqueOn)},
};

/// A motion runs: a client's or homing's.
bool running(S s) { return s == S::kMoving || s == S::kHoming; }

int code(S s) { return static_cast<int>(s); }
int code(C c) { return static_cast<int>(c); }

MotionStep oracle(MotionMachine m, MotionInput in) {
  MotionStep w{};
  const C cmd = code(in.command) < kCommands ? in.command : C::kNone;
  const bool unknown_state = code(m.state) >= kStates;
  // Faults: a new one, a latched one (the supervisor's), the fault state, an unreadable state.
  const std::uint32_t latched = in.latched | in.faults;
  if (latched || m.state == S::kFault || unknown_state) {
    if (running(m.state)) w.abort = R::kFaulted;
    const std::uint32_t now = in.faults | in.causes;
    if (cmd == C::kClear && now == 0) {
      w.machine = MotionMachine{S::kDisabled, false};
      w.outcome = CommandOutcome::kAccepted;
      return w;
    }
    w.machine = MotionMachine{S::kFault, false};
    w.stop = StopCategory::kCategory0;
    if (cmd != C::kNone) {
      w.outcome = CommandOutcome::kRefused;
      w.refusal = R::kFaulted;
      w.cause = cmd == C::kClear ? now : latched;
    }
    return w;
  }
  // Events: the generator's reports, then the runtime's stop request.
  S s = m.state;
  bool pending = s == S::kStopping && m.disable_at_rest;
  if (in.yield && s != S::kDisabled) {
    if (running(s)) w.abort = R::kCollision;
    s = S::kYielding;
    pending = false;
  } else if (running(s) && in.motion_finished) {
    w.completion = s == S::kHoming ? MotionCompletion::kHomed : MotionCompletion::kFinished;
    s = S::kHolding;
  } else if (running(s) && in.stop_request != R::kNone) {
    s = S::kStopping;
    w.abort = in.stop_request;
  } else if (s == S::kStopping && in.stopped) {
    s = pending ? S::kDisabled : S::kHolding;
    pending = false;
    w.completion = MotionCompletion::kStopped;
  }
  // The command, from the table.
  if (cmd == C::kClear) w.outcome = CommandOutcome::kAccepted;
  if (cmd != C::kNone && cmd != C::kClear) {
    Cell cell = kTable[code(s)][code(cmd) - 1];
    if (cmd == C::kMove && cell.refusal == R::kNone && !in.homed) cell = refuse(s, R::kNotHomed);
    s = cell.to;
    w.outcome = cell.refusal == R::kNone ? CommandOutcome::kAccepted : CommandOutcome::kRefused;
    w.refusal = cell.refusal;
    if (cell.abort != R::kNone) w.abort = cell.abort;
    if (cell.pending != Pending::kKeep) pending = cell.pending == Pending::kSet;
    w.enabling = cell.enabling;
  }
  w.machine = MotionMachine{s, s == S::kStopping && pending};
  w.torque = !(s == S::kDisabled || s == S::kFault);
  if (s == S::kStopping) w.stop = StopCategory::kCategory2;
  w.capture_pose = s == S::kHolding && m.state != S::kHolding;
  return w;
}

/// Every field of a step, by code and name, so that one comparison checks all and says what differs.
std::string describe(const MotionStep& t) {
  auto f = [](const char* name, auto v) {
    return std::string(name) + "=" + motion_name(v) + "(" + std::to_string(static_cast<int>(v)) + ") ";
  };
  return f("state", t.machine.state) + "pending=" + std::to_string(t.machine.disable_at_rest) + " " +
         f("outcome", t.outcome) + f("refusal", t.refusal) + "cause=" + std::to_string(t.cause) + " " +
         f("abort", t.abort) + f("completion", t.completion) + f("stop", t.stop) +
         "torque=" + std::to_string(t.torque) + " capture=" + std::to_string(t.capture_pose) +
         " enabling=" + std::to_string(t.enabling);
}

std::string describe(const MotionMachine& m, const MotionInput& in) {
  return std::string("from ") + motion_name(m.state) + "(" + std::to_string(code(m.state)) +
         ") pending=" + std::to_string(m.disable_at_rest) + " latched=" + std::to_string(in.latched) +
         " command=" + motion_name(in.command) + "(" + std::to_string(code(in.command)) +
         ") faults=" + std::to_string(in.faults) + " causes=" + std::to_string(in.causes) +
         " stop_request=" + motion_name(in.stop_request) + " finished=" + std::to_string(in.motion_finished) +
         " stopped=" + std::to_string(in.stopped) + " yield=" + std::to_string(in.yield) +
         " homed=" + std::to_string(in.homed);
}

bool torque_state(S s) {
  return s == S::kHolding || s == S::kMoving || s == S::kStopping || s == S::kYielding || s == S::kHoming;
}

/// The safety properties of one tick, whatever the table says.
void check_properties(const MotionMachine& m, const MotionInput& in, const MotionStep& t) {
  const S to = t.machine.state;
  const bool was_fault = m.state == S::kFault || in.latched != 0 || code(m.state) >= kStates;
  // A fault is category 0, torque off, in the same tick, and named as it came by a refusal's cause.
  if (in.faults != 0) {
    ASSERT_EQ(to, S::kFault);
    ASSERT_EQ(t.stop, StopCategory::kCategory0);
    ASSERT_FALSE(t.torque);
    ASSERT_TRUE(t.refusal != R::kFaulted || in.command == C::kClear || (t.cause & in.faults) == in.faults);
  }
  // Torque and the stop in effect follow the state; the output keeps the machine's invariants.
  ASSERT_EQ(t.torque, torque_state(to));
  ASSERT_EQ(t.stop == StopCategory::kCategory0, to == S::kFault);
  ASSERT_EQ(t.stop == StopCategory::kCategory2, to == S::kStopping);
  ASSERT_TRUE(!t.machine.disable_at_rest || to == S::kStopping);
  // Faults are sticky: only an accepted clear with no cause present leaves fault, for disabled.
  if (was_fault && to != S::kFault) {
    ASSERT_EQ(in.command, C::kClear);
    ASSERT_EQ(t.outcome, CommandOutcome::kAccepted);
    ASSERT_EQ(in.faults | in.causes, 0u);
    ASSERT_EQ(to, S::kDisabled);
  }
  // The machine keeps no latch of its own: a refusal `faulted` names the supervisor's, with this tick's faults.
  ASSERT_TRUE(t.refusal != R::kFaulted || in.command == C::kClear || t.cause == (in.latched | in.faults));
  if (was_fault && in.command == C::kClear && (in.faults | in.causes) != 0) {
    ASSERT_EQ(t.refusal, R::kFaulted);
    ASSERT_EQ(t.cause, in.faults | in.causes);  // the refusal names the cause still present
  }
  // No tick reaches moving from disabled, fault or yielding: only an enabled machine moves, and a
  // yielding one holds first; an arm not homed never starts a move; only an accepted home starts homing.
  ASSERT_TRUE(to != S::kMoving || m.state == S::kHolding || running(m.state) || m.state == S::kStopping);
  ASSERT_TRUE(to != S::kMoving || m.state == S::kMoving || in.homed);
  ASSERT_TRUE(to != S::kHoming || m.state == S::kHoming ||
              (in.command == C::kHome && t.outcome == CommandOutcome::kAccepted));
  // A collision to yield to leaves every powered state yielding, in the same tick, unless a command
  // of that tick holds or disables; a fault still wins.
  if (in.yield && in.faults == 0 && !was_fault && torque_state(m.state) && in.command != C::kEnable &&
      in.command != C::kStop && in.command != C::kDisable) {
    ASSERT_EQ(to, S::kYielding);
  }
  ASSERT_TRUE(to != S::kYielding || (in.yield && !was_fault) || m.state == S::kYielding);
  // Every command gets an outcome; every refusal has a name, one the machine decides.
  ASSERT_EQ(t.outcome == CommandOutcome::kNone, code(in.command) == 0 || code(in.command) >= kCommands);
  ASSERT_EQ(t.outcome == CommandOutcome::kRefused, t.refusal != R::kNone);
  if (t.outcome == CommandOutcome::kRefused) {
    ASSERT_STRNE(motion_name(t.refusal), "?");
    ASSERT_TRUE(t.refusal == R::kNotEnabled || t.refusal == R::kFaulted || t.refusal == R::kStopping ||
                t.refusal == R::kYielding || t.refusal == R::kBusy || t.refusal == R::kNotHomed ||
                t.refusal == R::kTorqueOn);
    ASSERT_TRUE(t.refusal != R::kNotHomed || (in.command == C::kMove && !in.homed));
  }
  ASSERT_TRUE(t.cause == 0 || t.refusal == R::kFaulted);  // a cause comes with a refusal `faulted` alone
  // Only a motion in progress is aborted, with a name; the pose is captured on entering holding.
  if (t.abort != R::kNone) {
    ASSERT_TRUE(running(m.state));
    ASSERT_STRNE(motion_name(t.abort), "none");
  }
  const bool ended = running(m.state) && to != m.state && t.completion != MotionCompletion::kFinished &&
                     t.completion != MotionCompletion::kHomed;
  ASSERT_TRUE(!ended || t.abort != R::kNone) << "a motion that ends without finishing is aborted, with a reason";
  ASSERT_EQ(t.capture_pose, to == S::kHolding && m.state != S::kHolding);
  if (t.enabling) {
    ASSERT_EQ(in.command, C::kEnable);
    ASSERT_EQ(to, S::kHolding);
  }
}

TEST(MotionStates, ExhaustiveAgainstTheTable) {
  const std::uint32_t latches[] = {0, kFaultEstop, kUndefinedBit};
  const std::uint32_t faults[] = {0, kFaultTracking, kUndefinedBit};
  const std::uint32_t causes[] = {0, kFaultEstop, 1u << 30};
  long cases = 0, refusals = 0, aborts = 0, faulting = 0;
  for (int st = 0; st <= kStates; ++st)  // one code past the list: an unreadable state
    for (int pending = 0; pending < 2; ++pending)
      for (std::uint32_t latched : latches)
        for (int cmd = 0; cmd <= kCommands; ++cmd)  // one code past the list: no command
          for (std::uint32_t f : faults)
            for (std::uint32_t cause : causes)
              for (int req = 0; req < kReasons; ++req)
                for (int ev = 0; ev < 16; ++ev) {
                  const MotionMachine m{static_cast<S>(st), pending != 0};
                  MotionInput in{};
                  in.latched = latched;
                  in.command = static_cast<C>(cmd);
                  in.faults = f;
                  in.causes = cause;
                  in.stop_request = static_cast<R>(req);
                  in.motion_finished = (ev & 1) != 0;
                  in.stopped = (ev & 2) != 0;
                  in.yield = (ev & 4) != 0;
                  in.homed = (ev & 8) == 0;
                  const MotionStep got = motion_next(m, in);
                  ASSERT_EQ(describe(got), describe(oracle(m, in))) << describe(m, in);
                  check_properties(m, in, got);
                  if (::testing::Test::HasFatalFailure()) FAIL() << describe(m, in) << "\n -> " << describe(got);
                  refusals += got.outcome == CommandOutcome::kRefused;
                  aborts += got.abort != R::kNone;
                  faulting += f != 0;
                  ++cases;
                }
  EXPECT_EQ(cases, 8L * 2 * 3 * 9 * 3 * 3 * kReasons * 16);
  EXPECT_GT(refusals, 0);  // the loop reached every kind of row
  EXPECT_GT(aborts, 0);
  EXPECT_GT(faulting, 0);
}

// ---- Properties over whole runs. ----

/// The supervisor's latch after a tick (Supervisor::latched, the one latch): this tick's faults added,
/// cleared by an accepted clear (the runtime re-initialises the supervisor).
std::uint32_t latch_after(std::uint32_t latched, const MotionInput& in, const MotionStep& t) {
  return in.command == C::kClear && t.outcome == CommandOutcome::kAccepted ? 0u : latched | in.faults;
}

/// The states reachable from disabled, over every input (faults: none or one named) but those
/// with a command left out.
std::set<int> reachable(std::set<C> left_out) {
  std::vector<std::pair<MotionMachine, std::uint32_t>> todo{{MotionMachine{}, 0u}};  // with the latch
  std::set<std::vector<std::uint32_t>> seen;
  std::set<int> states;
  while (!todo.empty()) {
    const auto [m, latched] = todo.back();
    todo.pop_back();
    if (!seen.insert({static_cast<std::uint32_t>(code(m.state)), latched, m.disable_at_rest}).second) continue;
    states.insert(code(m.state));
    for (int cmd = 0; cmd < kCommands; ++cmd)
      for (std::uint32_t f : {0u, static_cast<std::uint32_t>(kFaultEstop)})
        for (int req = 0; req < kReasons; ++req)
          for (int ev = 0; ev < 8; ++ev) {
            if (left_out.count(static_cast<C>(cmd)) != 0) continue;
            MotionInput in{.command = static_cast<C>(cmd),
                           .faults = f,
                           .latched = latched | f,
                           .causes = f,
                           .stop_request = static_cast<R>(req),
                           .motion_finished = (ev & 1) != 0,
                           .stopped = (ev & 2) != 0,
                           .yield = (ev & 4) != 0};
            for (int present = 0; present < 2; ++present, in.causes = 0) {
              const MotionStep t = motion_next(m, in);
              todo.push_back({t.machine, latch_after(latched, in, t)});
            }
          }
  }
  return states;
}

TEST(MotionStates, NoPathReachesMovingWithoutEnable) {
  EXPECT_EQ(reachable({C::kEnable}), (std::set<int>{code(S::kDisabled), code(S::kFault)}));
  // The search is a real one: with enable every state is reachable.
  EXPECT_EQ(reachable({C::kNone}).size(), static_cast<std::size_t>(kStates));
  // And without move and home no motion starts, so nothing stops.
  EXPECT_EQ(reachable({C::kMove, C::kHome}),
            (std::set<int>{code(S::kDisabled), code(S::kHolding), code(S::kFault), code(S::kYielding)}));
  // Without move, homing still moves (and stops).
  EXPECT_EQ(reachable({C::kMove}).count(code(S::kMoving)), 0u);
}

TEST(MotionStates, AFaultIsCategoryZeroWithTorqueOffInTheSameTickFromEveryState) {
  for (int st = 0; st < kStates; ++st)
    for (std::uint32_t f : {static_cast<std::uint32_t>(kFaultEstop), kUndefinedBit}) {
      const MotionStep t = motion_next({static_cast<S>(st), false}, {.command = C::kMove, .faults = f});
      EXPECT_EQ(t.machine.state, S::kFault) << st;
      EXPECT_EQ(t.stop, StopCategory::kCategory0);
      EXPECT_FALSE(t.torque);
      EXPECT_EQ(t.refusal, R::kFaulted);
      EXPECT_EQ(t.cause, f);  // the tick's fault, not yet in the supervisor's latch, named all the same
      EXPECT_EQ(t.abort, running(static_cast<S>(st)) ? R::kFaulted : R::kNone);
    }
}

// ---- Names. ----

template <class E>
void expect_named(const char* list) {
  std::set<std::string> names;
  for (int i = 0; i < MotionNames<E>::kCount; ++i) {
    const std::string name = motion_name(static_cast<E>(i));
    EXPECT_FALSE(name.empty()) << list << " " << i;
    for (char ch : name)
      EXPECT_TRUE(std::islower(static_cast<unsigned char>(ch)) || ch == '_' ||
                  std::isdigit(static_cast<unsigned char>(ch)))
          << name;
    EXPECT_TRUE(names.insert(name).second) << list << ": " << name << " twice";
    EXPECT_GT(std::strlen(MotionNames<E>::kDocs[i]), 10u) << list << " " << name;
  }
  EXPECT_STREQ(motion_name(static_cast<E>(MotionNames<E>::kCount)), "?") << list;
}

TEST(MotionStates, EveryEntryOfEveryListHasAUniqueNameAndAMeaning) {
  expect_named<MotionState>("states");
  expect_named<MotionCommand>("commands");
  expect_named<MotionReason>("reasons");
  expect_named<CommandOutcome>("outcomes");
  expect_named<StopCategory>("stop categories");
  expect_named<MotionCompletion>("completions");
}

TEST(MotionStates, TheIssuesNamesAreTheNamesInTelemetry) {
  const std::vector<std::string> states(std::begin(MotionNames<S>::kNames), std::end(MotionNames<S>::kNames));
  EXPECT_EQ(states,
            (std::vector<std::string>{"disabled", "holding", "moving", "stopping", "fault", "yielding", "homing"}));
  EXPECT_STREQ(motion_name(R::kNotHomed), "not_homed");  // issue 27's
  EXPECT_STREQ(motion_name(R::kOutOfWorkspace), "out_of_workspace");
  EXPECT_STREQ(motion_name(R::kNearSingular), "near_singular");
  EXPECT_STREQ(motion_name(R::kOverLimit), "over_limit");
  EXPECT_STREQ(motion_name(R::kNotEnabled), "not_enabled");
  EXPECT_STREQ(motion_name(R::kQueueFull), "queue_full");
  EXPECT_STREQ(motion_name(R::kFaulted), "faulted");
  EXPECT_STREQ(motion_name(R::kStaleStream), "stale_stream");
  EXPECT_STREQ(motion_name(R::kLimitReached), "limit_reached");
  EXPECT_STREQ(motion_name(R::kLinkSilent), "link_silent");
  EXPECT_STREQ(motion_name(R::kCollision), "collision");
  EXPECT_STREQ(motion_name(R::kYielding), "yielding");
  EXPECT_STREQ(motion_name(CollisionReaction::kCategory0), "category_0");
  EXPECT_STREQ(motion_name(CollisionReaction::kCategory2), "category_2");
  EXPECT_STREQ(motion_name(CollisionReaction::kYield), "yield");
  EXPECT_STREQ(motion_name(C::kMove), "move");
}

// ---- Sequences. ----

/// A machine driven tick by tick, with the supervisor's latch as the runtime keeps it (latch_after).
struct Arm {
  MotionMachine m{};
  std::uint32_t latched = 0;
  MotionStep last{};
  MotionStep tick(MotionInput in) {
    in.latched = latched | in.faults;
    last = motion_next(m, in);
    m = last.machine;
    latched = latch_after(latched, in, last);
    return last;
  }
  MotionStep command(C c) { return tick({.command = c}); }
};

/// An arm enabled and moving.
Arm moving_arm() {
  Arm a;
  a.command(C::kEnable);
  a.command(C::kMove);
  return a;
}

/// A tick that started a category-2 stop of a motion, for the reason given: torque on while it
/// decelerates.
void expect_category_2_stop(const MotionStep& s, R why) {
  EXPECT_EQ(s.machine.state, S::kStopping);
  EXPECT_EQ(s.stop, StopCategory::kCategory2);
  EXPECT_EQ(s.abort, why);
  EXPECT_TRUE(s.torque);
}

constexpr MotionState after(std::initializer_list<MotionInput> ticks) {
  MotionMachine m{};
  for (const MotionInput& in : ticks) m = motion_next(m, in).machine;
  return m.state;
}
// The machine is usable at compile time.
static_assert(after({{.command = C::kEnable}, {.command = C::kMove}}) == S::kMoving);
static_assert(after({{.command = C::kMove}}) == S::kDisabled);
static_assert(after({{.command = C::kEnable}, {.command = C::kMove}, {.faults = kFaultEstop}}) == S::kFault);

TEST(MotionSequences, EnableMoveStopStoppedHolds) {
  Arm a;
  const MotionStep e = a.command(C::kEnable);
  EXPECT_EQ(e.machine.state, S::kHolding);
  EXPECT_TRUE(e.enabling && e.capture_pose && e.torque);
  EXPECT_EQ(a.command(C::kMove).outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(a.m.state, S::kMoving);
  EXPECT_FALSE(a.last.capture_pose);
  const MotionStep s = a.command(C::kStop);
  expect_category_2_stop(s, R::kStopCommand);
  EXPECT_EQ(a.tick({}).machine.state, S::kStopping);  // decelerating
  const MotionStep r = a.tick({.stopped = true});
  EXPECT_EQ(r.machine.state, S::kHolding);
  EXPECT_EQ(r.completion, MotionCompletion::kStopped);
  EXPECT_TRUE(r.capture_pose && r.torque && !r.enabling);
  EXPECT_EQ(r.stop, StopCategory::kNone);
}

TEST(MotionSequences, AMoveWhileMovingIsAcceptedAndAFinishedMoveHolds) {
  Arm a = moving_arm();
  const MotionStep again = a.command(C::kMove);
  EXPECT_EQ(again.outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(again.machine.state, S::kMoving);
  EXPECT_EQ(again.abort, R::kNone);
  const MotionStep done = a.tick({.motion_finished = true});
  EXPECT_EQ(done.machine.state, S::kHolding);
  EXPECT_EQ(done.completion, MotionCompletion::kFinished);
  EXPECT_TRUE(done.capture_pose);
}

TEST(MotionSequences, AStaleStreamStopsWithCategoryTwoAndHoldsWithoutAFault) {
  Arm a = moving_arm();
  const MotionStep s = a.tick({.stop_request = R::kStaleStream});
  expect_category_2_stop(s, R::kStaleStream);
  EXPECT_EQ(a.tick({.stop_request = R::kStaleStream}).abort, R::kNone);  // reported once
  const MotionStep move = a.command(C::kMove);                           // refused during the stop
  EXPECT_EQ(move.outcome, CommandOutcome::kRefused);
  EXPECT_EQ(move.refusal, R::kStopping);
  const MotionStep h = a.tick({.stopped = true});
  EXPECT_EQ(h.machine.state, S::kHolding);
  EXPECT_EQ(a.latched, 0u);
  EXPECT_TRUE(h.torque);
  EXPECT_EQ(a.command(C::kMove).outcome, CommandOutcome::kAccepted);  // at rest, a move starts again
}

TEST(MotionSequences, ASilentCommandLinkStopsWithCategoryTwoOnlyWhileMoving) {
  Arm a = moving_arm();
  const MotionStep s = a.tick({.stop_request = R::kLinkSilent});
  expect_category_2_stop(s, R::kLinkSilent);
  EXPECT_EQ(a.tick({.stop_request = R::kLinkSilent}).abort, R::kNone);  // reported once
  const MotionStep h = a.tick({.stopped = true});
  EXPECT_EQ(h.machine.state, S::kHolding);
  EXPECT_EQ(a.latched, 0u);
  EXPECT_EQ(a.tick({.stop_request = R::kLinkSilent}).machine.state, S::kHolding);  // holding: nothing to stop
  Arm d;
  EXPECT_EQ(d.tick({.stop_request = R::kLinkSilent}).machine.state, S::kDisabled);
}

TEST(MotionSequences, DisableWhileMovingStopsFirstThenCutsTheTorque) {
  Arm a = moving_arm();
  const MotionStep s = a.command(C::kDisable);
  EXPECT_EQ(s.outcome, CommandOutcome::kAccepted);
  expect_category_2_stop(s, R::kDisableCommand);  // power on while it decelerates
  const MotionStep d = a.tick({.stopped = true});
  EXPECT_EQ(d.machine.state, S::kDisabled);
  EXPECT_EQ(d.completion, MotionCompletion::kStopped);
  EXPECT_FALSE(d.torque || d.capture_pose);
}

TEST(MotionSequences, AnEnableDuringAStopToDisableCancelsTheDisable) {
  Arm a = moving_arm();
  a.command(C::kDisable);
  EXPECT_EQ(a.command(C::kEnable).outcome, CommandOutcome::kAccepted);
  EXPECT_FALSE(a.m.disable_at_rest);
  EXPECT_EQ(a.tick({.stopped = true}).machine.state, S::kHolding);
}

TEST(MotionSequences, AFaultLatchesUntilAClearWithItsCauseGoneThenDisabled) {
  Arm a = moving_arm();
  const MotionStep f = a.tick({.faults = kFaultEstop, .causes = kFaultEstop});
  EXPECT_EQ(f.machine.state, S::kFault);
  EXPECT_EQ(f.abort, R::kFaulted);
  EXPECT_EQ(f.stop, StopCategory::kCategory0);
  EXPECT_FALSE(f.torque);
  for (C c : {C::kEnable, C::kDisable, C::kMove, C::kStop}) {
    const MotionStep r = a.command(c);
    EXPECT_EQ(r.refusal, R::kFaulted) << motion_name(c);
    EXPECT_EQ(r.cause, static_cast<std::uint32_t>(kFaultEstop));
  }
  const MotionStep held = a.tick({.command = C::kClear, .causes = kFaultEstop});  // E-stop still pressed
  EXPECT_EQ(held.outcome, CommandOutcome::kRefused);
  EXPECT_EQ(held.refusal, R::kFaulted);
  EXPECT_EQ(held.cause, static_cast<std::uint32_t>(kFaultEstop));
  EXPECT_EQ(held.machine.state, S::kFault);
  const MotionStep cleared = a.command(C::kClear);
  EXPECT_EQ(cleared.outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(cleared.machine.state, S::kDisabled);
  EXPECT_EQ(a.latched, 0u);
  EXPECT_FALSE(cleared.torque);
  EXPECT_EQ(a.command(C::kMove).refusal, R::kNotEnabled);
  EXPECT_TRUE(a.command(C::kEnable).enabling);
}

TEST(MotionSequences, RepeatedCommandsAreAcceptedAndChangeNothing) {
  Arm a;
  EXPECT_EQ(a.command(C::kDisable).outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(a.command(C::kClear).outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(a.m.state, S::kDisabled);
  a.command(C::kEnable);
  const MotionStep again = a.command(C::kEnable);
  EXPECT_EQ(again.outcome, CommandOutcome::kAccepted);
  EXPECT_FALSE(again.enabling || again.capture_pose);  // the observer is not restarted
  EXPECT_EQ(a.command(C::kStop).outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(a.m.state, S::kHolding);
  EXPECT_EQ(a.command(C::kStop).refusal, R::kNone);
}

TEST(MotionSequences, AnUnreadableStateCodeFaults) {
  const MotionStep t = motion_next({static_cast<S>(kStates), false}, {.command = C::kMove});
  EXPECT_EQ(t.machine.state, S::kFault);
  EXPECT_FALSE(t.torque);
  EXPECT_EQ(t.refusal, R::kFaulted);
}

}  // namespace

TEST(MotionSequences, AYieldAbortsTheMotionWithCollisionAndAStopHoldsThePoseItReached) {
  MotionMachine m{S::kMoving, false};
  MotionStep t = motion_next(m, {.yield = true});
  EXPECT_EQ(t.machine.state, S::kYielding);
  EXPECT_EQ(t.abort, R::kCollision);
  EXPECT_TRUE(t.torque);
  EXPECT_EQ(t.stop, StopCategory::kNone);  // a reaction, not a stop
  m = t.machine;
  t = motion_next(m, {.command = C::kMove});
  EXPECT_EQ(t.refusal, R::kYielding);
  EXPECT_EQ(t.machine.state, S::kYielding);
  t = motion_next(m, {.command = C::kStop});
  EXPECT_EQ(t.outcome, CommandOutcome::kAccepted);
  EXPECT_EQ(t.machine.state, S::kHolding);
  EXPECT_TRUE(t.capture_pose);
  EXPECT_FALSE(t.enabling);  // the observer runs on: it was never stopped
  // A fault while yielding is category 0 like anywhere else.
  t = motion_next(m, {.faults = kFaultEstop});
  EXPECT_EQ(t.machine.state, S::kFault);
  EXPECT_FALSE(t.torque);
  // A stop to disable that meets a collision yields; the pending disable is dropped.
  t = motion_next({S::kStopping, true}, {.yield = true});
  EXPECT_EQ(t.machine.state, S::kYielding);
  EXPECT_FALSE(t.machine.disable_at_rest);
  // Disabled, nothing yields: no torque to yield with.
  EXPECT_EQ(motion_next({}, {.yield = true}).machine.state, S::kDisabled);
}
