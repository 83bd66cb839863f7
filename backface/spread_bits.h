// kSpread[b]: the eight bits of b as eight bytes 0/1 (byte j = bit j), for writing eight per-unit
// flags from one byte of bits (the cluster and normal-mask passes). Internal to backface/.
#pragma once

#include <array>
#include <cstdint>

namespace walkvis {

constexpr std::array<uint64_t, 256> makeSpreadBits() {
  std::array<uint64_t, 256> t{};
  for (uint64_t b = 0; b < 256; ++b) {
    for (int j = 0; j < 8; ++j) t[b] |= ((b >> j) & 1u) << (8 * j);
  }
  return t;
}
inline constexpr std::array<uint64_t, 256> kSpread = makeSpreadBits();

}  // namespace walkvis
