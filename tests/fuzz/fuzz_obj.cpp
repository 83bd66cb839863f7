// libFuzzer target: OBJ text through loadObjFromMemory.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "scenes/loaders.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const walkvis::Scene scene =
        walkvis::loadObjFromMemory(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.obj");
    walkvis::checkSceneInvariants(scene);
  } catch (const walkvis::Error&) {
  }
  return 0;
}
