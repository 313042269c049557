// SPI2 as a write-only master (RM0090 28.3.3, 28.3.5, 28.5): 8-bit frames, MSB first, software slave
// management (the board drives its devices' select lines as GPIO outputs). Each byte waits for TXE
// before it is written and for RXNE after (the received byte is read and dropped: no overrun), a
// transfer for BSY low at its end; every wait is bounded, and a wait that runs out fails the
// transfer. The board configures the SCK and MOSI pins and gives the SPI mode and the device's
// fastest clock (e.g. boards/stm32f4/dac_bus.hpp, the AD5754R pair's bus).
#pragma once

#include <cstdint>

#include "gpio.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

/// SPI baud-rate field for the fastest clock within max_hz: f_PCLK / 2^(BR+1).
constexpr std::uint32_t spi_baud_field(std::uint32_t pclk_hz, std::uint32_t max_hz) {
  std::uint32_t br = 0;
  while (br < 7 && (pclk_hz >> (br + 1)) > max_hz) ++br;
  return br;
}
static_assert(spi_baud_field(84000000, 1000000) == 6 && spi_baud_field(1000000, 1000) == 7,
              "656 kHz from 84 MHz; the slowest clock when none is slow enough");

/// Clock polarity and phase: mode = CPOL << 1 | CPHA (RM0090 28.3.1; CPHA is CR1 bit 0, CPOL bit 1).
enum class SpiMode : std::uint8_t { kMode0 = 0, kMode1 = 1, kMode2 = 2, kMode3 = 3 };
static_assert(static_cast<std::uint32_t>(SpiMode::kMode3) == (SpiRegs::kCpol | SpiRegs::kCpha), "CR1's bits");

class SpiMaster {
 public:
  /// Polls of each flag before the transfer fails: a byte is 8 SPI clocks (at most 16 bus cycles
  /// at /2), so this is far above any real wait.
  static constexpr std::uint32_t kPolls = 200;

  /// SPI2's clock, then master in `mode` at the fastest clock within `max_hz` from the APB1 clock
  /// `pclk1_hz`. Its SCK and MOSI pins (alternate function 5) are the board's to configure.
  void init(const Chip& chip, SpiMode mode, std::uint32_t pclk1_hz, std::uint32_t max_hz) {
    chip.rcc->APB1ENR = chip.rcc->APB1ENR | RccRegs::kSpi2En;
    read_back(chip.rcc->APB1ENR);
    spi_ = chip.spi2;
    const std::uint32_t cr1 = SpiRegs::kMstr | static_cast<std::uint32_t>(mode) | SpiRegs::kSsm | SpiRegs::kSsi |
                              SpiRegs::br(spi_baud_field(pclk1_hz, max_hz));
    spi_->CR1 = cr1;
    spi_->CR1 = cr1 | SpiRegs::kSpe;
  }

  /// Sends n bytes and waits until the last has left; false if a wait ran out (the rest unsent).
  bool send(const std::uint8_t* bytes, int n) {
    bool ok = true;
    for (int i = 0; i < n; ++i) {
      ok = ok && poll_until([&] { return (spi_->SR & SpiRegs::kTxe) != 0; }, kPolls);
      if (!ok) break;
      spi_->DR = bytes[i];
      ok = poll_until([&] { return (spi_->SR & SpiRegs::kRxne) != 0; }, kPolls);
      read_back(spi_->DR);
    }
    return poll_until([&] { return (spi_->SR & SpiRegs::kBsy) == 0; }, kPolls) && ok;
  }

 private:
  SpiRegs* spi_ = nullptr;
};

}  // namespace stm32f4
