// printf-free text lines (newlib's printf would bring in malloc), emitted over semihosting or taken
// as text for another output.
#pragma once

#include <cstdint>

#include "cortex_m.hpp"

namespace cortex_m::text {

class Line {
 public:
  Line& str(const char* s) {
    while (*s && n_ < kMax - 1) buf_[n_++] = *s++;
    return *this;
  }
  Line& u32(std::uint32_t v) {
    char tmp[11];
    int k = 0;
    do {
      tmp[k++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v);
    while (k && n_ < kMax - 1) buf_[n_++] = tmp[--k];
    return *this;
  }
  Line& i32(std::int32_t v) {
    if (v < 0) {
      str("-");
      return u32(static_cast<std::uint32_t>(-(v + 1)) + 1u);
    }
    return u32(static_cast<std::uint32_t>(v));
  }
  /// Fixed-point decimal with `decimals` digits.
  Line& fix(float v, int decimals) {
    if (!(v == v)) return str("nan");
    if (v < 0) {
      str("-");
      v = -v;
    }
    std::uint32_t scale = 1;
    for (int i = 0; i < decimals; ++i) scale *= 10;
    const std::uint32_t whole = static_cast<std::uint32_t>(v);
    const std::uint32_t frac = static_cast<std::uint32_t>((v - static_cast<float>(whole)) * scale + 0.5f);
    u32(whole + frac / scale).str(".");
    std::uint32_t f = frac % scale, d = scale / 10;
    for (int i = 0; i < decimals; ++i, d /= 10) {
      buf_[n_ < kMax - 1 ? n_++ : n_] = static_cast<char>('0' + (d ? (f / d) % 10 : 0));
    }
    return *this;
  }
  /// The line so far (NUL-terminated, no newline), e.g. for a UART.
  const char* text() {
    buf_[n_] = 0;
    return buf_;
  }
  void emit() {
    buf_[n_ < kMax - 1 ? n_++ : n_] = '\n';
    buf_[n_] = 0;
    semihost::write(buf_);
    n_ = 0;
  }

 private:
  static constexpr int kMax = 160;
  char buf_[kMax];
  int n_ = 0;
};

}  // namespace cortex_m::text
