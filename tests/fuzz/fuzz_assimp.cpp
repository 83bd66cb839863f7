// libFuzzer target: any format assimp reads, through loadAssimpFromMemory. The first byte picks
// the extension hint (kHints[byte % 8]); the rest are the file's bytes. scripts/fuzz puts that
// byte in front of each seed by its extension. Bit 3 of that byte turns merging off, so both
// addFace() alone and mesh_merge.h see assimp's triangle soups.
#include <cstddef>
#include <cstdint>
#include <span>

#include "scenes/loaders.h"
#include "tests/fuzz/fuzz_check.h"

namespace {
constexpr const char* kHints[8] = {"ifc", "fbx", "dae", "3ds", "ply", "stl", "off", "obj"};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  walkvis::LoadOptions options;
  options.merge_faces = (data[0] & 8) == 0;
  // scripts/fuzz gives each input 10 s under ASan; an instance explosion that assimp expands
  // within its node and triangle caps (kMaxColladaNodes, kMaxTriangles) reads for longer.
  options.import_seconds_max = 2;
  try {
    const walkvis::Scene scene =
        walkvis::loadAssimpFromMemory(std::span<const uint8_t>(data + 1, size - 1), kHints[data[0] % 8], "fuzz", options);
    walkvis::checkSceneInvariants(scene);
  } catch (const walkvis::Error&) {
  }
  return 0;
}
