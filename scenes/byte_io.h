// Little helpers shared by walkvis' binary files (BSP and tree files): an append-only byte
// writer and the FNV-1a 64 checksum [FNV] over a payload. Native byte order (files are caches of a
// build, read back on the same kind of machine).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "scenes/scene.h"

namespace walkvis {

inline uint64_t fnv1a(const uint8_t* data, size_t size) {
  uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < size; ++i) {
    h ^= data[i];
    h *= 1099511628211ull;
  }
  return h;
}

struct ByteWriter {
  std::vector<uint8_t> bytes;
  template <typename T>
  void put(T value) {
    const size_t at = bytes.size();
    bytes.resize(at + sizeof(T));
    std::memcpy(bytes.data() + at, &value, sizeof(T));
  }
  void putPlane(const Plane& p) {
    put(p.n.x);
    put(p.n.y);
    put(p.n.z);
    put(p.d);
  }
};

}  // namespace walkvis
