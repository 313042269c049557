// The board's analog inputs (pins.hpp): the amplifiers' current monitors and the joints'
// potentiometers, converted in one ADC1 scan a tick and moved by DMA2 (stm32f4::AdcScan, adc.hpp). The
// six currents come first, at 56 sampling cycles each: all six in the first 19 us of the tick, before
// the tick writes its DAC codes, so each is the amplifier's response to the codes the tick before wrote.
// Then the six potentiometers at 480 cycles; the twelve take 160 us at the 21 MHz ADC clock.
//
// The current monitors' coding (osc::robot::kDriveTrain.current): each monitor's bipolar output is
// level-shifted to mid-scale (0 A at VREF+ / 2), so code AdcScan::kMidScale (2048) is 0 A and
// read_currents gives the code less it: +-(2^(bits-1) - 1) = +-2047 at +-range times the DAC's
// full-scale current, kCurrentCodesPerFullScale (2047 / 1.25 = 1637.6) at the DAC's full scale,
// positive where a positive DAC code drives the amplifier. docs/stm32f4.md, "Current monitors and
// amplifier fault lines": the front end, its filter, the volts per ampere.
#pragma once

#include <cstdint>

#include "adc.hpp"
#include "hal/hal.hpp"
#include "osc/robot.hpp"
#include "pins.hpp"

namespace stm32f4 {

/// The board's one scan: the current monitors (table 0), then the potentiometers (table 1).
using AnalogScan = AdcScan<pins::kCurrentMonitors, pins::kPots>;
class AnalogInputs : public AnalogScan {
 public:
  static constexpr int kCurrentTable = 0, kPotTable = 1;

  /// The potentiometers' codes of the scan update() took this tick (0 .. 4095), in joint order;
  /// false when it had none.
  bool read(std::uint16_t pots[hal::kJoints]) const { return AnalogScan::read<kPotTable>(pots); }
  /// Each amplifier's current of that scan as a signed code (the code less kMidScale: -2048 .. 2047),
  /// in channel order; false when it had none.
  bool read_currents(std::int16_t currents[hal::kJoints]) const { return read_centred<kCurrentTable>(currents); }
};
static_assert(AnalogInputs::kSizes[AnalogInputs::kCurrentTable] == hal::kJoints &&
                  AnalogInputs::kSizes[AnalogInputs::kPotTable] == hal::kJoints,
              "a current monitor per amplifier and a potentiometer per joint");

/// The arm's current monitors (osc::robot::kDriveTrain.current), read at the board's resolution.
inline constexpr bool kHasCurrentMonitors = osc::has_current_monitors(osc::robot::kDriveTrain);
static_assert(!kHasCurrentMonitors || osc::robot::kDriveTrain.current.bits == AnalogInputs::kBits,
              "the arm's current monitors are read by the board's 12-bit ADC");
/// The codes at +-range times the DAC's full-scale current: +-(2^(bits-1) - 1).
inline constexpr std::int32_t kCurrentSpanCodes = AnalogInputs::kMidScale - 1;
/// The codes at the DAC's full-scale current: the span over the range (0 for an arm without monitors).
inline constexpr double kCurrentCodesPerFullScale =
    kHasCurrentMonitors ? kCurrentSpanCodes / osc::robot::kDriveTrain.current.range : 0.0;
static_assert(kCurrentCodesPerFullScale <= kCurrentSpanCodes, "the DAC's full scale within the ADC's span");

}  // namespace stm32f4
