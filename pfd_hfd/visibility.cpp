// Point-sampled area-to-area visibility for the HFD tree (James & Day, "The hidden face
// determination tree", 1998 [JamesDay1998HFD]: "acceptable visual results can be gained with point
// sampling"), with occlusion rays through Embree 3 (Wald et al., "Embree: A Kernel Framework for
// Efficient CPU Ray Tracing", SIGGRAPH 2014 [Embree2014]).
//
// What counts as seen matches the exact reference of walkthrough/raycast.h: only FRONT sides are
// drawn, so a blocker stops a ray only when the ray meets its front side (an intersection filter
// drops back-side hits), and the target counts as seen only from eyes in its front half-space.
//
// Sampling (docs/DESIGN.md, "Sizes and errors": uniform samples miss walls seen through doors):
//  1. uniform: region corners, points along the region's edges and area-stratified interior points,
//     against the target's (inset) corners and area-stratified interior points, paired in a
//     diagonal order so that the first rays already use every eye and every target point;
//  2. refinement by stepping past blocker edges: a blocked ray's nearest blocker (the input
//     polygon it belongs to, so a wall cut into fragments by the BSP is stepped over at once) is
//     passed just beyond each of its nearest edges, either by moving the target point (the ray
//     from the same eye through the point just past the edge, continued to the target) or by
//     moving the eye (the line from the same target point through that point, continued to the
//     height plane). Chains of such steps find rays through door and window openings and around
//     jambs; they start from seeds that favour the region's corners and boundary.
// Everything is deterministic in (options.seed, fragment, region, height).
#include "pfd_hfd/visibility.h"

#include "core/check.h"
#include "core/embree_scene.h"
#include "core/rng.h"
#include "pfd_hfd/hull_distance.h"
#include "pfd_hfd/region_pieces.h"

#include <embree3/rtcore.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>

namespace walkvis {
namespace {

// The ray stops this far (times the scene's extent, measured along the target's normal) in front
// of the target's plane. Embree works in single precision on coordinates relative to the scene's
// centre, whose rounding is 2^-24 ≈ 6e-8 of the extent: 1e-5 is over 100 times that, so neither
// the target nor its coplanar neighbours (other fragments of the same wall) can be hit, while a
// real blocker is missed only when it lies within 1e-5 of the extent of the target's plane (a
// decal on it), which hides at most a sliver.
constexpr double kEndGap = 1e-5;
// Grazing rays end nearer the target (see castClear), but never nearer than this: 16 times the
// single-precision rounding of coordinates.
constexpr double kMinGap = 1e-6;
// Region samples are kept this far (times the extent) inside their piece: a region edge usually
// lies on a wall's plane, and an eye exactly on a wall could see through it in single precision.
// An eye that close to a wall sees nothing a sample this far away does not, up to a sliver.
constexpr double kRegionInset = 1e-5;
// Target samples are pulled towards the centroid by this fraction (at least), and by the end gap
// in absolute terms: a point on the target's edge lies on the edge of its neighbours too (a
// perpendicular wall at a corner), whose single-precision triangles could stop the ray.
constexpr double kTargetShrink = 1e-3;
// Stepping past a blocker edge: the new ray passes this fraction of the eye-to-hit distance beyond
// the edge (at least the end gap): small enough to get through an opening 1/1000 of the view
// wide, large enough not to graze the edge's own polygon in single precision.
constexpr double kStepMargin = 1e-3;
constexpr uint32_t kMaxStepDepth = 6;  // steps chained from one seed ray
// Proof: blockers tried along each centre ray (the nearest may be a small thing in front of the
// wall that hides everything), and halvings of a region or target part.
constexpr uint32_t kProofHits = 3;
constexpr uint32_t kMaxProofDepth = 6;
// Occluder patches: at most this many input polygons joined across shared edges for one sub-cone
// (a corridor's walls, floor and ceiling are a few dozen; beyond that the proof gives up).
constexpr uint32_t kMaxPatch = 48;


// The squared diameter of a point set (largest squared distance between two of its points).
double diameter2(std::span<const glm::dvec2> v) {
  double d = 0.0;
  for (size_t a = 0; a < v.size(); ++a)
    for (size_t b = a + 1; b < v.size(); ++b) d = std::max(d, glm::dot(v[b] - v[a], v[b] - v[a]));
  return d;
}

// Random point of a convex polygon by area (fan triangles), from two uniform numbers.
glm::dvec2 pointInConvex(const Convex2& poly, double u, double w, std::vector<double>& cum) {
  const auto& v = poly.v;
  cum.clear();
  double total = 0.0;
  for (size_t k = 1; k + 1 < v.size(); ++k) {
    total += std::abs(cross2(v[k] - v[0], v[k + 1] - v[0]));
    cum.push_back(total);
  }
  if (!(total > 0.0)) return poly.centroid;
  const double pick = u * total;
  size_t k = std::lower_bound(cum.begin(), cum.end(), pick) - cum.begin();
  if (k >= cum.size()) k = cum.size() - 1;
  const double lo = k == 0 ? 0.0 : cum[k - 1];
  double a = (pick - lo) / std::max(cum[k] - lo, 1e-300);  // reuse the remainder as one coordinate
  a = std::clamp(a, 0.0, 1.0);
  double b = w;
  if (a + b > 1.0) {
    a = 1.0 - a;
    b = 1.0 - b;
  }
  return v[0] + a * (v[k + 1] - v[0]) + b * (v[k + 2] - v[0]);
}

// Convex hull (Andrew's monotone chain), counter-clockwise, collinear points dropped.
std::vector<glm::dvec2> convexHull(std::vector<glm::dvec2> pts) {
  std::sort(pts.begin(), pts.end(), [](const glm::dvec2& a, const glm::dvec2& b) {
    return a.x < b.x || (a.x == b.x && a.y < b.y);
  });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  std::vector<glm::dvec2> hull(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross2(hull[k - 1] - hull[k - 2], pts[i] - hull[k - 2]) <= 0.0) --k;
    hull[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross2(hull[k - 1] - hull[k - 2], pts[i - 1] - hull[k - 2]) <= 0.0) --k;
    hull[k++] = pts[i - 1];
  }
  hull.resize(k - 1);
  return hull;
}

// An orthonormal basis (u, w) of a plane with u × w = n, so counter-clockwise seen from the front
// is counter-clockwise in (u, w).
void planeBasis(const glm::dvec3& n, glm::dvec3& u, glm::dvec3& w) {
  const glm::dvec3 a = std::abs(n.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  u = glm::normalize(glm::cross(a, n));
  w = glm::cross(n, u);
}

// Per outline edge, the edges of other outlines on the same line that overlap it (either
// direction): CSR, partners[first[e], first[e + 1]). "On the line" within `tol`: a T-junction's
// vertices are rounded, and a crack that narrow is below Embree's single precision too.
struct EdgePartners {
  std::vector<uint32_t> first;     // per edge, plus one
  std::vector<uint32_t> partners;  // edge indices
  std::vector<uint32_t> owner;     // per edge, its outline
};

// The edge after e in its outline's ring (outline_first as in Impl, owner as in EdgePartners).
uint32_t nextInRing(const std::vector<uint32_t>& outline_first, const std::vector<uint32_t>& owner, uint32_t e) {
  return e + 1 == outline_first[owner[e] + 1] ? outline_first[owner[e]] : e + 1;
}

EdgePartners collinearPartners(const std::vector<uint32_t>& outline_first, const std::vector<glm::dvec3>& verts,
                               double cell, double tol) {
  EdgePartners ep;
  const uint32_t outlines = static_cast<uint32_t>(outline_first.size()) - 1;
  const size_t edges = verts.size();
  ep.owner.assign(edges, 0);
  for (uint32_t o = 0; o < outlines; ++o)
    for (uint32_t e = outline_first[o]; e < outline_first[o + 1]; ++e) ep.owner[e] = o;
  auto next = [&](uint32_t e) { return nextInRing(outline_first, ep.owner, e); };
  auto tiny = [&](uint32_t e) { return outline_first[ep.owner[e] + 1] - outline_first[ep.owner[e]] < 3; };
  auto cellKey = [&](int64_t x, int64_t y, int64_t z) {
    return mixHash(mixHash(mixHash(0, static_cast<uint64_t>(x)), static_cast<uint64_t>(y)), static_cast<uint64_t>(z));
  };
  auto cellOf = [&](const glm::dvec3& p) { return glm::floor(p / cell); };
  // Each edge is entered in the cells of points at most half a cell apart along it; a partner
  // overlapping it by any length then has a point in one of the 27 cells around one of them.
  auto samples = [&](uint32_t e) {
    const double len = glm::length(verts[next(e)] - verts[e]);
    return static_cast<uint32_t>(std::min(1e6, std::ceil(2.0 * len / cell))) + 1;
  };
  auto sampleCell = [&](uint32_t e, uint32_t k, uint32_t n) {
    return cellOf(verts[e] + (verts[next(e)] - verts[e]) * (static_cast<double>(k) / n));
  };
  std::unordered_map<uint64_t, std::vector<uint32_t>> grid;
  for (uint32_t e = 0; e < edges; ++e) {
    if (tiny(e)) continue;
    const uint32_t n = samples(e);
    uint64_t last = 0;
    for (uint32_t k = 0; k <= n; ++k) {
      const glm::dvec3 c = sampleCell(e, k, n);
      const uint64_t key = cellKey(static_cast<int64_t>(c.x), static_cast<int64_t>(c.y), static_cast<int64_t>(c.z));
      if (k > 0 && key == last) continue;
      last = key;
      auto& list = grid[key];
      if (list.empty() || list.back() != e) list.push_back(e);
    }
  }
  ep.first.assign(edges + 1, 0);
  std::vector<uint32_t> found;
  for (uint32_t e = 0; e < edges; ++e) {
    ep.first[e] = static_cast<uint32_t>(ep.partners.size());
    if (tiny(e)) continue;
    const glm::dvec3 a = verts[e], b = verts[next(e)];
    const double len = glm::length(b - a);
    if (!(len > tol)) continue;
    const glm::dvec3 u = (b - a) / len;
    found.clear();
    const uint32_t n = samples(e);
    for (uint32_t k = 0; k <= n; ++k) {
      const glm::dvec3 c = sampleCell(e, k, n);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const auto it = grid.find(cellKey(static_cast<int64_t>(c.x) + dx, static_cast<int64_t>(c.y) + dy,
                                              static_cast<int64_t>(c.z) + dz));
            if (it != grid.end()) found.insert(found.end(), it->second.begin(), it->second.end());
          }
    }
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    for (uint32_t f : found) {
      if (ep.owner[f] == ep.owner[e]) continue;
      const glm::dvec3 c = verts[f], d = verts[next(f)];
      const double tc = glm::dot(c - a, u), td = glm::dot(d - a, u);
      if (glm::length(c - a - tc * u) > tol || glm::length(d - a - td * u) > tol) continue;
      if (std::min(std::max(tc, td), len) - std::max(std::min(tc, td), 0.0) > tol) ep.partners.push_back(f);
    }
  }
  ep.first[edges] = static_cast<uint32_t>(ep.partners.size());
  return ep;
}

struct Hit {
  uint32_t fragment = 0;
  double t = 0.0;  // along the unnormalised direction (target - eye)
};

// A blocked refinement ray, kept for the steps past its blocker's edges.
struct StepParent {
  glm::dvec3 eye, target, x;  // x: where it met the blocker
  double hit_t = 0.0;
  uint32_t outline = 0;
  glm::dvec3 blocker_normal{0.0};
};

struct Probe {
  static constexpr uint32_t kNoParent = UINT32_MAX;
  glm::dvec3 eye{0.0};  // a seed ray (parent == kNoParent), else worked out from the parent's step
  glm::dvec3 target{0.0};
  uint32_t parent = kNoParent;
  uint32_t edge = 0, variant = 0;  // the parent's outline edge stepped past; 0 moves the target, 1 the eye
  uint32_t depth = 0;  // steps from its seed
};

// A region part against a target part still to be proved hidden (runs of Scratch::pool).
struct ProofItem {
  uint32_t region_first, region_count, target_first, target_count, depth;
};

// Per-thread working memory, reused across queries so that a warm thread allocates nothing.
struct Scratch {
  // The region of the last query and what was made of it (a batch asks many targets from one
  // region): its rings as given, and the pieces, their area, perimeter and grid.
  std::vector<glm::dvec2> region_flat;
  std::vector<uint32_t> region_sizes;
  double region_area = 0.0, perimeter = 0.0;
  PieceGrid grid;
  std::vector<Convex2> pieces;
  std::vector<double> piece_cum;
  std::vector<double> tri_cum;
  std::vector<glm::dvec3> eyes;
  std::vector<glm::dvec3> targets;
  std::vector<glm::dvec2> clip;
  std::vector<glm::dvec2> target2;  // the target in its plane basis, counter-clockwise, inset
  Convex2 target_c;                 // the same, for sampling
  // What the proof must show hidden: target2 in the sampled mode; in the conservative mode the
  // target pulled in by the minimum gap only (see prepareTarget).
  std::vector<glm::dvec2> proof_target;
  // Breadth first: chains are tried shortest first, and chains of one length in the order they
  // were found. Every child is one step longer than the probe it comes from, so a plain FIFO gives
  // exactly that order (a binary heap on (depth, push order) cost a fifth of an HFD build).
  std::vector<Probe> queue;
  std::vector<StepParent> parents;
  std::vector<std::pair<double, uint32_t>> edge_order;
  std::vector<glm::dvec2> pool;  // proof: region and target parts, each a run of vertices
  std::vector<glm::dvec2> poly, poly2;
  std::vector<ProofItem> items;
  // Occluder patch: its outlines, their edges still to look at, and a stamp per outline of the
  // scene (stamp == patch_stamp: in the patch).
  std::vector<uint32_t> patch, patch_edges, outline_stamp;
  uint32_t patch_stamp = 0;
  std::vector<glm::dvec3> hull3;  // the segments' hull: region part and target part, in 3D
  std::vector<glm::dvec3> region3, target3;
  std::vector<double> breaks;
  std::vector<glm::dvec2> spans;  // partner edges in the patch, as (start, end) along an edge
};

// The region's convex pieces, counter-clockwise, zero-area ones dropped, with their total area
// and perimeter and the grid over them, into sc.
void buildPieces(std::span<const std::vector<glm::dvec2>> region, Scratch& sc) {
  sc.pieces.clear();
  double region_area = 0.0, perimeter = 0.0;
  for (const auto& piece : region) {
    if (piece.size() < 3) continue;
    double a2 = 0.0;
    glm::dvec2 c{0.0};
    for (size_t i = 0; i < piece.size(); ++i) {
      const double cr = cross2(piece[i], piece[(i + 1) % piece.size()]);
      a2 += cr;
      c += (piece[i] + piece[(i + 1) % piece.size()]) * cr;
    }
    if (!(std::abs(a2) > 0.0) || !std::isfinite(a2)) continue;
    Convex2 cp;
    cp.v = piece;
    if (a2 < 0.0) std::reverse(cp.v.begin(), cp.v.end());
    cp.area = 0.5 * std::abs(a2);
    cp.centroid = c / (3.0 * a2);
    for (const auto& v : cp.v) cp.radius = std::max(cp.radius, glm::length(v - cp.centroid));
    for (size_t i = 0; i < cp.v.size(); ++i) perimeter += glm::length(cp.v[(i + 1) % cp.v.size()] - cp.v[i]);
    region_area += cp.area;
    sc.pieces.push_back(std::move(cp));
  }
  sc.region_area = region_area;
  sc.perimeter = perimeter;
  sc.grid.build(sc.pieces);
}

Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

}  // namespace

struct VisibilityScene::Impl {
  EmbreeScene embree;
  VisibilityOptions options;
  glm::dvec3 origin{0.0};
  double extent = 1.0;
  std::vector<glm::dvec3> vertices;       // fragment vertices (copy of the BSP's)
  std::vector<Polygon> fragments;
  std::vector<uint32_t> triangle_fragment;
  std::vector<glm::vec3> fragment_normal;  // single precision, for the intersection filter
  // Per fragment, the outline of its input polygon (convex hull of all that polygon's fragments):
  // outline_vertices[outline_first[o], outline_first[o + 1]), counter-clockwise from the front.
  std::vector<uint32_t> fragment_outline;
  std::vector<uint32_t> outline_first;
  std::vector<glm::dvec3> outline_vertices;
  // The same outlines in their own plane's basis (planeBasis(plane.n), origin plane.n * plane.d),
  // and their planes, for the proof.
  std::vector<glm::dvec2> outline_2d;
  std::vector<Plane> outline_plane;
  std::vector<std::array<glm::dvec3, 2>> outline_basis;  // planeBasis(outline_plane[o].n)
  // Per outline edge (index outline_first[o] + k, from vertex k to k + 1), the edges of other
  // outlines along the same line that overlap it: where they run the other way the two outlines
  // are consistently oriented neighbours there (a wall and the next, or the three walls beside
  // one tall one at a T-junction).
  EdgePartners edge_partners;

  // What visibleTarget tests: a convex polygon (counter-clockwise from the front), its plane, the
  // outline it belongs to (never a patch of its own occluders), and the key its samples are
  // seeded with.
  static constexpr uint32_t kNoOutline = UINT32_MAX;
  struct Target {
    std::span<const glm::dvec3> vertices;
    Plane plane;
    uint32_t outline = kNoOutline;
    uint64_t key = 0;
  };
  bool visibleTarget(const Target& shape, std::span<const std::vector<glm::dvec2>> region, double height,
                     VisibilityCounters& counters, glm::dvec2* witness) const;
  class Query;  // one visibleTarget call's steps

  glm::vec3 rel(const glm::dvec3& p) const { return glm::vec3(p - origin); }

  // Occlusion of the segment eye + t (target - eye), t in [0, tfar]. With `hit`, the nearest
  // front-side blocker is reported (rtcIntersect1), otherwise any (rtcOccluded1).
  bool blocked(const glm::dvec3& eye, const glm::dvec3& target, double tfar, Hit* hit, double tnear = 0.0) const {
    const glm::vec3 o = rel(eye);
    const glm::dvec3 d = target - eye;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (!hit) {
      RTCRay ray{};
      ray.org_x = o.x, ray.org_y = o.y, ray.org_z = o.z;
      ray.dir_x = static_cast<float>(d.x), ray.dir_y = static_cast<float>(d.y), ray.dir_z = static_cast<float>(d.z);
      ray.tnear = 0.0f;
      ray.tfar = static_cast<float>(tfar);
      ray.mask = ~0u;
      rtcOccluded1(embree.scene(), &context, &ray);
      return ray.tfar < 0.0f;  // Embree marks an occluded ray with tfar = -inf
    }
    RTCRayHit rh{};
    rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
    rh.ray.dir_x = static_cast<float>(d.x), rh.ray.dir_y = static_cast<float>(d.y),
    rh.ray.dir_z = static_cast<float>(d.z);
    rh.ray.tnear = static_cast<float>(tnear);
    rh.ray.tfar = static_cast<float>(tfar);
    rh.ray.mask = ~0u;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(embree.scene(), &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit->fragment = triangle_fragment[rh.hit.primID];
    hit->t = rh.ray.tfar;
    return true;
  }

  // How far a point x of outline o's plane lies inside the outline: the least distance to the
  // lines of its edges, negative outside.
  double clearance(uint32_t o, const glm::dvec3& x) const {
    const glm::dvec3 rel_x = x - outline_plane[o].n * outline_plane[o].d;
    const glm::dvec2 q{glm::dot(rel_x, outline_basis[o][0]), glm::dot(rel_x, outline_basis[o][1])};
    const uint32_t of = outline_first[o], oc = outline_first[o + 1] - of;
    double least = std::numeric_limits<double>::infinity();
    for (uint32_t k = 0; k < oc; ++k) {
      const glm::dvec2 a = outline_2d[of + k], ab = outline_2d[of + (k + 1) % oc] - a;
      const double len = glm::length(ab);
      if (len > 0.0) least = std::min(least, cross2(ab, q - a) / len);
    }
    return least;
  }

  // The edge after e in its outline's ring.
  uint32_t nextEdge(uint32_t e) const { return nextInRing(outline_first, edge_partners.owner, e); }

  // True when every segment from conv(region3) to conv(target3) meets the front side of an
  // outline of one patch grown from `seed`: outlines joined across shared, oppositely oriented
  // edges (Impl::edge_partners), so that the patch is an oriented surface whose boundary is where
  // its outlines' edges do not cancel in pairs. A segment's signed count of crossings with it
  // (+1 entering a front side, -1 a back side) stays the same while the segment moves, as long as
  // no segment meets the boundary and no end point touches the patch. The segments from R to T
  // fill conv(R ∪ T) and move continuously, so when that hull keeps clear of the boundary and R
  // and T keep clear of the patch, one segment's count is every segment's. A count of at
  // least 1 means a front side is entered: blocked, as the Embree rays are. A corridor's walls
  // hide what lies beyond its bend together though no one of them does (occluder fusion). The
  // patch grows only across boundary edges that come within `margin` of the hull, and gives up at
  // an opening, at the target's own outline, or beyond kMaxPatch outlines.
  bool patchCovers(uint32_t seed, uint32_t target_outline, std::span<const glm::dvec3> region3,
                   std::span<const glm::dvec3> target3, double margin, double end_gap, double min_crack,
                   Scratch& sc) const {
    const size_t outlines = outline_first.size() - 1;
    if (sc.outline_stamp.size() < outlines) sc.outline_stamp.assign(outlines, 0), sc.patch_stamp = 0;
    if (++sc.patch_stamp == 0) {
      std::fill(sc.outline_stamp.begin(), sc.outline_stamp.end(), 0u);
      sc.patch_stamp = 1;
    }
    const uint32_t stamp = sc.patch_stamp;
    sc.hull3.assign(region3.begin(), region3.end());
    sc.hull3.insert(sc.hull3.end(), target3.begin(), target3.end());
    sc.patch.clear();
    sc.patch_edges.clear();
    auto add = [&](uint32_t o) {
      sc.outline_stamp[o] = stamp;
      sc.patch.push_back(o);
      for (uint32_t e = outline_first[o]; e < outline_first[o + 1]; ++e) sc.patch_edges.push_back(e);
    };
    if (seed == target_outline || outline_first[seed + 1] - outline_first[seed] < 3) return false;
    add(seed);
    const EdgePartners& ep = edge_partners;
    while (!sc.patch_edges.empty()) {
      const uint32_t e = sc.patch_edges.back();
      sc.patch_edges.pop_back();
      const glm::dvec3 a = outline_vertices[e], b = outline_vertices[nextEdge(e)];
      const double len = glm::length(b - a);
      if (!(len > 0.0)) continue;
      const glm::dvec3 u = (b - a) / len;
      // The patch's boundary along this edge: where the edge and the partners in the patch do not
      // cancel (one running each way). The partners in the patch as intervals along the edge; the
      // breakpoints at their ends cut it into stretches of one multiplicity each.
      sc.spans.clear();
      for (uint32_t i = ep.first[e]; i < ep.first[e + 1]; ++i) {
        const uint32_t f = ep.partners[i];
        if (sc.outline_stamp[ep.owner[f]] != stamp) continue;
        sc.spans.push_back({glm::dot(outline_vertices[f] - a, u), glm::dot(outline_vertices[nextEdge(f)] - a, u)});
      }
      sc.breaks.clear();
      sc.breaks.push_back(0.0);
      sc.breaks.push_back(len);
      for (const glm::dvec2& sp : sc.spans)
        for (double t : {sp.x, sp.y}) sc.breaks.push_back(std::clamp(t, 0.0, len));
      std::sort(sc.breaks.begin(), sc.breaks.end());
      bool open = false;  // some boundary stretch comes near the hull
      for (size_t k = 0; k + 1 < sc.breaks.size() && !open; ++k) {
        const double t0 = sc.breaks[k], t1 = sc.breaks[k + 1];
        if (!(t1 - t0 > min_crack)) continue;  // a crack below the partners' tolerance
        const double mid = 0.5 * (t0 + t1);
        int net = 1;
        for (const glm::dvec2& sp : sc.spans)
          if (std::min(sp.x, sp.y) <= mid && mid <= std::max(sp.x, sp.y)) net += sp.y < sp.x ? -1 : 1;
        if (net == 0) continue;
        const glm::dvec3 piece[2] = {a + t0 * u, a + t1 * u};
        open = !hullsSeparated(piece, sc.hull3, margin);
      }
      if (!open) continue;  // every boundary stretch here is clear of every segment
      // Join the outlines across it: each partner running the other way, not yet in the patch.
      bool grown = false;
      for (uint32_t i = ep.first[e]; i < ep.first[e + 1]; ++i) {
        const uint32_t f = ep.partners[i], q = ep.owner[f];
        if (sc.outline_stamp[q] == stamp) continue;
        if (!(glm::dot(outline_vertices[nextEdge(f)] - outline_vertices[f], u) < 0.0)) continue;
        if (q == target_outline || sc.patch.size() >= kMaxPatch) return false;
        add(q);
        grown = true;
      }
      if (!grown) return false;  // an opening (or a same-way overlap) next to the segments
      sc.patch_edges.push_back(e);  // look again with the new partners
    }
    // The ends: eyes off the patch by the margin, target points by the end gap (the rays stop that
    // far short of the target's plane; a crossing nearer would not be cast).
    for (uint32_t o : sc.patch) {
      const std::span<const glm::dvec3> ov(outline_vertices.data() + outline_first[o], outline_first[o + 1] - outline_first[o]);
      if (!hullsSeparated(ov, region3, margin) || !hullsSeparated(ov, target3, end_gap)) return false;
    }
    // One segment's count: centroid to centroid, or when that one passes too near an edge of the
    // patch to count in double precision (a symmetric scene puts it on a shared edge), a segment
    // between points pulled towards vertices of the two parts.
    glm::dvec3 ce{0.0}, cp{0.0};
    for (const auto& r : region3) ce += r;
    for (const auto& t : target3) cp += t;
    ce /= static_cast<double>(region3.size());
    cp /= static_cast<double>(target3.size());
    for (uint32_t attempt = 0; attempt < 4; ++attempt) {
      const glm::dvec3 e = attempt == 0 ? ce : ce + 0.37 * (region3[attempt % region3.size()] - ce);
      const glm::dvec3 p = attempt == 0 ? cp : cp + 0.29 * (target3[(attempt * 2 + 1) % target3.size()] - cp);
      const std::optional<int> count = signedCrossings(e, p, margin, sc.patch);
      if (count) return *count >= 1;
    }
    return false;
  }

  // The signed count of the crossings of segment e-p with the outlines `patch` (+1 entering a
  // front side), or nullopt when it passes within `margin` of an outline's edge.
  std::optional<int> signedCrossings(const glm::dvec3& e, const glm::dvec3& p, double margin,
                                     std::span<const uint32_t> patch) const {
    int count = 0;
    for (uint32_t o : patch) {
      const Plane& op = outline_plane[o];
      const double de = glm::dot(op.n, e) - op.d, dp = glm::dot(op.n, p) - op.d;
      // An end on the plane lies off the outline (the hull tests above): no crossing there.
      if (!((de > 0.0 && dp < 0.0) || (de < 0.0 && dp > 0.0))) continue;
      const double c = clearance(o, e + (de / (de - dp)) * (p - e));
      if (c < -margin) continue;
      if (!(c > margin)) return std::nullopt;  // too near an edge to count in double precision
      count += de > 0.0 ? 1 : -1;
    }
    return count;
  }

  // Occlusion of up to kPacket segments at once (one Embree packet: the rays of one test run from
  // one region to one fragment, coherent enough for packet traversal). Returns the first segment
  // k < n that is unblocked, or -1.
  static constexpr int kPacket = 16;
  int firstClear16(const glm::dvec3* eyes, const glm::dvec3* targets, const double* tfar, int n) const {
    RTCRay16 ray;
    alignas(64) int valid[kPacket];
    for (int k = 0; k < kPacket; ++k) {
      valid[k] = k < n ? -1 : 0;
      const int i = k < n ? k : 0;
      const glm::vec3 o = rel(eyes[i]);
      const glm::dvec3 d = targets[i] - eyes[i];
      ray.org_x[k] = o.x, ray.org_y[k] = o.y, ray.org_z[k] = o.z;
      ray.dir_x[k] = static_cast<float>(d.x), ray.dir_y[k] = static_cast<float>(d.y),
      ray.dir_z[k] = static_cast<float>(d.z);
      ray.tnear[k] = 0.0f;
      ray.tfar[k] = static_cast<float>(tfar[i]);
      ray.time[k] = 0.0f;
      ray.mask[k] = ~0u;
      ray.id[k] = static_cast<unsigned>(k);
      ray.flags[k] = 0;
    }
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcOccluded16(valid, embree.scene(), &context, &ray);
    for (int k = 0; k < n; ++k)
      if (!(ray.tfar[k] < 0.0f)) return k;
    return -1;
  }
};

namespace {

void filterFrontSide(const RTCFilterFunctionNArguments* args) {
  const auto* normals = static_cast<const glm::vec3*>(args->geometryUserPtr);
  for (unsigned k = 0; k < args->N; ++k) {
    if (args->valid[k] != -1) continue;
    const unsigned prim = RTCHitN_primID(args->hit, args->N, k);
    const glm::vec3& n = normals[prim];
    const float dn = n.x * RTCRayN_dir_x(args->ray, args->N, k) + n.y * RTCRayN_dir_y(args->ray, args->N, k) +
                     n.z * RTCRayN_dir_z(args->ray, args->N, k);
    // A ray leaving a polygon's front or running in its plane is not stopped: back faces are not
    // drawn (raycast.h), and a polygon seen edge-on covers nothing.
    if (!(dn < 0.0f)) args->valid[k] = 0;
  }
}

}  // namespace

VisibilityScene::VisibilityScene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
VisibilityScene::VisibilityScene(VisibilityScene&&) noexcept = default;
VisibilityScene& VisibilityScene::operator=(VisibilityScene&&) noexcept = default;
VisibilityScene::~VisibilityScene() = default;

const VisibilityOptions& VisibilityScene::options() const { return impl_->options; }

std::string VisibilityScene::deviceInfo() const {
  auto prop = [&](RTCDeviceProperty p) { return rtcGetDeviceProperty(impl_->embree.device(), p); };
  const ssize_t v = prop(RTC_DEVICE_PROPERTY_VERSION);
  return "Embree " + std::to_string(v / 10000) + "." + std::to_string(v / 100 % 100) + "." + std::to_string(v % 100) +
         ": native packets 4 " + (prop(RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED) ? "yes" : "no") + ", 8 " +
         (prop(RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) ? "yes" : "no") + ", 16 " +
         (prop(RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) ? "yes" : "no") + "; streams " +
         (prop(RTC_DEVICE_PROPERTY_RAY_STREAM_SUPPORTED) ? "yes" : "no");
}

bool VisibilityScene::occluded(const glm::dvec3& from, const glm::dvec3& to) const {
  return impl_->blocked(from, to, 1.0, nullptr);
}

VisibilityScene VisibilityScene::build(const BspTree& bsp, const VisibilityOptions& options) {
  auto impl = std::make_unique<Impl>();
  Impl& s = *impl;
  s.options = options;
  s.vertices = bsp.vertices;
  s.fragments = bsp.fragments;
  if (!s.vertices.empty()) {
    glm::dvec3 lo = s.vertices[0], hi = s.vertices[0];
    for (const auto& v : s.vertices) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    s.origin = 0.5 * (lo + hi);
    s.extent = std::max(glm::length(hi - lo), 1e-300);
    if (!std::isfinite(s.extent)) throw Error("visibility: scene bounds are not finite");
  }

  // Outlines: the convex hull of each input polygon's fragments, in that polygon's plane.
  const size_t nf = s.fragments.size();
  std::vector<glm::dvec3> exact;  // per outline vertex, the scene vertex it stands for
  s.fragment_outline.assign(nf, 0);
  {
    std::vector<uint32_t> order(nf);
    for (uint32_t f = 0; f < nf; ++f) order[f] = f;
    auto key = [&](uint32_t f) { return f < bsp.fragment_polygon.size() ? bsp.fragment_polygon[f] : f; };
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    std::vector<glm::dvec2> pts;
    std::vector<glm::dvec3> pts3;
    s.outline_first.push_back(0);
    for (size_t i = 0; i < nf;) {
      size_t j = i;
      while (j < nf && key(order[j]) == key(order[i])) ++j;
      const Plane& pl = s.fragments[order[i]].plane;
      glm::dvec3 u, w;
      planeBasis(pl.n, u, w);
      const glm::dvec3 base = pl.n * pl.d;
      pts.clear();
      pts3.clear();
      for (size_t k = i; k < j; ++k)
        for (const auto& v : bsp.fragmentVertices(order[k])) {
          pts.push_back({glm::dot(v - base, u), glm::dot(v - base, w)});
          pts3.push_back(v);
        }
      const std::vector<glm::dvec2> hull = convexHull(pts);
      const uint32_t o = static_cast<uint32_t>(s.outline_first.size() - 1);
      for (const auto& h : hull) {
        s.outline_vertices.push_back(base + h.x * u + h.y * w);
        // The scene vertex the hull point was projected from (the hull keeps input points).
        const size_t src = static_cast<size_t>(std::find(pts.begin(), pts.end(), h) - pts.begin());
        exact.push_back(src < pts3.size() ? pts3[src] : s.outline_vertices.back());
      }
      s.outline_2d.insert(s.outline_2d.end(), hull.begin(), hull.end());
      s.outline_plane.push_back(pl);
      s.outline_basis.push_back({u, w});
      s.outline_first.push_back(static_cast<uint32_t>(s.outline_vertices.size()));
      for (size_t k = i; k < j; ++k) s.fragment_outline[order[k]] = o;
      i = j;
    }
  }

  // Cells of 1/256 of the extent: a few per wall on a building, tens of edges per cell at most.
  s.edge_partners = collinearPartners(s.outline_first, exact, s.extent / 256.0, kMinGap * s.extent);

  std::vector<uint32_t> indices;
  for (uint32_t f = 0; f < nf; ++f) {
    const Polygon& p = s.fragments[f];
    if (p.vertex_count < 3) continue;
    for (uint32_t v = 1; v + 1 < p.vertex_count; ++v) {
      indices.insert(indices.end(), {p.first_vertex, p.first_vertex + v, p.first_vertex + v + 1});
      s.triangle_fragment.push_back(f);
      s.fragment_normal.push_back(glm::vec3(p.plane.n));
    }
  }
  // The filter lets a ray pass the back of a fragment (front sides block, as a wall's front does).
  s.embree = EmbreeScene({.vertices = s.vertices,
                          .origin = s.origin,
                          .indices = indices,
                          .intersect_filter = filterFrontSide,
                          .occluded_filter = filterFrontSide,
                          .user_data = s.fragment_normal.data()},
                         "visibility");
  return VisibilityScene(std::move(impl));
}

bool VisibilityScene::visibleFromRegion(uint32_t fragment, std::span<const std::vector<glm::dvec2>> region,
                                        double height, VisibilityCounters& counters, glm::dvec2* witness) const {
  const Impl& s = *impl_;
  WALKVIS_DCHECK(!region.empty());
  if (fragment >= s.fragments.size()) {
    ++counters.tests;
    return false;
  }
  const Polygon& p = s.fragments[fragment];
  const Impl::Target target{std::span<const glm::dvec3>(s.vertices).subspan(p.first_vertex, p.vertex_count), p.plane,
                            s.fragment_outline[fragment], fragment};
  return s.visibleTarget(target, region, height, counters, witness);
}

bool VisibilityScene::boxVisibleFromRegion(const glm::dvec3& lo, const glm::dvec3& hi,
                                           std::span<const std::vector<glm::dvec2>> region, double height,
                                           VisibilityCounters& counters) const {
  const Impl& s = *impl_;
  if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) return true;  // not a box (NaN): nothing is claimed
  // An eye inside the box sees the object from within, where no face stands between: such a
  // region is never said to miss the box (its pieces' bounds meeting the box's footprint).
  if (height >= lo.y && height <= hi.y) {
    for (const auto& piece : region) {
      if (piece.empty()) continue;
      glm::dvec2 plo = piece[0], phi = piece[0];
      for (const glm::dvec2& v : piece) {
        plo = glm::min(plo, v);
        phi = glm::max(phi, v);
      }
      if (plo.x <= hi.x && phi.x >= lo.x && plo.y <= hi.z && phi.y >= lo.z) return true;
    }
  }
  uint64_t key = 0x6a09e667f3bcc908ull;
  for (const double c : {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z}) {
    uint64_t bits;
    std::memcpy(&bits, &c, 8);
    key = mixHash(key, bits);
  }
  // The six faces, each counter-clockwise seen from outside (its normal outward). A face of no
  // area (a flat object's box) is left out: the two faces it lies between stand for the object.
  const glm::dvec3 c[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                           {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  struct Face {
    int v[4];
    glm::dvec3 n;
    double d;
    bool flat;
  };
  const Face faces[6] = {
      {{0, 4, 7, 3}, {-1, 0, 0}, -lo.x, lo.y == hi.y || lo.z == hi.z},
      {{1, 2, 6, 5}, {1, 0, 0}, hi.x, lo.y == hi.y || lo.z == hi.z},
      {{0, 1, 5, 4}, {0, -1, 0}, -lo.y, lo.x == hi.x || lo.z == hi.z},
      {{3, 7, 6, 2}, {0, 1, 0}, hi.y, lo.x == hi.x || lo.z == hi.z},
      {{0, 3, 2, 1}, {0, 0, -1}, -lo.z, lo.x == hi.x || lo.y == hi.y},
      {{4, 5, 6, 7}, {0, 0, 1}, hi.z, lo.x == hi.x || lo.y == hi.y},
  };
  for (int f = 0; f < 6; ++f) {
    if (faces[f].flat) continue;
    const glm::dvec3 v[4] = {c[faces[f].v[0]], c[faces[f].v[1]], c[faces[f].v[2]], c[faces[f].v[3]]};
    // No blocker has outline kNoOutline, so the proof may use any patch.
    const Impl::Target target{std::span<const glm::dvec3>(v, 4), Plane{faces[f].n, faces[f].d}, Impl::kNoOutline,
                              mixHash(key, static_cast<uint64_t>(f))};
    if (s.visibleTarget(target, region, height, counters, nullptr)) return true;
  }
  return false;
}

// One test of a target from a region (Impl::visibleTarget) as named steps over its shared state:
// the samples' seed, the region's pieces and the target's plane; then a first packet of uniform
// rays, the proof, the rest of the uniform rays, and the refinement past blockers' edges. The
// steps run in that order and each draws from the one random stream in the order written, so the
// answer is a function of the scene, the options, the target's key, the region and the height.
class VisibilityScene::Impl::Query {
 public:
  Query(const Impl& scene, const Target& shape, std::span<const std::vector<glm::dvec2>> region, double height,
        VisibilityCounters& counters)
      : s_(scene),
        opt_(scene.options),
        shape_(shape),
        region_(region),
        height_(height),
        counters_(counters),
        sc_(scratch()),
        region_inset_(kRegionInset * scene.extent),
        end_gap_(kEndGap * scene.extent),
        min_gap_(kMinGap * scene.extent) {}

  bool run(glm::dvec2* witness);

 private:
  // Set-up.
  uint64_t seed() const;
  void preparePieces();
  void prepareTarget();
  // Geometry of one ray.
  glm::dvec3 eyeAt(const glm::dvec2& p) const { return glm::dvec3(p.x, height_, p.y); }
  glm::dvec3 target3(const glm::dvec2& q) const { return tbase_ + q.x * tu_ + q.y * tw_; }
  double eyeSide(const glm::dvec3& e) const { return glm::dot(shape_.plane.n, e) - shape_.plane.d; }
  double rayEnd(const glm::dvec3& e, const glm::dvec3& p) const;
  int castClear(const glm::dvec3& e, const glm::dvec3& p, Hit* hit, double tnear = 0.0);
  // 0. The proof.
  bool covers(uint32_t o, std::span<const glm::dvec2> rp, std::span<const glm::dvec2> tq) const;
  bool proofItems(uint32_t max_items);
  glm::dvec2 centroidOf(uint32_t first, uint32_t count) const;
  bool halve(uint32_t first, uint32_t count, uint32_t out[4]);
  int proveHidden();
  // 1. Uniform samples.
  void sampleEyes();
  void sampleTargets();
  bool uniformPackets(uint64_t packets);
  // 2. Refinement.
  bool stepRay(const StepParent& pa, uint32_t k, uint32_t variant, glm::dvec3& e_out, glm::dvec3& p_out) const;
  bool refine(glm::dvec2* witness);
  bool visibleWith(glm::dvec2* witness, const glm::dvec3& eye) {
    ++counters_.visible;
    if (witness) *witness = {eye.x, eye.z};
    return true;
  }

  const Impl& s_;
  const VisibilityOptions& opt_;
  // Only a proof may reject: the conservative mode, or a region too large for sampled verdicts.
  bool strict_ = false;
  const Target& shape_;
  std::span<const std::vector<glm::dvec2>> region_;
  const double height_;
  VisibilityCounters& counters_;
  Scratch& sc_;
  const double region_inset_, end_gap_, min_gap_;
  uint64_t rng_ = 0;
  // The target's plane basis: tbase_ + q.x tu_ + q.y tw_ for a point q of sc_.target2.
  glm::dvec3 tu_{0.0}, tw_{0.0}, tbase_{0.0};
  glm::dvec2 tc_{0.0};        // the target's centroid in that basis
  glm::dvec3 clear_eye_{0.0};  // the eye of the unblocked ray that answers "visible" (the witness)
  // The uniform pairs (eyes × targets) and the next one to cast.
  uint32_t ne_ = 0, nt_ = 0;
  uint64_t pairs_ = 0, next_pair_ = 0;
};

bool VisibilityScene::Impl::visibleTarget(const Target& shape, std::span<const std::vector<glm::dvec2>> region,
                                          double height, VisibilityCounters& counters, glm::dvec2* witness) const {
  ++counters.tests;
  if (shape.vertices.size() < 3) return false;
  return Query(*this, shape, region, height, counters).run(witness);
}

bool VisibilityScene::Impl::Query::run(glm::dvec2* witness) {
  rng_ = seed();
  preparePieces();
  if (sc_.pieces.empty()) return false;
  strict_ = opt_.conservative || sc_.region_area > opt_.sampled_max_area;
  prepareTarget();
  if (sc_.target2.size() < 3) return false;  // collapsed to a segment: seen edge-on at most
  sampleEyes();
  sampleTargets();
  if (uniformPackets(1)) return visibleWith(witness, clear_eye_);
  if (opt_.proof_rays > 0 || strict_) {
    const uint64_t rays_before = counters_.rays;
    const int proof = proveHidden();
    counters_.proof_rays += counters_.rays - rays_before;
    if (proof == 2) return visibleWith(witness, clear_eye_);
    if (proof == 1) {
      ++counters_.proved_hidden;
      return false;
    }
  }
  if (strict_) {
    // Not proved hidden: kept, whatever further sampling would say.
    ++counters_.visible;
    ++counters_.kept_unproven;
    if (witness) *witness = glm::dvec2(std::numeric_limits<double>::quiet_NaN());
    return true;
  }
  if (uniformPackets(std::numeric_limits<uint64_t>::max())) return visibleWith(witness, clear_eye_);
  return refine(witness);
}

// The options' seed, the target's key, the region's vertices and the height.
uint64_t VisibilityScene::Impl::Query::seed() const {
  uint64_t h = mixHash(opt_.seed, shape_.key);
  uint64_t bits;
  std::memcpy(&bits, &height_, 8);
  h = mixHash(h, bits);
  for (const auto& piece : region_)
    for (const auto& v : piece) {
      std::memcpy(&bits, &v.x, 8);
      h = mixHash(h, bits);
      std::memcpy(&bits, &v.y, 8);
      h = mixHash(h, bits);
    }
  return h;
}

// Region pieces, counter-clockwise, zero-area ones dropped: made again only when the region
// differs from the last query's on this thread.
void VisibilityScene::Impl::Query::preparePieces() {
  bool same_region = sc_.region_sizes.size() == region_.size();
  for (size_t i = 0, at = 0; same_region && i < region_.size(); at += region_[i].size(), ++i)
    same_region = sc_.region_sizes[i] == region_[i].size() && at + region_[i].size() <= sc_.region_flat.size() &&
                  std::equal(region_[i].begin(), region_[i].end(),
                             sc_.region_flat.begin() + static_cast<std::ptrdiff_t>(at));
  if (same_region) return;
  sc_.region_sizes.clear();
  sc_.region_flat.clear();
  for (const auto& piece : region_) {
    sc_.region_sizes.push_back(static_cast<uint32_t>(piece.size()));
    sc_.region_flat.insert(sc_.region_flat.end(), piece.begin(), piece.end());
  }
  buildPieces(region_, sc_);
}

// The target in its plane basis, pulled in from its edges.
void VisibilityScene::Impl::Query::prepareTarget() {
  const Plane& tp = shape_.plane;
  planeBasis(tp.n, tu_, tw_);
  tbase_ = tp.n * tp.d;
  sc_.target2.clear();
  tc_ = glm::dvec2(0.0);
  // Corners nearer than the minimum gap to the previous one are dropped. BSP splits through a
  // vertex leave such near-duplicates (freedoom1 E1M1: a floor triangle of five corners, two
  // 1e-13 apart from their neighbours), and the direction of an edge that short is rounding
  // noise: taken for a side of the target, its line cut through the middle, so rayEnd found
  // every sample on its outside, cast no ray, and the floor beside the eye was never seen (15.7%
  // of one eye's pixels). The target changes by less than the gap, which the single-precision
  // scene cannot resolve and the conservative proof target is pulled in by.
  for (const glm::dvec3& corner : shape_.vertices) {
    const glm::dvec3 v = corner - tbase_;
    const glm::dvec2 q{glm::dot(v, tu_), glm::dot(v, tw_)};
    if (!sc_.target2.empty() && glm::length(q - sc_.target2.back()) <= min_gap_) continue;
    sc_.target2.push_back(q);
  }
  while (sc_.target2.size() > 1 && glm::length(sc_.target2.back() - sc_.target2.front()) <= min_gap_)
    sc_.target2.pop_back();
  for (const auto& q : sc_.target2) tc_ += q;
  tc_ /= static_cast<double>(sc_.target2.size());
  // A conservative verdict must hold for the whole fragment: the band that the samples' shrink
  // leaves along its edges is neither sampled nor otherwise proved, and an edge seen grazing past
  // a blocker's top lies in it (freedoom2 MAP01, level 5: 10 pixels of a fragment the proof of
  // the shrunk target had hidden). The minimum gap keeps the corners off the planes of the walls
  // that meet the target there.
  if (strict_) {
    sc_.proof_target = sc_.target2;
    for (auto& v : sc_.proof_target) v = pullTowards(v, tc_, 0.0, min_gap_);
  }
  for (auto& v : sc_.target2) v = pullTowards(v, tc_, kTargetShrink, end_gap_);
  sc_.target_c.v = sc_.target2;
  sc_.target_c.centroid = tc_;
}

// Where the ray from e to p ends (a parameter along p - e), or -1 when it is not cast. Only eyes
// in the target's front half-space, at least 2 end gaps from its plane, can see it (nearer ones
// see it edge-on, and the ray would end before it starts).
double VisibilityScene::Impl::Query::rayEnd(const glm::dvec3& e, const glm::dvec3& p) const {
  const double side = eyeSide(e);
  if (!(side > min_gap_)) return -1.0;  // not a ray: the front side is not seen (or only edge-on)
  // The ray's last stretch, within `gap` of the target's plane, is not cast. Its shadow on the
  // plane runs from p towards the eye's foot for gap * (in-plane length / side); it must stay
  // inside the target, or a blocker standing on the target's edge (a wall meeting it at a
  // corner) could be skipped by a grazing ray. So the gap shrinks for grazing rays, down to
  // min_gap; below that the target is seen too nearly edge-on to cast a ray to p.
  const glm::dvec3 to_eye = e - p;
  const glm::dvec2 w2{glm::dot(to_eye, tu_), glm::dot(to_eye, tw_)};
  const double in_plane = glm::length(w2);
  double gap = std::min(end_gap_, 0.5 * side);
  if (in_plane > 0.0) {
    const glm::dvec3 pq = p - tbase_;
    const glm::dvec2 q{glm::dot(pq, tu_), glm::dot(pq, tw_)};
    const glm::dvec2 u2 = w2 / in_plane;
    double exit = std::numeric_limits<double>::infinity();
    const size_t n = sc_.target2.size();
    for (size_t i = 0; i < n; ++i) {
      const glm::dvec2 a = sc_.target2[i], ab = sc_.target2[(i + 1) % n] - a;
      const double rate = cross2(ab, u2);
      if (rate < 0.0) exit = std::min(exit, std::max(0.0, cross2(ab, q - a)) / -rate);
    }
    gap = std::min(gap, 0.5 * exit * side / in_plane);
  }
  if (!(gap >= min_gap_)) return -1.0;
  return 1.0 - gap / side;
}

// Casts one ray; 1 when unblocked, 0 blocked, -1 not cast. `tnear` skips blockers met before it.
int VisibilityScene::Impl::Query::castClear(const glm::dvec3& e, const glm::dvec3& p, Hit* hit, double tnear) {
  const double tfar = rayEnd(e, p);
  if (!(tfar > tnear)) return -1;
  ++counters_.rays;
  return s_.blocked(e, p, tfar, hit, tnear) ? 0 : 1;
}

// ---- 0. Proof by one occluder (a blocker, or a patch of them) per sub-cone (exact, used after
// the first packet) ----
// The segments from a convex region piece R (at the height) to a convex part T of the inset
// target fill conv(R ∪ T); where R lies strictly in front of a blocker's plane and T strictly
// behind, they cross that plane inside conv of the crossings of the vertex-to-vertex segments.
// So when those crossings all lie inside the blocker's outline (by a margin), every sampled ray
// would be blocked by its front side: the fragment is hidden from R with no further rays. The
// candidate blockers are those met by a ray from R's centroid to T's centroid, alone or grown
// into a patch (Impl::patchCovers); where none covers, the larger of R and T is halved and each
// half proved alone, within a ray budget.
bool VisibilityScene::Impl::Query::covers(uint32_t o, std::span<const glm::dvec2> rp,
                                          std::span<const glm::dvec2> tq) const {
  const Plane& op = s_.outline_plane[o];
  if (s_.outline_first[o + 1] - s_.outline_first[o] < 3) return false;
  // The margin: the minimum gap, 16 times the single-precision rounding of Embree's
  // coordinates, so that a crossing proved inside is inside the float triangles too (and below
  // the region's shrink, so that a room's own wall can cover eyes near it).
  const double margin = min_gap_;
  for (const auto& r : rp)
    if (!(glm::dot(op.n, eyeAt(r)) - op.d > margin)) return false;
  for (const auto& t : tq)
    if (!(glm::dot(op.n, target3(t)) - op.d < -margin)) return false;
  for (const auto& r : rp) {
    const glm::dvec3 r3 = eyeAt(r);
    const double dr = glm::dot(op.n, r3) - op.d;
    for (const auto& t : tq) {
      const glm::dvec3 t3 = target3(t);
      const double dt = glm::dot(op.n, t3) - op.d;
      if (!(s_.clearance(o, r3 + (dr / (dr - dt)) * (t3 - r3)) >= margin)) return false;
    }
  }
  return true;
}

// The proof's first items: each region piece's part in front of the target, shrunk, against
// the whole inset target. False when the proof cannot finish (more items than rays, or a piece
// too thin to shrink).
bool VisibilityScene::Impl::Query::proofItems(uint32_t max_items) {
  sc_.pool.clear();
  sc_.items.clear();
  const std::vector<glm::dvec2>& pt = strict_ ? sc_.proof_target : sc_.target2;
  const uint32_t t_first = 0, t_count = static_cast<uint32_t>(pt.size());
  sc_.pool.insert(sc_.pool.end(), pt.begin(), pt.end());
  // Only the part of each piece in front of the target (by the minimum gap) casts rays.
  const Plane& tp = shape_.plane;
  const glm::dvec2 g{tp.n.x, tp.n.z};
  const double c0 = tp.n.y * height_ - tp.d - min_gap_;
  for (const auto& piece : sc_.pieces) {
    // Each item costs at least one ray of the budget, so with more items than rays the proof
    // cannot finish: stop before shrinking the rest (a region of a whole level has thousands of
    // pieces, and shrinking them was most of a test's time there).
    if (sc_.items.size() > max_items) return false;
    if (circleBehind(piece, g, c0) || !clipHalfPlane(piece.v, g, c0, sc_.clip)) continue;
    // Shrunk by four times the eye margin of the covers (a patch's separating plane keeps the
    // margin on both sides, so twice it from the eyes): region edges usually lie on walls, and an
    // eye on a wall's plane (or at a room's corner) crosses it nowhere inside its outline. No
    // more than that: HFD regions can be a few samples' insets wide, and eyes of the band given
    // up here see what the proof would hide (a band of half the inset, as this once was, made
    // freedoom2 MAP01's pixel error 30 times larger with the proof run before any ray). A piece
    // too thin to shrink is not proved at all.
    sc_.poly = sc_.clip;
    for (size_t k = 0; k < sc_.poly.size(); ++k) {
      const glm::dvec2 a = sc_.poly[k], ab = sc_.poly[(k + 1) % sc_.poly.size()] - a;
      const double len = glm::length(ab);
      // The direction of an edge shorter than the minimum gap is rounding noise (see
      // prepareTarget): shrinking along it could cut the piece anywhere. Left unshrunk, the piece
      // only stays larger there, by less than the gap.
      if (!(len > min_gap_)) continue;
      const glm::dvec2 inward = glm::dvec2(-ab.y, ab.x) / len;
      if (!clipHalfPlane(sc_.clip, inward, -glm::dot(inward, a) - 4.0 * min_gap_, sc_.poly2)) return false;
      sc_.clip.swap(sc_.poly2);
    }
    const uint32_t first = static_cast<uint32_t>(sc_.pool.size());
    sc_.pool.insert(sc_.pool.end(), sc_.clip.begin(), sc_.clip.end());
    sc_.items.push_back({first, static_cast<uint32_t>(sc_.clip.size()), t_first, t_count, 0});
  }
  return true;
}

glm::dvec2 VisibilityScene::Impl::Query::centroidOf(uint32_t first, uint32_t count) const {
  glm::dvec2 c{0.0};
  for (uint32_t k = 0; k < count; ++k) c += sc_.pool[first + k];
  return c / static_cast<double>(count);
}

// Halves the polygon pool[first, +count) across its longest vertex-to-vertex direction; the
// halves are appended to the pool. False when it cannot be split.
bool VisibilityScene::Impl::Query::halve(uint32_t first, uint32_t count, uint32_t out[4]) {
  glm::dvec2 axis{0.0};
  double best = 0.0;
  for (uint32_t a = 0; a < count; ++a)
    for (uint32_t b = a + 1; b < count; ++b) {
      const glm::dvec2 d = sc_.pool[first + b] - sc_.pool[first + a];
      if (glm::dot(d, d) > best) best = glm::dot(d, d), axis = d;
    }
  if (!(best > 0.0)) return false;
  const glm::dvec2 c = centroidOf(first, count);
  sc_.poly.assign(sc_.pool.begin() + first, sc_.pool.begin() + first + count);
  for (int side = 0; side < 2; ++side) {
    const glm::dvec2 gs = side == 0 ? axis : -axis;
    if (!clipHalfPlane(sc_.poly, gs, -glm::dot(gs, c), sc_.clip)) return false;
    out[2 * side] = static_cast<uint32_t>(sc_.pool.size());
    out[2 * side + 1] = static_cast<uint32_t>(sc_.clip.size());
    sc_.pool.insert(sc_.pool.end(), sc_.clip.begin(), sc_.clip.end());
  }
  return true;
}

// 1 proved hidden, 2 a ray was unblocked (visible, clear_eye_ its eye), 0 neither.
int VisibilityScene::Impl::Query::proveHidden() {
  const uint32_t max_items =
      strict_ ? std::max(opt_.proof_rays, opt_.conservative_proof_rays) : opt_.proof_rays;
  if (!proofItems(max_items)) return 0;
  uint32_t budget = max_items;
  while (!sc_.items.empty()) {
    const ProofItem it = sc_.items.back();
    sc_.items.pop_back();
    const std::span<const glm::dvec2> rp(sc_.pool.data() + it.region_first, it.region_count);
    const std::span<const glm::dvec2> tq(sc_.pool.data() + it.target_first, it.target_count);
    const glm::dvec3 e = eyeAt(centroidOf(it.region_first, it.region_count));
    const glm::dvec3 p = target3(centroidOf(it.target_first, it.target_count));
    bool covered = false;
    double tnear = 0.0;
    uint32_t last_outline = UINT32_MAX;
    bool parts3 = false;
    for (uint32_t hits = 0; hits < kProofHits && budget > 0 && !covered; ++hits) {
      Hit hit;
      const int r = castClear(e, p, &hit, tnear);
      if (r < 0) return 0;
      --budget;
      if (r == 1 && hits == 0) clear_eye_ = e;
      if (r == 1) return hits == 0 ? 2 : 0;  // past the first blocker: not a sampled ray
      const uint32_t o = s_.fragment_outline[hit.fragment];
      // The next blocker along the same ray: a relative step past this hit, 1e-6 of the ray,
      // far above float rounding of t and far below any wall's thickness along it.
      tnear = hit.t + 1e-6;
      if (o == last_outline) continue;
      last_outline = o;
      covered = covers(o, rp, tq);
      if (!covered && opt_.fuse_occluders) {
        if (!parts3) {  // the item's parts in 3D, once for all the blockers tried
          sc_.region3.clear();
          sc_.target3.clear();
          for (const auto& rv : rp) sc_.region3.push_back(eyeAt(rv));
          for (const auto& t : tq) sc_.target3.push_back(target3(t));
          parts3 = true;
        }
        covered = s_.patchCovers(o, shape_.outline, sc_.region3, sc_.target3, min_gap_, end_gap_, min_gap_, sc_);
        if (covered) ++counters_.patch_covers;
      }
    }
    if (covered) continue;
    if (it.depth >= kMaxProofDepth || budget == 0) return 0;
    // Halve whichever of R and T is larger, in scene units.
    const bool split_region = diameter2(rp) >= diameter2(tq);
    uint32_t halves[4];
    if (!halve(split_region ? it.region_first : it.target_first, split_region ? it.region_count : it.target_count,
               halves))
      return 0;
    for (int k = 1; k >= 0; --k) {
      ProofItem child = it;
      child.depth = it.depth + 1;
      if (split_region) child.region_first = halves[2 * k], child.region_count = halves[2 * k + 1];
      else child.target_first = halves[2 * k], child.target_count = halves[2 * k + 1];
      sc_.items.push_back(child);
    }
  }
  return 1;
}

// ---- 1. Uniform samples ----
// Eyes: a quarter of the samples at corners (all corners when fewer), a quarter along the edges,
// a quarter in front of the target (near_samples), the rest inside by area.
void VisibilityScene::Impl::Query::sampleEyes() {
  const uint32_t R = std::max<uint32_t>(1, opt_.region_samples);
  sc_.eyes.clear();
  size_t corners = 0;
  for (const auto& p : sc_.pieces) corners += p.v.size();
  const uint32_t n_corner = static_cast<uint32_t>(std::min<size_t>(corners, std::max<uint32_t>(1, R / 4)));
  const uint32_t n_edge = std::min<uint32_t>(R - std::min(R, n_corner), std::max<uint32_t>(1, R / 4));
  const uint32_t n_near = opt_.near_samples ? std::min<uint32_t>(R - std::min(R, n_corner + n_edge), R / 4) : 0;
  const uint32_t n_area = R - std::min(R, n_corner + n_edge + n_near);
  const double stride = static_cast<double>(corners) / n_corner;
  const double offset = uniform01(rng_);
  for (uint32_t k = 0; k < n_corner; ++k) {
    size_t idx = static_cast<size_t>((k + offset) * stride) % corners;
    for (const auto& p : sc_.pieces) {
      if (idx < p.v.size()) {
        sc_.eyes.push_back(eyeAt(pullTowards(p.v[idx], p.centroid, 0.0, region_inset_)));
        break;
      }
      idx -= p.v.size();
    }
  }
  // Along the perimeter (stratified, one random offset).
  const double off = uniform01(rng_);
  for (uint32_t k = 0; k < n_edge; ++k) {
    double at = (k + off) / n_edge * sc_.perimeter;
    bool done = false;
    for (const auto& p : sc_.pieces) {
      for (size_t i = 0; i < p.v.size() && !done; ++i) {
        const glm::dvec2 a = p.v[i], b = p.v[(i + 1) % p.v.size()];
        const double len = glm::length(b - a);
        if (at <= len || (&p == &sc_.pieces.back() && i + 1 == p.v.size())) {
          const glm::dvec2 q = len > 0.0 ? a + std::min(at / len, 1.0) * (b - a) : a;
          sc_.eyes.push_back(eyeAt(pullTowards(q, p.centroid, 0.0, region_inset_)));
          done = true;
        }
        at -= len;
      }
      if (done) break;
    }
  }
  // In front of the target: the region's nearest point to a point of the target moved out along
  // its normal, at stratified distances up to the target's diameter. A wall of one room of a
  // large region is seen from that room only, which area samples hit rarely (docs/DESIGN.md,
  // "Sizes and errors": room grids); these eyes stand in it, facing the wall from a useful distance.
  if (n_near > 0) {
    const double diameter = std::sqrt(diameter2(sc_.target2));
    for (uint32_t k = 0; k < n_near; ++k) {
      const glm::dvec2 q = k == 0 ? tc_ : pointInConvex(sc_.target_c, uniform01(rng_), uniform01(rng_), sc_.tri_cum);
      const glm::dvec3 in_front = target3(q) + shape_.plane.n * (diameter * (k + uniform01(rng_)) / n_near);
      const std::optional<glm::dvec2> eye2 =
          nearestInPieces(sc_.pieces, {in_front.x, in_front.z}, region_inset_, nullptr, 0.0, sc_.clip, sc_.grid);
      sc_.eyes.push_back(eyeAt(eye2.value_or(glm::dvec2(0.0))));
    }
  }
  // Inside: stratified over the area (1D strata over the pieces' cumulative area, jittered).
  sc_.piece_cum.clear();
  double acc = 0.0;
  for (const auto& p : sc_.pieces) sc_.piece_cum.push_back(acc += p.area);
  for (uint32_t k = 0; k < n_area; ++k) {
    const double at = (k + uniform01(rng_)) / n_area * sc_.region_area;
    size_t pi = std::lower_bound(sc_.piece_cum.begin(), sc_.piece_cum.end(), at) - sc_.piece_cum.begin();
    if (pi >= sc_.pieces.size()) pi = sc_.pieces.size() - 1;
    const glm::dvec2 q = pointInConvex(sc_.pieces[pi], uniform01(rng_), uniform01(rng_), sc_.tri_cum);
    sc_.eyes.push_back(eyeAt(pullTowards(q, sc_.pieces[pi].centroid, 0.0, region_inset_)));
  }
}

// Target points: up to half the samples at corners, the rest by area. Then the pairs.
void VisibilityScene::Impl::Query::sampleTargets() {
  const uint32_t P = std::max<uint32_t>(1, opt_.polygon_samples);
  sc_.targets.clear();
  const uint32_t n_corner = std::min<uint32_t>(static_cast<uint32_t>(sc_.target2.size()), P / 2);
  for (uint32_t k = 0; k < n_corner; ++k) sc_.targets.push_back(target3(sc_.target2[k * sc_.target2.size() / n_corner]));
  const uint32_t n_area = P - n_corner;
  for (uint32_t k = 0; k < n_area; ++k) {
    // Stratified in the first coordinate, which picks the fan triangle and one barycentric.
    const double u = (k + uniform01(rng_)) / n_area;
    sc_.targets.push_back(target3(pointInConvex(sc_.target_c, u, uniform01(rng_), sc_.tri_cum)));
  }
  ne_ = static_cast<uint32_t>(sc_.eyes.size());
  nt_ = static_cast<uint32_t>(sc_.targets.size());
  pairs_ = static_cast<uint64_t>(ne_) * nt_;
  next_pair_ = 0;
}

// Casts packets until `packets` were cast or the pairs run out; true when a ray was unblocked
// (clear_eye_ its eye). Diagonal order: block b pairs eye i with target (b + i) mod nt, so every
// pair comes once and the first block already uses every eye. Rays go in packets of
// Impl::kPacket (the answer does not depend on the packet size: any unblocked ray keeps the
// fragment).
bool VisibilityScene::Impl::Query::uniformPackets(uint64_t packets) {
  glm::dvec3 pe[Impl::kPacket], pt[Impl::kPacket];
  double pf[Impl::kPacket];
  for (uint64_t cast = 0; cast < packets && next_pair_ < pairs_; ++cast) {
    int n = 0;
    for (; next_pair_ < pairs_ && n < Impl::kPacket; ++next_pair_) {
      const uint32_t i = static_cast<uint32_t>(next_pair_ % ne_);
      const uint32_t j = static_cast<uint32_t>((next_pair_ / ne_ + i) % nt_);
      const double tfar = rayEnd(sc_.eyes[i], sc_.targets[j]);
      if (!(tfar > 0.0)) continue;
      pe[n] = sc_.eyes[i], pt[n] = sc_.targets[j], pf[n] = tfar;
      ++n;
    }
    if (n == 0) break;
    counters_.rays += static_cast<uint64_t>(n);
    const int clear = s_.firstClear16(pe, pt, pf, n);
    if (clear >= 0) {
      clear_eye_ = pe[clear];
      return true;
    }
  }
  return false;
}

// ---- 2. Refinement: step past the edges of the nearest blockers ----
// A step's ray is worked out only when it comes off the queue (most never do: the budget runs
// out first); the order of the queue is the same as if each were worked out when pushed, and a
// step that yields no ray is dropped then, as it would have been.
bool VisibilityScene::Impl::Query::stepRay(const StepParent& pa, uint32_t k, uint32_t variant, glm::dvec3& e_out,
                                           glm::dvec3& p_out) const {
  const uint32_t of = s_.outline_first[pa.outline], oc = s_.outline_first[pa.outline + 1] - of;
  const glm::dvec3 a = s_.outline_vertices[of + k], b = s_.outline_vertices[of + (k + 1) % oc];
  const glm::dvec3 edge = b - a;
  const double el = glm::length(edge);
  if (!(el > 0.0)) return false;
  const glm::dvec3 dir = pa.target - pa.eye;
  const double margin = std::max(end_gap_, kStepMargin * pa.hit_t * glm::length(dir));
  // Outline counter-clockwise seen from the blocker's front: outside is to the edge's right.
  const glm::dvec3 out = glm::normalize(glm::cross(edge, pa.blocker_normal));
  const glm::dvec3 xp = closestOnSegment(a, b, pa.x) + margin * out;
  if (variant == 0) {
    // (a) Keep the eye, move the target point: the eye and the edge span a plane; target
    // points on xp's side of it (by the margin scaled to the target's distance) are seen past
    // the edge. The nearest such point of the inset target to the current one.
    const glm::dvec3 m3 = glm::cross(edge, a - pa.eye);
    const double ml = glm::length(m3);
    if (!(ml > 0.0)) return false;
    const glm::dvec3 mn = m3 / ml;
    const double sgn = glm::dot(mn, xp - a) >= 0.0 ? 1.0 : -1.0;
    const double offset = margin * glm::length(dir) / std::max(pa.hit_t * glm::length(dir), end_gap_);
    const glm::dvec2 g = sgn * glm::dvec2(glm::dot(mn, tu_), glm::dot(mn, tw_));
    const double c0 = sgn * glm::dot(mn, tbase_ - a) - offset;  // keep g·q + c0 >= 0
    if (!clipHalfPlane(sc_.target2, g, c0, sc_.clip)) return false;
    double d2c;
    const glm::dvec3 q = pa.target - tbase_;
    const glm::dvec2 q2 = closestInConvex(sc_.clip, {glm::dot(q, tu_), glm::dot(q, tw_)}, d2c);
    const glm::dvec3 p2 = target3(q2);
    if (!(glm::length(p2 - pa.target) > end_gap_)) return false;
    e_out = pa.eye, p_out = p2;
    return true;
  }
  // (b) Keep the target point, move the eye: the same with the plane through the target point
  // and the edge, cut with the height plane; the nearest such point of the region.
  const glm::dvec3 m3 = glm::cross(edge, a - pa.target);
  const double ml = glm::length(m3);
  if (!(ml > 0.0)) return false;
  const glm::dvec3 mn = m3 / ml;
  const double sgn = glm::dot(mn, xp - a) >= 0.0 ? 1.0 : -1.0;
  const double to_hit = std::max((1.0 - pa.hit_t) * glm::length(dir), end_gap_);
  const double offset = margin * glm::length(dir) / to_hit;
  const glm::dvec2 g = sgn * glm::dvec2(mn.x, mn.z);
  const double c0 = sgn * (mn.y * (height_ - a.y) - mn.x * a.x - mn.z * a.z) - offset;
  const std::optional<glm::dvec2> e2 =
      nearestInPieces(sc_.pieces, {pa.eye.x, pa.eye.z}, region_inset_, &g, c0, sc_.clip, sc_.grid);
  if (!e2) return false;
  const glm::dvec3 e3 = eyeAt(*e2);
  if (!(glm::length(e3 - pa.eye) > end_gap_)) return false;
  e_out = e3, p_out = pa.target;
  return true;
}

bool VisibilityScene::Impl::Query::refine(glm::dvec2* witness) {
  if (opt_.refine_rays == 0) return false;
  sc_.queue.clear();
  // Seeds: eyes in sample order (corners and edges first) each against a target point, spread
  // over the uniform pairs.
  const uint32_t seeds = std::max<uint32_t>(1, std::min<uint32_t>(opt_.refine_rays / 16, ne_ * nt_));
  for (uint32_t k = 0; k < seeds; ++k) {
    const uint32_t i = k % ne_;
    const uint32_t j = static_cast<uint32_t>((k / ne_ + k * 7 + 3) % nt_);
    Probe seed;
    seed.eye = sc_.eyes[i], seed.target = sc_.targets[j];
    sc_.queue.push_back(seed);
  }
  size_t head = 0;
  sc_.parents.clear();
  uint32_t budget = opt_.refine_rays;
  while (head < sc_.queue.size() && budget > 0) {
    const Probe pr = sc_.queue[head++];
    glm::dvec3 eye = pr.eye, target = pr.target;
    if (pr.parent != Probe::kNoParent && !stepRay(sc_.parents[pr.parent], pr.edge, pr.variant, eye, target)) continue;
    Hit hit;
    const int r = castClear(eye, target, &hit);
    if (r < 0) continue;
    --budget;
    ++counters_.refine_rays;
    if (r == 1) {
      ++counters_.refined_visible;
      return visibleWith(witness, eye);
    }
    if (pr.depth >= kMaxStepDepth || budget == 0) continue;
    const glm::dvec3 x = eye + hit.t * (target - eye);
    const uint32_t o = s_.fragment_outline[hit.fragment];
    const uint32_t of = s_.outline_first[o], oc = s_.outline_first[o + 1] - of;
    if (oc < 3) continue;
    sc_.edge_order.clear();
    for (uint32_t k = 0; k < oc; ++k) {
      const glm::dvec3 a = s_.outline_vertices[of + k], b = s_.outline_vertices[of + (k + 1) % oc];
      const glm::dvec3 q = closestOnSegment(a, b, x);
      sc_.edge_order.push_back({glm::dot(q - x, q - x), k});
    }
    std::sort(sc_.edge_order.begin(), sc_.edge_order.end());
    const uint32_t parent = static_cast<uint32_t>(sc_.parents.size());
    sc_.parents.push_back({eye, target, x, hit.t, o, s_.fragments[hit.fragment].plane.n});
    for (uint32_t m = 0; m < oc; ++m)
      for (uint32_t variant = 0; variant < 2; ++variant) {
        Probe child;
        child.depth = pr.depth + 1;
        child.parent = parent;
        child.edge = sc_.edge_order[m].second;
        child.variant = variant;
        sc_.queue.push_back(child);
      }
  }
  return false;
}

}  // namespace walkvis
