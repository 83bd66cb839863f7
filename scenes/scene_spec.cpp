// The one scene argument: file formats by extension, WAD maps as FILE.wad:MAP, generators as
// gen:NAME?key=value&...; and the checks every loaded scene passes.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>

#include "scenes/generators.h"
#include "scenes/loaders.h"
#include "scenes/scene.h"
#include "scenes/walkable.h"

namespace walkvis {
namespace {

constexpr const char* kDoomWadDir = "/usr/share/games/doom";

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// A bare WAD name like `freedoom2.wad` is also looked up where Debian installs Doom WADs.
std::string resolveWad(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(path, ec) || path.find('/') != std::string::npos) return path;
  const std::string system_path = std::string(kDoomWadDir) + "/" + path;
  if (fs::exists(system_path, ec)) return system_path;
  return path;
}

Scene generate(const std::string& spec) {
  const std::string body = spec.substr(4);
  const size_t q = body.find('?');
  const std::string name = body.substr(0, q);
  std::map<std::string, std::string> values;
  if (q != std::string::npos) {
    const std::string query = body.substr(q + 1);
    size_t start = 0;
    while (start <= query.size()) {
      size_t amp = query.find('&', start);
      if (amp == std::string::npos) amp = query.size();
      const std::string pair = query.substr(start, amp - start);
      if (!pair.empty()) {
        const size_t eq = pair.find('=');
        if (eq == std::string::npos || eq == 0) {
          throw Error(spec + ": generator parameter '" + pair + "' is not key=value");
        }
        const std::string key = pair.substr(0, eq);
        if (values.count(key)) throw Error(spec + ": generator parameter '" + key + "' given twice");
        values[key] = pair.substr(eq + 1);
      }
      start = amp + 1;
    }
  }
  if (name.empty()) throw Error(spec + ": no generator named (e.g. gen:office)");
  GeneratorParams params("gen:" + name, std::move(values));
  Scene scene = generateScene(name, params);
  params.checkAllUsed();
  return scene;
}

}  // namespace

std::string asciiLower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string oneLineMessage(const std::string& text, size_t max_chars) {
  std::string out;
  for (char c : text) {
    if (c == '\n' || c == '\r') {
      if (!out.empty() && out.back() != ' ') out += "; ";
    } else if (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f) {
      out += c;
    }
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
  if (out.size() > max_chars) out = out.substr(0, max_chars) + "...";
  return out.empty() ? std::string("unknown error") : out;
}

GeneratorParams::GeneratorParams(std::string generator, std::map<std::string, std::string> values)
    : generator_(std::move(generator)), values_(std::move(values)) {}

int64_t GeneratorParams::getInt(const std::string& key, int64_t fallback, int64_t lo, int64_t hi) {
  used_.insert(key);
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  const std::string& s = it->second;
  int64_t value = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) {
    throw Error(generator_ + ": parameter " + key + "='" + s + "' is not an integer");
  }
  if (value < lo || value > hi) {
    throw Error(generator_ + ": parameter " + key + "=" + s + " is out of range [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
  }
  return value;
}

double GeneratorParams::getDouble(const std::string& key, double fallback, double lo, double hi) {
  used_.insert(key);
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  const std::string& s = it->second;
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size() || s.empty() || !std::isfinite(value)) {
    throw Error(generator_ + ": parameter " + key + "='" + s + "' is not a finite number");
  }
  if (value < lo || value > hi) {
    throw Error(generator_ + ": parameter " + key + "=" + s + " is out of range [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
  }
  return value;
}

void GeneratorParams::checkAllUsed() const {
  for (const auto& [key, value] : values_) {
    if (!used_.count(key)) {
      std::string known;
      for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
      throw Error(generator_ + ": unknown parameter '" + key + "' (known: " + known + ")");
    }
  }
}

Scene loadScene(const std::string& spec, const LoadOptions& options) {
  if (!options.loader.empty() && options.loader != "assimp") {
    throw Error(spec + ": unknown loader '" + options.loader + "' (expected assimp, or none for the default)");
  }
  if (options.up_axis != 0 && options.up_axis != 'y' && options.up_axis != 'z') {
    throw Error(spec + ": the up axis must be y or z");
  }
  if (options.unit_scale == 0.0 || !std::isfinite(options.unit_scale)) {
    throw Error(spec + ": the unit scale must be a positive finite number");
  }
  const std::string& floors = options.floors;
  if (!floors.empty() && floors != "faces" && floors != "navmesh") {
    throw Error(spec + ": unknown floor method '" + floors + "' (expected faces or navmesh)");
  }
  Scene scene;
  double default_eye = 1.7;
  bool wad = false;
  bool mesh_file = false;  // OBJ, glTF or assimp: floors from the navmesh by default
  bool native_file = false;  // the project's own OBJ and glTF loaders: up axis and units applied here
  if (spec.rfind("gen:", 0) == 0) {
    scene = generate(spec);
    // The furnished building generators are meshes as an architect's tool would export them.
    const std::string name = spec.substr(4, spec.find('?') == std::string::npos ? std::string::npos : spec.find('?') - 4);
    mesh_file = name == "table_room" || name == "house" || name == "ramp";
  } else {
    std::string path = spec;
    std::string map;
    const size_t colon = spec.rfind(':');
    if (colon != std::string::npos && endsWith(asciiLower(spec.substr(0, colon)), ".wad")) {
      path = spec.substr(0, colon);
      map = spec.substr(colon + 1);
    }
    const std::string ext = asciiLower(std::filesystem::path(path).extension().string());
    if (ext == ".wad") {
      path = resolveWad(path);
      if (map.empty()) {
        std::string names;
        for (const auto& n : wadMapNames(path)) names += (names.empty() ? "" : " ") + n;
        throw Error(path + ": name a map, e.g. " + path + ":" +
                         (names.empty() ? std::string("MAP01") : names.substr(0, names.find(' '))) +
                         " (maps: " + names + ")");
      }
      scene = loadWadMap(path, map);
      default_eye = 41.0;
      wad = true;
    } else if (options.loader == "assimp") {
      scene = loadAssimp(path, options);
      mesh_file = true;
    } else if (ext == ".obj") {
      scene = loadObj(path, options.merge_faces);
      mesh_file = native_file = true;
    } else if (ext == ".gltf" || ext == ".glb") {
      scene = loadGltf(path, options.merge_faces);
      mesh_file = native_file = true;
    } else if (!ext.empty() && assimpReadsExtension(ext)) {
      scene = loadAssimp(path, options);
      mesh_file = true;
    } else {
      throw Error(spec + ": unknown scene format '" + ext +
                       "' (expected .obj, .gltf, .glb, FILE.wad:MAP, gen:NAME, or a format assimp reads: "
                       ".ifc, .fbx, .dae, .3ds, .blend, .ply, .stl, .off, ...)");
    }
  }
  if (native_file && (options.up_axis == 'z' || options.unit_scale > 0.0)) {
    transformScene(scene, options.up_axis == 'z', options.unit_scale > 0.0 ? options.unit_scale : 1.0);
    scene.report.notes.push_back(std::string("up axis ") + (options.up_axis == 'z' ? "z (turned to y)" : "y") +
                                 ", unit scale " + std::to_string(options.unit_scale > 0.0 ? options.unit_scale : 1.0) +
                                 " (given on the command line)");
  }
  if (scene.polygons.empty()) {
    const uint64_t dropped = scene.report.dropped_degenerate + scene.report.dropped_zero_area;
    throw Error(spec + ": empty scene (no polygons; " + std::to_string(scene.report.input_faces) +
                     " input faces, " + std::to_string(dropped) + " dropped as degenerate or zero-area)");
  }
  scene.name = spec;
  if (options.eye_height > 0.0) {
    scene.eye_height = options.eye_height;
  } else if (default_eye == 41.0) {
    scene.eye_height = default_eye;
  }
  // WAD maps keep their exact sector floors unless asked; mesh files take the navmesh's floors;
  // generators keep the levels they made, or every upward face height.
  const bool navmesh = floors == "navmesh" || (floors.empty() && mesh_file && scene.levels.empty());
  if (navmesh) {
    deriveWalkableLevels(scene, options.walkable);
  } else if (floors == "faces" || scene.levels.empty()) {
    if (!wad || floors == "faces") deriveFloorLevels(scene);
  }
  placeStartEye(scene);
  return scene;
}

}  // namespace walkvis
