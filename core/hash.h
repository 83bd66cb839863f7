// The one hash: FNV-1a 64 (Fowler, Noll & Vo [FNV], docs/REFERENCES.md). Over bytes it is the
// checksum of walkvis' files and the scene hash a BSP file records; over whole 64-bit words (one
// xor and one multiply per word) it keys hash tables of coordinates, planes and id runs.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <initializer_list>

namespace walkvis {

constexpr uint64_t kFnvOffset = 1469598103934665603ull;
constexpr uint64_t kFnvPrime = 1099511628211ull;

// FNV-1a 64 over `size` bytes, continuing from `h` (kFnvOffset starts a new hash).
inline uint64_t fnv1a(const void* data, size_t size, uint64_t h = kFnvOffset) {
  const auto* b = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) {
    h ^= b[i];
    h *= kFnvPrime;
  }
  return h;
}

// One FNV-1a step over a whole word.
constexpr uint64_t fnv1aWord(uint64_t h, uint64_t word) { return (h ^ word) * kFnvPrime; }

// FNV-1a steps over the bit patterns of doubles (so -0.0 and 0.0 differ: add 0.0 first where they
// must hash alike).
inline uint64_t fnv1aDoubles(std::initializer_list<double> values, uint64_t h = kFnvOffset) {
  for (double v : values) h = fnv1aWord(h, std::bit_cast<uint64_t>(v));
  return h;
}

}  // namespace walkvis
