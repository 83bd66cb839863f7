// Convex pieces of a region of the height plane (x, z), and the nearest-point query the HFD
// visibility test asks of them (pfd_hfd/visibility.cpp): where to stand to see past a blocker's
// edge, the region's point in front of a target. Internal to pfd_hfd.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

namespace walkvis {

inline double cross2(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

// Closest point of segment [a, b] to p.
template <typename V>
V closestOnSegment(const V& a, const V& b, const V& p) {
  const V ab = b - a;
  const double len2 = glm::dot(ab, ab);
  if (!(len2 > 0.0)) return a;
  const double t = std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0);
  return a + t * ab;
}

// A convex polygon of the plane, counter-clockwise.
struct Convex2 {
  std::vector<glm::dvec2> v;
  double area = 0.0;
  glm::dvec2 centroid{0.0};
  double radius = 0.0;  // the farthest vertex from the centroid
};

// Whether p lies in the counter-clockwise convex polygon (its boundary included).
bool insideConvex(const std::vector<glm::dvec2>& poly, const glm::dvec2& p);
// The point of the polygon nearest p (p itself when inside); dist2 its squared distance.
glm::dvec2 closestInConvex(const std::vector<glm::dvec2>& poly, const glm::dvec2& p, double& dist2);
// The part of a convex polygon where g·q + c0 >= 0 (Sutherland–Hodgman with one edge), into
// `out`; false when it is empty or degenerate.
bool clipHalfPlane(const std::vector<glm::dvec2>& poly, const glm::dvec2& g, double c0, std::vector<glm::dvec2>& out);
// True when the piece's bounding circle lies wholly where g·q + c0 < 0, so that clipping it to
// the half-plane leaves nothing (by a relative factor of 1e-9 beyond the bound's rounding, ~1e-16:
// never a piece that clipping would keep).
bool circleBehind(const Convex2& piece, const glm::dvec2& g, double c0);
// The same for the rectangle lo..hi.
bool rectBehind(const glm::dvec2& lo, const glm::dvec2& hi, const glm::dvec2& g, double c0);
// Pulls p towards c by `gap` (absolute) and at least the fraction `shrink`, but never past c.
glm::dvec2 pullTowards(const glm::dvec2& p, const glm::dvec2& c, double shrink, double gap);

// A uniform grid over the bounding boxes of a region's pieces, so that a nearest-point query
// looks at the pieces near the point instead of all of them: the region of a whole level has
// thousands of pieces, and the visibility refinement asks for a nearest eye at every step.
struct PieceGrid {
  static constexpr size_t kMinPieces = 32;  // below this, a query scans every piece
  glm::dvec2 lo{0.0};
  double cell_w = 1.0, cell_h = 1.0;
  int nx = 0, ny = 0;  // 0: no cells
  std::vector<uint32_t> first, items;  // cell c holds pieces items[first[c], first[c + 1])
  std::vector<uint32_t> seen;          // per piece, the query that looked at it last
  uint32_t query = 0;

  // About one cell per piece, shaped like the pieces' bounding box; no cells for fewer than
  // kMinPieces. Every piece is listed in each cell its bounding box meets.
  void build(std::span<const Convex2> pieces);
  // The cell column (row) of x (y), clamped to the grid; clamped before the conversion, since a
  // point far outside (or NaN) would not fit an int.
  int cellX(double x) const { return cellOf((x - lo.x) / cell_w, nx); }
  int cellY(double y) const { return cellOf((y - lo.y) / cell_h, ny); }
  static int cellOf(double t, int n) {
    return t >= 0.0 ? static_cast<int>(std::min(std::floor(t), static_cast<double>(n - 1))) : 0;
  }
};

// The point of the convex pieces nearest to `want`, pulled `inset` towards its piece's centroid;
// with a half-plane g·q + c0 >= 0 (`g` non-null), only the part of each piece inside it (`clip`
// is scratch). nullopt when no piece has such a part. `grid` must be built over these pieces (or
// have no cells); it only limits which pieces are looked at, so the distance is the nearest all
// the same (a tie between pieces may fall to another of them than a scan in order would take).
std::optional<glm::dvec2> nearestInPieces(std::span<const Convex2> pieces, const glm::dvec2& want, double inset,
                                          const glm::dvec2* g, double c0, std::vector<glm::dvec2>& clip,
                                          PieceGrid& grid);

}  // namespace walkvis
