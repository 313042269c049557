// The flash controller (RM0090 3.6: unlocking 3.6.1, sector erase 3.6.3, programming 3.6.4; the
// registers 3.9) and the two sectors of the STM32F407 that hold the parameters: sectors 10 and 11 of
// the 1 MiB part, 128 KiB each at 0x080C0000 and 0x080E0000 (RM0090 3.3, the flash module
// organization of the STM32F40x/41x), as a persist::FlashMedium for persist::RecordStore
// (boards/common/persist). linker/stm32f407.ld ends the image before them.
//
// Each erase or program is one operation: wait until the controller is idle, unlock (KEY1 then
// KEY2, only while CR is locked: a wrong key sequence locks CR until reset, so no key is written
// that is not needed), clear stale flags, start, wait until BSY clears, check and clear the error
// flags, lock. Word programming at x32 (PSIZE 2: the parallelism for 2.7-3.6 V). Every wait is a
// bounded poll; the outcome is a FlashStatus with a name.
//
// While an erase or a program runs, the CPU stalls on every read of the same bank (RM0090 3.6), and
// the STM32F407 has one bank: the code runs from it, so the core stands still, interrupts included
// (the control tick, the E-stop's handler), for up to 2 s an erase (128 KiB at x32, data sheet
// DS8626) and 100 us a word. That is acceptable only for a save with the torque off (amplifiers
// disabled), and the watchdog must allow it (the board's 5 ms IWDG would expire: lengthen its reload
// before a save, or save before it starts).
#pragma once

#include <atomic>
#include <cstdint>

#include "record_store.hpp"
#include "stm32f4_regs.hpp"

namespace stm32f4 {

// X(Name, name, what it means): how a flash operation ended, with the names a boot prints.
#define STM32F4_FLASH_STATUS_LIST(X)                                                                \
  X(Ok, "ok", "the operation completed without an error flag")                                      \
  X(BusyTimeout, "busy_timeout", "BSY did not clear within the poll budget")                        \
  X(Locked, "locked", "CR stayed locked after the key sequence")                                    \
  X(BadAddress, "bad_address", "a sector or word outside the parameter sectors: nothing done")      \
  X(WriteProtected, "write_protected", "WRPERR: the sector is write-protected (option bytes)")      \
  X(AlignmentError, "alignment_error", "PGAERR: the data does not fit one 128-bit flash row")       \
  X(ParallelismError, "parallelism_error", "PGPERR: the access size is not the one PSIZE selects")  \
  X(SequenceError, "sequence_error", "PGSERR: a write to the flash while CR was not set up for it") \
  X(OperationError, "operation_error", "OPERR: an operation that could not run (reported with ERRIE only)")

#define STM32F4_FLASH_X_ENUMERATOR(Name, name, doc) k##Name,
#define STM32F4_FLASH_X_NAME(Name, name, doc) name,
enum class FlashStatus : std::uint8_t { STM32F4_FLASH_STATUS_LIST(STM32F4_FLASH_X_ENUMERATOR) kCount };
/// Names in FlashStatus order.
inline constexpr const char* kFlashStatusNames[static_cast<int>(FlashStatus::kCount)] = {
    STM32F4_FLASH_STATUS_LIST(STM32F4_FLASH_X_NAME)};
#undef STM32F4_FLASH_X_ENUMERATOR
#undef STM32F4_FLASH_X_NAME
constexpr const char* flash_status_name(FlashStatus s) { return kFlashStatusNames[static_cast<int>(s)]; }

/// The error flags of SR as a status: the first set, in the list's order; kOk when none is.
constexpr FlashStatus flash_status_of(std::uint32_t sr) {
  if (sr & FlashRegs::kWrperr) return FlashStatus::kWriteProtected;
  if (sr & FlashRegs::kPgaerr) return FlashStatus::kAlignmentError;
  if (sr & FlashRegs::kPgperr) return FlashStatus::kParallelismError;
  if (sr & FlashRegs::kPgserr) return FlashStatus::kSequenceError;
  if (sr & FlashRegs::kOperr) return FlashStatus::kOperationError;
  return FlashStatus::kOk;
}

/// Polls of SR for BSY. At least one cycle a poll (a loop of a load, a test and a branch takes
/// more), at 168 MHz: an erase gets at least 2.3 s (128 KiB at x32: 2 s at most, DS8626), a word
/// at least 595 us (100 us at most). At the 16 MHz fallback clock the waits are longer still.
struct FlashPolls {
  std::uint32_t erase = 400000000;
  std::uint32_t program = 100000;
};

/// Sector erase and word programming. Regs is the register block: FlashRegs on the chip (and in a
/// host test, a block in RAM); a test may give a block of the same member names that records every
/// write (tests/boards/stm32f4/test_stm32f4.cpp).
template <class Regs = FlashRegs>
class FlashController {
 public:
  static constexpr std::uint32_t kLastSector = 11;  ///< sectors 0-11 of the 1 MiB part (SNB 4 bits)

  explicit FlashController(Regs& regs, const FlashPolls& polls = {}) : regs_(regs), polls_(polls) {}

  /// Erases a sector (SER, SNB, STRT; RM0090 3.6.3).
  FlashStatus erase_sector(std::uint32_t sector) {
    if (sector > kLastSector) return FlashStatus::kBadAddress;
    if (const FlashStatus s = begin(); s != FlashStatus::kOk) return s;
    regs_.CR = (regs_.CR & ~kOperationBits) | FlashRegs::kPsizeX32 | FlashRegs::kSer | FlashRegs::snb(sector);
    regs_.CR = regs_.CR | FlashRegs::kStrt;
    return finish(polls_.erase);
  }

  /// Programs one word (PG with PSIZE x32, then the word's write; RM0090 3.6.4). address: a word of
  /// the flash, 4-byte aligned.
  FlashStatus program_word(volatile std::uint32_t* address, std::uint32_t value) {
    if (const FlashStatus s = begin(); s != FlashStatus::kOk) return s;
    regs_.CR = (regs_.CR & ~kOperationBits) | FlashRegs::kPsizeX32 | FlashRegs::kPg;
    *address = value;
    // The flash is Normal memory and SR a peripheral's: a barrier (a DMB on the M4) keeps the
    // first read of SR from passing the word's write, which would read BSY before it is set.
    std::atomic_thread_fence(std::memory_order_seq_cst);
    return finish(polls_.program);
  }

 private:
  static constexpr std::uint32_t kOperationBits =
      FlashRegs::kPg | FlashRegs::kSer | FlashRegs::kSnbMask | FlashRegs::kPsizeMask | FlashRegs::kStrt;
  static constexpr std::uint32_t kFlags = FlashRegs::kErrors | FlashRegs::kEop;

  bool idle(std::uint32_t polls) {
    return poll_until([&] { return (regs_.SR & FlashRegs::kBsy) == 0; }, polls);
  }
  /// Writes 1 to the flags set (rc_w1: that clears them, and a zero bit changes nothing).
  void clear_flags() {
    const std::uint32_t set = regs_.SR & kFlags;
    if (set != 0) regs_.SR = set;
  }

  /// Idle (a previous erase may still run: its budget), unlocked, no stale flag. On a timeout
  /// nothing has been written.
  FlashStatus begin() {
    if (!idle(polls_.erase)) return FlashStatus::kBusyTimeout;
    if (regs_.CR & FlashRegs::kLock) {
      regs_.KEYR = FlashRegs::kKey1;
      regs_.KEYR = FlashRegs::kKey2;
      if (regs_.CR & FlashRegs::kLock) return FlashStatus::kLocked;
    }
    clear_flags();
    return FlashStatus::kOk;
  }

  /// Waits for the end of the operation, reads and clears the error flags, locks. The lock comes
  /// also after a timeout (ST's HAL too clears PG and SER after its wait, whatever the outcome): a
  /// controller left unlocked with PG set would program any stray write to the flash.
  FlashStatus finish(std::uint32_t polls) {
    const bool done = idle(polls);
    const std::uint32_t sr = regs_.SR;
    clear_flags();
    regs_.CR = (regs_.CR & ~kOperationBits) | FlashRegs::kLock;
    flush_caches();
    return done ? flash_status_of(sr) : FlashStatus::kBusyTimeout;
  }

  /// Resets the ART accelerator's caches (RM0090 3.5.2: a cache is reset only while disabled), so
  /// that no line of the flash from before the operation is read afterwards (the store reads back
  /// what it programmed); ST's HAL does this after an erase. The caches come back as they were.
  void flush_caches() {
    const std::uint32_t acr = regs_.ACR;
    const std::uint32_t off = acr & ~(FlashRegs::kIcen | FlashRegs::kDcen | FlashRegs::kIcrst | FlashRegs::kDcrst);
    regs_.ACR = off;
    regs_.ACR = off | FlashRegs::kIcrst | FlashRegs::kDcrst;
    regs_.ACR = off;
    regs_.ACR = acr & ~(FlashRegs::kIcrst | FlashRegs::kDcrst);
  }

  Regs& regs_;
  FlashPolls polls_;
};

/// Sectors 10 and 11 as the record store's two sectors (persist::FlashMedium): sector 0 of the store
/// is the chip's sector 10, sector 1 its sector 11. The memory is read through a pointer to the first
/// word of sector 10: the flash itself on the chip, a RAM array of 2 * kSectorWords words in a host
/// test. Regs: as FlashController's (FlashRegs on the chip: FlashSectors<>, or deduced from the block).
template <class Regs = FlashRegs>
class FlashSectors {
 public:
  static constexpr int kSectors = 2;
  static constexpr std::uint32_t kFirstSector = 10;
  static constexpr std::uint32_t kSectorBytes = 128 * 1024;
  static constexpr std::uint32_t kSectorWords = kSectorBytes / 4;
  static constexpr std::uintptr_t kBase = 0x080C0000u;  ///< sector 10; sector 11 at 0x080E0000

  explicit FlashSectors(Regs& regs, volatile std::uint32_t* memory = hardware_memory(), const FlashPolls& polls = {})
      : controller_(regs, polls), memory_(memory) {}

  std::uint32_t sector_words() const { return kSectorWords; }

  bool erase(int sector) {
    status_ = in_range(sector, 0) ? controller_.erase_sector(kFirstSector + static_cast<std::uint32_t>(sector))
                                  : FlashStatus::kBadAddress;
    return status_ == FlashStatus::kOk;
  }
  bool program(int sector, std::uint32_t word_offset, std::uint32_t value) {
    status_ = in_range(sector, word_offset) ? controller_.program_word(word(sector, word_offset), value)
                                            : FlashStatus::kBadAddress;
    return status_ == FlashStatus::kOk;
  }
  std::uint32_t read(int sector, std::uint32_t word_offset) const {
    return in_range(sector, word_offset) ? *word(sector, word_offset) : persist::kErased;
  }

  /// How the last erase or program ended (its name: flash_status_name).
  FlashStatus last_status() const { return status_; }

  static volatile std::uint32_t* hardware_memory() { return reinterpret_cast<volatile std::uint32_t*>(kBase); }

 private:
  static bool in_range(int sector, std::uint32_t word_offset) {
    return sector >= 0 && sector < kSectors && word_offset < kSectorWords;
  }
  volatile std::uint32_t* word(int sector, std::uint32_t word_offset) const {
    return memory_ + static_cast<std::uint32_t>(sector) * kSectorWords + word_offset;
  }

  FlashController<Regs> controller_;
  volatile std::uint32_t* memory_;
  FlashStatus status_ = FlashStatus::kOk;
};
static_assert(persist::FlashMedium<FlashSectors<>>);
static_assert(FlashSectors<>::kBase + 2 * FlashSectors<>::kSectorBytes == 0x08100000u,
              "the last two sectors of the 1 MiB flash");

}  // namespace stm32f4
