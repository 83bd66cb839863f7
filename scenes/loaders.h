// Scene loaders for files. Each throws Error with a one-line message that names the file
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

// `merge`: adjacent coplanar faces of one object (OBJ: `o`/`g` groups; glTF: a primitive of a node
// instance) become one face (mesh_merge.h).
Scene loadObj(const std::string& path, bool merge = true);
Scene loadObjFromMemory(std::string_view text, const std::string& context, bool merge = true);

Scene loadGltf(const std::string& path, bool merge = true);  // .gltf (JSON, external or embedded buffers) or .glb
Scene loadGltfFromMemory(std::span<const uint8_t> bytes, const std::string& context, bool binary, bool merge = true);

// Doom-format WAD maps (Doom and Freedoom): `map` like "MAP07" or "E1M1".
Scene loadWadMap(const std::string& path, const std::string& map);
Scene loadWadMapFromMemory(std::span<const uint8_t> bytes, const std::string& map, const std::string& context);
std::vector<std::string> wadMapNames(const std::string& path);

// Every format assimp reads (IFC 2x3, FBX, Collada, 3DS, Blender, PLY, STL, OFF, and OBJ/glTF when
// asked), through assimp (scenes/assimp.cpp). Units and up axis as the file states them, unless
// options.up_axis / options.unit_scale override; the scene comes out y-up in metres; colours from
// the materials, node transforms and instancing applied, each mesh instance one object for
// mesh_merge.h. What was assumed goes into report.notes. Error naming the file and assimp's
// reason on bad input.
Scene loadAssimp(const std::string& path, const LoadOptions& options);
// `extension_hint` like "ifc" or "fbx" tells assimp the format of the bytes.
Scene loadAssimpFromMemory(std::span<const uint8_t> bytes, const std::string& extension_hint,
                           const std::string& context, const LoadOptions& options);
// True when assimp has a reader for files ending in `extension` (with or without the dot).
bool assimpReadsExtension(const std::string& extension);

// Message helpers for loaders: a third-party library's error text as one short line (line breaks
// become "; ", control characters go, cut at `max_chars`), and ASCII lower case.
std::string oneLineMessage(const std::string& text, size_t max_chars = 300);
std::string asciiLower(std::string s);

}  // namespace walkvis
