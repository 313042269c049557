// The board's serial link over USART2 (RM0090 30.3, 30.6): 8N1, 16x oversampling, both directions.
//
// Receive: the RXNE interrupt (on_rx_interrupt(), from the board's USART2 vector) moves each byte
// into a ring (ByteRing) the main loop empties (read()). The data register holds one byte: a byte
// time at 460 800 baud is 22 us, and the main loop may be busy for a millisecond or two (preparing a
// move: its path check), so polling would lose bytes. A byte lost anyway (the ring full, or the
// register overrun, ORE) is counted.
// Transmit: frames queue whole (FrameQueue: kSlots frames of at most Capacity bytes, no heap), from
// the control tick (telemetry, answers, state frames) and the main loop (answers it gives at once);
// the main loop sends them byte by byte whenever the transmit register is empty (pump()), so neither
// waits for the line. A frame offered to a full queue is dropped and counted (dropped()).
// Concurrency: one producer and one consumer per queue, each index written by one side only; the
// board keeps its two transmit producers (tick, main loop) apart by masking the control interrupt
// in the main loop's offer (board::App). Pins and baud rate: the board's (init()).
#pragma once

#include <atomic>
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

/// Orders the stores around an index update for the other side (an interrupt on the same core): a
/// compiler barrier; the core itself keeps program order.
inline void ring_fence() { std::atomic_signal_fence(std::memory_order_seq_cst); }

/// Bytes from an interrupt (push) to the main loop (pop); N a power of two. The indices run freely
/// (unsigned wrap), each written by its side only.
template <unsigned N>
class ByteRing {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "a power of two");

 public:
  /// Producer: false (nothing stored, counted) when full.
  bool push(std::uint8_t b) {
    const unsigned t = tail_;
    if (t - head_ == N) {
      lost_ = lost_ + 1;
      return false;
    }
    buf_[t % N] = b;
    ring_fence();
    tail_ = t + 1;
    return true;
  }
  /// Consumer: false when empty.
  bool pop(std::uint8_t& b) {
    const unsigned h = head_;
    if (h == tail_) return false;
    b = buf_[h % N];
    ring_fence();
    head_ = h + 1;
    return true;
  }
  bool empty() const { return head_ == tail_; }
  unsigned size() const { return tail_ - head_; }
  /// Bytes refused because the ring was full.
  std::uint32_t lost() const { return lost_; }

 private:
  std::uint8_t buf_[N] = {};
  volatile unsigned head_ = 0, tail_ = 0;
  volatile std::uint32_t lost_ = 0;
};

/// Whole frames of at most Capacity bytes, Slots of them, from a producer (push) to a consumer
/// (front, pop).
template <int Slots, int Capacity>
class FrameQueue {
  static_assert(Slots >= 1 && Capacity >= 1);

 public:
  /// Producer: the n bytes (1..Capacity) queued; false (dropped, counted) when full or too long.
  bool push(const std::uint8_t* p, int n) {
    const unsigned t = tail_;
    if (n < 1 || n > Capacity || t - head_ == static_cast<unsigned>(Slots)) {
      dropped_ = dropped_ + 1;
      return false;
    }
    Slot& s = slot_[t % Slots];
    for (int i = 0; i < n; ++i) s.bytes[i] = p[i];
    s.len = n;
    ring_fence();
    tail_ = t + 1;  // last: from here the consumer may send it
    return true;
  }
  /// Consumer: the oldest frame (nullptr when empty) and its length.
  const std::uint8_t* front(int& n) const {
    if (empty()) return nullptr;
    const Slot& s = slot_[head_ % Slots];
    n = s.len;
    return s.bytes;
  }
  /// Consumer: the oldest frame is sent; its slot is free again.
  void pop() {
    ring_fence();
    head_ = head_ + 1;
  }
  bool empty() const { return head_ == tail_; }
  int size() const { return static_cast<int>(tail_ - head_); }
  /// Frames refused (the queue full).
  std::uint32_t dropped() const { return dropped_; }

 private:
  struct Slot {
    std::uint8_t bytes[Capacity];
    int len;
  };
  Slot slot_[Slots] = {};
  volatile unsigned head_ = 0, tail_ = 0;
  volatile std::uint32_t dropped_ = 0;
};

/// USART2 receiving into a ring of RxBytes and sending frames of at most Capacity bytes, Slots of
/// them queued.
template <int Slots, int Capacity, unsigned RxBytes>
class UsartLink {
 public:
  /// Clock, pins (USART2_TX and USART2_RX: `tx`, `rx`), `baud` from `pclk1_hz`; the receive
  /// interrupt enabled in the USART (the board enables its NVIC line).
  void init(const Chip& chip, std::uint32_t pclk1_hz, std::uint32_t baud, const PinConfig& tx, const PinConfig& rx) {
    chip.rcc->APB1ENR = chip.rcc->APB1ENR | RccRegs::kUsart2En;
    read_back(chip.rcc->APB1ENR);
    pin_configure(chip, tx);
    pin_configure(chip, rx);
    u_ = chip.usart2;
    u_->CR1 = 0;
    u_->BRR = usart_brr(pclk1_hz, baud);
    u_->CR1 = UsartRegs::kUe | UsartRegs::kTe | UsartRegs::kRe | UsartRegs::kRxneie;
  }

  // ---- receive
  /// The USART's interrupt: the received byte into the ring. Reading SR then DR clears RXNE and an
  /// overrun (ORE: a byte lost in the USART, counted); an interrupt without RXNE reads nothing.
  void on_rx_interrupt() {
    const std::uint32_t sr = u_->SR;
    if (sr & UsartRegs::kOre) overruns_ = overruns_ + 1;
    if (sr & (UsartRegs::kRxne | UsartRegs::kOre)) rx_.push(static_cast<std::uint8_t>(u_->DR));
  }
  /// The next received byte (main loop); false when none waits.
  bool read(std::uint8_t& b) { return rx_.pop(b); }
  bool rx_empty() const { return rx_.empty(); }
  /// Bytes lost: the USART overran (the interrupt came too late), or the ring was full.
  std::uint32_t rx_overruns() const { return overruns_; }
  std::uint32_t rx_lost() const { return rx_.lost(); }

  // ---- transmit
  /// Queues a frame of n bytes (at most Capacity); false (dropped, counted) when the queue is full.
  /// Callers that may pre-empt each other must not both call it (the board masks).
  bool offer(const std::uint8_t* p, int n) { return tx_.push(p, n); }
  /// Sends what fits into the transmitter now (at most `max` bytes); returns how many (main loop).
  int pump(int max = Capacity) {
    int sent = 0, n = 0;
    for (const std::uint8_t* f; sent < max && (f = tx_.front(n)) != nullptr && (u_->SR & UsartRegs::kTxe) != 0;) {
      u_->DR = f[pos_];
      ++sent;
      if (++pos_ == n) {
        pos_ = 0;
        tx_.pop();
      }
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
  /// Frames still queued or going out.
  bool busy() const { return !tx_.empty(); }
  int queued() const { return tx_.size(); }
  std::uint32_t dropped() const { return tx_.dropped(); }

 private:
  static constexpr std::uint32_t kBlockingPolls = 100000;  // > 1 byte time at 460 800 baud and 168 MHz
  UsartRegs* u_ = nullptr;
  FrameQueue<Slots, Capacity> tx_;
  int pos_ = 0;  // the next byte of the front frame (main loop only)
  ByteRing<RxBytes> rx_;
  volatile std::uint32_t overruns_ = 0;
};

}  // namespace stm32f4
