// Six bipolar ±10 V torque commands from two Analog Devices AD5754R (quad, 16-bit, serial input,
// voltage output DAC with internal 2.5 V reference): chip 0 channels A, B, C drive joints 1, 2, 3;
// chip 1 channels A, B, C joints 4, 5, 6; channel D of each is unused (0 V, powered down).
//
// Serial interface, in our words from the AD5724R/AD5734R/AD5754R data sheet (Rev. F; "Serial
// Interface", "Input Shift Register" and "Register" tables):
//   - a write is one 24-bit frame, MSB first, framed by SYNC low; SDIN is sampled on SCLK's falling
//     edges (SPI mode 2 here: clock idles high, data taken on the first, falling, edge), up to
//     30 MHz;
//   - bit 23 R/W (0: write), bit 22 zero, bits 21-19 the register (0 DAC, 1 output range select,
//     2 power control, 3 control), bits 18-16 the channel (0-3 = A-D, 4 = all four), bits 15-0
//     the data;
//   - a DAC register write lands in the channel's input register; with LDAC held high the outputs
//     do not move until LDAC is pulsed low (at least 20 ns), which updates every channel of the chip
//     at once: one pulse on the shared LDAC line updates all six joints together;
//   - a falling edge on CLR sets every output to the clear code at once (control register "clear
//     select" 0: 0 V in a bipolar range), without the serial interface;
//   - output range select code 4 is ±10 V (with the internal reference, gain 4: ±10 V span);
//   - power control: bits 0-3 power up channels A-D, bit 4 the internal reference; everything is
//     powered down after power-on;
//   - control register with channel field 1: bit 3 thermal shutdown enable, bit 2 current clamp
//     enable, bit 1 clear select, bit 0 SDO disable;
//   - bipolar coding is two's complement with the BIN/2sCOMP pin tied low (offset binary with it
//     high): code 0 is 0 V, +32767 is +10 V × 32767/32768, -32768 is -10 V.
// The hardware (SPI, SYNC, LDAC, CLR pins) is the Bus template parameter, a board's: on the STM32F4
// board boards/stm32f4/dac_bus.hpp, in tests/boards/stm32f4/test_stm32f4.cpp a recording bus. The driver knows no
// chip (its target, ad5754r, exports this folder alone).
#pragma once

#include <concepts>
#include <cstdint>

#include "hal/hal.hpp"

namespace ad5754r {

enum Register : std::uint8_t { kDacRegister = 0, kOutputRange = 1, kPowerControl = 2, kControl = 3 };
constexpr std::uint8_t kAllChannels = 4;
constexpr std::uint16_t kRangeBipolar10V = 4;
constexpr std::uint8_t kControlFunctionSet = 1;  ///< channel field of a control-register write: settings
constexpr std::uint16_t kTsdEnable = 1u << 3, kClampEnable = 1u << 2, kSdoDisable = 1u << 0;  // clear select 0
constexpr std::uint16_t kPowerUpABC = 0x7u, kPowerUpReference = 1u << 4;

constexpr std::uint32_t kMaxSclkHz = 30000000;  ///< the fastest SCLK (data sheet, timing characteristics)

constexpr int kChips = 2;
constexpr int kChannelsUsed = 3;  ///< per chip
static_assert(kChips * kChannelsUsed == hal::kJoints, "one DAC channel per joint");

/// One 24-bit frame, in the order it is shifted out.
struct Frame {
  std::uint8_t byte[3];
  constexpr bool operator==(const Frame&) const = default;
};
constexpr Frame frame(Register reg, std::uint8_t channel, std::uint16_t data) {
  return {{static_cast<std::uint8_t>((reg << 3) | (channel & 7u)), static_cast<std::uint8_t>(data >> 8),
           static_cast<std::uint8_t>(data & 0xFFu)}};
}
/// The 16-bit two's-complement word of a signed code (saturated to the 16-bit range).
constexpr std::uint16_t code_word(std::int32_t code) {
  const std::int32_t c = code > 32767 ? 32767 : code < -32768 ? -32768 : code;
  return static_cast<std::uint16_t>(static_cast<std::uint32_t>(c) & 0xFFFFu);
}
/// Joint j's chip and channel.
constexpr int chip_of(int joint) { return joint / kChannelsUsed; }
constexpr std::uint8_t channel_of(int joint) { return static_cast<std::uint8_t>(joint % kChannelsUsed); }

/// What the DAC pair needs from the hardware.
template <class B>
concept Bus = requires(B& b, int chip, const Frame& f) {
  { b.write(chip, f) } -> std::same_as<bool>;  // one frame to one chip (SYNC low .. high); false: bus fault
  { b.ldac_pulse() } -> std::same_as<void>;    // LDAC low then high: every written channel updates
  { b.clear_pulse() } -> std::same_as<void>;   // CLR low then high: every output to 0 V now
};

template <Bus B>
class DacPair {
 public:
  explicit DacPair(B& bus) : bus_(bus) {}

  /// Set-up after power-on: ±10 V range, clamp and thermal shutdown on, clear to 0 V, SDO off, every
  /// channel at code 0 (loaded), then channels A-C and the reference powered up. Returns false if
  /// the bus failed.
  bool init() {
    bool ok = true;
    for (int c = 0; c < kChips; ++c) {
      ok = bus_.write(c, frame(kOutputRange, kAllChannels, kRangeBipolar10V)) && ok;
      ok = bus_.write(c, frame(kControl, kControlFunctionSet, kTsdEnable | kClampEnable | kSdoDisable)) && ok;
      ok = bus_.write(c, frame(kDacRegister, kAllChannels, 0)) && ok;
    }
    bus_.ldac_pulse();
    for (int c = 0; c < kChips; ++c) ok = bus_.write(c, frame(kPowerControl, 0, kPowerUpABC | kPowerUpReference)) && ok;
    return ok;
  }

  /// One tick's burst: the six codes into the input registers, then one LDAC pulse, so that every
  /// joint's output changes at the same instant. Returns false if the bus failed (the outputs then
  /// keep their previous values until the next burst or a clear).
  bool write(const std::int32_t codes[hal::kJoints]) {
    bool ok = true;
    for (int j = 0; j < hal::kJoints; ++j)
      ok = bus_.write(chip_of(j), frame(kDacRegister, channel_of(j), code_word(codes[j]))) && ok;
    bus_.ldac_pulse();
    return ok;
  }

  /// Every output to 0 V at once (the CLR line), whatever the bus is doing.
  void clear() { bus_.clear_pulse(); }

 private:
  B& bus_;
};

}  // namespace ad5754r
