// The board's pin map: every pin the firmware uses, its alternate function (datasheet DS8626,
// table 9 "alternate function mapping") and its role, in one place; the chip's drivers
// (boards/common/stm32f4) take their pins from here. The encoder table also names each joint's
// timer, its counter width and its clock-enable bit; the potentiometers' and the current monitors'
// tables each input's ADC channel (data sheet DS8626, table 7) and sample time. docs/stm32f4.md,
// "Wiring", is this file as a table; the pins are chosen free on the STM32F4DISCOVERY (MB997) where
// they can be (the exceptions are noted there: the current monitors' six are its on-board parts').
#pragma once

#include <cstdint>

#include "adc.hpp"
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
/// two ticks, about 240 times the fastest joint's counts per tick. The index pulse (once per motor
/// revolution) on the same timer's CH3 or CH4, the timer's alternate function on a free pin: TIM5's
/// CH3 and CH4 exist only on PA2 and PA3 in the 100-pin package (PH12 and PI0 are the 176-pin
/// part's), so the command link's RX moved from PA3 to PD6 to free PA3.
inline constexpr EncoderChannel kEncoders[hal::kJoints] = {
    // timer, width, clock enable, A, B, invert, index, its channel
    {Timer::kTim1, 16, &RccRegs::APB2ENR, RccRegs::kTim1En, enc(PE(9), 1), enc(PE(11), 1), false, enc(PE(13), 1),
     3},  // joint 1: TIM1_CH1/2, index TIM1_CH3
    {Timer::kTim2, 32, &RccRegs::APB1ENR, RccRegs::kTim2En, enc(PA(15), 1), enc(PB(3), 1), false, enc(PB(11), 1),
     4},  // joint 2: TIM2_CH1/2, index TIM2_CH4
    {Timer::kTim3, 16, &RccRegs::APB1ENR, RccRegs::kTim3En, enc(PB(4), 2), enc(PB(5), 2), false, enc(PC(8), 2),
     3},  // joint 3: TIM3_CH1/2, index TIM3_CH3
    {Timer::kTim4, 16, &RccRegs::APB1ENR, RccRegs::kTim4En, enc(PB(6), 2), enc(PB(7), 2), false, enc(PB(8), 2),
     3},  // joint 4: TIM4_CH1/2, index TIM4_CH3
    {Timer::kTim5, 32, &RccRegs::APB1ENR, RccRegs::kTim5En, enc(PA(0), 2), enc(PA(1), 2), false, enc(PA(3), 2),
     4},  // joint 5: TIM5_CH1/2, index TIM5_CH4
    {Timer::kTim8, 16, &RccRegs::APB2ENR, RccRegs::kTim8En, enc(PC(6), 3), enc(PC(7), 3), false, enc(PC(9), 3),
     4},  // joint 6: TIM8_CH1/2, index TIM8_CH4
};

// ---------------------------------------------------------------- analog inputs: ADC1
// One scan a tick (stm32f4::AnalogInputs, analog_inputs.hpp): the current monitors, then the
// potentiometers. The package's sixteen ADC1 pins (PA0-PA7, PB0-PB1, PC0-PC5; the 100-pin part has no
// port F) are the encoders' and the link's (PA0-PA3), the potentiometers' and the current monitors'.

/// Each joint's potentiometer (wiper to the pin, ends to VREF+ and VSSA), in joint order: channels
/// that are free on the Discovery. 480 sampling cycles: any potentiometer's impedance (adc.hpp).
inline constexpr AnalogInput kPots[hal::kJoints] = {
    {analog(PC(1)), 11, 480},  // joint 1: ADC123_IN11
    {analog(PC(2)), 12, 480},  // joint 2: ADC123_IN12
    {analog(PC(4)), 14, 480},  // joint 3: ADC12_IN14
    {analog(PC(5)), 15, 480},  // joint 4: ADC12_IN15
    {analog(PB(0)), 8, 480},   // joint 5: ADC12_IN8
    {analog(PB(1)), 9, 480},   // joint 6: ADC12_IN9
};
/// Each amplifier's current monitor, in channel order (the DACs' channels): its bipolar output
/// level-shifted to mid-scale (0 A at VREF+ / 2) behind an RC anti-alias filter of 1-2 kHz
/// (docs/stm32f4.md, "Current monitors and amplifier fault lines"). The last six ADC1 pins, each an
/// on-board part's on the Discovery (PA4 the audio codec's LRCK, PA5-PA7 the accelerometer's SPI, PC0
/// the USB power switch's enable with its pull-up, PC3 the microphone's output): freed there first.
/// 56 sampling cycles (the filter's capacitor charges the ADC's): converted first, 19 us from the start.
inline constexpr AnalogInput kCurrentMonitors[hal::kJoints] = {
    {analog(PA(4)), 4, 56},   // amplifier 1: ADC12_IN4
    {analog(PA(5)), 5, 56},   // amplifier 2: ADC12_IN5
    {analog(PA(6)), 6, 56},   // amplifier 3: ADC12_IN6
    {analog(PA(7)), 7, 56},   // amplifier 4: ADC12_IN7
    {analog(PC(0)), 10, 56},  // amplifier 5: ADC123_IN10
    {analog(PC(3)), 13, 56},  // amplifier 6: ADC123_IN13
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
/// Each amplifier's fault output, in channel order, on port E (free on the Discovery): an open-drain
/// output that holds its line low while the amplifier is healthy, internal pull-up. High is a fault:
/// the amplifier's (it lets go), or a broken wire or an unplugged amplifier (the pull-up).
constexpr PinConfig kAmpFaults[hal::kJoints] = {input(PE(7), Pull::kUp),  input(PE(8), Pull::kUp),
                                                input(PE(10), Pull::kUp), input(PE(12), Pull::kUp),
                                                input(PE(14), Pull::kUp), input(PE(15), Pull::kUp)};

// ---------------------------------------------------------------- telemetry
constexpr PinConfig kUartTx = alternate(PA(2), 7, Speed::kMedium);          // USART2_TX
constexpr PinConfig kUartRx = alternate(PD(6), 7, Speed::kLow, Pull::kUp);  // USART2_RX (PA3: joint 5's index)

// ---------------------------------------------------------------- every pin, once
constexpr PinConfig kOthers[] = {kDacSck,    kDacMosi, kDacSync[0], kDacSync[1], kDacLdac, kDacClr,
                                 kAmpEnable, kEstop,   kFaultLed,   kUartTx,     kUartRx};
/// Every pin of the map: each encoder's A, B and index, each potentiometer's, each current monitor's,
/// each amplifier fault line's, then the others.
constexpr int kPinCount = 6 * hal::kJoints + static_cast<int>(sizeof(kOthers) / sizeof(kOthers[0]));
constexpr Pin pin_at(int i) {
  const int n = hal::kJoints;
  if (i < 3 * n) {
    const EncoderChannel& e = kEncoders[i / 3];
    return i % 3 == 0 ? e.a.pin : i % 3 == 1 ? e.b.pin : e.index.pin;
  }
  if (i < 4 * n) return kPots[i - 3 * n].pin.pin;
  if (i < 5 * n) return kCurrentMonitors[i - 4 * n].pin.pin;
  if (i < 6 * n) return kAmpFaults[i - 5 * n].pin;
  return kOthers[i - 6 * n].pin;
}
/// No pin twice among `pins`.
constexpr bool distinct(const Pin* pins, int n) {
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (pins[i] == pins[j]) return false;
  return true;
}
constexpr bool pins_distinct() {
  Pin all[kPinCount] = {};
  for (int i = 0; i < kPinCount; ++i) all[i] = pin_at(i);
  return distinct(all, kPinCount);
}
static_assert(pins_distinct(), "a pin is used twice in the pin map");
static_assert(kEstop.pin.n == kEstopExtiLine, "EXTI line n is pin n of some port");

}  // namespace stm32f4::pins
