// The parameter table over the link (osc/link/param_frames.hpp, through the command port): get lists every
// parameter with its range and the table's layout; set, save, reset and load give the values back; a
// board's store takes save and load.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "osc/link/command_port.hpp"
#include "osc/link/param_frames.hpp"
#include "task_util.hpp"

namespace {

using namespace osc;
using osc::test::disabled_task;

// ------------------------------------------------------------------------------- over the link

struct ParamLink : ::testing::Test {
  std::unique_ptr<ControlTask<double>> task = disabled_task<double>();
  CommandPort<double> port;
  std::vector<pil::ParamAnswerFrame> answers;

  pil::ParamAnswerFrame ask(std::uint8_t op, int index = 0, int element = 0, float value = 0) {
    pil::ParamFrame f;
    f.id = static_cast<std::uint32_t>(answers.size() + 1);
    f.op = op;
    f.index = static_cast<std::uint8_t>(index);
    f.element = static_cast<std::uint8_t>(element);
    f.value = value;
    std::uint8_t buf[pil::kMaxFrame];
    const int n = pil::encode(f, buf);
    pil::Parser parser;
    bool taken = false;
    for (int k = 0; k < n; ++k)
      if (parser.feed(buf[k]) == pil::Parser::kFrame)
        taken = port.receive(*task, parser, [this](const std::uint8_t* b, int len) {
          pil::Parser p;
          for (int j = 0; j < len; ++j)
            if (p.feed(b[j]) == pil::Parser::kFrame) {
              pil::ParamAnswerFrame a;
              if (p.decode(a)) answers.push_back(a);
            }
        });
    EXPECT_TRUE(taken);
    EXPECT_EQ(answers.size(), f.id);
    return answers.empty() ? pil::ParamAnswerFrame{} : answers.back();
  }
};

TEST_F(ParamLink, GetListsEveryParameterWithItsRangeAndTheLayout) {
  for (int i = 0; i < kParamCount; ++i) {
    const pil::ParamAnswerFrame a = ask(pil::kParamOpGet, i, kParams[i].count - 1);
    EXPECT_EQ(a.status, static_cast<std::uint8_t>(ParamStatus::kOk)) << kParams[i].name;
    EXPECT_EQ(a.count, kParamCount);
    EXPECT_EQ(a.layout, kParamLayout);
    EXPECT_FLOAT_EQ(a.value, static_cast<float>(param_default(i, kParams[i].count - 1)));
    EXPECT_FLOAT_EQ(a.hi, static_cast<float>(kParams[i].hi_of(kParams[i].count - 1)));
    EXPECT_EQ((a.flags & pil::kParamFlagTorqueOff) != 0, kParams[i].access == ParamAccess::kTorqueOff);
  }
  EXPECT_EQ(ask(pil::kParamOpGet, kParamCount).status, static_cast<std::uint8_t>(ParamStatus::kUnknownParam));
  EXPECT_EQ(ask(pil::kParamOpGet, 0, 6).status, static_cast<std::uint8_t>(ParamStatus::kBadElement));
  EXPECT_EQ(ask(pil::kParamOpCount).status, static_cast<std::uint8_t>(ParamStatus::kBadOp));
}

TEST_F(ParamLink, SetSaveResetLoadGivesTheValuesBack) {
  const int ks = param_index("ks"), thr = param_index("collision_threshold");
  EXPECT_EQ(ask(pil::kParamOpLoad).status, static_cast<std::uint8_t>(ParamStatus::kNoRecord));
  pil::ParamAnswerFrame a = ask(pil::kParamOpSet, ks, 0, 80);
  EXPECT_EQ(a.status, static_cast<std::uint8_t>(ParamStatus::kOk));
  EXPECT_FLOAT_EQ(a.value, 80);
  EXPECT_GT(a.margins[0], 1);  // judged: the observer's margin
  EXPECT_EQ(ask(pil::kParamOpSet, thr, 2, 15).status, static_cast<std::uint8_t>(ParamStatus::kOk));
  EXPECT_EQ(ask(pil::kParamOpSave).status, static_cast<std::uint8_t>(ParamStatus::kOk));
  EXPECT_EQ(ask(pil::kParamOpReset).status, static_cast<std::uint8_t>(ParamStatus::kOk));
  EXPECT_FLOAT_EQ(ask(pil::kParamOpGet, ks, 0).value, params::kKs[0]);
  EXPECT_FLOAT_EQ(ask(pil::kParamOpGet, thr, 2).value, 0);
  EXPECT_EQ(ask(pil::kParamOpLoad).status, static_cast<std::uint8_t>(ParamStatus::kOk));
  EXPECT_FLOAT_EQ(ask(pil::kParamOpGet, ks, 0).value, 80);
  EXPECT_FLOAT_EQ(ask(pil::kParamOpGet, thr, 2).value, 15);
  EXPECT_DOUBLE_EQ(task->gains.ks(0), 80);
  // A refused set answers the value as it stays, and the reason.
  a = ask(pil::kParamOpSet, param_index("k"), 0, 2500);
  EXPECT_EQ(a.status, static_cast<std::uint8_t>(ParamStatus::kOutOfRange));
  EXPECT_FLOAT_EQ(a.value, params::kK[0]);
  EXPECT_EQ(ask(pil::kParamOpSet, param_index("k"), 3, 25).status, static_cast<std::uint8_t>(ParamStatus::kOk));
  a = ask(pil::kParamOpSet, param_index("ki"), 3, 3500);
  EXPECT_EQ(a.status, static_cast<std::uint8_t>(ParamStatus::kUnstableLoop));
  EXPECT_FLOAT_EQ(a.value, params::kKi[3]);
  EXPECT_GT(a.margins[0], 1);  // the observer's margin met, the loop's not
  EXPECT_LT(a.margins[3], 1);
  EXPECT_EQ(ask(pil::kParamOpSet, param_index("k"), 3, 32).status, static_cast<std::uint8_t>(ParamStatus::kOk));
  // Torque on: save, load and reset are refused.
  task->machine.state = MotionState::kHolding;
  for (std::uint8_t op : {pil::kParamOpSave, pil::kParamOpLoad, pil::kParamOpReset})
    EXPECT_EQ(ask(op).status, static_cast<std::uint8_t>(ParamStatus::kTorqueOn)) << pil::kParamOpNames[op];
  const pil::ParamAnswerFrame c = ask(pil::kParamOpCheck);
  EXPECT_EQ(c.status, static_cast<std::uint8_t>(ParamStatus::kOk));
  EXPECT_GT(c.margins[0], 50);
  EXPECT_GT(c.margins[2], 1);
  EXPECT_GT(c.margins[3], 2);  // the loop's, the paper's gains at the start pose
  EXPECT_EQ(c.flags & pil::kParamFlagWarn37, 0);
}

TEST_F(ParamLink, ABoardsStoreTakesSaveAndLoad) {
  struct Counting {
    ParamRecord r{};
    int saves = 0, loads = 0;
  } c;
  ParamStorage s;
  s.ctx = &c;
  s.save = [](void* ctx, const ParamRecord& r) {
    auto* k = static_cast<Counting*>(ctx);
    k->r = r;
    return ++k->saves < 2;  // the second save fails
  };
  s.load = [](void* ctx, ParamRecord& r) {
    auto* k = static_cast<Counting*>(ctx);
    ++k->loads;
    r = k->r;
    return ParamStatus::kLayoutMismatch;
  };
  port.set_param_storage(s);
  EXPECT_EQ(ask(pil::kParamOpSave).status, static_cast<std::uint8_t>(ParamStatus::kOk));
  EXPECT_EQ(ask(pil::kParamOpSave).status, static_cast<std::uint8_t>(ParamStatus::kStoreFailed));
  EXPECT_EQ(ask(pil::kParamOpLoad).status, static_cast<std::uint8_t>(ParamStatus::kLayoutMismatch));
  EXPECT_EQ(c.saves, 2);
  EXPECT_EQ(c.loads, 1);
}

}  // namespace
