// The one byte reader and writer of walkvis' binary files (BSP and tree files), and whole-file
// reads and atomic writes. Native byte order: the files are caches of a build, read back on the
// same kind of machine.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "core/geometry.h"

namespace walkvis {

// An append-only buffer of fields written one by one, no padding.
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

// Reads fields back in order. Every read is bounds-checked: running past the end, a non-finite
// number where one must be finite, or a count larger than what is left throws Error with
// `prefix` + what is wrong (the prefix names the file and its kind, "F: tree file: ").
class ByteReader {
 public:
  ByteReader(std::span<const uint8_t> bytes, std::string prefix) : bytes_(bytes), prefix_(std::move(prefix)) {}
  template <typename T>
  T get() {
    if (bytes_.size() - pos_ < sizeof(T)) fail("truncated");
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  double getFinite() {
    const double v = get<double>();
    if (!std::isfinite(v)) fail("non-finite number");
    return v;
  }
  Plane getPlane() {
    Plane p;
    p.n.x = get<double>();
    p.n.y = get<double>();
    p.n.z = get<double>();
    p.d = get<double>();
    return p;
  }
  // A u32 count of elements of `element_bytes` each, which must fit in what is left.
  uint32_t count(size_t element_bytes) {
    const uint32_t n = get<uint32_t>();
    if (static_cast<uint64_t>(n) * element_bytes > remaining()) fail("truncated (count too large)");
    return n;
  }
  // The next `size` bytes as a view (for a part in a format of its own); throws when fewer are left.
  std::span<const uint8_t> take(size_t size) {
    if (size > remaining()) fail("truncated");
    const std::span<const uint8_t> part = bytes_.subspan(pos_, size);
    pos_ += size;
    return part;
  }
  size_t position() const { return pos_; }
  size_t remaining() const { return bytes_.size() - pos_; }
  [[noreturn]] void fail(std::string_view what) const { throw Error(prefix_ + std::string(what)); }

 private:
  std::span<const uint8_t> bytes_;
  size_t pos_ = 0;
  std::string prefix_;
};

// The whole file. Error naming the path when it is a directory, cannot be opened or read.
std::vector<uint8_t> readFileBytes(const std::string& path);

// Writes `parts` one after the other to a temporary file next to `path` (path + ".tmp"), then
// renames it into place, so `path` is never left half-written. Error "<path>: cannot write <what>
// (<reason>)" on failure, with the temporary file removed.
void writeFileAtomically(const std::string& path, std::span<const std::span<const uint8_t>> parts,
                         std::string_view what);
inline void writeFileAtomically(const std::string& path, std::span<const uint8_t> bytes, std::string_view what) {
  const std::span<const uint8_t> parts[1] = {bytes};
  writeFileAtomically(path, parts, what);
}
// The same for text (CSV, HTML, camera paths).
inline void writeTextFileAtomically(const std::string& path, std::string_view text, std::string_view what) {
  writeFileAtomically(path, std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()), what);
}

}  // namespace walkvis
