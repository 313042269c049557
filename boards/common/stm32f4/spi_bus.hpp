// The DAC bus (ad5754r::Bus): SPI2 as master (RM0090 28.3.3, 28.3.5, 28.5) in mode 2, 8-bit frames,
// software slave management, plus GPIO outputs for each chip's SYNC, the shared LDAC and CLR
// (pins.hpp). Each byte waits for TXE before it is written and for RXNE after (the received byte is
// read and dropped: no overrun), the frame for BSY low before SYNC rises; every wait is bounded, and
// a wait that runs out fails the frame (SYNC still rises: the chip drops a frame cut short).
#pragma once

#include <cstdint>

#include "ad5754r.hpp"
#include "gpio.hpp"
#include "pins.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

/// SPI baud-rate field for the fastest clock within max_hz: f_PCLK / 2^(BR+1).
constexpr std::uint32_t spi_baud_field(std::uint32_t pclk_hz, std::uint32_t max_hz) {
  std::uint32_t br = 0;
  while (br < 7 && (pclk_hz >> (br + 1)) > max_hz) ++br;
  return br;
}
constexpr std::uint32_t kDacMaxSclkHz = 30000000;  // AD5754R data sheet, timing characteristics
static_assert(spi_baud_field(42000000, kDacMaxSclkHz) == 0, "21 MHz from the 42 MHz APB1");
static_assert(spi_baud_field(84000000, kDacMaxSclkHz) == 1, "21 MHz from 84 MHz");

class SpiDacBus {
 public:
  /// Polls of each flag before the frame fails: a byte is 8 SPI clocks (at most 16 bus cycles at
  /// /2), so this is far above any real wait.
  static constexpr std::uint32_t kPolls = 200;

  /// SPI2 clock, pins (SYNC, LDAC and CLR idle high), master mode 2 at most 30 MHz from `pclk1_hz`.
  void init(const Chip& chip, std::uint32_t pclk1_hz) {
    chip.rcc->APB1ENR = chip.rcc->APB1ENR | RccRegs::kSpi2En;
    read_back(chip.rcc->APB1ENR);
    for (const PinConfig& p :
         {pins::kDacSync[0], pins::kDacSync[1], pins::kDacLdac, pins::kDacClr, pins::kDacSck, pins::kDacMosi})
      pin_configure(chip, p);
    spi_ = chip.spi2;
    for (int c = 0; c < ad5754r::kChips; ++c) sync_[c] = &chip.port(pins::kDacSync[c].pin.port);
    ldac_ = &chip.port(pins::kDacLdac.pin.port);
    clr_ = &chip.port(pins::kDacClr.pin.port);
    const std::uint32_t cr1 = SpiRegs::kMstr | SpiRegs::kCpol | SpiRegs::kSsm | SpiRegs::kSsi |
                              SpiRegs::br(spi_baud_field(pclk1_hz, kDacMaxSclkHz));
    spi_->CR1 = cr1;
    spi_->CR1 = cr1 | SpiRegs::kSpe;
  }

  bool write(int chip, const ad5754r::Frame& f) {
    pin_write(*sync_[chip], pins::kDacSync[chip].pin.n, false);
    bool ok = true;
    for (std::uint8_t b : f.byte) {
      ok = ok && poll_until([&] { return (spi_->SR & SpiRegs::kTxe) != 0; }, kPolls);
      if (!ok) break;
      spi_->DR = b;
      ok = poll_until([&] { return (spi_->SR & SpiRegs::kRxne) != 0; }, kPolls);
      read_back(spi_->DR);
    }
    ok = poll_until([&] { return (spi_->SR & SpiRegs::kBsy) == 0; }, kPolls) && ok;
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
  SpiRegs* spi_ = nullptr;
  GpioRegs* sync_[ad5754r::kChips] = {};
  GpioRegs* ldac_ = nullptr;
  GpioRegs* clr_ = nullptr;
  std::uint32_t errors_ = 0;
};
static_assert(ad5754r::Bus<SpiDacBus>);

}  // namespace stm32f4
