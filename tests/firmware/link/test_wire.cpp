// The link's bytes below the frames (osc/link/wire.hpp): the frames' CRC-16/CCITT-FALSE.
#include <gtest/gtest.h>

#include <cstdint>

#include "osc/link/wire.hpp"

namespace {

// CRC-16/CCITT-FALSE: the catalogue's check value (CRC of the ASCII digits "123456789" is 0x29B1),
// and the table-driven form equal to the bitwise definition on every length and start value.
TEST(PilProtocol, Crc16IsCcittFalse) {
  const std::uint8_t digits[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(pil::crc16(digits, 9), 0x29B1);
  EXPECT_EQ(pil::crc16_bitwise(digits, 9), 0x29B1);
  std::uint8_t buf[300];
  std::uint32_t x = 12345;
  for (std::uint8_t& b : buf) b = static_cast<std::uint8_t>((x = x * 1664525u + 1013904223u) >> 24);
  for (int n = 0; n <= 300; n += 7)
    for (std::uint16_t init : {std::uint16_t{0xFFFF}, std::uint16_t{0}, std::uint16_t{0x1D0F}})
      ASSERT_EQ(pil::crc16(buf, n, init), pil::crc16_bitwise(buf, n, init)) << n << " " << init;
}

}  // namespace
