// Convex partition of an odd-winding (even-odd) planar region.
//
// Sources: CGAL 5.5 user manual [CGAL], 2D Triangulation, "Triangulating a Polygonal Domain"
// (examples/Triangulation_2/polygon_triangulation.cpp: faces marked by nesting level from the
// infinite face); S. Hertel and K. Mehlhorn, "Fast triangulation of simple polygons", FCT 1983
// [HertelMehlhorn1983]
// (remove a diagonal of a triangulation whenever both its endpoints stay convex; at most 4x the
// optimal number of convex pieces).
//
// The rings go into a constrained Delaunay triangulation with exact constructions, so crossing,
// overlapping and touching ring edges are split exactly and never trip a precondition. The
// hierarchy of Constrained_triangulation_plus_2 counts how many ring edges cover each triangulation
// edge; crossing an edge covered an odd number of times flips inside/outside, which is the
// even-odd rule even where two rings share an edge (their shared edge cancels).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <numeric>
#include <vector>

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_plus_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include "scenes/scene.h"

namespace walkvis {
namespace {

using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = Kernel::Point_2;

struct FaceInfo {
  int parity = -1;  // -1: not reached yet, 0: outside, 1: inside
  uint32_t triangle = UINT32_MAX;
};

using Vb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, Kernel>;
using Fb0 = CGAL::Constrained_triangulation_face_base_2<Kernel>;
using Fb = CGAL::Triangulation_face_base_with_info_2<FaceInfo, Kernel, Fb0>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::Exact_intersections_tag>;
using CdtPlus = CGAL::Constrained_triangulation_plus_2<Cdt>;

// The triangulation edge (u, v) of face f opposite vertex i, with u -> v counter-clockwise in f.
bool oddCover(const CdtPlus& cdt, CdtPlus::Face_handle f, int i) {
  if (!f->is_constrained(i)) return false;
  auto u = f->vertex(CdtPlus::ccw(i));
  auto v = f->vertex(CdtPlus::cw(i));
  return cdt.number_of_enclosing_constraints(u, v) % 2 == 1;
}

// Parity flood from the infinite face: crossing an odd-covered edge flips inside/outside.
void markInside(const CdtPlus& cdt) {
  std::deque<CdtPlus::Face_handle> queue;
  cdt.infinite_face()->info().parity = 0;
  queue.push_back(cdt.infinite_face());
  while (!queue.empty()) {
    auto f = queue.front();
    queue.pop_front();
    for (int i = 0; i < 3; ++i) {
      auto n = f->neighbor(i);
      if (n->info().parity != -1) continue;
      n->info().parity = f->info().parity ^ (oddCover(cdt, f, i) ? 1 : 0);
      queue.push_back(n);
    }
  }
}

// a -> b -> c keeps the polygon convex at b: a left turn, or straight on (never a reversal).
bool convexAt(const Point& a, const Point& b, const Point& c) {
  auto o = CGAL::orientation(a, b, c);
  if (o == CGAL::LEFT_TURN) return true;
  if (o == CGAL::RIGHT_TURN) return false;
  return (b - a) * (c - b) > 0;
}

}  // namespace

std::vector<std::vector<glm::dvec2>> convexPartition(const std::vector<std::vector<glm::dvec2>>& rings) {
  CdtPlus cdt;
  for (const auto& ring : rings) {
    // Non-finite points cannot be placed; dropping them keeps the rest of the ring closed.
    std::vector<Point> pts;
    pts.reserve(ring.size());
    for (const auto& p : ring) {
      if (std::isfinite(p.x) && std::isfinite(p.y)) pts.emplace_back(p.x, p.y);
    }
    if (pts.size() < 2) continue;
    // One constraint per edge, so an edge a ring runs twice is counted twice.
    for (size_t i = 0; i < pts.size(); ++i) {
      const Point& a = pts[i];
      const Point& b = pts[(i + 1) % pts.size()];
      if (a != b) cdt.insert_constraint(a, b);
    }
  }
  if (cdt.dimension() < 2) return {};
  markInside(cdt);

  std::vector<CdtPlus::Vertex_handle> verts;
  for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
    v->info() = static_cast<uint32_t>(verts.size());
    verts.push_back(v);
  }

  // Every inside triangle starts as its own polygon (vertex ids, counter-clockwise).
  std::vector<std::vector<uint32_t>> polys;
  std::vector<CdtPlus::Face_handle> faces;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (f->info().parity != 1) continue;
    f->info().triangle = static_cast<uint32_t>(polys.size());
    polys.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
    faces.push_back(f);
  }
  std::vector<uint32_t> owner(polys.size());  // union-find over polygons
  std::iota(owner.begin(), owner.end(), 0u);
  auto find = [&](uint32_t x) {
    while (owner[x] != x) x = owner[x] = owner[owner[x]];
    return x;
  };

  // Hertel–Mehlhorn: drop each inner diagonal whose removal leaves both endpoints convex.
  // Longer diagonals first tends to give fewer, fatter pieces.
  struct Diagonal {
    uint32_t a, b;  // triangles on either side
    uint32_t u, v;  // u -> v counter-clockwise in a
    double length2;
  };
  std::vector<Diagonal> diagonals;
  for (auto f : faces) {
    for (int i = 0; i < 3; ++i) {
      auto n = f->neighbor(i);
      if (cdt.is_infinite(n) || n->info().parity != 1) continue;
      uint32_t ta = f->info().triangle, tb = n->info().triangle;
      if (ta > tb) continue;  // each diagonal once
      auto u = f->vertex(CdtPlus::ccw(i)), v = f->vertex(CdtPlus::cw(i));
      double dx = CGAL::to_double(u->point().x() - v->point().x());
      double dy = CGAL::to_double(u->point().y() - v->point().y());
      diagonals.push_back({ta, tb, u->info(), v->info(), dx * dx + dy * dy});
    }
  }
  std::stable_sort(diagonals.begin(), diagonals.end(),
                   [](const Diagonal& x, const Diagonal& y) { return x.length2 > y.length2; });

  auto pt = [&](uint32_t id) -> const Point& { return verts[id]->point(); };
  for (const auto& d : diagonals) {
    uint32_t pa = find(d.a), pb = find(d.b);
    if (pa == pb) continue;
    auto& A = polys[pa];  // contains u -> v
    auto& B = polys[pb];  // contains v -> u
    size_t na = A.size(), nb = B.size();
    size_t iu = na, jv = nb;
    for (size_t k = 0; k < na; ++k) {
      if (A[k] == d.u && A[(k + 1) % na] == d.v) iu = k;
    }
    for (size_t k = 0; k < nb; ++k) {
      if (B[k] == d.v && B[(k + 1) % nb] == d.u) jv = k;
    }
    if (iu == na || jv == nb) continue;  // the edge is no longer on both boundaries
    size_t iv = (iu + 1) % na, ju = (jv + 1) % nb;
    // At u: A's predecessor of u, then B's successor of u. At v: B's predecessor, A's successor.
    if (!convexAt(pt(A[(iu + na - 1) % na]), pt(d.u), pt(B[(ju + 1) % nb]))) continue;
    if (!convexAt(pt(B[(jv + nb - 1) % nb]), pt(d.v), pt(A[(iv + 1) % na]))) continue;
    std::vector<uint32_t> merged;
    merged.reserve(na + nb - 2);
    for (size_t k = 0; k < na; ++k) merged.push_back(A[(iv + k) % na]);  // v ... u
    for (size_t k = 1; k + 1 < nb; ++k) merged.push_back(B[(ju + k) % nb]);  // after u ... before v
    A = std::move(merged);
    B.clear();
    B.shrink_to_fit();
    owner[pb] = pa;
  }

  std::vector<std::vector<glm::dvec2>> out;
  for (uint32_t p = 0; p < polys.size(); ++p) {
    if (find(p) != p || polys[p].size() < 3) continue;
    const auto& poly = polys[p];
    size_t n = poly.size();
    std::vector<glm::dvec2> piece;
    for (size_t k = 0; k < n; ++k) {
      // Straight-on vertices carry no shape; leaving them out keeps the pieces small.
      const Point& a = pt(poly[(k + n - 1) % n]);
      const Point& b = pt(poly[k]);
      const Point& c = pt(poly[(k + 1) % n]);
      if (CGAL::orientation(a, b, c) == CGAL::COLLINEAR) continue;
      glm::dvec2 q(CGAL::to_double(b.x()), CGAL::to_double(b.y()));
      if (piece.empty() || piece.back() != q) piece.push_back(q);
    }
    while (piece.size() > 1 && piece.front() == piece.back()) piece.pop_back();
    if (piece.size() < 3) continue;
    // Relative to the first vertex, so coordinates near 1e6 do not cancel away small areas.
    double area2 = 0.0;
    for (size_t k = 1; k + 1 < piece.size(); ++k) {
      const glm::dvec2 a = piece[k] - piece[0], b = piece[k + 1] - piece[0];
      area2 += a.x * b.y - b.x * a.y;
    }
    // Rounding exact intersection points to doubles can flatten a sliver; such a piece has no area left.
    if (!(area2 > 0.0)) continue;
    out.push_back(std::move(piece));
  }
  return out;
}

}  // namespace walkvis
