// Exact reference by ray casting: Embree 3 (Wald et al., "Embree: A Kernel Framework for Efficient
// CPU Ray Tracing", SIGGRAPH 2014 [Embree2014]) finds candidates in single precision; every
// decision that classifies a pixel is re-made in double precision against the Polygon's own plane.
//
// Back faces are skipped in an intersection filter (Embree 3 has backface culling only as a
// compile-time option). The filter reads a per-view front-facing table through an extended
// RTCIntersectContext, the idiom Embree 3 documents for per-ray user data.
#include "walkthrough/raycast.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <string>

#include "core/embree_scene.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

struct FilterContext {
  RTCIntersectContext context;  // must be first: Embree passes a pointer to it
  const uint8_t* front = nullptr;
  const uint32_t* triangle_polygon = nullptr;
  std::vector<uint32_t>* collect = nullptr;  // when set, every front-facing hit is recorded and rejected
};

void filterFrontFacing(const RTCFilterFunctionNArguments* args) {
  const auto* ctx = reinterpret_cast<const FilterContext*>(args->context);
  for (unsigned k = 0; k < args->N; ++k) {
    if (args->valid[k] != -1) continue;
    const unsigned prim = RTCHitN_primID(args->hit, args->N, k);
    const uint32_t polygon = ctx->triangle_polygon[prim];
    if (!ctx->front[polygon]) {
      args->valid[k] = 0;
    } else if (ctx->collect) {
      ctx->collect->push_back(polygon);
      args->valid[k] = 0;
    }
  }
}

}  // namespace

std::optional<double> exactPolygonHit(std::span<const glm::dvec3> verts, const Plane& plane, const glm::dvec3& eye,
                                      const glm::dvec3& dir, double near, double far) {
  if (verts.size() < 3) return std::nullopt;
  const double side = glm::dot(plane.n, eye) - plane.d;
  const double approach = glm::dot(plane.n, dir);
  if (!(side > 0.0) || !(approach < 0.0)) return std::nullopt;
  const double t = side / -approach;
  if (!(t >= near && t <= far)) return std::nullopt;
  // Inside test relative to the eye: the hit point is t * dir from it, which keeps precision for
  // large coordinates. The test runs over the triangle fan that the GL renderer and Embree draw, so
  // it agrees with them even for a polygon that breaks the convexity contract (for a convex
  // polygon it is the plain convex test): a fan triangle counts when the point is on the inner side
  // of its three edges, seen from the front, as a rasteriser draws only counter-clockwise ones.
  // A fan triangle of zero area (repeated vertices, e.g. split points that rounded onto each other)
  // is skipped: a rasteriser draws nothing for it, while its zero-length edges would pass the edge
  // test for every point of the plane.
  const glm::dvec3 x = t * dir;
  const glm::dvec3 a = verts[0] - eye;
  auto inner = [&](const glm::dvec3& p, const glm::dvec3& q) {
    return glm::dot(plane.n, glm::cross(q - p, x - p)) >= 0.0;
  };
  bool inside = false;
  for (size_t k = 1; k + 1 < verts.size() && !inside; ++k) {
    const glm::dvec3 b = verts[k] - eye, c = verts[k + 1] - eye;
    if (!(glm::dot(plane.n, glm::cross(b - a, c - a)) > 0.0)) continue;
    inside = inner(a, b) && inner(b, c) && inner(c, a);
  }
  if (!inside) return std::nullopt;
  return t;
}

struct RayCaster::Impl {
  EmbreeScene embree;
  std::vector<glm::dvec3> vertices;
  std::vector<Polygon> polygons;
  std::vector<uint32_t> triangle_polygon;
  glm::dvec3 origin{0.0};  // Embree coordinates are relative to this (the bounds' centre)
  double extent = 0.0;     // the bounds' diagonal


  void initRay(RTCRayHit& rh, const View& view, const glm::dvec3& dir, float tnear, float tfar) const {
    const glm::dvec3 o = view.eye - origin;
    rh.ray.org_x = static_cast<float>(o.x);
    rh.ray.org_y = static_cast<float>(o.y);
    rh.ray.org_z = static_cast<float>(o.z);
    rh.ray.dir_x = static_cast<float>(dir.x);
    rh.ray.dir_y = static_cast<float>(dir.y);
    rh.ray.dir_z = static_cast<float>(dir.z);
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.time = 0.0f;
    rh.ray.mask = ~0u;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  }
};

RayCaster::RayCaster(std::span<const glm::dvec3> vertices, std::span<const Polygon> polygons)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.vertices.assign(vertices.begin(), vertices.end());
  s.polygons.assign(polygons.begin(), polygons.end());
  if (!s.vertices.empty()) {
    glm::dvec3 lo = s.vertices[0], hi = s.vertices[0];
    for (const auto& v : s.vertices) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    s.origin = 0.5 * (lo + hi);
    s.extent = glm::length(hi - lo);
  }
  std::vector<uint32_t> indices;
  for (size_t k = 0; k < s.polygons.size(); ++k) {
    const Polygon& p = s.polygons[k];
    if (p.vertex_count < 3 || p.first_vertex > s.vertices.size() ||
        p.vertex_count > s.vertices.size() - p.first_vertex)
      continue;
    for (uint32_t v = 1; v + 1 < p.vertex_count; ++v) {
      indices.push_back(p.first_vertex);
      indices.push_back(p.first_vertex + v);
      indices.push_back(p.first_vertex + v + 1);
      s.triangle_polygon.push_back(static_cast<uint32_t>(k));
    }
  }
  s.embree = EmbreeScene(
      {.vertices = s.vertices, .origin = s.origin, .indices = indices, .intersect_filter = filterFrontFacing},
      "ray caster");
}

RayCaster::RayCaster(RayCaster&&) noexcept = default;
RayCaster& RayCaster::operator=(RayCaster&&) noexcept = default;
RayCaster::~RayCaster() = default;

size_t RayCaster::polygonCount() const { return impl_->polygons.size(); }

std::vector<uint8_t> RayCaster::frontFacing(const glm::dvec3& eye) const {
  const std::vector<Polygon>& polygons = impl_->polygons;
  std::vector<uint8_t> front(polygons.size());
  for (size_t k = 0; k < polygons.size(); ++k)
    front[k] = glm::dot(polygons[k].plane.n, eye) - polygons[k].plane.d > 0.0;
  return front;
}

static bool frontTableFits(std::span<const uint8_t> front, size_t polygons) {
  return front.size() == polygons;
}

void RayCaster::castNearest(const View& view, std::span<const uint8_t> front, std::vector<RayHit>& out) const {
  const Impl& s = *impl_;
  if (!frontTableFits(front, s.polygons.size())) throw std::invalid_argument("castNearest: front table size");
  const int size = view.size;
  out.assign(static_cast<size_t>(size) * size, RayHit{});
  if (s.triangle_polygon.empty()) return;
  const float tnear = static_cast<float>(view.near), tfar = static_cast<float>(view.far);
  const glm::dvec3 o = view.eye - s.origin;
  const int tiles = (size + 3) / 4;
  // 4 × 4 pixel tiles as 16-ray packets: neighbouring pixel rays are coherent, which is what
  // Embree's packet traversal is fast for.
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles * tiles, 16), [&](const tbb::blocked_range<int>& range) {
    FilterContext ctx;
    rtcInitIntersectContext(&ctx.context);
    ctx.context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    ctx.front = front.data();
    ctx.triangle_polygon = s.triangle_polygon.data();
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    for (int tile = range.begin(); tile < range.end(); ++tile) {
      const int i0 = (tile % tiles) * 4, j0 = (tile / tiles) * 4;
      for (int k = 0; k < 16; ++k) {
        const int i = i0 + (k & 3), j = j0 + (k >> 2);
        valid[k] = i < size && j < size ? -1 : 0;
        const glm::dvec3 dir = pixelRay(view, std::min(i, size - 1), std::min(j, size - 1));
        rh.ray.org_x[k] = static_cast<float>(o.x);
        rh.ray.org_y[k] = static_cast<float>(o.y);
        rh.ray.org_z[k] = static_cast<float>(o.z);
        rh.ray.dir_x[k] = static_cast<float>(dir.x);
        rh.ray.dir_y[k] = static_cast<float>(dir.y);
        rh.ray.dir_z[k] = static_cast<float>(dir.z);
        rh.ray.tnear[k] = tnear;
        rh.ray.tfar[k] = tfar;
        rh.ray.time[k] = 0.0f;
        rh.ray.mask[k] = ~0u;
        rh.ray.id[k] = static_cast<unsigned>(k);
        rh.ray.flags[k] = 0;
        rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
      }
      rtcIntersect16(valid, s.embree.scene(), &ctx.context, &rh);
      for (int k = 0; k < 16; ++k) {
        if (!valid[k] || rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
        RayHit& h = out[static_cast<size_t>(j0 + (k >> 2)) * size + i0 + (k & 3)];
        h.polygon = s.triangle_polygon[rh.hit.primID[k]];
        h.t = rh.ray.tfar[k];
      }
    }
  });
}

std::vector<RayHit> RayCaster::exactHits(const View& view, std::span<const uint8_t> front, int i, int j,
                                         std::span<const uint32_t> also_check) const {
  const Impl& s = *impl_;
  if (!frontTableFits(front, s.polygons.size())) throw std::invalid_argument("exactHits: front table size");
  const glm::dvec3 dir = pixelRay(view, i, j);
  auto exactHit = [&](uint32_t k) -> std::optional<double> {
    const Polygon& p = s.polygons[k];
    if (p.first_vertex > s.vertices.size() || p.vertex_count > s.vertices.size() - p.first_vertex) return std::nullopt;
    return exactPolygonHit({s.vertices.data() + p.first_vertex, p.vertex_count}, p.plane, view.eye, dir, view.near,
                           view.far);
  };
  std::vector<uint32_t> candidates;
  if (!s.triangle_polygon.empty()) {
    FilterContext ctx;
    rtcInitIntersectContext(&ctx.context);
    ctx.front = front.data();
    ctx.triangle_polygon = s.triangle_polygon.data();
    // Only hits up to the farthest polygon asked about (or the nearest hit when none of them is on
    // the ray) can change a classification, so the all-hits query stops a little beyond it: the
    // margin covers single-precision error in Embree's t; the double test applies exact bounds.
    RTCRayHit rh;
    double limit = -1.0;
    for (uint32_t k : also_check)
      if (k < s.polygons.size())
        if (auto t = exactHit(k)) limit = std::max(limit, *t);
    if (limit < 0.0) {
      s.initRay(rh, view, dir, static_cast<float>(view.near), static_cast<float>(view.far));
      rtcIntersect1(s.embree.scene(), &ctx.context, &rh);
      limit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? static_cast<double>(rh.ray.tfar) : view.far;
    }
    const double slack = 1e-3 * limit + 1e-5 * s.extent;
    ctx.collect = &candidates;
    s.initRay(rh, view, dir, static_cast<float>(view.near * (1.0 - 1e-5)),
              static_cast<float>(std::min(limit + slack, view.far * (1.0 + 1e-5))));
    rtcIntersect1(s.embree.scene(), &ctx.context, &rh);
  }
  for (uint32_t k : also_check)
    if (k < s.polygons.size()) candidates.push_back(k);
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  std::vector<RayHit> hits;
  for (uint32_t k : candidates) {
    const Polygon& p = s.polygons[k];
    if (auto t = exactHit(k)) {
      const std::span<const glm::dvec3> verts(s.vertices.data() + p.first_vertex, p.vertex_count);
      // The image region a convex polygon covers is convex, so four corners decide the square.
      bool solid = true;
      const CubeFrame f = cubeFrame(view.face);
      const double e = 2.0 * kEdgeMarginPixels / view.size;
      for (int corner = 0; corner < 4 && solid; ++corner) {
        const glm::dvec3 offset = ((corner & 1) ? e : -e) * f.right + ((corner & 2) ? e : -e) * f.up;
        solid = exactPolygonHit(verts, p.plane, view.eye, dir + offset, view.near, view.far).has_value();
      }
      hits.push_back({k, *t, solid});
    }
  }
  std::sort(hits.begin(), hits.end(),
            [](const RayHit& a, const RayHit& b) { return a.t != b.t ? a.t < b.t : a.polygon < b.polygon; });
  return hits;
}

}  // namespace walkvis
