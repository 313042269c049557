// Analog inputs on ADC1 (RM0090 section 13): one scan of the regular group over a board's table of
// inputs (AnalogInput: the pin and its channel; the board's pins.hpp) per control tick, moved by
// DMA2 into a buffer in RAM; the board reads its joints' potentiometers with it.
//
// When: the tick's update() takes the scan the previous tick started and starts the next one (the
// software trigger, SWSTART); it never waits for a conversion. So the codes a tick gets were sampled
// during the tick before (at most one period old). 12-bit, right-aligned; every channel sampled for
// 480 ADC clock cycles. The ADC clock is PCLK2 / 4 = 21 MHz (84 MHz APB2; at most 36 MHz, DS8626
// "ADC characteristics"), a conversion 480 + 12 = 492 cycles (23.4 us; RM0090 13.5), a scan of six
// 141 us: well within the 1 ms tick. At the HSI fallback (PCLK2 16 MHz / 2 = 8 MHz) it is 369 us.
//
// Why 480 cycles: the sample time must charge the ADC's sampling capacitor (C_ADC 4 pF behind
// R_ADC 6 kOhm) through the source to within half an LSB. DS8626's equation 1 bounds the source's
// impedance for k sampling cycles: R_AIN < (k - 0.5) / (f_ADC C_ADC ln(2^(N+2))) - R_ADC; at 21 MHz
// and N = 12, 15 cycles allow 11.8 kOhm, 56 cycles the data sheet's own limit of 50 kOhm, 480 far
// more. A potentiometer of R shows at most R / 4 at mid-travel (2.5 kOhm for 10 kOhm), plus the
// series resistor of any filter before the pin: the longest sample time takes any of them, and costs
// nothing here (the scan runs between ticks, the core does not wait for it).
//
// Why the regular group and DMA: six channels, and the injected group's JDR1-4 hold four (two
// injected sequences a tick would need a second start: a wait or an interrupt). The regular group
// converts all six in sequence (scan mode, RM0090 13.3.8) into its one data register, and DMA2 stream 0,
// channel 0 (ADC1's request, RM0090 table 43) moves each result to the buffer before the next
// conversion ends (23 us later); the tick checks that the stream completed. Normal mode (not
// circular) with DDS = 0: each start re-arms the stream for one scan, so a scan that went wrong leaves
// nothing behind for the next (RM0090 13.8.1, "Using the DMA").
//
// No sample (update() and read() false) when, at the tick:
//   - the ADC lost a result (OVR: a conversion ended before the DMA had taken the one before), or
//     the stream reports a transfer or direct-mode error: the buffer may be shifted;
//   - the scan has not completed (the stream's TCIF is not set);
//   - no scan ran: the first tick after init(), and the tick after a failed scan.
// A failed scan is stopped (ADON cleared: the conversion in progress ends, RM0090 13.3.1), the stream
// disabled (a bounded wait for its EN bit, the only wait here), and the ADC powered up again; the next
// tick starts a fresh scan, long after the ADC's stabilization time (t_STAB, 3 us, DS8626).
#pragma once

#include <cstdint>
#include <iterator>
#include <type_traits>

#include "gpio.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

/// One analog input: its pin (analog mode) and ADC1's channel on it.
struct AnalogInput {
  PinConfig pin;
  std::uint8_t channel;
};

/// ADC1's channel on a pin, -1 where it has none (DS8626 table 7: ADC123_IN0-3 on PA0-PA3,
/// ADC12_IN4-7 on PA4-PA7, ADC12_IN8-9 on PB0-PB1, ADC123_IN10-13 on PC0-PC3, ADC12_IN14-15 on
/// PC4-PC5; port F's inputs are ADC3's alone).
constexpr int adc1_channel_of(Pin p) {
  if (p.port == Port::A && p.n <= 7) return p.n;
  if (p.port == Port::B && p.n <= 1) return 8 + p.n;
  if (p.port == Port::C && p.n <= 5) return 10 + p.n;
  return -1;
}

/// The ADC clock's upper limit at VDDA 2.4-3.6 V (DS8626, "ADC characteristics").
constexpr std::uint32_t kAdcMaxHz = 36000000;
/// The smallest divider of PCLK2 (ADCPRE: 2, 4, 6 or 8) that keeps the ADC clock within kAdcMaxHz.
constexpr std::uint32_t adc_divider(std::uint32_t pclk2) {
  for (std::uint32_t d = 2; d < 8; d += 2)
    if (pclk2 <= kAdcMaxHz * d) return d;
  return 8;
}
static_assert(adc_divider(84000000) == 4 && adc_divider(16000000) == 2, "21 MHz on the PLL, 8 MHz on HSI");

/// The scan of a table of inputs (`Inputs`: a constexpr array of AnalogInput, in the order the codes
/// are read: the joints' order for the potentiometers) on ADC1, through DMA2 stream 0.
template <const auto& Inputs>
class AdcScan {
  static_assert(std::is_same_v<std::remove_cvref_t<decltype(Inputs[0])>, AnalogInput>, "an array of AnalogInput");

 public:
  static constexpr int kCount = static_cast<int>(std::size(Inputs));
  static_assert(kCount >= 1 && kCount <= 16, "a regular sequence converts 1 to 16 channels");
  static constexpr std::uint32_t kSampleCycles = 480;
  /// A conversion at 12 bits: the sample time and 12 cycles (RM0090 13.5).
  static constexpr std::uint32_t kConversionCycles = kSampleCycles + 12;
  static constexpr std::uint32_t kCodeMask = 0xFFFu;
  /// Polls of the stream's EN bit after clearing it: it clears once the transfer in progress ends,
  /// a few bus cycles.
  static constexpr std::uint32_t kStreamPolls = 1000;

  /// One scan's duration [ns] at an ADC clock [Hz].
  static constexpr std::uint32_t scan_ns(std::uint32_t adc_hz) {
    return static_cast<std::uint32_t>(static_cast<std::uint64_t>(kCount) * kConversionCycles * 1000000000u / adc_hz);
  }

  /// SMPR1 and SMPR2: 480 cycles (SMP 7) for every channel of the table, 3 (SMP 0) for the others.
  static constexpr std::uint32_t smpr1() {
    std::uint32_t v = 0;
    for (const AnalogInput& in : Inputs)
      if (in.channel >= 10) v |= AdcRegs::kSmp480 << (3u * (in.channel - 10u));
    return v;
  }
  static constexpr std::uint32_t smpr2() {
    std::uint32_t v = 0;
    for (const AnalogInput& in : Inputs)
      if (in.channel < 10) v |= AdcRegs::kSmp480 << (3u * in.channel);
    return v;
  }
  /// SQRn (n = 1, 2, 3): the channels in the table's order (SQ1 first, in SQR3), the length in SQR1.
  static constexpr std::uint32_t sqr(int n) {
    std::uint32_t v = n == 1 ? AdcRegs::sqr1_length(kCount) : 0u;
    for (int i = 0; i < kCount; ++i)
      if (3 - i / 6 == n) v |= static_cast<std::uint32_t>(Inputs[i].channel) << (5 * (i % 6));
    return v;
  }
  /// Scan mode, 12-bit (RES 0), no interrupt.
  static constexpr std::uint32_t kCr1 = AdcRegs::kScan;
  /// On, the DMA's requests; one scan per software start (CONT 0), EOC at the end of the sequence
  /// (EOCS 0: the overrun is detected anyway with DMA = 1), no new request after the stream's last
  /// transfer (DDS 0), right-aligned, no external trigger.
  static constexpr std::uint32_t kCr2 = AdcRegs::kAdon | AdcRegs::kDma;
  /// Channel 0, peripheral to memory (DIR 0), half-words on both sides, memory address incremented,
  /// normal mode (not circular), high priority; no interrupt.
  static constexpr std::uint32_t kStreamConfig =
      DmaStream::chsel(0) | DmaStream::kPlHigh | DmaStream::kMsizeHalf | DmaStream::kPsizeHalf | DmaStream::kMinc;
  static constexpr std::uint32_t kStreamErrors = DmaRegs::kTeif0 | DmaRegs::kDmeif0;

  static constexpr bool channels_match_pins() {
    for (const AnalogInput& in : Inputs)
      if (adc1_channel_of(in.pin.pin) != in.channel || in.pin.mode != Mode::kAnalog) return false;
    return true;
  }
  static_assert(channels_match_pins(), "each input an analog pin carrying its ADC1 channel (DS8626 table 7)");

  /// Clocks (ADC1, DMA2), pins, the ADC's sequence and the stream (GPIO port clocks already on). The
  /// ADC is left on and idle: the first update() starts the first scan.
  void init(const Chip& chip, std::uint32_t pclk2) {
    adc_ = chip.adc1;
    dma_ = chip.dma2;
    stream_ = &chip.dma2->S[0];
    RccRegs& rcc = *chip.rcc;
    rcc.APB2ENR = rcc.APB2ENR | RccRegs::kAdc1En;
    read_back(rcc.APB2ENR);
    rcc.AHB1ENR = rcc.AHB1ENR | RccRegs::kDma2En;
    read_back(rcc.AHB1ENR);
    for (const AnalogInput& in : Inputs) pin_configure(chip, in.pin);
    chip.adc_common->CCR = AdcCommonRegs::adcpre(adc_divider(pclk2));  // independent ADCs, no multi-ADC DMA
    adc_->CR2 = 0;
    adc_->CR1 = kCr1;
    adc_->SMPR1 = smpr1();
    adc_->SMPR2 = smpr2();
    adc_->SQR1 = sqr(1);
    adc_->SQR2 = sqr(2);
    adc_->SQR3 = sqr(3);
    stream_->CR = 0;
    stream_idle();
    stream_->CR = kStreamConfig;
    stream_->PAR = static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(&adc_->DR));
    // The buffer is this object's, in SRAM: the DMA reaches SRAM1/2, not the CCM (RM0090 2.3).
    stream_->M0AR = static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(&buffer_[0]));
    stream_->FCR = 0;  // direct mode
    dma_->LIFCR = DmaRegs::kStream0Flags;
    adc_->SR = 0;
    adc_->CR2 = AdcRegs::kAdon;  // powered up: t_STAB has passed by the first tick
    running_ = false;
    valid_ = false;
  }

  /// Once a tick: the scan the previous tick started (true: complete, no overrun: read() gives its
  /// codes this tick), then the next scan started.
  bool update() {
    valid_ = false;
    if (running_) {
      const std::uint32_t sr = adc_->SR;
      const std::uint32_t isr = dma_->LISR;
      if ((sr & AdcRegs::kOvr) != 0 || (isr & kStreamErrors) != 0) {
        ++overruns_;
        stop();
        return false;
      }
      if ((isr & DmaRegs::kTcif0) == 0) {
        ++incomplete_;
        stop();
        return false;
      }
      for (int i = 0; i < kCount; ++i) latest_[i] = static_cast<std::uint16_t>(buffer_[i] & kCodeMask);
      valid_ = true;
      ++scans_;
    }
    running_ = start();
    return valid_;
  }

  /// The codes of the scan update() took this tick, in the table's order; false when it had none.
  bool read(std::uint16_t codes[kCount]) const {
    if (!valid_) return false;
    for (int i = 0; i < kCount; ++i) codes[i] = latest_[i];
    return true;
  }

  std::uint32_t scans() const { return scans_; }            ///< complete scans taken
  std::uint32_t overruns() const { return overruns_; }      ///< scans lost to OVR or a stream error
  std::uint32_t incomplete() const { return incomplete_; }  ///< scans not complete at the next tick
  std::uint32_t stuck() const { return stuck_; }            ///< starts refused: the stream never stopped
  /// The DMA's destination (a host test plays the DMA into it).
  volatile std::uint16_t* dma_buffer() { return buffer_; }

 private:
  bool stream_idle() {
    return poll_until([&] { return (stream_->CR & DmaStream::kEn) == 0; }, kStreamPolls);
  }

  /// The stream re-armed for one scan, the ADC's flags cleared and its DMA requests re-enabled
  /// (with DDS 0 the DMA bit must go to 0 and back to 1, RM0090 13.8.1), the scan started.
  bool start() {
    stream_->CR = kStreamConfig;  // already disabled by the end of its transfer (normal mode)
    if (!stream_idle()) {
      ++stuck_;
      return false;
    }
    dma_->LIFCR = DmaRegs::kStream0Flags;
    stream_->NDTR = static_cast<std::uint32_t>(kCount);
    stream_->CR = kStreamConfig | DmaStream::kEn;
    adc_->SR = 0;  // OVR, EOC, STRT (every flag clears on a written 0; none other is used)
    adc_->CR2 = AdcRegs::kAdon;
    adc_->CR2 = kCr2;
    adc_->CR2 = kCr2 | AdcRegs::kSwstart;
    return true;
  }

  /// A failed scan stopped: the ADC off (ends the conversion in progress), the stream disabled, the
  /// ADC on again. The next update() starts afresh.
  void stop() {
    adc_->CR2 = 0;
    stream_->CR = kStreamConfig;
    stream_idle();
    adc_->CR2 = AdcRegs::kAdon;
    running_ = false;
  }

  AdcRegs* adc_ = nullptr;
  DmaRegs* dma_ = nullptr;
  DmaStream* stream_ = nullptr;
  volatile std::uint16_t buffer_[kCount] = {};
  std::uint16_t latest_[kCount] = {};
  bool running_ = false;
  bool valid_ = false;
  std::uint32_t scans_ = 0, overruns_ = 0, incomplete_ = 0, stuck_ = 0;
};

}  // namespace stm32f4
