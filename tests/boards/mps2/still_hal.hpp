// A HAL for the standalone MPS2 images that run the control task in the real 1 kHz TIMER0
// interrupt without a plant: the encoders held at the start pose (joint 1 offset by `jump` counts,
// to inject an encoder jump), the potentiometers reading the start pose where the arm has pots (so
// that the tick measured includes the position cross-check, as on a board with pots), no index
// pulse, the DAC codes kept in memory, the overrun seen as the next timer interrupt already pending
// when a tick starts; current monitors reading the codes written (WithCurrents), where the arm has them.
// board::StillHal is the arm's: with pots (StillPotHal) or without (StillHalBase), with current monitors or not.
#pragma once

#include <array>
#include <cstdint>
#include <type_traits>

#include "board.hpp"
#include "hal/hal.hpp"
#include "osc/control/faults.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/io.hpp"

namespace board {

struct StillHalBase {
  std::int32_t codes[osc::kDof] = {};
  std::int32_t jump = 0;
  bool read_encoders(std::int32_t c[osc::kDof]) {
    for (int i = 0; i < osc::kDof; ++i) c[i] = 0;
    c[0] = jump;
    return true;
  }
  void write_dacs(const std::int32_t c[osc::kDof]) {
    for (int i = 0; i < osc::kDof; ++i) codes[i] = c[i];
  }
  std::uint32_t cycles() { return board::cycles(); }
  void fault_output(bool active) { board::fault_output(active); }
  std::uint32_t io_faults() {
    // The next tick already pending when this one starts: the previous one overran.
    return board::control_timer_pending() ? static_cast<std::uint32_t>(osc::kFaultOverrun) : 0u;
  }
  bool take_index(int, std::int32_t&) { return false; }
  bool codes_zero() const {
    for (int c : codes)
      if (c != 0) return false;
    return true;
  }
};

/// The same with the pots (hal::PositionHal).
struct StillPotHal : StillHalBase {
  // hal::PositionHal: the start pose's codes, every tick.
  bool read_pots(std::uint16_t c[osc::kDof]) {
    static constexpr auto kCodes = [] {
      const auto& d = osc::robot::kDriveTrain;
      const double full = (1 << d.pot_bits) - 1;
      std::array<std::uint16_t, osc::kDof> a{};
      for (int i = 0; i < osc::kDof; ++i) {
        const double span = d.pot_max[i] - d.pot_min[i];  // 0 on an arm without pots (not used there)
        a[i] = span > 0 ? static_cast<std::uint16_t>((osc::robot::kQStart[i] - d.pot_min[i]) / span * full + 0.5) : 0;
      }
      return a;
    }();
    for (int i = 0; i < osc::kDof; ++i) c[i] = kCodes[i];
    return true;
  }
};

/// The same with current monitors (hal::CurrentHal) of healthy drives: each reads the code written last, on the
/// ADC's scale (so that the tick measured includes the drive check and its dither, as on a board with them).
template <class Base>
struct WithCurrents : Base {
  bool read_currents(std::int16_t a[osc::kDof]) {
    static constexpr std::int32_t kAdcPerCodeQ16 = [] {
      const osc::CurrentMonitor& m = osc::robot::kDriveTrain.current;
      const auto top = static_cast<double>(osc::current_max_code(m));
      return static_cast<std::int32_t>(top / (m.range * static_cast<double>(osc::kDacMaxCode)) * 65536 + 0.5);
    }();
    for (int i = 0; i < osc::kDof; ++i) a[i] = static_cast<std::int16_t>((this->codes[i] * kAdcPerCodeQ16) >> 16);
    return true;
  }
  std::uint32_t amp_faults() { return 0; }
};

using StillPositionHal = std::conditional_t<osc::has_pots(osc::robot::kDriveTrain), StillPotHal, StillHalBase>;
using StillHal = std::conditional_t<osc::has_current_monitors(osc::robot::kDriveTrain), WithCurrents<StillPositionHal>,
                                    StillPositionHal>;
static_assert(hal::ControlHal<StillHal> && hal::PositionHal<StillHal> == osc::has_pots(osc::robot::kDriveTrain));
static_assert(hal::CurrentHal<StillHal> == osc::has_current_monitors(osc::robot::kDriveTrain));

}  // namespace board
