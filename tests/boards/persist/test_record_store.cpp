// The record store (boards/common/persist/record_store.hpp) on the host, over a fake NOR flash in RAM
// (erase sets every word to ones, program ANDs a value in) that can lose power in the middle of any
// operation: a lost erase leaves its sector partly erased (some words erased, the others unchanged or
// garbage), a lost program a torn word (a subset of the bits it clears). A save interrupted at every
// operation, with every kind of tear, leaves the previous record the one loaded (or none, when there
// was none), over several saves in a row, from blank and from garbage flash; the record's layout word
// for word against an encoder written here from the format's description; layouts, sizes, the
// sequence number's wrap, the failures of the medium, and the CRC-32 against known values.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "record_store.hpp"

using namespace persist;

namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::uint16_t kLayout = 7;
constexpr std::uint32_t kWords = 32;  // a small sector: 27 payload words, 108 bytes

/// How an operation cut short by a power loss leaves the flash.
enum class Tear : std::uint8_t {
  kUnchanged,  ///< nothing happened
  kFull,       ///< the operation completed, then the power went
  kHalf,       ///< an erase: the first half of the words erased, the rest unchanged; a program: the lower
               ///< half of the bits it clears
  kAlternate,  ///< an erase: every other word erased, the others garbage; a program: every other bit
  kGarbage,    ///< an erase: the first third erased, the rest garbage; a program: a random subset
};
constexpr Tear kTears[] = {Tear::kUnchanged, Tear::kFull, Tear::kHalf, Tear::kAlternate, Tear::kGarbage};
const char* tear_name(Tear t) {
  const char* names[] = {"unchanged", "full", "half", "alternate", "garbage"};
  return names[static_cast<int>(t)];
}

/// A NOR flash of two sectors in RAM (a persist::FlashMedium). Every erase and program is an
/// operation, counted from 0; lose_power_at(k, tear) cuts operation k short as `tear` says (it returns
/// false) and every later one does nothing and returns false, until revive() (the next boot). A read
/// outside a sector is recorded (the store must never make one).
class FakeFlash {
 public:
  static constexpr int kSectors = 2;
  explicit FakeFlash(std::uint32_t words = kWords) : words_(words) {
    for (auto& s : cells_) s.assign(words, kErased);
  }

  std::uint32_t sector_words() const { return words_; }
  bool erase(int sector) {
    if (!inside(sector, 0)) return false;
    const long op = ops_++;
    if (dead_ || erase_fails) return false;
    std::vector<std::uint32_t>& c = cells_[sector];
    if (op != lose_at_) {
      if (!erase_ignored) c.assign(words_, kErased);
      return true;
    }
    dead_ = true;
    for (std::uint32_t i = 0; i < words_; ++i) {
      switch (tear_) {
        case Tear::kUnchanged:
          break;
        case Tear::kFull:
          c[i] = kErased;
          break;
        case Tear::kHalf:
          if (i < words_ / 2) c[i] = kErased;
          break;
        case Tear::kAlternate:
          c[i] = i % 2 == 0 ? kErased : random();
          break;
        case Tear::kGarbage:
          c[i] = i < words_ / 3 ? kErased : random();
          break;
      }
    }
    return false;
  }
  bool program(int sector, std::uint32_t word_offset, std::uint32_t value) {
    if (!inside(sector, word_offset)) return false;
    const long op = ops_++;
    if (dead_ || program_fails) return false;
    std::uint32_t& w = cells_[sector][word_offset];
    const std::uint32_t clears = w & ~value & ~stuck_bits;  // the bits this program clears
    if (op != lose_at_) {
      w &= ~clears;
      return true;
    }
    dead_ = true;
    w &= ~(clears & torn_mask(clears));
    return false;
  }
  std::uint32_t read(int sector, std::uint32_t word_offset) const {
    if (!inside(sector, word_offset)) return 0;
    return cells_[sector][word_offset];
  }

  void lose_power_at(long op, Tear tear) {
    ops_ = 0;
    lose_at_ = op;
    tear_ = tear;
  }
  void revive() {
    dead_ = false;
    lose_at_ = -1;
  }
  long operations() const { return ops_; }
  void count_from_zero() { ops_ = 0; }
  bool read_outside() const { return outside_; }
  std::vector<std::uint32_t>& sector(int s) { return cells_[s]; }
  void fill_with_garbage() {
    for (auto& s : cells_)
      for (std::uint32_t& w : s) w = random();
  }

  bool erase_fails = false;      ///< every erase reports a failure and does nothing
  bool erase_ignored = false;    ///< every erase reports success and does nothing
  bool program_fails = false;    ///< every program reports a failure and does nothing
  std::uint32_t stuck_bits = 0;  ///< bits no program clears (reported as success)

 private:
  bool inside(int sector, std::uint32_t word_offset) const {
    const bool in = sector >= 0 && sector < kSectors && word_offset < words_;
    if (!in) outside_ = true;
    return in;
  }
  /// Which of the bits a torn program was to clear did clear.
  std::uint32_t torn_mask(std::uint32_t clears) {
    std::uint32_t mask = 0;
    int seen = 0;
    const int half = std::popcount(clears) / 2;
    for (int b = 0; b < 32; ++b) {
      if (!(clears & (1u << b))) continue;
      const bool take =
          tear_ == Tear::kFull || (tear_ == Tear::kHalf && seen < half) || (tear_ == Tear::kAlternate && seen % 2 == 0);
      if (take) mask |= 1u << b;
      ++seen;
    }
    return tear_ == Tear::kGarbage ? random() : mask;
  }
  std::uint32_t random() {  // xorshift32
    rng_ ^= rng_ << 13;
    rng_ ^= rng_ >> 17;
    rng_ ^= rng_ << 5;
    return rng_;
  }

  std::uint32_t words_;
  std::vector<std::uint32_t> cells_[kSectors];
  long ops_ = 0, lose_at_ = -1;
  Tear tear_ = Tear::kUnchanged;
  bool dead_ = false;
  mutable bool outside_ = false;
  std::uint32_t rng_ = 0x2545F491u;
};
static_assert(FlashMedium<FakeFlash>);

/// Not a medium: one sector, or no read.
struct OneSector {
  static constexpr int kSectors = 1;
  std::uint32_t sector_words() const { return 8; }
  bool erase(int) { return true; }
  bool program(int, std::uint32_t, std::uint32_t) { return true; }
  std::uint32_t read(int, std::uint32_t) const { return 0; }
};
struct NoRead {
  static constexpr int kSectors = 2;
  std::uint32_t sector_words() const { return 8; }
  bool erase(int) { return true; }
  bool program(int, std::uint32_t, std::uint32_t) { return true; }
};
static_assert(!FlashMedium<OneSector> && !FlashMedium<NoRead>);

Bytes payload(std::size_t n, int seed) {
  Bytes b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<std::uint8_t>(seed * 37 + i * 11 + 1);
  return b;
}

/// The record of a payload, word for word, encoded here from the format's description (the top of
/// record_store.hpp), not from the store's code.
std::vector<std::uint32_t> record_image(const Bytes& p, std::uint16_t layout, std::uint32_t sequence) {
  std::vector<std::uint32_t> w = {0x4D524150u, layout | static_cast<std::uint32_t>(p.size() << 16), sequence};
  for (std::size_t i = 0; i < p.size(); i += 4) {
    std::uint32_t v = 0;
    for (std::size_t b = 0; b < 4; ++b) v |= std::uint32_t{i + b < p.size() ? p[i + b] : std::uint8_t{0xFF}} << (8 * b);
    w.push_back(v);
  }
  Bytes bytes;
  for (std::uint32_t v : w)
    for (int b = 0; b < 4; ++b) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * b)));
  w.push_back(crc32(bytes.data(), bytes.size()));
  w.push_back(0x600DDA7Au);
  return w;
}

/// Writes a record straight into a sector (erased first), as a save would have left it.
void plant(FakeFlash& f, int sector, const Bytes& p, std::uint16_t layout, std::uint32_t sequence) {
  std::vector<std::uint32_t>& s = f.sector(sector);
  s.assign(s.size(), kErased);
  const std::vector<std::uint32_t> image = record_image(p, layout, sequence);
  std::copy(image.begin(), image.end(), s.begin());
}

/// What the flash loads now: exactly `want` with this sequence number, or (want_any false) no record.
::testing::AssertionResult loads(FakeFlash& f, bool want_any, const Bytes& want = {}, std::uint32_t sequence = 0,
                                 std::uint16_t layout = kLayout) {
  RecordStore<FakeFlash> store(f);
  Bytes got(200, 0xA5);
  const LoadResult r = store.load(got.data(), got.size(), layout);
  if (f.read_outside()) return ::testing::AssertionFailure() << "the store read outside a sector";
  if (!want_any) {
    if (r.loaded()) return ::testing::AssertionFailure() << "loaded a record of sequence " << r.sequence;
    if (got != Bytes(200, 0xA5)) return ::testing::AssertionFailure() << "the buffer was written";
    return ::testing::AssertionSuccess();
  }
  if (!r.loaded()) return ::testing::AssertionFailure() << "nothing loaded: " << status_name(r.status);
  got.resize(r.length);
  if (got != want) return ::testing::AssertionFailure() << "another payload, " << r.length << " bytes";
  if (r.sequence != sequence)
    return ::testing::AssertionFailure() << "sequence " << r.sequence << ", expected " << sequence;
  return ::testing::AssertionSuccess();
}

/// The record a flash holds before a save: none, or this payload with this sequence number.
struct Previous {
  bool any = false;
  Bytes bytes;
  std::uint32_t sequence = 0;
};

/// Saves `next` with the power lost in every operation of the save (each with every tear): after the
/// next boot the flash loads exactly `before` (or nothing), except when only the commit word's program
/// was cut short and it came out whole: then the new record. Then saves `next` for good and checks it
/// loads. Returns what the flash holds now.
Previous interrupt_everywhere(FakeFlash& flash, const Bytes& next, const Previous& before) {
  const std::uint32_t sequence = before.any ? before.sequence + 1 : kFirstSequence;
  FakeFlash probe = flash;
  probe.count_from_zero();
  EXPECT_TRUE(RecordStore<FakeFlash>(probe).save(next.data(), next.size(), kLayout).saved());
  const long ops = probe.operations();
  EXPECT_EQ(ops, 1 + static_cast<long>(record_words(next.size()))) << "one erase, a program a word";
  for (long k = 0; k < ops; ++k) {
    for (Tear tear : kTears) {
      SCOPED_TRACE(::testing::Message() << "power lost in operation " << k << " of " << ops << ", " << tear_name(tear));
      FakeFlash f = flash;
      f.lose_power_at(k, tear);
      EXPECT_FALSE(RecordStore<FakeFlash>(f).save(next.data(), next.size(), kLayout).saved());
      f.revive();
      if (k == ops - 1 && tear == Tear::kFull)
        EXPECT_TRUE(loads(f, true, next, sequence)) << "the commit word is whole: the new record";
      else
        EXPECT_TRUE(loads(f, before.any, before.bytes, before.sequence));
    }
  }
  const SaveResult r = RecordStore<FakeFlash>(flash).save(next.data(), next.size(), kLayout);
  EXPECT_TRUE(r.saved()) << status_name(r.status);
  EXPECT_EQ(r.sequence, sequence);
  EXPECT_TRUE(loads(flash, true, next, sequence));
  return {true, next, sequence};
}

// ------------------------------------------------------------------------------------------ CRC-32

TEST(PersistCrc32, StandardCheckValues) {
  const char* check = "123456789";
  EXPECT_EQ(crc32(reinterpret_cast<const std::uint8_t*>(check), 9), 0xCBF43926u) << "the CRC-32 check value";
  static_assert(crc32(nullptr, 0) == 0u);
  // Bytes 0..255: python3 -c "import zlib; print(hex(zlib.crc32(bytes(range(256)))))" printed 0x29058c73.
  Bytes all(256);
  for (int i = 0; i < 256; ++i) all[i] = static_cast<std::uint8_t>(i);
  EXPECT_EQ(crc32(all.data(), all.size()), 0x29058C73u);
  // A word is its four bytes, least significant first.
  const std::uint8_t le[4] = {0x78, 0x56, 0x34, 0x12};
  EXPECT_EQ(crc32_final(crc32_word(kCrc32Init, 0x12345678u)), crc32(le, 4));
}

// ------------------------------------------------------------------------------------- the format

TEST(PersistRecord, ASavedRecordIsTheDescribedLayoutWordForWord) {
  FakeFlash f;
  const Bytes p = payload(13, 1);  // 13 bytes: the last payload word padded with three 0xFF
  const SaveResult r = RecordStore<FakeFlash>(f).save(p.data(), p.size(), kLayout);
  ASSERT_TRUE(r.saved()) << status_name(r.status);
  EXPECT_EQ(r.sector, 0) << "a blank flash: sector 0 first";
  EXPECT_EQ(r.sequence, kFirstSequence);
  const std::vector<std::uint32_t> image = record_image(p, kLayout, kFirstSequence);
  ASSERT_EQ(image.size(), record_words(13));
  for (std::size_t i = 0; i < f.sector(0).size(); ++i)
    EXPECT_EQ(f.sector(0)[i], i < image.size() ? image[i] : kErased) << "word " << i;
  EXPECT_EQ(f.sector(0)[6] >> 8, 0xFFFFFFu) << "padding";
  char magic[5] = {};
  std::memcpy(magic, &f.sector(0)[0], 4);
  EXPECT_STREQ(magic, "PARM");
  EXPECT_TRUE(loads(f, true, p, kFirstSequence));
}

TEST(PersistRecord, EveryStatusHasItsOwnName) {
  std::vector<std::string> names;
  for (int i = 0; i < kLoadStatuses; ++i) names.push_back(kLoadStatusNames[i]);
  for (int i = 0; i < kSaveStatuses; ++i) names.push_back(kSaveStatusNames[i]);
  for (std::size_t i = 0; i < names.size(); ++i)
    for (std::size_t j = i + 1; j < names.size(); ++j) EXPECT_NE(names[i], names[j]);
  EXPECT_STREQ(status_name(LoadStatus::kLayoutMismatch), "layout_mismatch");
  EXPECT_STREQ(status_name(SaveStatus::kVerifyFailed), "verify_failed");
  EXPECT_EQ(kLoadStatuses, 4);
  EXPECT_EQ(kSaveStatuses, 5);
}

TEST(PersistRecord, TheFakeFlashIsNor) {
  FakeFlash f;
  EXPECT_TRUE(f.program(0, 3, 0xF0F0F0F0u));
  EXPECT_TRUE(f.program(0, 3, 0x0FF00FFFu));
  EXPECT_EQ(f.read(0, 3), 0x00F000F0u) << "programming only clears bits";
  EXPECT_TRUE(f.erase(0));
  EXPECT_EQ(f.read(0, 3), kErased);
  // Torn programs of 0x0000FF00 over an erased word: 24 bits to clear.
  const std::pair<Tear, std::uint32_t> torn[] = {{Tear::kUnchanged, 0xFFFFFFFFu},
                                                 {Tear::kFull, 0x0000FF00u},
                                                 {Tear::kHalf, 0xFFF0FF00u},
                                                 {Tear::kAlternate, 0xAAAAFFAAu}};
  for (const auto& [tear, want] : torn) {
    FakeFlash g;
    g.lose_power_at(0, tear);
    EXPECT_FALSE(g.program(1, 0, 0x0000FF00u));
    EXPECT_EQ(g.read(1, 0), want) << tear_name(tear);
    EXPECT_FALSE(g.program(1, 1, 0u)) << "no power";
    EXPECT_EQ(g.read(1, 1), kErased);
  }
}

// ---------------------------------------------------------------------------------- load and save

TEST(PersistStore, BlankFlashLoadsNone) {
  FakeFlash f;
  Bytes buf(16, 0x11);
  const LoadResult r = RecordStore<FakeFlash>(f).load(buf.data(), buf.size(), kLayout);
  EXPECT_EQ(r.status, LoadStatus::kNone);
  EXPECT_STREQ(status_name(r.status), "none");
  EXPECT_EQ(buf, Bytes(16, 0x11)) << "the caller's defaults stay";
}

TEST(PersistStore, GarbageFlashLoadsNoneAndTakesASave) {
  FakeFlash f;
  f.fill_with_garbage();
  EXPECT_TRUE(loads(f, false));
  interrupt_everywhere(f, payload(9, 2), {});
  EXPECT_FALSE(f.read_outside());
}

TEST(PersistStore, SavesAlternateBetweenTheSectorsWithRisingSequenceNumbers) {
  FakeFlash f;
  RecordStore<FakeFlash> store(f);
  for (int i = 0; i < 6; ++i) {
    const Bytes p = payload(5 + 3 * static_cast<std::size_t>(i), i);
    const SaveResult r = store.save(p.data(), p.size(), kLayout);
    ASSERT_TRUE(r.saved()) << status_name(r.status);
    EXPECT_EQ(r.sector, i % 2);
    EXPECT_EQ(r.sequence, kFirstSequence + static_cast<std::uint32_t>(i));
    EXPECT_TRUE(loads(f, true, p, r.sequence));
  }
}

TEST(PersistStore, PowerLossAtEveryStepOfTheFirstSaveLeavesNoRecord) {
  FakeFlash f;
  interrupt_everywhere(f, payload(13, 3), {});
}

TEST(PersistStore, PowerLossAtEveryStepOfEverySaveLeavesThePreviousRecord) {
  FakeFlash f;
  Previous held = interrupt_everywhere(f, payload(13, 4), {});  // A
  // B, then five more: each interrupted everywhere, over both sectors in turn, with payloads of
  // every padding (0 to 3 bytes), an empty one, and one that fills the sector.
  const std::size_t sizes[] = {7, 0, 40, 1, 2, 108};
  for (std::size_t i = 0; i < std::size(sizes); ++i) {
    SCOPED_TRACE(::testing::Message() << "save " << i + 2 << ", " << sizes[i] << " bytes");
    held = interrupt_everywhere(f, payload(sizes[i], static_cast<int>(10 + i)), held);
  }
  EXPECT_EQ(held.sequence, kFirstSequence + 6);
}

TEST(PersistStore, ASaveAfterAnInterruptedOneTakesTheNextSequenceNumber) {
  FakeFlash f;
  const Bytes a = payload(10, 5), b = payload(10, 6), c = payload(10, 7);
  ASSERT_TRUE(RecordStore<FakeFlash>(f).save(a.data(), a.size(), kLayout).saved());
  f.lose_power_at(4, Tear::kHalf);  // in the middle of B's payload
  EXPECT_EQ(RecordStore<FakeFlash>(f).save(b.data(), b.size(), kLayout).status, SaveStatus::kProgramFailed);
  f.revive();
  EXPECT_TRUE(loads(f, true, a, kFirstSequence));
  const SaveResult r = RecordStore<FakeFlash>(f).save(c.data(), c.size(), kLayout);
  ASSERT_TRUE(r.saved());
  EXPECT_EQ(r.sector, 1) << "the torn sector again: A's is never touched";
  EXPECT_TRUE(loads(f, true, c, kFirstSequence + 1));
}

TEST(PersistStore, OnlyAnotherLayoutIsAMismatch) {
  FakeFlash f;
  const Bytes old_table = payload(12, 8), new_table = payload(20, 9);
  ASSERT_TRUE(RecordStore<FakeFlash>(f).save(old_table.data(), old_table.size(), 3).saved());
  Bytes buf(64, 0);
  LoadResult r = RecordStore<FakeFlash>(f).load(buf.data(), buf.size(), 4);
  EXPECT_EQ(r.status, LoadStatus::kLayoutMismatch);
  EXPECT_STREQ(status_name(r.status), "layout_mismatch");
  EXPECT_EQ(buf, Bytes(64, 0));
  // The new layout's first save keeps the old record (the other sector): each layout loads its own.
  ASSERT_TRUE(RecordStore<FakeFlash>(f).save(new_table.data(), new_table.size(), 4).saved());
  EXPECT_TRUE(loads(f, true, new_table, kFirstSequence + 1, 4));
  EXPECT_TRUE(loads(f, true, old_table, kFirstSequence, 3));
  r = RecordStore<FakeFlash>(f).load(buf.data(), buf.size(), 5);
  EXPECT_EQ(r.status, LoadStatus::kLayoutMismatch);
}

TEST(PersistStore, APayloadTooLargeIsRefusedWithoutTouchingTheFlash) {
  FakeFlash f;
  RecordStore<FakeFlash> store(f);
  EXPECT_EQ(store.max_payload(), (kWords - kOverheadWords) * 4);
  const Bytes a = payload(20, 1), big = payload(store.max_payload() + 1, 2);
  ASSERT_TRUE(store.save(a.data(), a.size(), kLayout).saved());
  f.count_from_zero();
  const SaveResult r = store.save(big.data(), big.size(), kLayout);
  EXPECT_EQ(r.status, SaveStatus::kPayloadTooLarge);
  EXPECT_STREQ(status_name(r.status), "payload_too_large");
  EXPECT_EQ(f.operations(), 0) << "neither erased nor programmed";
  EXPECT_TRUE(loads(f, true, a, kFirstSequence));
  // A buffer too small for the record of this layout: too_large, the buffer untouched.
  Bytes small(19, 0x22);
  const LoadResult l = store.load(small.data(), small.size(), kLayout);
  EXPECT_EQ(l.status, LoadStatus::kTooLarge);
  EXPECT_EQ(small, Bytes(19, 0x22));
  // The length is 16 bits: a sector of 2^16 words still takes at most 65535 bytes.
  FakeFlash large(1u << 16);
  EXPECT_EQ(RecordStore<FakeFlash>(large).max_payload(), 0xFFFFu);
  const Bytes huge = payload(0x10000, 3);
  EXPECT_EQ(RecordStore<FakeFlash>(large).save(huge.data(), huge.size(), kLayout).status, SaveStatus::kPayloadTooLarge);
}

TEST(PersistStore, TheSequenceNumberWrapsAround) {
  FakeFlash f;
  const Bytes a = payload(8, 1);
  plant(f, 0, a, kLayout, 0xFFFFFFFEu);
  EXPECT_TRUE(loads(f, true, a, 0xFFFFFFFEu)) << "a planted record loads: the format is the described one";
  Previous held{true, a, 0xFFFFFFFEu};
  // 0xFFFFFFFF, then 0 (newer than 0xFFFFFFFF), then 1, each interrupted everywhere.
  for (std::uint32_t want : {0xFFFFFFFFu, 0u, 1u}) {
    held = interrupt_everywhere(f, payload(8, static_cast<int>(want & 0xFF) + 2), held);
    EXPECT_EQ(held.sequence, want);
  }
  // Either sector may hold the newer one.
  for (int newer_sector : {0, 1}) {
    FakeFlash g;
    const Bytes older = payload(4, 5), newest = payload(4, 6);
    plant(g, 1 - newer_sector, older, kLayout, 0xFFFFFFFFu);
    plant(g, newer_sector, newest, kLayout, 0u);
    EXPECT_TRUE(loads(g, true, newest, 0u)) << "newer in sector " << newer_sector;
  }
}

TEST(PersistStore, ADamagedNewestRecordFallsBackToThePreviousOne) {
  const Bytes a = payload(16, 1), b = payload(16, 2);
  const auto two_records = [&] {
    FakeFlash f;
    plant(f, 0, a, kLayout, 5);
    plant(f, 1, b, kLayout, 6);
    return f;
  };
  FakeFlash f = two_records();
  EXPECT_TRUE(loads(f, true, b, 6));
  f.sector(1)[4] &= ~0x10u;  // one payload bit: the CRC fails
  EXPECT_TRUE(loads(f, true, a, 5));
  f = two_records();
  f.sector(1)[record_words(16) - 1] = kErased;  // no commit word
  EXPECT_TRUE(loads(f, true, a, 5));
  f = two_records();
  f.sector(1)[0] = 0;  // no magic
  EXPECT_TRUE(loads(f, true, a, 5));
  f = two_records();
  f.sector(1)[1] = header_word(kLayout, 200);  // a length past the sector
  EXPECT_TRUE(loads(f, true, a, 5));
  EXPECT_FALSE(f.read_outside());
}

TEST(PersistStore, TheMediumsFailuresAreNamedAndKeepThePreviousRecord) {
  const Bytes a = payload(10, 1), b = payload(10, 2);
  FakeFlash base;
  ASSERT_TRUE(RecordStore<FakeFlash>(base).save(a.data(), a.size(), kLayout).saved());
  const auto save_b = [&](FakeFlash& f) { return RecordStore<FakeFlash>(f).save(b.data(), b.size(), kLayout); };

  FakeFlash f = base;
  f.erase_fails = true;
  EXPECT_EQ(save_b(f).status, SaveStatus::kEraseFailed);
  f = base;
  f.sector(1)[2] = 0x1234u;  // leftovers the erase does not remove
  f.erase_ignored = true;
  EXPECT_STREQ(status_name(save_b(f).status), "erase_failed") << "the sector does not read back erased";
  EXPECT_TRUE(loads(f, true, a, kFirstSequence));
  f = base;
  f.program_fails = true;
  EXPECT_STREQ(status_name(save_b(f).status), "program_failed");
  EXPECT_TRUE(loads(f, true, a, kFirstSequence));
  f = base;
  f.stuck_bits = 1u << 9;  // a bit that will not program: the read-back catches it before the commit
  const SaveResult r = save_b(f);
  EXPECT_STREQ(status_name(r.status), "verify_failed");
  EXPECT_EQ(f.sector(1)[record_words(10) - 1], kErased) << "never committed";
  f.stuck_bits = 0;
  EXPECT_TRUE(loads(f, true, a, kFirstSequence));
}

}  // namespace
