// Six quadrature encoders on six timers in encoder mode (RM0090 14.3.16 and 17.3.12): encoder
// mode 3 counts every edge of both channels (x4), up or down by the phase between them. TIM2 and
// TIM5 count in 32 bits, TIM1, TIM3, TIM4 and TIM8 in 16; each reading is extended to the HAL's
// 32-bit count by hal::EncoderUnwrap (the difference since the last tick as a signed 16-bit number
// for a 16-bit counter: right as long as fewer than 32768 counts pass between two ticks, about 240
// times the fastest joint's counts per tick). The table of timers and pins is pins.hpp.
#pragma once

#include <cstdint>

#include "gpio.hpp"
#include "hal/hal.hpp"
#include "pins.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

class EncoderBank {
 public:
  /// Digital input filter of both channels (ICxF): 8 consecutive equal samples at the timer clock
  /// (48 ns at 168 MHz, 95 ns at 84 MHz) before an edge counts.
  static constexpr std::uint32_t kInputFilter = 3;

  /// Clocks, pins and counters (GPIO port clocks already on); every count starts at 0.
  void init(const Chip& chip) {
    for (int i = 0; i < hal::kJoints; ++i) {
      const pins::EncoderChannel& e = pins::kEncoders[i];
      Reg& enr = chip.rcc->*e.enable_register;
      enr = enr | e.enable_bit;
      read_back(enr);
      pin_configure(chip, e.a);
      pin_configure(chip, e.b);
      TimRegs& t = chip.timer(e.timer);
      t.CR1 = 0;
      t.SMCR = TimRegs::kSmsEncoder3;
      t.CCMR1 = TimRegs::kCc1sTi1 | TimRegs::kCc2sTi2 | TimRegs::ic1f(kInputFilter) | TimRegs::ic2f(kInputFilter);
      t.CCER = e.invert ? TimRegs::kCc1p : 0u;
      t.PSC = 0;
      t.ARR = e.bits == 32 ? 0xFFFFFFFFu : 0xFFFFu;
      t.CNT = 0;
      t.CR1 = TimRegs::kCen;
      tim_[i] = &t;
    }
    restart();
  }

  /// Counts from here on are relative to the counters' present values.
  void restart() {
    for (int i = 0; i < hal::kJoints; ++i) {
      const std::uint32_t raw = tim_[i]->CNT;
      narrow_[i] = {raw & 0xFFFFu, 0};
      wide_[i] = {raw, 0};
    }
  }

  /// Accumulated counts of every joint since init() or restart().
  void read(std::int32_t counts[hal::kJoints]) {
    for (int i = 0; i < hal::kJoints; ++i) {
      const std::uint32_t raw = tim_[i]->CNT;
      counts[i] = pins::kEncoders[i].bits == 32 ? wide_[i].update(raw) : narrow_[i].update(raw);
    }
  }

 private:
  TimRegs* tim_[hal::kJoints] = {};
  hal::EncoderUnwrap<16> narrow_[hal::kJoints];
  hal::EncoderUnwrap<32> wide_[hal::kJoints];
};

}  // namespace stm32f4
