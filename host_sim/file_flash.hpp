// A NOR flash of two sectors kept in a file: the virtual board's parameter store (osc_sim --param-file), the
// medium of persist::FlashParamStore (boards/common/param_store/param_store.hpp) as a board's flash sectors are.
// The file is the image of the two sectors, every word little-endian as a Cortex-M stores it: what a board's
// flash would hold, so that a restarted simulator finds what the last one saved (issue 57, a power cycle).
//
// NOR semantics as persist::FlashMedium asks: erase sets a sector's words to 0xFFFFFFFF, program clears bits
// (old & value). Each erase or program is written through to the file at once (pwrite), so a simulator killed
// between two writes leaves what a board losing power there would: the record store's protocol keeps the previous
// record loadable. A file that is not an image of this size is refused by name, and nothing is written to it.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace sim {

class FileFlash {
 public:
  static constexpr int kSectors = 2;

  explicit FileFlash(std::uint32_t sector_words)
      : words_(sector_words), data_(2 * std::size_t{sector_words}, kErased) {}
  ~FileFlash() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileFlash(const FileFlash&) = delete;
  FileFlash& operator=(const FileFlash&) = delete;

  /// Opens `path`: an image of this size is read; a missing file is created, erased (every byte 0xFF). Anything
  /// else (another size, unreadable) is a named error in err, and the file is left as it was.
  bool open(const std::string& path, std::string& err) {
    path_ = path;
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT, 0644);
    if (fd_ < 0) return err = path + ": " + std::strerror(errno), false;
    const off_t size = ::lseek(fd_, 0, SEEK_END);
    const off_t want = static_cast<off_t>(data_.size() * 4);
    if (size == 0) return write_all(err);
    if (size != want)
      return err = path + ": not a parameter store's image (" + std::to_string(size) + " bytes; an image is " +
                   std::to_string(want) + ")",
             false;
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(want));
    if (::pread(fd_, bytes.data(), bytes.size(), 0) != static_cast<ssize_t>(bytes.size()))
      return err = path + ": cannot read: " + std::strerror(errno), false;
    for (std::size_t i = 0; i < data_.size(); ++i)
      data_[i] = std::uint32_t{bytes[4 * i]} | std::uint32_t{bytes[4 * i + 1]} << 8 |
                 std::uint32_t{bytes[4 * i + 2]} << 16 | std::uint32_t{bytes[4 * i + 3]} << 24;
    return true;
  }

  std::uint32_t sector_words() const { return words_; }
  bool erase(int sector) {
    for (std::uint32_t i = 0; i < words_; ++i) data_[at(sector, i)] = kErased;
    for (std::uint32_t i = 0; i < words_; ++i)
      if (!put(sector, i)) return false;
    return true;
  }
  bool program(int sector, std::uint32_t offset, std::uint32_t value) {
    if (offset >= words_) return false;
    data_[at(sector, offset)] &= value;
    return put(sector, offset);
  }
  std::uint32_t read(int sector, std::uint32_t offset) const {
    return offset < words_ ? data_[at(sector, offset)] : kErased;
  }
  const std::string& path() const { return path_; }

 private:
  static constexpr std::uint32_t kErased = 0xFFFFFFFFu;
  std::size_t at(int sector, std::uint32_t offset) const { return static_cast<std::size_t>(sector) * words_ + offset; }
  /// Word `offset` of `sector` into the file.
  bool put(int sector, std::uint32_t offset) {
    const std::uint32_t w = data_[at(sector, offset)];
    const std::uint8_t b[4] = {static_cast<std::uint8_t>(w), static_cast<std::uint8_t>(w >> 8),
                               static_cast<std::uint8_t>(w >> 16), static_cast<std::uint8_t>(w >> 24)};
    return ::pwrite(fd_, b, 4, static_cast<off_t>(at(sector, offset) * 4)) == 4;
  }
  /// The whole image into a new (empty) file.
  bool write_all(std::string& err) {
    for (int s = 0; s < kSectors; ++s)
      for (std::uint32_t i = 0; i < words_; ++i)
        if (!put(s, i)) return err = path_ + ": cannot write: " + std::strerror(errno), false;
    return true;
  }

  std::uint32_t words_;
  std::vector<std::uint32_t> data_;
  int fd_ = -1;
  std::string path_;
};

}  // namespace sim
