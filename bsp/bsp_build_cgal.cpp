// Autopartition BSP build with exact classification.
// Source: H. Fuchs, Z. M. Kedem, B. F. Naylor, "On visible surface generation by a priori tree
// structures", SIGGRAPH 1980 (autopartition: node plane = plane of one of its polygons, coplanar
// polygons stay at the node, straddlers are split). Splitting-plane choice: least-crossed among a
// few sampled candidates with a balance tie-break, or random-order autopartition (Paterson and
// Yao, "Efficient binary space partitions for hidden-surface removal and solid modeling", 1990).
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
// lazy points' memory (~100-200 bytes for a projected or constructed vertex, ~60 for a plain one)
// and roughly 2x in time; exact evaluations themselves stay rare (see `walkvis bench bsp`).
// The splitting-plane HEURISTIC uses plain doubles with a tolerance: it only picks a plane, so
// it needs no exactness.
//
// Splitting-plane choice (least-crossed), by node size m: m <= lookahead_max, every distinct
// plane with one level of lookahead; else, when m × (distinct planes) <= full_count_max, every
// distinct plane counted on the whole set (a bounding-box filter settles most plane/fragment
// pairs); else `candidates` planes scored on `samples` fragments. In both exact modes a "free"
// plane (crossing none of the set, cf. the free cuts of Paterson and Yao 1990) may be taken first
// (free_first), and horizontal planes' crossings weigh horizontal_weight. Measured on
// freedoom2.wad MAP10 (n 6,862, `walkvis bench bsp`): sampling only 1.724, + lookahead 1.700,
// + full count 1.626, + free first 1.630 (but MAP26 1.466 -> 1.429, MAP14 1.444 -> 1.432),
// + horizontal_weight 0.5 1.606. Free first is off by default: it doubles the mean depth (MAP10
// 14.1 -> 34.3, MAP26 11.3 -> 31.1) for N/n 1.611 -> 1.606. Split weights 5..1000, lookahead up
// to 1,024 and seeds change N/n by < 0.03.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/intersections.h>

#include <algorithm>
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

class Builder {
 public:
  Builder(const Scene& scene, const BspOptions& options, BspTree& tree)
      : scene_(scene), options_(options), tree_(tree), rng_(options.seed) {}

  uint64_t run();

 private:
  int classify(const Vtx& v, const NodePlane& p);
  void partition(const std::vector<uint32_t>& in, const NodePlane& plane, std::vector<uint32_t>& on,
                 std::vector<uint32_t>& front, std::vector<uint32_t>& back);
  uint32_t chooseSplitter(const std::vector<uint32_t>& frags);
  uint32_t chooseWithLookahead(const std::vector<uint32_t>& frags);
  std::optional<uint32_t> chooseByFullCount(const std::vector<uint32_t>& frags);
  int boxSide(const Plane& pl, uint32_t fi) const;
  // Factor on a candidate's crossing count: horizontal_weight for a horizontal plane (normal ±y).
  double crossWeight(const Plane& pl) const {
    return pl.n.x == 0.0 && pl.n.z == 0.0 ? options_.horizontal_weight : 1.0;
  }
  void pushFrag(const Frag& f);
  int heuristicSide(const Plane& pl, const Frag& f) const;
  void emit(uint32_t frag, const NodePlane& plane);
  uint64_t randomBelow(uint64_t n) { return rng_() % n; }  // bias < n / 2^64: irrelevant here

  const Scene& scene_;
  const BspOptions& options_;
  BspTree& tree_;
  std::mt19937_64 rng_;
  std::vector<Vtx> verts_;
  std::vector<Frag> frags_;
  std::vector<Box> boxes_;  // per fragment, parallel to frags_
  std::vector<int8_t> sides_;     // scratch
  std::vector<uint32_t> sample_;  // scratch
  std::vector<uint32_t> reps_;    // scratch of chooseWithLookahead: one fragment per distinct plane
  std::vector<uint64_t> masks_;   // scratch of chooseWithLookahead: per plane, split/front/back/on bitsets
  uint64_t fallbacks_ = 0;
  uint64_t refined_ = 0;  // stored vertices rounded from the exact point
  double heuristic_tol_ = 0.0;
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
  const Plane& node = scene_.polygons[plane.poly].plane;
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
      if (!kplane) kplane.emplace(plane.a, plane.b, plane.c, -plane.d);
      // Straddler: walk the loop once, vertices with side >= 0 go front, <= 0 go back, and each
      // edge whose ends are strictly on opposite sides adds its exact intersection to both.
      const uint32_t front_first = static_cast<uint32_t>(verts_.size());
      std::vector<Vtx> back_verts;
      back_verts.reserve(f.count + 2);
      for (uint32_t i = 0; i < f.count; ++i) {
        const uint32_t j = (i + 1) % f.count;
        const Vtx vi = verts_[f.first + i];
        if (sides_[i] >= 0) verts_.push_back(vi);
        if (sides_[i] <= 0) back_verts.push_back(vi);
        if (sides_[i] * sides_[j] < 0) {
          const K::Segment_3 seg(vi.p, verts_[f.first + j].p);
          const auto hit = CGAL::intersection(seg, *kplane);
          const EPoint* ip = hit ? boost::get<EPoint>(&*hit) : nullptr;
          if (!ip) throw std::logic_error("bsp: exact split found no intersection point");
          const Vtx x = makeVtx(*ip);
          verts_.push_back(x);
          back_verts.push_back(x);
        }
      }
      const uint32_t front_count = static_cast<uint32_t>(verts_.size()) - front_first;
      pushFrag(Frag{f.poly, front_first, front_count});
      front.push_back(static_cast<uint32_t>(frags_.size() - 1));
      const uint32_t back_first = static_cast<uint32_t>(verts_.size());
      for (auto& v : back_verts) verts_.push_back(std::move(v));
      pushFrag(Frag{f.poly, back_first, static_cast<uint32_t>(back_verts.size())});
      back.push_back(static_cast<uint32_t>(frags_.size() - 1));
    }
  }
}

// Side of a fragment for the heuristic (doubles with a tolerance): 2 = crossed, 1 = front,
// -1 = back, 0 = on.
int Builder::heuristicSide(const Plane& pl, const Frag& f) const {
  bool pos = false, neg = false;
  for (uint32_t i = 0; i < f.count; ++i) {
    const double v = glm::dot(pl.n, verts_[f.first + i].mid) - pl.d;
    pos = pos || v > heuristic_tol_;
    neg = neg || v < -heuristic_tol_;
  }
  return pos && neg ? 2 : pos ? 1 : neg ? -1 : 0;
}

// Least crossed with one level of lookahead, for small sets, where most splits happen (on
// freedoom2 MAP10, 64% of the splits of the plain least-crossed tree were made at nodes of <= 64
// fragments). Plain least-crossed is greedy: around a pillar standing on a floor it takes a
// pillar wall (it crosses one floor piece) and later pays again for every other wall, where the
// floor plane (crossing nothing, all floor pieces coplanar) would have separated them for free.
// Here every distinct plane of the set is a candidate and is scored, on the whole set, by
//   split_weight · (crossed(c) + min_p crossed_F(p) + min_p crossed_B(p)) + |F − B| − coplanar_weight · on(c)
// where F and B are the fragments c sends front and back (crossed ones in both) and
// min_p crossed_F(p) is the fewest of F that any plane of a fragment of F crosses: the best next
// split on each side. A crossed fragment's pieces are counted as the whole fragment (an estimate:
// a piece may miss a plane its parent crossed). Cost: sides of all m fragments against all
// P <= m distinct planes (m·P vertex tests), then P² bitset intersections of m bits.
uint32_t Builder::chooseWithLookahead(const std::vector<uint32_t>& frags) {
  const size_t m = frags.size();
  const size_t words = (m + 63) / 64;
  reps_.clear();
  for (uint32_t fi : frags) {
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
  auto bestNext = [&](const std::vector<uint64_t>& set) {
    int64_t best = -1;
    for (size_t p = 0; p < planes; ++p) {
      const uint64_t* on = mask(p, 3);
      const uint64_t* crossed = mask(p, 0);
      bool present = false;
      int64_t c = 0;
      for (size_t w = 0; w < words; ++w) {
        present = present || (on[w] & set[w]) != 0;
        c += std::popcount(crossed[w] & set[w]);
      }
      if (present && (best < 0 || c < best)) {
        best = c;
        if (best == 0) break;
      }
    }
    return std::max<int64_t>(best, 0);
  };
  std::vector<uint64_t> front_set(words), back_set(words);
  double best_score = INFINITY;
  uint32_t best = reps_[0];
  if (options_.free_first) {
    // A free plane (crossing nothing) first, the most balanced one; see chooseByFullCount.
    for (size_t c = 0; c < planes; ++c) {
      if (count(mask(c, 0)) != 0) continue;
      const double score = static_cast<double>(std::abs(count(mask(c, 1)) - count(mask(c, 2))));
      if (score < best_score) {
        best_score = score;
        best = reps_[c];
      }
    }
    if (best_score < INFINITY) return best;
  }
  for (size_t c = 0; c < planes; ++c) {
    const uint64_t *crossed = mask(c, 0), *front = mask(c, 1), *back = mask(c, 2);
    for (size_t w = 0; w < words; ++w) {
      front_set[w] = front[w] | crossed[w];
      back_set[w] = back[w] | crossed[w];
    }
    const int64_t splits = count(crossed);
    const int64_t nf = count(front_set.data()), nb = count(back_set.data());
    const int64_t on = count(mask(c, 3));
    // A lower bound on the score without the lookahead: skip the lookahead when it cannot win.
    const double base = options_.split_weight * crossWeight(scene_.polygons[frags_[reps_[c]].poly].plane) *
                            static_cast<double>(splits) +
                        static_cast<double>(std::abs(nf - nb)) -
                        options_.coplanar_weight * static_cast<double>(on);
    if (base >= best_score) continue;
    const int64_t next = (nf > 0 ? bestNext(front_set) : 0) + (nb > 0 ? bestNext(back_set) : 0);
    const double score = base + options_.split_weight * static_cast<double>(next);
    if (score < best_score) {
      best_score = score;
      best = reps_[c];
    }
  }
  return best;
}

void Builder::pushFrag(const Frag& f) {
  Box b{verts_[f.first].mid, verts_[f.first].mid};
  for (uint32_t i = 1; i < f.count; ++i) {
    b.lo = glm::min(b.lo, verts_[f.first + i].mid);
    b.hi = glm::max(b.hi, verts_[f.first + i].mid);
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
std::optional<uint32_t> Builder::chooseByFullCount(const std::vector<uint32_t>& frags) {
  const size_t m = frags.size();
  if (options_.full_count_max == 0) return std::nullopt;
  // Distinct planes: key on the coefficients made canonical (first nonzero normal component > 0).
  struct Key {
    double a, b, c, d;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      uint64_t h = 1469598103934665603ull;
      for (double v : {k.a, k.b, k.c, k.d}) {
        h ^= std::bit_cast<uint64_t>(v + 0.0);  // + 0.0: -0.0 and 0.0 hash alike
        h *= 1099511628211ull;
      }
      return static_cast<size_t>(h);
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
      return std::nullopt;
  }
  double best_score = INFINITY;
  bool best_free = false;
  uint32_t best = reps_[0];
  for (uint32_t rep : reps_) {
    const Plane& pl = scene_.polygons[frags_[rep].poly].plane;
    const double weight = options_.split_weight * crossWeight(pl);
    int64_t crossed = 0, front = 0, back = 0;
    bool pruned = false;
    for (uint32_t fi : frags) {
      const int side = boxSide(pl, fi);
      if (side == 2) {
        ++crossed;
        // Past this, the plane cannot beat the best: a free one, or a lower lower bound.
        if (best_free || weight * static_cast<double>(crossed) >= best_score) {
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
    const double score = weight * static_cast<double>(crossed) + static_cast<double>(std::abs(front - back));
    if ((is_free && !best_free) || (is_free == best_free && score < best_score)) {
      best_score = score;
      best_free = is_free;
      best = rep;
    }
  }
  return best;
}

uint32_t Builder::chooseSplitter(const std::vector<uint32_t>& frags) {
  const size_t m = frags.size();
  if (m == 1) return frags[0];
  if (options_.heuristic == SplitHeuristic::kRandom) return frags[randomBelow(m)];
  if (m <= options_.lookahead_max) return chooseWithLookahead(frags);
  if (const auto full = chooseByFullCount(frags)) return *full;

  // Least crossed: each candidate plane is scored on a sample of the set (all of it when small),
  // enough to rank candidates, few enough that the choice costs O(candidates · samples) per node.
  const size_t k = std::max<size_t>(1, std::min<size_t>(options_.candidates, m));
  double best_score = INFINITY;
  uint32_t best = frags[0];
  const size_t max_samples = std::max<size_t>(1, options_.samples);
  const bool all_samples = m <= max_samples;
  const size_t samples = all_samples ? m : max_samples;
  sample_.resize(samples);
  for (size_t i = 0; i < samples; ++i) sample_[i] = all_samples ? frags[i] : frags[randomBelow(m)];
  for (size_t c = 0; c < k; ++c) {
    const uint32_t cand = m <= k ? frags[c] : frags[randomBelow(m)];
    const Plane& pl = scene_.polygons[frags_[cand].poly].plane;
    int64_t splits = 0, front = 0, back = 0, on = 0;
    for (uint32_t fi : sample_) {
      const Frag& f = frags_[fi];
      bool pos = false, neg = false;
      for (uint32_t i = 0; i < f.count; ++i) {
        const double v = glm::dot(pl.n, verts_[f.first + i].mid) - pl.d;
        pos = pos || v > heuristic_tol_;
        neg = neg || v < -heuristic_tol_;
      }
      if (pos && neg) {
        ++splits;
      } else if (pos) {
        ++front;
      } else if (neg) {
        ++back;
      } else {
        ++on;
      }
    }
    const double score = options_.split_weight * static_cast<double>(splits) -
                         options_.coplanar_weight * static_cast<double>(on) +
                         static_cast<double>(std::abs(front - back));
    if (score < best_score) {
      best_score = score;
      best = cand;
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

  verts_.reserve(scene_.vertices.size() * 2);
  frags_.reserve(n * 2);
  boxes_.reserve(n * 2);
  std::vector<uint32_t> all(n);
  for (size_t i = 0; i < n; ++i) {
    const Polygon& poly = scene_.polygons[i];
    const Plane& pl = poly.plane;
    std::optional<K::Plane_3> kplane;
    const uint32_t first = static_cast<uint32_t>(verts_.size());
    for (const glm::dvec3& v : scene_.polygonVertices(poly)) {
      if (exact::planeSign(pl.n.x, pl.n.y, pl.n.z, pl.d, v.x, v.y, v.z) == 0) {
        verts_.push_back(Vtx{EPoint(v.x, v.y, v.z), v, glm::dvec3(0.0), true});
      } else {
        if (!kplane) kplane.emplace(pl.n.x, pl.n.y, pl.n.z, -pl.d);
        verts_.push_back(makeVtx(kplane->projection(EPoint(v.x, v.y, v.z))));
      }
    }
    pushFrag(Frag{static_cast<uint32_t>(i), first, poly.vertex_count});
    all[i] = static_cast<uint32_t>(i);
  }

  struct Task {
    int32_t node;
    std::vector<uint32_t> frags;
  };
  std::vector<Task> stack;
  tree_.nodes.emplace_back();
  tree_.root = 0;
  stack.push_back(Task{0, std::move(all)});
  std::vector<uint32_t> on, front, back;
  while (!stack.empty()) {
    Task task = std::move(stack.back());
    stack.pop_back();
    const uint32_t splitter = chooseSplitter(task.frags);
    const uint32_t poly = frags_[splitter].poly;
    const Plane& pl = scene_.polygons[poly].plane;
    const NodePlane plane{pl.n.x, pl.n.y, pl.n.z, pl.d, poly};
    on.clear();
    front.clear();
    back.clear();
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
    const uint32_t depth = node.depth;
    // Back pushed first so the front subtree is built (and its fragments numbered) first.
    for (int side = 0; side < 2; ++side) {
      std::vector<uint32_t>& set = side == 0 ? back : front;
      if (set.empty()) continue;
      const int32_t child = static_cast<int32_t>(tree_.nodes.size());
      BspNode c;
      c.parent = task.node;
      c.depth = depth + 1;
      tree_.nodes.push_back(c);
      (side == 0 ? tree_.nodes[task.node].back : tree_.nodes[task.node].front) = child;
      stack.push_back(Task{child, std::move(set)});
      set = {};
    }
  }
  return fallbacks_;
}

}  // namespace

uint64_t buildBspExact(const Scene& scene, const BspOptions& options, BspTree& tree) {
  Builder builder(scene, options, tree);
  return builder.run();
}

}  // namespace detail
}  // namespace walkvis
