// Method selection and the unit → polygon expansion shared by every backface method (backface.h).
#include "backface/backface.h"

#include <algorithm>
#include <cmath>

#include "core/check.h"

namespace walkvis {

std::string_view backfaceMethodName(BackfaceMethod method) {
  switch (method) {
    case BackfaceMethod::kPolygon: return "polygon";
    case BackfaceMethod::kMask: return "mask";
    case BackfaceMethod::kCluster: return "cluster";
    case BackfaceMethod::kCone: return "cone";
    case BackfaceMethod::kHierarchy: return "hierarchy";
  }
  return "?";
}

BackfaceMethod parseBackfaceMethod(std::string_view name) {
  for (BackfaceMethod m : {BackfaceMethod::kPolygon, BackfaceMethod::kMask, BackfaceMethod::kCluster,
                           BackfaceMethod::kCone, BackfaceMethod::kHierarchy}) {
    if (backfaceMethodName(m) == name) return m;
  }
  throw Error("backface method '" + std::string(name) + "': expected polygon, mask, cluster, cone or hierarchy");
}

std::unique_ptr<BackfaceCuller> makeBackfaceCuller(BackfaceMethod method, const BackfaceInput& input,
                                                   const BackfaceOptions& options) {
  for (size_t i = 0; i < input.polygons.size(); ++i) {
    const Polygon& p = input.polygons[i];
    if (!std::isfinite(p.plane.n.x) || !std::isfinite(p.plane.n.y) || !std::isfinite(p.plane.n.z) ||
        !std::isfinite(p.plane.d)) {
      throw Error("backface: polygon " + std::to_string(i) + " has a non-finite plane");
    }
    if (static_cast<size_t>(p.first_vertex) + p.vertex_count > input.vertices.size() || p.vertex_count < 3) {
      throw Error("backface: polygon " + std::to_string(i) + " has vertices outside the vertex array");
    }
  }
  switch (method) {
    case BackfaceMethod::kPolygon: return makePolygonCuller(input);
    case BackfaceMethod::kMask: return makeNormalMaskCuller(input, options);
    case BackfaceMethod::kCluster: return makeClusterCuller(input, options);
    case BackfaceMethod::kCone: return makeConeCuller(input, options);
    case BackfaceMethod::kHierarchy: return makeHierarchyCuller(input, options);
  }
  throw Error("backface: unknown method");
}

void expandToPolygons(const BackfaceCuller& culler, std::span<const uint8_t> unit_culled,
                      std::span<uint8_t> polygon_culled) {
  WALKVIS_DCHECK(unit_culled.size() == culler.unitCount());
  WALKVIS_DCHECK(polygon_culled.size() == culler.polygonCount());
  std::fill(polygon_culled.begin(), polygon_culled.end(), uint8_t{0});
  const size_t units = culler.unitCount();
  // Two passes so that a polygon shared by several units (meshlets) is culled only when all are.
  for (size_t u = 0; u < units; ++u) {
    if (unit_culled[u]) {
      for (uint32_t p : culler.unitPolygons(u)) polygon_culled[p] = 1;
    }
  }
  for (size_t u = 0; u < units; ++u) {
    if (!unit_culled[u]) {
      for (uint32_t p : culler.unitPolygons(u)) polygon_culled[p] = 0;
    }
  }
}

}  // namespace walkvis
