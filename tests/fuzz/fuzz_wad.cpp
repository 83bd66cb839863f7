// libFuzzer target: WAD bytes through loadWadMapFromMemory for MAP01 (the map tiny.wad holds;
// Freedoom's E1M1-style names take the same path).
#include <cstddef>
#include <cstdint>
#include <span>

#include "scenes/loaders.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const walkvis::Scene scene =
        walkvis::loadWadMapFromMemory(std::span<const uint8_t>(data, size), "MAP01", "fuzz.wad");
    walkvis::checkSceneInvariants(scene);
  } catch (const walkvis::Error&) {
  }
  return 0;
}
