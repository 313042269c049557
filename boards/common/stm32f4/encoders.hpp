// Quadrature encoders on timers in encoder mode (RM0090 14.3.16 and 17.3.12): encoder mode 3
// counts every edge of both channels (x4), up or down by the phase between them. TIM2 and TIM5
// count in 32 bits, TIM1, TIM3, TIM4 and TIM8 in 16; each reading is extended to the HAL's 32-bit
// count by hal::EncoderUnwrap (the difference since the last tick as a signed 16-bit number for a
// 16-bit counter: right as long as fewer than 32768 counts pass between two ticks). Which timer and
// pins each joint uses is the board's: a table of EncoderChannel in its pins.hpp, the template
// argument of EncoderBank.
//
// Index pulses: a third channel of each timer (CH3 or CH4, on TI3 or TI4) in input capture on the
// index's rising edge (RM0090 17.3.6 and 18.3.5, input capture mode) latches the counter in CCRx in
// hardware and sets CCxIF. Every read() (the control tick's) takes each latched capture (reading CCRx
// clears CCxIF) and converts it to the accumulated count read() returns, with that same read's raw
// counter and position: position + (capture - raw), the difference sign-extended to the counter's
// width. Right while fewer than 2^15 counts (16-bit counters; 2^31 for 32-bit) pass between the
// pulse and that read, which the unwrap itself already needs between two ticks. take_index() hands
// each latched count out once. A second pulse before the tick took the first sets CCxOF
// (overcapture): the latest capture is the one reported, and the overcapture is counted.
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
/// set it for a joint whose encoder counts against the joint's positive direction. The index pulse
/// on the timer's channel `index_channel` (3 or 4), captured on its rising edge.
struct EncoderChannel {
  Timer timer;
  int bits;                       // counter width: 32 for TIM2 and TIM5, else 16
  Reg RccRegs::*enable_register;  // its clock enable
  std::uint32_t enable_bit;
  PinConfig a, b;
  bool invert;
  PinConfig index;
  int index_channel;  // 3: CH3 (TI3), 4: CH4 (TI4)
};

/// Takes channel x's (1..4) latched input capture, if there is one: true when CCxIF was set, with
/// CCRx's value. Reading CCRx clears CCxIF (RM0090 17.4.5, 18.4.5), so no write can clear the flag
/// of a capture that comes meanwhile. A capture that came while CCxIF was still set has set CCxOF
/// (overcapture) and overwritten CCRx: the value is the latest; `overcaptured` reports it, and
/// CCxOF alone is cleared (SR's flags clear on a written 0, a written 1 leaves them as they are).
/// Regs: TimRegs on the chip; a test may give a block with the same member names that behaves as
/// the hardware's (tests/boards/stm32f4/test_stm32f4.cpp).
template <class Regs>
bool take_capture(Regs& t, int x, std::uint32_t& capture, bool& overcaptured) {
  const std::uint32_t sr = t.SR;
  if ((sr & TimRegs::ccif(x)) == 0) return false;
  capture = t.CCR[x - 1];
  overcaptured = (sr & TimRegs::ccof(x)) != 0;
  if (overcaptured) t.SR = ~TimRegs::ccof(x);
  return true;
}

/// The accumulated count at a captured counter value, from a read of the same counter: `position`
/// (the accumulated count at raw counter value `raw`) plus the difference capture - raw taken as a
/// signed `bits`-bit number. Right while fewer than 2^(bits-1) counts lie between the two.
constexpr std::int32_t count_at_capture(int bits, std::int32_t position, std::uint32_t raw, std::uint32_t capture) {
  const std::uint32_t shift = static_cast<std::uint32_t>(32 - bits);
  const std::int32_t d = static_cast<std::int32_t>((capture - raw) << shift) >> shift;
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(position) + static_cast<std::uint32_t>(d));
}
static_assert(count_at_capture(16, 90000, 24464, 65530) == 65530, "a capture before a 16-bit wrap");
static_assert(count_at_capture(16, -6, 65530, 3) == 3, "a capture after a wrap backwards");
static_assert(count_at_capture(32, 5, 0xFFFFFFFEu, 2) == 9, "32-bit");

/// The encoders of a table of channels (`Channels`: a constexpr array of EncoderChannel, one per
/// joint, in joint order).
template <const auto& Channels>
class EncoderBank {
  static_assert(std::is_same_v<std::remove_cvref_t<decltype(Channels[0])>, EncoderChannel>,
                "an array of EncoderChannel");
  static constexpr bool index_channels_valid() {
    for (const EncoderChannel& e : Channels)
      if (e.index_channel != 3 && e.index_channel != 4) return false;
    return true;
  }
  static_assert(index_channels_valid(), "an index on CH3 or CH4 (CH1 and CH2 are the encoder's A and B)");

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
      // The index: input capture on TI3 or TI4 with the same filter, rising edge (CCxP = CCxNP = 0).
      // CCxS is written while CCxE is still 0 (CCER is 0 until the next line).
      t.CCER = 0;
      const bool ch4 = e.index_channel == 4;
      t.CCMR2 = ch4 ? TimRegs::kCc4sTi4 | TimRegs::ic4f(kInputFilter) : TimRegs::kCc3sTi3 | TimRegs::ic3f(kInputFilter);
      pin_configure(chip, e.index);
      t.CCER = (e.invert ? TimRegs::kCc1p : 0u) | (ch4 ? TimRegs::kCc4e : TimRegs::kCc3e);
      t.PSC = 0;
      t.ARR = e.bits == 32 ? 0xFFFFFFFFu : 0xFFFFu;
      t.CNT = 0;
      t.SR = 0;  // no stale capture
      t.CR1 = TimRegs::kCen;
      tim_[i] = &t;
    }
    restart();
  }

  /// Counts from here on are relative to the counters' present values (an index count latched
  /// before is dropped: it was relative to the old ones).
  void restart() {
    for (int i = 0; i < kCount; ++i) {
      const std::uint32_t raw = tim_[i]->CNT;
      narrow_[i] = {raw & 0xFFFFu, 0};
      wide_[i] = {raw, 0};
      index_pending_[i] = false;
    }
  }

  /// Accumulated counts of every joint since init() or restart(); each index capture latched since
  /// the last read, converted to the same counts (take_index).
  void read(std::int32_t counts[kCount]) {
    for (int i = 0; i < kCount; ++i) {
      const EncoderChannel& e = Channels[i];
      const std::uint32_t raw = e.bits == 32 ? tim_[i]->CNT : tim_[i]->CNT & 0xFFFFu;
      counts[i] = e.bits == 32 ? wide_[i].update(raw) : narrow_[i].update(raw);
      std::uint32_t capture = 0;
      bool over = false;
      if (take_capture(*tim_[i], e.index_channel, capture, over)) {
        // A newer pulse replaces one the caller has not taken yet.
        index_count_[i] = count_at_capture(e.bits, counts[i], raw, capture);
        index_pending_[i] = true;
        if (over) ++overcaptures_[i];
      }
    }
  }

  /// The index pulse of joint `channel` latched since the last call: true once per latched capture,
  /// with the accumulated count at its edge. False for a channel outside the bank.
  bool take_index(int channel, std::int32_t& count) {
    if (channel < 0 || channel >= kCount || !index_pending_[channel]) return false;
    count = index_count_[channel];
    index_pending_[channel] = false;
    return true;
  }

  /// Index pulses of joint `channel` lost to a newer one before the tick took them (CCxOF).
  std::uint32_t overcaptures(int channel) const { return overcaptures_[channel]; }

 private:
  TimRegs* tim_[kCount] = {};
  hal::EncoderUnwrap<16> narrow_[kCount];
  hal::EncoderUnwrap<32> wide_[kCount];
  std::int32_t index_count_[kCount] = {};
  bool index_pending_[kCount] = {};
  std::uint32_t overcaptures_[kCount] = {};
};

}  // namespace stm32f4
