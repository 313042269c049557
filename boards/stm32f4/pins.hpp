// The board's pin map: every pin the firmware uses, its alternate function (datasheet DS8626,
// table 9 "alternate function mapping") and its role, in one place; the chip's drivers
// (boards/common/stm32f4) take their pins from here. The encoder table also names each joint's
// timer, its counter width and its clock-enable bit. docs/stm32f4.md, "Wiring", is this file as a
// table; the pins are chosen free on the STM32F4DISCOVERY (MB997) where they can be (the exceptions
// are noted there).
#pragma once

#include <cstdint>

#include "encoders.hpp"
#include "gpio.hpp"
#include "hal/hal.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4::pins {

constexpr Pin PA(std::uint8_t n) { return {Port::A, n}; }
constexpr Pin PB(std::uint8_t n) { return {Port::B, n}; }
constexpr Pin PC(std::uint8_t n) { return {Port::C, n}; }
constexpr Pin PD(std::uint8_t n) { return {Port::D, n}; }
constexpr Pin PE(std::uint8_t n) { return {Port::E, n}; }

// ---------------------------------------------------------------- encoders
// The inputs come from line receivers (push-pull); the pull-ups only hold an unplugged input still.
constexpr PinConfig enc(Pin p, std::uint8_t af) { return alternate(p, af, Speed::kLow, Pull::kUp); }
/// One timer in encoder mode per joint (stm32f4::EncoderChannel, encoders.hpp). `invert`: set it for
/// a joint whose encoder counts against the joint's positive direction (first power-up,
/// docs/stm32f4.md). A 16-bit counter is unwrapped right while fewer than 32768 counts pass between
/// two ticks, about 240 times the fastest joint's counts per tick.
inline constexpr EncoderChannel kEncoders[hal::kJoints] = {
    {Timer::kTim1, 16, &RccRegs::APB2ENR, RccRegs::kTim1En, enc(PE(9), 1), enc(PE(11), 1), false},  // joint 1
    {Timer::kTim2, 32, &RccRegs::APB1ENR, RccRegs::kTim2En, enc(PA(15), 1), enc(PB(3), 1), false},  // joint 2
    {Timer::kTim3, 16, &RccRegs::APB1ENR, RccRegs::kTim3En, enc(PB(4), 2), enc(PB(5), 2), false},   // joint 3
    {Timer::kTim4, 16, &RccRegs::APB1ENR, RccRegs::kTim4En, enc(PB(6), 2), enc(PB(7), 2), false},   // joint 4
    {Timer::kTim5, 32, &RccRegs::APB1ENR, RccRegs::kTim5En, enc(PA(0), 2), enc(PA(1), 2), false},   // joint 5
    {Timer::kTim8, 16, &RccRegs::APB2ENR, RccRegs::kTim8En, enc(PC(6), 3), enc(PC(7), 3), false},   // joint 6
};

// ---------------------------------------------------------------- DAC: two AD5754R on SPI2
constexpr PinConfig kDacSck = alternate(PB(13), 5, Speed::kVeryHigh);   // SPI2_SCK  -> SCLK of both
constexpr PinConfig kDacMosi = alternate(PB(15), 5, Speed::kVeryHigh);  // SPI2_MOSI -> SDIN of both
/// SYNC (frame select, active low) of each chip: chip 0 drives joints 1-3, chip 1 joints 4-6.
constexpr PinConfig kDacSync[2] = {output(PD(8), true, Speed::kHigh), output(PD(9), true, Speed::kHigh)};
constexpr PinConfig kDacLdac = output(PD(10), true, Speed::kHigh);  // LDAC of both, active low
constexpr PinConfig kDacClr = output(PD(11), true, Speed::kHigh);   // CLR of both, active low

// ---------------------------------------------------------------- safety I/O
/// Amplifier enable, active high, with an external pull-down: disabled while the MCU is in reset,
/// unprogrammed or unpowered, and from boot until the supervisor runs healthy.
constexpr PinConfig kAmpEnable = output(PD(0), false);
/// E-stop: the chain of normally closed contacts from this pin to GND, internal pull-up: closed
/// (run) reads low; pressed, or a broken wire, reads high (rising edge: EXTI line 1).
constexpr PinConfig kEstop = input(PD(1), Pull::kUp);
constexpr int kEstopExtiLine = 1;
/// Fault LED (the STM32F4DISCOVERY's red LD5), active high.
constexpr PinConfig kFaultLed = output(PD(14), false);

// ---------------------------------------------------------------- telemetry
constexpr PinConfig kUartTx = alternate(PA(2), 7, Speed::kMedium);          // USART2_TX
constexpr PinConfig kUartRx = alternate(PA(3), 7, Speed::kLow, Pull::kUp);  // USART2_RX

// ---------------------------------------------------------------- every pin, once
constexpr PinConfig kOthers[] = {kDacSck,    kDacMosi, kDacSync[0], kDacSync[1], kDacLdac, kDacClr,
                                 kAmpEnable, kEstop,   kFaultLed,   kUartTx,     kUartRx};
constexpr int kPinCount = 2 * hal::kJoints + static_cast<int>(sizeof(kOthers) / sizeof(kOthers[0]));
constexpr Pin pin_at(int i) {
  return i < 2 * hal::kJoints ? (i % 2 ? kEncoders[i / 2].b.pin : kEncoders[i / 2].a.pin)
                              : kOthers[i - 2 * hal::kJoints].pin;
}
constexpr bool pins_distinct() {
  for (int i = 0; i < kPinCount; ++i)
    for (int j = i + 1; j < kPinCount; ++j)
      if (pin_at(i) == pin_at(j)) return false;
  return true;
}
static_assert(pins_distinct(), "a pin is used twice in the pin map");
static_assert(kEstop.pin.n == kEstopExtiLine, "EXTI line n is pin n of some port");

}  // namespace stm32f4::pins
