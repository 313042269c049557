// A board's parameter store (issue 27; docs/stm32f4.md, "Parameters in flash"): the parameter table's record
// (osc/runtime/parameters.hpp, ParamRecord) kept by persist::RecordStore on a flash medium, behind the command
// port's ParamStorage (save, load: osc/link/param_frames.hpp) and read once at power-on. Free of any chip: the
// STM32F4 keeps it in its flash sectors 10 and 11 (stm32f4::FlashSectors, boards/stm32f4/app.hpp), the virtual
// board in a file (osc_sim --param-file: host_sim/file_flash.hpp, two sectors of kImageSectorWords), a host test
// in a fake flash.
//
// A save on the STM32F4 stalls the core: an erase of a 128 KiB sector takes up to 2 s (DS8626), during which every
// fetch from flash waits, the control interrupt's included. The command port only saves with the torque off (the
// DACs at zero, the amplifier disabled), and the main loop calls it with the tick masked; the watchdog, fed by the
// ticks every millisecond and set to 5 ms, is stretched to its longest (LSI / 256, reload 4095: 22 s at the fastest
// LSI) around the save and set back after it (Safety::watchdog_stretch / watchdog_start's values).
#pragma once

#include <cstdint>
#include <cstring>

#include "osc/link/param_frames.hpp"
#include "record_store.hpp"  // boards/common/persist

namespace persist {

/// The sectors of a store kept as a file (the virtual board's --param-file): 4 KiB each, the table's record and
/// its five words of framing with room to grow.
constexpr std::uint32_t kImageSectorWords = 1024;
static_assert(osc::kParamSlots + 5 <= kImageSectorWords, "a record fits a sector of the file's image");

/// Whether the payload of a record is the parameter table's: its size is the layout's.
static_assert(sizeof(osc::ParamRecord) == 4 * osc::kParamSlots, "a record is the table's slots, f32 each");

/// What a power-on found in the store and did with it (FlashParamStore::apply_to): the record's load, and whether
/// the task took it.
struct BootLoad {
  LoadResult load;
  osc::ParamStatus applied;
  /// Why the task runs on its defaults (none, layout_mismatch, ..., or the task's refusal: bad_record, ...); nullptr
  /// when the record was applied: "loaded, sequence load.sequence".
  const char* defaults_why() const {
    if (!load.loaded()) return status_name(load.status);
    return applied == osc::ParamStatus::kOk ? nullptr : osc::param_status_name(applied);
  }
};

/// The watchdog of a store where none runs (the host).
struct NoWatchdog {
  void stretch() {}
  void restore() {}
};

/// The store over a flash medium (stm32f4::FlashSectors on the board, a file on the host, a fake in a host test) and
/// a watchdog with stretch() and restore() (the board's Safety; NoWatchdog where none runs).
template <class Sectors, class Watchdog>
class FlashParamStore {
 public:
  FlashParamStore(Sectors& sectors, Watchdog& watchdog) : store_(sectors), watchdog_(watchdog) {}

  /// The command port's storage: save and load through this store.
  osc::ParamStorage storage() { return {this, &FlashParamStore::save_to, &FlashParamStore::load_from}; }

  /// The newest valid record at boot, and what became of it.
  persist::LoadResult load(osc::ParamRecord& r) const {
    std::uint8_t bytes[sizeof(osc::ParamRecord)];
    const persist::LoadResult res = store_.load(bytes, sizeof bytes, osc::kParamLayout);
    if (res.loaded() && res.length == sizeof bytes)
      std::memcpy(&r, bytes, sizeof r);
    else if (res.loaded())
      return {persist::LoadStatus::kLayoutMismatch, res.sequence, res.length, res.sector};  // a shorter record
    return res;
  }

  /// A power-on's load: the newest valid record applied to the task as a whole (param_apply: checked, the gains'
  /// margins too), before the interrupts start.
  template <class S>
  [[gnu::cold]] BootLoad apply_to(osc::ControlTask<S>& task) const {
    osc::ParamRecord r;
    const LoadResult res = load(r);
    return {res, res.loaded() ? osc::param_apply(task, r) : osc::ParamStatus::kNoRecord};
  }

  /// The last save's result (a boot or a test reports it).
  persist::SaveResult last_save() const { return last_save_; }

 private:
  static bool save_to(void* ctx, const osc::ParamRecord& r) {
    auto* s = static_cast<FlashParamStore*>(ctx);
    std::uint8_t bytes[sizeof r];
    std::memcpy(bytes, &r, sizeof r);
    s->watchdog_.stretch();
    s->last_save_ = s->store_.save(bytes, sizeof bytes, osc::kParamLayout);
    s->watchdog_.restore();
    return s->last_save_.saved();
  }
  static osc::ParamStatus load_from(void* ctx, osc::ParamRecord& r) {
    const persist::LoadResult res = static_cast<const FlashParamStore*>(ctx)->load(r);
    switch (res.status) {
      case persist::LoadStatus::kLoaded:
        return osc::ParamStatus::kOk;
      case persist::LoadStatus::kNone:
        return osc::ParamStatus::kNoRecord;
      default:
        return osc::ParamStatus::kLayoutMismatch;
    }
  }

  persist::RecordStore<Sectors> store_;
  Watchdog& watchdog_;
  persist::SaveResult last_save_{persist::SaveStatus::kSaved, 0, -1};
};

}  // namespace persist
