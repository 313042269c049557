// The 1 kHz control interrupt: a timer's update event (RM0090 20.3 for the basic timers TIM6/TIM7;
// the same bits on TIM2..TIM5). The counter runs at 1 MHz (prescaler from the timer's kernel clock)
// and reloads every 1000 counts. URS: only the counter's overflow raises the interrupt, not the UG
// that loads the prescaler.
#pragma once

#include <cstdint>

#include "stm32f4_regs.hpp"

namespace stm32f4 {

struct TimerDivider {
  std::uint32_t psc, arr;
};
/// Prescaler to 1 MHz and reload for `hz` update events a second.
constexpr TimerDivider control_divider(std::uint32_t timer_clock_hz, std::uint32_t hz) {
  return {timer_clock_hz / 1000000u - 1u, 1000000u / hz - 1u};
}
static_assert(control_divider(84000000, 1000).psc == 83 && control_divider(84000000, 1000).arr == 999, "1 kHz");
/// No prescaler, the reload counts the timer clock itself: for a 32-bit timer (TIM2, TIM5).
constexpr TimerDivider control_divider_32bit(std::uint32_t timer_clock_hz, std::uint32_t hz) {
  return {0, timer_clock_hz / hz - 1u};
}

/// Starts the periodic update interrupt. A prescaler other than 0 is loaded at once by an update
/// event (UG; the prescaler register is buffered), with the counter restarted from 0; with prescaler
/// 0 neither is needed (both are at their reset values), and neither is written.
inline void control_timer_start(TimRegs& t, TimerDivider d) {
  t.CR1 = 0;
  t.DIER = 0;
  t.PSC = d.psc;
  t.ARR = d.arr;
  t.CR1 = TimRegs::kUrs;
  if (d.psc != 0) {
    t.EGR = TimRegs::kUg;
    t.CNT = 0;
  }
  t.SR = 0;
  t.DIER = TimRegs::kUie;
  t.CR1 = TimRegs::kUrs | TimRegs::kCen;
}
inline void control_timer_ack(TimRegs& t) { t.SR = ~TimRegs::kUif; }
inline bool control_timer_pending(const TimRegs& t) { return (t.SR & TimRegs::kUif) != 0; }

}  // namespace stm32f4
