// STM32F405/407 registers the chip's drivers (this folder, boards/common/stm32f4) use, written from
// the reference manual (ST RM0090, rev. 19: the section named at each block) and the ARMv7-M core
// where noted. Minimal: only the blocks and bits the drivers touch. Each block is a struct whose
// layout is the manual's register map (offsets static_assert'ed); a driver takes a reference to a
// block, so that a host test can hand it a block in RAM (tests/boards/stm32f4/test_stm32f4.cpp). Chip (at the end)
// names every block the drivers use: at their hardware addresses on the target, or fakes in a test.
// A board that needs another block or bit adds it here. No core-only instruction here: the header
// compiles on the host.
#pragma once

#include <cstddef>
#include <cstdint>

namespace stm32f4 {

using Reg = volatile std::uint32_t;

/// Reads a register and drops the value: e.g. after enabling a peripheral clock, so that the write
/// has taken effect before the peripheral's first access (errata ES0182, "delay after an RCC
/// peripheral clock enabling").
inline void read_back(const Reg& r) {
  const std::uint32_t v = r;
  static_cast<void>(v);
}

/// Polls `ready` at most `polls` times: true as soon as it holds, false if it never did. Every wait
/// on a hardware flag in these drivers is one of these.
template <class Ready>
bool poll_until(Ready ready, std::uint32_t polls) {
  for (std::uint32_t i = 0; i < polls; ++i)
    if (ready()) return true;
  return false;
}

// ---------------------------------------------------------------- RCC (RM0090 7.3)
struct RccRegs {
  Reg CR;       // 0x00 clock control
  Reg PLLCFGR;  // 0x04 main PLL configuration
  Reg CFGR;     // 0x08 clock configuration
  Reg CIR;      // 0x0C clock interrupt
  Reg AHB1RSTR, AHB2RSTR, AHB3RSTR, reserved0;
  Reg APB1RSTR, APB2RSTR, reserved1[2];
  Reg AHB1ENR;  // 0x30 GPIO port clocks
  Reg AHB2ENR, AHB3ENR, reserved2;
  Reg APB1ENR;  // 0x40 TIM2..7, SPI2/3, USART2/3, ...
  Reg APB2ENR;  // 0x44 TIM1/8, USART1/6, SPI1, SYSCFG, ...
  Reg reserved3[2];
  Reg AHB1LPENR, AHB2LPENR, AHB3LPENR, reserved4, APB1LPENR, APB2LPENR, reserved5[2];
  Reg BDCR;  // 0x70 backup domain control
  Reg CSR;   // 0x74 control/status: LSI, reset flags

  // CR
  static constexpr std::uint32_t kHsiOn = 1u << 0, kHsiRdy = 1u << 1, kHseOn = 1u << 16, kHseRdy = 1u << 17,
                                 kHseByp = 1u << 18, kCssOn = 1u << 19, kPllOn = 1u << 24, kPllRdy = 1u << 25;
  // PLLCFGR: PLLM [5:0], PLLN [14:6], PLLP [17:16] (0: /2, 1: /4, 2: /6, 3: /8), PLLSRC bit 22 (1: HSE),
  // PLLQ [27:24]
  static constexpr std::uint32_t pllcfgr(std::uint32_t m, std::uint32_t n, std::uint32_t p, std::uint32_t q) {
    return m | (n << 6) | (((p / 2) - 1) << 16) | (1u << 22) | (q << 24);
  }
  // CFGR: SW [1:0] and SWS [3:2] (0 HSI, 1 HSE, 2 PLL), HPRE [7:4] (0: /1), PPRE1 [12:10] and
  // PPRE2 [15:13] (0: /1, 4: /2, 5: /4, 6: /8, 7: /16)
  static constexpr std::uint32_t kSwMask = 3u, kSwHsi = 0u, kSwPll = 2u;
  static constexpr std::uint32_t kSwsMask = 3u << 2, kSwsHsi = 0u << 2, kSwsPll = 2u << 2;
  static constexpr std::uint32_t kHpreMask = 0xFu << 4, kPpre1Mask = 7u << 10, kPpre2Mask = 7u << 13;
  static constexpr std::uint32_t kPpre1Div4 = 5u << 10, kPpre2Div2 = 4u << 13;
  // AHB1ENR: GPIOxEN bit x (A = 0 ... I = 8), DMA2EN bit 22
  static constexpr std::uint32_t kDma2En = 1u << 22;
  // APB1ENR
  static constexpr std::uint32_t kTim2En = 1u << 0, kTim3En = 1u << 1, kTim4En = 1u << 2, kTim5En = 1u << 3,
                                 kTim6En = 1u << 4, kSpi2En = 1u << 14, kUsart2En = 1u << 17;
  // APB2ENR
  static constexpr std::uint32_t kTim1En = 1u << 0, kTim8En = 1u << 1, kAdc1En = 1u << 8, kSyscfgEn = 1u << 14;
  // CSR: reset flags (cleared by writing RMVF)
  static constexpr std::uint32_t kRmvf = 1u << 24, kPinRstf = 1u << 26, kPorRstf = 1u << 27, kSftRstf = 1u << 28,
                                 kIwdgRstf = 1u << 29;
};
static_assert(offsetof(RccRegs, AHB1ENR) == 0x30 && offsetof(RccRegs, APB1ENR) == 0x40 &&
                  offsetof(RccRegs, APB2ENR) == 0x44 && offsetof(RccRegs, CSR) == 0x74,
              "RCC register map (RM0090 7.3.24)");

// ---------------------------------------------------------------- FLASH interface (RM0090 3.9)
struct FlashRegs {
  Reg ACR;      // 0x00 access control: LATENCY [2:0] wait states, PRFTEN 8, ICEN 9, DCEN 10, ICRST 11, DCRST 12
  Reg KEYR;     // 0x04 key: kKey1 then kKey2 clears CR's LOCK (a wrong sequence locks CR until reset)
  Reg OPTKEYR;  // 0x08 option key (not used)
  Reg SR;       // 0x0C status: EOP 0, OPERR 1, WRPERR 4, PGAERR 5, PGPERR 6, PGSERR 7 (each cleared by
                //      writing 1), BSY 16
  Reg CR;       // 0x10 control: PG 0, SER 1, MER 2, SNB [6:3] (sectors 0-11), PSIZE [9:8], STRT 16,
                //      EOPIE 24, ERRIE 25, LOCK 31
  Reg OPTCR;    // 0x14 option control (not used)
  static constexpr std::uint32_t kLatencyMask = 7u, kPrften = 1u << 8, kIcen = 1u << 9, kDcen = 1u << 10,
                                 kIcrst = 1u << 11, kDcrst = 1u << 12;
  static constexpr std::uint32_t kKey1 = 0x45670123u, kKey2 = 0xCDEF89ABu;
  static constexpr std::uint32_t kEop = 1u << 0, kOperr = 1u << 1, kWrperr = 1u << 4, kPgaerr = 1u << 5,
                                 kPgperr = 1u << 6, kPgserr = 1u << 7, kBsy = 1u << 16;
  static constexpr std::uint32_t kErrors = kOperr | kWrperr | kPgaerr | kPgperr | kPgserr;
  static constexpr std::uint32_t kPg = 1u << 0, kSer = 1u << 1, kSnbMask = 0xFu << 3, kPsizeMask = 3u << 8,
                                 kStrt = 1u << 16, kLock = 1u << 31;
  // PSIZE: 0 x8, 1 x16, 2 x32 (the size for 2.7-3.6 V, RM0090 3.6.2), 3 x64 (external VPP)
  static constexpr std::uint32_t kPsizeX32 = 2u << 8;
  static constexpr std::uint32_t snb(std::uint32_t sector) { return sector << 3; }
};
static_assert(offsetof(FlashRegs, KEYR) == 0x04 && offsetof(FlashRegs, OPTKEYR) == 0x08 &&
                  offsetof(FlashRegs, SR) == 0x0C && offsetof(FlashRegs, CR) == 0x10 &&
                  offsetof(FlashRegs, OPTCR) == 0x14,
              "FLASH register map (RM0090 3.9.7)");

// ---------------------------------------------------------------- GPIO (RM0090 8.4)
struct GpioRegs {
  Reg MODER;    // 0x00 2 bits a pin: 0 input, 1 output, 2 alternate function, 3 analog
  Reg OTYPER;   // 0x04 1 bit a pin: 0 push-pull, 1 open drain
  Reg OSPEEDR;  // 0x08 2 bits a pin: 0 low ... 3 very high
  Reg PUPDR;    // 0x0C 2 bits a pin: 0 none, 1 pull-up, 2 pull-down
  Reg IDR;      // 0x10 input levels
  Reg ODR;      // 0x14 output levels
  Reg BSRR;     // 0x18 write: bits 0..15 set, bits 16..31 reset (atomic)
  Reg LCKR;     // 0x1C
  Reg AFR[2];   // 0x20 AFRL (pins 0..7), 0x24 AFRH (pins 8..15): 4 bits a pin
};
static_assert(offsetof(GpioRegs, BSRR) == 0x18 && offsetof(GpioRegs, AFR) == 0x20, "GPIO register map (RM0090 8.4.11)");

// ---------------------------------------------------------------- timers (RM0090 14.4, 15.4, 17.4)
/// TIM1/TIM8 (advanced), TIM2..TIM5 (general purpose) and TIM6/TIM7 (basic) share these offsets; a
/// basic timer has only CR1, CR2, DIER, SR, EGR, CNT, PSC and ARR. TIM2 and TIM5 have 32-bit CNT and
/// ARR, the others 16-bit (the upper half reads 0).
struct TimRegs {
  Reg CR1;     // 0x00 CEN bit 0, URS bit 2
  Reg CR2;     // 0x04
  Reg SMCR;    // 0x08 slave mode: SMS [2:0] (3: encoder mode 3, both inputs' edges)
  Reg DIER;    // 0x0C UIE bit 0
  Reg SR;      // 0x10 UIF bit 0, CCxIF bit x (x = 1..4), CCxOF bit 8 + x; every flag cleared by writing 0
               //      (a 1 written leaves it as it is); CCxIF also by reading CCRx
  Reg EGR;     // 0x14 UG bit 0
  Reg CCMR1;   // 0x18 CC1S [1:0], IC1F [7:4], CC2S [9:8], IC2F [15:12]
  Reg CCMR2;   // 0x1C CC3S [1:0], IC3F [7:4], CC4S [9:8], IC4F [15:12] (input capture: 1 = ICx on TIx)
  Reg CCER;    // 0x20 CC1P bit 1, CC1NP bit 3, CC2P bit 5, CC2NP bit 7; CCxE bit 4(x-1) (capture enabled),
               //      CCxP bit 4(x-1)+1 and CCxNP bit 4(x-1)+3 (both 0: the rising edge)
  Reg CNT;     // 0x24
  Reg PSC;     // 0x28
  Reg ARR;     // 0x2C
  Reg RCR;     // 0x30
  Reg CCR[4];  // 0x34..0x40 CCR1..CCR4: in input capture, the counter at the channel's last edge (read only)
  Reg BDTR, DCR, DMAR;
  static constexpr std::uint32_t kCen = 1u << 0, kUrs = 1u << 2, kUie = 1u << 0, kUif = 1u << 0, kUg = 1u << 0;
  static constexpr std::uint32_t kSmsEncoder3 = 3u;
  static constexpr std::uint32_t kCc1sTi1 = 1u << 0, kCc2sTi2 = 1u << 8, kCc3sTi3 = 1u << 0, kCc4sTi4 = 1u << 8;
  static constexpr std::uint32_t ic1f(std::uint32_t f) { return f << 4; }
  static constexpr std::uint32_t ic2f(std::uint32_t f) { return f << 12; }
  static constexpr std::uint32_t ic3f(std::uint32_t f) { return f << 4; }
  static constexpr std::uint32_t ic4f(std::uint32_t f) { return f << 12; }
  static constexpr std::uint32_t kCc1p = 1u << 1, kCc2p = 1u << 5;
  static constexpr std::uint32_t kCc3e = 1u << 8, kCc3p = 1u << 9, kCc3np = 1u << 11, kCc4e = 1u << 12,
                                 kCc4p = 1u << 13, kCc4np = 1u << 15;
  /// SR's capture/compare flag of channel x (1..4), and its overcapture flag.
  static constexpr std::uint32_t ccif(int x) { return 1u << x; }
  static constexpr std::uint32_t ccof(int x) { return 1u << (8 + x); }
};
static_assert(offsetof(TimRegs, CCMR2) == 0x1C && offsetof(TimRegs, CCER) == 0x20 && offsetof(TimRegs, CNT) == 0x24 &&
                  offsetof(TimRegs, ARR) == 0x2C && offsetof(TimRegs, CCR) == 0x34 &&
                  offsetof(TimRegs, CCR) + 3 * sizeof(Reg) == 0x40 && offsetof(TimRegs, DMAR) == 0x4C,
              "timer register map (RM0090 17.4.21)");
static_assert(TimRegs::ccif(3) == 1u << 3 && TimRegs::ccif(4) == 1u << 4 && TimRegs::ccof(3) == 1u << 11 &&
                  TimRegs::ccof(4) == 1u << 12,
              "CC3IF bit 3, CC4IF bit 4, CC3OF bit 11, CC4OF bit 12 (RM0090 17.4.5, 18.4.5)");

// ---------------------------------------------------------------- ADC (RM0090 13.13)
/// One ADC (ADC1 at 0x40012000; ADC2 and ADC3 follow at 0x100 each).
struct AdcRegs {
  Reg SR;       // 0x00 AWD 0, EOC 1, JEOC 2, JSTRT 3, STRT 4, OVR 5 (each cleared by writing 0)
  Reg CR1;      // 0x04 AWDCH [4:0], EOCIE 5, SCAN 8, DISCEN 11, RES [25:24] (0: 12-bit), OVRIE 26
  Reg CR2;      // 0x08 ADON 0, CONT 1, DMA 8, DDS 9, EOCS 10, ALIGN 11 (0: right), EXTEN [29:28] (0: software
                //      trigger only), SWSTART 30 (cleared by hardware as the conversion starts)
  Reg SMPR1;    // 0x0C sample time of channels 10-18: SMPx [2:0] at 3 (x - 10)
  Reg SMPR2;    // 0x10 sample time of channels 0-9: SMPx [2:0] at 3 x
  Reg JOFR[4];  // 0x14..0x20 injected channels' data offsets (not used)
  Reg HTR;      // 0x24 analog watchdog high threshold (not used)
  Reg LTR;      // 0x28 analog watchdog low threshold (not used)
  Reg SQR1;     // 0x2C regular sequence: SQ13..SQ16 (5 bits each from bit 0), L [23:20] = conversions - 1
  Reg SQR2;     // 0x30 SQ7..SQ12
  Reg SQR3;     // 0x34 SQ1..SQ6: the channel of the sequence's n-th conversion at 5 (n - 1)
  Reg JSQR;     // 0x38 injected sequence (not used)
  Reg JDR[4];   // 0x3C..0x48 injected data (not used)
  Reg DR;       // 0x4C regular data: the last conversion, right-aligned in [11:0] at 12 bits
  static constexpr std::uint32_t kEoc = 1u << 1, kStrt = 1u << 4, kOvr = 1u << 5;
  static constexpr std::uint32_t kScan = 1u << 8, kResMask = 3u << 24;
  static constexpr std::uint32_t kAdon = 1u << 0, kCont = 1u << 1, kDma = 1u << 8, kDds = 1u << 9, kEocs = 1u << 10,
                                 kAlign = 1u << 11, kExtenMask = 3u << 28, kSwstart = 1u << 30;
  /// SMPx: 0 3 cycles, 1 15, 2 28, 3 56, 4 84, 5 112, 6 144, 7 480 (RM0090 13.13.4)
  static constexpr std::uint32_t kSmp480 = 7u;
  static constexpr std::uint32_t sqr1_length(std::uint32_t conversions) { return (conversions - 1u) << 20; }
};
static_assert(offsetof(AdcRegs, SMPR1) == 0x0C && offsetof(AdcRegs, SMPR2) == 0x10 && offsetof(AdcRegs, JOFR) == 0x14 &&
                  offsetof(AdcRegs, HTR) == 0x24 && offsetof(AdcRegs, LTR) == 0x28 && offsetof(AdcRegs, SQR1) == 0x2C &&
                  offsetof(AdcRegs, SQR2) == 0x30 && offsetof(AdcRegs, SQR3) == 0x34 &&
                  offsetof(AdcRegs, JSQR) == 0x38 && offsetof(AdcRegs, JDR) == 0x3C && offsetof(AdcRegs, DR) == 0x4C,
              "ADC register map (RM0090 13.13.18)");

/// The registers the three ADCs share, at ADC1 + 0x300.
struct AdcCommonRegs {
  Reg CSR;  // 0x00 (ADC1 + 0x300) the three ADCs' flags, read only (not used)
  Reg CCR;  // 0x04 MULTI [4:0] (0: independent ADCs), DELAY [11:8], DMA [15:14] (multi-ADC), ADCPRE [17:16]
            //      (the ADC clock: PCLK2 / 2, 4, 6, 8), VBATE 22, TSVREFE 23
  Reg CDR;  // 0x08 multi-ADC data (not used)
  static constexpr std::uint32_t kAdcpreMask = 3u << 16;
  /// ADCPRE for a divider of PCLK2 (2, 4, 6 or 8).
  static constexpr std::uint32_t adcpre(std::uint32_t divider) { return ((divider / 2u) - 1u) << 16; }
};
static_assert(offsetof(AdcCommonRegs, CCR) == 0x04 && offsetof(AdcCommonRegs, CDR) == 0x08,
              "ADC common register map (RM0090 13.13.18: CSR, CCR, CDR at ADC1 + 0x300)");

// ---------------------------------------------------------------- DMA (RM0090 10.5)
/// One stream of a DMA controller (8 per controller, 0x18 apart from 0x10).
struct DmaStream {
  Reg CR;    // 0x00 EN 0, DMEIE 1, TEIE 2, HTIE 3, TCIE 4, PFCTRL 5, DIR [7:6] (0: peripheral to memory), CIRC 8,
             //      PINC 9, MINC 10, PSIZE [12:11] and MSIZE [14:13] (0: byte, 1: half-word, 2: word), PL [17:16],
             //      DBM 18, CHSEL [27:25]; written only while EN reads 0
  Reg NDTR;  // 0x04 transfers left (reloaded only by software in normal mode)
  Reg PAR;   // 0x08 peripheral address
  Reg M0AR;  // 0x0C memory address
  Reg M1AR;  // 0x10 second memory address (double buffer; not used)
  Reg FCR;   // 0x14 FTH [1:0], DMDIS 2 (0: direct mode, no FIFO), FS [5:3], FEIE 7
  static constexpr std::uint32_t kEn = 1u << 0, kCirc = 1u << 8, kPinc = 1u << 9, kMinc = 1u << 10;
  static constexpr std::uint32_t kDirMask = 3u << 6, kPsizeHalf = 1u << 11, kMsizeHalf = 1u << 13, kPlHigh = 2u << 16;
  static constexpr std::uint32_t kDmdis = 1u << 2;
  static constexpr std::uint32_t chsel(std::uint32_t channel) { return channel << 25; }
};
struct DmaRegs {
  Reg LISR;   // 0x00 flags of streams 0-3 (read only): stream 0 FEIF 0, DMEIF 2, TEIF 3, HTIF 4, TCIF 5
  Reg HISR;   // 0x04 streams 4-7
  Reg LIFCR;  // 0x08 writing 1 clears the flag of LISR at the same position
  Reg HIFCR;  // 0x0C
  DmaStream S[8];
  // Stream 0's flags (LISR, LIFCR)
  static constexpr std::uint32_t kFeif0 = 1u << 0, kDmeif0 = 1u << 2, kTeif0 = 1u << 3, kHtif0 = 1u << 4,
                                 kTcif0 = 1u << 5;
  static constexpr std::uint32_t kStream0Flags = kFeif0 | kDmeif0 | kTeif0 | kHtif0 | kTcif0;
};
static_assert(sizeof(DmaStream) == 0x18 && offsetof(DmaRegs, S) == 0x10 &&
                  offsetof(DmaRegs, S) + 7 * sizeof(DmaStream) + offsetof(DmaStream, FCR) == 0xCC,
              "DMA register map (RM0090 10.5.11)");

// ---------------------------------------------------------------- SPI (RM0090 28.5)
struct SpiRegs {
  Reg CR1;  // 0x00 CPHA 0, CPOL 1, MSTR 2, BR [5:3] (f_PCLK / 2^(BR+1)), SPE 6, SSI 8, SSM 9, DFF 11 (0: 8-bit)
  Reg CR2;  // 0x04
  Reg SR;   // 0x08 RXNE 0, TXE 1, MODF 5, OVR 6, BSY 7
  Reg DR;   // 0x0C
  Reg CRCPR, RXCRCR, TXCRCR, I2SCFGR, I2SPR;
  static constexpr std::uint32_t kCpha = 1u << 0, kCpol = 1u << 1, kMstr = 1u << 2, kSpe = 1u << 6, kSsi = 1u << 8,
                                 kSsm = 1u << 9;
  static constexpr std::uint32_t br(std::uint32_t b) { return b << 3; }
  static constexpr std::uint32_t kRxne = 1u << 0, kTxe = 1u << 1, kBsy = 1u << 7;
};
static_assert(offsetof(SpiRegs, DR) == 0x0C && offsetof(SpiRegs, I2SPR) == 0x20, "SPI register map (RM0090 28.5.10)");

// ---------------------------------------------------------------- USART (RM0090 30.6)
struct UsartRegs {
  Reg SR;   // 0x00 ORE 3, RXNE 5, TC 6, TXE 7
  Reg DR;   // 0x04
  Reg BRR;  // 0x08 DIV_Mantissa [15:4], DIV_Fraction [3:0] (16x oversampling)
  Reg CR1;  // 0x0C RE 2, TE 3, RXNEIE 5, UE 13
  Reg CR2, CR3, GTPR;
  static constexpr std::uint32_t kOre = 1u << 3, kRxne = 1u << 5, kTc = 1u << 6, kTxe = 1u << 7;
  static constexpr std::uint32_t kRe = 1u << 2, kTe = 1u << 3, kRxneie = 1u << 5, kUe = 1u << 13;
};
static_assert(offsetof(UsartRegs, CR1) == 0x0C && offsetof(UsartRegs, GTPR) == 0x18,
              "USART register map (RM0090 30.6.8)");

// ---------------------------------------------------------------- IWDG (RM0090 21.4)
struct IwdgRegs {
  Reg KR;   // 0x00 key: kStart starts it, kReload feeds it, kUnlock opens PR and RLR for writing
  Reg PR;   // 0x04 prescaler [2:0]: LSI / 4 << PR
  Reg RLR;  // 0x08 reload value [11:0]
  Reg SR;   // 0x0C PVU bit 0, RVU bit 1: an update of PR or RLR is still in progress
  static constexpr std::uint32_t kStart = 0xCCCCu, kReload = 0xAAAAu, kUnlock = 0x5555u;
  static constexpr std::uint32_t kPvu = 1u << 0, kRvu = 1u << 1;
};
static_assert(offsetof(IwdgRegs, SR) == 0x0C, "IWDG register map (RM0090 21.4.5)");

// ---------------------------------------------------------------- EXTI, SYSCFG (RM0090 12.3, 9.2)
struct ExtiRegs {
  Reg IMR;    // 0x00 interrupt mask: 1 = line enabled
  Reg EMR;    // 0x04
  Reg RTSR;   // 0x08 rising-edge trigger
  Reg FTSR;   // 0x0C falling-edge trigger
  Reg SWIER;  // 0x10 software interrupt: writing 1 sets the line's pending bit
  Reg PR;     // 0x14 pending: cleared by writing 1
};
static_assert(offsetof(ExtiRegs, PR) == 0x14, "EXTI register map (RM0090 12.3.7)");

struct SyscfgRegs {
  Reg MEMRMP, PMC;
  Reg EXTICR[4];  // 0x08..0x14: 4 bits a line, the port (A = 0, B = 1, ...) that drives EXTI line n
  Reg reserved[2];
  Reg CMPCR;
};
static_assert(offsetof(SyscfgRegs, EXTICR) == 0x08 && offsetof(SyscfgRegs, CMPCR) == 0x20,
              "SYSCFG register map (RM0090 9.2.8)");

// ---------------------------------------------------------------- DBGMCU (RM0090 38.16)
struct DbgmcuRegs {
  Reg IDCODE, CR;
  Reg APB1_FZ;  // 0x08 DBG_IWDG_STOP bit 12: the watchdog stops while the core is halted by a debugger
  Reg APB2_FZ;
  static constexpr std::uint32_t kIwdgStop = 1u << 12;
};

// ---------------------------------------------------------------- addresses (RM0090 2.3, table 1)
enum class Port : std::uint8_t { A, B, C, D, E, F, G, H, I };
constexpr int kPorts = 9;

namespace addr {
constexpr std::uintptr_t kTim2 = 0x40000000u, kTim3 = 0x40000400u, kTim4 = 0x40000800u, kTim5 = 0x40000C00u,
                         kTim6 = 0x40001000u, kIwdg = 0x40003000u, kSpi2 = 0x40003800u, kUsart2 = 0x40004400u,
                         kTim1 = 0x40010000u, kTim8 = 0x40010400u, kSyscfg = 0x40013800u, kExti = 0x40013C00u,
                         kAdc1 = 0x40012000u, kAdcCommon = kAdc1 + 0x300u, kGpioA = 0x40020000u, kGpioStride = 0x400u,
                         kRcc = 0x40023800u, kFlash = 0x40023C00u, kDma2 = 0x40026400u, kDbgmcu = 0xE0042000u;
}  // namespace addr

/// The timers the drivers use: TIM1..TIM5 and TIM8 (encoder mode or a periodic interrupt), TIM6 (basic:
/// a periodic interrupt).
enum class Timer : std::uint8_t { kTim1, kTim2, kTim3, kTim4, kTim5, kTim8, kTim6 };
constexpr int kTimers = 7;

/// Every register block the drivers use: the hardware's (hardware()), or fakes in RAM.
struct Chip {
  RccRegs* rcc;
  FlashRegs* flash;
  GpioRegs* gpio[kPorts];
  TimRegs* tim[kTimers];
  SpiRegs* spi2;
  UsartRegs* usart2;
  IwdgRegs* iwdg;
  ExtiRegs* exti;
  SyscfgRegs* syscfg;
  DbgmcuRegs* dbgmcu;
  AdcRegs* adc1;
  AdcCommonRegs* adc_common;
  DmaRegs* dma2;

  GpioRegs& port(Port p) const { return *gpio[static_cast<int>(p)]; }
  TimRegs& timer(Timer t) const { return *tim[static_cast<int>(t)]; }

  /// The blocks at their addresses (target only: dereferencing them on a host is meaningless).
  static Chip hardware() {
    Chip c{};
    c.rcc = at<RccRegs>(addr::kRcc);
    c.flash = at<FlashRegs>(addr::kFlash);
    for (int i = 0; i < kPorts; ++i) c.gpio[i] = at<GpioRegs>(addr::kGpioA + addr::kGpioStride * i);
    const std::uintptr_t tims[kTimers] = {addr::kTim1, addr::kTim2, addr::kTim3, addr::kTim4,
                                          addr::kTim5, addr::kTim8, addr::kTim6};
    for (int i = 0; i < kTimers; ++i) c.tim[i] = at<TimRegs>(tims[i]);
    c.spi2 = at<SpiRegs>(addr::kSpi2);
    c.usart2 = at<UsartRegs>(addr::kUsart2);
    c.iwdg = at<IwdgRegs>(addr::kIwdg);
    c.exti = at<ExtiRegs>(addr::kExti);
    c.syscfg = at<SyscfgRegs>(addr::kSyscfg);
    c.dbgmcu = at<DbgmcuRegs>(addr::kDbgmcu);
    c.adc1 = at<AdcRegs>(addr::kAdc1);
    c.adc_common = at<AdcCommonRegs>(addr::kAdcCommon);
    c.dma2 = at<DmaRegs>(addr::kDma2);
    return c;
  }

 private:
  template <class T>
  static T* at(std::uintptr_t a) {
    return reinterpret_cast<T*>(a);
  }
};

}  // namespace stm32f4
