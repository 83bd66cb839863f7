// Convex region pieces and the grid-accelerated nearest-point query (region_pieces.h).
#include "pfd_hfd/region_pieces.h"

#include <limits>

#include <glm/common.hpp>

#include "core/check.h"

namespace walkvis {
namespace {

// The cells piece p's bounding box meets, as index ranges.
void cellsOf(const PieceGrid& grid, const Convex2& p, int& x0, int& x1, int& y0, int& y1) {
  glm::dvec2 plo = p.v[0], phi = p.v[0];
  for (const glm::dvec2& v : p.v) plo = glm::min(plo, v), phi = glm::max(phi, v);
  x0 = grid.cellX(plo.x), x1 = grid.cellX(phi.x), y0 = grid.cellY(plo.y), y1 = grid.cellY(phi.y);
}

}  // namespace

bool insideConvex(const std::vector<glm::dvec2>& poly, const glm::dvec2& p) {
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i)
    if (cross2(poly[(i + 1) % n] - poly[i], p - poly[i]) < 0.0) return false;
  return true;
}

glm::dvec2 closestInConvex(const std::vector<glm::dvec2>& poly, const glm::dvec2& p, double& dist2) {
  if (insideConvex(poly, p)) {
    dist2 = 0.0;
    return p;
  }
  glm::dvec2 best = poly[0];
  dist2 = std::numeric_limits<double>::infinity();
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2 q = closestOnSegment(poly[i], poly[(i + 1) % n], p);
    const double d2 = glm::dot(q - p, q - p);
    if (d2 < dist2) {
      dist2 = d2;
      best = q;
    }
  }
  return best;
}

bool clipHalfPlane(const std::vector<glm::dvec2>& poly, const glm::dvec2& g, double c0, std::vector<glm::dvec2>& out) {
  out.clear();
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2& p = poly[i];
    const glm::dvec2& q = poly[(i + 1) % n];
    const double fp = glm::dot(g, p) + c0, fq = glm::dot(g, q) + c0;
    if (fp >= 0.0) out.push_back(p);
    if ((fp >= 0.0) != (fq >= 0.0)) out.push_back(p + (fp / (fp - fq)) * (q - p));
  }
  return out.size() >= 3;
}

bool circleBehind(const Convex2& piece, const glm::dvec2& g, double c0) {
  return glm::dot(g, piece.centroid) + c0 < -piece.radius * glm::length(g) * (1.0 + 1e-9);
}

bool rectBehind(const glm::dvec2& lo, const glm::dvec2& hi, const glm::dvec2& g, double c0) {
  const double top = std::max(g.x * lo.x, g.x * hi.x) + std::max(g.y * lo.y, g.y * hi.y) + c0;
  return top < -1e-9 * (std::abs(g.x) * std::max(std::abs(lo.x), std::abs(hi.x)) +
                        std::abs(g.y) * std::max(std::abs(lo.y), std::abs(hi.y)) + std::abs(c0));
}

glm::dvec2 pullTowards(const glm::dvec2& p, const glm::dvec2& c, double shrink, double gap) {
  const double len = glm::length(p - c);
  if (!(len > 0.0)) return c;
  const double f = std::min(0.5, std::max(shrink, gap / len));
  return p + f * (c - p);
}

void PieceGrid::build(std::span<const Convex2> pieces) {
  nx = ny = 0;
  if (pieces.size() < kMinPieces) return;
  glm::dvec2 hi = pieces[0].v[0];
  lo = hi;
  for (const Convex2& p : pieces)
    for (const glm::dvec2& v : p.v) lo = glm::min(lo, v), hi = glm::max(hi, v);
  const glm::dvec2 size = glm::max(hi - lo, glm::dvec2(1e-300));
  // About one cell per piece, shaped like the region's box.
  const double n = static_cast<double>(pieces.size());
  nx = static_cast<int>(std::clamp(std::sqrt(n * size.x / size.y), 1.0, 1024.0));
  ny = static_cast<int>(std::clamp(n / nx, 1.0, 1024.0));
  cell_w = size.x / nx, cell_h = size.y / ny;
  first.assign(static_cast<size_t>(nx) * ny + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    for (uint32_t i = 0; i < pieces.size(); ++i) {
      int x0, x1, y0, y1;
      cellsOf(*this, pieces[i], x0, x1, y0, y1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const size_t c = static_cast<size_t>(y) * nx + x;
          if (pass == 0) ++first[c + 1];
          else items[first[c]++] = i;
        }
    }
    if (pass == 0) {
      for (size_t c = 1; c < first.size(); ++c) first[c] += first[c - 1];
      items.assign(first.back(), 0);
    } else {  // the fill advanced each cell's start to the next one's: shift back
      for (size_t c = first.size() - 1; c > 0; --c) first[c] = first[c - 1];
      first[0] = 0;
    }
  }
  seen.assign(pieces.size(), 0);
  query = 0;
}

std::optional<glm::dvec2> nearestInPieces(std::span<const Convex2> pieces, const glm::dvec2& want, double inset,
                                          const glm::dvec2* g, double c0, std::vector<glm::dvec2>& clip,
                                          PieceGrid& grid) {
  WALKVIS_DCHECK(grid.nx == 0 || grid.seen.size() == pieces.size());  // built over these pieces
  double best = std::numeric_limits<double>::infinity();
  std::optional<glm::dvec2> out;
  auto consider = [&](const Convex2& piece) {
    // A piece whose bounding circle lies farther than the best point so far cannot hold a nearer
    // one. The factor keeps the rounding of the bound (~1e-16 relative) from skipping a piece
    // that ties.
    const double lower = glm::length(want - piece.centroid) - piece.radius;
    if (lower > 0.0 && lower * lower > best * (1.0 + 1e-9)) return;
    if (g && circleBehind(piece, *g, c0)) return;
    if (g && !clipHalfPlane(piece.v, *g, c0, clip)) return;
    double d2;
    const glm::dvec2 c = closestInConvex(g ? clip : piece.v, want, d2);
    if (d2 < best) {
      best = d2;
      out = pullTowards(c, piece.centroid, 0.0, inset);
    }
  };
  if (grid.nx == 0) {
    for (const Convex2& piece : pieces) consider(piece);
    return out;
  }
  if (g && rectBehind(grid.lo, grid.lo + glm::dvec2(grid.nx * grid.cell_w, grid.ny * grid.cell_h), *g, c0))
    return out;
  // Rings of cells around want's cell, nearest first. The nearest point of a piece lies in a
  // cell its box covers, where the piece is listed, so a cell farther than the best point so far
  // holds nothing nearer, and once every cell left lies outside a box of cells whose inside is
  // farther from want than the best point, so does the rest.
  if (++grid.query == 0) std::fill(grid.seen.begin(), grid.seen.end(), 0u), grid.query = 1;
  const int cx = grid.cellX(want.x), cy = grid.cellY(want.y);
  const double inf = std::numeric_limits<double>::infinity();
  const int rings = std::max({cx, grid.nx - 1 - cx, cy, grid.ny - 1 - cy});
  auto farther = [&](double d) { return d > 0.0 && d * d > best * (1.0 + 1e-9); };
  const glm::dvec2 cell{grid.cell_w, grid.cell_h};
  auto visit = [&](int x, int y) {
    const glm::dvec2 c_lo = grid.lo + glm::dvec2(x, y) * cell;
    if (farther(glm::length(glm::max(glm::max(c_lo - want, want - (c_lo + cell)), glm::dvec2(0.0))))) return;
    if (g && rectBehind(c_lo, c_lo + cell, *g, c0)) return;
    const size_t c = static_cast<size_t>(y) * grid.nx + x;
    for (uint32_t i = grid.first[c]; i < grid.first[c + 1]; ++i) {
      const uint32_t piece = grid.items[i];
      if (grid.seen[piece] == grid.query) continue;
      grid.seen[piece] = grid.query;
      consider(pieces[piece]);
    }
  };
  for (int k = 0; k <= rings; ++k) {
    if (k > 0) {
      // The cells of ring k lie beyond the box of rings 0..k-1, on the sides where it ends
      // before the grid does.
      const double x0 = grid.lo.x + (cx - k + 1) * grid.cell_w, x1 = grid.lo.x + (cx + k) * grid.cell_w;
      const double y0 = grid.lo.y + (cy - k + 1) * grid.cell_h, y1 = grid.lo.y + (cy + k) * grid.cell_h;
      if (want.x >= x0 && want.x <= x1 && want.y >= y0 && want.y <= y1) {
        const double d = std::min({cx - k + 1 > 0 ? want.x - x0 : inf, cx + k < grid.nx ? x1 - want.x : inf,
                                   cy - k + 1 > 0 ? want.y - y0 : inf, cy + k < grid.ny ? y1 - want.y : inf});
        if (farther(d)) break;
      }
    }
    for (int y = std::max(0, cy - k); y <= std::min(grid.ny - 1, cy + k); ++y) {
      if (y == cy - k || y == cy + k) {  // a whole row of ring k
        for (int x = std::max(0, cx - k); x <= std::min(grid.nx - 1, cx + k); ++x) visit(x, y);
      } else {  // its two ends
        if (cx - k >= 0) visit(cx - k, y);
        if (cx + k < grid.nx) visit(cx + k, y);
      }
    }
  }
  return out;
}

}  // namespace walkvis
