// The exact orientation predicate for mesh merging (mesh_merge.h). Source: CGAL 5.5,
// Exact_predicates_inexact_constructions_kernel::Orientation_3 (a static/dynamic interval filter
// with an exact fallback).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "scenes/mesh_merge.h"

namespace walkvis {

int orient3dExact(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& d) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  const auto o = CGAL::orientation(Point(a.x, a.y, a.z), Point(b.x, b.y, b.z), Point(c.x, c.y, c.z),
                                   Point(d.x, d.y, d.z));
  return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}

}  // namespace walkvis
