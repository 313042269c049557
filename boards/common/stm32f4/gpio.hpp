// GPIO pins (RM0090 8.3, 8.4): a pin's configuration as data (PinConfig; a board's pin map,
// boards/<board>/pins.hpp, is a table of them) and the few operations the drivers need, over a
// port's register block.
#pragma once

#include <cstdint>

#include "stm32f4_regs.hpp"

namespace stm32f4 {

enum class Mode : std::uint8_t { kInput = 0, kOutput = 1, kAlternate = 2, kAnalog = 3 };
enum class Pull : std::uint8_t { kNone = 0, kUp = 1, kDown = 2 };
enum class Speed : std::uint8_t { kLow = 0, kMedium = 1, kHigh = 2, kVeryHigh = 3 };

struct Pin {
  Port port;
  std::uint8_t n;  // 0..15
  constexpr bool operator==(const Pin&) const = default;
};

/// What a pin is: its mode, alternate function number (kAlternate), pull resistor, output speed, and
/// for an output the level it starts at (set before the pin becomes an output: no glitch).
struct PinConfig {
  Pin pin;
  Mode mode;
  std::uint8_t af = 0;
  Pull pull = Pull::kNone;
  Speed speed = Speed::kLow;
  bool initial_high = false;
};

constexpr PinConfig alternate(Pin p, std::uint8_t af, Speed s = Speed::kHigh, Pull pull = Pull::kNone) {
  return {p, Mode::kAlternate, af, pull, s, false};
}
constexpr PinConfig output(Pin p, bool initial_high, Speed s = Speed::kMedium) {
  return {p, Mode::kOutput, 0, Pull::kNone, s, initial_high};
}
constexpr PinConfig input(Pin p, Pull pull) { return {p, Mode::kInput, 0, pull, Speed::kLow, false}; }
/// An analog input (an ADC channel): no pull resistor, the digital input off (RM0090 8.3.12).
constexpr PinConfig analog(Pin p) { return {p, Mode::kAnalog, 0, Pull::kNone, Speed::kLow, false}; }

/// Drives pin n high or low (BSRR: one atomic write, safe against an interrupt's write to the port).
inline void pin_write(GpioRegs& g, std::uint8_t n, bool high) { g.BSRR = high ? 1u << n : 1u << (n + 16u); }
inline bool pin_read(const GpioRegs& g, std::uint8_t n) { return ((g.IDR >> n) & 1u) != 0; }

/// Configures one pin (read-modify-write of the port's registers: call before interrupts use the port).
inline void pin_configure(GpioRegs& g, const PinConfig& c) {
  const std::uint32_t n = c.pin.n, two = 2u * n;
  if (c.mode == Mode::kOutput) pin_write(g, c.pin.n, c.initial_high);
  g.OTYPER = g.OTYPER & ~(1u << n);  // push-pull
  g.OSPEEDR = (g.OSPEEDR & ~(3u << two)) | (static_cast<std::uint32_t>(c.speed) << two);
  g.PUPDR = (g.PUPDR & ~(3u << two)) | (static_cast<std::uint32_t>(c.pull) << two);
  Reg& afr = g.AFR[n / 8];
  const std::uint32_t four = 4u * (n % 8);
  afr = (afr & ~(0xFu << four)) | (static_cast<std::uint32_t>(c.af & 0xFu) << four);
  g.MODER = (g.MODER & ~(3u << two)) | (static_cast<std::uint32_t>(c.mode) << two);
}
inline void pin_configure(const Chip& chip, const PinConfig& c) { pin_configure(chip.port(c.pin.port), c); }

}  // namespace stm32f4
