// The parameter table over the link (issue 27): a param frame (get, set, save, load, reset, check;
// osc/link/command_frames.hpp) against the control task's parameters (osc/runtime/parameters.hpp)
// and the board's parameter store, answered by one param_answer frame. The command port
// (osc/link/command_port.hpp) hands every param frame here as it receives it.
//
// The store: save and load move one ParamRecord. A board gives its own (ParamStorage: the STM32F4's
// two flash sectors; the QEMU images and the virtual board a file when one is named, osc_sim
// --param-file: boards/common/param_store/param_store.hpp); without one the port keeps the record in
// RAM (RamParamStore), which a reset of the board loses (docs/protocol.md says so). Save, load and
// reset need the torque off, as ODrive refuses to save while armed: a record changes gains that the
// running observer uses.
#pragma once

#include <cstdint>

#include "osc/link/frames.hpp"
#include "osc/runtime/parameters.hpp"

namespace osc {

/// Where save and load keep the record: two calls on a board's context (no virtual call).
struct ParamStorage {
  void* ctx = nullptr;
  bool (*save)(void* ctx, const ParamRecord& r) = nullptr;
  /// The newest valid record of this table's layout into r: ok, no_record or layout_mismatch.
  ParamStatus (*load)(void* ctx, ParamRecord& r) = nullptr;
};

/// A store in RAM: the QEMU boards' and the simulator's (lost at a reset of the board).
class RamParamStore {
 public:
  ParamStorage storage() { return {this, &RamParamStore::save_to, &RamParamStore::load_from}; }

 private:
  static bool save_to(void* ctx, const ParamRecord& r) {
    auto* s = static_cast<RamParamStore*>(ctx);
    s->record_ = r;
    s->valid_ = true;
    return true;
  }
  static ParamStatus load_from(void* ctx, ParamRecord& r) {
    const auto* s = static_cast<const RamParamStore*>(ctx);
    if (!s->valid_) return ParamStatus::kNoRecord;
    r = s->record_;
    return ParamStatus::kOk;
  }
  ParamRecord record_{};
  bool valid_ = false;
};

namespace detail {
inline void param_answer_element(pil::ParamAnswerFrame& a, int i, int e) {
  const ParamInfo& p = kParams[i];
  a.lo = static_cast<float>(p.lo_of(e));
  a.hi = static_cast<float>(p.hi_of(e));
  if (p.access == ParamAccess::kTorqueOff) a.flags |= pil::kParamFlagTorqueOff;
  if (p.persists) a.flags |= pil::kParamFlagPersists;
}
inline void param_answer_margins(pil::ParamAnswerFrame& a, const GainMargins& m) {
  a.margins[0] = static_cast<float>(m.observer);
  a.margins[1] = static_cast<float>(m.b_max);
  a.margins[2] = static_cast<float>(m.condition37);
  a.margins[3] = static_cast<float>(m.loop);
  if (!(m.condition37 > 1)) a.flags |= pil::kParamFlagWarn37;
}
}  // namespace detail

/// Handles a param frame: the answer, and the task's parameters or the store changed as it says.
template <class S>
pil::ParamAnswerFrame param_answer(ControlTask<S>& task, const pil::ParamFrame& f, const ParamStorage& store) {
  pil::ParamAnswerFrame a;
  a.id = f.id;
  a.op = f.op;
  a.index = f.index;
  a.element = f.element;
  a.count = static_cast<std::uint8_t>(kParamCount);
  a.layout = kParamLayout;
  ParamStatus s = ParamStatus::kOk;
  const int i = f.index, e = f.element;
  switch (f.op) {
    case pil::kParamOpGet:
    case pil::kParamOpSet: {
      s = param_address_status(i, e);
      if (s != ParamStatus::kOk) break;
      if (f.op == pil::kParamOpSet) {
        GainMargins m;
        m.observer = -1;  // not judged (a runtime parameter, or refused before the gains were)
        s = param_set(task, i, e, static_cast<double>(f.value), &m);
        if (m.observer >= 0) detail::param_answer_margins(a, m);
      }
      detail::param_answer_element(a, i, e);
      a.value = static_cast<float>(param_get(task, i, e));
      break;
    }
    case pil::kParamOpSave:
      if (!param_torque_off(task))
        s = ParamStatus::kTorqueOn;
      else if (!store.save || !store.save(store.ctx, param_capture(task)))
        s = ParamStatus::kStoreFailed;
      break;
    case pil::kParamOpLoad: {
      if (!param_torque_off(task)) {
        s = ParamStatus::kTorqueOn;
        break;
      }
      ParamRecord r{};
      s = store.load ? store.load(store.ctx, r) : ParamStatus::kNoRecord;
      if (s == ParamStatus::kOk) s = param_apply(task, r);
      break;
    }
    case pil::kParamOpReset:
      s = param_apply(task, param_defaults());
      break;
    case pil::kParamOpCheck:
      detail::param_answer_margins(a, param_margins(task));
      break;
    default:
      s = ParamStatus::kBadOp;
  }
  a.status = static_cast<std::uint8_t>(s);
  return a;
}

}  // namespace osc
