// Walking physics: segment and ball queries against the walls through the BSP tree (Fuchs, Kedem,
// Naylor 1980: a query shape descends only into the half-spaces it reaches, as in BSP ray
// tracing, Naylor & Thibault 1986), and a grid over the floor levels' walkable pieces and the
// connections' patches (stairs and ramps, each on its own plane).
#include "walkthrough/movement.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "core/sample.h"

namespace walkvis {

namespace {

// Distance from p to a convex planar polygon (vertices CCW around plane.n), with the in-polygon
// test enlarged by tol (so seams between fragments are closed).
double pointPolygonDistance(std::span<const glm::dvec3> v, const Plane& plane, const glm::dvec3& p, double tol) {
  const double s = glm::dot(plane.n, p) - plane.d;
  const glm::dvec3 q = p - s * plane.n;
  bool inside = true;
  const size_t n = v.size();
  for (size_t i = 0; i < n && inside; ++i) {
    const glm::dvec3 e = v[(i + 1) % n] - v[i];
    const double len = glm::length(e);
    if (glm::dot(glm::cross(e, q - v[i]), plane.n) < -tol * len) inside = false;
  }
  if (inside) return std::abs(s);
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 a = v[i], e = v[(i + 1) % n] - v[i];
    const double ee = glm::dot(e, e);
    const double t = ee > 0.0 ? std::clamp(glm::dot(p - a, e) / ee, 0.0, 1.0) : 0.0;
    best = std::min(best, glm::length(p - (a + t * e)));
  }
  return best;
}

bool pointInPolygon(std::span<const glm::dvec3> v, const Plane& plane, const glm::dvec3& q, double tol) {
  const size_t n = v.size();
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 e = v[(i + 1) % n] - v[i];
    if (glm::dot(glm::cross(e, q - v[i]), plane.n) < -tol * glm::length(e)) return false;
  }
  return true;
}

}  // namespace

Walker::Walker(const Scene& scene, const BspTree& bsp, const MoveOptions& options) : scene_(scene), bsp_(bsp) {
  radius_ = options.radius_factor * scene.eye_height;
  step_ = options.step_factor * scene.eye_height;
  const Bounds b = sceneBounds(scene);
  double scale = 1.0;
  for (int k = 0; k < 3; ++k) scale = std::max({scale, std::abs(b.lo[k]), std::abs(b.hi[k])});
  tol_ = 1e-9 * scale;
  stack_.reserve(2 * bsp.nodes.size() + 2);

  double total = 0.0;
  double lx = std::numeric_limits<double>::infinity(), lz = lx, hx = -lx, hz = -lx;
  const auto addPiece = [&](const std::vector<glm::dvec2>& ring, uint32_t owner, uint32_t index, bool patch) {
    if (ring.size() < 3) return;
    Piece p{owner, index, ring[0].x, ring[0].y, ring[0].x, ring[0].y, patch};
    double area2 = 0.0;
    for (size_t k = 0; k < ring.size(); ++k) {
      const glm::dvec2 u = ring[k], w = ring[(k + 1) % ring.size()];
      p.lo_x = std::min(p.lo_x, u.x), p.hi_x = std::max(p.hi_x, u.x);
      p.lo_z = std::min(p.lo_z, u.y), p.hi_z = std::max(p.hi_z, u.y);
      area2 += u.x * w.y - w.x * u.y;
    }
    lx = std::min(lx, p.lo_x), hx = std::max(hx, p.hi_x), lz = std::min(lz, p.lo_z), hz = std::max(hz, p.hi_z);
    pieces_.push_back(p);
    if (!patch) {
      total += std::abs(area2) * 0.5;
      piece_area_cumulative_.push_back(total);
    }
  };
  for (uint32_t l = 0; l < scene.levels.size(); ++l) {
    const auto& pieces = scene.levels[l].walkable;
    for (uint32_t i = 0; i < pieces.size(); ++i) addPiece(pieces[i], l, i, false);
  }
  level_pieces_ = pieces_.size();
  // Patches on planes too steep to stand on (n.y not positive) carry no floor height.
  for (uint32_t c = 0; c < scene.connections.size(); ++c) {
    const auto& patches = scene.connections[c].patches;
    for (uint32_t i = 0; i < patches.size(); ++i)
      if (patches[i].plane.n.y > 0.0) addPiece(patches[i].piece, c, i, true);
  }
  if (pieces_.empty()) return;
  // About two cells per piece, at most 512 per side: a few pieces per cell on Freedoom maps.
  const double w = std::max(hx - lx, tol_), h = std::max(hz - lz, tol_);
  const double cells = std::min(2.0 * pieces_.size(), 512.0 * 512.0);
  cell_ = std::sqrt(w * h / cells);
  grid_nx_ = std::clamp(static_cast<int>(std::ceil(w / cell_)), 1, 512);
  grid_nz_ = std::clamp(static_cast<int>(std::ceil(h / cell_)), 1, 512);
  cell_ = std::max(w / grid_nx_, h / grid_nz_) * (1.0 + 1e-12);
  grid_x0_ = lx, grid_z0_ = lz;
  std::vector<std::vector<uint32_t>> cells_of(static_cast<size_t>(grid_nx_) * grid_nz_);
  auto cellIndex = [&](double v, double v0, int n) {
    return std::clamp(static_cast<int>(std::floor((v - v0) / cell_)), 0, n - 1);
  };
  for (uint32_t i = 0; i < pieces_.size(); ++i) {
    const Piece& p = pieces_[i];
    const int x0 = cellIndex(p.lo_x - tol_, grid_x0_, grid_nx_), x1 = cellIndex(p.hi_x + tol_, grid_x0_, grid_nx_);
    const int z0 = cellIndex(p.lo_z - tol_, grid_z0_, grid_nz_), z1 = cellIndex(p.hi_z + tol_, grid_z0_, grid_nz_);
    for (int z = z0; z <= z1; ++z)
      for (int x = x0; x <= x1; ++x) cells_of[static_cast<size_t>(z) * grid_nx_ + x].push_back(i);
  }
  cell_start_.push_back(0);
  for (const auto& c : cells_of) {
    cell_pieces_.insert(cell_pieces_.end(), c.begin(), c.end());
    cell_start_.push_back(static_cast<uint32_t>(cell_pieces_.size()));
  }
}

const std::vector<glm::dvec2>& Walker::ring(const Piece& p) const {
  return p.patch ? scene_.connections[p.level].patches[p.index].piece : scene_.levels[p.level].walkable[p.index];
}

double Walker::pieceFloor(const Piece& p, double x, double z) const {
  if (!p.patch) return scene_.levels[p.level].floor_y;
  const Plane& pl = scene_.connections[p.level].patches[p.index].plane;
  return (pl.d - pl.n.x * x - pl.n.z * z) / pl.n.y;
}

bool Walker::insidePiece(const Piece& p, double x, double z) const {
  if (x < p.lo_x - tol_ || x > p.hi_x + tol_ || z < p.lo_z - tol_ || z > p.hi_z + tol_) return false;
  const auto& ring = this->ring(p);
  bool neg = false, pos = false;
  for (size_t k = 0; k < ring.size(); ++k) {
    const glm::dvec2 u = ring[k], w = ring[(k + 1) % ring.size()];
    const glm::dvec2 e = w - u;
    const double c = e.x * (z - u.y) - e.y * (x - u.x);
    // sqrt of the sum, not hypot: coordinates are far from overflow, and the web viewer computes
    // the same bits without Math.hypot, which allocates in V8 (walkthrough/web/viewer.js).
    const double slack = tol_ * std::sqrt(e.x * e.x + e.y * e.y);
    if (c < -slack) neg = true;
    if (c > slack) pos = true;
  }
  return !(neg && pos);
}

std::optional<size_t> Walker::gridCell(double x, double z) const {
  if (pieces_.empty() || !std::isfinite(x) || !std::isfinite(z)) return std::nullopt;
  const double fx = (x - grid_x0_) / cell_, fz = (z - grid_z0_) / cell_;
  if (fx < -1.0 || fz < -1.0 || fx > grid_nx_ + 1.0 || fz > grid_nz_ + 1.0) return std::nullopt;
  const int cx = std::clamp(static_cast<int>(std::floor(fx)), 0, grid_nx_ - 1);
  const int cz = std::clamp(static_cast<int>(std::floor(fz)), 0, grid_nz_ - 1);
  return static_cast<size_t>(cz) * grid_nx_ + cx;
}

std::optional<uint32_t> Walker::levelUnder(double x, double z, double max_floor_y) const {
  const std::optional<size_t> cell = gridCell(x, z);
  if (!cell) return std::nullopt;
  const size_t c = *cell;
  std::optional<uint32_t> best;
  for (uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
    const Piece& p = pieces_[cell_pieces_[k]];
    if (p.patch) continue;
    const double fy = scene_.levels[p.level].floor_y;
    if (fy > max_floor_y) continue;
    if (best && scene_.levels[*best].floor_y >= fy) continue;
    if (insidePiece(p, x, z)) best = p.level;
  }
  return best;
}

std::optional<Walker::Floor> Walker::floorUnder(double x, double z, double max_floor_y) const {
  const std::optional<size_t> cell = gridCell(x, z);
  if (!cell) return std::nullopt;
  const size_t c = *cell;
  std::optional<Floor> best;
  for (uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
    const Piece& p = pieces_[cell_pieces_[k]];
    const double fy = pieceFloor(p, x, z);
    if (fy > max_floor_y) continue;
    const int level = p.patch ? -1 : static_cast<int>(p.level);
    if (best && (best->y > fy || (best->y == fy && (best->level >= 0 || level < 0)))) continue;
    if (insidePiece(p, x, z)) best = Floor{fy, level};
  }
  return best;
}

std::optional<std::pair<glm::dvec2, uint32_t>> Walker::randomWalkablePoint(uint64_t& rng) const {
  if (level_pieces_ == 0 || !(piece_area_cumulative_.back() > 0.0)) return std::nullopt;
  const size_t i = pickByWeight(piece_area_cumulative_, rng);
  const auto& ring = scene_.levels[pieces_[i].level].walkable[pieces_[i].index];
  return std::make_pair(uniformPointInConvex<glm::dvec2>(ring, rng), pieces_[i].level);
}

bool Walker::wallBlocks(uint32_t f, const glm::dvec3& a, const glm::dvec3& b, double radius) const {
  const Plane& pl = bsp_.fragments[f].plane;
  if (!(std::abs(pl.n.y) < kWallMaxNormalY)) return false;
  const auto v = bsp_.fragmentVertices(f);
  const double sa = glm::dot(pl.n, a) - pl.d, sb = glm::dot(pl.n, b) - pl.d;
  // Crossing: strictly from one side to the other, or ending on the plane, inside the polygon.
  if ((sa > tol_ && sb < -tol_) || (sa < -tol_ && sb > tol_)) {
    const glm::dvec3 p = a + (sa / (sa - sb)) * (b - a);
    if (pointInPolygon(v, pl, p, tol_)) return true;
  } else if (std::abs(sb) <= tol_ && pointInPolygon(v, pl, b, tol_)) {
    return true;
  }
  if (radius > 0.0 && std::abs(sb) < radius) {
    const double db = pointPolygonDistance(v, pl, b, tol_);
    if (db < radius && db < pointPolygonDistance(v, pl, a, tol_) - tol_) return true;
  }
  return false;
}

bool Walker::blocks(int32_t node_index, const glm::dvec3& a, const glm::dvec3& b, double radius,
                    glm::dvec3* blocker) const {
  // Explicit stack (BSP depth can be large on big maps), the walker's own: the root and each of a
  // node's two children are pushed at most once, so it never outgrows the 2 · nodes + 2 the
  // constructor reserved and a move allocates nothing.
  std::vector<int32_t>& stack = stack_;
  stack.clear();
  stack.push_back(node_index);
  while (!stack.empty()) {
    const int32_t ni = stack.back();
    stack.pop_back();
    if (ni < 0) continue;
    const BspNode& node = bsp_.nodes[ni];
    const double sa = glm::dot(node.plane.n, a) - node.plane.d, sb = glm::dot(node.plane.n, b) - node.plane.d;
    const double lo = std::min(sa, sb - radius) - tol_, hi = std::max(sa, sb + radius) + tol_;
    if (lo <= 0.0 && hi >= 0.0) {
      for (uint32_t k = 0; k < node.fragment_count; ++k) {
        const uint32_t f = node.first_fragment + k;
        if (wallBlocks(f, a, b, radius)) {
          if (blocker) *blocker = bsp_.fragments[f].plane.n;
          return true;
        }
      }
    }
    if (hi > 0.0) stack.push_back(node.front);
    if (lo < 0.0) stack.push_back(node.back);
  }
  return false;
}

bool Walker::segmentClear(const glm::dvec3& a, const glm::dvec3& b, double radius, glm::dvec3* blocker) const {
  if (bsp_.root < 0) return true;
  return !blocks(bsp_.root, a, b, radius, blocker);
}

WalkState Walker::place(const glm::dvec3& eye) const {
  const auto floor = floorUnder(eye.x, eye.z, eye.y - scene_.eye_height + step_ + tol_);
  if (!floor) return {eye, -1};
  return {{eye.x, floor->y + scene_.eye_height, eye.z}, floor->level};
}

std::optional<WalkState> Walker::tryMove(const WalkState& from, const glm::dvec2& d) const {
  if (!std::isfinite(d.x) || !std::isfinite(d.y)) return std::nullopt;
  const glm::dvec3 mid{from.eye.x + d.x, from.eye.y, from.eye.z + d.y};
  if (!segmentClear(from.eye, mid, radius_)) return std::nullopt;
  const double floor_now =
      from.level >= 0 ? scene_.levels[from.level].floor_y : from.eye.y - scene_.eye_height;
  const auto floor = floorUnder(mid.x, mid.z, floor_now + step_ + tol_);
  if (!floor) {
    // Walking off the walkable region: refused when standing on a level or a patch (a floor at
    // the eye's own height under it); in the air the eye keeps its height.
    if (from.level >= 0) return std::nullopt;
    const auto under = floorUnder(from.eye.x, from.eye.z, floor_now + tol_);
    if (under && under->y >= floor_now - tol_) return std::nullopt;
    return WalkState{mid, -1};
  }
  const WalkState to{{mid.x, floor->y + scene_.eye_height, mid.z}, floor->level};
  // Vertically only crossings matter: stepping up or dropping down beside a riser is the point.
  if (to.eye.y != mid.y && !segmentClear(mid, to.eye, 0.0)) return std::nullopt;
  return to;
}

WalkState Walker::move(const WalkState& from, const glm::dvec2& d) const {
  if (d.x == 0.0 && d.y == 0.0) return from;
  if (auto to = tryMove(from, d)) return *to;
  glm::dvec3 n;
  const glm::dvec3 mid{from.eye.x + d.x, from.eye.y, from.eye.z + d.y};
  if (!segmentClear(from.eye, mid, radius_, &n)) {
    const glm::dvec2 nh{n.x, n.z};
    const double len = std::hypot(nh.x, nh.y);
    if (len > 0.0) {
      const glm::dvec2 u = nh / len;
      if (auto to = tryMove(from, d - glm::dot(d, u) * u)) return *to;
    }
  }
  if (auto to = tryMove(from, {d.x, 0.0})) return *to;
  if (auto to = tryMove(from, {0.0, d.y})) return *to;
  return from;
}

}  // namespace walkvis
