// A record store on NOR flash: the newest of an opaque payload of bytes (the parameter table, which
// this header does not know) kept in one of two erase sectors, so that a power loss at any point of
// a save leaves the previous record loadable. Free of any chip: it runs over the concept FlashMedium
// (two sectors of 32-bit words: erase, program, read), which a chip's flash driver satisfies
// (stm32f4::FlashSectors, boards/common/stm32f4/flash.hpp) and a test's fake flash in RAM too
// (tests/boards/persist/test_record_store.cpp). No heap, no exceptions, nothing cached between calls.
//
// A record, from word 0 of its sector (every word little-endian, as the Cortex-M stores it):
//
//   word 0          kMagic
//   word 1          layout version (bits 15..0) | payload length in bytes (bits 31..16)
//   word 2          sequence number
//   words 3..3+P-1  the payload, 4 bytes a word, the last word padded with 0xFF (P = ceil(length / 4))
//   word 3+P        CRC-32 (IEEE 802.3) over the bytes of words 0..3+P-1
//   word 4+P        kCommit, programmed last
//
// A record is valid when its magic, its length (the record fits in the sector), its commit word and
// its CRC all check. A sector holds one record. A save erases the sector that does not hold the
// newest valid record, programs the record there in word order with the commit word last, and reads
// it back. Until the commit word is whole the new record is invalid, and the other sector, which the
// save never touches, still holds the previous one. Once it is whole, the new record is the newer
// of the two by sequence number (serial-number arithmetic: newer means a positive 32-bit signed
// difference, so the count may wrap from 0xFFFFFFFF to 0).
//
// A torn word (power lost while it was programmed: some of its bits cleared, some not) cannot
// complete a record: the commit word is compared whole, and a torn body word fails the CRC. A lost
// erase leaves the target sector partly erased: whatever it holds is an older record, garbage or
// nothing, and never newer than the previous record, which is in the other sector.
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>

namespace persist {

/// What the store needs from the flash: kSectors (two) erase sectors of sector_words() 32-bit words
/// each, with NOR semantics: erase sets every word of a sector to 0xFFFFFFFF, program can only clear
/// bits (a word becomes old & value). erase and program return false when the hardware reports a
/// failure; read returns what the sector holds.
template <class F>
concept FlashMedium = requires(F& f, const F& cf, int sector, std::uint32_t word_offset, std::uint32_t value) {
  { F::kSectors } -> std::convertible_to<int>;
  { cf.sector_words() } -> std::convertible_to<std::uint32_t>;
  { f.erase(sector) } -> std::same_as<bool>;
  { f.program(sector, word_offset, value) } -> std::same_as<bool>;
  { cf.read(sector, word_offset) } -> std::same_as<std::uint32_t>;
}
&&F::kSectors == 2;

// ---------------------------------------------------------------------------------------- CRC-32

/// CRC-32 of IEEE 802.3 (zlib's, Ethernet's): reflected, polynomial 0xEDB88320, initial value and
/// final xor 0xFFFFFFFF. Computed a nibble at a time from a table of 16 words (64 bytes of flash).
namespace detail {
struct Crc32Table {
  std::uint32_t v[16];
};
constexpr Crc32Table crc32_nibble_table() {
  Crc32Table t{};
  for (std::uint32_t i = 0; i < 16; ++i) {
    std::uint32_t c = i;
    for (int b = 0; b < 4; ++b) c = (c & 1u) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
    t.v[i] = c;
  }
  return t;
}
inline constexpr Crc32Table kCrc32Table = crc32_nibble_table();
}  // namespace detail

inline constexpr std::uint32_t kCrc32Init = 0xFFFFFFFFu;

/// One byte into a running CRC (start from kCrc32Init, finish with crc32_final).
constexpr std::uint32_t crc32_byte(std::uint32_t crc, std::uint8_t byte) {
  crc ^= byte;
  crc = (crc >> 4) ^ detail::kCrc32Table.v[crc & 0xFu];
  return (crc >> 4) ^ detail::kCrc32Table.v[crc & 0xFu];
}
/// A word's four bytes, least significant first (the word's bytes in memory on a little-endian core).
constexpr std::uint32_t crc32_word(std::uint32_t crc, std::uint32_t word) {
  for (int i = 0; i < 4; ++i) crc = crc32_byte(crc, static_cast<std::uint8_t>(word >> (8 * i)));
  return crc;
}
constexpr std::uint32_t crc32_final(std::uint32_t crc) { return crc ^ 0xFFFFFFFFu; }
/// The CRC-32 of n bytes.
constexpr std::uint32_t crc32(const std::uint8_t* p, std::size_t n) {
  std::uint32_t crc = kCrc32Init;
  for (std::size_t i = 0; i < n; ++i) crc = crc32_byte(crc, p[i]);
  return crc32_final(crc);
}

// ---------------------------------------------------------------------------------- record layout

inline constexpr std::uint32_t kMagic = 0x4D524150u;   ///< the bytes "PARM" in memory order
inline constexpr std::uint32_t kCommit = 0x600DDA7Au;  ///< the last word: the record is whole
inline constexpr std::uint32_t kErased = 0xFFFFFFFFu;  ///< an erased word
inline constexpr std::uint32_t kMagicWord = 0, kHeaderWord = 1, kSequenceWord = 2, kPayloadWord = 3;
/// Header, CRC and commit words around the payload.
inline constexpr std::uint32_t kOverheadWords = 5;
/// The sequence number of the first record on a flash without a valid one.
inline constexpr std::uint32_t kFirstSequence = 1;

constexpr std::uint32_t payload_words(std::size_t bytes) { return static_cast<std::uint32_t>((bytes + 3) / 4); }
constexpr std::uint32_t record_words(std::size_t bytes) { return kOverheadWords + payload_words(bytes); }
constexpr std::uint32_t header_word(std::uint16_t layout, std::size_t bytes) {
  return layout | (static_cast<std::uint32_t>(bytes) << 16);
}
/// Serial-number arithmetic (RFC 1982 in 32 bits): a is newer than b when a - b, as a signed
/// difference, is positive. 0 is newer than 0xFFFFFFFF.
constexpr bool newer(std::uint32_t a, std::uint32_t b) { return static_cast<std::int32_t>(a - b) > 0; }

// --------------------------------------------------------------------------------------- statuses

// X(Name, name, what it means): the statuses of load and save, with the names a boot prints.
#define PERSIST_LOAD_STATUS_LIST(X)                                                                    \
  X(Loaded, "loaded", "the newest valid record of this layout was copied into the payload")            \
  X(None, "none", "no valid record in either sector (blank or garbage flash): use the defaults")       \
  X(LayoutMismatch, "layout_mismatch", "valid records, none of this layout version: use the defaults") \
  X(TooLarge, "too_large", "valid records of this layout, none whose payload fits the buffer: use the defaults")

#define PERSIST_SAVE_STATUS_LIST(X)                                                                              \
  X(Saved, "saved", "the record was written, committed and read back: it is the one load returns")               \
  X(PayloadTooLarge, "payload_too_large", "the payload does not fit a sector (or 65535 bytes): nothing written") \
  X(EraseFailed, "erase_failed", "the erase failed or the sector did not read back erased")                      \
  X(ProgramFailed, "program_failed", "the flash failed to program a word")                                       \
  X(VerifyFailed, "verify_failed", "a word read back differs from the one programmed")

#define PERSIST_X_ENUMERATOR(Name, name, doc) k##Name,
#define PERSIST_X_NAME(Name, name, doc) name,
#define PERSIST_X_COUNT(Name, name, doc) +1
enum class LoadStatus : std::uint8_t { PERSIST_LOAD_STATUS_LIST(PERSIST_X_ENUMERATOR) };
enum class SaveStatus : std::uint8_t { PERSIST_SAVE_STATUS_LIST(PERSIST_X_ENUMERATOR) };
inline constexpr int kLoadStatuses = 0 PERSIST_LOAD_STATUS_LIST(PERSIST_X_COUNT);
inline constexpr int kSaveStatuses = 0 PERSIST_SAVE_STATUS_LIST(PERSIST_X_COUNT);
/// Names in LoadStatus and SaveStatus order.
inline constexpr const char* kLoadStatusNames[kLoadStatuses] = {PERSIST_LOAD_STATUS_LIST(PERSIST_X_NAME)};
inline constexpr const char* kSaveStatusNames[kSaveStatuses] = {PERSIST_SAVE_STATUS_LIST(PERSIST_X_NAME)};
#undef PERSIST_X_ENUMERATOR
#undef PERSIST_X_NAME
#undef PERSIST_X_COUNT

constexpr const char* status_name(LoadStatus s) { return kLoadStatusNames[static_cast<int>(s)]; }
constexpr const char* status_name(SaveStatus s) { return kSaveStatusNames[static_cast<int>(s)]; }

struct LoadResult {
  LoadStatus status;
  std::uint32_t sequence;  ///< kLoaded: the record's sequence number
  std::uint16_t length;    ///< kLoaded: the payload's length in bytes
  int sector;              ///< kLoaded: the sector it came from; else -1
  bool loaded() const { return status == LoadStatus::kLoaded; }
};

struct SaveResult {
  SaveStatus status;
  std::uint32_t sequence;  ///< the sequence number the record has (or would have had)
  int sector;              ///< the sector written (or being written); -1 when none was touched
  bool saved() const { return status == SaveStatus::kSaved; }
};

// ------------------------------------------------------------------------------------------ store

template <FlashMedium F>
class RecordStore {
 public:
  explicit RecordStore(F& flash) : flash_(flash) {}

  /// The largest payload a record can carry: its length is 16 bits and the record fits a sector.
  std::size_t max_payload() const {
    const std::uint32_t words = flash_.sector_words();
    if (words <= kOverheadWords) return 0;
    const std::size_t bytes = std::size_t{words - kOverheadWords} * 4;
    return bytes < 0xFFFFu ? bytes : 0xFFFFu;
  }

  /// Copies the newest valid record of this layout whose payload fits `capacity` bytes into
  /// `payload` (untouched unless kLoaded). The result says why nothing was loaded otherwise.
  LoadResult load(std::uint8_t* payload, std::size_t capacity, std::uint16_t layout) const {
    bool any_valid = false, any_too_large = false;
    int best = -1;
    Header h[F::kSectors];
    for (int s = 0; s < F::kSectors; ++s) {
      h[s] = parse(s);
      if (!h[s].valid) continue;
      any_valid = true;
      if (h[s].layout != layout) continue;
      if (h[s].length > capacity) {
        any_too_large = true;
        continue;
      }
      if (best < 0 || newer(h[s].sequence, h[best].sequence)) best = s;
    }
    if (best < 0) {
      const LoadStatus why = any_too_large ? LoadStatus::kTooLarge
                             : any_valid   ? LoadStatus::kLayoutMismatch
                                           : LoadStatus::kNone;
      return {why, 0, 0, -1};
    }
    for (std::uint32_t i = 0; i < h[best].length; ++i)
      payload[i] = static_cast<std::uint8_t>(flash_.read(best, kPayloadWord + i / 4) >> (8 * (i % 4)));
    return {LoadStatus::kLoaded, h[best].sequence, h[best].length, best};
  }

  /// Writes a record of n bytes as the newest one: into the sector that does not hold the newest
  /// valid record, with the next sequence number. The order (erase, header and payload and CRC, read
  /// back, commit word, read back) is what keeps the previous record loadable whenever the power goes
  /// (the top of this file). The record kept is the newest of any layout: after a change of layout
  /// version, the first save of the new layout replaces the older record, not the newest.
  SaveResult save(const std::uint8_t* payload, std::size_t n, std::uint16_t layout) {
    int newest = -1;
    std::uint32_t newest_sequence = 0;
    for (int s = 0; s < F::kSectors; ++s) {
      const Header h = parse(s);
      if (h.valid && (newest < 0 || newer(h.sequence, newest_sequence))) {
        newest = s;
        newest_sequence = h.sequence;
      }
    }
    // The next number wraps from 0xFFFFFFFF to 0, which is newer by serial arithmetic.
    const std::uint32_t sequence = newest < 0 ? kFirstSequence : newest_sequence + 1;
    if (n > max_payload()) return {SaveStatus::kPayloadTooLarge, sequence, -1};
    const int target = newest == 0 ? 1 : 0;
    const std::uint32_t crc_at = kPayloadWord + payload_words(n), commit_at = crc_at + 1;

    if (!flash_.erase(target)) return {SaveStatus::kEraseFailed, sequence, target};
    for (std::uint32_t i = 0; i <= commit_at; ++i)
      if (flash_.read(target, i) != kErased) return {SaveStatus::kEraseFailed, sequence, target};

    // Header, payload and CRC in word order; the CRC runs over exactly the words programmed.
    std::uint32_t crc = kCrc32Init;
    for (std::uint32_t i = 0; i < crc_at; ++i) {
      const std::uint32_t w = body_word(i, payload, n, layout, sequence);
      crc = crc32_word(crc, w);
      if (!flash_.program(target, i, w)) return {SaveStatus::kProgramFailed, sequence, target};
    }
    crc = crc32_final(crc);
    if (!flash_.program(target, crc_at, crc)) return {SaveStatus::kProgramFailed, sequence, target};
    // Read back before the commit: a record whose body did not program as written is never
    // committed (it stays invalid, and the previous record stays the newest).
    for (std::uint32_t i = 0; i < crc_at; ++i)
      if (flash_.read(target, i) != body_word(i, payload, n, layout, sequence))
        return {SaveStatus::kVerifyFailed, sequence, target};
    if (flash_.read(target, crc_at) != crc) return {SaveStatus::kVerifyFailed, sequence, target};

    if (!flash_.program(target, commit_at, kCommit)) return {SaveStatus::kProgramFailed, sequence, target};
    const Header h = parse(target);
    if (!h.valid || h.sequence != sequence || h.layout != layout || h.length != n)
      return {SaveStatus::kVerifyFailed, sequence, target};
    return {SaveStatus::kSaved, sequence, target};
  }

 private:
  struct Header {
    bool valid = false;
    std::uint16_t layout = 0, length = 0;
    std::uint32_t sequence = 0;
  };

  /// Word i (< the CRC's) of the record of this payload.
  static std::uint32_t body_word(std::uint32_t i, const std::uint8_t* payload, std::size_t n, std::uint16_t layout,
                                 std::uint32_t sequence) {
    if (i == kMagicWord) return kMagic;
    if (i == kHeaderWord) return header_word(layout, n);
    if (i == kSequenceWord) return sequence;
    std::uint32_t w = 0;
    for (std::size_t b = 0; b < 4; ++b) {
      const std::size_t at = std::size_t{i - kPayloadWord} * 4 + b;
      w |= std::uint32_t{at < n ? payload[at] : std::uint8_t{0xFF}} << (8 * b);
    }
    return w;
  }

  /// The record at the start of a sector, checked: magic, a length that fits, the commit word, the
  /// CRC. Reads only words inside the sector.
  Header parse(int sector) const {
    Header h;
    if (flash_.read(sector, kMagicWord) != kMagic) return h;
    const std::uint32_t header = flash_.read(sector, kHeaderWord);
    const std::uint16_t length = static_cast<std::uint16_t>(header >> 16);
    if (length > max_payload()) return h;
    const std::uint32_t crc_at = kPayloadWord + payload_words(length);
    if (flash_.read(sector, crc_at + 1) != kCommit) return h;
    std::uint32_t crc = kCrc32Init;
    for (std::uint32_t i = 0; i < crc_at; ++i) crc = crc32_word(crc, flash_.read(sector, i));
    if (crc32_final(crc) != flash_.read(sector, crc_at)) return h;
    h.valid = true;
    h.layout = static_cast<std::uint16_t>(header & 0xFFFFu);
    h.length = length;
    h.sequence = flash_.read(sector, kSequenceWord);
    return h;
  }

  F& flash_;
};

}  // namespace persist
