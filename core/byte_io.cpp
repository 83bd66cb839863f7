#include "core/byte_io.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <system_error>

namespace walkvis {

std::vector<uint8_t> readFileBytes(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw Error(path + ": is a directory, not a file");
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw Error(path + ": cannot open (" + std::strerror(errno) + ")");
  // Read in growing blocks rather than trusting a size up front: the file may be a pipe or change.
  std::vector<uint8_t> bytes;
  size_t used = 0;
  for (;;) {
    if (used == bytes.size()) bytes.resize(std::max<size_t>(1 << 20, 2 * bytes.size()));
    const size_t got = std::fread(bytes.data() + used, 1, bytes.size() - used, f);
    used += got;
    if (got == 0) break;
  }
  bytes.resize(used);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw Error(path + ": read error");
  return bytes;
}

void writeFileAtomically(const std::string& path, std::span<const std::span<const uint8_t>> parts,
                         std::string_view what) {
  const std::string tmp = path + ".tmp";
  auto fail = [&](const std::string& reason) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw Error(path + ": cannot write " + std::string(what) + " (" + reason + ")");
  };
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) fail("cannot create " + tmp + ": " + std::strerror(errno));
  bool ok = true;
  for (std::span<const uint8_t> part : parts)
    ok = ok && (part.empty() || std::fwrite(part.data(), 1, part.size(), f) == part.size());
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) fail("write failed");
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail(ec.message());
}

}  // namespace walkvis
