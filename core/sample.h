// Uniform random points, drawn from core/rng.h's generator: one implementation for every eye,
// sample and tour point that walkvis picks by area.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "core/check.h"
#include "core/rng.h"

namespace walkvis {

// Twice the area of triangle abc (2D or 3D).
inline double twiceTriangleArea(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  return std::abs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}
inline double twiceTriangleArea(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  return glm::length(glm::cross(b - a, c - a));
}

// An index i with probability (cumulative[i] - cumulative[i - 1]) / cumulative.back(), for
// non-decreasing `cumulative` with a positive last entry (a running sum of weights).
inline size_t pickByWeight(std::span<const double> cumulative, uint64_t& state) {
  WALKVIS_DCHECK(!cumulative.empty() && cumulative.back() > 0.0);
  const double pick = uniform01(state) * cumulative.back();
  const size_t i = static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
  return std::min(i, cumulative.size() - 1);  // rounding can leave `pick` at the total
}

// A uniform point of a convex polygon of >= 3 vertices: a fan triangle by area, then uniform
// barycentrics folded into it. A polygon without area gives its first vertex.
template <typename V>
V uniformPointInConvex(std::span<const V> poly, uint64_t& state) {
  WALKVIS_DCHECK(poly.size() >= 3);
  double total = 0.0;
  for (size_t k = 1; k + 1 < poly.size(); ++k) total += twiceTriangleArea(poly[0], poly[k], poly[k + 1]);
  if (!(total > 0.0)) return poly[0];
  double pick = uniform01(state) * total;
  size_t k = 1;
  for (; k + 2 < poly.size(); ++k) {
    const double a = twiceTriangleArea(poly[0], poly[k], poly[k + 1]);
    if (pick < a) break;
    pick -= a;
  }
  double u = uniform01(state), v = uniform01(state);
  if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
  return poly[0] + u * (poly[k] - poly[0]) + v * (poly[k + 1] - poly[0]);
}

}  // namespace walkvis
