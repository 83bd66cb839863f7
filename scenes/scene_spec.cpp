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

namespace walkvis {
namespace {

constexpr const char* kDoomWadDir = "/usr/share/games/doom";

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

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
          throw SceneError(spec + ": generator parameter '" + pair + "' is not key=value");
        }
        const std::string key = pair.substr(0, eq);
        if (values.count(key)) throw SceneError(spec + ": generator parameter '" + key + "' given twice");
        values[key] = pair.substr(eq + 1);
      }
      start = amp + 1;
    }
  }
  if (name.empty()) throw SceneError(spec + ": no generator named (e.g. gen:office)");
  GeneratorParams params("gen:" + name, std::move(values));
  Scene scene = generateScene(name, params);
  params.checkAllUsed();
  return scene;
}

}  // namespace

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
    throw SceneError(generator_ + ": parameter " + key + "='" + s + "' is not an integer");
  }
  if (value < lo || value > hi) {
    throw SceneError(generator_ + ": parameter " + key + "=" + s + " is out of range [" + std::to_string(lo) + ", " +
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
    throw SceneError(generator_ + ": parameter " + key + "='" + s + "' is not a finite number");
  }
  if (value < lo || value > hi) {
    throw SceneError(generator_ + ": parameter " + key + "=" + s + " is out of range [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
  }
  return value;
}

void GeneratorParams::checkAllUsed() const {
  for (const auto& [key, value] : values_) {
    if (!used_.count(key)) {
      std::string known;
      for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
      throw SceneError(generator_ + ": unknown parameter '" + key + "' (known: " + known + ")");
    }
  }
}

Scene loadScene(const std::string& spec, const LoadOptions& options) {
  Scene scene;
  double default_eye = 1.7;
  if (spec.rfind("gen:", 0) == 0) {
    scene = generate(spec);
  } else {
    std::string path = spec;
    std::string map;
    const size_t colon = spec.rfind(':');
    if (colon != std::string::npos && endsWith(lower(spec.substr(0, colon)), ".wad")) {
      path = spec.substr(0, colon);
      map = spec.substr(colon + 1);
    }
    const std::string ext = lower(std::filesystem::path(path).extension().string());
    if (ext == ".obj") {
      scene = loadObj(path);
    } else if (ext == ".gltf" || ext == ".glb") {
      scene = loadGltf(path);
    } else if (ext == ".wad") {
      path = resolveWad(path);
      if (map.empty()) {
        std::string names;
        for (const auto& n : wadMapNames(path)) names += (names.empty() ? "" : " ") + n;
        throw SceneError(path + ": name a map, e.g. " + path + ":" +
                         (names.empty() ? std::string("MAP01") : names.substr(0, names.find(' '))) +
                         " (maps: " + names + ")");
      }
      scene = loadWadMap(path, map);
      default_eye = 41.0;
    } else {
      throw SceneError(spec + ": unknown scene format '" + ext +
                       "' (expected .obj, .gltf, .glb, FILE.wad:MAP or gen:NAME)");
    }
  }
  if (scene.polygons.empty()) {
    const uint64_t dropped = scene.report.dropped_degenerate + scene.report.dropped_zero_area;
    throw SceneError(spec + ": empty scene (no polygons; " + std::to_string(scene.report.input_faces) +
                     " input faces, " + std::to_string(dropped) + " dropped as degenerate or zero-area)");
  }
  scene.name = spec;
  if (options.eye_height > 0.0) {
    scene.eye_height = options.eye_height;
  } else if (default_eye == 41.0) {
    scene.eye_height = default_eye;
  }
  if (scene.levels.empty()) deriveFloorLevels(scene);
  placeStartEye(scene);
  return scene;
}

}  // namespace walkvis
