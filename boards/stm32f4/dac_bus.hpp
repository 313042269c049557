// The board's DAC bus (ad5754r::Bus): SPI2 (stm32f4::SpiMaster) in mode 2 at up to the AD5754R's
// 30 MHz, plus GPIO outputs for each chip's SYNC, the shared LDAC and CLR (pins.hpp). A frame is
// its three bytes under the chip's SYNC; a frame whose SPI wait runs out fails (SYNC still rises:
// the chip drops a frame cut short).
#pragma once

#include <cstdint>

#include "ad5754r.hpp"
#include "gpio.hpp"
#include "pins.hpp"
#include "spi_bus.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

static_assert(spi_baud_field(42000000, ad5754r::kMaxSclkHz) == 0, "21 MHz from the 42 MHz APB1");
static_assert(spi_baud_field(84000000, ad5754r::kMaxSclkHz) == 1, "21 MHz from 84 MHz");

class SpiDacBus {
 public:
  /// The pins (SYNC, LDAC and CLR idle high), then SPI2 as master in mode 2 at most 30 MHz from the
  /// APB1 clock `pclk1_hz`.
  void init(const Chip& chip, std::uint32_t pclk1_hz) {
    for (const PinConfig& p :
         {pins::kDacSync[0], pins::kDacSync[1], pins::kDacLdac, pins::kDacClr, pins::kDacSck, pins::kDacMosi})
      pin_configure(chip, p);
    for (int c = 0; c < ad5754r::kChips; ++c) sync_[c] = &chip.port(pins::kDacSync[c].pin.port);
    ldac_ = &chip.port(pins::kDacLdac.pin.port);
    clr_ = &chip.port(pins::kDacClr.pin.port);
    spi_.init(chip, SpiMode::kMode2, pclk1_hz, ad5754r::kMaxSclkHz);
  }

  bool write(int chip, const ad5754r::Frame& f) {
    pin_write(*sync_[chip], pins::kDacSync[chip].pin.n, false);
    const bool ok = spi_.send(f.byte, sizeof f.byte);
    pin_write(*sync_[chip], pins::kDacSync[chip].pin.n, true);
    if (!ok) ++errors_;
    return ok;
  }
  /// LDAC low for at least the part's minimum pulse width (20 ns: the write and two read-backs of
  /// the port take longer at 168 MHz), then high.
  void ldac_pulse() { pulse(*ldac_, pins::kDacLdac.pin.n); }
  /// CLR low then high (a no-op before init(): a fault handler may call it that early).
  void clear_pulse() {
    if (clr_ != nullptr) pulse(*clr_, pins::kDacClr.pin.n);
  }
  /// Frames that failed since start.
  std::uint32_t errors() const { return errors_; }

 private:
  static void pulse(GpioRegs& g, std::uint8_t n) {
    pin_write(g, n, false);
    read_back(g.ODR);
    read_back(g.ODR);
    pin_write(g, n, true);
  }
  SpiMaster spi_;
  GpioRegs* sync_[ad5754r::kChips] = {};
  GpioRegs* ldac_ = nullptr;
  GpioRegs* clr_ = nullptr;
  std::uint32_t errors_ = 0;
};
static_assert(ad5754r::Bus<SpiDacBus>);

}  // namespace stm32f4
