// The one random number generator: splitmix64 (Steele, Lea & Flood 2014 [SteeleLeaFlood2014],
// docs/REFERENCES.md) with our own mapping to [0, 1). Everything random in walkvis (generated
// buildings, sample points, eyes, tours) draws from it, so a seed gives the same figures with every
// standard library: std::uniform_*_distribution and std::discrete_distribution differ between them.
#pragma once

#include <cstdint>

namespace walkvis {

// Advances `state` and returns the next 64 random bits.
inline uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// Uniform in [0, 1), on the grid of 2^-53 (the top 53 bits of the next draw).
inline double uniform01(uint64_t& state) { return static_cast<double>(splitmix64(state) >> 11) * 0x1.0p-53; }

// Mixes `v` into the hash `h` (boost's hash_combine step, then one splitmix64 round): seeds for
// streams that must not depend on the order in which work is done, such as one per sample key.
inline uint64_t mixHash(uint64_t h, uint64_t v) {
  uint64_t s = h ^ (v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2));
  return splitmix64(s);
}

// The same generator as a value, for code that draws many numbers from one stream.
struct Rng {
  uint64_t state = 0;
  uint64_t next() { return splitmix64(state); }
  double uniform() { return uniform01(state); }                                // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }  // [lo, hi) up to rounding
  bool chance(double p) { return uniform() < p; }
  // Uniform in [0, n) for n > 0. The modulo's bias is below n / 2^64: nothing walkvis draws notices it.
  uint64_t below(uint64_t n) { return next() % n; }
};

}  // namespace walkvis
