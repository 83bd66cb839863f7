// glTF 2.0 scenes (.gltf JSON with external or data-URI buffers, .glb binary). Format: the Khronos
// glTF 2.0 specification, https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html.
//
// tinygltf parses the JSON and buffers; it does not check that accessors, buffer views and node
// references stay inside what they point at, so every index and byte range used here is checked
// first and anything malformed is a one-line Error naming the file. Each triangle of a
// TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive of the default scene's node trees becomes one
// input face, in world coordinates (node matrices or TRS applied); each primitive of a node instance
// is one object for face merging (mesh_merge.h). Images are never decoded.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>  // tinygltf uses std::ofstream even with TINYGLTF_NO_FS
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
// Our own file callbacks below decide whether a buffer may come from disk at all.
#define TINYGLTF_NO_FS
#include <tiny_gltf.h>

#include "core/byte_io.h"
#include "scenes/loaders.h"
#include "scenes/mesh_merge.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

// A BSP over more input faces than this is far beyond what a walkthrough tree can hold; the cap
// also bounds the memory a small file can demand by instancing one mesh from many nodes.
constexpr uint64_t kMaxTriangles = uint64_t{1} << 22;
// tinygltf takes sizes as unsigned int.
constexpr uint64_t kMaxFileBytes = uint64_t{1} << 31;

struct FileAccess {
  bool allowed = false;
};

bool fileExists(const std::string& path, void* user) {
  if (!static_cast<FileAccess*>(user)->allowed) return false;
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec) && std::filesystem::file_size(path, ec) < kMaxFileBytes && !ec;
}

std::string expandFilePath(const std::string& path, void*) { return path; }

bool readWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  if (!static_cast<FileAccess*>(user)->allowed) {
    if (err) *err = "external files are not read when loading from memory";
    return false;
  }
  try {
    *out = readFileBytes(path);
  } catch (const Error& e) {
    if (err) *err = e.what();
    return false;
  }
  return true;
}

bool writeWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err = "walkvis never writes glTF files";
  return false;
}

// Images are never needed: accept them undecoded.
bool skipImage(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

// tinygltf turns `extras` and `extensions` into its own Value tree by recursion, one call per level:
// deep nesting overflows the stack. Real glTF nests about ten levels; far more is refused up front.
constexpr int kMaxJsonDepth = 256;

// The deepest nesting of arrays and objects in JSON text (strings skipped; no other checks).
void checkJsonDepth(std::string_view json, const std::string& context) {
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) {
        throw Error(context + ": malformed glTF: JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                         " levels");
      }
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

uint32_t u32le(const uint8_t* p) {
  return uint32_t{p[0]} | (uint32_t{p[1]} << 8) | (uint32_t{p[2]} << 16) | (uint32_t{p[3]} << 24);
}

class GltfBuilder {
 public:
  GltfBuilder(const tinygltf::Model& model, const std::string& context, bool merge)
      : model_(model), context_(context), merge_(merge) {}

  [[noreturn]] void fail(const std::string& what) const { throw Error(context_ + ": " + what); }

  Scene build() {
    std::vector<int> roots;
    if (!model_.scenes.empty()) {
      int s = model_.defaultScene < 0 ? 0 : model_.defaultScene;
      if (s >= static_cast<int>(model_.scenes.size())) {
        fail("default scene " + std::to_string(s) + " out of range (" + std::to_string(model_.scenes.size()) +
             " scenes)");
      }
      roots = model_.scenes[static_cast<size_t>(s)].nodes;
    } else {
      // No scene: every node that is no other node's child is a root.
      std::vector<bool> is_child(model_.nodes.size(), false);
      for (const auto& node : model_.nodes) {
        for (int c : node.children) {
          if (c >= 0 && c < static_cast<int>(model_.nodes.size())) is_child[static_cast<size_t>(c)] = true;
        }
      }
      for (size_t i = 0; i < model_.nodes.size(); ++i) {
        if (!is_child[i]) roots.push_back(static_cast<int>(i));
      }
    }
    visited_.assign(model_.nodes.size(), false);
    // Explicit stack: a malicious file can chain nodes deeper than the call stack goes.
    std::vector<std::pair<int, glm::dmat4>> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, glm::dmat4(1.0));
    std::vector<std::pair<int, glm::dmat4>> instances;  // (mesh, world transform)
    while (!stack.empty()) {
      const auto [index, parent] = stack.back();
      stack.pop_back();
      const tinygltf::Node& node = nodeAt(index);
      const glm::dmat4 world = parent * localTransform(node, index);
      if (node.mesh >= 0 || node.mesh < -1) instances.emplace_back(node.mesh, world);
      for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.emplace_back(*it, world);
    }
    // Count before building: a small file instancing one mesh from many nodes must be refused
    // before it has cost the memory and time, not after.
    uint64_t triangles = 0;
    for (const auto& [mesh, world] : instances) {
      triangles += declaredTriangles(mesh);
      if (triangles > kMaxTriangles) fail("more than " + std::to_string(kMaxTriangles) + " triangles");
    }
    for (const auto& [mesh, world] : instances) addMesh(mesh, world);
    if (scene_.report.input_faces == 0) fail("no faces (no triangles in the default scene)");
    if (skipped_primitives_ > 0) {
      scene_.report.notes.push_back(std::to_string(skipped_primitives_) +
                                    " point or line primitive(s) skipped (no area)");
    }
    return std::move(scene_);
  }

 private:
  const tinygltf::Node& nodeAt(int index) {
    if (index < 0 || index >= static_cast<int>(model_.nodes.size())) {
      fail("node " + std::to_string(index) + " out of range (" + std::to_string(model_.nodes.size()) + " nodes)");
    }
    // The spec makes node hierarchies disjoint strict trees; a second visit would be a cycle or a
    // node with two parents, and repeated children could blow the scene up exponentially.
    if (visited_[static_cast<size_t>(index)]) {
      fail("node " + std::to_string(index) + " is reached twice (a cycle or a node with two parents)");
    }
    visited_[static_cast<size_t>(index)] = true;
    return model_.nodes[static_cast<size_t>(index)];
  }

  glm::dmat4 localTransform(const tinygltf::Node& node, int index) const {
    const std::string what = "node " + std::to_string(index);
    if (!node.matrix.empty()) {
      if (node.matrix.size() != 16) fail(what + ": matrix has " + std::to_string(node.matrix.size()) + " numbers, not 16");
      return glm::make_mat4(node.matrix.data());  // glTF matrices are column-major, as glm's
    }
    glm::dmat4 m(1.0);
    if (!node.translation.empty()) {
      if (node.translation.size() != 3) fail(what + ": translation needs 3 numbers");
      m = glm::translate(m, glm::dvec3(node.translation[0], node.translation[1], node.translation[2]));
    }
    if (!node.rotation.empty()) {
      if (node.rotation.size() != 4) fail(what + ": rotation needs 4 numbers");
      glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);  // glTF: x y z w
      const double len = glm::length(q);
      if (!(len > 0.0) || !std::isfinite(len)) fail(what + ": rotation is not a unit quaternion");
      m = m * glm::mat4_cast(q / len);
    }
    if (!node.scale.empty()) {
      if (node.scale.size() != 3) fail(what + ": scale needs 3 numbers");
      m = glm::scale(m, glm::dvec3(node.scale[0], node.scale[1], node.scale[2]));
    }
    return m;
  }

  // The checked byte range of an accessor: element i starts at data + i * stride.
  struct View {
    const uint8_t* data = nullptr;
    size_t count = 0;
    size_t stride = 0;
    int component_type = 0;
    int components = 0;
  };

  View accessorView(int index, const std::string& what) const {
    if (index < 0 || index >= static_cast<int>(model_.accessors.size())) {
      fail(what + ": accessor " + std::to_string(index) + " out of range (" +
           std::to_string(model_.accessors.size()) + " accessors)");
    }
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(index)];
    const std::string name = what + ": accessor " + std::to_string(index);
    if (a.sparse.isSparse) fail(name + " is sparse (not supported)");
    const int comp_size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
    const int comps = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
    if (comp_size <= 0) fail(name + " has bad componentType " + std::to_string(a.componentType));
    if (comps <= 0) fail(name + " has bad type " + std::to_string(a.type));
    View v;
    v.count = a.count;
    v.component_type = a.componentType;
    v.components = comps;
    if (a.count == 0) return v;
    if (a.bufferView < 0 || a.bufferView >= static_cast<int>(model_.bufferViews.size())) {
      fail(name + ": bufferView " + std::to_string(a.bufferView) + " out of range (" +
           std::to_string(model_.bufferViews.size()) + " buffer views)");
    }
    const tinygltf::BufferView& bv = model_.bufferViews[static_cast<size_t>(a.bufferView)];
    if (bv.buffer < 0 || bv.buffer >= static_cast<int>(model_.buffers.size())) {
      fail(name + ": buffer " + std::to_string(bv.buffer) + " out of range (" + std::to_string(model_.buffers.size()) +
           " buffers)");
    }
    const std::vector<unsigned char>& data = model_.buffers[static_cast<size_t>(bv.buffer)].data;
    if (bv.byteLength > data.size() || bv.byteOffset > data.size() - bv.byteLength) {
      fail(name + ": bufferView " + std::to_string(a.bufferView) + " (offset " + std::to_string(bv.byteOffset) +
           ", length " + std::to_string(bv.byteLength) + ") out of range of its buffer (" +
           std::to_string(data.size()) + " bytes)");
    }
    const size_t elem = static_cast<size_t>(comp_size) * static_cast<size_t>(comps);
    const size_t stride = bv.byteStride == 0 ? elem : bv.byteStride;
    if (stride < elem) fail(name + ": byteStride " + std::to_string(stride) + " < element size " + std::to_string(elem));
    // Last byte needed: byteOffset + stride·(count − 1) + elem, computed without overflow.
    const size_t len = bv.byteLength;
    const bool fits = a.byteOffset <= len && elem <= len - a.byteOffset &&
                      (a.count - 1) <= (len - a.byteOffset - elem) / stride;
    if (!fits) {
      fail(name + " (offset " + std::to_string(a.byteOffset) + ", " + std::to_string(a.count) + " elements of " +
           std::to_string(elem) + " bytes, stride " + std::to_string(stride) + ") out of range of bufferView " +
           std::to_string(a.bufferView) + " (" + std::to_string(len) + " bytes)");
    }
    v.data = data.data() + bv.byteOffset + a.byteOffset;
    v.stride = stride;
    return v;
  }

  std::vector<glm::dvec3> positions(int index, const std::string& what) const {
    const View v = accessorView(index, what);
    if (v.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT || v.components != 3) {
      fail(what + ": POSITION accessor " + std::to_string(index) + " is not float VEC3");
    }
    std::vector<glm::dvec3> out(v.count);
    for (size_t i = 0; i < v.count; ++i) {
      float f[3];
      std::memcpy(f, v.data + i * v.stride, sizeof f);
      if (!std::isfinite(f[0]) || !std::isfinite(f[1]) || !std::isfinite(f[2])) {
        fail(what + ": POSITION " + std::to_string(i) + " is not finite");
      }
      out[i] = glm::dvec3(f[0], f[1], f[2]);
    }
    return out;
  }

  std::vector<uint32_t> indices(int index, size_t vertex_count, const std::string& what) const {
    const View v = accessorView(index, what);
    if (v.components != 1) fail(what + ": index accessor " + std::to_string(index) + " is not SCALAR");
    std::vector<uint32_t> out(v.count);
    for (size_t i = 0; i < v.count; ++i) {
      const uint8_t* p = v.data + i * v.stride;
      uint32_t value = 0;
      switch (v.component_type) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: value = p[0]; break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: value = uint32_t{p[0]} | (uint32_t{p[1]} << 8); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: value = u32le(p); break;
        default: fail(what + ": index accessor " + std::to_string(index) + " has componentType " +
                      std::to_string(v.component_type) + " (expected unsigned byte, short or int)");
      }
      if (value >= vertex_count) {
        fail(what + ": index " + std::to_string(value) + " out of range (" + std::to_string(vertex_count) +
             " vertices)");
      }
      out[i] = value;
    }
    return out;
  }

  // The primitive's base colour; none for no material or the default white (colour from a
  // texture), where a per-face colour tells faces apart better.
  std::optional<uint32_t> materialColor(int material, const std::string& what) const {
    if (material < 0) return std::nullopt;
    if (material >= static_cast<int>(model_.materials.size())) {
      fail(what + ": material " + std::to_string(material) + " out of range (" +
           std::to_string(model_.materials.size()) + " materials)");
    }
    const auto& f = model_.materials[static_cast<size_t>(material)].pbrMetallicRoughness.baseColorFactor;
    if (f.size() < 3) return std::nullopt;
    uint32_t out = 0;
    for (int i = 0; i < 3; ++i) {
      const double c = std::isfinite(f[static_cast<size_t>(i)]) ? std::clamp(f[static_cast<size_t>(i)], 0.0, 1.0) : 0.0;
      out = (out << 8) | static_cast<uint32_t>(std::lround(c * 255.0));
    }
    if (out == 0xffffff) return std::nullopt;
    return out;
  }

  // Triangles the mesh's primitives hold (their accessors' byte ranges checked); 0 for a mesh or
  // primitive addMesh will refuse, so that it gives the error.
  uint64_t declaredTriangles(int mesh_index) const {
    if (mesh_index < 0 || mesh_index >= static_cast<int>(model_.meshes.size())) return 0;
    const auto& primitives = model_.meshes[static_cast<size_t>(mesh_index)].primitives;
    uint64_t total = 0;
    for (size_t p = 0; p < primitives.size(); ++p) {
      const auto& prim = primitives[p];
      const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      int accessor = prim.indices;
      if (accessor < 0) {
        const auto it = prim.attributes.find("POSITION");
        accessor = it == prim.attributes.end() ? -1 : it->second;
      }
      if (accessor < 0) continue;
      const uint64_t n =
          accessorView(accessor, "mesh " + std::to_string(mesh_index) + " primitive " + std::to_string(p)).count;
      if (mode == TINYGLTF_MODE_TRIANGLES) total += n / 3;
      if ((mode == TINYGLTF_MODE_TRIANGLE_STRIP || mode == TINYGLTF_MODE_TRIANGLE_FAN) && n >= 3) total += n - 2;
    }
    return total;
  }

  void addMesh(int mesh_index, const glm::dmat4& world) {
    if (mesh_index < 0 || mesh_index >= static_cast<int>(model_.meshes.size())) {
      fail("mesh " + std::to_string(mesh_index) + " out of range (" + std::to_string(model_.meshes.size()) + " meshes)");
    }
    const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(mesh_index)];
    // A mirroring transform turns counter-clockwise triangles clockwise (glTF spec, 3.7.4).
    const bool flip = glm::determinant(glm::dmat3(world)) < 0.0;
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const tinygltf::Primitive& prim = mesh.primitives[p];
      const std::string what = "mesh " + std::to_string(mesh_index) + " primitive " + std::to_string(p);
      const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
          mode == 3 /* LINE_STRIP */) {
        ++skipped_primitives_;
        continue;
      }
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        fail(what + ": bad mode " + std::to_string(prim.mode));
      }
      const auto pos_it = prim.attributes.find("POSITION");
      if (pos_it == prim.attributes.end()) fail(what + " has no POSITION attribute");
      const std::vector<glm::dvec3> local = positions(pos_it->second, what);
      std::vector<uint32_t> order;
      if (prim.indices >= 0) {
        order = indices(prim.indices, local.size(), what);
      } else {
        if (prim.indices < -1) fail(what + ": indices accessor " + std::to_string(prim.indices) + " out of range");
        order.resize(local.size());
        for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<uint32_t>(i);
      }
      if (mode == TINYGLTF_MODE_TRIANGLES && order.size() % 3 != 0) {
        fail(what + ": " + std::to_string(order.size()) + " vertices is not a whole number of triangles");
      }
      const size_t triangles = mode == TINYGLTF_MODE_TRIANGLES ? order.size() / 3
                                                                : (order.size() >= 3 ? order.size() - 2 : 0);
      std::vector<glm::dvec3> world_pos(local.size());
      for (size_t i = 0; i < local.size(); ++i) world_pos[i] = glm::dvec3(world * glm::dvec4(local[i], 1.0));
      const std::optional<uint32_t> material_color = materialColor(prim.material, what);
      const std::string face_context = context_ + ": " + what;
      // One object per primitive of a node instance (mesh_merge.h).
      std::vector<uint32_t> object_indices;
      object_indices.reserve(3 * triangles);
      for (size_t t = 0; t < triangles; ++t) {
        std::array<uint32_t, 3> tri;
        if (mode == TINYGLTF_MODE_TRIANGLES) {
          tri = {order[3 * t], order[3 * t + 1], order[3 * t + 2]};
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
          // Every other strip triangle is listed clockwise; swap two corners to keep CCW.
          tri = t % 2 == 0 ? std::array{order[t], order[t + 1], order[t + 2]}
                           : std::array{order[t + 1], order[t], order[t + 2]};
        } else {
          tri = {order[0], order[t + 1], order[t + 2]};
        }
        if (flip) std::swap(tri[1], tri[2]);
        object_indices.insert(object_indices.end(), tri.begin(), tri.end());
      }
      const std::vector<uint32_t> sizes(triangles, 3u);
      const std::vector<uint32_t> colors(triangles, material_color ? *material_color : kFaceColorById);
      const MeshObjectInput object{world_pos, object_indices, sizes, colors};
      addMeshObject(scene_, object, merge_, face_context);
    }
  }

  const tinygltf::Model& model_;
  const std::string& context_;
  const bool merge_;
  Scene scene_;
  std::vector<bool> visited_;
  uint64_t skipped_primitives_ = 0;
};

Scene loadGltfBytes(std::span<const uint8_t> bytes, const std::string& context, bool binary, bool files_allowed,
                    const std::string& base_dir, bool merge) {
  if (bytes.size() >= kMaxFileBytes) throw Error(context + ": file too large for glTF (" +
                                                       std::to_string(bytes.size()) + " bytes)");
  if (binary) {
    // The 12-byte GLB header, checked here for clearer messages than tinygltf's.
    if (bytes.size() < 12) {
      throw Error(context + ": truncated GLB header (" + std::to_string(bytes.size()) + " bytes, need 12)");
    }
    if (std::memcmp(bytes.data(), "glTF", 4) != 0) throw Error(context + ": not a GLB file (bad magic)");
    const uint32_t version = u32le(bytes.data() + 4);
    if (version != 2) throw Error(context + ": GLB version " + std::to_string(version) + " (only 2 is supported)");
    const uint32_t length = u32le(bytes.data() + 8);
    if (length > bytes.size()) {
      throw Error(context + ": truncated GLB (header says " + std::to_string(length) + " bytes, file has " +
                       std::to_string(bytes.size()) + ")");
    }
    if (bytes.size() < 20) throw Error(context + ": truncated GLB (no JSON chunk)");
    const size_t json_length = std::min<size_t>(u32le(bytes.data() + 12), bytes.size() - 20);
    checkJsonDepth({reinterpret_cast<const char*>(bytes.data()) + 20, json_length}, context);
  } else {
    checkJsonDepth({reinterpret_cast<const char*>(bytes.data()), bytes.size()}, context);
  }
  tinygltf::TinyGLTF loader;
  FileAccess access{files_allowed};
  loader.SetFsCallbacks({&fileExists, &expandFilePath, &readWholeFile, &writeWholeFile, &access});
  loader.SetImageLoader(&skipImage, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  try {
    const auto size = static_cast<unsigned int>(bytes.size());
    if (binary) {
      ok = loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), size, base_dir);
    } else {
      ok = loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()), size,
                                      base_dir);
    }
  } catch (const std::exception& e) {
    // nlohmann::json and std containers inside tinygltf may throw on odd input.
    // tinygltf's messages may quote a whole data URI: 200 characters are plenty.
    throw Error(context + ": malformed glTF: " + oneLineMessage(e.what(), 200));
  }
  if (!ok) throw Error(context + ": malformed glTF: " + oneLineMessage(err, 200));
  return GltfBuilder(model, context, merge).build();
}

}  // namespace

Scene loadGltfFromMemory(std::span<const uint8_t> bytes, const std::string& context, bool binary, bool merge) {
  return loadGltfBytes(bytes, context, binary, /*files_allowed=*/false, "", merge);
}

Scene loadGltf(const std::string& path, bool merge) {
  const std::vector<uint8_t> bytes = readFileBytes(path);
  std::string ext = std::filesystem::path(path).extension().string();
  ext = asciiLower(ext);
  const bool binary = ext == ".glb";
  std::string dir = std::filesystem::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  return loadGltfBytes(bytes, path, binary, /*files_allowed=*/true, dir, merge);
}

}  // namespace walkvis
