// A NOR flash of two sectors kept in a host file through semihosting: the QEMU images' parameter store when their
// command line names one (pil_firmware.cpp, "params=PATH"; osc_sim --qemu --param-file). The MPS2 boards' QEMU
// models no flash a program can erase and write, and semihosting reaches the host's files (QEMU's
// -semihosting-config target=native), so the file stands for the flash: a restarted image reads what the last one
// saved, a power cycle. The file is the same image as the virtual board's (host_sim/file_flash.hpp: two sectors
// of persist::kImageSectorWords words, each little-endian), so a store saved by one is loaded by the other.
//
// The medium of persist::FlashParamStore (boards/common/param_store/param_store.hpp, over persist::RecordStore):
// erase sets a sector's words to 0xFFFFFFFF, program clears bits (old & value), each written through at once. The
// host creates the file (osc_sim checks its size first); open() here takes it only when it has the image's size.
#pragma once

#include <cstdint>

#include "cortex_m.hpp"

namespace board {

template <std::uint32_t kWords>
class SemihostFlash {
 public:
  static constexpr int kSectors = 2;

  /// The file `path` (n bytes), opened for reading and writing ("r+b"): true when it is open and has the size of
  /// two sectors.
  bool open(const char* path, std::uint32_t n) {
    handle_ = cortex_m::semihost::open(path, n, 3);
    if (handle_ >= 0 && cortex_m::semihost::file_length(handle_) == static_cast<int>(kSectors * kWords * 4))
      return true;
    handle_ = -1;
    return false;
  }
  std::uint32_t sector_words() const { return kWords; }
  bool erase(int sector) {
    std::uint8_t ones[64];
    for (std::uint8_t& b : ones) b = 0xFF;
    for (std::uint32_t at = 0; at < kWords * 4; at += sizeof ones)
      if (!cortex_m::semihost::seek(handle_, offset(sector, 0) + at) ||
          cortex_m::semihost::write(handle_, ones, static_cast<int>(sizeof ones)) != 0)
        return false;
    return true;
  }
  bool program(int sector, std::uint32_t word, std::uint32_t value) {
    if (word >= kWords) return false;
    const std::uint32_t w = read(sector, word) & value;
    const std::uint8_t b[4] = {static_cast<std::uint8_t>(w), static_cast<std::uint8_t>(w >> 8),
                               static_cast<std::uint8_t>(w >> 16), static_cast<std::uint8_t>(w >> 24)};
    return cortex_m::semihost::seek(handle_, offset(sector, word)) && cortex_m::semihost::write(handle_, b, 4) == 0;
  }
  /// Word `word` of `sector`; 0 when it cannot be read (no record checks with it).
  std::uint32_t read(int sector, std::uint32_t word) const {
    std::uint8_t b[4];
    if (word >= kWords || !cortex_m::semihost::seek(handle_, offset(sector, word)) ||
        cortex_m::semihost::read(handle_, b, 4) != 0)
      return 0;
    return std::uint32_t{b[0]} | std::uint32_t{b[1]} << 8 | std::uint32_t{b[2]} << 16 | std::uint32_t{b[3]} << 24;
  }

 private:
  static std::uint32_t offset(int sector, std::uint32_t word) {
    return (static_cast<std::uint32_t>(sector) * kWords + word) * 4;
  }
  int handle_ = -1;
};

}  // namespace board
