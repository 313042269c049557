// Analog inputs on ADC1 (RM0090 section 13): one scan of the regular group per control tick over a
// board's tables of inputs (AnalogInput: the pin, its channel, its sample time; the board's pins.hpp),
// the tables one after the other in one sequence, moved by DMA2 into a buffer in RAM. The STM32F4 board
// reads its amplifiers' current monitors and its joints' potentiometers with it (one scan of twelve).
//
// When: the tick's update() takes the scan the previous tick started and starts the next one (the
// software trigger, SWSTART); it never waits for a conversion. So the codes a tick gets were sampled
// during the tick before (at most one period old), each at its place in the sequence. 12-bit,
// right-aligned. The ADC clock is PCLK2 / 4 = 21 MHz (84 MHz APB2; at most 36 MHz, DS8626 "ADC
// characteristics"); a conversion takes its input's sample time and 12 cycles (RM0090 13.5): 68 cycles
// (3.2 us) at 56, 492 (23.4 us) at 480. The board's scan, six inputs at 56 cycles and six at 480, is
// 3360 cycles: 160 us, and 420 us at the HSI fallback (PCLK2 16 MHz / 2 = 8 MHz): within the 1 ms tick.
//
// The sample time must charge the ADC's sampling capacitor (C_ADC 4 pF behind R_ADC 6 kOhm) through the
// source to within half an LSB. DS8626's equation 1 bounds the source's impedance for k sampling
// cycles: R_AIN < (k - 0.5) / (f_ADC C_ADC ln(2^(N+2))) - R_ADC; at 21 MHz and N = 12, 15 cycles allow
// 11.8 kOhm, 56 cycles the data sheet's own limit of 50 kOhm, 480 far more. A source with a capacitor
// at the pin far larger than C_ADC (an anti-alias filter's) charges the sampling capacitor itself: the
// error is C_ADC / C of a step between two channels (4e-5 with 100 nF, a sixth of an LSB).
//
// Why the regular group and DMA: more than four channels, and the injected group's JDR1-4 hold four
// (two injected sequences a tick would need a second start: a wait or an interrupt). The regular group
// converts the whole sequence (scan mode, RM0090 13.3.8) into its one data register, and DMA2 stream 0,
// channel 0 (ADC1's request, RM0090 table 43) moves each result to the buffer before the next
// conversion ends (3 us later at the shortest sample time here); the tick checks that the stream
// completed. Normal mode (not circular) with DDS = 0: each start re-arms the stream for one scan, so a
// scan that went wrong leaves nothing behind for the next (RM0090 13.8.1, "Using the DMA").
//
// A bipolar signal level-shifted to mid-scale (a current monitor's) is read as its code less the
// mid-scale code, 2^(bits - 1) (read_centred): -2048 .. 2047 at 12 bits, 0 at mid-scale.
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

#include <array>
#include <cstdint>
#include <iterator>
#include <type_traits>

#include "gpio.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

/// One analog input: its pin (analog mode), ADC1's channel on it and its sample time [ADC clock
/// cycles: 3, 15, 28, 56, 84, 112, 144 or 480].
struct AnalogInput {
  PinConfig pin;
  std::uint8_t channel;
  std::uint16_t sample_cycles;
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

/// SMPx for a sample time in ADC clock cycles (RM0090 13.13.4, 13.13.5), -1 for one the ADC does not have.
constexpr int adc_sample_code(std::uint32_t cycles) {
  constexpr std::uint32_t kCycles[8] = {3, 15, 28, 56, 84, 112, 144, 480};
  for (int code = 0; code < 8; ++code)
    if (kCycles[code] == cycles) return code;
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

/// The scan of tables of inputs (`Tables`: constexpr arrays of AnalogInput) on ADC1, through DMA2
/// stream 0: one sequence, the tables one after the other, each in its own order (read<t>() gives
/// table t's codes in it).
template <const auto&... Tables>
class AdcScan {
  static_assert(sizeof...(Tables) >= 1, "at least one table");
  static_assert((std::is_same_v<std::remove_cvref_t<decltype(Tables[0])>, AnalogInput> && ...),
                "arrays of AnalogInput");

 public:
  static constexpr int kTables = static_cast<int>(sizeof...(Tables));
  /// Each table's length, and where it starts in the sequence.
  static constexpr int kSizes[kTables] = {static_cast<int>(std::size(Tables))...};
  static constexpr int first(int table) { return table == 0 ? 0 : first(table - 1) + kSizes[table - 1]; }
  static constexpr int kCount = first(kTables - 1) + kSizes[kTables - 1];
  static_assert(kCount <= 16, "a regular sequence converts 1 to 16 channels");
  /// Every input in the sequence's order.
  static constexpr std::array<AnalogInput, kCount> kInputs = [] {
    std::array<AnalogInput, kCount> all{};
    int i = 0;
    const auto append = [&](const auto& table) {
      for (const AnalogInput& in : table) all[i++] = in;
    };
    (append(Tables), ...);
    return all;
  }();

  /// The resolution (RES 0), and the code at mid-scale: a level-shifted bipolar signal's zero.
  static constexpr int kBits = 12;
  static constexpr std::uint32_t kCodeMask = (1u << kBits) - 1u;
  static constexpr std::int32_t kMidScale = 1 << (kBits - 1);
  /// Polls of the stream's EN bit after clearing it: it clears once the transfer in progress ends,
  /// a few bus cycles.
  static constexpr std::uint32_t kStreamPolls = 1000;

  /// One input's conversion [ADC clock cycles] at 12 bits: its sample time and 12 cycles (RM0090 13.5).
  static constexpr std::uint32_t conversion_cycles(const AnalogInput& in) { return in.sample_cycles + 12u; }
  /// The first `n` conversions of the sequence [ADC clock cycles] (all of them by default: the scan).
  static constexpr std::uint32_t sequence_cycles(int n = kCount) {
    std::uint32_t cycles = 0;
    for (int i = 0; i < n; ++i) cycles += conversion_cycles(kInputs[i]);
    return cycles;
  }
  /// The first `n` conversions' duration [ns] at an ADC clock [Hz] (the whole scan by default).
  static constexpr std::uint32_t scan_ns(std::uint32_t adc_hz, int n = kCount) {
    return static_cast<std::uint32_t>(std::uint64_t{sequence_cycles(n)} * 1000000000u / adc_hz);
  }

  /// SMPR1 (channels 10-18) and SMPR2 (0-9): each input's sample time, 3 cycles (SMP 0) for the others.
  static constexpr std::uint32_t smpr1() {
    std::uint32_t v = 0;
    for (const AnalogInput& in : kInputs)
      if (in.channel >= 10)
        v |= static_cast<std::uint32_t>(adc_sample_code(in.sample_cycles)) << (3u * (in.channel - 10u));
    return v;
  }
  static constexpr std::uint32_t smpr2() {
    std::uint32_t v = 0;
    for (const AnalogInput& in : kInputs)
      if (in.channel < 10) v |= static_cast<std::uint32_t>(adc_sample_code(in.sample_cycles)) << (3u * in.channel);
    return v;
  }
  /// SQRn (n = 1, 2, 3): the channels in the sequence's order (SQ1 first, in SQR3), the length in SQR1.
  static constexpr std::uint32_t sqr(int n) {
    std::uint32_t v = n == 1 ? AdcRegs::sqr1_length(kCount) : 0u;
    for (int i = 0; i < kCount; ++i)
      if (3 - i / 6 == n) v |= static_cast<std::uint32_t>(kInputs[i].channel) << (5 * (i % 6));
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

  static constexpr bool inputs_valid() {
    for (const AnalogInput& in : kInputs)
      if (adc1_channel_of(in.pin.pin) != in.channel || in.pin.mode != Mode::kAnalog ||
          adc_sample_code(in.sample_cycles) < 0)
        return false;
    return true;
  }
  static_assert(inputs_valid(),
                "each input an analog pin carrying its ADC1 channel (DS8626 table 7), sampled for a time the ADC has");

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
    for (const AnalogInput& in : kInputs) pin_configure(chip, in.pin);
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

  /// Table `T`'s codes (0 .. 4095) of the scan update() took this tick, in the table's order; false
  /// when it had none.
  template <int T>
  bool read(std::uint16_t codes[]) const {
    static_assert(T >= 0 && T < kTables, "a table of the scan");
    if (!valid_) return false;
    for (int i = 0; i < kSizes[T]; ++i) codes[i] = latest_[first(T) + i];
    return true;
  }
  /// The same, each code less the mid-scale code (-2048 .. 2047): the inputs of a bipolar signal
  /// level-shifted to mid-scale.
  template <int T>
  bool read_centred(std::int16_t codes[]) const {
    static_assert(T >= 0 && T < kTables, "a table of the scan");
    if (!valid_) return false;
    for (int i = 0; i < kSizes[T]; ++i) codes[i] = static_cast<std::int16_t>(latest_[first(T) + i] - kMidScale);
    return true;
  }

  std::uint32_t scans() const { return scans_; }            ///< complete scans taken
  std::uint32_t overruns() const { return overruns_; }      ///< scans lost to OVR or a stream error
  std::uint32_t incomplete() const { return incomplete_; }  ///< scans not complete at the next tick
  std::uint32_t stuck() const { return stuck_; }            ///< starts refused: the stream never stopped
  /// The DMA's destination, in the sequence's order (a host test plays the DMA into it).
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
