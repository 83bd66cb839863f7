// The modern peer: meshlet normal-cone culling from meshoptimizer [meshoptimizer] (Arseny Kapoulkine,
// https://github.com/zeux/meshoptimizer, Debian libmeshoptimizer-dev): meshopt_buildMeshlets
// (64 vertices / 124 triangles), meshopt_computeMeshletBounds, and the cone test that the header
// documents as the one safe for perspective, with the meshlet's bounding sphere:
//   dot(center − eye, cone_axis) >= cone_cutoff · |center − eye| + radius   → cull.
// Polygons are fan-triangulated over positions welded by exact equality, made relative to the
// centre of their bounding box (as a camera-relative renderer would) and rounded to float (the
// library's input format); the eye is made relative to the same centre in double. A unit is a meshlet; a polygon whose triangles fall into several
// meshlets is culled only when all of them are (expandToPolygons). State: the sphere and the cone,
// 32 bytes per meshlet. No margin of ours: this is the library's test as documented, measured as
// it is (false culls, if any, are the library's float arithmetic and are reported).
//
// Zero-area polygons (they were the "false culls" `bench backface` reported in the Freedoom MAP01
// PFD lists; counts: docs/backface/README.md, "Meshlet cones"):
// meshopt_computeClusterBounds (clusterizer.cpp) skips triangles whose float cross product is
// exactly zero, as invisible, and returns all-zero bounds for a meshlet of only such triangles
// (its comment: "degenerate cluster, no valid triangles => trivial reject (cone data is 0)"); the
// documented test then reads 0 >= 0·|c − e| + 0 and culls it for every eye. Our ground truth (the polygon's plane) calls such a polygon front-facing from
// its front side, so the bench counts it as a false cull; it has no pixels. Every such cull seen
// was of this kind (BSP fragments of MAP01 that are points or segments, of tiny area in double,
// exactly zero after rounding to float), or a sliver of the same kind whose float triangles have
// an area made by rounding alone and so a normal unrelated to its plane (segment-like fragments
// whose float normals lie far off the plane). coneInvisiblePolygons() names both kinds, so that a
// report can tell them apart from a culled polygon that has area.
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "backface/backface.h"
#include "core/check.h"
#include "core/hash.h"

namespace walkvis {
namespace {

struct ConeBounds {
  float center[3];
  float radius;
  float axis[3];
  float cutoff;
};
static_assert(sizeof(ConeBounds) == 32);

struct Vec3Hash {
  size_t operator()(const glm::dvec3& v) const {
    return static_cast<size_t>(fnv1aDoubles({v.x, v.y, v.z}));
  }
};

struct TriKeyHash {
  size_t operator()(const std::array<uint32_t, 3>& t) const {
    return (static_cast<size_t>(t[0]) * 73856093u) ^ (static_cast<size_t>(t[1]) * 19349663u) ^
           (static_cast<size_t>(t[2]) * 83492791u);
  }
};

// The library's input: fan triangles over positions welded by exact equality, relative to the
// centre of the input's box, in float.
struct MeshInput {
  glm::dvec3 origin{0.0};
  std::vector<float> positions;
  std::vector<uint32_t> indices, triangle_polygon;
};

MeshInput meshInput(const BackfaceInput& input) {
  MeshInput m;
  std::unordered_map<glm::dvec3, uint32_t, Vec3Hash> weld;
  if (!input.vertices.empty()) {
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (const auto& v : input.vertices) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    m.origin = 0.5 * (lo + hi);
  }
  auto vertexIndex = [&](const glm::dvec3& v) {
    auto [it, inserted] = weld.try_emplace(v, static_cast<uint32_t>(weld.size()));
    if (inserted) {
      m.positions.push_back(static_cast<float>(v.x - m.origin.x));
      m.positions.push_back(static_cast<float>(v.y - m.origin.y));
      m.positions.push_back(static_cast<float>(v.z - m.origin.z));
    }
    return it->second;
  };
  for (size_t p = 0; p < input.polygons.size(); ++p) {
    const Polygon& poly = input.polygons[p];
    const uint32_t first = vertexIndex(input.vertices[poly.first_vertex]);
    uint32_t prev = vertexIndex(input.vertices[poly.first_vertex + 1]);
    for (uint32_t k = 2; k < poly.vertex_count; ++k) {
      const uint32_t next = vertexIndex(input.vertices[poly.first_vertex + k]);
      m.indices.insert(m.indices.end(), {first, prev, next});
      m.triangle_polygon.push_back(static_cast<uint32_t>(p));
      prev = next;
    }
  }
  return m;
}

class ConeCuller final : public BackfaceCuller {
 public:
  ConeCuller(const BackfaceInput& input, const BackfaceOptions& options) {
    if (options.cone_max_vertices < 3 || options.cone_max_vertices > 255 || options.cone_max_triangles < 1 ||
        options.cone_max_triangles > 512 || options.cone_max_triangles % 4 != 0) {
      throw Error("backface cone: meshlet limits must be 3..255 vertices and 4..512 triangles (a multiple of 4)");
    }
    polygon_count_ = input.polygons.size();
    MeshInput mesh = meshInput(input);
    origin_ = mesh.origin;
    const std::vector<float>& positions = mesh.positions;
    const std::vector<uint32_t>& indices = mesh.indices;
    const std::vector<uint32_t>& triangle_polygon = mesh.triangle_polygon;
    unit_begin_.push_back(0);
    if (indices.empty()) return;
    const size_t vertex_count = positions.size() / 3;
    const size_t max_meshlets =
        meshopt_buildMeshletsBound(indices.size(), options.cone_max_vertices, options.cone_max_triangles);
    std::vector<meshopt_Meshlet> meshlets(max_meshlets);
    std::vector<unsigned int> meshlet_vertices(max_meshlets * options.cone_max_vertices);
    std::vector<unsigned char> meshlet_triangles(max_meshlets * options.cone_max_triangles * 3);
    const size_t meshlet_count = meshopt_buildMeshlets(
        meshlets.data(), meshlet_vertices.data(), meshlet_triangles.data(), indices.data(), indices.size(),
        positions.data(), vertex_count, 3 * sizeof(float), options.cone_max_vertices, options.cone_max_triangles,
        options.cone_weight);

    // Meshlets hold local triangles; find each one's polygon through its (sorted) vertex triple.
    std::unordered_map<std::array<uint32_t, 3>, std::vector<uint32_t>, TriKeyHash> by_key;
    for (size_t t = 0; t < triangle_polygon.size(); ++t) {
      std::array<uint32_t, 3> key{indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]};
      std::sort(key.begin(), key.end());
      by_key[key].push_back(triangle_polygon[t]);
    }
    bounds_.reserve(meshlet_count);
    std::vector<uint32_t> unit;
    for (size_t m = 0; m < meshlet_count; ++m) {
      const meshopt_Meshlet& ml = meshlets[m];
      const meshopt_Bounds b =
          meshopt_computeMeshletBounds(&meshlet_vertices[ml.vertex_offset], &meshlet_triangles[ml.triangle_offset],
                                       ml.triangle_count, positions.data(), vertex_count, 3 * sizeof(float));
      bounds_.push_back({{b.center[0], b.center[1], b.center[2]},
                         b.radius,
                         {b.cone_axis[0], b.cone_axis[1], b.cone_axis[2]},
                         b.cone_cutoff});
      unit.clear();
      for (uint32_t t = 0; t < ml.triangle_count; ++t) {
        std::array<uint32_t, 3> key;
        for (int k = 0; k < 3; ++k) {
          key[static_cast<size_t>(k)] =
              meshlet_vertices[ml.vertex_offset + meshlet_triangles[ml.triangle_offset + 3 * t + static_cast<uint32_t>(k)]];
        }
        std::sort(key.begin(), key.end());
        auto it = by_key.find(key);
        if (it == by_key.end() || it->second.empty()) {
          throw Error("backface cone: meshoptimizer returned a triangle that is not in the input");
        }
        unit.push_back(it->second.back());
        it->second.pop_back();
      }
      std::sort(unit.begin(), unit.end());
      unit.erase(std::unique(unit.begin(), unit.end()), unit.end());
      unit_polygons_.insert(unit_polygons_.end(), unit.begin(), unit.end());
      unit_begin_.push_back(static_cast<uint32_t>(unit_polygons_.size()));
    }
  }

  BackfaceMethod method() const override { return BackfaceMethod::kCone; }
  size_t stateBytes() const override { return bounds_.size() * sizeof(ConeBounds); }

  void cull(const BackfaceView& view, std::span<uint8_t> unit_culled) const override {
    WALKVIS_DCHECK(unit_culled.size() == unitCount());
    const double ex = view.eye.x - origin_.x, ey = view.eye.y - origin_.y, ez = view.eye.z - origin_.z;
    const size_t n = bounds_.size();
    for (size_t m = 0; m < n; ++m) {
      const ConeBounds& b = bounds_[m];
      const double dx = b.center[0] - ex, dy = b.center[1] - ey, dz = b.center[2] - ez;
      const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
      unit_culled[m] = dx * b.axis[0] + dy * b.axis[1] + dz * b.axis[2] >= b.cutoff * len + b.radius;
    }
  }

 private:
  glm::dvec3 origin_{0.0};
  std::vector<ConeBounds> bounds_;
};

}  // namespace

void coneInvisiblePolygons(const BackfaceInput& input, std::span<uint8_t> polygon_invisible) {
  if (polygon_invisible.size() != input.polygons.size()) {
    throw Error("backface cone: coneInvisiblePolygons needs one flag per polygon");
  }
  const MeshInput mesh = meshInput(input);
  const size_t vertex_count = mesh.positions.size() / 3;
  // The library's own verdict per polygon: bounds of its triangles alone; all zero (radius 0 and
  // an empty cone) is its "no valid triangles" case. A polygon with a triangle of nonzero float
  // area has distinct corners, hence a radius > 0. Then slivers whose float area is rounding noise.
  size_t t = 0;
  for (size_t p = 0; p < input.polygons.size(); ++p) {
    size_t end = t;
    while (end < mesh.triangle_polygon.size() && mesh.triangle_polygon[end] == p) ++end;
    bool invisible = true;
    for (size_t at = t; at < end && invisible; at += 512) {  // the library takes at most 512 triangles
      const size_t n = std::min<size_t>(512, end - at);
      const meshopt_Bounds b = meshopt_computeClusterBounds(mesh.indices.data() + 3 * at, 3 * n, mesh.positions.data(),
                                                            vertex_count, 3 * sizeof(float));
      invisible = b.radius == 0.0f && b.cone_cutoff == 0.0f && b.cone_axis[0] == 0.0f && b.cone_axis[1] == 0.0f &&
                  b.cone_axis[2] == 0.0f;
    }
    if (!invisible) {
      // Rounding a vertex to float moves it by up to 2⁻²⁴·|v| per coordinate (≤ 2⁻²³·L in all, L the
      // largest coordinate, relative to the origin, of the polygon); that changes the area by up to
      // about that times the polygon's extent D. An area below 2⁻²²·L·D (double that) can be created
      // or erased by the rounding alone: the float triangles' normal is noise, not the plane's
      // (MAP01: segment-like fragments 80 units long of area ~1e-11, float normal 117° off).
      const Polygon& poly = input.polygons[p];
      glm::dvec3 area2(0.0);
      double extent = 0.0, magnitude = 0.0;
      const glm::dvec3 v0 = input.vertices[poly.first_vertex] - mesh.origin;
      for (uint32_t k = 0; k < poly.vertex_count; ++k) {
        const glm::dvec3 v = input.vertices[poly.first_vertex + k] - mesh.origin;
        magnitude = std::max({magnitude, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
        extent = std::max(extent, 2.0 * glm::length(v - v0));
        if (k >= 2) area2 += glm::cross(input.vertices[poly.first_vertex + k - 1] - mesh.origin - v0, v - v0);
      }
      invisible = 0.5 * glm::length(area2) <= std::ldexp(1.0, -22) * magnitude * extent;
    }
    polygon_invisible[p] = invisible ? 1 : 0;
    t = end;
  }
}

std::unique_ptr<BackfaceCuller> makeConeCuller(const BackfaceInput& input, const BackfaceOptions& options) {
  return std::make_unique<ConeCuller>(input, options);
}

}  // namespace walkvis
