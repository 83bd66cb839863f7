// Autopartition BSP build with exact classification.
// Source: H. Fuchs, Z. M. Kedem, B. F. Naylor, "On visible surface generation by a priori tree
// structures", SIGGRAPH 1980 [FuchsKedemNaylor1980] (autopartition: node plane = plane of one of
// its polygons, coplanar polygons stay at the node, straddlers are split). Splitting-plane choice:
// least-crossed among a few sampled candidates with a balance tie-break, or random-order
// autopartition (Paterson and Yao, "Efficient binary space partitions for hidden-surface removal
// and solid modeling", 1990 [PatersonYao1990]).
//
// Exactness and its cost. Node planes are the input polygons' double coefficients (n, d), read
// as exact rationals. Fragment vertices are CGAL Epeck (lazy exact) points: an input vertex is
// projected exactly onto its polygon's plane (a plain double point when it already lies on it
// exactly, which is the case for the axis-aligned walls, floors and ceilings of buildings), and a
// straddler is split at the exact intersection of its edge with the node plane. Every vertex side
// is exact: a double evaluation with a forward error bound that includes the width of CGAL's
// interval approximation decides almost all; exactly representable points then use the
// floating-point expansion path of exact_sign.h (cheap), and only the rest force CGAL's exact
// (GMP rational) evaluation of the lazy point. The counter stats.exact_fallbacks reports how many
// classifications the double filter could not decide. The cost over a plain double build is the
// lazy points' memory and time; exact evaluations themselves stay rare (`walkvis bench bsp`).
// The splitting-plane HEURISTIC uses doubles: it only picks a plane, so it needs no exactness,
// but it must see the splits the exact build will make. Plane coefficients are rounded, so a point
// on a sloped wall's line (a floor corner there, the end of a collinear wall, which is a separate
// polygon with its own rounded plane) lies a hair off that wall's plane and the exact build splits
// a sliver off its polygon. Counting such vertices as "on" (a tolerance) hid those splits, so
// within the tolerance a vertex counts by the exact side of its double position
// (exact_heuristic_sides; exact for the input's double vertices, a close guess for constructed
// ones), unless the build drops such slivers (drop_slivers): then it counts as on, as the build
// will not split there.
//
// Splitting-plane choice (least-crossed), by node size m: m <= lookahead_max, every distinct
// plane with one level of lookahead; else, when m × (distinct planes) <= full_count_max, every
// distinct plane counted on the whole set (a bounding-box filter settles most plane/fragment
// pairs); else `candidates` planes scored on `samples` fragments. In both exact modes a "free"
// plane (crossing none of the set, cf. the free cuts of Paterson and Yao 1990) may be taken first
// (free_first), and horizontal planes' crossings weigh horizontal_weight.
//
// Pilot method (choosePilot, Duin and Voss 1999 [DuinVoss1999]): at nodes of >= pilot_min_set
// fragments and depth <= pilot_depth_max the pilot_candidates best planes by the greedy score are
// each completed by a greedy rollout (double approximation, count only) and the fewest total wins.
//
// What each knob buys, measured: docs/bsp/README.md (docs/bsp/knobs.sh makes the sweep again).
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cassert>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <unordered_map>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "bsp/bsp_internal.h"
#include "bsp/exact_sign.h"
#include "core/hash.h"

namespace walkvis {

namespace exact {

int planeSignRational(double a, double b, double c, double d, double x, double y, double z) {
  if (!(std::isfinite(a) && std::isfinite(b) && std::isfinite(c) && std::isfinite(d) && std::isfinite(x) &&
        std::isfinite(y) && std::isfinite(z)))
    return 0;
  using Q = CGAL::Exact_rational;
  const Q v = Q(a) * Q(x) + Q(b) * Q(y) + Q(c) * Q(z) - Q(d);
  return static_cast<int>(CGAL::sign(v));
}

}  // namespace exact

namespace detail {
namespace {

using K = CGAL::Epeck;
using EPoint = K::Point_3;
using EFT = K::Exact_kernel::FT;

struct Vtx {
  EPoint p;
  glm::dvec3 mid;     // approximation of p (midpoint of CGAL's interval)
  glm::dvec3 width;   // interval widths, >= the distance from mid to p per coordinate
  bool exact_double;  // p == mid exactly
};

Vtx makeVtx(const EPoint& p) {
  const auto a = CGAL::approx(p);
  Vtx v{p, {}, {}, true};
  for (int i = 0; i < 3; ++i) {
    const double lo = a[i].inf(), hi = a[i].sup();
    v.mid[i] = lo == hi ? lo : 0.5 * lo + 0.5 * hi;
    v.width[i] = hi - lo;  // rounded to nearest, still >= |mid - exact| (at most half the width)
    v.exact_double = v.exact_double && lo == hi;
  }
  return v;
}

struct Frag {
  uint32_t poly;   // input polygon
  uint32_t first;  // into Builder::verts
  uint32_t count;
};

struct Box {
  glm::dvec3 lo, hi;  // of the vertex approximations (mid), for the heuristic only
};

struct NodePlane {
  double a, b, c, d;
  uint32_t poly;
};

// A floor or ceiling plane (normal ±y exactly, as the loaders write them).
bool isHorizontal(const Plane& pl) { return pl.n.x == 0.0 && pl.n.z == 0.0; }

// The same plane in either orientation (coefficients equal or exactly negated).
bool samePlane(const Plane& a, const Plane& b) {
  return (a.n == b.n && a.d == b.d) || (a.n == -b.n && a.d == -b.d);
}

// A splitter candidate (a fragment whose plane is the candidate) and its greedy score (lower wins).
struct Ranked {
  double score;
  uint32_t rep;
};

// Keeps the k lowest scores in `top`, ascending; an equal score does not displace an earlier one,
// so the first of equally good candidates stays first (as with a plain strict-less best).
void offerRanked(std::vector<Ranked>& top, size_t k, double score, uint32_t rep) {
  if (top.size() >= k && !(score < top.back().score)) return;
  const auto it =
      std::upper_bound(top.begin(), top.end(), score, [](double s, const Ranked& r) { return s < r.score; });
  top.insert(it, Ranked{score, rep});
  if (top.size() > k) top.pop_back();
}

// The score a candidate must beat to enter a top-k list.
double rankThreshold(const std::vector<Ranked>& top, size_t k) { return top.size() >= k ? top.back().score : INFINITY; }

class Builder {
 public:
  Builder(const Scene& scene, const BspOptions& options, const DetailGroups& groups, BspTree& tree)
      : scene_(scene), options_(options), group_(groups.group), tree_(tree), rng_(options.seed) {}

  uint64_t run();

 private:
  int classify(const Vtx& v, const NodePlane& p);
  void partition(const std::vector<uint32_t>& in, const NodePlane& plane, std::vector<uint32_t>& on,
                 std::vector<uint32_t>& front, std::vector<uint32_t>& back);
  // The piece of straddler fi on `side` (+1 front, -1 back) of the plane as a new fragment, its
  // index returned; sides_ holds fi's vertex sides.
  uint32_t splitOff(uint32_t fi, const NodePlane& plane, int side, std::optional<K::Plane_3>& kplane);
  // The best `k` splitters of the set by the greedy score, best first, into `top`.
  void rankSplitters(const std::vector<uint32_t>& frags, size_t k, std::vector<Ranked>& top);
  uint32_t chooseSplitter(const std::vector<uint32_t>& frags);
  uint32_t choosePilot(const std::vector<uint32_t>& frags);
  void chooseWithLookahead(const std::vector<uint32_t>& frags, size_t k, std::vector<Ranked>& top);
  bool chooseByFullCount(const std::vector<uint32_t>& frags, size_t k, std::vector<Ranked>& top);
  void chooseBySampling(const std::vector<uint32_t>& frags, size_t k, std::vector<Ranked>& top);
  void partitionApprox(const std::vector<uint32_t>& in, const Plane& pl, uint64_t& on,
                       std::vector<uint32_t>& front, std::vector<uint32_t>& back);
  uint64_t rolloutCount(std::vector<uint32_t> frags, uint64_t bound);
  int boxSide(const Plane& pl, uint32_t fi) const;
  // Factor on a candidate's crossing count: horizontal_weight for a horizontal plane (normal ±y).
  double crossWeight(const Plane& pl) const {
    return isHorizontal(pl) ? options_.horizontal_weight : 1.0;
  }
  // What crossing fragment `fi` counts in a candidate's crossings: horizontal_fragment_weight for
  // a floor or ceiling, else 1.
  double crossedWeight(uint32_t fi) const {
    return isHorizontal(scene_.polygons[frags_[fi].poly].plane) ? options_.horizontal_fragment_weight : 1.0;
  }
  void pushFrag(const Frag& f);
  void pushVtx(Vtx v) {
    hv_.push_back(v.mid);
    verts_.push_back(std::move(v));
  }
  int heuristicSide(const Plane& pl, const Frag& f) const;
  // Side of a heuristic vertex position for counting (+1, -1, 0 = on). Beyond heuristic_tol_ the
  // double value decides; within it, with exact_heuristic_sides, the exact side of the double
  // point (what the build's exact classification says for a vertex that is that double), else 0.
  int vertexSide(const Plane& pl, const glm::dvec3& p, double& value) const {
    value = glm::dot(pl.n, p) - pl.d;
    if (value > heuristic_tol_) return 1;
    if (value < -heuristic_tol_) return -1;
    if (!options_.exact_heuristic_sides || options_.drop_slivers) return 0;  // as the build will: not split
    // An axis-aligned plane (one nonzero normal component, ±1) was evaluated exactly: the products
    // with 0 and ±1 are exact and so is a difference of doubles that is 0 only when they are equal.
    if (int{pl.n.x == 0.0} + int{pl.n.y == 0.0} + int{pl.n.z == 0.0} == 2) return value > 0 ? 1 : value < 0 ? -1 : 0;
    return exact::planeSign(pl.n.x, pl.n.y, pl.n.z, pl.d, p.x, p.y, p.z);
  }
  void emit(uint32_t frag, const NodePlane& plane);
  struct Task {
    int32_t node;
    std::vector<uint32_t> frags;
  };
  // Makes `node`'s non-empty sides its children and queues them, the back first so that the front
  // subtree is built (and its fragments numbered) first.
  void pushChildren(int32_t node, std::vector<uint32_t>& front, std::vector<uint32_t>& back, std::vector<Task>& stack);
  // Makes task's node a separating or cutting node (plane, no fragments) over the given sides.
  void emptyNode(Task& task, const Plane& plane, std::vector<uint32_t>& front, std::vector<uint32_t>& back,
                 std::vector<Task>& stack) {
    task.frags = {};
    BspNode& node = tree_.nodes[task.node];
    node.plane = plane;
    node.polygon = kSeparatorPolygon;
    node.first_fragment = static_cast<uint32_t>(tree_.fragments.size());
    node.fragment_count = 0;
    pushChildren(task.node, front, back, stack);
  }
  // Whether the budget pilot_work_max still covers a pilot at a node of m fragments, estimated
  // as pilot_candidates rollouts of m fragments over ~log2(m) + 1 levels each.
  bool pilotAffordable(size_t m) const {
    const double estimate = static_cast<double>(options_.pilot_candidates) * static_cast<double>(m) *
                            (std::log2(static_cast<double>(m)) + 1.0);
    return static_cast<double>(pilot_work_) + estimate <= static_cast<double>(options_.pilot_work_max);
  }
  uint64_t randomBelow(uint64_t n) { return rng_() % n; }  // bias < n / 2^64: irrelevant here
  // Whether fragment fi may give the plane of a node over `frags`: a detail fragment may not while
  // a structural one is left (bsp.h, detail_extent). Sets candidates_restricted_ for the set.
  void restrictCandidates(const std::vector<uint32_t>& frags) {
    candidates_restricted_ = false;
    if (group_.empty()) return;
    for (uint32_t fi : frags) {
      if (group_[frags_[fi].poly] == kStructureGroup) {
        candidates_restricted_ = true;
        return;
      }
    }
  }
  bool candidate(uint32_t fi) const {
    return !candidates_restricted_ || group_[frags_[fi].poly] == kStructureGroup;
  }
  // A plane that separates the detail groups of a set of detail fragments only (bsp.h,
  // detail_extent), crossing none: true with the plane and the set's two sides, false when the
  // set holds structure or a single group, or when no such plane was found (counted).
  bool separate(const std::vector<uint32_t>& frags, Plane& plane, std::vector<uint32_t>& front,
                std::vector<uint32_t>& back);
  bool axisSeparator(size_t total, Plane& plane);  // total: fragments of the set
  // For a set of detail fragments with no separating plane (or inside one group): an axis-aligned
  // plane at the median vertex coordinate, when it scores better than the best polygon plane
  // (which on a curved or hollow mesh crosses its neighbours level after level). Needs separate()
  // to have found the set detail-only.
  bool chooseCut(const std::vector<uint32_t>& frags, uint32_t best_polygon_fragment, Plane& plane);
  // Heuristic sides (heuristicSide) of the fragments `frags` against pl, counted.
  struct SideCounts {
    int64_t crossed = 0, front = 0, back = 0, on = 0;
  };
  SideCounts countSides(std::span<const uint32_t> frags, const Plane& pl) const;
  // The sampled greedy score of pl over `counts`: split_weight · crossed + |front − back|.
  double greedyScore(const SideCounts& c) const {
    return options_.split_weight * static_cast<double>(c.crossed) + static_cast<double>(std::abs(c.front - c.back));
  }
  bool detail_only_ = false;  // of the last set separate() looked at
  uint64_t cuts_ = 0;
  std::vector<double> coords_;  // scratch of chooseCut
  bool faceSeparator(const std::vector<uint32_t>& frags, Plane& plane);
  uint32_t slotOf(uint32_t fi) const { return group_slot_[group_[frags_[fi].poly]]; }

  const Scene& scene_;
  const BspOptions& options_;
  // Per input polygon, its detail group (detailGroups); empty: all structure.
  const std::vector<uint32_t>& group_;
  BspTree& tree_;
  std::mt19937_64 rng_;
  std::vector<Vtx> verts_;
  // Heuristic positions, verts_[i].mid for i < verts_.size(); past that, the double vertices of
  // the fragments a pilot rollout makes (dropped after each rollout).
  std::vector<glm::dvec3> hv_;
  std::vector<Frag> frags_;
  std::vector<Box> boxes_;  // per fragment, parallel to frags_
  std::vector<int8_t> sides_;     // scratch
  std::vector<uint32_t> sample_;  // scratch
  std::vector<uint32_t> reps_;    // scratch of chooseWithLookahead: one fragment per distinct plane
  std::vector<uint64_t> masks_;   // scratch of chooseWithLookahead: per plane, split/front/back/on bitsets
  std::vector<Ranked> ranked_;    // scratch of chooseSplitter
  std::vector<double> dist_;      // scratch of partitionApprox
  std::vector<int8_t> vside_;     // scratch of partitionApprox
  uint64_t fallbacks_ = 0;
  uint64_t slivers_ = 0;      // pieces dropped (BspOptions::drop_slivers)
  double sliver_tol_ = 0.0;
  uint64_t pilot_work_ = 0;  // fragments of all rollout node sets so far (bounded by pilot_work_max)
  uint64_t refined_ = 0;  // stored vertices rounded from the exact point
  double heuristic_tol_ = 0.0;
  bool candidates_restricted_ = false;
  // Scratch of separate(): per group its slot in group_box_ (kNoSlot when not in the set).
  struct GroupBox {
    glm::dvec3 lo, hi;  // encloses the exact vertices of the group's fragments in the set
    uint32_t fragments;
    int8_t side;        // where separate() puts it: -1 back, +1 front
    bool pos, neg;      // scratch of a face-plane candidate
  };
  static constexpr uint32_t kNoSlot = UINT32_MAX;
  std::vector<uint32_t> group_slot_;
  std::vector<GroupBox> group_box_;
  std::vector<uint32_t> group_order_;
  uint64_t separators_ = 0;
  uint64_t inseparable_ = 0;
  std::vector<uint32_t> structural_;  // scratch of chooseBySampling and the random heuristic
};

int Builder::classify(const Vtx& v, const NodePlane& p) {
  if (v.exact_double) {
    const int s = exact::planeSign(p.a, p.b, p.c, p.d, v.mid.x, v.mid.y, v.mid.z);
    return s;
  }
  const double val = p.a * v.mid.x + p.b * v.mid.y + p.c * v.mid.z - p.d;
  const double mag = std::abs(p.a * v.mid.x) + std::abs(p.b * v.mid.y) + std::abs(p.c * v.mid.z) + std::abs(p.d);
  const double spread = std::abs(p.a) * v.width.x + std::abs(p.b) * v.width.y + std::abs(p.c) * v.width.z;
  // spread bounds |n·(p - mid)|; its own rounding and that of val are covered by the relative
  // terms (as in exact::planeSign), 1e-300 covers subnormal losses.
  const double bound = spread * (1.0 + 8.0 * DBL_EPSILON) + 16.0 * DBL_EPSILON * mag + 1e-300;
  if (val > bound) return 1;
  if (val < -bound) return -1;
  ++fallbacks_;
  const auto& e = CGAL::exact(v.p);
  const EFT s = EFT(p.a) * e.x() + EFT(p.b) * e.y() + EFT(p.c) * e.z() - EFT(p.d);
  return static_cast<int>(CGAL::sign(s));
}

void Builder::partition(const std::vector<uint32_t>& in, const NodePlane& plane, std::vector<uint32_t>& on,
                        std::vector<uint32_t>& front, std::vector<uint32_t>& back) {
  const Plane node{{plane.a, plane.b, plane.c}, plane.d};
  std::optional<K::Plane_3> kplane;  // built on the first split only
  for (uint32_t fi : in) {
    const Frag f = frags_[fi];
    const Plane& own = scene_.polygons[f.poly].plane;
    // Same or exactly opposite coefficients: every vertex lies exactly on the node plane (they
    // were projected onto their own plane), no test needed.
    if ((own.n == node.n && own.d == node.d) || (own.n == -node.n && own.d == -node.d)) {
      on.push_back(fi);
      continue;
    }
    sides_.resize(f.count);
    bool pos = false, neg = false;
    for (uint32_t i = 0; i < f.count; ++i) {
      const int s = classify(verts_[f.first + i], plane);
      sides_[i] = static_cast<int8_t>(s);
      pos = pos || s > 0;
      neg = neg || s < 0;
    }
    if (!pos && !neg) {
      on.push_back(fi);
    } else if (!neg) {
      front.push_back(fi);
    } else if (!pos) {
      back.push_back(fi);
    } else {
      // A sliver: when every vertex on one side lies within sliver_tol_ of the plane, that side's
      // piece lies in a slab thinner than the float coordinates frames are drawn with can resolve
      // (bsp.h, drop_slivers). It is dropped (counted) and the rest goes whole to its side: no
      // fragment is made that no pixel could show, and the order of what is kept stays exact.
      if (options_.drop_slivers) {
        bool front_thin = true, back_thin = true;
        for (uint32_t i = 0; i < f.count; ++i) {
          const glm::dvec3& m = verts_[f.first + i].mid;
          const double dist = std::abs(plane.a * m.x + plane.b * m.y + plane.c * m.z - plane.d);
          if (sides_[i] > 0 && !(dist <= sliver_tol_)) front_thin = false;
          if (sides_[i] < 0 && !(dist <= sliver_tol_)) back_thin = false;
        }
        if (front_thin != back_thin) {
          ++slivers_;
          splitOff(fi, plane, front_thin ? -1 : 1, kplane);
          (front_thin ? back : front).push_back(static_cast<uint32_t>(frags_.size() - 1));
          continue;
        }
      }
      const uint32_t front_piece = splitOff(fi, plane, 1, kplane);
      front.push_back(front_piece);
      back.push_back(splitOff(fi, plane, -1, kplane));
    }
  }
}

uint32_t Builder::splitOff(uint32_t fi, const NodePlane& plane, int side, std::optional<K::Plane_3>& kplane) {
  if (!kplane) kplane.emplace(plane.a, plane.b, plane.c, -plane.d);
  // Walk the loop once: vertices on `side` or on the plane are kept, and each edge whose ends are
  // strictly on opposite sides adds its exact intersection (sides_ holds the vertices' sides).
  const Frag f = frags_[fi];
  const uint32_t first = static_cast<uint32_t>(verts_.size());
  for (uint32_t i = 0; i < f.count; ++i) {
    const uint32_t j = (i + 1) % f.count;
    const Vtx vi = verts_[f.first + i];
    if (sides_[i] * side >= 0) pushVtx(vi);
    if (sides_[i] * sides_[j] < 0) {
      const K::Segment_3 seg(vi.p, verts_[f.first + j].p);
      const auto hit = CGAL::intersection(seg, *kplane);
      const EPoint* ip = hit ? boost::get<EPoint>(&*hit) : nullptr;
      if (!ip) throw std::logic_error("bsp: exact split found no intersection point");
      pushVtx(makeVtx(*ip));
    }
  }
  pushFrag(Frag{f.poly, first, static_cast<uint32_t>(verts_.size()) - first});
  return static_cast<uint32_t>(frags_.size() - 1);
}

// Side of a fragment for the heuristic (doubles with a tolerance): 2 = crossed, 1 = front,
// -1 = back, 0 = on.
int Builder::heuristicSide(const Plane& pl, const Frag& f) const {
  bool pos = false, neg = false;
  double v;
  for (uint32_t i = 0; i < f.count; ++i) {
    const int side = vertexSide(pl, hv_[f.first + i], v);
    pos = pos || side > 0;
    neg = neg || side < 0;
  }
  return pos && neg ? 2 : pos ? 1 : neg ? -1 : 0;
}

// Least crossed with one level of lookahead, for small sets, where most splits happen
// (docs/bsp/README.md). Plain least-crossed is greedy: around a pillar standing on a floor it takes a
// pillar wall (it crosses one floor piece) and later pays again for every other wall, where the
// floor plane (crossing nothing, all floor pieces coplanar) would have separated them for free.
// Here every distinct plane of the set is a candidate and is scored, on the whole set, by
//   split_weight · (crossed(c) + min_p crossed_F(p) + min_p crossed_B(p)) + |F − B|
// where F and B are the fragments c sends front and back (crossed ones in both) and
// min_p crossed_F(p) is the fewest of F that any plane of a fragment of F crosses: the best next
// split on each side. A crossed fragment's pieces are counted as the whole fragment (an estimate:
// a piece may miss a plane its parent crossed). Cost: sides of all m fragments against all
// P <= m distinct planes (m·P vertex tests), then P² bitset intersections of m bits.
void Builder::chooseWithLookahead(const std::vector<uint32_t>& frags, size_t k, std::vector<Ranked>& top) {
  const size_t m = frags.size();
  const size_t words = (m + 63) / 64;
  reps_.clear();
  size_t candidate_planes = 0;
  // Candidates come first in reps_ so that [0, candidate_planes) are the planes a node may take.
  for (int pass = 0; pass < 2; ++pass) {
  for (uint32_t fi : frags) {
    if (candidate(fi) != (pass == 0)) continue;
    const Plane& pl = scene_.polygons[frags_[fi].poly].plane;
    bool seen = false;
    for (uint32_t r : reps_) {
      const Plane& q = scene_.polygons[frags_[r].poly].plane;
      if ((q.n == pl.n && q.d == pl.d) || (q.n == -pl.n && q.d == -pl.d)) {
        seen = true;
        break;
      }
    }
    if (!seen) reps_.push_back(fi);
  }
  if (pass == 0) candidate_planes = reps_.size();
  }
  const size_t planes = reps_.size();
  // Per plane four bitsets over the set: crossed, front, back, on.
  masks_.assign(planes * 4 * words, 0);
  auto mask = [&](size_t p, int kind) { return masks_.data() + (p * 4 + static_cast<size_t>(kind)) * words; };
  for (size_t p = 0; p < planes; ++p) {
    const Plane& pl = scene_.polygons[frags_[reps_[p]].poly].plane;
    for (size_t i = 0; i < m; ++i) {
      const int side = heuristicSide(pl, frags_[frags[i]]);
      const int kind = side == 2 ? 0 : side == 1 ? 1 : side == -1 ? 2 : 3;
      mask(p, kind)[i / 64] |= uint64_t{1} << (i % 64);
    }
  }
  auto count = [&](const uint64_t* a) {
    int64_t c = 0;
    for (size_t w = 0; w < words; ++w) c += std::popcount(a[w]);
    return c;
  };
  // The fewest fragments of `set` crossed by the plane of any fragment of `set` (0 when empty).
  // Horizontal fragments of the set (floors, ceilings): a crossing of one weighs
  // horizontal_fragment_weight.
  const double hf_extra = options_.horizontal_fragment_weight - 1.0;
  std::vector<uint64_t> horizontal(words, 0);
  for (size_t i = 0; i < m; ++i)
    if (isHorizontal(scene_.polygons[frags_[frags[i]].poly].plane)) horizontal[i / 64] |= uint64_t{1} << (i % 64);
  auto crossings = [&](const uint64_t* crossed, const uint64_t* set) {
    int64_t c = 0, h = 0;
    for (size_t w = 0; w < words; ++w) {
      const uint64_t x = set ? crossed[w] & set[w] : crossed[w];
      c += std::popcount(x);
      h += std::popcount(x & horizontal[w]);
    }
    return static_cast<double>(c) + hf_extra * static_cast<double>(h);
  };
  auto bestNext = [&](const std::vector<uint64_t>& set) {
    double best = -1;
    for (size_t p = 0; p < planes; ++p) {
      const uint64_t* on = mask(p, 3);
      bool present = false;
      for (size_t w = 0; w < words && !present; ++w) present = (on[w] & set[w]) != 0;
      if (!present) continue;
      const double c = crossings(mask(p, 0), set.data());
      if (best < 0 || c < best) {
        best = c;
        if (best == 0) break;
      }
    }
    return std::max(best, 0.0);
  };
  std::vector<uint64_t> front_set(words), back_set(words);
  if (options_.free_first) {
    // A free plane (crossing nothing) first, the most balanced one; see chooseByFullCount.
    for (size_t c = 0; c < candidate_planes; ++c) {
      if (count(mask(c, 0)) != 0) continue;
      offerRanked(top, k, static_cast<double>(std::abs(count(mask(c, 1)) - count(mask(c, 2)))), reps_[c]);
    }
    if (!top.empty()) return;
  }
  for (size_t c = 0; c < candidate_planes; ++c) {
    const uint64_t *crossed = mask(c, 0), *front = mask(c, 1), *back = mask(c, 2);
    for (size_t w = 0; w < words; ++w) {
      front_set[w] = front[w] | crossed[w];
      back_set[w] = back[w] | crossed[w];
    }
    const double splits = crossings(crossed, nullptr);
    const int64_t nf = count(front_set.data()), nb = count(back_set.data());
    // A lower bound on the score without the lookahead: skip the lookahead when it cannot win.
    const double base = options_.split_weight * crossWeight(scene_.polygons[frags_[reps_[c]].poly].plane) *
                            static_cast<double>(splits) +
                        static_cast<double>(std::abs(nf - nb));
    if (base >= rankThreshold(top, k)) continue;
    const double next = (nf > 0 ? bestNext(front_set) : 0.0) + (nb > 0 ? bestNext(back_set) : 0.0);
    offerRanked(top, k, base + options_.split_weight * static_cast<double>(next), reps_[c]);
  }
}

void Builder::pushFrag(const Frag& f) {
  Box b{hv_[f.first], hv_[f.first]};
  for (uint32_t i = 1; i < f.count; ++i) {
    b.lo = glm::min(b.lo, hv_[f.first + i]);
    b.hi = glm::max(b.hi, hv_[f.first + i]);
  }
  frags_.push_back(f);
  boxes_.push_back(b);
}

// heuristicSide with a bounding-box shortcut: a box wholly beyond the tolerance on one side
// decides without the vertex loop (same answer: every vertex lies in the box).
int Builder::boxSide(const Plane& pl, uint32_t fi) const {
  const Box& b = boxes_[fi];
  const glm::dvec3 c = 0.5 * (b.lo + b.hi), e = 0.5 * (b.hi - b.lo);
  const double dist = glm::dot(pl.n, c) - pl.d;
  const double r = glm::dot(glm::abs(pl.n), e);
  if (dist - r > heuristic_tol_) return 1;
  if (dist + r < -heuristic_tol_) return -1;
  return heuristicSide(pl, frags_[fi]);
}

// Least crossed over EVERY distinct plane of the set, each counted on the whole set, for sets
// where (fragments × distinct planes) <= options_.full_count_max; std::nullopt otherwise. With
// options_.free_first a plane that crosses nothing ("free": it separates or peels off fragments
// at no cost) beats every plane that crosses something, the most balanced free plane first.
// Sampling candidates misses most free planes of a big set (a floor at the cell's lowest level,
// a wall whose plane only touches the cell's boundary); taking them early removes their
// fragments before other planes can cut them.
bool Builder::chooseByFullCount(const std::vector<uint32_t>& frags, size_t top_k, std::vector<Ranked>& top) {
  const size_t m = frags.size();
  if (options_.full_count_max == 0) return false;
  // Distinct planes: key on the coefficients made canonical (first nonzero normal component > 0).
  struct Key {
    double a, b, c, d;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      // + 0.0: -0.0 and 0.0 hash alike
      return static_cast<size_t>(fnv1aDoubles({k.a + 0.0, k.b + 0.0, k.c + 0.0, k.d + 0.0}));
    }
  };
  std::unordered_map<Key, uint32_t, KeyHash> seen;
  seen.reserve(m);
  reps_.clear();
  for (uint32_t fi : frags) {
    const Plane& pl = scene_.polygons[frags_[fi].poly].plane;
    const bool flip = pl.n.x < 0 || (pl.n.x == 0 && (pl.n.y < 0 || (pl.n.y == 0 && pl.n.z < 0)));
    const Key k = flip ? Key{-pl.n.x + 0.0, -pl.n.y + 0.0, -pl.n.z + 0.0, -pl.d + 0.0}
                       : Key{pl.n.x + 0.0, pl.n.y + 0.0, pl.n.z + 0.0, pl.d + 0.0};
    if (seen.emplace(k, fi).second) reps_.push_back(fi);
    if (static_cast<double>(reps_.size()) * static_cast<double>(m) > static_cast<double>(options_.full_count_max))
      return false;
  }
  // A free plane's score is lowered by free_bonus, far more than any score (at most
  // split_weight · m + m), so free planes rank before all others and among themselves by balance.
  const double free_bonus = 1e18;
  for (uint32_t rep : reps_) {
    if (!candidate(rep)) continue;
    const Plane& pl = scene_.polygons[frags_[rep].poly].plane;
    const double weight = options_.split_weight * crossWeight(pl);
    double crossed = 0;
    int64_t front = 0, back = 0;
    bool pruned = false;
    for (uint32_t fi : frags) {
      const int side = boxSide(pl, fi);
      if (side == 2) {
        crossed += crossedWeight(fi);
        // Past this, the plane cannot enter the top k (a free plane's score is below any bound).
        if (weight * crossed >= rankThreshold(top, top_k)) {
          pruned = true;
          break;
        }
      } else if (side == 1) {
        ++front;
      } else if (side == -1) {
        ++back;
      }
    }
    if (pruned) continue;
    const bool is_free = options_.free_first && crossed == 0;
    const double score = weight * crossed + static_cast<double>(std::abs(front - back));
    offerRanked(top, top_k, is_free ? score - free_bonus : score, rep);
  }
  return true;
}

void Builder::rankSplitters(const std::vector<uint32_t>& frags, size_t k, std::vector<Ranked>& top) {
  top.clear();
  restrictCandidates(frags);
  if (frags.size() <= options_.lookahead_max) {
    chooseWithLookahead(frags, k, top);
  } else if (!chooseByFullCount(frags, k, top)) {
    top.clear();
    chooseBySampling(frags, k, top);
  }
}

uint32_t Builder::chooseSplitter(const std::vector<uint32_t>& frags) {
  const size_t m = frags.size();
  if (m == 1) return frags[0];
  if (options_.heuristic == SplitHeuristic::kRandom) {
    restrictCandidates(frags);
    if (!candidates_restricted_) return frags[randomBelow(m)];
    structural_.clear();
    for (uint32_t fi : frags)
      if (candidate(fi)) structural_.push_back(fi);
    return structural_[randomBelow(structural_.size())];
  }
  rankSplitters(frags, 1, ranked_);
  return ranked_.empty() ? frags[0] : ranked_[0].rep;
}

void Builder::chooseBySampling(const std::vector<uint32_t>& frags, size_t top_k, std::vector<Ranked>& top) {
  const size_t m = frags.size();
  // Least crossed: each candidate plane is scored on a sample of the set (all of it when small),
  // enough to rank candidates, few enough that the choice costs O(candidates · samples) per node.
  const size_t k = std::max<size_t>(1, std::min<size_t>(options_.candidates, m));
  const size_t max_samples = std::max<size_t>(1, options_.samples);
  const bool all_samples = m <= max_samples;
  const size_t samples = all_samples ? m : max_samples;
  sample_.resize(samples);
  for (size_t i = 0; i < samples; ++i) sample_[i] = all_samples ? frags[i] : frags[randomBelow(m)];
  // Candidates are drawn from the fragments that may give the node's plane.
  const std::vector<uint32_t>* pool = &frags;
  if (candidates_restricted_) {
    structural_.clear();
    for (uint32_t fi : frags)
      if (candidate(fi)) structural_.push_back(fi);
    pool = &structural_;
  }
  const size_t pool_size = pool->size();
  const size_t kc = std::min(k, pool_size);
  for (size_t c = 0; c < kc; ++c) {
    const uint32_t cand = pool_size <= kc ? (*pool)[c] : (*pool)[randomBelow(pool_size)];
    const Plane& pl = scene_.polygons[frags_[cand].poly].plane;
    const double score = greedyScore(countSides(sample_, pl));
    offerRanked(top, top_k, score, cand);
  }
}

// The double counterpart of partition, for pilot rollouts: sides with the heuristic tolerance,
// straddlers split at double intersections into new fragments of hv_/frags_/boxes_ (dropped by
// choosePilot after the rollout). Only the number of fragments on the plane is kept.
void Builder::partitionApprox(const std::vector<uint32_t>& in, const Plane& node, uint64_t& on,
                              std::vector<uint32_t>& front, std::vector<uint32_t>& back) {
  std::vector<double>& dist = dist_;
  for (uint32_t fi : in) {
    const Frag f = frags_[fi];
    if (samePlane(scene_.polygons[f.poly].plane, node)) {
      ++on;
      continue;
    }
    const int side = boxSide(node, fi);
    if (side == 0) {
      ++on;
    } else if (side == 1) {
      front.push_back(fi);
    } else if (side == -1) {
      back.push_back(fi);
    } else {
      dist.resize(f.count);
      vside_.resize(f.count);
      for (uint32_t i = 0; i < f.count; ++i) vside_[i] = static_cast<int8_t>(vertexSide(node, hv_[f.first + i], dist[i]));
      for (int piece = 0; piece < 2; ++piece) {
        const int sign = piece == 0 ? 1 : -1;
        const uint32_t first = static_cast<uint32_t>(hv_.size());
        for (uint32_t i = 0; i < f.count; ++i) {
          const uint32_t j = (i + 1) % f.count;
          if (sign * vside_[i] >= 0) hv_.push_back(hv_[f.first + i]);
          if (vside_[i] * vside_[j] < 0) {
            // Near the plane the two values may carry no sign information (a sliver split decided
            // exactly): any point of the edge will do for counting, so t is clamped.
            const double den = dist[i] - dist[j];
            const double t = den != 0.0 ? std::clamp(dist[i] / den, 0.0, 1.0) : 0.5;
            hv_.push_back(hv_[f.first + i] + t * (hv_[f.first + j] - hv_[f.first + i]));
          }
        }
        pushFrag(Frag{f.poly, first, static_cast<uint32_t>(hv_.size()) - first});
        (piece == 0 ? front : back).push_back(static_cast<uint32_t>(frags_.size() - 1));
      }
    }
  }
}

// Fragments of the subtree plain greedy would build over `frags` (counted on the double
// approximation), or some count >= bound once it is clear that it reaches bound.
uint64_t Builder::rolloutCount(std::vector<uint32_t> frags, uint64_t bound) {
  uint64_t total = 0;
  std::vector<std::vector<uint32_t>> stack;
  stack.push_back(std::move(frags));
  std::vector<uint32_t> front, back;
  while (!stack.empty() && total < bound) {
    std::vector<uint32_t> set = std::move(stack.back());
    stack.pop_back();
    if (set.size() == 1) {
      ++total;
      continue;
    }
    pilot_work_ += set.size();
    const uint32_t splitter = chooseSplitter(set);
    front.clear();
    back.clear();
    partitionApprox(set, scene_.polygons[frags_[splitter].poly].plane, total, front, back);
    if (!front.empty()) stack.push_back(front);
    if (!back.empty()) stack.push_back(back);
  }
  return total;
}

// Pilot method (Duin and Voss, "The Pilot Method: A Strategy for Heuristic Repetition with
// Application to the Steiner Problem in Graphs", Networks 34, 1999): the best pilot_candidates
// planes by the greedy score are each completed by a greedy rollout of both subtrees, and the
// one whose whole subtree has the fewest fragments wins (the greedy's own first choice on ties).
uint32_t Builder::choosePilot(const std::vector<uint32_t>& frags) {
  std::vector<Ranked> top;
  rankSplitters(frags, options_.pilot_candidates, top);
  if (top.empty()) return frags[0];
  const size_t saved_hv = hv_.size(), saved_frags = frags_.size();
  uint64_t best_total = UINT64_MAX;
  uint32_t best = top[0].rep;
  std::vector<uint32_t> front, back;
  for (size_t c = 0; c < top.size(); ++c) {
    const Plane& pl = scene_.polygons[frags_[top[c].rep].poly].plane;
    bool repeated = false;  // sampling may offer one plane twice
    for (size_t e = 0; e < c && !repeated; ++e) repeated = samePlane(scene_.polygons[frags_[top[e].rep].poly].plane, pl);
    if (repeated) continue;
    uint64_t total = 0;
    front.clear();
    back.clear();
    partitionApprox(frags, pl, total, front, back);
    if (!front.empty() && total < best_total) total += rolloutCount(front, best_total - total);
    if (!back.empty() && total < best_total) total += rolloutCount(back, best_total - total);
    hv_.resize(saved_hv);
    frags_.resize(saved_frags);
    boxes_.resize(saved_frags);
    if (total < best_total) {
      best_total = total;
      best = top[c].rep;
    }
  }
  return best;
}

void Builder::emit(uint32_t fi, const NodePlane& plane) {
  const Frag& f = frags_[fi];
  const Polygon& input = scene_.polygons[f.poly];
  Polygon out;
  out.first_vertex = static_cast<uint32_t>(tree_.vertices.size());
  out.vertex_count = f.count;
  out.face_id = input.face_id;
  out.plane = input.plane;
  for (uint32_t i = 0; i < f.count; ++i) {
    const Vtx& v = verts_[f.first + i];
    // The stored vertex should be the exact point rounded, not the midpoint of a wide interval:
    // a split by a nearly parallel plane gives an ill-conditioned intersection whose interval can
    // be far wider than the point's true error. Past a few ulps, ask for the exact point.
    const double scale = std::max({std::abs(v.mid.x), std::abs(v.mid.y), std::abs(v.mid.z), 1e-300});
    if (!v.exact_double && std::max({v.width.x, v.width.y, v.width.z}) > 0x1p-40 * scale) {
      ++refined_;
      const auto& e = CGAL::exact(v.p);
      tree_.vertices.emplace_back(CGAL::to_double(e.x()), CGAL::to_double(e.y()), CGAL::to_double(e.z()));
    } else {
      tree_.vertices.push_back(v.mid);
    }
    // On an axis-aligned plane (normal ±e_k exactly) the exact vertex has coordinate k equal to
    // ±d, a double: store exactly that, so that floors, ceilings and walls stay exactly flat in
    // the double approximations too (an interval midpoint could be off by an ulp).
    for (int k = 0; k < 3; ++k) {
      const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
      if (std::abs(input.plane.n[k]) == 1.0 && input.plane.n[k1] == 0.0 && input.plane.n[k2] == 0.0)
        tree_.vertices.back()[k] = input.plane.n[k] * input.plane.d;
    }
  }
  tree_.fragments.push_back(out);
  tree_.fragment_polygon.push_back(f.poly);
  const Plane& node = scene_.polygons[plane.poly].plane;
  int8_t orientation = 0;
  if (input.plane.n == node.n && input.plane.d == node.d) {
    orientation = 1;
  } else if (input.plane.n == -node.n && input.plane.d == -node.d) {
    orientation = -1;
  }
  tree_.fragment_orientation.push_back(orientation);
}

void Builder::pushChildren(int32_t node, std::vector<uint32_t>& front, std::vector<uint32_t>& back,
                           std::vector<Task>& stack) {
  const uint32_t depth = tree_.nodes[node].depth;
  for (int side = 0; side < 2; ++side) {
    std::vector<uint32_t>& set = side == 0 ? back : front;
    if (set.empty()) continue;
    const int32_t child = static_cast<int32_t>(tree_.nodes.size());
    BspNode c;
    c.parent = node;
    c.depth = depth + 1;
    tree_.nodes.push_back(c);
    (side == 0 ? tree_.nodes[node].back : tree_.nodes[node].front) = child;
    stack.push_back(Task{child, std::move(set)});
    set = {};
  }
}

bool Builder::separate(const std::vector<uint32_t>& frags, Plane& plane, std::vector<uint32_t>& front,
                       std::vector<uint32_t>& back) {
  if (group_.empty() || frags.size() < 2) return false;
  group_box_.clear();
  group_order_.clear();
  bool detail_only = true;
  detail_only_ = false;
  for (uint32_t fi : frags) {
    const uint32_t g = group_[frags_[fi].poly];
    if (g == kStructureGroup) {
      detail_only = false;
      break;
    }
    if (group_slot_[g] == kNoSlot) {
      group_slot_[g] = static_cast<uint32_t>(group_box_.size());
      group_box_.push_back({glm::dvec3(INFINITY), glm::dvec3(-INFINITY), 0, 0, false, false});
      group_order_.push_back(g);
    }
    GroupBox& box = group_box_[group_slot_[g]];
    ++box.fragments;
    const Frag& f = frags_[fi];
    for (uint32_t i = 0; i < f.count; ++i) {
      const Vtx& v = verts_[f.first + i];
      // mid ± width encloses the exact point; one more ulp outwards covers the rounding of ±.
      for (int k = 0; k < 3; ++k) {
        box.lo[k] = std::min(box.lo[k], v.exact_double ? v.mid[k] : std::nextafter(v.mid[k] - v.width[k], -INFINITY));
        box.hi[k] = std::max(box.hi[k], v.exact_double ? v.mid[k] : std::nextafter(v.mid[k] + v.width[k], INFINITY));
      }
    }
  }
  bool found = false;
  detail_only_ = detail_only;
  if (detail_only && group_box_.size() >= 2) {
    found = axisSeparator(frags.size(), plane) || faceSeparator(frags, plane);
    if (!found) ++inseparable_;
  }
  if (found) {
    for (uint32_t fi : frags) (group_box_[slotOf(fi)].side < 0 ? back : front).push_back(fi);
#ifndef NDEBUG
    // The rule of a separator, checked exactly: every vertex on its group's side or on the plane.
    const NodePlane np{plane.n.x, plane.n.y, plane.n.z, plane.d, kSeparatorPolygon};
    for (uint32_t fi : frags)
      for (uint32_t i = 0; i < frags_[fi].count; ++i)
        assert(classify(verts_[frags_[fi].first + i], np) * group_box_[slotOf(fi)].side >= 0);
#endif
  }
  for (uint32_t g : group_order_) group_slot_[g] = kNoSlot;
  return found;
}

// An axis-aligned plane in a gap between the groups' boxes: per axis (y first: a horizontal plane
// adds no line to the PFD regions at eye height), the groups sorted by their low side, and a gap
// wherever every group so far ends at or before the next one begins. The most balanced gap wins
// (by fragments). The boxes enclose the exact vertices, so the sides need no further test.
bool Builder::axisSeparator(size_t total, Plane& plane) {
  const size_t g = group_box_.size();
  std::vector<uint32_t> order(g);
  double best_score = INFINITY;
  int best_axis = -1;
  double best_c = 0.0;
  size_t best_k = 0;
  const auto sortAlong = [&](int axis) {
    for (uint32_t i = 0; i < g; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return group_box_[a].lo[axis] != group_box_[b].lo[axis] ? group_box_[a].lo[axis] < group_box_[b].lo[axis] : a < b;
    });
  };
  for (int axis : {1, 0, 2}) {
    sortAlong(axis);
    double reach = -INFINITY;
    size_t below = 0;
    for (size_t k = 0; k + 1 < g; ++k) {
      reach = std::max(reach, group_box_[order[k]].hi[axis]);
      below += group_box_[order[k]].fragments;
      const double next = group_box_[order[k + 1]].lo[axis];
      if (!(reach <= next)) continue;
      const double score = std::abs(2.0 * static_cast<double>(below) - static_cast<double>(total));
      if (score < best_score) {
        best_score = score;
        best_axis = axis;
        best_k = k;
        best_c = reach + 0.5 * (next - reach);  // within [reach, next]: both are finite here
      }
    }
  }
  if (best_axis < 0) return false;
  plane.n = glm::dvec3(0.0);
  plane.n[best_axis] = 1.0;
  plane.d = best_c;
  // By position in the sweep, not by the box against c: groups flat in the plane itself may go
  // either way, and both sides must keep at least one group.
  sortAlong(best_axis);
  for (size_t k = 0; k < g; ++k) group_box_[order[k]].side = k <= best_k ? -1 : 1;
  return true;
}

// The plane of one group's face with that group wholly behind it (a face of its hull) and every
// other group wholly on one side; up to kFaceCandidates faces spread over the set are tried, every
// vertex classified exactly. The most balanced such plane wins.
bool Builder::faceSeparator(const std::vector<uint32_t>& frags, Plane& plane) {
  constexpr size_t kFaceCandidates = 32;
  const size_t stride = std::max<size_t>(1, frags.size() / kFaceCandidates);
  const size_t total = frags.size();
  double best_score = INFINITY;
  uint32_t best_poly = kSeparatorPolygon;
  for (size_t c = 0; c < frags.size(); c += stride) {
    const uint32_t poly = frags_[frags[c]].poly;
    const Plane& pl = scene_.polygons[poly].plane;
    const NodePlane np{pl.n.x, pl.n.y, pl.n.z, pl.d, poly};
    for (GroupBox& b : group_box_) b.pos = b.neg = false;
    bool straddles = false;
    for (size_t i = 0; i < frags.size() && !straddles; ++i) {
      const Frag& f = frags_[frags[i]];
      GroupBox& b = group_box_[slotOf(frags[i])];
      for (uint32_t k = 0; k < f.count && !straddles; ++k) {
        const int s = classify(verts_[f.first + k], np);
        b.pos = b.pos || s > 0;
        b.neg = b.neg || s < 0;
        straddles = b.pos && b.neg;
      }
    }
    if (straddles || group_box_[slotOf(frags[c])].pos) continue;
    size_t in_front = 0;
    for (const GroupBox& b : group_box_) in_front += b.pos ? b.fragments : 0;
    if (in_front == 0) continue;
    const double score = std::abs(2.0 * static_cast<double>(in_front) - static_cast<double>(total));
    if (score < best_score) {
      best_score = score;
      best_poly = poly;
      for (GroupBox& b : group_box_) b.side = b.pos ? 1 : -1;
    }
  }
  if (best_poly == kSeparatorPolygon) return false;
  plane = scene_.polygons[best_poly].plane;
  return true;
}

Builder::SideCounts Builder::countSides(std::span<const uint32_t> frags, const Plane& pl) const {
  SideCounts c;
  for (uint32_t fi : frags) {
    const int side = heuristicSide(pl, frags_[fi]);
    c.crossed += side == 2;
    c.front += side == 1;
    c.back += side == -1;
    c.on += side == 0;
  }
  return c;
}

bool Builder::chooseCut(const std::vector<uint32_t>& frags, uint32_t best_polygon_fragment, Plane& plane) {
  if (!detail_only_ || frags.size() < 2) return false;
  const SideCounts polygon = countSides(frags, scene_.polygons[frags_[best_polygon_fragment].poly].plane);
  if (polygon.crossed == 0) return false;  // a free polygon plane costs nothing
  double best = greedyScore(polygon);
  bool found = false;
  for (int axis : {1, 0, 2}) {
    coords_.clear();
    for (uint32_t fi : frags)
      for (uint32_t i = 0; i < frags_[fi].count; ++i) coords_.push_back(hv_[frags_[fi].first + i][axis]);
    const auto mid = coords_.begin() + static_cast<std::ptrdiff_t>(coords_.size() / 2);
    std::nth_element(coords_.begin(), mid, coords_.end());
    Plane cut;
    cut.n = glm::dvec3(0.0);
    cut.n[axis] = 1.0;
    cut.d = *mid;  // a vertex coordinate: rings of vertices on it are not split
    const SideCounts c = countSides(frags, cut);
    const double score = greedyScore(c);
    const bool two_sided = c.crossed > 0 || (c.front > 0 && c.back > 0);
    if (score < best && two_sided) {
      best = score;
      plane = cut;
      found = true;
    }
  }
  return found;
}

uint64_t Builder::run() {
  const size_t n = scene_.polygons.size();
  if (n == 0) return 0;
  // Heuristic tolerance only: a vertex within 1e-9 of the scene's extent counts as on a plane
  // when counting crossings. Classification in the tree itself is exact.
  Bounds b = sceneBounds(scene_);
  const double extent = std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z, std::abs(b.lo.x),
                                  std::abs(b.lo.y), std::abs(b.lo.z), std::abs(b.hi.x), std::abs(b.hi.y),
                                  std::abs(b.hi.z)});
  heuristic_tol_ = 1e-9 * extent;
  // 2^-30 of the extent: 64 times below the float resolution of the frames' vertices (2^-24 of
  // the extent), 2^22 times above the double rounding that puts a shared vertex off its
  // neighbour's plane (2^-52 of it).
  sliver_tol_ = 0x1p-30 * extent;

  verts_.reserve(scene_.vertices.size() * 2);
  hv_.reserve(scene_.vertices.size() * 2);
  frags_.reserve(n * 2);
  boxes_.reserve(n * 2);
  uint32_t groups = 0;
  for (uint32_t g : group_)
    if (g != kStructureGroup) groups = std::max(groups, g + 1);
  group_slot_.assign(groups, kNoSlot);
  std::vector<uint32_t> all(n);
  for (size_t i = 0; i < n; ++i) {
    const Polygon& poly = scene_.polygons[i];
    const Plane& pl = poly.plane;
    std::optional<K::Plane_3> kplane;
    const uint32_t first = static_cast<uint32_t>(verts_.size());
    for (const glm::dvec3& v : scene_.polygonVertices(poly)) {
      if (exact::planeSign(pl.n.x, pl.n.y, pl.n.z, pl.d, v.x, v.y, v.z) == 0) {
        pushVtx(Vtx{EPoint(v.x, v.y, v.z), v, glm::dvec3(0.0), true});
      } else {
        if (!kplane) kplane.emplace(pl.n.x, pl.n.y, pl.n.z, -pl.d);
        pushVtx(makeVtx(kplane->projection(EPoint(v.x, v.y, v.z))));
      }
    }
    pushFrag(Frag{static_cast<uint32_t>(i), first, poly.vertex_count});
    all[i] = static_cast<uint32_t>(i);
  }

  std::vector<Task> stack;
  tree_.nodes.emplace_back();
  tree_.root = 0;
  stack.push_back(Task{0, std::move(all)});
  std::vector<uint32_t> on, front, back;
  while (!stack.empty()) {
    Task task = std::move(stack.back());
    stack.pop_back();
    on.clear();
    front.clear();
    back.clear();
    Plane separator;
    if (separate(task.frags, separator, front, back)) {
      ++separators_;
      emptyNode(task, separator, front, back, stack);
      continue;
    }
    // Not with free_first: its rule (a free plane first) would be overruled by the rollouts.
    const bool pilot = options_.heuristic == SplitHeuristic::kLeastCrossed && options_.pilot_candidates > 1 &&
                       !options_.free_first &&
                       task.frags.size() >= std::max<uint32_t>(2, options_.pilot_min_set) &&
                       tree_.nodes[task.node].depth <= options_.pilot_depth_max &&
                       pilotAffordable(task.frags.size());
    const uint32_t splitter = pilot ? choosePilot(task.frags) : chooseSplitter(task.frags);
    Plane cut;
    if (chooseCut(task.frags, splitter, cut)) {
      const NodePlane cut_plane{cut.n.x, cut.n.y, cut.n.z, cut.d, kSeparatorPolygon};
      const uint64_t slivers_before = slivers_;
      partition(task.frags, cut_plane, on, front, back);
      // Fragments in the cut plane go to the side they face: either side orders them right.
      for (uint32_t fi : on) (glm::dot(scene_.polygons[frags_[fi].poly].plane.n, cut.n) > 0.0 ? front : back).push_back(fi);
      on.clear();
      if (front.empty() || back.empty()) {
        // The exact sides put everything on one side (nothing was split, and no sliver it dropped
        // counts): a polygon plane instead.
        front.clear();
        back.clear();
        slivers_ = slivers_before;
      }
    }
    if (!front.empty()) {
      ++cuts_;
      emptyNode(task, cut, front, back, stack);
      continue;
    }
    const uint32_t poly = frags_[splitter].poly;
    const Plane& pl = scene_.polygons[poly].plane;
    const NodePlane plane{pl.n.x, pl.n.y, pl.n.z, pl.d, poly};
    partition(task.frags, plane, on, front, back);
    task.frags = {};  // release before the children's sets grow
    // The splitter first, so a node's first fragment lies on the node's own input polygon.
    auto it = std::find(on.begin(), on.end(), splitter);
    if (it != on.end()) std::iter_swap(on.begin(), it);

    BspNode& node = tree_.nodes[task.node];
    node.plane = pl;
    node.polygon = poly;
    node.first_fragment = static_cast<uint32_t>(tree_.fragments.size());
    node.fragment_count = static_cast<uint32_t>(on.size());
    for (uint32_t fi : on) emit(fi, plane);
    pushChildren(task.node, front, back, stack);
  }
  tree_.stats.detail_separators = separators_;
  tree_.stats.detail_inseparable = inseparable_;
  tree_.stats.detail_cuts = cuts_;
  tree_.stats.slivers_dropped = slivers_;
  return fallbacks_;
}

}  // namespace

uint64_t buildBspExact(const Scene& scene, const BspOptions& options, const DetailGroups& groups, BspTree& tree) {
  Builder builder(scene, options, groups, tree);
  return builder.run();
}

}  // namespace detail
}  // namespace walkvis
