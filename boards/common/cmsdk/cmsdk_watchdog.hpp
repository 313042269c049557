// The Arm CMSDK APB watchdog (Cortex-M System Design Kit TRM, DDI 0479), for any board built from
// CMSDK parts; the board supplies its base address and clock (boards/<board>/board.hpp).
//
// A 32-bit down counter on WDOGCLK, started by CTRL.INTEN. It counts LOAD clock cycles; at zero it
// raises its interrupt (WDOGINT) and counts LOAD again; if it reaches zero a second time with the
// interrupt still raised and CTRL.RESEN set, it asserts its reset output (WDOGRES). A write to
// INTCLR clears the interrupt and restarts the count from LOAD: that is the feed. While LOCK is
// locked every other register ignores writes; writing kUnlockKey to LOCK unlocks it, any other
// value locks it again. Each function below unlocks, writes and locks again.
#pragma once

#include <cstddef>
#include <cstdint>

namespace cmsdk {

struct WatchdogRegs {
  volatile std::uint32_t LOAD;    // 0x000 the count; a write restarts the counter from it
  volatile std::uint32_t VALUE;   // 0x004 the counter (read only)
  volatile std::uint32_t CTRL;    // 0x008 kIntEnable (counter and interrupt on), kResetEnable
  volatile std::uint32_t INTCLR;  // 0x00C write: clear the interrupt, restart from LOAD
  volatile std::uint32_t RIS;     // 0x010 raw interrupt status (bit 0)
  volatile std::uint32_t MIS;     // 0x014 masked interrupt status (bit 0)
  std::uint32_t reserved[(0xC00 - 0x018) / 4];
  volatile std::uint32_t LOCK;  // 0xC00 kUnlockKey unlocks; reads 1 while locked
  static constexpr std::uint32_t kIntEnable = 1u << 0, kResetEnable = 1u << 1;
  static constexpr std::uint32_t kUnlockKey = 0x1ACCE551u;
};
static_assert(offsetof(WatchdogRegs, RIS) == 0x010 && offsetof(WatchdogRegs, LOCK) == 0xC00,
              "CMSDK APB watchdog register map");

/// LOAD for a first expiry `us` microseconds after a feed, with a clock of `clock_hz`.
constexpr std::uint32_t watchdog_load(std::uint32_t clock_hz, std::uint32_t us) {
  return static_cast<std::uint32_t>(static_cast<std::uint64_t>(clock_hz) * us / 1000000u);
}

/// The watchdog at `Base`. Two stages: the interrupt LOAD clock cycles after the last feed, the
/// reset LOAD cycles after that.
template <std::uintptr_t Base>
struct Watchdog {
  static WatchdogRegs& regs() { return *reinterpret_cast<WatchdogRegs*>(Base); }

  /// Writes registers while unlocked (every write of this driver), then locks again.
  template <class Write>
  static void unlocked(Write write) {
    WatchdogRegs& w = regs();
    w.LOCK = WatchdogRegs::kUnlockKey;
    write(w);
    w.LOCK = 0;
  }

  /// Starts counting from `load` with the interrupt and the reset output enabled.
  static void start(std::uint32_t load) {
    unlocked([load](WatchdogRegs& w) {
      w.LOAD = load;
      w.INTCLR = 1;
      w.CTRL = WatchdogRegs::kIntEnable | WatchdogRegs::kResetEnable;
    });
  }
  /// Clears the interrupt and restarts the count from LOAD.
  static void feed() {
    unlocked([](WatchdogRegs& w) { w.INTCLR = 1; });
  }
  /// Stops the counter (interrupt and reset off).
  static void stop() {
    unlocked([](WatchdogRegs& w) {
      w.CTRL = 0;
      w.INTCLR = 1;
    });
  }
  /// Pauses the watchdog for a wait of unknown length; start() resumes it from a full count. The
  /// part stops its counter when CTRL.INTEN goes low (DDI 0479). QEMU 7.2's model (Debian 12's;
  /// later QEMU stops it as the part does) does not: its counter runs on, and its second expiry
  /// latches the reset even with CTRL.RESEN low, to be asserted as soon as start() sets RESEN. So
  /// the count restarts from the longest LOAD too: the two expiries are 2^33 clock cycles away
  /// (344 s at 25 MHz), where stop() leaves them two LOADs away.
  static void pause() {
    unlocked([](WatchdogRegs& w) {
      w.CTRL = 0;
      w.LOAD = 0xFFFFFFFFu;
      w.INTCLR = 1;
    });
  }
  /// The count has expired once since the last feed (the interrupt is raised).
  static bool expired_once() { return (regs().RIS & 1u) != 0; }
};

}  // namespace cmsdk
