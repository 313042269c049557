// Fuzz target: the parameter table over the link (osc/link/param_frames.hpp, through the command
// port's receive) against a control task in double, float and fixed point. Byte 0 picks the scalar
// (bits 0-1) and whether the torque is on (bit 2: the motion state holding). Then each request is a
// param frame: an op byte, an index byte, an element byte, and a value (flag byte bit 0: raw f32
// bits, NaNs and infinities included; else a 16-bit integer times a step of the element's range).
//
// Invariants, every request:
//  - exactly one param_answer frame, its id, op, index and element echoed, its status a name of the
//    list, the table's size and layout;
//  - a refused set changes nothing (every slot of the task's record the same); an accepted one
//    changes that element only (a `every` gain: its vector), to the value asked within the scalar's
//    resolution;
//  - after any request every value is within its range and the gains keep the observer's margin
//    above 1 and the sampled loop's at least 1 (a set or a load never makes either unstable);
//  - with the torque on, nothing written torque_off changes, and save, load and reset are refused.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>

#include "fuzz_util.hpp"
#include "osc/link/command_port.hpp"
#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"

namespace {

using namespace osc;

template <class S>
struct Fixture {
  std::unique_ptr<ControlTask<S>> task = std::make_unique<ControlTask<S>>();
  CommandPort<S> port;
  Fixture() {
    task->init(Model<S>::of(robot::kArm), Gains<S>::paper(), FrictionMode::kAdaptive, joint_vector<S>(robot::kQStart),
               0, TaskStart::kDisabled);
  }
};

/// The resolution of a value in the scalar S (the rounding a set may leave).
template <class S>
double resolution(double v) {
  if constexpr (fixed::is_q_v<S>)
    return 2.0 / static_cast<double>(std::int64_t{1} << S::kFractionBits);
  else
    return std::fabs(v) * static_cast<double>(std::numeric_limits<S>::epsilon()) * 2 + 1e-30;
}

template <class S>
void run(fuzz::Input& in, bool torque_on) {
  static Fixture<S>* fx = new Fixture<S>();  // one task per scalar: its state carries across inputs (a record, a set)
  fx->task->init(Model<S>::of(robot::kArm), Gains<S>::paper(), FrictionMode::kAdaptive, joint_vector<S>(robot::kQStart),
                 0, TaskStart::kDisabled);
  ControlTask<S>& task = *fx->task;
  if (torque_on) task.machine.state = MotionState::kHolding;
  std::uint32_t id = 0;
  while (in.left() >= 4) {
    pil::ParamFrame f;
    f.id = ++id;
    f.op = static_cast<std::uint8_t>(in.u8() % (pil::kParamOpCount + 1));
    f.index = static_cast<std::uint8_t>(in.u8() % (kParamCount + 2));
    f.element = static_cast<std::uint8_t>(in.u8() % 8);
    const std::uint8_t how = in.u8();
    if (how & 1) {
      const std::uint32_t bits = in.u32();
      std::memcpy(&f.value, &bits, 4);
    } else {
      const int i = f.index < kParamCount ? f.index : 0, e = f.element < kParams[i].count ? f.element : 0;
      const double lo = kParams[i].lo_of(e), hi = kParams[i].hi_of(e);
      const double step = (hi - lo) / 30000.0;
      f.value = static_cast<float>(lo + static_cast<std::int16_t>(in.u16()) * step);
    }
    const ParamRecord before = param_capture(task);
    std::uint8_t buf[pil::kMaxFrame];
    const int n = pil::encode(f, buf);
    pil::Parser parser;
    int answers = 0;
    pil::ParamAnswerFrame a{};
    for (int k = 0; k < n; ++k)
      if (parser.feed(buf[k]) == pil::Parser::kFrame)
        FUZZ_CHECK(fx->port.receive(task, parser, [&](const std::uint8_t* b, int len) {
          pil::Parser p;
          for (int j = 0; j < len; ++j)
            if (p.feed(b[j]) == pil::Parser::kFrame) {
              FUZZ_CHECK(p.decode(a));
              ++answers;
            }
        }));
    FUZZ_CHECK(answers == 1);
    FUZZ_CHECK(a.id == f.id && a.op == f.op && a.index == f.index && a.element == f.element);
    FUZZ_CHECK(a.status < kParamStatusCount);
    FUZZ_CHECK(a.count == kParamCount && a.layout == kParamLayout);
    const auto status = static_cast<ParamStatus>(a.status);
    const ParamRecord after = param_capture(task);
    // Which slots the request may have changed.
    int lo_slot = 0, hi_slot = -1;
    if (f.op == pil::kParamOpSet && status == ParamStatus::kOk) {
      const ParamInfo& p = kParams[f.index];
      const bool every = p.gain >= 0 && kGainInfo[p.gain].param.form == GainForm::kEvery;
      lo_slot = hi_slot = param_slot(f.index) + f.element;
      // The stream timeout is kept in whole ticks: read back within half a tick.
      const double tick = p.gain < 0 && p.runtime == RuntimeParam::kParamStreamTimeout ? 0.5e-3 : 0.0;
      // Read from the task: a parameter that does not persist is at its default in a record (param_capture).
      FUZZ_CHECK(std::fabs(param_get(task, f.index, f.element) - static_cast<double>(f.value)) <=
                 resolution<S>(f.value) + 1e-6 * std::fabs(static_cast<double>(f.value)) + tick);
      if (!p.persists) FUZZ_CHECK(after.value[lo_slot] == static_cast<float>(param_default(f.index, f.element)));
      FUZZ_CHECK(!torque_on || p.access == ParamAccess::kAlways);
      (void)every;  // a kEvery gain is one slot: its vector is set whole, and read from element 0
    } else if ((f.op == pil::kParamOpLoad || f.op == pil::kParamOpReset) && status == ParamStatus::kOk) {
      FUZZ_CHECK(!torque_on);
      lo_slot = 0, hi_slot = kParamSlots - 1;
    }
    if (torque_on && (f.op == pil::kParamOpSave || f.op == pil::kParamOpLoad || f.op == pil::kParamOpReset))
      FUZZ_CHECK(status == ParamStatus::kTorqueOn);
    for (int k = 0; k < kParamSlots; ++k)
      if (k < lo_slot || k > hi_slot) FUZZ_CHECK(std::memcmp(&before.value[k], &after.value[k], 4) == 0);
    // Every value in range, the observer stable.
    for (int i = 0; i < kParamCount; ++i)
      for (int e = 0; e < kParams[i].count; ++e) {
        const double v = after.value[param_slot(i) + e];
        FUZZ_CHECK(std::isfinite(v));
        FUZZ_CHECK(v >= kParams[i].lo_of(e) - resolution<S>(v) && v <= kParams[i].hi_of(e) + resolution<S>(v));
      }
    const GainMargins m = param_margins(task);
    FUZZ_CHECK(m.observer > 1);
    FUZZ_CHECK(m.loop >= 1);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  const std::uint8_t first = in.u8();
  const bool torque_on = (first & 4) != 0;
  switch (first & 3) {
    case 0:
      run<double>(in, torque_on);
      break;
    case 1:
      run<float>(in, torque_on);
      break;
    default:
      run<Fixed>(in, torque_on);
      break;
  }
  return 0;
}
