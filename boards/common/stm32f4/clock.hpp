// Clock tree (RM0090 6.2 and 7.3; flash wait states RM0090 3.5.1, table 10): the 8 MHz crystal
// (HSE) through the main PLL to a 168 MHz system clock, AHB 168 MHz, APB1 42 MHz (its timers 84 MHz),
// APB2 84 MHz (its timers 168 MHz), five flash wait states (168 MHz at 2.7-3.6 V).
//
// Every wait on a ready flag is a bounded number of polls. When a step does not complete, the
// result names it (BootFault) and the clock falls back to what the chip starts on: the internal
// 16 MHz RC oscillator (HSI), every bus and timer at 16 MHz; HSE and PLL are switched off again.
// Never a hang. QEMU's netduinoplus2 does not model the RCC (it reads as zero): there the HSE never
// becomes ready and the fallback is taken (the boot smoke test, docs/stm32f4.md).
#pragma once

#include <cstdint>

#include "stm32f4_regs.hpp"

namespace stm32f4 {

/// What went wrong at boot. kNone: every step completed.
enum class BootFault : std::uint8_t {
  kNone,
  kHseTimeout,     ///< the crystal oscillator never reported ready (HSERDY)
  kPllTimeout,     ///< the PLL never locked (PLLRDY)
  kFlashLatency,   ///< the flash did not take the wait states (ACR read back)
  kSwitchTimeout,  ///< the system clock never switched to the PLL (SWS)
  kWatchdogSetup,  ///< the independent watchdog never took its prescaler and reload (IWDG_SR)
  kDacSetup,       ///< a DAC set-up frame did not complete on the SPI bus
};
constexpr const char* boot_fault_name(BootFault f) {
  switch (f) {
    case BootFault::kNone:
      return "none";
    case BootFault::kHseTimeout:
      return "hse_timeout";
    case BootFault::kPllTimeout:
      return "pll_timeout";
    case BootFault::kFlashLatency:
      return "flash_latency";
    case BootFault::kSwitchTimeout:
      return "clock_switch_timeout";
    case BootFault::kWatchdogSetup:
      return "watchdog_setup";
    case BootFault::kDacSetup:
      return "dac_setup";
  }
  return "?";
}

/// The clocks the peripherals see [Hz], and how the set-up ended.
struct Clocks {
  std::uint32_t sysclk, hclk, pclk1, pclk2;
  std::uint32_t tim_apb1, tim_apb2;  ///< timer kernel clocks: x2 when the APB prescaler is not 1
  BootFault fault;
  bool on_pll() const { return fault == BootFault::kNone; }
};
constexpr Clocks kHsiClocks = {16000000, 16000000, 16000000, 16000000, 16000000, 16000000, BootFault::kNone};
constexpr Clocks kPllClocks = {168000000, 168000000, 42000000, 84000000, 84000000, 168000000, BootFault::kNone};

/// PLL from the 8 MHz crystal: VCO input 8 MHz / M = 1 MHz, VCO 1 MHz * N = 336 MHz,
/// SYSCLK = VCO / P = 168 MHz, 48 MHz domain = VCO / Q = 48 MHz.
struct PllSetting {
  std::uint32_t hse_hz = 8000000, m = 8, n = 336, p = 2, q = 7;
  constexpr std::uint32_t sysclk() const { return hse_hz / m * n / p; }
};
constexpr PllSetting kPll{};
static_assert(kPll.sysclk() == kPllClocks.sysclk && kPll.hse_hz / kPll.m * kPll.n / kPll.q == 48000000,
              "168 MHz system clock, 48 MHz for USB/SDIO");
constexpr std::uint32_t kFlashWaitStates = 5;  // 150 < HCLK <= 168 MHz at 2.7-3.6 V

/// How many times each ready flag is polled before giving up. A poll is a few cycles at 16 MHz (the
/// clock the set-up runs on), so the HSE gets more than 10 ms (the crystal needs a few), the PLL
/// more than 1 ms (it locks in well under 1 ms).
struct ClockPolls {
  std::uint32_t hse = 50000, pll = 20000, flash = 16, sw = 5000;
};

namespace detail {
/// Back to the reset clock: HSI as the system clock, every prescaler /1, PLL and HSE off.
inline Clocks clock_fallback(RccRegs& rcc, BootFault why, const ClockPolls& polls) {
  rcc.CFGR = rcc.CFGR & ~(RccRegs::kSwMask | RccRegs::kHpreMask | RccRegs::kPpre1Mask | RccRegs::kPpre2Mask);
  poll_until([&] { return (rcc.CFGR & RccRegs::kSwsMask) == RccRegs::kSwsHsi; }, polls.sw);
  rcc.CR = rcc.CR & ~(RccRegs::kPllOn | RccRegs::kHseOn);
  Clocks c = kHsiClocks;
  c.fault = why;
  return c;
}
}  // namespace detail

/// Sets up the clock tree (runs on HSI, from reset, before any peripheral is clocked). Returns the
/// clocks in use: kPllClocks, or kHsiClocks with the step that failed.
inline Clocks clock_init(RccRegs& rcc, FlashRegs& flash, const ClockPolls& polls = {}, const PllSetting& pll = kPll) {
  rcc.CR = rcc.CR | RccRegs::kHseOn;
  if (!poll_until([&] { return (rcc.CR & RccRegs::kHseRdy) != 0; }, polls.hse))
    return detail::clock_fallback(rcc, BootFault::kHseTimeout, polls);

  rcc.CR = rcc.CR & ~RccRegs::kPllOn;  // PLLCFGR may be written only while the PLL is off
  rcc.PLLCFGR = RccRegs::pllcfgr(pll.m, pll.n, pll.p, pll.q);
  rcc.CR = rcc.CR | RccRegs::kPllOn;
  if (!poll_until([&] { return (rcc.CR & RccRegs::kPllRdy) != 0; }, polls.pll))
    return detail::clock_fallback(rcc, BootFault::kPllTimeout, polls);

  // Wait states before the faster clock; the manual asks to read ACR back to check they are taken.
  flash.ACR = kFlashWaitStates | FlashRegs::kPrften | FlashRegs::kIcen | FlashRegs::kDcen;
  if (!poll_until([&] { return (flash.ACR & FlashRegs::kLatencyMask) == kFlashWaitStates; }, polls.flash))
    return detail::clock_fallback(rcc, BootFault::kFlashLatency, polls);

  // AHB /1, APB1 /4 (42 MHz, its maximum), APB2 /2 (84 MHz, its maximum), then the switch.
  rcc.CFGR = (rcc.CFGR & ~(RccRegs::kHpreMask | RccRegs::kPpre1Mask | RccRegs::kPpre2Mask)) | RccRegs::kPpre1Div4 |
             RccRegs::kPpre2Div2;
  rcc.CFGR = (rcc.CFGR & ~RccRegs::kSwMask) | RccRegs::kSwPll;
  if (!poll_until([&] { return (rcc.CFGR & RccRegs::kSwsMask) == RccRegs::kSwsPll; }, polls.sw))
    return detail::clock_fallback(rcc, BootFault::kSwitchTimeout, polls);
  return kPllClocks;
}

}  // namespace stm32f4
