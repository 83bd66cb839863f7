// Exact reference images: one ray per pixel centre (camera.h's pixelRay, the same rays the GL
// renderer samples) through an Embree 3 scene of the polygons' fan triangles, with only
// FRONT-FACING polygons counted as hits (back faces are never drawn, so they are transparent to
// the reference too). Where a pixel needs classifying, every front-facing polygon on the ray is
// re-intersected in double precision (plane of the Polygon, inclusive point-in-convex-polygon test).
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "scenes/scene.h"
#include "walkthrough/camera.h"
#include "walkthrough/renderer.h"

namespace walkvis {

// Rasterisers snap vertices to a sub-pixel grid (GL requires at least 4 bits, llvmpipe uses 8:
// 1/256 pixel) and set up edges in float, so a polygon edge this close to a pixel centre may fall
// on either side of it in a GL image. 1/64 pixel is 4 times llvmpipe's snapping step.
constexpr double kEdgeMarginPixels = 1.0 / 64.0;

struct RayHit {
  uint32_t polygon = kNoPolygon;
  double t = std::numeric_limits<double>::infinity();  // camera depth (pixelRay has forward component 1)
  // The rays through the corners of a square of ±kEdgeMarginPixels around the pixel centre hit the
  // polygon too (exactHits only): a rasteriser must cover this pixel with it.
  bool solid = true;
};

// The double-precision hit of one polygon by the ray eye + t * dir, t in [near, far]: the polygon
// must be front-facing (n·eye > d), and the hit point inside it or on its boundary (inside one of
// its counter-clockwise fan triangles: the same shape the renderer draws). nullopt otherwise
// (including polygons with fewer than 3 vertices).
std::optional<double> exactPolygonHit(std::span<const glm::dvec3> polygon_vertices, const Plane& plane,
                                      const glm::dvec3& eye, const glm::dvec3& dir, double near, double far);

class RayCaster {
 public:
  // Builds an Embree scene of the polygons (convex, CCW seen from the front, fan-triangulated). The
  // spans are copied. Throws std::runtime_error when Embree fails.
  RayCaster(std::span<const glm::dvec3> vertices, std::span<const Polygon> polygons);
  RayCaster(RayCaster&&) noexcept;
  RayCaster& operator=(RayCaster&&) noexcept;
  ~RayCaster();

  // Per polygon, 1 when the eye is in its front half-space (n·eye > d, double): what counts as a
  // hit for that eye. Pass it to the calls below (compute it once per eye).
  std::vector<uint8_t> frontFacing(const glm::dvec3& eye) const;

  // Nearest front-facing hit per pixel of the view (Embree, single precision), size * size
  // entries in camera.h pixel order; polygon kNoPolygon where the ray hits nothing within
  // [near, far]. Rays are cast in parallel (TBB). `front` = frontFacing(view.eye).
  void castNearest(const View& view, std::span<const uint8_t> front, std::vector<RayHit>& out) const;

  // The front-facing polygons on the ray through pixel (i, j) within [near, far], nearer than a
  // little beyond the farthest polygon of `also_check` that the ray hits (or than the nearest hit
  // when it hits none of them; kNoPolygon entries are ignored): every hit that can decide how a
  // pixel showing one of `also_check` is classified. Embree finds the candidates, each confirmed
  // and intersected in double precision (exactPolygonHit), with RayHit::solid set; sorted by t,
  // then by polygon index. Thread-safe.
  std::vector<RayHit> exactHits(const View& view, std::span<const uint8_t> front, int i, int j,
                                std::span<const uint32_t> also_check = {}) const;

  size_t polygonCount() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace walkvis
