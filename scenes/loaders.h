// Scene loaders for files. Each throws SceneError with a one-line message that names the file
// (and line, for OBJ) on bad input. The *FromMemory forms exist for the fuzzers and tests; `context`
// is the name used in messages. Loaders fill polygons, face colours, report and (WAD) levels and start
// eye; loadScene() derives levels and the start eye where a loader leaves them empty.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "scenes/scene.h"

namespace walkvis {

Scene loadObj(const std::string& path);
Scene loadObjFromMemory(std::string_view text, const std::string& context);

Scene loadGltf(const std::string& path);  // .gltf (JSON, external or embedded buffers) or .glb
Scene loadGltfFromMemory(std::span<const uint8_t> bytes, const std::string& context, bool binary);

// Doom-format WAD maps (Doom and Freedoom): `map` like "MAP07" or "E1M1".
Scene loadWadMap(const std::string& path, const std::string& map);
Scene loadWadMapFromMemory(std::span<const uint8_t> bytes, const std::string& map, const std::string& context);
std::vector<std::string> wadMapNames(const std::string& path);

// Reads a whole file; SceneError naming the path when it is missing or unreadable.
std::vector<uint8_t> readFileBytes(const std::string& path);

}  // namespace walkvis
