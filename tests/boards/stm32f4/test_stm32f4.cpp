// The STM32F4 board's drivers on the host (the chip's, boards/common/stm32f4; the AD5754R's,
// boards/common/devices/ad5754r; the board's, boards/stm32f4), each pointed at fake register blocks in
// RAM (a Chip of zeroed structs the test presets and reads back): the bounded clock set-up and its
// fallbacks, the encoder unwrap across the 16- and 32-bit counter wraps, the AD5754R frames and the
// one LDAC per burst, the SPI bus and its bounded waits, the zero-on-fault path, the E-stop latch,
// the amplifier enable, the watchdog fed only by healthy ticks, the control timer, the USART link
// (receive ring, frame queue) and the command link's silence (a category-2 stop, link_silent); the
// potentiometers' ADC scan over DMA (its set-up, a tick's read, the no-sample cases), the index
// captures converted to accumulated counts, the pin map. The control task runs for real
// (ControlTask<double>) over the board's HAL binding.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <vector>

#include "ad5754r.hpp"
#include "adc.hpp"
#include "analog_inputs.hpp"
#include "board_hal.hpp"
#include "clock.hpp"
#include "control_timer.hpp"
#include "dac_bus.hpp"
#include "encoders.hpp"
#include "flash.hpp"
#include "param_store.hpp"
#include "osc/link/command_port.hpp"
#include "osc/link/telemetry.hpp"
#include "osc/robot.hpp"
#include "pins.hpp"
#include "record_store.hpp"
#include "safety.hpp"
#include "spi_bus.hpp"
#include "usart.hpp"
#include "test_util.hpp"

using namespace stm32f4;

namespace {

/// The board's encoders: a timer per joint, as its pin map says.
using Encoders = EncoderBank<pins::kEncoders>;
/// The board's analog inputs: ADC1's scan of the pin map's current monitors and potentiometers.
using Analog = AnalogInputs;

/// Every register block of the board, in RAM, zeroed.
struct FakeChip {
  RccRegs rcc{};
  FlashRegs flash{};
  GpioRegs gpio[kPorts]{};
  TimRegs tim[kTimers]{};
  SpiRegs spi2{};
  UsartRegs usart2{};
  IwdgRegs iwdg{};
  ExtiRegs exti{};
  SyscfgRegs syscfg{};
  DbgmcuRegs dbgmcu{};
  AdcRegs adc1{};
  AdcCommonRegs adc_common{};
  DmaRegs dma2{};
  Chip chip() {
    Chip c{};
    c.rcc = &rcc;
    c.flash = &flash;
    for (int i = 0; i < kPorts; ++i) c.gpio[i] = &gpio[i];
    for (int i = 0; i < kTimers; ++i) c.tim[i] = &tim[i];
    c.spi2 = &spi2;
    c.usart2 = &usart2;
    c.iwdg = &iwdg;
    c.exti = &exti;
    c.syscfg = &syscfg;
    c.dbgmcu = &dbgmcu;
    c.adc1 = &adc1;
    c.adc_common = &adc_common;
    c.dma2 = &dma2;
    return c;
  }
  GpioRegs& port(Port p) { return gpio[static_cast<int>(p)]; }
  TimRegs& timer(Timer t) { return tim[static_cast<int>(t)]; }
};

/// The last BSRR write to a pin's port drove that pin high (true) or low (false); fails if it did
/// not touch the pin at all.
::testing::AssertionResult drove(FakeChip& f, const PinConfig& p, bool high) {
  const std::uint32_t bsrr = f.port(p.pin.port).BSRR;
  const std::uint32_t bit = high ? 1u << p.pin.n : 1u << (p.pin.n + 16);
  if (bsrr == bit) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "BSRR of the pin's port is 0x" << std::hex << bsrr << ", expected 0x" << bit;
}

// ------------------------------------------------------------------------------------------ clock

TEST(Stm32Clock, FallsBackToHsiWhenTheCrystalNeverStarts) {
  FakeChip f;  // the RCC reads zero, as under QEMU: HSERDY never comes
  const Clocks c = clock_init(f.rcc, f.flash);
  EXPECT_EQ(c.fault, BootFault::kHseTimeout);
  EXPECT_STREQ(boot_fault_name(c.fault), "hse_timeout");
  EXPECT_EQ(c.sysclk, 16000000u);
  EXPECT_EQ(c.tim_apb1, 16000000u);
  EXPECT_FALSE(c.on_pll());
  EXPECT_EQ(f.rcc.CR & (RccRegs::kHseOn | RccRegs::kPllOn), 0u) << "HSE and PLL switched off again";
  EXPECT_EQ(f.rcc.CFGR & RccRegs::kSwMask, RccRegs::kSwHsi);
  EXPECT_EQ(f.rcc.PLLCFGR, 0u) << "the PLL was not touched";
}

TEST(Stm32Clock, FallsBackWhenThePllNeverLocks) {
  FakeChip f;
  f.rcc.CR = RccRegs::kHseRdy;  // the crystal runs, PLLRDY never comes
  const Clocks c = clock_init(f.rcc, f.flash);
  EXPECT_EQ(c.fault, BootFault::kPllTimeout);
  EXPECT_EQ(c.sysclk, 16000000u);
  // M = 8, N = 336, P = 2 (field 0), source HSE, Q = 7 (RM0090 7.3.2).
  EXPECT_EQ(f.rcc.PLLCFGR, 8u | (336u << 6) | (0u << 16) | (1u << 22) | (7u << 24));
  EXPECT_EQ(f.rcc.CR & (RccRegs::kHseOn | RccRegs::kPllOn), 0u);
  EXPECT_EQ(f.flash.ACR, 0u) << "no wait states set before the PLL locked";
}

TEST(Stm32Clock, FallsBackWhenTheSwitchToThePllNeverHappens) {
  FakeChip f;
  f.rcc.CR = RccRegs::kHseRdy | RccRegs::kPllRdy;  // SWS stays at HSI
  const Clocks c = clock_init(f.rcc, f.flash, ClockPolls{100, 100, 4, 50});
  EXPECT_EQ(c.fault, BootFault::kSwitchTimeout);
  EXPECT_EQ(c.pclk1, 16000000u);
  EXPECT_EQ(f.rcc.CFGR & (RccRegs::kSwMask | RccRegs::kHpreMask | RccRegs::kPpre1Mask | RccRegs::kPpre2Mask), 0u)
      << "back to HSI with every bus at /1";
  EXPECT_EQ(f.rcc.CR & (RccRegs::kHseOn | RccRegs::kPllOn), 0u);
}

TEST(Stm32Clock, ReachesThePllAt168MHzWithFiveWaitStates) {
  FakeChip f;
  f.rcc.CR = RccRegs::kHseRdy | RccRegs::kPllRdy;
  f.rcc.CFGR = RccRegs::kSwsPll;  // the switch status the hardware would show
  const Clocks c = clock_init(f.rcc, f.flash);
  EXPECT_EQ(c.fault, BootFault::kNone);
  EXPECT_TRUE(c.on_pll());
  EXPECT_EQ(c.sysclk, 168000000u);
  EXPECT_EQ(c.pclk1, 42000000u);
  EXPECT_EQ(c.tim_apb1, 84000000u);
  EXPECT_EQ(c.tim_apb2, 168000000u);
  EXPECT_EQ(f.flash.ACR, 5u | FlashRegs::kPrften | FlashRegs::kIcen | FlashRegs::kDcen);
  EXPECT_EQ(f.rcc.CFGR & RccRegs::kSwMask, RccRegs::kSwPll);
  EXPECT_EQ(f.rcc.CFGR & RccRegs::kPpre1Mask, RccRegs::kPpre1Div4);
  EXPECT_EQ(f.rcc.CFGR & RccRegs::kPpre2Mask, RccRegs::kPpre2Div2);
  EXPECT_NE(f.rcc.CR & (RccRegs::kHseOn | RccRegs::kPllOn), 0u);
}

TEST(Stm32Clock, EveryBootFaultHasAName) {
  for (BootFault b : {BootFault::kHseTimeout, BootFault::kPllTimeout, BootFault::kFlashLatency,
                      BootFault::kSwitchTimeout, BootFault::kWatchdogSetup, BootFault::kDacSetup})
    EXPECT_STRNE(boot_fault_name(b), "?");
}

// --------------------------------------------------------------------------------------- encoders

TEST(Stm32Encoders, InitPutsEveryTimerInEncoderModeWithItsPins) {
  FakeChip f;
  Encoders enc;
  enc.init(f.chip());
  for (const EncoderChannel& e : pins::kEncoders) {
    const TimRegs& t = f.timer(e.timer);
    EXPECT_EQ(t.SMCR, 3u) << "encoder mode 3 (x4)";
    EXPECT_EQ(t.CCMR1 & 0x0303u, 0x0101u) << "CC1S = TI1, CC2S = TI2";
    EXPECT_EQ(t.ARR, e.bits == 32 ? 0xFFFFFFFFu : 0xFFFFu);
    EXPECT_EQ(t.CR1 & TimRegs::kCen, TimRegs::kCen);
    EXPECT_NE(f.rcc.*e.enable_register & e.enable_bit, 0u);
    for (const PinConfig& p : {e.a, e.b}) {
      const GpioRegs& g = f.port(p.pin.port);
      EXPECT_EQ((g.MODER >> (2 * p.pin.n)) & 3u, 2u) << "alternate function";
      EXPECT_EQ((g.AFR[p.pin.n / 8] >> (4 * (p.pin.n % 8))) & 0xFu, p.af);
    }
  }
  // The table's widths are the hardware's: TIM2 and TIM5 are the 32-bit timers.
  for (const EncoderChannel& e : pins::kEncoders)
    EXPECT_EQ(e.bits, e.timer == Timer::kTim2 || e.timer == Timer::kTim5 ? 32 : 16);
}

TEST(Stm32Encoders, SixteenBitCountersUnwrapAcrossBothWraps) {
  FakeChip f;
  Encoders enc;
  enc.init(f.chip());
  TimRegs& t = f.timer(Timer::kTim1);  // joint 1, 16-bit
  std::int32_t c[hal::kJoints];
  // Steps of up to 30000 counts between ticks (below the 32768 limit), through 0 and 65535 both ways.
  const std::vector<std::pair<std::uint32_t, std::int32_t>> steps = {
      {65530u, -6},                       // backwards through 0
      {30000u, 30000},                    // forwards through 0 again (+30006)
      {60000u, 60000},                    // forwards
      {24464u, 90000},                    // forwards through 65535 (+30000)
      {60000u, 60000},                    // backwards through 65535 (-30000)
      {35536u, 35536},                    // backwards
      {5536u, 5536},   {45536u, -20000},  // backwards through 0 (-25536)
  };
  for (const auto& [raw, want] : steps) {
    t.CNT = raw;
    enc.read(c);
    EXPECT_EQ(c[0], want) << "raw " << raw;
  }
}

TEST(Stm32Encoders, ThirtyTwoBitCountersUnwrapAcrossBothWraps) {
  FakeChip f;
  Encoders enc;
  enc.init(f.chip());
  EXPECT_EQ(f.timer(Timer::kTim2).CNT, 0u) << "init zeroes the counters";
  f.timer(Timer::kTim2).CNT = 0xFFFFFF00u;  // counts from here on (restart) near the 32-bit wrap
  f.timer(Timer::kTim5).CNT = 0x7FFFFFF0u;  // and near the signed boundary
  enc.restart();
  std::int32_t c[hal::kJoints];
  enc.read(c);
  EXPECT_EQ(c[1], 0);
  EXPECT_EQ(c[4], 0);
  f.timer(Timer::kTim2).CNT = 0x00000100u;  // forwards through 0xFFFFFFFF: +512
  f.timer(Timer::kTim5).CNT = 0x80000010u;  // forwards through the signed boundary: +32
  enc.read(c);
  EXPECT_EQ(c[1], 512);
  EXPECT_EQ(c[4], 32);
  f.timer(Timer::kTim2).CNT = 0xFFFFFFFEu;  // backwards through 0: -258
  f.timer(Timer::kTim5).CNT = 0x7FFFFFFFu;  // backwards: -17
  enc.read(c);
  EXPECT_EQ(c[1], 512 - 258);
  EXPECT_EQ(c[4], 32 - 17);
}

TEST(Stm32Encoders, EveryJointReadsItsOwnTimer) {
  FakeChip f;
  Encoders enc;
  enc.init(f.chip());
  for (int j = 0; j < hal::kJoints; ++j)
    f.timer(pins::kEncoders[j].timer).CNT = static_cast<std::uint32_t>(10 * (j + 1));
  std::int32_t c[hal::kJoints];
  enc.read(c);
  for (int j = 0; j < hal::kJoints; ++j) EXPECT_EQ(c[j], 10 * (j + 1));
}

// ----------------------------------------------------------------------------------- index pulses

/// A timer block with TimRegs' member names (take_capture's Regs) whose SR and CCRx behave as the
/// hardware's: a 0 written to a flag of SR clears it, a 1 leaves it (rc_w0); reading CCRx clears
/// CCxIF; edge(x, v) latches the counter value v as an edge on channel x does (CCxOF too when CCxIF
/// is still set).
struct CapturingTimer {
  struct Status {
    std::uint32_t value = 0;
    int writes = 0;
    Status& operator=(std::uint32_t v) {
      value &= v;
      ++writes;
      return *this;
    }
    operator std::uint32_t() const { return value; }
  };
  struct Capture {
    CapturingTimer* owner;
    int x;
    std::uint32_t value = 0;
    operator std::uint32_t() const {
      owner->SR.value &= ~TimRegs::ccif(x);
      return value;
    }
  };
  Status SR;
  Capture CCR[4] = {{this, 1}, {this, 2}, {this, 3}, {this, 4}};
  CapturingTimer() = default;
  CapturingTimer(const CapturingTimer&) = delete;
  CapturingTimer& operator=(const CapturingTimer&) = delete;
  void edge(int x, std::uint32_t v) {
    if (SR.value & TimRegs::ccif(x)) SR.value |= TimRegs::ccof(x);
    SR.value |= TimRegs::ccif(x);
    CCR[x - 1].value = v;
  }
};

TEST(Stm32Index, ACaptureIsTakenOnceAndAnOvercaptureGivesTheLatest) {
  CapturingTimer t;
  std::uint32_t v = 0;
  bool over = true;
  EXPECT_FALSE(take_capture(t, 3, v, over)) << "no edge yet";
  t.edge(3, 1234);
  ASSERT_TRUE(take_capture(t, 3, v, over));
  EXPECT_EQ(v, 1234u);
  EXPECT_FALSE(over);
  EXPECT_EQ(t.SR.writes, 0) << "CC3IF cleared by reading CCR3: no write that could clear a newer edge's flag";
  EXPECT_FALSE(take_capture(t, 3, v, over)) << "once";
  t.edge(3, 100);
  t.edge(3, 200);  // a second edge before the first was taken: CC3OF
  t.edge(4, 77);   // and one on channel 4
  ASSERT_TRUE(take_capture(t, 3, v, over));
  EXPECT_EQ(v, 200u) << "the latest";
  EXPECT_TRUE(over);
  EXPECT_EQ(t.SR.value & (TimRegs::ccif(3) | TimRegs::ccof(3)), 0u) << "CC3IF and CC3OF cleared";
  EXPECT_EQ(t.SR.value, TimRegs::ccif(4)) << "channel 4's flag untouched";
  EXPECT_FALSE(take_capture(t, 3, v, over));
  ASSERT_TRUE(take_capture(t, 4, v, over));
  EXPECT_EQ(v, 77u);
  EXPECT_FALSE(over);
  EXPECT_EQ(t.SR.value, 0u);
}

/// An index edge on joint j's timer as the hardware latches it: the counter value in CCRx, CCxIF set.
void index_edge(FakeChip& f, int j, std::uint32_t counter) {
  const EncoderChannel& e = pins::kEncoders[j];
  TimRegs& t = f.timer(e.timer);
  t.CCR[e.index_channel - 1] = counter;
  t.SR = t.SR | TimRegs::ccif(e.index_channel);
}
/// What the driver's read of CCRx did on the chip, which RAM does not: CCxIF cleared.
void ccr_read(FakeChip& f, int j) {
  const EncoderChannel& e = pins::kEncoders[j];
  TimRegs& t = f.timer(e.timer);
  t.SR = t.SR & ~TimRegs::ccif(e.index_channel);
}

TEST(Stm32Index, InitCapturesEachIndexOnItsRisingEdgeOnItsPin) {
  FakeChip f;
  Encoders enc;
  enc.init(f.chip());
  for (const EncoderChannel& e : pins::kEncoders) {
    const TimRegs& t = f.timer(e.timer);
    if (e.index_channel == 3) {
      EXPECT_EQ(t.CCMR2, 0x01u | (3u << 4)) << "CC3S = TI3, IC3F = 3";
      EXPECT_EQ(t.CCER & 0xFF00u, 1u << 8) << "CC3E; CC3P = CC3NP = 0: the rising edge";
    } else {
      EXPECT_EQ(t.CCMR2, (0x01u | (3u << 4)) << 8) << "CC4S = TI4, IC4F = 3";
      EXPECT_EQ(t.CCER & 0xFF00u, 1u << 12) << "CC4E; CC4P = CC4NP = 0: the rising edge";
    }
    EXPECT_EQ(t.CCER & 0xFFu, 0u) << "A and B as before (no invert)";
    EXPECT_EQ(t.DIER, 0u) << "no interrupt: the tick takes the captures";
    const GpioRegs& g = f.port(e.index.pin.port);
    EXPECT_EQ((g.MODER >> (2 * e.index.pin.n)) & 3u, 2u) << "alternate function";
    EXPECT_EQ((g.AFR[e.index.pin.n / 8] >> (4 * (e.index.pin.n % 8))) & 0xFu, e.index.af);
  }
}

TEST(Stm32Index, AnIndexIsTheAccumulatedCountAtItsEdgeOnceAcrossSixteenBitWraps) {
  FakeChip f;
  Encoders enc;
  enc.init(f.chip());
  TimRegs& t = f.timer(Timer::kTim1);  // joint 1, 16-bit, index on CH3
  std::int32_t c[hal::kJoints], n = 0;
  for (std::uint32_t raw : {30000u, 60000u}) {
    t.CNT = raw;
    enc.read(c);
  }
  ASSERT_EQ(c[0], 60000);
  EXPECT_FALSE(enc.take_index(0, n)) << "no edge yet";
  index_edge(f, 0, 65530);  // the edge at count 65530, then the counter wraps
  t.CNT = 24464;            // 90000
  enc.read(c);
  ccr_read(f, 0);
  ASSERT_EQ(c[0], 90000);
  ASSERT_TRUE(enc.take_index(0, n));
  EXPECT_EQ(n, 65530) << "captured before the wrap, read after it";
  EXPECT_FALSE(enc.take_index(0, n)) << "once";
  enc.read(c);
  EXPECT_FALSE(enc.take_index(0, n)) << "no new edge";
  // Backwards through the wrap: the edge at 65539 (counter 3), read at 65000 (counter 65000).
  index_edge(f, 0, 3);
  t.CNT = 65000;
  enc.read(c);
  ccr_read(f, 0);
  ASSERT_EQ(c[0], 65000);
  ASSERT_TRUE(enc.take_index(0, n));
  EXPECT_EQ(n, 65539) << "captured after the wrap, read before it";
  // Below zero: joint 4 (16-bit) from 0 back to -536, its edge at -6.
  TimRegs& t4 = f.timer(Timer::kTim4);
  index_edge(f, 3, 65530);
  t4.CNT = 65000;
  enc.read(c);
  ccr_read(f, 3);
  ASSERT_EQ(c[3], -536);
  ASSERT_TRUE(enc.take_index(3, n));
  EXPECT_EQ(n, -6);
}

TEST(Stm32Index, EveryChannelLatchesItsOwnIndexAndThirtyTwoBitCountersToo) {
  FakeChip f;
  Encoders enc;
  enc.init(f.chip());
  f.timer(Timer::kTim2).CNT = 0xFFFFFF00u;  // joint 2 (32-bit, index on CH4) near the 32-bit wrap
  enc.restart();
  std::int32_t c[hal::kJoints], n = 0;
  index_edge(f, 1, 0xFFFFFFF0u);      // +240, before the wrap
  index_edge(f, 4, 0x00001000u);      // joint 5 (32-bit, CH4): +4096
  index_edge(f, 5, 0xFFF0u);          // joint 6 (16-bit, CH4): -16
  f.timer(Timer::kTim2).CNT = 0x100;  // +512, after the wrap
  enc.read(c);
  for (int j : {1, 4, 5}) ccr_read(f, j);
  ASSERT_EQ(c[1], 512);
  for (int j : {0, 2, 3}) EXPECT_FALSE(enc.take_index(j, n)) << "joint " << j + 1 << ": no edge";
  ASSERT_TRUE(enc.take_index(1, n));
  EXPECT_EQ(n, 240);
  EXPECT_FALSE(enc.take_index(1, n));
  ASSERT_TRUE(enc.take_index(5, n)) << "joint 2's take left joint 6's";
  EXPECT_EQ(n, -16);
  ASSERT_TRUE(enc.take_index(4, n));
  EXPECT_EQ(n, 4096);
  EXPECT_FALSE(enc.take_index(-1, n));
  EXPECT_FALSE(enc.take_index(hal::kJoints, n));
  // A capture on a channel that is not the joint's index (CH3 of TIM2) is not an index.
  f.timer(Timer::kTim2).SR = TimRegs::ccif(3);
  enc.read(c);
  EXPECT_FALSE(enc.take_index(1, n));
  // Two edges before the tick (CC4OF): the latest, counted; a restart drops an untaken index.
  f.timer(Timer::kTim2).SR = 0;
  index_edge(f, 1, 0x200);
  f.timer(Timer::kTim2).SR = f.timer(Timer::kTim2).SR | TimRegs::ccof(4);
  enc.read(c);
  EXPECT_EQ(f.timer(Timer::kTim2).SR & TimRegs::ccof(4), 0u) << "CC4OF cleared (written 0)";
  f.timer(Timer::kTim2).SR = 0;  // RAM took the 1s of that write as set flags
  EXPECT_EQ(enc.overcaptures(1), 1u);
  ASSERT_TRUE(enc.take_index(1, n));
  EXPECT_EQ(n, 512 + 256);
  index_edge(f, 1, 0x300);
  enc.read(c);
  ccr_read(f, 1);
  enc.restart();
  EXPECT_FALSE(enc.take_index(1, n)) << "relative to the counts before the restart: dropped";
}

// ------------------------------------------------------------------- analog inputs: pots, currents

/// The currents at 0 A: each code at mid-scale.
constexpr std::uint16_t kZeroCurrents[hal::kJoints] = {2048, 2048, 2048, 2048, 2048, 2048};

/// The end of a scan as the DMA and the ADC leave it: the twelve codes in the buffer in the sequence's
/// order (the six currents, then the six potentiometers), the stream disabled with its transfers done
/// (TCIF0, and HTIF0 half-way), the ADC's end of sequence.
void scan_done(FakeChip& f, Analog& analog, const std::uint16_t (&pots)[hal::kJoints],
               const std::uint16_t (&currents)[hal::kJoints] = kZeroCurrents) {
  for (int i = 0; i < hal::kJoints; ++i) {
    analog.dma_buffer()[i] = currents[i];
    analog.dma_buffer()[hal::kJoints + i] = pots[i];
  }
  f.dma2.S[0].CR = f.dma2.S[0].CR & ~DmaStream::kEn;
  f.dma2.S[0].NDTR = 0;
  f.dma2.LISR = DmaRegs::kTcif0 | DmaRegs::kHtif0;
  f.adc1.SR = AdcRegs::kEoc | AdcRegs::kStrt;
}
/// A scan was started since `forget` cleared the marks: the stream re-armed for twelve half-words
/// with its flags cleared, the ADC's flags cleared, its DMA requests on and the software start set.
::testing::AssertionResult started(FakeChip& f) {
  const DmaStream& s = f.dma2.S[0];
  if (f.dma2.LIFCR != 0x3Du) return ::testing::AssertionFailure() << "LIFCR 0x" << std::hex << f.dma2.LIFCR;
  if (s.NDTR != 12u) return ::testing::AssertionFailure() << "NDTR " << s.NDTR;
  if ((s.CR & DmaStream::kEn) == 0) return ::testing::AssertionFailure() << "stream not enabled";
  if (f.adc1.SR != 0u) return ::testing::AssertionFailure() << "ADC flags not cleared";
  if (f.adc1.CR2 != ((1u << 30) | (1u << 8) | 1u))
    return ::testing::AssertionFailure() << "CR2 0x" << std::hex << f.adc1.CR2 << ", not ADON | DMA | SWSTART";
  return ::testing::AssertionSuccess();
}
/// What the start's write of LIFCR did on the chip, which RAM does not: those flags of LISR cleared.
void lifcr_cleared(FakeChip& f) { f.dma2.LISR = f.dma2.LISR & ~f.dma2.LIFCR; }
void forget(FakeChip& f) {
  f.dma2.LIFCR = 0;
  f.dma2.S[0].NDTR = 0;
  f.adc1.CR2 = AdcRegs::kAdon;
}

TEST(Stm32Pots, InitSetsUpOneScanOfTheCurrentsThenThePotsThroughDma) {
  FakeChip f;
  Analog analog;
  analog.init(f.chip(), 84000000);
  EXPECT_NE(f.rcc.APB2ENR & (1u << 8), 0u) << "ADC1EN";
  EXPECT_NE(f.rcc.AHB1ENR & (1u << 22), 0u) << "DMA2EN";
  EXPECT_EQ(f.adc_common.CCR, 1u << 16) << "ADCPRE /4: 21 MHz from 84 MHz; independent ADCs";
  EXPECT_EQ(f.adc1.CR1, 1u << 8) << "SCAN; RES 0: 12-bit; no interrupt";
  EXPECT_EQ(f.adc1.CR2, 1u) << "on and idle (no CONT, no external trigger): the first tick starts it";
  // 480 cycles (SMP 7) on the potentiometers' channels 11, 12, 14, 15 (SMPR1) and 8, 9 (SMPR2); 56
  // (SMP 3) on the current monitors' 10, 13 (SMPR1) and 4-7 (SMPR2); 3 (SMP 0) on the others.
  EXPECT_EQ(f.adc1.SMPR1, (3u << 0) | (7u << 3) | (7u << 6) | (3u << 9) | (7u << 12) | (7u << 15));
  EXPECT_EQ(f.adc1.SMPR2, (3u << 12) | (3u << 15) | (3u << 18) | (3u << 21) | (7u << 24) | (7u << 27));
  // Twelve conversions (L = 11): SQ1..SQ6 the amplifiers' channels in channel order, SQ7..SQ12 the
  // potentiometers' in joint order, nothing in SQ13..SQ16.
  EXPECT_EQ(f.adc1.SQR1, 11u << 20);
  EXPECT_EQ(f.adc1.SQR3, 4u | (5u << 5) | (6u << 10) | (7u << 15) | (10u << 20) | (13u << 25));
  EXPECT_EQ(f.adc1.SQR2, 11u | (12u << 5) | (14u << 10) | (15u << 15) | (8u << 20) | (9u << 25));
  for (int j = 0; j < hal::kJoints; ++j) {
    EXPECT_EQ((f.adc1.SQR3 >> (5 * j)) & 0x1Fu, pins::kCurrentMonitors[j].channel) << "amplifier " << j + 1;
    EXPECT_EQ((f.adc1.SQR2 >> (5 * j)) & 0x1Fu, pins::kPots[j].channel) << "joint " << j + 1;
  }
  const DmaStream& s = f.dma2.S[0];
  EXPECT_EQ(s.CR, (2u << 16) | (1u << 13) | (1u << 11) | (1u << 10))
      << "channel 0, peripheral to memory, half-words, memory increment, normal mode, high priority; off";
  EXPECT_EQ(s.PAR, static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(&f.adc1.DR)));
  EXPECT_EQ(s.M0AR, static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(analog.dma_buffer())));
  EXPECT_EQ(s.FCR, 0u) << "direct mode";
  for (const auto* table : {&pins::kPots, &pins::kCurrentMonitors})
    for (const AnalogInput& in : *table) {
      const GpioRegs& g = f.port(in.pin.pin.port);
      EXPECT_EQ((g.MODER >> (2 * in.pin.pin.n)) & 3u, 3u) << "analog";
      EXPECT_EQ((g.PUPDR >> (2 * in.pin.pin.n)) & 3u, 0u) << "no pull resistor";
    }
  Analog slow;
  FakeChip g;
  slow.init(g.chip(), 16000000);
  EXPECT_EQ(g.adc_common.CCR, 0u) << "HSI fallback: /2, 8 MHz";
}

TEST(Stm32Pots, EachTickTakesTheScanThePreviousTickStartedAndStartsTheNext) {
  FakeChip f;
  Analog analog;
  analog.init(f.chip(), 84000000);
  std::uint16_t codes[hal::kJoints] = {};
  EXPECT_FALSE(analog.update()) << "the first tick: no scan ran yet";
  EXPECT_FALSE(analog.read(codes));
  EXPECT_TRUE(started(f));
  const std::uint16_t first[hal::kJoints] = {100, 4095, 2048, 0, 1, 3000};
  scan_done(f, analog, first);
  forget(f);
  ASSERT_TRUE(analog.update());
  EXPECT_TRUE(started(f)) << "the next scan, right after the read";
  ASSERT_TRUE(analog.read(codes));
  for (int j = 0; j < hal::kJoints; ++j) EXPECT_EQ(codes[j], first[j]) << "joint " << j + 1;
  EXPECT_TRUE(analog.read(codes)) << "the same tick's codes, again";
  const std::uint16_t second[hal::kJoints] = {7, 6, 5, 4, 3, 2};
  scan_done(f, analog, second);
  forget(f);
  ASSERT_TRUE(analog.update());
  ASSERT_TRUE(analog.read(codes));
  for (int j = 0; j < hal::kJoints; ++j) EXPECT_EQ(codes[j], second[j]) << "joint " << j + 1;
  EXPECT_EQ(analog.scans(), 2u);
}

TEST(Stm32Pots, AnOverrunAnIncompleteScanOrAStreamErrorIsNoSample) {
  FakeChip f;
  Analog analog;
  analog.init(f.chip(), 84000000);
  std::uint16_t codes[hal::kJoints] = {};
  std::int16_t currents[hal::kJoints] = {};
  const std::uint16_t c[hal::kJoints] = {1, 2, 3, 4, 5, 6};
  analog.update();
  // A result lost (OVR): the buffer may be shifted.
  scan_done(f, analog, c);
  f.adc1.SR = f.adc1.SR | AdcRegs::kOvr;
  forget(f);
  EXPECT_FALSE(analog.update());
  EXPECT_FALSE(analog.read(codes));
  EXPECT_FALSE(analog.read_currents(currents)) << "the currents of that scan neither";
  EXPECT_EQ(analog.overruns(), 1u);
  EXPECT_EQ(f.adc1.CR2, 1u) << "stopped, on again, no scan started this tick";
  EXPECT_EQ(f.dma2.S[0].CR & DmaStream::kEn, 0u) << "the stream disabled";
  EXPECT_FALSE(analog.update()) << "the tick after: nothing ran";
  EXPECT_TRUE(started(f)) << "a fresh scan";
  scan_done(f, analog, c);
  EXPECT_TRUE(analog.update()) << "and the one after has a sample again";
  EXPECT_TRUE(analog.read_currents(currents));
  // Not complete at the tick (only half the transfers done).
  f.dma2.LISR = DmaRegs::kHtif0;
  forget(f);
  EXPECT_FALSE(analog.update());
  EXPECT_FALSE(analog.read(codes));
  EXPECT_FALSE(analog.read_currents(currents));
  EXPECT_EQ(analog.incomplete(), 1u);
  EXPECT_EQ(f.adc1.CR2, 1u) << "stopped: the rest of the late scan never reaches the next one's buffer";
  EXPECT_FALSE(analog.update());
  // A transfer error of the stream.
  scan_done(f, analog, c);
  f.dma2.LISR = f.dma2.LISR | DmaRegs::kTeif0;
  EXPECT_FALSE(analog.update());
  EXPECT_FALSE(analog.read_currents(currents));
  EXPECT_EQ(analog.overruns(), 2u);
  EXPECT_EQ(analog.scans(), 1u);
}

TEST(Stm32Pots, TheClockTheChannelsTheSampleTimesAndTheScanTime) {
  EXPECT_EQ(adc_divider(84000000), 4u);
  EXPECT_EQ(adc_divider(16000000), 2u);
  EXPECT_EQ(adc_divider(168000000), 6u) << "28 MHz: within 36 MHz";
  EXPECT_EQ(Analog::kCount, 12);
  EXPECT_EQ(Analog::scan_ns(21000000), 160000u) << "6 x (56 + 12) + 6 x (480 + 12) cycles at 21 MHz";
  EXPECT_EQ(Analog::scan_ns(21000000, 6), 19428u) << "the six currents, first";
  EXPECT_EQ(Analog::scan_ns(8000000), 420000u) << "at the HSI fallback";
  EXPECT_LT(Analog::scan_ns(8000000), 500000u) << "within half the 1 ms tick";
  EXPECT_EQ(adc1_channel_of(pins::PA(0)), 0);
  EXPECT_EQ(adc1_channel_of(pins::PA(7)), 7);
  EXPECT_EQ(adc1_channel_of(pins::PB(1)), 9);
  EXPECT_EQ(adc1_channel_of(pins::PC(0)), 10);
  EXPECT_EQ(adc1_channel_of(pins::PC(5)), 15);
  for (Pin p : {pins::PA(8), pins::PB(2), pins::PC(6), pins::PD(0), pins::PE(13)}) EXPECT_EQ(adc1_channel_of(p), -1);
  // RM0090 13.13.4: SMP 0..7 = 3, 15, 28, 56, 84, 112, 144, 480 cycles.
  const std::uint32_t cycles[8] = {3, 15, 28, 56, 84, 112, 144, 480};
  for (int code = 0; code < 8; ++code) EXPECT_EQ(adc_sample_code(cycles[code]), code);
  for (std::uint32_t other : {0u, 4u, 57u, 479u, 481u}) EXPECT_EQ(adc_sample_code(other), -1);
}

TEST(Stm32Currents, EachCurrentIsItsCodeLessMidScale) {
  FakeChip f;
  Analog analog;
  analog.init(f.chip(), 84000000);
  std::int16_t currents[hal::kJoints] = {};
  EXPECT_FALSE(analog.update());
  EXPECT_FALSE(analog.read_currents(currents)) << "no current before the first scan completed";
  const std::uint16_t pots[hal::kJoints] = {10, 20, 30, 40, 50, 60};
  // 0 -> -2048, 2048 (0 A) -> 0, 4095 -> +2047, and their neighbours; bits above the twelfth dropped.
  const std::uint16_t codes[hal::kJoints] = {0, 2048, 4095, 1, 2047, 0xF000u | 2049u};
  const std::int16_t want[hal::kJoints] = {-2048, 0, 2047, -2047, -1, 1};
  scan_done(f, analog, pots, codes);
  ASSERT_TRUE(analog.update());
  ASSERT_TRUE(analog.read_currents(currents));
  for (int c = 0; c < hal::kJoints; ++c) EXPECT_EQ(currents[c], want[c]) << "amplifier " << c + 1;
  std::uint16_t p[hal::kJoints] = {};
  ASSERT_TRUE(analog.read(p));
  for (int j = 0; j < hal::kJoints; ++j) EXPECT_EQ(p[j], pots[j]) << "the potentiometers after the currents";
  EXPECT_EQ(Analog::kMidScale, 2048);
}

TEST(Stm32Currents, TheScaleIsTheDriveTrainsCurrentMonitors) {
  const osc::CurrentMonitor& m = osc::robot::kDriveTrain.current;
  ASSERT_TRUE(kHasCurrentMonitors) << "both arms' tables declare current monitors";
  EXPECT_EQ(m.bits, 12);
  EXPECT_EQ(kCurrentSpanCodes, 2047) << "+-(2^(bits-1) - 1) at +-range times the DAC's full scale";
  EXPECT_NEAR(kCurrentCodesPerFullScale, 2047 / m.range, 1e-12);
  EXPECT_NEAR(kCurrentCodesPerFullScale, 1637.6, 1e-9) << "the arms' range, 1.25";
}

// ------------------------------------------------------------------------------------------- pins

TEST(Stm32Pins, TheIndexAndPotentiometerPinsWithTheirFunctions) {
  using namespace pins;
  // DS8626 table 9: TIM1_CH3 PE13 AF1, TIM2_CH4 PB11 AF1, TIM3_CH3 PC8 AF2, TIM4_CH3 PB8 AF2,
  // TIM5_CH4 PA3 AF2, TIM8_CH4 PC9 AF3.
  const Pin index[hal::kJoints] = {PE(13), PB(11), PC(8), PB(8), PA(3), PC(9)};
  const std::uint8_t af[hal::kJoints] = {1, 1, 2, 2, 2, 3};
  const int channel[hal::kJoints] = {3, 4, 3, 3, 4, 4};
  // DS8626 table 7: ADC123_IN11 PC1, ADC123_IN12 PC2, ADC12_IN14 PC4, ADC12_IN15 PC5, ADC12_IN8 PB0,
  // ADC12_IN9 PB1.
  const Pin pot[hal::kJoints] = {PC(1), PC(2), PC(4), PC(5), PB(0), PB(1)};
  const std::uint8_t adc[hal::kJoints] = {11, 12, 14, 15, 8, 9};
  for (int j = 0; j < hal::kJoints; ++j) {
    SCOPED_TRACE(j + 1);
    EXPECT_TRUE(kEncoders[j].index.pin == index[j]);
    EXPECT_EQ(kEncoders[j].index.mode, Mode::kAlternate);
    EXPECT_EQ(kEncoders[j].index.af, af[j]);
    EXPECT_EQ(kEncoders[j].index_channel, channel[j]);
    EXPECT_TRUE(kPots[j].pin.pin == pot[j]);
    EXPECT_EQ(kPots[j].pin.mode, Mode::kAnalog);
    EXPECT_EQ(kPots[j].pin.pull, Pull::kNone);
    EXPECT_EQ(kPots[j].channel, adc[j]);
  }
  EXPECT_TRUE(kUartRx.pin == PD(6)) << "USART2_RX moved off PA3 (TIM5_CH4)";
  EXPECT_EQ(kUartRx.af, 7);
  // Every pin once (the pin map's static_assert), and the check finds a pin used twice.
  EXPECT_TRUE(pins_distinct());
  EXPECT_EQ(kPinCount, 6 * hal::kJoints + 11);
  const Pin twice[] = {PC(1), PE(13), PA(3), PC(1)};
  EXPECT_FALSE(distinct(twice, 4));
  EXPECT_TRUE(distinct(twice, 3));
  Pin all[kPinCount];
  for (int i = 0; i < kPinCount; ++i) all[i] = pin_at(i);
  all[3 * hal::kJoints + 4] = PA(3);  // joint 5's potentiometer on joint 5's index pin
  EXPECT_FALSE(distinct(all, kPinCount));
}

TEST(Stm32Pins, TheCurrentMonitorAndFaultLinePinsAreInTheMap) {
  using namespace pins;
  // DS8626 table 7: ADC12_IN4-7 on PA4-PA7, ADC123_IN10 PC0, ADC123_IN13 PC3: the six ADC1 pins left.
  const Pin monitor[hal::kJoints] = {PA(4), PA(5), PA(6), PA(7), PC(0), PC(3)};
  const std::uint8_t adc[hal::kJoints] = {4, 5, 6, 7, 10, 13};
  const Pin fault[hal::kJoints] = {PE(7), PE(8), PE(10), PE(12), PE(14), PE(15)};
  for (int c = 0; c < hal::kJoints; ++c) {
    SCOPED_TRACE(c + 1);
    EXPECT_TRUE(kCurrentMonitors[c].pin.pin == monitor[c]);
    EXPECT_EQ(kCurrentMonitors[c].pin.mode, Mode::kAnalog);
    EXPECT_EQ(kCurrentMonitors[c].channel, adc[c]);
    EXPECT_EQ(kCurrentMonitors[c].sample_cycles, 56u);
    EXPECT_EQ(kPots[c].sample_cycles, 480u);
    EXPECT_TRUE(kAmpFaults[c].pin == fault[c]);
    EXPECT_EQ(kAmpFaults[c].mode, Mode::kInput);
    EXPECT_EQ(kAmpFaults[c].pull, Pull::kUp) << "a broken wire reads high: a fault";
  }
  // The map's check covers them: a current monitor or a fault line on a pin already taken is found.
  Pin all[kPinCount];
  for (int i = 0; i < kPinCount; ++i) all[i] = pin_at(i);
  ASSERT_TRUE(distinct(all, kPinCount));
  EXPECT_TRUE(all[4 * hal::kJoints] == PA(4)) << "the current monitors follow the potentiometers";
  EXPECT_TRUE(all[5 * hal::kJoints] == PE(7)) << "then the fault lines";
  all[4 * hal::kJoints + 5] = PC(1);  // amplifier 6's monitor on joint 1's potentiometer
  EXPECT_FALSE(distinct(all, kPinCount));
  all[4 * hal::kJoints + 5] = PC(3);
  all[5 * hal::kJoints + 1] = PE(9);  // amplifier 2's fault line on joint 1's encoder A
  EXPECT_FALSE(distinct(all, kPinCount));
}

// -------------------------------------------------------------------------------------------- DAC

/// A DAC bus that records what the chips would see.
struct RecordingBus {
  struct Event {
    enum Kind { kFrame, kLdac, kClear } kind;
    int chip;
    ad5754r::Frame frame;
  };
  std::vector<Event> events;
  bool fail = false;
  bool write(int chip, const ad5754r::Frame& fr) {
    events.push_back({Event::kFrame, chip, fr});
    return !fail;
  }
  void ldac_pulse() { events.push_back({Event::kLdac, -1, {}}); }
  void clear_pulse() { events.push_back({Event::kClear, -1, {}}); }
};
static_assert(ad5754r::Bus<RecordingBus>);

TEST(Stm32Dac, FramesOfKnownCodes) {
  using namespace ad5754r;
  // Register bits 21-19, channel 18-16, data 15-0, MSB first.
  EXPECT_EQ(frame(kDacRegister, 0, code_word(32767)), (Frame{{0x00, 0x7F, 0xFF}}));
  EXPECT_EQ(frame(kDacRegister, 2, code_word(-1)), (Frame{{0x02, 0xFF, 0xFF}}));
  EXPECT_EQ(frame(kDacRegister, 1, code_word(-32767)), (Frame{{0x01, 0x80, 0x01}}));
  EXPECT_EQ(frame(kDacRegister, 1, code_word(0)), (Frame{{0x01, 0x00, 0x00}})) << "0 V in two's complement";
  EXPECT_EQ(frame(kOutputRange, kAllChannels, kRangeBipolar10V), (Frame{{0x0C, 0x00, 0x04}}));
  EXPECT_EQ(frame(kPowerControl, 0, kPowerUpABC | kPowerUpReference), (Frame{{0x10, 0x00, 0x17}}));
  EXPECT_EQ(frame(kControl, kControlFunctionSet, kTsdEnable | kClampEnable | kSdoDisable), (Frame{{0x19, 0x00, 0x0D}}));
  EXPECT_EQ(code_word(40000), 0x7FFFu) << "saturated";
  EXPECT_EQ(code_word(-40000), 0x8000u);
}

TEST(Stm32Dac, OneBurstOfSixFramesThenOneLatchForAllJoints) {
  RecordingBus bus;
  ad5754r::DacPair<RecordingBus> dac(bus);
  const std::int32_t codes[hal::kJoints] = {1000, -2000, 32767, -32767, 0, 12345};
  ASSERT_TRUE(dac.write(codes));
  ASSERT_EQ(bus.events.size(), 7u) << "six frames and one LDAC pulse";
  const int chip[hal::kJoints] = {0, 0, 0, 1, 1, 1};
  const std::uint8_t channel[hal::kJoints] = {0, 1, 2, 0, 1, 2};
  for (int j = 0; j < hal::kJoints; ++j) {
    SCOPED_TRACE(j);
    EXPECT_EQ(bus.events[j].kind, RecordingBus::Event::kFrame) << "no latch before every joint's code is in";
    EXPECT_EQ(bus.events[j].chip, chip[j]);
    const std::uint16_t w = ad5754r::code_word(codes[j]);
    EXPECT_EQ(bus.events[j].frame,
              (ad5754r::Frame{{channel[j], static_cast<std::uint8_t>(w >> 8), static_cast<std::uint8_t>(w & 0xFF)}}));
  }
  EXPECT_EQ(bus.events[6].kind, RecordingBus::Event::kLdac);
}

TEST(Stm32Dac, InitSetsTheRangeAndZeroBeforePoweringUp) {
  RecordingBus bus;
  ad5754r::DacPair<RecordingBus> dac(bus);
  ASSERT_TRUE(dac.init());
  using E = RecordingBus::Event;
  std::vector<E::Kind> kinds;
  for (const E& e : bus.events) kinds.push_back(e.kind);
  const std::vector<E::Kind> want = {E::kFrame, E::kFrame, E::kFrame, E::kFrame, E::kFrame,
                                     E::kFrame, E::kLdac,  E::kFrame, E::kFrame};
  ASSERT_EQ(kinds, want);
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(bus.events[3 * c].frame, (ad5754r::Frame{{0x0C, 0x00, 0x04}})) << "±10 V, all channels";
    EXPECT_EQ(bus.events[3 * c + 2].frame, (ad5754r::Frame{{0x04, 0x00, 0x00}})) << "0 V, all channels";
    EXPECT_EQ(bus.events[7 + c].frame, (ad5754r::Frame{{0x10, 0x00, 0x17}})) << "A-C and reference up last";
    EXPECT_EQ(bus.events[7 + c].chip, c);
  }
  bus.fail = true;
  EXPECT_FALSE(dac.init());
}

TEST(Stm32SpiBus, ConfiguresMode2MasterAndSendsAFrameUnderSync) {
  FakeChip f;
  SpiDacBus bus;
  bus.init(f.chip(), 42000000);
  EXPECT_EQ(f.spi2.CR1, SpiRegs::kMstr | SpiRegs::kCpol | SpiRegs::kSsm | SpiRegs::kSsi | SpiRegs::kSpe)
      << "master, CPOL 1 CPHA 0, 21 MHz (BR 0), 8-bit";
  EXPECT_TRUE(drove(f, pins::kDacClr, true)) << "outputs idle high";
  f.spi2.SR = SpiRegs::kTxe | SpiRegs::kRxne;  // every byte goes at once, BSY low
  EXPECT_TRUE(bus.write(1, {{0x02, 0xAB, 0xCD}}));
  EXPECT_EQ(f.spi2.DR, 0xCDu) << "the last byte written";
  EXPECT_TRUE(drove(f, pins::kDacSync[1], true)) << "SYNC of chip 1 back high";
  bus.ldac_pulse();
  EXPECT_TRUE(drove(f, pins::kDacLdac, true));
  EXPECT_EQ(bus.errors(), 0u);
}

TEST(Stm32SpiBus, ATransmitterThatNeverEmptiesFailsTheFrameBoundedly) {
  FakeChip f;
  SpiDacBus bus;
  bus.init(f.chip(), 42000000);
  f.spi2.SR = 0;  // TXE never set
  EXPECT_FALSE(bus.write(0, {{0x00, 0x12, 0x34}}));
  EXPECT_EQ(f.spi2.DR, 0u) << "nothing written";
  EXPECT_TRUE(drove(f, pins::kDacSync[0], true)) << "SYNC released: the chip drops the frame";
  f.spi2.SR = SpiRegs::kTxe | SpiRegs::kRxne | SpiRegs::kBsy;  // busy forever
  EXPECT_FALSE(bus.write(0, {{0x00, 0x12, 0x34}}));
  EXPECT_EQ(bus.errors(), 2u);
}

// ------------------------------------------------------------------------------------------ flash

/// A FLASH block with FlashRegs' member names (FlashController's Regs) that records every write and
/// answers as the controller would: KEY1 then KEY2 in KEYR clears LOCK (any other sequence leaves
/// it set, unless keys_unlock is false: then nothing does); CR ignores writes while locked, except
/// none are made then; a 1 written to an SR flag clears it; an operation (STRT, or PG set) raises
/// `raise` in SR (an error flag; BSY: it never ends), and an erase sets its sector of `memory` (the
/// chip's sectors 10 and 11, FlashSectors' layout) to ones.
struct RecordingFlash {
  enum Id : std::uint8_t { kAcr, kKeyr, kOptkeyr, kSr, kCr, kOptcr };
  struct Write {
    Id reg;
    std::uint32_t value;
    bool operator==(const Write&) const = default;
  };
  struct Register {
    RecordingFlash* owner;
    Id id;
    std::uint32_t value = 0;
    Register& operator=(std::uint32_t v) {
      owner->write(*this, v);
      return *this;
    }
    operator std::uint32_t() const { return value; }
  };
  Register ACR{this, kAcr}, KEYR{this, kKeyr}, OPTKEYR{this, kOptkeyr}, SR{this, kSr}, CR{this, kCr},
      OPTCR{this, kOptcr};
  std::vector<Write> writes;
  std::uint32_t raise = 0;
  bool keys_unlock = true;
  std::uint32_t* memory = nullptr;

  RecordingFlash() { CR.value = FlashRegs::kLock; }  // locked from reset
  RecordingFlash(const RecordingFlash&) = delete;
  RecordingFlash& operator=(const RecordingFlash&) = delete;

  std::vector<std::uint32_t> writes_to(Id id) const {
    std::vector<std::uint32_t> v;
    for (const Write& w : writes)
      if (w.reg == id) v.push_back(w.value);
    return v;
  }

 private:
  bool key1_ = false;
  void write(Register& r, std::uint32_t v) {
    writes.push_back({r.id, v});
    if (r.id == kKeyr) {
      if (keys_unlock && key1_ && v == FlashRegs::kKey2) CR.value &= ~FlashRegs::kLock;
      key1_ = v == FlashRegs::kKey1;
    } else if (r.id == kSr) {
      SR.value &= ~(v & (FlashRegs::kErrors | FlashRegs::kEop));
    } else if (r.id == kCr) {
      if (CR.value & FlashRegs::kLock) return;
      const bool starts = (v & FlashRegs::kStrt) || ((v & FlashRegs::kPg) && !(CR.value & FlashRegs::kPg));
      CR.value = v & ~FlashRegs::kStrt;  // STRT reads 0 once the operation is over
      if (starts) SR.value |= raise;
      if ((v & FlashRegs::kStrt) && memory != nullptr) {
        const std::uint32_t sector = ((v & FlashRegs::kSnbMask) >> 3) - 10;
        std::fill_n(memory + sector * (128 * 1024 / 4), 128 * 1024 / 4, 0xFFFFFFFFu);
      }
    } else {
      r.value = v;
    }
  }
};
using Rec = RecordingFlash;
constexpr std::uint32_t kCachesOn = 5u | FlashRegs::kPrften | FlashRegs::kIcen | FlashRegs::kDcen;
constexpr FlashPolls kFewPolls{1000, 100};

/// The writes that reset the caches after an operation (ACR at kCachesOn before).
std::vector<Rec::Write> cache_reset() {
  const std::uint32_t off = 5u | FlashRegs::kPrften;
  return {{Rec::kAcr, off},
          {Rec::kAcr, off | FlashRegs::kIcrst | FlashRegs::kDcrst},
          {Rec::kAcr, off},
          {Rec::kAcr, kCachesOn}};
}

TEST(Stm32Flash, ASectorEraseUnlocksSetsSerSnbAndStrtAtX32AndLocks) {
  for (std::uint32_t sector : {10u, 11u}) {
    SCOPED_TRACE(sector);
    Rec f;
    f.ACR.value = kCachesOn;
    FlashController<Rec> flash(f);
    ASSERT_EQ(flash.erase_sector(sector), FlashStatus::kOk);
    const std::uint32_t erase = FlashRegs::kPsizeX32 | FlashRegs::kSer | (sector << 3);
    std::vector<Rec::Write> want = {{Rec::kKeyr, 0x45670123u},  // KEY1
                                    {Rec::kKeyr, 0xCDEF89ABu},  // KEY2
                                    {Rec::kCr, erase},
                                    {Rec::kCr, erase | FlashRegs::kStrt},
                                    {Rec::kCr, FlashRegs::kLock}};
    for (const Rec::Write& w : cache_reset()) want.push_back(w);
    EXPECT_EQ(f.writes, want);
    EXPECT_EQ(erase, (2u << 8) | (1u << 1) | (sector << 3)) << "PSIZE [9:8] = 2 (x32), SER bit 1, SNB [6:3]";
    EXPECT_EQ(FlashRegs::kStrt | FlashRegs::kLock, (1u << 16) | (1u << 31)) << "STRT bit 16, LOCK bit 31";
    EXPECT_EQ(f.CR.value, FlashRegs::kLock) << "locked at the end";
    EXPECT_EQ(f.ACR.value, kCachesOn) << "the caches back on";
  }
}

TEST(Stm32Flash, AWordIsProgrammedWithPgAtX32AndLocked) {
  Rec f;
  f.ACR.value = kCachesOn;
  FlashController<Rec> flash(f);
  volatile std::uint32_t word = 0xFFFFFFFFu;
  ASSERT_EQ(flash.program_word(&word, 0x12345678u), FlashStatus::kOk);
  EXPECT_EQ(word, 0x12345678u);
  EXPECT_EQ(f.writes_to(Rec::kKeyr), (std::vector<std::uint32_t>{FlashRegs::kKey1, FlashRegs::kKey2}));
  EXPECT_EQ(f.writes_to(Rec::kCr),
            (std::vector<std::uint32_t>{FlashRegs::kPsizeX32 | FlashRegs::kPg, FlashRegs::kLock}));
  // Already unlocked: no key (a wrong key sequence locks CR until reset: none that is not needed).
  Rec g;
  g.CR.value = 0;
  FlashController<Rec>(g).program_word(&word, 0u);
  EXPECT_TRUE(g.writes_to(Rec::kKeyr).empty());
  EXPECT_EQ(g.CR.value, FlashRegs::kLock);
}

TEST(Stm32Flash, AnErrorFlagFailsTheOperationWithItsNameAndIsCleared) {
  const std::pair<std::uint32_t, const char*> flags[] = {{FlashRegs::kWrperr, "write_protected"},
                                                         {FlashRegs::kPgaerr, "alignment_error"},
                                                         {FlashRegs::kPgperr, "parallelism_error"},
                                                         {FlashRegs::kPgserr, "sequence_error"},
                                                         {FlashRegs::kOperr, "operation_error"}};
  for (const auto& [flag, name] : flags) {
    SCOPED_TRACE(name);
    for (bool erase : {true, false}) {
      Rec f;
      f.raise = flag;
      FlashController<Rec> flash(f);
      volatile std::uint32_t word = 0xFFFFFFFFu;
      const FlashStatus s = erase ? flash.erase_sector(11) : flash.program_word(&word, 0u);
      EXPECT_STREQ(flash_status_name(s), name);
      EXPECT_EQ(f.SR.value, 0u) << "cleared (written 1)";
      EXPECT_EQ(f.writes_to(Rec::kSr), (std::vector<std::uint32_t>{flag}));
      EXPECT_EQ(f.CR.value, FlashRegs::kLock);
    }
  }
  // A stale flag from before is cleared before the operation and does not fail it.
  Rec f;
  f.SR.value = FlashRegs::kPgserr;
  EXPECT_EQ(FlashController<Rec>(f).erase_sector(10), FlashStatus::kOk);
}

TEST(Stm32Flash, AStuckBsyFailsBoundedly) {
  Rec before;  // busy before the operation: nothing is written
  before.SR.value = FlashRegs::kBsy;
  EXPECT_EQ(FlashController<Rec>(before, kFewPolls).erase_sector(10), FlashStatus::kBusyTimeout);
  EXPECT_TRUE(before.writes.empty());
  Rec during;  // BSY never clears after STRT: bounded, then locked all the same
  during.raise = FlashRegs::kBsy;
  const FlashStatus s = FlashController<Rec>(during, kFewPolls).erase_sector(10);
  EXPECT_EQ(s, FlashStatus::kBusyTimeout);
  EXPECT_STREQ(flash_status_name(s), "busy_timeout");
  EXPECT_EQ(during.CR.value & FlashRegs::kLock, FlashRegs::kLock);
  EXPECT_EQ(during.CR.value & (FlashRegs::kSer | FlashRegs::kSnbMask), 0u);
}

TEST(Stm32Flash, AControllerThatStaysLockedOrABadSectorDoesNothing) {
  Rec f;
  f.keys_unlock = false;
  FlashController<Rec> flash(f);
  EXPECT_EQ(flash.erase_sector(10), FlashStatus::kLocked);
  EXPECT_EQ(f.writes_to(Rec::kCr).size(), 0u) << "no operation started";
  Rec g;
  EXPECT_EQ(FlashController<Rec>(g).erase_sector(12), FlashStatus::kBadAddress);
  EXPECT_TRUE(g.writes.empty());
  for (FlashStatus s = FlashStatus::kOk; s != FlashStatus::kCount;
       s = static_cast<FlashStatus>(static_cast<int>(s) + 1))
    EXPECT_NE(flash_status_name(s), nullptr);
}

TEST(Stm32Flash, TheParameterSectorsCarryTheRecordStore) {
  std::vector<std::uint32_t> memory(2 * FlashSectors<>::kSectorWords, 0u);  // not erased yet
  Rec f;
  f.memory = memory.data();
  FlashSectors<Rec> sectors(f, memory.data());
  persist::RecordStore<FlashSectors<Rec>> store(sectors);
  const std::uint8_t a[5] = {1, 2, 3, 4, 5}, b[3] = {9, 8, 7};
  ASSERT_TRUE(store.save(a, sizeof a, 1).saved());
  EXPECT_EQ(memory[0], persist::kMagic) << "sector 10 first";
  EXPECT_EQ(f.writes_to(Rec::kCr)[0], FlashRegs::kPsizeX32 | FlashRegs::kSer | (10u << 3));
  f.writes.clear();
  ASSERT_TRUE(store.save(b, sizeof b, 1).saved());
  EXPECT_EQ(f.writes_to(Rec::kCr)[0], FlashRegs::kPsizeX32 | FlashRegs::kSer | (11u << 3));
  EXPECT_EQ(memory[FlashSectors<>::kSectorWords], persist::kMagic) << "sector 11 at 0x080E0000";
  std::uint8_t got[8] = {};
  const persist::LoadResult r = store.load(got, sizeof got, 1);
  ASSERT_TRUE(r.loaded());
  EXPECT_EQ(r.sequence, persist::kFirstSequence + 1);
  EXPECT_EQ(got[0], 9);
  EXPECT_EQ(f.CR.value, FlashRegs::kLock);
  // A failing sector: the store's status, and the driver's name for it (what a boot would print).
  f.raise = FlashRegs::kWrperr;
  EXPECT_EQ(store.save(a, sizeof a, 1).status, persist::SaveStatus::kEraseFailed);
  EXPECT_STREQ(flash_status_name(sectors.last_status()), "write_protected");
  EXPECT_FALSE(sectors.program(2, 0, 0u));
  EXPECT_FALSE(sectors.program(0, FlashSectors<>::kSectorWords, 0u));
  EXPECT_EQ(sectors.last_status(), FlashStatus::kBadAddress);
  EXPECT_EQ(sectors.read(1, FlashSectors<>::kSectorWords), persist::kErased);
  EXPECT_EQ(FlashSectors<>::hardware_memory(), reinterpret_cast<volatile std::uint32_t*>(0x080C0000u));
}

/// The board's parameter store (param_store.hpp) over the sectors: the command port's save and load
/// of the parameter table, each save inside one watchdog stretch; what the boot loads; a record of
/// another table (layout) not loaded.
TEST(Stm32Flash, TheBoardsParameterStoreSavesAndLoadsTheTable) {
  std::vector<std::uint32_t> memory(2 * FlashSectors<>::kSectorWords, 0u);
  Rec f;
  f.memory = memory.data();
  FlashSectors<Rec> sectors(f, memory.data());
  struct CountingWatchdog {
    int stretched = 0, restored = 0;
    void stretch() { ++stretched; }
    void restore() { ++restored; }
  } dog;
  persist::FlashParamStore<FlashSectors<Rec>, CountingWatchdog> store(sectors, dog);
  osc::ParamRecord r{};
  EXPECT_EQ(store.load(r).status, persist::LoadStatus::kNone);
  const osc::ParamStorage s = store.storage();
  EXPECT_EQ(s.load(s.ctx, r), osc::ParamStatus::kNoRecord);
  osc::ParamRecord saved = osc::param_defaults();
  saved.value[osc::param_slot(osc::param_index("ks")) + 1] = 80;
  ASSERT_TRUE(s.save(s.ctx, saved));
  EXPECT_EQ(dog.stretched, 1);
  EXPECT_EQ(dog.restored, 1);
  ASSERT_EQ(s.load(s.ctx, r), osc::ParamStatus::kOk);
  EXPECT_EQ(std::memcmp(&r, &saved, sizeof r), 0);
  // The boot's path: the record applied to a task (disabled) as a whole.
  auto task = std::make_unique<osc::ControlTask<float>>();
  task->init(osc::Model<float>::of(osc::robot::kArm), osc::Gains<float>::paper(), osc::FrictionMode::kAdaptive,
             osc::joint_vector<float>(osc::robot::kQStart), 0, osc::TaskStart::kDisabled);
  ASSERT_EQ(osc::param_apply(*task, r), osc::ParamStatus::kOk);
  EXPECT_EQ(task->gains.ks(1), 80.0f);
  // A record of another table: not this one's.
  persist::RecordStore<FlashSectors<Rec>> raw(sectors);
  const std::uint8_t other[8] = {};
  ASSERT_TRUE(raw.save(other, sizeof other, static_cast<std::uint16_t>(osc::kParamLayout + 1)).saved());
  EXPECT_EQ(s.load(s.ctx, r), osc::ParamStatus::kOk) << "the older record of this layout is still there";
  ASSERT_TRUE(raw.save(other, sizeof other, static_cast<std::uint16_t>(osc::kParamLayout + 1)).saved());
  EXPECT_EQ(s.load(s.ctx, r), osc::ParamStatus::kLayoutMismatch) << "both sectors now hold the other table's";
  // A failed save is reported, the watchdog set back all the same.
  f.raise = FlashRegs::kWrperr;
  EXPECT_FALSE(s.save(s.ctx, saved));
  EXPECT_EQ(store.last_save().status, persist::SaveStatus::kEraseFailed);
  EXPECT_EQ(dog.restored, 2);
}

TEST(Stm32Flash, TheChipsFlashBlockDrivesTheSectors) {
  FakeChip fc;  // the chip's FLASH block in RAM, as the other drivers' blocks: unlocked, never busy
  std::vector<std::uint32_t> memory(2 * FlashSectors<>::kSectorWords, 0xFFFFFFFFu);
  FlashSectors sectors(*fc.chip().flash, memory.data());
  EXPECT_TRUE(sectors.program(1, 7, 0xA5A5A5A5u));
  EXPECT_EQ(memory[FlashSectors<>::kSectorWords + 7], 0xA5A5A5A5u);
  EXPECT_EQ(fc.flash.CR, FlashRegs::kLock) << "locked after the word";
  EXPECT_EQ(fc.flash.KEYR, 0u) << "it was unlocked: no key written";
  // RAM ignores the keys, as a controller locked until reset does: the next operation fails locked.
  EXPECT_FALSE(sectors.erase(0));
  EXPECT_STREQ(flash_status_name(sectors.last_status()), "locked");
  EXPECT_EQ(fc.flash.KEYR, FlashRegs::kKey2);
  fc.flash.CR = 0;
  fc.flash.SR = FlashRegs::kPgperr;  // RAM keeps the flag (writing 1 does not clear it): reported
  EXPECT_FALSE(sectors.erase(0));
  EXPECT_STREQ(flash_status_name(sectors.last_status()), "parallelism_error");
}

// ------------------------------------------------------------- the board's HAL and the control task

/// A DAC that records the codes of every burst.
struct RecordingDac {
  std::vector<std::vector<std::int32_t>> bursts;
  int clears = 0;
  bool ok = true;
  bool write(const std::int32_t c[hal::kJoints]) {
    bursts.emplace_back(c, c + hal::kJoints);
    return ok;
  }
  void clear() { ++clears; }
  bool last_zero() const {
    for (std::int32_t c : bursts.back())
      if (c != 0) return false;
    return true;
  }
};
struct FakeCycles {
  static inline std::uint32_t now = 0;
  static std::uint32_t cycles() { return now += 100; }
};

struct BoardRig {
  FakeChip f;
  Encoders enc;
  RecordingDac dac;
  Analog analog;
  Safety safety;
  BoardHal<Encoders, RecordingDac, FakeCycles, Analog> hal{enc, dac, analog, safety, f.timer(Timer::kTim6)};
  osc::ControlTask<double> task;
  BoardRig() {
    const Chip c = f.chip();
    enc.init(c);
    analog.init(c, 84000000);
    safety.init(c);
    task.init(osc::Model<double>::of(osc::robot::kArm), osc::Gains<double>::paper(), osc::FrictionMode::kAdaptive,
              osc::joint_vector<double>(osc::robot::kQStart), 168000);
  }
  /// A tick as the control interrupt runs it.
  std::uint32_t tick() {
    control_timer_ack(f.timer(Timer::kTim6));
    return hal.tick(task);
  }
};
static_assert(hal::ControlHal<BoardHal<Encoders, RecordingDac, FakeCycles, Analog>>);
static_assert(hal::PositionHal<BoardHal<Encoders, RecordingDac, FakeCycles, Analog>>);
static_assert(hal::CurrentHal<BoardHal<Encoders, RecordingDac, FakeCycles, Analog>>);
// What BoardHal needs from its drivers: the board's and the fakes satisfy it...
static_assert(EncoderInput<Encoders> && DacOutput<ad5754r::DacPair<SpiDacBus>> && DacOutput<RecordingDac> &&
              CycleClock<FakeCycles> && PotInput<Analog> && CurrentInput<Analog>);
// ...and a driver that lacks a function, returns the wrong type or needs an instance does not: BoardHal
// refuses it.
struct DacWithoutClear {
  bool write(const std::int32_t*) { return true; }
};
struct DacWithVoidWrite {
  void write(const std::int32_t*) {}  // cannot report a bus fault
  void clear() {}
};
struct EncodersWithoutRead {
  void init(const Chip&) {}
  bool take_index(int, std::int32_t&) { return false; }
};
struct EncodersWithoutIndex {
  void read(std::int32_t*) {}
};
struct CyclesOfAnInstance {
  std::uint32_t cycles() { return 0; }
};
struct PotsWithoutUpdate {
  bool read(std::uint16_t*) const { return false; }
  bool read_currents(std::int16_t*) const { return false; }
};
struct PotsWithVoidRead {
  bool update() { return false; }
  void read(std::uint16_t*) const {}  // cannot say there is no sample
  bool read_currents(std::int16_t*) const { return false; }
};
struct PotsWithoutCurrents {  // the potentiometers' scan alone
  bool update() { return false; }
  bool read(std::uint16_t*) const { return false; }
};
struct CurrentsAsUnsignedCodes {
  bool update() { return false; }
  bool read(std::uint16_t*) const { return false; }
  bool read_currents(std::uint16_t*) const { return false; }  // raw codes: no sign, no zero
};
struct CurrentsWithVoidRead {
  bool update() { return false; }
  bool read(std::uint16_t*) const { return false; }
  void read_currents(std::int16_t*) const {}  // cannot say there is no sample
};
static_assert(!DacOutput<DacWithoutClear> && !DacOutput<DacWithVoidWrite>);
static_assert(!EncoderInput<EncodersWithoutRead> && !EncoderInput<EncodersWithoutIndex>);
static_assert(!CycleClock<CyclesOfAnInstance>);
static_assert(!PotInput<PotsWithoutUpdate> && !PotInput<PotsWithVoidRead>);
static_assert(PotInput<PotsWithoutCurrents> && !CurrentInput<PotsWithoutCurrents>);
static_assert(!CurrentInput<CurrentsAsUnsignedCodes> && !CurrentInput<CurrentsWithVoidRead>);
template <class E, class D, class C, class P = Analog>
concept BoardHalOf = requires {
  typename BoardHal<E, D, C, P>;
};
static_assert(BoardHalOf<Encoders, RecordingDac, FakeCycles>);
static_assert(!BoardHalOf<Encoders, DacWithVoidWrite, FakeCycles>);
static_assert(!BoardHalOf<EncodersWithoutRead, RecordingDac, FakeCycles>);
static_assert(!BoardHalOf<EncodersWithoutIndex, RecordingDac, FakeCycles>);
static_assert(!BoardHalOf<Encoders, RecordingDac, CyclesOfAnInstance>);
static_assert(!BoardHalOf<Encoders, RecordingDac, FakeCycles, PotsWithVoidRead>);
static_assert(!BoardHalOf<Encoders, RecordingDac, FakeCycles, PotsWithoutCurrents>);
static_assert(!BoardHalOf<Encoders, RecordingDac, FakeCycles, CurrentsAsUnsignedCodes>);

TEST(Stm32Board, AmplifierOffUntilTheSupervisorRunsHealthy) {
  BoardRig r;
  EXPECT_TRUE(r.f.port(pins::kAmpEnable.pin.port).MODER & (1u << (2 * pins::kAmpEnable.pin.n)));
  EXPECT_TRUE(drove(r.f, pins::kFaultLed, false)) << "init: LED off, set before the pin became an output";
  EXPECT_FALSE(r.safety.amplifier_enabled());
  ASSERT_EQ(r.tick(), 0u);
  EXPECT_EQ(r.task.sup.state, osc::SupervisorState::kRun);
  EXPECT_TRUE(r.safety.amplifier_enabled());
  EXPECT_TRUE(drove(r.f, pins::kAmpEnable, true));
  EXPECT_NE(r.dac.bursts.back()[1], 0) << "the controller holds joint 2 against gravity";
}

TEST(Stm32Board, ABootFaultKeepsTheAmplifierOffAndTheCodesZero) {
  BoardRig r;
  r.hal.permit_torque(false);
  for (int k = 0; k < 5; ++k) ASSERT_EQ(r.tick(), 0u);
  EXPECT_EQ(r.task.sup.state, osc::SupervisorState::kRun) << "the control task itself runs";
  EXPECT_NE(r.task.codes[1], 0);
  EXPECT_TRUE(r.dac.last_zero());
  EXPECT_FALSE(r.safety.amplifier_enabled());
  EXPECT_TRUE(drove(r.f, pins::kAmpEnable, false));
}

TEST(Stm32Board, AnyFaultZeroesTheCodesAndDropsTheAmplifierInTheSameTick) {
  BoardRig r;
  for (int k = 0; k < 3; ++k) ASSERT_EQ(r.tick(), 0u);
  ASSERT_FALSE(r.dac.last_zero());
  r.f.timer(pins::kEncoders[0].timer).CNT = 5000;  // an encoder jump
  EXPECT_NE(r.tick() & osc::kFaultEncoderJump, 0u);
  EXPECT_EQ(r.task.sup.state, osc::SupervisorState::kFault);
  EXPECT_TRUE(r.dac.last_zero());
  EXPECT_FALSE(r.safety.amplifier_enabled());
  EXPECT_TRUE(drove(r.f, pins::kAmpEnable, false));
  r.tick();
  EXPECT_TRUE(r.dac.last_zero()) << "and every tick after";
}

TEST(Stm32Board, TheEstopInterruptLatchesTheFaultWithinOneTick) {
  BoardRig r;
  EXPECT_EQ(r.f.syscfg.EXTICR[0], 3u << 4) << "EXTI line 1 from port D";
  EXPECT_EQ(r.f.exti.RTSR, 1u << 1);
  EXPECT_EQ(r.f.exti.IMR, 1u << 1);
  for (int k = 0; k < 3; ++k) ASSERT_EQ(r.tick(), 0u);
  ASSERT_TRUE(r.safety.amplifier_enabled());
  r.f.exti.PR = 0;
  r.safety.on_estop_interrupt();  // the EXTI1 handler
  EXPECT_EQ(r.f.exti.PR, 1u << 1) << "pending bit cleared";
  EXPECT_FALSE(r.safety.amplifier_enabled()) << "amplifier off in the interrupt itself";
  EXPECT_TRUE(drove(r.f, pins::kFaultLed, true));
  EXPECT_NE(r.tick() & osc::kFaultEstop, 0u) << "the next tick";
  EXPECT_EQ(r.task.sup.state, osc::SupervisorState::kFault);
  EXPECT_NE(r.task.sup.latched & osc::kFaultEstop, 0u);
  EXPECT_TRUE(r.dac.last_zero());
  EXPECT_FALSE(r.safety.amplifier_enabled());
}

TEST(Stm32Board, AnEstopHeldBeforeBootFaultsTheFirstTick) {
  BoardRig r;
  r.f.port(pins::kEstop.pin.port).IDR = 1u << pins::kEstop.pin.n;  // open chain: no edge ever comes
  EXPECT_NE(r.tick() & osc::kFaultEstop, 0u);
  EXPECT_FALSE(r.safety.amplifier_enabled());
  EXPECT_TRUE(r.dac.last_zero());
}

TEST(Stm32Board, AnEstopDuringTheBurstClearsTheOutputs) {
  struct RacingDac : RecordingDac {
    Safety* s = nullptr;
    bool write(const std::int32_t c[hal::kJoints]) {
      s->on_estop_interrupt();  // the E-stop interrupt preempts the burst
      return RecordingDac::write(c);
    }
  };
  FakeChip f;
  Encoders enc;
  RacingDac dac;
  Analog analog;
  Safety safety;
  enc.init(f.chip());
  safety.init(f.chip());
  dac.s = &safety;
  BoardHal<Encoders, RacingDac, FakeCycles, Analog> hal{enc, dac, analog, safety, f.timer(Timer::kTim6)};
  const std::int32_t codes[hal::kJoints] = {1, 2, 3, 4, 5, 6};
  hal.write_dacs(codes);
  EXPECT_EQ(dac.clears, 1) << "CLR pulsed: the codes of that burst never reach the joints";
}

TEST(Stm32Board, TheSafeStateBeforeInitIsHarmless) {
  // A fault handler may run before the drivers are set up: nothing to switch yet, and no crash.
  Safety safety;
  SpiDacBus bus;
  safety.force_safe();
  bus.clear_pulse();
  EXPECT_FALSE(safety.amplifier_enabled());
}

TEST(Stm32Board, TheWatchdogIsFedOnlyByHealthyTicks) {
  BoardRig r;
  EXPECT_EQ(r.safety.watchdog_start(), BootFault::kNone);
  EXPECT_EQ(r.f.iwdg.PR, 0u);
  EXPECT_EQ(r.f.iwdg.RLR, 40u);
  EXPECT_EQ(r.f.iwdg.KR, IwdgRegs::kReload);
  EXPECT_NE(r.f.dbgmcu.APB1_FZ & DbgmcuRegs::kIwdgStop, 0u) << "paused while a debugger halts the core";
  for (int k = 0; k < 3; ++k) {
    r.f.iwdg.KR = 0;
    ASSERT_EQ(r.tick(), 0u);
    EXPECT_EQ(r.f.iwdg.KR, IwdgRegs::kReload) << "healthy tick " << k;
  }
  r.f.timer(pins::kEncoders[2].timer).CNT = 60000;  // encoder jump: the fault latches
  r.f.iwdg.KR = 0;
  r.tick();
  EXPECT_EQ(r.f.iwdg.KR, 0u) << "the faulted tick does not feed";
  for (int k = 0; k < 3; ++k) {
    r.tick();
    EXPECT_EQ(r.f.iwdg.KR, 0u) << "nor any tick after it";
  }
  EXPECT_EQ(r.hal.feeds(), 3u);
}

TEST(Stm32Board, AWatchdogThatNeverTakesItsSettingsIsABootFault) {
  BoardRig r;
  r.f.iwdg.SR = IwdgRegs::kRvu;  // the reload update never completes (no LSI)
  EXPECT_EQ(r.safety.watchdog_start(), BootFault::kWatchdogSetup);
}

TEST(Stm32Board, ATickThatFindsTheNextOnePendingIsAnOverrun) {
  BoardRig r;
  ASSERT_EQ(r.tick(), 0u);
  r.f.timer(Timer::kTim6).SR = TimRegs::kUif;  // set again right after the acknowledgement
  EXPECT_NE(r.hal.tick(r.task) & osc::kFaultOverrun, 0u);
}

TEST(Stm32Board, ADacBusFaultLatchesOnTheNextTick) {
  BoardRig r;
  ASSERT_EQ(r.tick(), 0u);
  r.dac.ok = false;
  EXPECT_EQ(r.tick(), 0u);
  EXPECT_NE(r.tick() & osc::kFaultDacBus, 0u);
  EXPECT_EQ(r.task.sup.state, osc::SupervisorState::kFault);
  EXPECT_TRUE(r.dac.last_zero());
  // In the catalogue: named in the console, the JSON and the telemetry reader (it once read "none").
  EXPECT_EQ(r.task.sup.latched & ~osc::kAllFaults, 0u);
  EXPECT_STREQ(osc::fault_name(r.task.sup.latched), "dac_bus");
}

TEST(Stm32Board, TheTickScansThePotsAndTheHalGivesThemAndTheIndex) {
  BoardRig r;
  std::uint16_t codes[hal::kJoints] = {};
  ASSERT_EQ(r.tick(), 0u);
  EXPECT_FALSE(r.hal.read_pots(codes)) << "the first tick started the first scan";
  EXPECT_TRUE(started(r.f));
  const std::uint16_t c[hal::kJoints] = {2048, 100, 4000, 1234, 3333, 17};
  scan_done(r.f, r.analog, c);
  index_edge(r.f, 2, 65535);  // joint 3's index one count below the start
  ASSERT_EQ(r.tick(), 0u);
  ccr_read(r.f, 2);
  ASSERT_TRUE(r.hal.read_pots(codes));
  for (int j = 0; j < hal::kJoints; ++j) EXPECT_EQ(codes[j], c[j]) << "joint " << j + 1;
  std::int32_t n = 0;
  EXPECT_FALSE(r.hal.take_index(0, n));
  ASSERT_TRUE(r.hal.take_index(2, n));
  EXPECT_EQ(n, -1);
  EXPECT_FALSE(r.hal.take_index(2, n));
  lifcr_cleared(r.f);
  ASSERT_EQ(r.tick(), 0u);  // the scan the last tick started has not completed
  EXPECT_FALSE(r.hal.read_pots(codes));
}

TEST(Stm32Board, TheTickScansTheCurrentsAndTheHalGivesThemSigned) {
  BoardRig r;
  std::int16_t currents[hal::kJoints] = {};
  ASSERT_EQ(r.tick(), 0u);
  EXPECT_FALSE(r.hal.read_currents(currents)) << "the first tick started the first scan";
  const std::uint16_t pots[hal::kJoints] = {2048, 100, 4000, 1234, 3333, 17};
  const std::uint16_t codes[hal::kJoints] = {4095, 0, 2048, 2100, 1000, 2047};
  scan_done(r.f, r.analog, pots, codes);
  ASSERT_EQ(r.tick(), 0u);
  ASSERT_TRUE(r.hal.read_currents(currents));
  const std::int16_t want[hal::kJoints] = {2047, -2048, 0, 52, -1048, -1};
  for (int c = 0; c < hal::kJoints; ++c) EXPECT_EQ(currents[c], want[c]) << "amplifier " << c + 1;
  // The next scan lost a result: no current that tick, as no potentiometer.
  scan_done(r.f, r.analog, pots, codes);
  r.f.adc1.SR = r.f.adc1.SR | AdcRegs::kOvr;
  ASSERT_EQ(r.tick(), 0u);
  EXPECT_FALSE(r.hal.read_currents(currents));
  std::uint16_t p[hal::kJoints] = {};
  EXPECT_FALSE(r.hal.read_pots(p));
}

/// Amplifier fault line c at a level, the other lines as they were.
void fault_line(FakeChip& f, int c, bool high) {
  const Pin p = pins::kAmpFaults[c].pin;
  GpioRegs& g = f.port(p.port);
  g.IDR = high ? g.IDR | (1u << p.n) : g.IDR & ~(1u << p.n);
}

TEST(Stm32Board, EachAmplifiersFaultLineIsItsBit) {
  BoardRig r;
  for (const PinConfig& p : pins::kAmpFaults) {
    const GpioRegs& g = r.f.port(p.pin.port);
    EXPECT_EQ((g.MODER >> (2 * p.pin.n)) & 3u, 0u) << "an input";
    EXPECT_EQ((g.PUPDR >> (2 * p.pin.n)) & 3u, 1u) << "with its pull-up";
  }
  EXPECT_EQ(r.hal.amp_faults(), 0u) << "every line held low: every amplifier healthy";
  for (int c = 0; c < hal::kJoints; ++c) {
    fault_line(r.f, c, true);
    EXPECT_EQ(r.hal.amp_faults(), 1u << c) << "amplifier " << c + 1 << "'s line high (its fault, or an open wire)";
    fault_line(r.f, c, false);
  }
  for (int c = 0; c < hal::kJoints; ++c) fault_line(r.f, c, true);
  EXPECT_EQ(r.hal.amp_faults(), 0x3Fu) << "every line open: an unplugged cable";
  r.f.port(Port::E).IDR = ~0u & ~((1u << 7) | (1u << 8) | (1u << 10) | (1u << 12) | (1u << 14) | (1u << 15));
  EXPECT_EQ(r.hal.amp_faults(), 0u) << "the port's other pins (joint 1's encoder) are no fault";
}

// ---------------------------------------------------------------------- control timer, telemetry

TEST(Stm32ControlTimer, OneKilohertzFromEachTimerClock) {
  FakeChip f;
  TimRegs& t = f.timer(Timer::kTim6);
  control_timer_start(t, control_divider(84000000, 1000));
  EXPECT_EQ(t.PSC, 83u);
  EXPECT_EQ(t.ARR, 999u);
  EXPECT_EQ(t.DIER, TimRegs::kUie);
  EXPECT_EQ(t.CR1, TimRegs::kUrs | TimRegs::kCen);
  EXPECT_EQ(control_divider(16000000, 1000).psc, 15u) << "HSI fallback";
  EXPECT_EQ(control_divider(48000000, 1000).psc, 47u) << "QEMU's timer clock";
  t.SR = TimRegs::kUif;
  EXPECT_TRUE(control_timer_pending(t));
  control_timer_ack(t);
  EXPECT_FALSE(control_timer_pending(t));
}

/// The board's link: 8 frames queued, a 512-byte receive ring.
using Link = UsartLink<8, pil::kMaxFrame, 512>;

TEST(Stm32Telemetry, AFrameGoesOutWhileTheTransmitterIsEmptyAndTheNextWaits) {
  FakeChip f;
  Link u;
  u.init(f.chip(), 42000000, 460800, pins::kUartTx, pins::kUartRx);
  EXPECT_EQ(f.usart2.BRR, 91u);
  EXPECT_EQ(f.usart2.CR1, UsartRegs::kUe | UsartRegs::kTe | UsartRegs::kRe | UsartRegs::kRxneie);
  osc::ControlTask<float> task;
  task.init(osc::Model<float>::of(osc::robot::kArm), osc::Gains<float>::paper(), osc::FrictionMode::kAdaptive,
            osc::joint_vector<float>(osc::robot::kQStart));
  const std::int32_t codes[hal::kJoints] = {1, -2, 3, -4, 5, -6};
  std::uint8_t buf[pil::kMaxFrame];
  const int n = pil::encode(osc::telemetry_frame(task, codes, 7, 1234), buf);
  ASSERT_EQ(n, pil::kMaxFrame);
  ASSERT_TRUE(u.offer(buf, n));
  EXPECT_EQ(u.pump(), 0) << "transmitter full: nothing goes";
  EXPECT_TRUE(u.offer(buf, n)) << "queued behind the first";
  EXPECT_EQ(u.queued(), 2);
  EXPECT_EQ(u.dropped(), 0u);
  f.usart2.SR = UsartRegs::kTxe;
  EXPECT_EQ(u.pump(10), 10);
  EXPECT_EQ(u.pump(n - 10), n - 10);
  EXPECT_EQ(f.usart2.DR, buf[n - 1]);
  EXPECT_EQ(u.queued(), 1) << "the first frame out, whole";
  EXPECT_EQ(u.pump(), n);
  EXPECT_FALSE(u.busy());
  // The bytes are the PIL's actuator frame: the host's parser reads them back.
  pil::Parser p;
  pil::Parser::Result res = pil::Parser::kPending;
  for (int i = 0; i < n; ++i) res = p.feed(buf[i]);
  ASSERT_EQ(res, pil::Parser::kFrame);
  pil::ActuatorFrame a;
  ASSERT_TRUE(p.decode(a));
  EXPECT_EQ(a.seq, 7u);
  EXPECT_EQ(a.codes[3], -4);
  EXPECT_EQ(a.stack_used, 1234u);
}

TEST(Stm32Link, ReceivedBytesGoThroughTheRingAndLostOnesAreCounted) {
  FakeChip f;
  Link u;
  u.init(f.chip(), 42000000, 460800, pins::kUartTx, pins::kUartRx);
  std::uint8_t b = 0;
  EXPECT_FALSE(u.read(b));
  f.usart2.SR = 0;
  u.on_rx_interrupt();  // no RXNE: nothing read
  EXPECT_TRUE(u.rx_empty());
  for (int i = 0; i < 3; ++i) {
    f.usart2.SR = UsartRegs::kRxne;
    f.usart2.DR = 0x40u + static_cast<std::uint32_t>(i);
    u.on_rx_interrupt();
  }
  f.usart2.SR = UsartRegs::kRxne | UsartRegs::kOre;  // a byte lost in the USART before this one
  f.usart2.DR = 0x7Fu;
  u.on_rx_interrupt();
  EXPECT_EQ(u.rx_overruns(), 1u);
  for (std::uint8_t want : {0x40, 0x41, 0x42, 0x7F}) {
    ASSERT_TRUE(u.read(b));
    EXPECT_EQ(b, want);
  }
  EXPECT_FALSE(u.read(b));
  // A main loop that falls behind: the ring takes 512 bytes, the rest are counted lost.
  for (int i = 0; i < 600; ++i) {
    f.usart2.SR = UsartRegs::kRxne;
    f.usart2.DR = static_cast<std::uint32_t>(i & 0xFF);
    u.on_rx_interrupt();
  }
  EXPECT_EQ(u.rx_lost(), 88u);
  int n = 0;
  for (; u.read(b); ++n) EXPECT_EQ(b, n & 0xFF);
  EXPECT_EQ(n, 512);
}

TEST(Stm32Link, TheRingsIndicesRunFreelyAcrossTheirWrap) {
  ByteRing<16> r;
  std::uint8_t b = 0;
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(r.push(static_cast<std::uint8_t>(i)));
    if (i % 3 == 2) {  // the consumer lags, then catches up
      for (int k = 2; k >= 0; --k) {
        ASSERT_TRUE(r.pop(b));
        EXPECT_EQ(b, static_cast<std::uint8_t>(i - k));
      }
    }
  }
  EXPECT_EQ(r.size(), 1000u % 3);
  EXPECT_EQ(r.lost(), 0u);
}

TEST(Stm32Link, AFullQueueDropsAndCountsTheFrameAndKeepsTheOrder) {
  FrameQueue<3, 8> q;
  const std::uint8_t a[] = {1, 2}, b[] = {3}, c[] = {4, 5, 6}, d[] = {7};
  EXPECT_TRUE(q.push(a, 2));
  EXPECT_TRUE(q.push(b, 1));
  EXPECT_TRUE(q.push(c, 3));
  EXPECT_FALSE(q.push(d, 1)) << "full";
  std::uint8_t big[9] = {};
  EXPECT_FALSE(q.push(big, 9)) << "longer than a slot";
  EXPECT_EQ(q.dropped(), 2u);
  int n = 0;
  for (const std::uint8_t* want : {a, b, c}) {
    const std::uint8_t* p = q.front(n);
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(p[0], want[0]);
    q.pop();
  }
  EXPECT_EQ(n, 3);
  EXPECT_EQ(q.front(n), nullptr);
  EXPECT_TRUE(q.push(d, 1)) << "room again";
}

TEST(Stm32Link, AnAnswerQueuedBehindTelemetryGoesOutWholeAndParses) {
  FakeChip f;
  Link u;
  u.init(f.chip(), 42000000, 460800, pins::kUartTx, pins::kUartRx);
  osc::ControlTask<float> task;
  task.init(osc::Model<float>::of(osc::robot::kArm), osc::Gains<float>::paper(), osc::FrictionMode::kAdaptive,
            osc::joint_vector<float>(osc::robot::kQStart));
  const std::int32_t codes[hal::kJoints] = {};
  std::uint8_t t[pil::kMaxFrame], a[pil::kMaxFrame];
  const int nt = pil::encode(osc::telemetry_frame(task, codes, 3, 0), t);
  pil::AnswerFrame ans{};
  ans.id = 77;
  const int na = pil::encode(ans, a);
  ASSERT_TRUE(u.offer(t, nt));
  ASSERT_TRUE(u.offer(a, na));
  f.usart2.SR = UsartRegs::kTxe;
  pil::Parser p;
  std::vector<pil::FrameType> got;
  for (int i = 0; i < nt + na; ++i) {
    ASSERT_EQ(u.pump(1), 1);
    if (p.feed(static_cast<std::uint8_t>(f.usart2.DR)) == pil::Parser::kFrame) got.push_back(p.type());
  }
  EXPECT_FALSE(u.busy());
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0], pil::kActuatorFrame);
  EXPECT_EQ(got[1], pil::kAnswerFrame);
  pil::AnswerFrame back;
  ASSERT_TRUE(p.decode(back));
  EXPECT_EQ(back.id, 77u);
}

/// The board's tick with the command link watched, as its control interrupt runs it.
struct WatchedRig : BoardRig {
  osc::CommandLinkWatch watch;
  bool commanded = true;
  std::uint32_t tick() {
    watch.before_tick(task, commanded);
    return BoardRig::tick();
  }
  /// Ticks until the motion is aborted (its reason), or `limit` ticks.
  osc::MotionReason run(int limit, int heard_every = 0) {
    for (int k = 1; k <= limit; ++k) {
      if (heard_every && k % heard_every == 0) watch.heard();
      EXPECT_EQ(tick(), 0u) << k;
      if (task.report.abort != osc::MotionReason::kNone) return task.report.abort;
    }
    return osc::MotionReason::kNone;
  }
};

TEST(Stm32CommandLink, ASilentLinkStopsTheMotionCategoryTwoAfterTheTimeout) {
  OSC_PUMA_TUNED("its rig's still encoders: the UR5e's fine encoders read encoder_stuck");
  auto r = std::make_unique<WatchedRig>();  // the paper's motion runs from the first tick
  constexpr int kTimeout = static_cast<int>(osc::CommandLinkWatch::kTimeoutTicks);
  static_assert(kTimeout == 500, "0.5 s at 1 kHz");
  r->watch.heard();
  ASSERT_EQ(r->run(kTimeout), osc::MotionReason::kNone) << "not before the timeout";
  EXPECT_EQ(r->task.machine.state, osc::MotionState::kMoving);
  EXPECT_EQ(r->run(1), osc::MotionReason::kLinkSilent);
  EXPECT_EQ(r->task.machine.state, osc::MotionState::kStopping);
  EXPECT_EQ(osc::state_frame_from_task(r->task).stop, static_cast<std::uint8_t>(osc::StopCategory::kCategory2));
  EXPECT_EQ(r->task.sup.latched, 0u) << "no fault: a controlled stop";
  EXPECT_TRUE(r->safety.amplifier_enabled()) << "torque on while it decelerates";
  EXPECT_EQ(r->watch.stops(), 1u);
  EXPECT_EQ(r->run(50), osc::MotionReason::kNone) << "aborted once";
}

TEST(Stm32CommandLink, FramesKeepTheMotionGoingAndNoHostMeansNoStop) {
  OSC_PUMA_TUNED("its rig's still encoders: the UR5e's fine encoders read encoder_stuck");
  auto r = std::make_unique<WatchedRig>();
  // (600 ticks at most: the encoders here stand still, and the paper's motion latches encoder_stuck
  // after about 620.)
  EXPECT_EQ(r->run(590, 200), osc::MotionReason::kNone) << "a frame every 0.2 s";
  EXPECT_EQ(r->task.machine.state, osc::MotionState::kMoving);
  EXPECT_LT(r->watch.silent_ticks(), 200u);
  auto quiet = std::make_unique<WatchedRig>();
  quiet->commanded = false;  // no host has sent a command: the paper's motion of a board alone
  EXPECT_EQ(quiet->run(590), osc::MotionReason::kNone);
  EXPECT_EQ(quiet->watch.stops(), 0u);
  EXPECT_EQ(quiet->watch.silent_ticks(), osc::CommandLinkWatch::kTimeoutTicks);
}

TEST(Stm32CommandLink, AStopRequestOutsideAMotionIsIgnoredAndCleared) {
  auto r = std::make_unique<WatchedRig>();
  osc::request_stop(r->task, osc::MotionReason::kLinkSilent);
  r->task.machine.state = osc::MotionState::kHolding;  // the machine alone decides: nothing to stop
  EXPECT_EQ(r->BoardRig::tick(), 0u);
  EXPECT_EQ(r->task.report.abort, osc::MotionReason::kNone);
  EXPECT_EQ(r->task.stop_request, osc::MotionReason::kNone) << "each tick takes the request it finds";
}

}  // namespace
