// Every format the Open Asset Import Library reads (IFC 2x3, FBX, Collada, 3DS, Blender, PLY, STL,
// OFF, OBJ, glTF, ...), through assimp 5.2 (https://github.com/assimp/assimp, the aiScene data
// structure: https://assimp-docs.readthedocs.io/en/latest/usage/use_the_lib.html).
//
// assimp triangulates, joins identical vertices, validates and drops points and lines; the node
// tree is walked here (not aiProcess_PreTransformVertices) in double precision, so a mesh that
// several nodes reference is added once per instance, each instance one object for mesh_merge.h.
//
// Units and up axis, and who applies them (measured with assimp 5.2.5, see tests/test_assimp.cpp):
// - IFC: assimp converts IfcSIUnit lengths (with their prefix) to metres and turns the model from
//   z-up to y-up with a rotation on the root node. Nothing more is done here, except that an IFC
//   without a length unit whose extent exceeds kMillimetreExtent is taken to be in millimetres.
// - Collada: assimp applies <unit meter=...> and <up_axis> on the root node.
// - 3DS: assimp turns 3ds' z-up to y-up on the root node; units are not stated (1 assumed).
// - FBX: assimp leaves both to us: UnitScaleFactor metadata is centimetres per file unit, the
//   UpAxis/FrontAxis/CoordAxis metadata (with signs) give the file's axes.
// - Everything else states nothing: y-up and metres are assumed.
// options.up_axis / options.unit_scale replace what the file states (assimp's own conversion of
// the file is undone where it did one), and the note says so.
//
// assimp 5.2 itself crashes on some malformed files; what was found and how it is kept out:
// Collada <instance_node> cycles (stack overflow) and instance explosions -> checkColladaNodes;
// IFC files cut off or referring to undefined entities (null dereference) -> checkStepReferences;
// anything else (an IFC entity of an unknown type name, found by fuzz_assimp) -> probeInChild,
// the import first run in a forked child. assimp's FBX parser leaks on a cut-off ASCII FBX
// (tests/fuzz/fuzz_assimp.supp).
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>

#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/metadata.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "core/byte_io.h"
#include "scenes/loaders.h"
#include "scenes/mesh_merge.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

// Larger files are not building models a walkthrough can hold; the cap also keeps a bad path
// (a disk image, say) from being read whole.
constexpr uint64_t kMaxFileBytes = uint64_t{512} << 20;
// Real node trees are a handful of levels deep (FZK-Haus: 8); deeper is a malformed file.
constexpr int kMaxNodeDepth = 256;
// Same cap as the glTF loader: far beyond what a walkthrough BSP holds, and it bounds what a small
// file can demand by instancing one mesh from many nodes.
constexpr uint64_t kMaxTriangles = uint64_t{1} << 22;
// An IFC without a length unit that is more than this many units across is not a 1 km building
// in metres but a normal one in millimetres (the usual unit of architectural CAD).
constexpr double kMillimetreExtent = 1000.0;
// assimp's matrices are float: a 90° rotation holds cos(π/2) as -4.37e-8, which would tilt every
// floor. Entries below this fraction of the matrix's largest entry are zero: well above float
// rounding (6e-8) and far below any rotation a model means (1e-6 rad is 0.2 arc seconds).
constexpr double kMatrixSnap = 1e-6;

std::string fixed(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// Loading from memory must never read other files (an OBJ's mtllib, a glTF's buffers): assimp's
// MemoryIOSystem passes every other name to the IO system below it, which here refuses.
class NoFilesIOSystem : public Assimp::IOSystem {
 public:
  bool Exists(const char*) const override { return false; }
  char getOsSeparator() const override { return '/'; }
  Assimp::IOStream* Open(const char*, const char*) override { return nullptr; }
  void Close(Assimp::IOStream* stream) override { delete stream; }
};

std::optional<double> metaNumber(const aiMetadata* meta, const char* key) {
  if (!meta) return std::nullopt;
  for (unsigned i = 0; i < meta->mNumProperties; ++i) {
    if (meta->mKeys[i] != aiString(key)) continue;
    const aiMetadataEntry& e = meta->mValues[i];
    if (!e.mData) return std::nullopt;
    switch (e.mType) {
      case AI_BOOL: return *static_cast<const bool*>(e.mData) ? 1.0 : 0.0;
      case AI_INT32: return *static_cast<const int32_t*>(e.mData);
      case AI_UINT64: return static_cast<double>(*static_cast<const uint64_t*>(e.mData));
      case AI_FLOAT: return *static_cast<const float*>(e.mData);
      case AI_DOUBLE: return *static_cast<const double*>(e.mData);
      default: return std::nullopt;
    }
  }
  return std::nullopt;
}

std::string metaString(const aiMetadata* meta, const char* key) {
  if (!meta) return {};
  aiString s;
  return meta->Get(std::string(key), s) ? std::string(s.C_Str()) : std::string();
}

enum class Format { kIfc, kCollada, kFbx, k3ds, kOther };

Format formatOf(const aiScene* scene, const std::string& ext) {
  const std::string source = metaString(scene->mMetaData, "SourceAsset_Format");
  if (source.find("IFC") != std::string::npos) return Format::kIfc;
  if (source.find("Collada") != std::string::npos) return Format::kCollada;
  if (source.find("FBX") != std::string::npos) return Format::kFbx;
  if (source.find("3DS") != std::string::npos) return Format::k3ds;
  if (!source.empty()) return Format::kOther;
  if (ext == "ifc" || ext == "ifczip") return Format::kIfc;
  if (ext == "dae") return Format::kCollada;
  if (ext == "fbx") return Format::kFbx;
  if (ext == "3ds") return Format::k3ds;
  return Format::kOther;
}

std::string_view asText(std::span<const uint8_t> bytes) {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

// Collada's <asset><unit meter="..."/> and <up_axis>, as assimp applies them; read here only to
// say so and to undo them for an override. The asset element comes first, so the head suffices.
struct ColladaAsset {
  double meter = 1.0;
  std::string up = "Y_UP";
};
ColladaAsset colladaAsset(std::span<const uint8_t> bytes) {
  ColladaAsset a;
  const std::string_view text = asText(bytes).substr(0, 1 << 16);
  const size_t unit = text.find("<unit");
  if (unit != std::string_view::npos) {
    const size_t end = text.find('>', unit);
    const size_t m = text.find("meter=", unit);
    if (m != std::string_view::npos && m < end && m + 7 < text.size()) {
      const std::string value(text.substr(m + 7, std::min<size_t>(32, text.size() - m - 7)));
      char* stop = nullptr;
      const double v = std::strtod(value.c_str(), &stop);
      if (stop != value.c_str() && std::isfinite(v) && v > 0.0) a.meter = v;
    }
  }
  for (const char* up : {"X_UP", "Z_UP", "Y_UP"}) {
    const size_t at = text.find(up);
    const size_t tag = text.find("<up_axis>");
    if (tag != std::string_view::npos && at != std::string_view::npos && at > tag && at < tag + 32) a.up = up;
  }
  return a;
}

// The IfcSIUnit length unit's factor to metres, as assimp applies it; nullopt when the file has
// no SI length unit (assimp then takes metres).
struct IfcUnit {
  std::optional<double> metres;
  std::string name;
  bool conversion_based = false;  // IfcConversionBasedUnit (feet, inches): assimp ignores it
};
IfcUnit ifcLengthUnit(std::span<const uint8_t> bytes) {
  IfcUnit u;
  const std::string_view text = asText(bytes);
  size_t at = 0;
  while ((at = text.find(".LENGTHUNIT.", at)) != std::string_view::npos) {
    const size_t start = text.rfind('=', at);
    const size_t end = text.find(';', at);
    if (start == std::string_view::npos || end == std::string_view::npos) break;
    const std::string record = asciiLower(std::string(text.substr(start, std::min<size_t>(end - start, 200))));
    if (record.find("ifcconversionbasedunit") != std::string::npos) u.conversion_based = true;
    if (record.find("ifcsiunit") != std::string::npos) {
      static constexpr std::array<std::pair<const char*, double>, 8> kPrefixes{{{".milli.", 1e-3},
                                                                               {".centi.", 1e-2},
                                                                               {".deci.", 1e-1},
                                                                               {".kilo.", 1e3},
                                                                               {".micro.", 1e-6},
                                                                               {".nano.", 1e-9},
                                                                               {".deca.", 1e1},
                                                                               {".hecto.", 1e2}}};
      u.metres = 1.0;
      u.name = "metre";
      for (const auto& [prefix, factor] : kPrefixes) {
        if (record.find(prefix) != std::string::npos) {
          u.metres = factor;
          u.name = std::string(prefix + 1, std::strlen(prefix) - 2) + "metre";
        }
      }
      return u;
    }
    at += 12;
  }
  return u;
}

// assimp 5.2's Collada importer follows <instance_node> recursively without a guard: a node that
// instances itself (or an ancestor) recurses until the stack overflows (SIGSEGV, found by hand
// and by fuzz_assimp), and a chain of nodes that each instance the next twice expands
// exponentially. So before assimp sees a Collada file, its node graph is read here with a plain
// tag scan (containment and instance_node edges; tags inside comments count too, which can only
// reject, never let through) and refused when it has a cycle, nests deeper than kMaxNodeDepth or
// expands to more than kMaxColladaNodes nodes.
constexpr uint64_t kMaxColladaNodes = uint64_t{1} << 20;

void checkColladaNodes(std::string_view text, const std::string& context) {
  std::unordered_map<std::string, uint32_t> ids;
  std::vector<std::vector<uint32_t>> edges;  // node -> children and instanced nodes
  std::vector<std::pair<uint32_t, std::string>> instances;
  std::vector<uint32_t> open;
  const auto attribute = [](std::string_view tag, std::string_view name) -> std::string {
    size_t at = 0;
    while ((at = tag.find(name, at)) != std::string_view::npos) {
      const size_t eq = at + name.size();
      if ((at == 0 || std::isspace(static_cast<unsigned char>(tag[at - 1]))) && eq + 1 < tag.size() && tag[eq] == '=' &&
          (tag[eq + 1] == '"' || tag[eq + 1] == '\'')) {
        const size_t end = tag.find(tag[eq + 1], eq + 2);
        if (end == std::string_view::npos) return {};
        return std::string(tag.substr(eq + 2, end - eq - 2));
      }
      at = eq;
    }
    return {};
  };
  size_t at = 0;
  while ((at = text.find('<', at)) != std::string_view::npos) {
    const size_t end = text.find('>', at);
    if (end == std::string_view::npos) break;
    const std::string_view tag = text.substr(at + 1, end - at - 1);
    at = end;
    const auto named = [&](std::string_view name) {
      return tag.size() >= name.size() && tag.substr(0, name.size()) == name &&
             (tag.size() == name.size() || std::isspace(static_cast<unsigned char>(tag[name.size()])) ||
              tag[name.size()] == '/');
    };
    if (named("node")) {
      const uint32_t n = static_cast<uint32_t>(edges.size());
      edges.emplace_back();
      const std::string id = attribute(tag, "id");
      if (!id.empty()) ids.emplace(id, n);
      if (!open.empty()) edges[open.back()].push_back(n);
      if (tag.empty() || tag.back() != '/') open.push_back(n);
      if (open.size() > static_cast<size_t>(kMaxNodeDepth)) {
        throw Error(context + ": Collada nodes nested deeper than " + std::to_string(kMaxNodeDepth) + " levels");
      }
    } else if (named("/node")) {
      if (!open.empty()) open.pop_back();
    } else if (named("instance_node") && !open.empty()) {
      std::string url = attribute(tag, "url");
      if (!url.empty() && url[0] == '#') url.erase(0, 1);
      instances.emplace_back(open.back(), url);
    }
  }
  for (const auto& [from, url] : instances) {
    const auto it = ids.find(url);
    if (it != ids.end()) edges[from].push_back(it->second);
  }
  // Depth-first over every node, iteratively: grey on the stack means a cycle. Expanded sizes
  // (how many nodes a node stands for, instances included) are summed on the way out, capped.
  std::vector<uint8_t> state(edges.size(), 0);  // 0 new, 1 on the stack, 2 done
  std::vector<uint64_t> expanded(edges.size(), 1);
  std::vector<std::pair<uint32_t, size_t>> stack;
  for (uint32_t root = 0; root < edges.size(); ++root) {
    if (state[root]) continue;
    stack.emplace_back(root, 0);
    state[root] = 1;
    while (!stack.empty()) {
      auto& [n, next] = stack.back();
      if (next < edges[n].size()) {
        const uint32_t c = edges[n][next++];
        if (state[c] == 1) throw Error(context + ": Collada node instances form a cycle");
        if (state[c] == 0) {
          state[c] = 1;
          stack.emplace_back(c, 0);
        }
        continue;
      }
      uint64_t total = 1;
      for (uint32_t c : edges[n]) total = std::min(kMaxColladaNodes + 1, total + expanded[c]);
      expanded[n] = total;
      if (total > kMaxColladaNodes) {
        throw Error(context + ": Collada node instances expand to more than " +
                         std::to_string(kMaxColladaNodes) + " nodes");
      }
      state[n] = 2;
      stack.pop_back();
    }
  }
}

// assimp 5.2's IFC (STEP) reader dereferences a null pointer when an entity refers to one the file
// does not define (SIGSEGV inside libassimp; found by fuzz_assimp on a truncated tiny.ifc, and
// nearly every truncation of an IFC file hits it). So every #N reference in the DATA section is
// checked against the #N= definitions first (ISO 10303-21: strings are '...' with '' for a quote,
// comments /* ... */). A DATA section without its ENDSEC (a cut-off file) is refused as well.
void checkStepReferences(std::string_view text, const std::string& context) {
  const size_t data = text.find("DATA;");
  if (data == std::string_view::npos) return;  // assimp says what is missing
  std::unordered_set<uint64_t> defined;
  std::vector<std::pair<uint64_t, uint64_t>> references;  // (record, referenced)
  uint64_t record = 0;
  bool ended = false;
  for (size_t i = data + 5; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\'') {
      const size_t end = text.find('\'', i + 1);
      if (end == std::string_view::npos) break;
      i = end;  // '' inside a string re-enters here at once: the same as one string
    } else if (c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      const size_t end = text.find("*/", i + 2);
      if (end == std::string_view::npos) break;
      i = end + 1;
    } else if (c == '#') {
      uint64_t id = 0;
      size_t j = i + 1;
      while (j < text.size() && std::isdigit(static_cast<unsigned char>(text[j])) && id < (uint64_t{1} << 60)) {
        id = id * 10 + static_cast<uint64_t>(text[j] - '0');
        ++j;
      }
      if (j == i + 1) continue;
      size_t k = j;
      while (k < text.size() && std::isspace(static_cast<unsigned char>(text[k]))) ++k;
      if (k < text.size() && text[k] == '=') {
        defined.insert(id);
        record = id;
      } else {
        references.emplace_back(record, id);
      }
      i = j - 1;
    } else if (c == 'E' && text.substr(i, 7) == "ENDSEC;") {
      ended = true;
      break;
    }
  }
  // A cut-off last record crashes the reader just the same.
  if (!ended) throw Error(context + ": IFC DATA section does not end (no ENDSEC;): the file is truncated");
  for (const auto& [from, to] : references) {
    if (!defined.count(to)) {
      throw Error(context + ": IFC entity #" + std::to_string(from) + " refers to #" + std::to_string(to) +
                       ", which the file does not define (truncated?)");
    }
  }
}

glm::dmat4 toDmat4(const aiMatrix4x4& a) {
  // aiMatrix4x4 is row-major (a1..a4 the first row), glm column-major.
  glm::dmat4 m(1.0);
  const ai_real* r = &a.a1;
  double largest = 0.0;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) largest = std::max(largest, std::abs(static_cast<double>(r[row * 4 + col])));
  }
  for (int row = 0; row < 4; ++row) {
    for (int col = 0; col < 4; ++col) {
      double v = r[row * 4 + col];
      if (row < 3 && col < 3 && std::abs(v) < kMatrixSnap * largest) v = 0.0;
      m[col][row] = v;
    }
  }
  return m;
}

// z-up to y-up, (x, y, z) -> (x, z, -y), as transformScene does.
const glm::dmat3 kZUpToYUp(glm::dvec3(1, 0, 0), glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0));

// FBX's axis metadata: file axis k (0 x, 1 y, 2 z) with a sign for right (coord), up and front.
// Returns the linear map to y-up (right +x, up +y, front +z), or nullopt when the metadata is
// absent or not a permutation.
std::optional<glm::dmat3> fbxAxes(const aiMetadata* meta, std::string& what) {
  const auto up = metaNumber(meta, "UpAxis"), up_sign = metaNumber(meta, "UpAxisSign");
  const auto front = metaNumber(meta, "FrontAxis"), front_sign = metaNumber(meta, "FrontAxisSign");
  const auto coord = metaNumber(meta, "CoordAxis"), coord_sign = metaNumber(meta, "CoordAxisSign");
  if (!up || !up_sign || !front || !front_sign || !coord || !coord_sign) return std::nullopt;
  const int axes[3] = {static_cast<int>(*coord), static_cast<int>(*up), static_cast<int>(*front)};
  const double signs[3] = {*coord_sign < 0 ? -1.0 : 1.0, *up_sign < 0 ? -1.0 : 1.0, *front_sign < 0 ? -1.0 : 1.0};
  bool seen[3] = {false, false, false};
  for (int a : axes) {
    if (a < 0 || a > 2 || seen[a]) return std::nullopt;
    seen[a] = true;
  }
  glm::dmat3 m(0.0);
  for (int target = 0; target < 3; ++target) m[axes[target]][target] = signs[target];  // column = source axis
  static constexpr const char* kNames = "xyz";
  what = std::string(signs[1] < 0 ? "-" : "+") + kNames[axes[1]] + " up, " + (signs[2] < 0 ? "-" : "+") +
         kNames[axes[2]] + " front";
  return m;
}

struct Instance {
  const aiMesh* mesh = nullptr;
  glm::dmat4 world{1.0};
};

// Mesh instances in node order, with the world transform of their node. Iterative, with a depth
// cap and a visited set: assimp builds trees, but a malformed file must not make us loop.
std::vector<Instance> collectInstances(const aiScene* scene, const std::string& context) {
  std::vector<Instance> out;
  struct Item {
    const aiNode* node;
    glm::dmat4 parent;
    int depth;
  };
  std::vector<Item> stack{{scene->mRootNode, glm::dmat4(1.0), 0}};
  std::unordered_set<const aiNode*> visited;
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    if (!item.node) continue;
    if (item.depth > kMaxNodeDepth) {
      throw Error(context + ": assimp: node tree deeper than " + std::to_string(kMaxNodeDepth) + " levels");
    }
    if (!visited.insert(item.node).second) throw Error(context + ": assimp: node reached twice (a cycle)");
    const glm::dmat4 world = item.parent * toDmat4(item.node->mTransformation);
    for (unsigned i = 0; i < item.node->mNumMeshes; ++i) {
      const unsigned m = item.node->mMeshes[i];
      if (m >= scene->mNumMeshes || !scene->mMeshes[m]) {
        throw Error(context + ": assimp: node '" + oneLineMessage(item.node->mName.C_Str()) + "' names mesh " +
                         std::to_string(m) + " of " + std::to_string(scene->mNumMeshes));
      }
      out.push_back({scene->mMeshes[m], world});
    }
    // Children pushed in reverse so they come off the stack in file order.
    for (unsigned c = item.node->mNumChildren; c-- > 0;) {
      stack.push_back({item.node->mChildren ? item.node->mChildren[c] : nullptr, world, item.depth + 1});
    }
  }
  return out;
}

// The material's diffuse colour as 0xRRGGBB; nullopt for assimp's stand-in material (formats
// without materials) or none.
std::optional<uint32_t> diffuseColor(const aiScene* scene, unsigned material) {
  if (material >= scene->mNumMaterials || !scene->mMaterials[material]) return std::nullopt;
  const aiMaterial* mat = scene->mMaterials[material];
  aiString name;
  if (mat->Get(AI_MATKEY_NAME, name) == AI_SUCCESS && std::strcmp(name.C_Str(), AI_DEFAULT_MATERIAL_NAME) == 0) {
    return std::nullopt;
  }
  aiColor4D c;
  if (mat->Get(AI_MATKEY_COLOR_DIFFUSE, c) != AI_SUCCESS) return std::nullopt;
  const auto channel = [](float v) {
    const double x = std::isfinite(v) ? std::clamp(static_cast<double>(v), 0.0, 1.0) : 0.0;
    return static_cast<uint32_t>(std::lround(x * 255.0));
  };
  return (channel(c.r) << 16) | (channel(c.g) << 8) | channel(c.b);
}

// How file coordinates (as assimp delivers them, root transform included) become y-up metres.
struct Frame {
  glm::dmat3 axes{1.0};  // applied first
  double scale = 1.0;
  std::vector<std::string> notes;
};

Frame chooseFrame(const aiScene* scene, Format format, std::span<const uint8_t> head, const LoadOptions& options,
                  const std::vector<Instance>& instances) {
  Frame f;
  const bool up_given = options.up_axis == 'y' || options.up_axis == 'z';
  const bool unit_given = options.unit_scale > 0.0;
  const glm::dmat3 given_up = options.up_axis == 'z' ? kZUpToYUp : glm::dmat3(1.0);
  const std::string up_note = std::string("up axis ") + (options.up_axis == 'z' ? "z (turned to y)" : "y") +
                              " (given on the command line)";
  const std::string unit_note = "unit scale " + fixed(options.unit_scale) + " m per file unit (given on the command line)";
  switch (format) {
    case Format::kIfc: {
      const IfcUnit unit = ifcLengthUnit(head);
      if (up_given) {
        f.axes = given_up * glm::inverse(kZUpToYUp);  // undo assimp's root rotation first
        f.notes.push_back(up_note + "; assimp's own IFC z-up to y-up turn undone");
      } else {
        f.notes.push_back("up axis: IFC is z-up; assimp's IFC importer turned it to y-up");
      }
      if (unit_given) {
        f.scale = options.unit_scale / unit.metres.value_or(1.0);
        f.notes.push_back(unit_note);
      } else if (unit.metres) {
        f.notes.push_back("units: the IFC length unit is " + unit.name +
                          (*unit.metres == 1.0 ? std::string() : ", converted to metres by assimp"));
      } else {
        // Extent of the model as assimp delivered it, for the millimetre heuristic.
        double extent = 0.0;
        glm::dvec3 lo(1e300), hi(-1e300);
        for (const auto& inst : instances) {
          for (unsigned v = 0; v < inst.mesh->mNumVertices; ++v) {
            const aiVector3D& p = inst.mesh->mVertices[v];
            const glm::dvec3 q = glm::dvec3(inst.world * glm::dvec4(p.x, p.y, p.z, 1.0));
            lo = glm::min(lo, q);
            hi = glm::max(hi, q);
          }
        }
        if (lo.x <= hi.x) extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
        const std::string kind = unit.conversion_based ? "only a conversion-based length unit (assimp ignores it)"
                                                       : "no length unit";
        if (std::isfinite(extent) && extent > kMillimetreExtent) {
          f.scale = 1e-3;
          f.notes.push_back("units: the IFC has " + kind + " and is " + fixed(extent) +
                            " units across: assumed millimetres (a building over 1 km across is unlikely)");
        } else {
          f.notes.push_back("units: the IFC has " + kind + ": assumed metres");
        }
      }
      break;
    }
    case Format::kCollada: {
      const ColladaAsset asset = colladaAsset(head);
      // The up axis: assimp was told to ignore it when one is given (see loadBytes).
      if (up_given) {
        f.axes = given_up;
        f.notes.push_back(up_note + "; the file's <up_axis> " + asset.up + " ignored");
      } else {
        f.notes.push_back("up axis: Collada <up_axis> " + asset.up + ", applied by assimp");
      }
      if (unit_given) {
        f.scale = options.unit_scale / asset.meter;
        f.notes.push_back(unit_note + "; the file's <unit meter=" + fixed(asset.meter) + "> undone");
      } else {
        f.notes.push_back("units: Collada <unit meter=" + fixed(asset.meter) + ">, applied by assimp");
      }
      break;
    }
    case Format::kFbx: {
      std::string what;
      const std::optional<glm::dmat3> axes = fbxAxes(scene->mMetaData, what);
      if (up_given) {
        f.axes = given_up;
        f.notes.push_back(up_note + "; the FBX axis metadata ignored");
      } else if (axes) {
        f.axes = *axes;
        f.notes.push_back("up axis: FBX axis metadata says " + what + ", turned to +y up, +z front");
      } else {
        f.notes.push_back("up axis: the FBX has no axis metadata: assumed y-up");
      }
      const std::optional<double> cm = metaNumber(scene->mMetaData, "UnitScaleFactor");
      if (unit_given) {
        f.scale = options.unit_scale;
        f.notes.push_back(unit_note + "; the FBX UnitScaleFactor ignored");
      } else if (cm && std::isfinite(*cm) && *cm > 0.0) {
        f.scale = *cm / 100.0;
        f.notes.push_back("units: FBX UnitScaleFactor " + fixed(*cm) + " cm per file unit, so " + fixed(f.scale) +
                          " m per unit");
      } else {
        f.scale = 0.01;
        f.notes.push_back("units: the FBX has no UnitScaleFactor: assumed centimetres (FBX's default)");
      }
      break;
    }
    case Format::k3ds:
      if (up_given) {
        f.axes = given_up * glm::inverse(kZUpToYUp);
        f.notes.push_back(up_note + "; assimp's own 3DS z-up to y-up turn undone");
      } else {
        f.notes.push_back("up axis: 3DS is z-up; assimp's 3DS importer turned it to y-up");
      }
      f.scale = unit_given ? options.unit_scale : 1.0;
      f.notes.push_back(unit_given ? unit_note : "units: 3DS states none: assumed metres");
      break;
    case Format::kOther:
      f.axes = given_up;
      f.scale = unit_given ? options.unit_scale : 1.0;
      f.notes.push_back(up_given ? up_note : "up axis: the format states none: assumed y-up");
      f.notes.push_back(unit_given ? unit_note : "units: the format states none: assumed metres");
      break;
  }
  return f;
}

void configure(Assimp::Importer& importer, const LoadOptions& options) {
  // No DefaultLogger is ever created, so assimp prints nothing.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // IfcSpace volumes are air, not walls (assimp's default, stated because walking depends on it).
  importer.SetPropertyBool(AI_CONFIG_IMPORT_IFC_SKIP_SPACE_REPRESENTATIONS, true);
  if (options.up_axis == 'y' || options.up_axis == 'z') {
    importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  }
}

const aiScene* importFile(Assimp::Importer& importer, std::span<const uint8_t> bytes, const std::string& path,
                          const std::string& ext, const LoadOptions& options) {
  configure(importer, options);
  constexpr unsigned kFlags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                              aiProcess_ValidateDataStructure | aiProcess_FindDegenerates | aiProcess_SortByPType;
  if (!path.empty()) return importer.ReadFile(path, kFlags);  // from disk: external files (OBJ .mtl) resolve
  importer.SetIOHandler(new NoFilesIOSystem);                 // the importer owns it
  return importer.ReadFileFromMemory(bytes.data(), bytes.size(), kFlags, ext.c_str());
}

// assimp 5.2 crashes on some malformed files in ways no scan here foresees (fuzz_assimp found
// null dereferences in the IFC reader for an entity of an unknown type name). So the import runs
// once in a forked child first, with stderr closed (a sanitizer's report would be a second line);
// a child that dies or exits other than 0 (read) or 3 (assimp's own error) means the file would
// crash us. The import in this process then follows. Costs one more import (FZK-Haus: +0.1 s).
void probeInChild(std::span<const uint8_t> bytes, const std::string& path, const std::string& ext,
                  const LoadOptions& options, const std::string& context) {
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return;  // cannot fork (no memory for it): import unguarded, as assimp's own caller would
  if (pid == 0) {
    // Die plainly by the signal: no sanitizer or libFuzzer crash handler (libFuzzer's would write
    // a crash artifact for the parent's input), and no core file.
    for (int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
    const rlimit no_core{0, 0};
    setrlimit(RLIMIT_CORE, &no_core);
    // A reader caught in a loop ends here rather than hanging the command: SIGALRM's default
    // action ends the child. The default limit is far above any real file's import (FZK-Haus:
    // 0.2 s; the 512 MiB size cap reads in well under a minute).
    std::signal(SIGALRM, SIG_DFL);
    alarm(std::max(1u, options.import_seconds_max));
    const int null_fd = open("/dev/null", O_WRONLY);
    if (null_fd >= 0) {
      dup2(null_fd, STDERR_FILENO);
      dup2(null_fd, STDOUT_FILENO);
    }
    int code = 3;
    try {
      Assimp::Importer importer;
      code = importFile(importer, bytes, path, ext, options) ? 0 : 3;
    } catch (...) {
      code = 3;
    }
    _exit(code);  // no atexit handlers, no leak check: the parent does the real work
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return;
  }
  if (WIFEXITED(status) && (WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 3)) return;
  if (WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM) {
    throw Error(context + ": assimp did not finish reading it in " + std::to_string(std::max(1u, options.import_seconds_max)) +
                     " s: the file is malformed or too large");
  }
  const std::string how = WIFSIGNALED(status) ? std::string("signal ") + std::to_string(WTERMSIG(status)) + " (" +
                                                    strsignal(WTERMSIG(status)) + ")"
                                              : "exit status " + std::to_string(WEXITSTATUS(status));
  throw Error(context + ": assimp crashed reading it (" + how + "): the file is malformed");
}

Scene loadBytes(std::span<const uint8_t> bytes, const std::string& path_or_empty, const std::string& ext_in,
                const std::string& context, const LoadOptions& options) {
  if (bytes.size() > kMaxFileBytes) {
    throw Error(context + ": file too large for the assimp loader (" + std::to_string(bytes.size() >> 20) +
                     " MiB, at most " + std::to_string(kMaxFileBytes >> 20) + " MiB)");
  }
  if (bytes.empty()) throw Error(context + ": empty file");
  std::string ext;
  for (char c : asciiLower(ext_in)) {
    if (std::isalnum(static_cast<unsigned char>(c)) && ext.size() < 16) ext += c;
  }
  // See checkStepReferences: IFC is the only STEP file assimp reads.
  {
    std::string_view head = asText(bytes).substr(0, 64);
    while (!head.empty() && std::isspace(static_cast<unsigned char>(head.front()))) head.remove_prefix(1);
    if (head.substr(0, 12) == "ISO-10303-21") checkStepReferences(asText(bytes), context);
  }
  // See checkColladaNodes: assimp picks its Collada reader by content too, so look at the bytes.
  if (ext == "dae" || ext == "xml" || asText(bytes).substr(0, 1 << 16).find("<COLLADA") != std::string_view::npos) {
    checkColladaNodes(asText(bytes), context);
  }
  probeInChild(bytes, path_or_empty, ext, options, context);
  Assimp::Importer importer;
  const aiScene* scene = nullptr;
  try {
    scene = importFile(importer, bytes, path_or_empty, ext, options);
  } catch (const std::exception& e) {
    throw Error(context + ": assimp: " + oneLineMessage(e.what()));
  }
  if (!scene) {
    const std::string error = oneLineMessage(importer.GetErrorString());
    // What assimp says when points and lines were all there was, or a mesh had no faces at all.
    if (error.find("No meshes remaining") != std::string::npos || error.find("contains no faces") != std::string::npos) {
      throw Error(context + ": no triangles (assimp: " + error + ")");
    }
    throw Error(context + ": assimp: " + error);
  }
  if (!scene->mRootNode) throw Error(context + ": assimp: no node tree");

  const std::vector<Instance> instances = collectInstances(scene, context);
  uint64_t triangles = 0;
  for (const auto& inst : instances) {
    if (inst.mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) triangles += inst.mesh->mNumFaces;
  }
  if (triangles == 0) {
    throw Error(context + ": no triangles (assimp read " + std::to_string(scene->mNumMeshes) + " meshes, " +
                     std::to_string(instances.size()) + " mesh instances, none with triangles)");
  }
  if (triangles > kMaxTriangles) {
    throw Error(context + ": " + std::to_string(triangles) + " triangles over all mesh instances, more than " +
                     std::to_string(kMaxTriangles));
  }

  const Format format = formatOf(scene, ext);
  const Frame frame = chooseFrame(scene, format, bytes, options, instances);

  Scene out;
  std::vector<glm::dvec3> positions;
  std::vector<uint32_t> indices, sizes, colors;
  uint32_t object = 0;
  for (const auto& inst : instances) {
    const aiMesh* mesh = inst.mesh;
    ++object;
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) || !mesh->mVertices || !mesh->mFaces) continue;
    glm::dmat4 world = inst.world;
    const glm::dmat3 linear = frame.scale * frame.axes * glm::dmat3(world);
    const glm::dvec3 offset = frame.scale * (frame.axes * glm::dvec3(world[3]));
    // A mirroring transform turns counter-clockwise faces clockwise: reverse them back.
    const bool mirrored = glm::determinant(linear) < 0.0;
    positions.resize(mesh->mNumVertices);
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      positions[v] = linear * glm::dvec3(p.x, p.y, p.z) + offset;
    }
    indices.clear();
    sizes.clear();
    for (unsigned fi = 0; fi < mesh->mNumFaces; ++fi) {
      const aiFace& face = mesh->mFaces[fi];
      if (face.mNumIndices != 3 || !face.mIndices) continue;  // points and lines left after sorting
      for (unsigned k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices) {
          throw Error(context + ": assimp: mesh '" + oneLineMessage(mesh->mName.C_Str()) + "' face " +
                           std::to_string(fi) + ": index " + std::to_string(face.mIndices[k]) + " out of range (" +
                           std::to_string(mesh->mNumVertices) + " vertices)");
        }
      }
      indices.push_back(face.mIndices[0]);
      indices.push_back(face.mIndices[mirrored ? 2 : 1]);
      indices.push_back(face.mIndices[mirrored ? 1 : 2]);
      sizes.push_back(3);
    }
    if (sizes.empty()) continue;
    // One colour for the whole instance without a material colour, so merging can still join its
    // coplanar triangles.
    const uint32_t color = diffuseColor(scene, mesh->mMaterialIndex).value_or(faceColor(object - 1));
    colors.assign(sizes.size(), color);
    MeshObjectInput input;
    input.positions = positions;
    input.indices = indices;
    input.face_sizes = sizes;
    input.face_colors = colors;
    addMeshObject(out, input, options.merge_faces, context);
  }
  out.report.notes.insert(out.report.notes.end(), frame.notes.begin(), frame.notes.end());
  out.report.notes.push_back("assimp: " + std::to_string(instances.size()) + " mesh instances of " +
                             std::to_string(scene->mNumMeshes) + " meshes, " + std::to_string(triangles) +
                             " triangles");
  return out;
}

std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  return asciiLower(ext);
}

}  // namespace

Scene loadAssimp(const std::string& path, const LoadOptions& options) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxFileBytes) {
    throw Error(path + ": file too large for the assimp loader (" + std::to_string(size >> 20) +
                     " MiB, at most " + std::to_string(kMaxFileBytes >> 20) + " MiB)");
  }
  // Read here too: a missing file gets our message, and the unit sniffing needs the bytes.
  const std::vector<uint8_t> bytes = readFileBytes(path);
  return loadBytes(bytes, path, extensionOf(path), path, options);
}

Scene loadAssimpFromMemory(std::span<const uint8_t> bytes, const std::string& extension_hint,
                           const std::string& context, const LoadOptions& options) {
  std::string ext = extension_hint;
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  return loadBytes(bytes, "", ext, context, options);
}

bool assimpReadsExtension(const std::string& extension) {
  std::string ext = asciiLower(extension);
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  if (ext.empty()) return false;
  // One importer for the question: constructing one registers every reader (milliseconds).
  static const Assimp::Importer* const importer = new Assimp::Importer;
  return importer->IsExtensionSupported("." + ext);
}

}  // namespace walkvis
