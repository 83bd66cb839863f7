// Hierarchical back-face computation: Kumar, Manocha, Garrett & Lin 1996
// [Kumar1996]. Method `hierarchy`.
//
// §4 clusters: polygons are grouped by normal (a grid on the cube faces of the normal: all normals
// of a cell are within 90° of the cell's axis, so both regions of every cluster have an interior)
// and by position (the paper's metric (1): the distance of the polygon's plane from an origin, here
// the model's centre). §4.1 hierarchy: each cluster is split into four normal sub-cells, and into
// two by the median plane distance where those differ (so four or eight sub-clusters), recursively
// down to `leaf_size` polygons (20 in the paper); a split that separates nothing falls back to a
// median split of the polygons' centroids along the widest axis.
// §5 regions: BackRegion = ∩ {n_i·x <= d_i}, FrontRegion = ∩ {n_i·x >= d_i}, built in
// kumar_regions_cgal.cpp (LP + dual hull). A parent's region is the intersection of its children's,
// so only the children's boundary planes are candidates for the parent's boundary (§4.1, R_A ⊂ ...).
// §5.4 Query cells: our cell of boundary face k is the whole cone from the centre c over face k
// (side planes p_k·y = p_j·y through c and each edge of the face, see kumar.h) rather than the
// paper's triangles: a face has fewer than six edges on average, so the cell test stays small, and
// the BT_i ↔ FQ_j overlap lists of §5.4 are not needed (each region keeps its own last cell).
// §6 tracking: from the last cell, walk to the neighbour with the largest p·y while it grows (the
// paper's walk across a failed side plane), with visit counters per boundary plane (§8.1); a move
// longer than jump_fraction of the model diagonal, or a walk longer than 8 + 2√m cells, falls back to
// the full test (a scan of every boundary plane, which re-seeds the cell). §6.1: when the eye was in
// a region last frame, the inscribed ball around c and the inscribed cone with apex c are tried
// first. §6.2: a Mixed node is recursed into; when the eye is in the BackRegion the FrontRegion
// is not tracked that frame, and vice versa. §7 rigid motion: the eye is moved into the model frame.
//
// Conservative arithmetic. Inside a region means max_k p_k·y <= 1 − tol with
//   tol = kTol·(1 + p_max·|y|₁) + kRound·scale/g_min,  kTol = 1e-6, kRound = 1e-12:
// then every plane (boundary, merged into one, or redundant) has n_i·e − d_i <= −g_i·tol/2, beyond
// the merging of near-equal dual points (1e-7) and the rounding of the double evaluations (~1e-16
// of p_max·|y|₁ and of scale), so isFrontFacing() is false for all of a
// culled cluster (BackRegion) and true for all of a kept-whole one (FrontRegion). The walk
// evaluates the same p_k·y as the full scan; a walk ending at s with 1 − 2·tol < s <= 1 − tol is
// re-checked by the full scan, so both give the same verdict unless rounding alone made a
// non-maximum look like a local maximum by more than tol: with dual points at least 1e-7·max|p|
// apart that takes rounding errors summed over ~10⁷ edge lengths, 10³ below tol.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>

#include "backface/kumar.h"

#include "core/check.h"

namespace walkvis {
namespace {

// Relative margin of the inside test, see the header comment: covers the merged dual points
// (kumar_regions_cgal.cpp, within 1e-7 of max|p|, so within 1e-7·p_max·|y|₁ in p·y) twice over,
// and the rounding of the evaluations by far.
constexpr double kTol = 1e-6;
// The plane offsets g_i = d_i − n_i·c and the evaluations n·e − d round at ~1e-16 of `scale`,
// which is ~1e-16·scale/g_min in p·y: 1e-12 leaves four orders.
constexpr double kRound = 1e-12;
// The inscribed cone is tested with this margin on the cosine: rounding of y·w and |y| is ~1e-16,
// so a pass is strictly inside the cone; cones narrower than kMinConeSin are not worth a test.
constexpr double kConeMargin = 1e-9;
constexpr double kMinConeSin = 1e-3;
constexpr int kMaxDepth = 64;  // splits halve the polygon count or the normal cell; 64 is never reached

struct BuildNode {
  std::vector<uint32_t> polygons;  // subtree polygons (build time)
  std::vector<uint32_t> children;
};

struct NormalCell {
  int face;
  double u0, u1, v0, v1;
};

// Cube face of a normal (axis of its largest component, sign) and the coordinates on that face.
void cubeCoords(const glm::dvec3& n, int& face, double& u, double& v) {
  const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
  const int a = ax >= ay && ax >= az ? 0 : (ay >= az ? 1 : 2);
  face = 2 * a + (n[a] < 0.0 ? 1 : 0);
  const double m = std::abs(n[a]);
  u = n[(a + 1) % 3] / m;
  v = n[(a + 2) % 3] / m;
}

}  // namespace

KumarHierarchy::KumarHierarchy(const BackfaceInput& input, const KumarOptions& options) {
  if (options.leaf_size < 1 || options.top_grid < 1 || options.top_grid > 64 || !(options.jump_fraction > 0.0)) {
    throw Error("backface hierarchy: leaf_size >= 1, top_grid in [1, 64] and jump_fraction > 0 required");
  }
  const size_t count = input.polygons.size();
  std::vector<int> face(count);
  std::vector<double> u(count), v(count), dist(count);
  std::vector<glm::dvec3> centroid(count, glm::dvec3(0.0));
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (size_t i = 0; i < count; ++i) {
    const Polygon& p = input.polygons[i];
    for (uint32_t k = 0; k < p.vertex_count; ++k) {
      const glm::dvec3& x = input.vertices[p.first_vertex + k];
      centroid[i] += x;
      lo = glm::min(lo, x);
      hi = glm::max(hi, x);
    }
    centroid[i] /= static_cast<double>(p.vertex_count);
    cubeCoords(p.plane.n, face[i], u[i], v[i]);
  }
  const glm::dvec3 model_center = count ? 0.5 * (lo + hi) : glm::dvec3(0.0);
  const double diag = count ? glm::length(hi - lo) : 1.0;
  jump_ = options.jump_fraction * (diag > 0.0 ? diag : 1.0);
  for (size_t i = 0; i < count; ++i) {
    dist[i] = std::abs(input.polygons[i].plane.d - glm::dot(input.polygons[i].plane.n, model_center));
  }

  // ---- Clusters and hierarchy (preorder) ----
  std::vector<BuildNode> build;
  std::vector<NormalCell> cells;
  leaf_begin_.push_back(0);
  auto make = [&](auto&& self, std::vector<uint32_t> polys, NormalCell cell, int depth) -> uint32_t {
    const uint32_t at = static_cast<uint32_t>(nodes_.size());
    nodes_.emplace_back();
    build.emplace_back();
    nodes_[at].leaf_begin = static_cast<uint32_t>(leaf_begin_.size() - 1);
    std::vector<std::vector<uint32_t>> groups;
    std::vector<NormalCell> group_cells;
    if (polys.size() > options.leaf_size && depth < kMaxDepth) {
      const double um = 0.5 * (cell.u0 + cell.u1), vm = 0.5 * (cell.v0 + cell.v1);
      double dmin = INFINITY, dmax = -INFINITY;
      for (uint32_t p : polys) {
        dmin = std::min(dmin, dist[p]);
        dmax = std::max(dmax, dist[p]);
      }
      // Plane distances closer than this share of the model are one position class.
      const bool by_distance = dmax - dmin > 1e-6 * diag;
      double dmed = 0.0;
      if (by_distance) {
        std::vector<double> ds;
        for (uint32_t p : polys) ds.push_back(dist[p]);
        std::nth_element(ds.begin(), ds.begin() + static_cast<std::ptrdiff_t>(ds.size() / 2), ds.end());
        dmed = ds[ds.size() / 2];
      }
      groups.assign(8, {});
      for (int g = 0; g < 8; ++g) {
        group_cells.push_back({cell.face, g & 1 ? um : cell.u0, g & 1 ? cell.u1 : um, g & 2 ? vm : cell.v0,
                               g & 2 ? cell.v1 : vm});
      }
      for (uint32_t p : polys) {
        const int g = (u[p] >= um ? 1 : 0) + (v[p] >= vm ? 2 : 0) + (by_distance && dist[p] >= dmed ? 4 : 0);
        groups[static_cast<size_t>(g)].push_back(p);
      }
      size_t nonempty = 0;
      for (const auto& g : groups) nonempty += !g.empty();
      if (nonempty < 2) {
        // Same normal cell and plane distance: split by position along the widest axis.
        glm::dvec3 clo(INFINITY), chi(-INFINITY);
        for (uint32_t p : polys) {
          clo = glm::min(clo, centroid[p]);
          chi = glm::max(chi, centroid[p]);
        }
        const glm::dvec3 ext = chi - clo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        std::vector<uint32_t> sorted = polys;
        const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
        std::nth_element(sorted.begin(), mid, sorted.end(),
                         [&](uint32_t a, uint32_t b) { return centroid[a][axis] < centroid[b][axis]; });
        groups = {std::vector<uint32_t>(sorted.begin(), mid), std::vector<uint32_t>(mid, sorted.end())};
        group_cells = {cell, cell};
      }
    }
    if (groups.empty()) {
      leaf_polygons_.insert(leaf_polygons_.end(), polys.begin(), polys.end());
      leaf_begin_.push_back(static_cast<uint32_t>(leaf_polygons_.size()));
    } else {
      for (size_t g = 0; g < groups.size(); ++g) {
        if (groups[g].empty()) continue;
        const uint32_t child = self(self, std::move(groups[g]), group_cells[g], depth + 1);
        build[at].children.push_back(child);
      }
    }
    nodes_[at].leaf_end = static_cast<uint32_t>(leaf_begin_.size() - 1);
    nodes_[at].skip = static_cast<uint32_t>(nodes_.size());
    build[at].polygons = std::move(polys);
    return at;
  };
  {
    const int grid = options.top_grid;
    std::vector<std::vector<uint32_t>> roots(static_cast<size_t>(6 * grid * grid));
    for (size_t i = 0; i < count; ++i) {
      const int iu = std::clamp(static_cast<int>((u[i] + 1.0) * 0.5 * grid), 0, grid - 1);
      const int iv = std::clamp(static_cast<int>((v[i] + 1.0) * 0.5 * grid), 0, grid - 1);
      roots[static_cast<size_t>((face[i] * grid + iu) * grid + iv)].push_back(static_cast<uint32_t>(i));
    }
    for (size_t r = 0; r < roots.size(); ++r) {
      if (roots[r].empty()) continue;
      const int f = static_cast<int>(r) / (grid * grid), iu = (static_cast<int>(r) / grid) % grid,
                iv = static_cast<int>(r) % grid;
      const double step = 2.0 / grid;
      make(make, std::move(roots[r]), {f, -1.0 + iu * step, -1.0 + (iu + 1) * step, -1.0 + iv * step,
                                       -1.0 + (iv + 1) * step}, 0);
    }
  }

  // ---- Regions, bottom-up (children follow their parent in preorder) ----
  std::vector<std::vector<uint32_t>> boundary_back(nodes_.size()), boundary_front(nodes_.size());
  std::vector<Plane> planes;
  for (size_t idx = nodes_.size(); idx-- > 0;) {
    Node& node = nodes_[idx];
    glm::dvec3 blo(INFINITY), bhi(-INFINITY);
    for (uint32_t p : build[idx].polygons) {
      const Polygon& poly = input.polygons[p];
      for (uint32_t k = 0; k < poly.vertex_count; ++k) {
        blo = glm::min(blo, input.vertices[poly.first_vertex + k]);
        bhi = glm::max(bhi, input.vertices[poly.first_vertex + k]);
      }
    }
    // The interior point is looked for in the cluster's box grown by twice its diagonal on every
    // side: the regions are unbounded cones away from the cluster, and a point well away from it
    // has room for a large inscribed ball.
    const double grow = 2.0 * std::max(glm::length(bhi - blo), 1e-9 * (diag > 0.0 ? diag : 1.0));
    blo -= glm::dvec3(grow);
    bhi += glm::dvec3(grow);
    for (int side = 0; side < 2; ++side) {
      std::vector<uint32_t> candidates;
      if (build[idx].children.empty()) {
        candidates = build[idx].polygons;
      } else {
        for (uint32_t c : build[idx].children) {
          const auto& b = side == 0 ? boundary_back[c] : boundary_front[c];
          candidates.insert(candidates.end(), b.begin(), b.end());
        }
        std::sort(candidates.begin(), candidates.end());
        candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
      }
      planes.clear();
      for (uint32_t p : candidates) {
        const Plane& pl = input.polygons[p].plane;
        planes.push_back(side == 0 ? pl : Plane{-pl.n, -pl.d});
      }
      KumarRegion region = buildKumarRegion(planes, blo, bhi);
      std::vector<uint32_t>& boundary = side == 0 ? boundary_back[idx] : boundary_front[idx];
      if (region.has_interior) {
        for (uint32_t& k : region.plane) k = candidates[k];  // now polygon indices
        for (uint32_t& k : region.members) k = candidates[k];
        boundary = region.members;
      } else {
        boundary = std::move(candidates);  // unknown boundary: the parent gets every candidate
      }
      // Inscribed cone with apex c: axis −(mean normal), half-angle θ with sin θ = min −n_k·w.
      glm::dvec3 axis(0.0);
      for (const glm::dvec3& p : region.dual) axis -= glm::normalize(p);
      double cos_half = 2.0;
      if (region.has_interior && glm::length(axis) > 0.0) {
        axis = glm::normalize(axis);
        double sin_half = INFINITY;
        for (const glm::dvec3& p : region.dual) sin_half = std::min(sin_half, -glm::dot(glm::normalize(p), axis));
        if (sin_half > kMinConeSin) cos_half = std::sqrt(std::max(0.0, 1.0 - sin_half * sin_half));
      }
      if (side == 0) {
        node.back = std::move(region);
        node.back_axis = axis;
        node.back_cos = cos_half;
      } else {
        node.front = std::move(region);
        node.front_axis = axis;
        node.front_cos = cos_half;
      }
    }
    node.back_offset = static_cast<uint32_t>(visit_.size());
    visit_.resize(visit_.size() + node.back.dual.size(), 0);
    node.front_offset = static_cast<uint32_t>(visit_.size());
    visit_.resize(visit_.size() + node.front.dual.size(), 0);
  }
}

std::span<const uint32_t> KumarHierarchy::nodePolygons(size_t node) const {
  const Node& n = nodes_[node];
  return {leaf_polygons_.data() + leaf_begin_[n.leaf_begin], leaf_begin_[n.leaf_end] - leaf_begin_[n.leaf_begin]};
}

namespace {

double tolerance(const KumarRegion& region, const glm::dvec3& y) {
  return kTol * (1.0 + region.p_max * (std::abs(y.x) + std::abs(y.y) + std::abs(y.z))) +
         kRound * region.scale / region.g_min;
}

}  // namespace

bool KumarHierarchy::inRegionFull(const KumarRegion& region, const glm::dvec3& eye, uint32_t* best) {
  if (!region.has_interior) return false;
  const glm::dvec3 y = eye - region.center;
  double top = -INFINITY;
  uint32_t arg = 0;
  for (size_t k = 0; k < region.dual.size(); ++k) {
    const double s = glm::dot(region.dual[k], y);
    if (s > top) {
      top = s;
      arg = static_cast<uint32_t>(k);
    }
  }
  if (best) *best = arg;
  return top <= 1.0 - tolerance(region, y);
}

bool KumarHierarchy::inRegion(const KumarRegion& region, RegionState& state, uint32_t visit_offset,
                              const glm::dvec3& axis, double cos_half, bool try_cone, const glm::dvec3& eye,
                              bool jumped) {
  if (!region.has_interior) return false;
  ++stats_.queries;
  const glm::dvec3 y = eye - region.center;
  const double tol = tolerance(region, y);
  if (try_cone) {
    // §6.1: the inscribed ball (|y| <= g_min gives p_k·y <= |y|/g_k <= 1) and cone (p_k·y <= 0).
    const double len = glm::length(y);
    if (len <= region.g_min * (1.0 - 2.0 * tol) ||
        (cos_half <= 1.0 && glm::dot(y, axis) > len * (cos_half + kConeMargin))) {
      ++stats_.inscribed_hits;
      return true;
    }
  }
  if (!jumped) {
    const glm::dvec3* dual = region.dual.data();
    const uint32_t m = static_cast<uint32_t>(region.dual.size());
    const uint32_t max_steps = 8 + 2 * static_cast<uint32_t>(std::sqrt(static_cast<double>(m)));
    uint32_t k = state.cell < m ? state.cell : 0;
    double s = glm::dot(dual[k], y);
    visit_[visit_offset + k] = frame_;
    bool blocked = false;
    uint32_t steps = 0;
    for (;;) {
      uint32_t next = k;
      double best = s;
      for (uint32_t a = region.adj_begin[k]; a < region.adj_begin[k + 1]; ++a) {
        const uint32_t j = region.adj[a];
        const double sj = glm::dot(dual[j], y);
        if (sj > best) {
          // §8.1 visit counter: a cell already entered this frame is not entered again.
          if (visit_[visit_offset + j] == frame_) {
            blocked = true;
            continue;
          }
          best = sj;
          next = j;
        }
      }
      if (next == k) break;
      k = next;
      s = best;
      visit_[visit_offset + k] = frame_;
      ++stats_.walk_steps;
      if (++steps > max_steps) break;
    }
    if (steps <= max_steps && !blocked) {
      state.cell = k;
      if (s > 1.0 - tol) return false;     // some plane is (nearly) crossed: exact either way
      if (s <= 1.0 - 2.0 * tol) return true;
    }
  }
  ++stats_.full_tests;
  uint32_t best = 0;
  const bool inside = inRegionFull(region, eye, &best);
  state.cell = best;
  return inside;
}

KumarVerdict KumarHierarchy::track(size_t index, const glm::dvec3& eye) {
  Node& node = nodes_[index];
  const bool jumped = !node.seen || glm::length(eye - node.last_eye) > jump_;
  auto back = [&] {
    return inRegion(node.back, node.back_state, node.back_offset, node.back_axis, node.back_cos,
                    node.last == KumarVerdict::kBack, eye, jumped);
  };
  auto front = [&] {
    return inRegion(node.front, node.front_state, node.front_offset, node.front_axis, node.front_cos,
                    node.last == KumarVerdict::kFront, eye, jumped);
  };
  KumarVerdict verdict = KumarVerdict::kMixed;
  // The region the eye was in last time first (§6.2: only that one is tracked while it holds).
  if (node.last == KumarVerdict::kFront) {
    if (front()) verdict = KumarVerdict::kFront;
    else if (back()) verdict = KumarVerdict::kBack;
  } else {
    if (back()) verdict = KumarVerdict::kBack;
    else if (front()) verdict = KumarVerdict::kFront;
  }
  node.last = verdict;
  node.last_eye = eye;
  node.seen = true;
  return verdict;
}

KumarVerdict KumarHierarchy::classifyFull(size_t index, const glm::dvec3& eye) const {
  const Node& node = nodes_[index];
  if (inRegionFull(node.back, eye, nullptr)) return KumarVerdict::kBack;
  if (inRegionFull(node.front, eye, nullptr)) return KumarVerdict::kFront;
  return KumarVerdict::kMixed;
}

void KumarHierarchy::beginFrame() {
  if (++frame_ == 0) {  // the counters wrapped: clear them so that no stale stamp matches
    std::fill(visit_.begin(), visit_.end(), 0u);
    frame_ = 1;
  }
}

void KumarHierarchy::cull(const glm::dvec3& eye, std::span<uint8_t> leaf_culled) {
  WALKVIS_DCHECK(leaf_culled.size() == leafCount());
  beginFrame();
  uint8_t* out = leaf_culled.data();
  const size_t count = nodes_.size();
  size_t i = 0;
  while (i < count) {
    const Node& node = nodes_[i];
    const KumarVerdict verdict = track(i, eye);
    if (verdict != KumarVerdict::kMixed) {
      std::memset(out + node.leaf_begin, verdict == KumarVerdict::kBack ? 1 : 0, node.leaf_end - node.leaf_begin);
      i = node.skip;
    } else {
      if (node.skip == i + 1) out[node.leaf_begin] = 0;  // a Mixed leaf is drawn
      ++i;
    }
  }
}

void KumarHierarchy::cullRigid(const glm::dmat3& rotation, const glm::dvec3& translation, const glm::dvec3& eye_world,
                               std::span<uint8_t> leaf_culled) {
  // world = R·object + t, R orthonormal: object = Rᵀ·(world − t).
  cull(glm::transpose(rotation) * (eye_world - translation), leaf_culled);
}

size_t KumarHierarchy::stateBytes() const {
  size_t bytes = nodes_.size() * sizeof(Node) + visit_.size() * sizeof(uint32_t);
  for (const Node& n : nodes_) {
    for (const KumarRegion* r : {&n.back, &n.front}) {
      bytes += r->dual.size() * sizeof(glm::dvec3) + r->adj_begin.size() * sizeof(uint32_t) +
               r->adj.size() * sizeof(uint32_t);
    }
  }
  return bytes;
}

namespace {

class HierarchyCuller final : public BackfaceCuller {
 public:
  HierarchyCuller(const BackfaceInput& input, const BackfaceOptions& options)
      : hierarchy_(input, {options.hierarchy_leaf_size, options.hierarchy_top_grid, options.hierarchy_jump}) {
    polygon_count_ = input.polygons.size();
    unit_begin_.push_back(0);
    for (size_t l = 0; l < hierarchy_.leafCount(); ++l) {
      const auto polys = hierarchy_.leafPolygons(l);
      unit_polygons_.insert(unit_polygons_.end(), polys.begin(), polys.end());
      unit_begin_.push_back(static_cast<uint32_t>(unit_polygons_.size()));
    }
  }
  BackfaceMethod method() const override { return BackfaceMethod::kHierarchy; }
  size_t stateBytes() const override { return hierarchy_.stateBytes(); }
  // The tracking state (last cells, visit counters) changes every frame: one culler per thread.
  void cull(const BackfaceView& view, std::span<uint8_t> unit_culled) const override {
    hierarchy_.cull(view.eye, unit_culled);
  }

 private:
  mutable KumarHierarchy hierarchy_;
};

}  // namespace

std::unique_ptr<BackfaceCuller> makeHierarchyCuller(const BackfaceInput& input, const BackfaceOptions& options) {
  return std::make_unique<HierarchyCuller>(input, options);
}

}  // namespace walkvis
