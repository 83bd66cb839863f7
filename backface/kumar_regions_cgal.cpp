// The CGAL step of Kumar, Manocha, Garrett & Lin 1996, "Hierarchical back-face computation"
// [Kumar1996], §5.1–5.2, Algorithms I and II:
// a feasible point O strictly inside the intersection of half-spaces by linear programming, then
// the dual points of the planes about O and their convex hull, whose vertices are the boundary
// planes h^b and whose edges are the boundary lines l^b.
//
// Algorithm II shifts every plane by δ and minimises −n_j·x; we instead maximise δ itself (the
// radius of the largest ball inside the region, kept bounded by a box around the cluster): the
// same LP family, with a point as far from the boundary as the box allows, which the paper's §8.1
// otherwise searches for by bisection on δ. CGAL's solver is exact (Gmpzf), so no perturbation of
// the minimisation vector is needed (§8.1); the hull uses exact predicates, so no perturbation of
// the input either.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Gmpzf.h>
#include <CGAL/QP_functions.h>
#include <CGAL/QP_models.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <numeric>

#include "backface/kumar.h"

namespace walkvis {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using HullMesh = CGAL::Surface_mesh<Point3>;

// Regions thinner than this share of the coordinate magnitudes are treated as flat (no interior):
// the plane evaluations round at ~1e-16 of those magnitudes and the tracking margins
// (hierarchical_kumar.cpp, kRound = 1e-12 of scale/g_min) would swamp a thinner region anyway.
constexpr double kMinThickness = 1e-9;
// With at most this many distinct boundary-plane candidates, or when the dual points do not span
// 3D, every candidate is made a neighbour of every other (the walk then finds the maximum in one
// step); above it a degenerate (coplanar) dual set is given up as "no interior" (conservative).
constexpr size_t kCompleteGraphMax = 1024;
// Dual points nearer than this share of the largest are merged (see below).
constexpr double kMerge = 1e-7;

}  // namespace

KumarRegion buildKumarRegion(std::span<const Plane> planes, const glm::dvec3& box_lo, const glm::dvec3& box_hi) {
  KumarRegion region;
  if (planes.empty()) return region;
  const glm::dvec3 box_center = 0.5 * (box_lo + box_hi);
  const glm::dvec3 half = 0.5 * (box_hi - box_lo);

  // Variables y (3, relative to the box centre) and r: n_i·y + r <= d_i − n_i·box_center,
  // y inside the box, 0 <= r <= |half|; minimise −r.
  CGAL::Quadratic_program<double> lp(CGAL::SMALLER, false, 0.0, false, 0.0);
  for (int j = 0; j < 3; ++j) {
    lp.set_l(j, true, -half[j]);
    lp.set_u(j, true, half[j]);
  }
  lp.set_l(3, true, 0.0);
  lp.set_u(3, true, glm::length(half) + 1.0);
  lp.set_c(3, -1.0);
  for (size_t i = 0; i < planes.size(); ++i) {
    const int row = static_cast<int>(i);
    for (int j = 0; j < 3; ++j) lp.set_a(j, row, planes[i].n[j]);
    lp.set_a(3, row, 1.0);
    lp.set_b(row, planes[i].d - glm::dot(planes[i].n, box_center));
  }
  const auto solution = CGAL::solve_linear_program(lp, CGAL::Gmpzf());
  if (!solution.is_optimal()) return region;
  glm::dvec3 y(0.0);
  auto value = solution.variable_values_begin();
  for (int j = 0; j < 3; ++j, ++value) y[j] = CGAL::to_double(*value);
  const glm::dvec3 c = box_center + y;

  // The interior point as stored (double): every g_i must be clearly positive.
  double max_d = 0.0;
  for (const Plane& p : planes) max_d = std::max(max_d, std::abs(p.d));
  const double scale = std::abs(c.x) + std::abs(c.y) + std::abs(c.z) + max_d;
  std::vector<double> g(planes.size());
  double g_min = INFINITY;
  for (size_t i = 0; i < planes.size(); ++i) {
    g[i] = planes[i].d - glm::dot(planes[i].n, c);
    g_min = std::min(g_min, g[i]);
  }
  if (!(g_min > kMinThickness * scale)) return region;

  // Dual points about c. Points closer than kMerge·max|p| are one boundary plane: the hull would
  // otherwise hold edges of ~1e-16 (coplanar polygons whose Newell planes differ in the last bits)
  // along which the tracking walk stalls at a false local maximum; the member kept is the first in
  // x order, and every merged plane's p·y stays within kMerge·max|p|·|y| of it (tracking's margin
  // covers that, see hierarchical_kumar.cpp).
  std::vector<glm::dvec3> dual(planes.size());
  double p_len = 0.0;
  for (size_t i = 0; i < planes.size(); ++i) {
    dual[i] = planes[i].n / g[i];
    p_len = std::max(p_len, glm::length(dual[i]));
  }
  const double merge = kMerge * p_len;
  std::vector<uint32_t> order(planes.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return dual[a].x < dual[b].x || (dual[a].x == dual[b].x && a < b);
  });
  std::vector<uint8_t> taken(planes.size(), 0);
  std::vector<Point3> points;
  std::vector<uint32_t> source;
  for (size_t oi = 0; oi < order.size(); ++oi) {
    const uint32_t i = order[oi];
    if (taken[i]) continue;
    taken[i] = 1;
    points.emplace_back(dual[i].x, dual[i].y, dual[i].z);
    source.push_back(i);
    region.members.push_back(i);
    for (size_t oj = oi + 1; oj < order.size() && dual[order[oj]].x - dual[i].x <= merge; ++oj) {
      const uint32_t j = order[oj];
      if (!taken[j] && glm::length(dual[j] - dual[i]) <= merge) {
        taken[j] = 1;
        region.members.push_back(j);  // dropped from the hull; the parent still sees its plane
      }
    }
  }

  // Do the dual points span 3D?
  bool spans3d = false;
  if (points.size() >= 4) {
    size_t b = 1;
    while (b < points.size() && points[b] == points[0]) ++b;
    size_t c2 = b + 1;
    while (c2 < points.size() && CGAL::collinear(points[0], points[b], points[c2])) ++c2;
    for (size_t d = c2 + 1; d < points.size() && !spans3d; ++d) {
      spans3d = CGAL::orientation(points[0], points[b], points[c2], points[d]) != CGAL::COPLANAR;
    }
  }

  region.center = c;
  region.g_min = g_min;
  region.scale = scale;
  if (!spans3d) {
    if (points.size() > kCompleteGraphMax) return region;  // has_interior stays false
    const size_t m = points.size();
    for (size_t k = 0; k < m; ++k) {
      region.dual.push_back(dual[source[k]]);
      region.plane.push_back(source[k]);
      region.adj_begin.push_back(static_cast<uint32_t>(region.adj.size()));
      for (size_t j = 0; j < m; ++j) {
        if (j != k) region.adj.push_back(static_cast<uint32_t>(j));
      }
    }
    region.adj_begin.push_back(static_cast<uint32_t>(region.adj.size()));
  } else {
    HullMesh hull;
    CGAL::convex_hull_3(points.begin(), points.end(), hull);
    std::map<std::array<double, 3>, uint32_t> source_of;
    for (size_t k = 0; k < points.size(); ++k) {
      source_of.emplace(std::array<double, 3>{points[k].x(), points[k].y(), points[k].z()}, source[k]);
    }
    std::vector<uint32_t> local(hull.number_of_vertices(), 0);
    uint32_t next = 0;
    for (auto v : hull.vertices()) {
      const Point3& q = hull.point(v);
      const uint32_t s = source_of.at({q.x(), q.y(), q.z()});
      local[v.idx()] = next++;
      region.dual.push_back(dual[s]);
      region.plane.push_back(s);
    }
    for (auto v : hull.vertices()) {
      region.adj_begin.push_back(static_cast<uint32_t>(region.adj.size()));
      for (auto w : CGAL::vertices_around_target(hull.halfedge(v), hull)) region.adj.push_back(local[w.idx()]);
    }
    region.adj_begin.push_back(static_cast<uint32_t>(region.adj.size()));
  }
  for (const glm::dvec3& p : region.dual) {
    region.p_max = std::max(region.p_max, std::abs(p.x) + std::abs(p.y) + std::abs(p.z));
  }
  region.has_interior = true;
  return region;
}

}  // namespace walkvis
