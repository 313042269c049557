// Shared helpers of the libFuzzer targets: an invariant check that aborts (libFuzzer then saves the
// input as a crash), and a reader that takes values from the fuzz input, zeros once it runs out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#define FUZZ_CHECK(cond)                                                                  \
  do {                                                                                    \
    if (!(cond)) {                                                                        \
      std::fprintf(stderr, "%s:%d: invariant violated: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (0)

namespace fuzz {

/// a + d modulo 2^32, as an encoder counter wraps (no signed overflow).
inline std::int32_t wrap_add(std::int32_t a, std::int32_t d) {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) + static_cast<std::uint32_t>(d));
}

class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : p_(data), n_(size) {}
  bool empty() const { return n_ == 0; }
  std::size_t left() const { return n_; }
  std::uint8_t u8() {
    if (n_ == 0) return 0;
    --n_;
    return *p_++;
  }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(u16()) | (static_cast<std::uint32_t>(u16()) << 16); }
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  /// Up to max bytes (fewer at the end of the input); returns how many were taken.
  std::size_t bytes(std::uint8_t* out, std::size_t max) {
    const std::size_t k = max < n_ ? max : n_;
    if (k) std::memcpy(out, p_, k);
    p_ += k;
    n_ -= k;
    return k;
  }
  /// The rest of the input.
  const std::uint8_t* rest(std::size_t& size) {
    size = n_;
    const std::uint8_t* r = p_;
    p_ += n_;
    n_ = 0;
    return r;
  }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
};

}  // namespace fuzz
