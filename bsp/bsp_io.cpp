// BSP tree files: versioned, checksummed, written atomically.
//
// Layout (little-endian, fields written one by one, no padding):
//   header  : magic "WVBSP\r\n\x1a" (8), u32 version, u32 0, u64 payload bytes, u64 FNV-1a 64 of the payload
//   payload : u64 scene_hash, i32 root, stats (u64 nodes, fragments, input_polygons, f64 ratio,
//             u32 depth_max, f64 depth_mean, build_seconds, u64 bytes, exact_fallbacks),
//             u64 vertex, fragment and node counts, then the arrays:
//             vertex   = 3 f64
//             fragment = u32 first_vertex, vertex_count, face_id, polygon, 4 f64 plane (n, d), i8 orientation
//             node     = 4 f64 plane, u32 polygon, i32 front, back, parent, u32 first_fragment, fragment_count, depth
// Loading checks the magic, version, size, checksum and then every index, so that a file that
// passes can be traversed without further checks (children after parents, parent links
// consistent, node fragment ranges tiling the fragments).
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "bsp/bsp.h"
#include "bsp/bsp_internal.h"
#include "core/byte_io.h"
#include "core/hash.h"

namespace walkvis {

namespace {

constexpr char kMagic[8] = {'W', 'V', 'B', 'S', 'P', '\r', '\n', '\x1a'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 + 8;
constexpr size_t kVertexBytes = 3 * 8;
constexpr size_t kFragmentBytes = 4 * 4 + 4 * 8 + 1;
constexpr size_t kNodeBytes = 4 * 8 + 7 * 4;

using Writer = ByteWriter;

std::vector<uint8_t> serialize(const BspTree& tree, bool with_timing) {
  Writer w;
  w.put<uint64_t>(tree.scene_hash);
  w.put<int32_t>(tree.root);
  const BspStats& s = tree.stats;
  w.put<uint64_t>(s.nodes);
  w.put<uint64_t>(s.fragments);
  w.put<uint64_t>(s.input_polygons);
  w.put<double>(s.ratio);
  w.put<uint32_t>(s.depth_max);
  w.put<double>(s.depth_mean);
  w.put<double>(with_timing ? s.build_seconds : 0.0);
  w.put<uint64_t>(s.bytes);
  w.put<uint64_t>(s.exact_fallbacks);
  w.put<uint64_t>(tree.vertices.size());
  w.put<uint64_t>(tree.fragments.size());
  w.put<uint64_t>(tree.nodes.size());
  for (const glm::dvec3& v : tree.vertices) {
    w.put(v.x);
    w.put(v.y);
    w.put(v.z);
  }
  for (size_t i = 0; i < tree.fragments.size(); ++i) {
    const Polygon& f = tree.fragments[i];
    w.put<uint32_t>(f.first_vertex);
    w.put<uint32_t>(f.vertex_count);
    w.put<uint32_t>(f.face_id);
    w.put<uint32_t>(tree.fragment_polygon[i]);
    w.putPlane(f.plane);
    w.put<int8_t>(tree.fragment_orientation[i]);
  }
  for (const BspNode& n : tree.nodes) {
    w.putPlane(n.plane);
    w.put<uint32_t>(n.polygon);
    w.put<int32_t>(n.front);
    w.put<int32_t>(n.back);
    w.put<int32_t>(n.parent);
    w.put<uint32_t>(n.first_fragment);
    w.put<uint32_t>(n.fragment_count);
    w.put<uint32_t>(n.depth);
  }
  return std::move(w.bytes);
}

}  // namespace

std::vector<uint8_t> bspFileBytes(const BspTree& tree, const std::string& context, bool with_timing) {
  if (tree.fragment_polygon.size() != tree.fragments.size() ||
      tree.fragment_orientation.size() != tree.fragments.size())
    throw Error(context + ": BSP tree to save has inconsistent fragment arrays");
  const std::vector<uint8_t> payload = serialize(tree, with_timing);
  Writer file;
  for (char c : kMagic) file.put<char>(c);
  file.put<uint32_t>(kVersion);
  file.put<uint32_t>(0);
  file.put<uint64_t>(payload.size());
  file.put<uint64_t>(fnv1a(payload.data(), payload.size()));
  file.bytes.insert(file.bytes.end(), payload.begin(), payload.end());
  return std::move(file.bytes);
}

void saveBsp(const BspTree& tree, const std::string& path) {
  writeFileAtomically(path, bspFileBytes(tree, path), "BSP file");
}

BspTree loadBsp(const std::string& path) {
  const std::vector<uint8_t> bytes = readFileBytes(path);
  return loadBspFromMemory(bytes, path);
}

BspTree loadBspFromMemory(std::span<const uint8_t> bytes, const std::string& context) {
  ByteReader head(bytes, context + ": BSP file: ");
  if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    head.fail("not a walkvis BSP file (bad magic)");
  for (size_t i = 0; i < sizeof kMagic; ++i) head.get<char>();
  const uint32_t version = head.get<uint32_t>();
  if (version != kVersion)
    head.fail("version " + std::to_string(version) + ", this build reads version " + std::to_string(kVersion));
  head.get<uint32_t>();
  const uint64_t payload_size = head.get<uint64_t>();
  const uint64_t checksum = head.get<uint64_t>();
  if (payload_size != bytes.size() - kHeaderBytes)
    head.fail("truncated or padded (payload " + std::to_string(bytes.size() - kHeaderBytes) + " bytes, header says " +
              std::to_string(payload_size) + ")");
  const std::span<const uint8_t> payload = bytes.subspan(kHeaderBytes);
  if (fnv1a(payload.data(), payload.size()) != checksum) head.fail("checksum mismatch (corrupt file)");

  ByteReader r(payload, context + ": BSP file: ");
  BspTree tree;
  tree.scene_hash = r.get<uint64_t>();
  tree.root = r.get<int32_t>();
  BspStats& s = tree.stats;
  s.nodes = r.get<uint64_t>();
  s.fragments = r.get<uint64_t>();
  s.input_polygons = r.get<uint64_t>();
  s.ratio = r.get<double>();
  s.depth_max = r.get<uint32_t>();
  s.depth_mean = r.get<double>();
  s.build_seconds = r.get<double>();
  s.bytes = r.get<uint64_t>();
  s.exact_fallbacks = r.get<uint64_t>();
  const uint64_t nv = r.get<uint64_t>(), nf = r.get<uint64_t>(), nn = r.get<uint64_t>();
  // Sizes must match the payload exactly before anything is allocated.
  if (nv > r.remaining() / kVertexBytes || nf > r.remaining() / kFragmentBytes || nn > r.remaining() / kNodeBytes ||
      nv * kVertexBytes + nf * kFragmentBytes + nn * kNodeBytes != r.remaining())
    r.fail("array sizes do not match the file size");
  if (nv >= UINT32_MAX || nf >= INT32_MAX || nn >= INT32_MAX) r.fail("too many elements");
  tree.vertices.resize(nv);
  for (auto& v : tree.vertices) {
    v.x = r.get<double>();
    v.y = r.get<double>();
    v.z = r.get<double>();
  }
  tree.fragments.resize(nf);
  tree.fragment_polygon.resize(nf);
  tree.fragment_orientation.resize(nf);
  for (size_t i = 0; i < nf; ++i) {
    Polygon& f = tree.fragments[i];
    f.first_vertex = r.get<uint32_t>();
    f.vertex_count = r.get<uint32_t>();
    f.face_id = r.get<uint32_t>();
    tree.fragment_polygon[i] = r.get<uint32_t>();
    f.plane = r.getPlane();
    tree.fragment_orientation[i] = r.get<int8_t>();
  }
  tree.nodes.resize(nn);
  for (size_t i = 0; i < nn; ++i) {
    BspNode& n = tree.nodes[i];
    n.plane = r.getPlane();
    n.polygon = r.get<uint32_t>();
    n.front = r.get<int32_t>();
    n.back = r.get<int32_t>();
    n.parent = r.get<int32_t>();
    n.first_fragment = r.get<uint32_t>();
    n.fragment_count = r.get<uint32_t>();
    n.depth = r.get<uint32_t>();
  }
  if (const std::string problem = detail::bspStructureProblem(tree); !problem.empty()) r.fail(problem);
  return tree;
}

}  // namespace walkvis
