// Telemetry over USART2 (RM0090 30.3, 30.6): 8N1, transmit and receive enabled, 16x oversampling.
// The control tick hands over a whole frame (offer()); the main loop sends it byte by byte whenever
// the transmit register is empty (pump()), so the tick never waits for the line. While a frame is
// still going out, offer() refuses the next one (counted: dropped()). The board gives the largest
// frame (the template argument) and the TX and RX pins (init()).
#pragma once

#include <cstdint>

#include "gpio.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

/// BRR for a baud rate (16x oversampling: USARTDIV = f_PCLK / (16 baud), BRR holds 16 USARTDIV as
/// mantissa and 4-bit fraction, i.e. f_PCLK / baud rounded).
constexpr std::uint32_t usart_brr(std::uint32_t pclk_hz, std::uint32_t baud) { return (pclk_hz + baud / 2) / baud; }
/// The baud rate a BRR gives.
constexpr std::uint32_t usart_baud(std::uint32_t pclk_hz, std::uint32_t brr) { return pclk_hz / brr; }
static_assert(usart_brr(42000000, 460800) == 91 && usart_brr(16000000, 460800) == 35, "BRR at 42 and 16 MHz");

/// USART2 sending frames of at most `Capacity` bytes.
template <int Capacity>
class TelemetryUart {
 public:
  /// Clock, pins (USART2_TX and USART2_RX: `tx`, `rx`), `baud` from `pclk1_hz`.
  void init(const Chip& chip, std::uint32_t pclk1_hz, std::uint32_t baud, const PinConfig& tx, const PinConfig& rx) {
    chip.rcc->APB1ENR = chip.rcc->APB1ENR | RccRegs::kUsart2En;
    read_back(chip.rcc->APB1ENR);
    pin_configure(chip, tx);
    pin_configure(chip, rx);
    u_ = chip.usart2;
    u_->CR1 = 0;
    u_->BRR = usart_brr(pclk1_hz, baud);
    u_->CR1 = UsartRegs::kUe | UsartRegs::kTe | UsartRegs::kRe;
  }

  /// Takes n bytes to send (at most Capacity); false (and nothing taken) while the previous
  /// ones are still going out.
  bool offer(const std::uint8_t* p, int n) {
    if (busy()) {
      ++dropped_;
      return false;
    }
    for (int i = 0; i < n; ++i) buf_[i] = p[i];
    pos_ = 0;
    len_ = n;  // last: from here pump() may send
    return true;
  }
  /// Sends what fits into the transmitter now (at most `max` bytes); returns how many.
  int pump(int max = Capacity) {
    int sent = 0;
    while (sent < max && pos_ < len_ && (u_->SR & UsartRegs::kTxe) != 0) {
      u_->DR = buf_[pos_];
      pos_ = pos_ + 1;
      ++sent;
    }
    return sent;
  }
  /// Sends a text, waiting for the transmitter (boot messages, before the control interrupt runs).
  void write_blocking(const char* s) {
    for (; *s; ++s) {
      poll_until([&] { return (u_->SR & UsartRegs::kTxe) != 0; }, kBlockingPolls);
      u_->DR = static_cast<std::uint8_t>(*s);
    }
  }
  bool busy() const { return pos_ < len_; }
  std::uint32_t dropped() const { return dropped_; }

 private:
  static constexpr std::uint32_t kBlockingPolls = 100000;  // > 1 byte time at 460 800 baud and 168 MHz
  UsartRegs* u_ = nullptr;
  std::uint8_t buf_[Capacity] = {};
  volatile int pos_ = 0, len_ = 0;
  std::uint32_t dropped_ = 0;
};

}  // namespace stm32f4
