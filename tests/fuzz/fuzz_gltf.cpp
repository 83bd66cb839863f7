// libFuzzer target: glTF through loadGltfFromMemory, as GLB when the input starts with the GLB
// magic and as JSON otherwise (so both parsers see mutations of their own seeds).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "scenes/loaders.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const bool binary = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  try {
    const walkvis::Scene scene =
        walkvis::loadGltfFromMemory(std::span<const uint8_t>(data, size), binary ? "fuzz.glb" : "fuzz.gltf", binary);
    walkvis::checkSceneInvariants(scene);
  } catch (const walkvis::Error&) {
  }
  return 0;
}
