// Quadrature encoders on timers in encoder mode (RM0090 14.3.16 and 17.3.12): encoder mode 3
// counts every edge of both channels (x4), up or down by the phase between them. TIM2 and TIM5
// count in 32 bits, TIM1, TIM3, TIM4 and TIM8 in 16; each reading is extended to the HAL's 32-bit
// count by hal::EncoderUnwrap (the difference since the last tick as a signed 16-bit number for a
// 16-bit counter: right as long as fewer than 32768 counts pass between two ticks). Which timer and
// pins each joint uses is the board's: a table of EncoderChannel in its pins.hpp, the template
// argument of EncoderBank.
#pragma once

#include <cstdint>
#include <iterator>
#include <type_traits>

#include "gpio.hpp"
#include "hal/hal.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

/// One joint's quadrature encoder: a timer in encoder mode 3 (x4: both edges of both channels),
/// channel A on the timer's CH1 input, B on CH2. `invert` reverses the counting direction (CC1P):
/// set it for a joint whose encoder counts against the joint's positive direction.
struct EncoderChannel {
  Timer timer;
  int bits;                       // counter width: 32 for TIM2 and TIM5, else 16
  Reg RccRegs::*enable_register;  // its clock enable
  std::uint32_t enable_bit;
  PinConfig a, b;
  bool invert;
};

/// The encoders of a table of channels (`Channels`: a constexpr array of EncoderChannel, one per
/// joint, in joint order).
template <const auto& Channels>
class EncoderBank {
  static_assert(std::is_same_v<std::remove_cvref_t<decltype(Channels[0])>, EncoderChannel>,
                "an array of EncoderChannel");

 public:
  /// Joints (timers) in the bank.
  static constexpr int kCount = static_cast<int>(std::size(Channels));
  /// Digital input filter of both channels (ICxF): 8 consecutive equal samples at the timer clock
  /// (48 ns at 168 MHz, 95 ns at 84 MHz) before an edge counts.
  static constexpr std::uint32_t kInputFilter = 3;

  /// Clocks, pins and counters (GPIO port clocks already on); every count starts at 0.
  void init(const Chip& chip) {
    for (int i = 0; i < kCount; ++i) {
      const EncoderChannel& e = Channels[i];
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
    for (int i = 0; i < kCount; ++i) {
      const std::uint32_t raw = tim_[i]->CNT;
      narrow_[i] = {raw & 0xFFFFu, 0};
      wide_[i] = {raw, 0};
    }
  }

  /// Accumulated counts of every joint since init() or restart().
  void read(std::int32_t counts[kCount]) {
    for (int i = 0; i < kCount; ++i) {
      const std::uint32_t raw = tim_[i]->CNT;
      counts[i] = Channels[i].bits == 32 ? wide_[i].update(raw) : narrow_[i].update(raw);
    }
  }

 private:
  TimRegs* tim_[kCount] = {};
  hal::EncoderUnwrap<16> narrow_[kCount];
  hal::EncoderUnwrap<32> wide_[kCount];
};

}  // namespace stm32f4
