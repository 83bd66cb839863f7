// Clustered backface culling: Johannsen & Carter, "Clustered Backface Culling", Journal of
// Graphics Tools 3(1), 1998 [JohannsenCarter1998].
//
// §2.1 test: a cluster with normals n_i and plane offsets n_i·p_i is all back-facing from e when
//   Comp_e'(N, M)·e' − d <= 0,   e' = e − b,   N = min_i n_i,  M = max_i n_i (component-wise),
//   d = min_i n_i·(p_i − b),    Comp picks N^c where e'^c <= 0 and M^c where e'^c > 0      (8)
// stored in single precision as N, M, d, b: 40 bytes (§2.4). §2.3 hierarchy: inner nodes merge
// their children (N* = min, M* = max — the printed formula says min for M*, a slip: docs/DESIGN.md,
// "Corrections"),
// re-choose b* and recompute d* over their polygons, and add the front-face test
//   Comp_e'(−M, −N)·e' + max_i n_i·(p_i − b) <= 0  (4 more bytes)
// so traversal stops at clusters that are all back-facing (culled) or all front-facing (kept).
// §2.4/§3 origin b: the 8 corners of the cluster's bounding box and its centroid, the one with the
// highest near-field culling probability (the share of the R×R×R box around b, R = 10 × the
// model's bounding-box diagonal, in which (8) culls).
// Walkthroughs (ours): with options.cluster_eye_lo/hi set, the probability is the share of that
// fixed eye box instead of the box around b (boxCullProbability); see backface.h for why the box
// around b merges every wall orientation of a building into one unculled cluster.
// §3 Algorithm 1, adapted to polygon lists (a polygon plays a tristrip, its vertex count its
// rendering cost C/R): seed = the remaining polygon with the highest culling probability; add the
// remaining polygons in order of decreasing n·n_seed while the merge pays off by the cost model;
// recur on the rest (ours: near-parallel candidates nearest plane first, so coplanar pieces of
// one wall merge before a parallel wall ends the growth, and a level cut into BSP fragments forms far
// fewer clusters: docs/backface/README.md, "Clustered backface test"). T/R: options.cluster_tr, by
// default clusterTrFor(polygon count). The merge condition: the paper's derivation
//   T + (1 − P_C)·C_C < 2T + (1 − P_A)·C_A + (1 − P_B)·C_B
// gives P_C > (P_A·C_A + P_B·C_B − T) / (C_A + C_B); the printed (9)/(10) carry +T, a sign slip
// (with +T a merge could never pass, since merging never raises the culling probability above the
// parts' weighted mean). We use −T. A cluster is capped at kMaxClusterPolygons (ours: keeps the
// build O(n·cap) on large coplanar regions).
//
// Per frame (ours): without the hierarchy (the default) every leaf test is evaluated,
// eight clusters per block of structure-of-arrays floats, a block per AVX2 operation where the CPU
// has AVX2 (checked at build) and four clusters per SSE operation otherwise, with
// Comp_e'(N, M)·e' = Σ_c max(N^c·e'^c, M^c·e'^c) (no branch), the flags written 8 bytes at a time;
// a cluster costs a small fraction of a node of the branchy §2.3 traversal (docs/backface/README.md,
// "Hierarchy"), so the hierarchy's saved tests no longer pay (cluster_hierarchy keeps it, evaluated
// as before). The flat pass evaluates in single precision with its own margin (kFloatMargin),
// relative to an origin at the centre of the model's box (b is stored relative to it), as a
// camera-relative renderer would, so that a model far from the world origin keeps its float resolution.
// Conservative arithmetic: the stored floats are rounded outward (N down, M up, d down, front-test
// offset up), which only weakens the test; (8) is then evaluated in double with the margin
// kRelMargin·(|e|₁ + scale) below zero.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "backface/backface.h"
#include "backface/spread_bits.h"
#include "core/check.h"

namespace walkvis {
namespace {

constexpr size_t kMaxClusterPolygons = 1024;
constexpr size_t kCandidateBatch = 256;  // candidates sorted per batch by n·n_seed
// Weight of the plane offset difference (a share of the largest) in the candidate order: below the
// 1 − cos gap of normals more than ~4e-5 rad apart, so it only orders near-parallel planes.
constexpr double kOffsetTieWeight = 1e-9;
// Rounding of (8) in double, of d and of the ground truth isFrontFacing() together stay below
// 12·2⁻⁵³·(|e|₁ + |b|₁ + |d| + |n·p|) ≈ 1.4e-15 of those magnitudes; 1e-12 leaves three orders.
constexpr double kRelMargin = 1e-12;
// Normal components whose coefficient is below this share of the largest are treated as zero in
// the probability integral (a heuristic estimate only; keeps the inclusion–exclusion formula from
// cancelling catastrophically).
constexpr double kTinyCoefficient = 1e-3;

float floatDown(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -INFINITY);
  return f;
}
float floatUp(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, INFINITY);
  return f;
}

// x rounded to single precision, as a double. Out of line: GCC 12.2 -O2 dropped the x and y
// roundings of an inlined `glm::dvec3 b(static_cast<float>(c.x), ...)` in choose() (seen in the
// object code: one cvtsd2ss of three), which stored an origin b other than the one d was
// computed for and culled front faces far from the origin (test FarFromOriginNoFrontFaceCulled).
[[gnu::noinline]] double toFloatPrecision(double x) {
  volatile float f = static_cast<float>(x);
  return static_cast<double>(f);
}

// Share of the unit cube [0,1]³ where a·t <= d.
double cubeFraction(std::array<double, 3> a, double d) {
  for (double& c : a) {
    if (c < 0.0) {  // t → 1 − t turns a negative coefficient positive
      d -= c;
      c = -c;
    }
  }
  const double amax = std::max({a[0], a[1], a[2]});
  std::array<double, 3> kept{};
  int k = 0;
  for (double c : a) {
    if (c > kTinyCoefficient * amax) kept[static_cast<size_t>(k++)] = c;
  }
  if (k == 0) return d >= 0.0 ? 1.0 : 0.0;
  double prod = 1.0, fact = 1.0;
  for (int i = 0; i < k; ++i) {
    prod *= kept[static_cast<size_t>(i)];
    fact *= i + 1;
  }
  double sum = 0.0;
  for (int s = 0; s < (1 << k); ++s) {
    double shift = d;
    int bits = 0;
    for (int i = 0; i < k; ++i) {
      if (s & (1 << i)) {
        shift -= kept[static_cast<size_t>(i)];
        ++bits;
      }
    }
    if (shift > 0.0) sum += ((bits & 1) ? -1.0 : 1.0) * std::pow(shift, k);
  }
  return std::clamp(sum / (fact * prod), 0.0, 1.0);
}

struct Test {  // §2.4: 40 bytes
  float n[3], m[3], b[3], d;
};
static_assert(sizeof(Test) == 40);

struct Node {  // preorder; a leaf is one cluster
  Test test;
  float front_d;           // max_i n_i·(p_i − b), rounded up (the front test's extra 4 bytes)
  uint32_t leaf_begin;     // leaves of the subtree, contiguous in preorder
  uint32_t leaf_end;
  uint32_t skip;           // the node after this subtree
};

// The flat pass (no hierarchy): the leaves' 40-byte tests regrouped as structure of arrays,
// kLanes clusters per block, tested four at a time with SSE (x86-64's baseline; the project sets
// no -march) and a scalar loop elsewhere.
constexpr size_t kLanes = 8;
struct alignas(16) LeafBlock {
  float n[3][kLanes], m[3][kLanes], b[3][kLanes], d[kLanes];  // N, M, b − origin, d; padding never culls
};
// Rounding of the flat test in single precision: float(e − origin) and e' = e − b cost
// 2⁻²⁴(2|e|₁ + |b|₁), the products, maxima and three sums at most 2⁻²⁴(4(|e|₁ + |b|₁) + 3|d|)
// more (|N^c|, |M^c| <= 1), so below 2⁻²⁴·6·(|e|₁ + |b|₁ + |d|) in all; 16 leaves a factor 2.6.
constexpr double kFloatMargin = 16.0 * 0x1p-24;
// |e − origin| beyond this: single precision would overflow or cannot resolve the model; the flat
// pass then culls nothing (a model 1e30 away from the eye is not drawn anyway).
constexpr double kMaxFloatEye = 1e30;

// Bit l set when lane l of the block culls: Σ_c max(N^c·e'^c, M^c·e'^c) − d <= limit. The scalar,
// SSE and AVX2 versions do the same single-precision operations in the same order (no FMA), so
// they give the same bits (test ClusterSimdPathsAgree).
inline unsigned blockBitsScalar(const LeafBlock& blk, float fx, float fy, float fz, float limit) {
  unsigned bits = 0;
  for (size_t l = 0; l < kLanes; ++l) {
    const float x = fx - blk.b[0][l], y = fy - blk.b[1][l], z = fz - blk.b[2][l];
    const float sx = std::max(blk.n[0][l] * x, blk.m[0][l] * x);
    const float sy = std::max(blk.n[1][l] * y, blk.m[1][l] * y);
    const float sz = std::max(blk.n[2][l] * z, blk.m[2][l] * z);
    const float back = ((sx + sy) + sz) - blk.d[l];
    bits |= static_cast<unsigned>(back <= limit) << l;
  }
  return bits;
}

#if defined(__SSE2__)
inline unsigned blockBitsSse(const LeafBlock& blk, float fx, float fy, float fz, float limit) {
  unsigned bits = 0;
  const __m128 ex = _mm_set1_ps(fx), ey = _mm_set1_ps(fy), ez = _mm_set1_ps(fz), lim = _mm_set1_ps(limit);
  for (size_t h = 0; h < kLanes; h += 4) {
    const __m128 x = _mm_sub_ps(ex, _mm_load_ps(blk.b[0] + h));
    const __m128 y = _mm_sub_ps(ey, _mm_load_ps(blk.b[1] + h));
    const __m128 z = _mm_sub_ps(ez, _mm_load_ps(blk.b[2] + h));
    const __m128 sx = _mm_max_ps(_mm_mul_ps(_mm_load_ps(blk.n[0] + h), x), _mm_mul_ps(_mm_load_ps(blk.m[0] + h), x));
    const __m128 sy = _mm_max_ps(_mm_mul_ps(_mm_load_ps(blk.n[1] + h), y), _mm_mul_ps(_mm_load_ps(blk.m[1] + h), y));
    const __m128 sz = _mm_max_ps(_mm_mul_ps(_mm_load_ps(blk.n[2] + h), z), _mm_mul_ps(_mm_load_ps(blk.m[2] + h), z));
    const __m128 back = _mm_sub_ps(_mm_add_ps(_mm_add_ps(sx, sy), sz), _mm_load_ps(blk.d + h));
    bits |= static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(back, lim))) << h;
  }
  return bits;
}

// One block per 8-lane operation. AVX2 is not in the project's baseline flags: the culler checks
// the CPU once at build (__builtin_cpu_supports) and uses SSE otherwise.
[[gnu::target("avx2")]] void flatPassAvx2(const LeafBlock* blocks, size_t count, float fx, float fy, float fz,
                                          float limit, uint8_t* out, size_t units) {
  static_assert(kLanes == 8);
  const __m256 ex = _mm256_set1_ps(fx), ey = _mm256_set1_ps(fy), ez = _mm256_set1_ps(fz), lim = _mm256_set1_ps(limit);
  const size_t full = units / kLanes;
  for (size_t k = 0; k < count; ++k) {
    const LeafBlock& blk = blocks[k];
    const __m256 x = _mm256_sub_ps(ex, _mm256_load_ps(blk.b[0]));
    const __m256 y = _mm256_sub_ps(ey, _mm256_load_ps(blk.b[1]));
    const __m256 z = _mm256_sub_ps(ez, _mm256_load_ps(blk.b[2]));
    const __m256 sx = _mm256_max_ps(_mm256_mul_ps(_mm256_load_ps(blk.n[0]), x), _mm256_mul_ps(_mm256_load_ps(blk.m[0]), x));
    const __m256 sy = _mm256_max_ps(_mm256_mul_ps(_mm256_load_ps(blk.n[1]), y), _mm256_mul_ps(_mm256_load_ps(blk.m[1]), y));
    const __m256 sz = _mm256_max_ps(_mm256_mul_ps(_mm256_load_ps(blk.n[2]), z), _mm256_mul_ps(_mm256_load_ps(blk.m[2]), z));
    const __m256 back = _mm256_sub_ps(_mm256_add_ps(_mm256_add_ps(sx, sy), sz), _mm256_load_ps(blk.d));
    const unsigned bits = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(back, lim, _CMP_LE_OQ)));
    const uint64_t bytes = kSpread[bits];
    std::memcpy(out + k * kLanes, &bytes, k < full ? kLanes : units - k * kLanes);
  }
}
#endif

bool cpuHasAvx2() {
#if defined(__SSE2__) && (defined(__x86_64__) || defined(__i386__))
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

// The flat pass of the best path the CPU has, at most `simd`.
BackfaceSimd resolveSimd(BackfaceSimd simd) {
#if defined(__SSE2__)
  const BackfaceSimd best = cpuHasAvx2() ? BackfaceSimd::kAvx2 : BackfaceSimd::kSse2;
#else
  const BackfaceSimd best = BackfaceSimd::kScalar;
#endif
  if (simd == BackfaceSimd::kAuto) return best;
  return static_cast<int>(simd) < static_cast<int>(best) ? simd : best;
}

struct PolyData {
  glm::dvec3 n;
  double dd;  // plane offset n·p
  glm::dvec3 lo, hi, sum;
  double vertices;
};

struct Stats {
  glm::dvec3 n_min{INFINITY}, n_max{-INFINITY}, lo{INFINITY}, hi{-INFINITY}, sum{0.0};
  double count = 0.0;  // vertices summed into `sum`
  double cost = 0.0;   // vertices: rendering cost over R
  void add(const PolyData& p) {
    n_min = glm::min(n_min, p.n);
    n_max = glm::max(n_max, p.n);
    lo = glm::min(lo, p.lo);
    hi = glm::max(hi, p.hi);
    sum += p.sum;
    count += p.vertices;
    cost += p.vertices;
  }
};

struct Choice {
  double probability = -1.0;
  glm::dvec3 b{0.0};        // world coordinates: origin + b_local, the b that d is computed for
  glm::dvec3 b_local{0.0};  // single-precision values, relative to the culler's origin
  double d = 0.0;
};

class ClusterCuller final : public BackfaceCuller {
 public:
  ClusterCuller(const BackfaceInput& input, const BackfaceOptions& options)
      : hierarchy_(options.cluster_hierarchy), simd_(resolveSimd(options.simd)) {
    if (!(options.cluster_near_field > 0.0)) throw Error("backface cluster: cluster_near_field must be > 0");
    const size_t count = input.polygons.size();
    polygon_count_ = count;
    polys_.resize(count);
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (size_t i = 0; i < count; ++i) {
      const Polygon& poly = input.polygons[i];
      PolyData& p = polys_[i];
      p.n = poly.plane.n;
      p.dd = poly.plane.d;
      p.lo = glm::dvec3(INFINITY);
      p.hi = glm::dvec3(-INFINITY);
      p.sum = glm::dvec3(0.0);
      for (uint32_t k = 0; k < poly.vertex_count; ++k) {
        const glm::dvec3& v = input.vertices[poly.first_vertex + k];
        p.lo = glm::min(p.lo, v);
        p.hi = glm::max(p.hi, v);
        p.sum += v;
      }
      p.vertices = poly.vertex_count;
      lo = glm::min(lo, p.lo);
      hi = glm::max(hi, p.hi);
      max_dd_ = std::max(max_dd_, std::abs(p.dd));
    }
    const double diag = count ? glm::length(hi - lo) : 0.0;
    half_ = 0.5 * options.cluster_near_field * (diag > 0.0 ? diag : 1.0);
    const glm::dvec3& elo = options.cluster_eye_lo;
    const glm::dvec3& ehi = options.cluster_eye_hi;
    eye_box_ = elo.x <= ehi.x && elo.y <= ehi.y && elo.z <= ehi.z;
    if (eye_box_) {
      for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(elo[k]) || !std::isfinite(ehi[k])) throw Error("backface cluster: the eye box is not finite");
      }
      if (elo == ehi) throw Error("backface cluster: the eye box is a point");
      eye_lo_ = elo;
      eye_hi_ = ehi;
    }

    // Camera-relative origin (as the cone peer's float positions): b is stored relative to the
    // centre of the model's box, so single precision resolves features far from the world origin.
    origin_ = count ? 0.5 * (lo + hi) : glm::dvec3(0.0);
    formClusters(clusterTrFor(count, options.cluster_tr));
    buildNodes();
    // scale_: the magnitudes the rounding of the tests is relative to (local coordinates), with
    // room for the double rounding of e − origin and origin + b (2⁻⁵³ of |origin|).
    scale_ = max_dd_ + std::abs(origin_.x) + std::abs(origin_.y) + std::abs(origin_.z);
    for (const Node& node : nodes_) {
      const Test& t = node.test;
      scale_ = std::max(scale_, 2.0 * (std::abs(double{t.b[0]}) + std::abs(double{t.b[1]}) + std::abs(double{t.b[2]})) +
                                    std::max(std::abs(double{t.d}), std::abs(double{node.front_d})));
    }
    float_scale_ = 0.0;
    for (const Node& node : nodes_) {
      const Test& t = node.test;
      float_scale_ = std::max(float_scale_, std::abs(double{t.b[0]}) + std::abs(double{t.b[1]}) +
                                                std::abs(double{t.b[2]}) + std::abs(double{t.d}));
    }
    float_scale_ += 1e-9 * (std::abs(origin_.x) + std::abs(origin_.y) + std::abs(origin_.z));
    buildBlocks();
    polys_.clear();
    polys_.shrink_to_fit();
  }

  BackfaceMethod method() const override { return BackfaceMethod::kCluster; }
  size_t stateBytes() const override {
    // A leaf needs only its 40-byte test; an inner node adds the front offset and its leaf range
    // and skip link.
    const size_t leaves = unitCount();
    return leaves * sizeof(Test) + (nodes_.size() - leaves) * sizeof(Node);
  }

  void cull(const BackfaceView& view, std::span<uint8_t> unit_culled) const override {
    WALKVIS_DCHECK(unit_culled.size() == unitCount());
    if (!hierarchy_) {
      cullFlat(view, unit_culled);
      return;
    }
    const glm::dvec3 e = view.eye - origin_;
    const double margin = kRelMargin * (std::abs(view.eye.x) + std::abs(view.eye.y) + std::abs(view.eye.z) + scale_);
    uint8_t* out = unit_culled.data();
    const Node* nodes = nodes_.data();
    const size_t count = nodes_.size();
    size_t i = 0;
    while (i < count) {
      const Node& node = nodes[i];
      const Test& t = node.test;
      const double ex = e.x - t.b[0], ey = e.y - t.b[1], ez = e.z - t.b[2];
      const double back = (ex > 0.0 ? t.m[0] : t.n[0]) * ex + (ey > 0.0 ? t.m[1] : t.n[1]) * ey +
                          (ez > 0.0 ? t.m[2] : t.n[2]) * ez - t.d;
      if (back <= -margin) {
        std::memset(out + node.leaf_begin, 1, node.leaf_end - node.leaf_begin);
        i = node.skip;
        continue;
      }
      if (node.leaf_end - node.leaf_begin == 1 && node.skip == i + 1) {
        out[node.leaf_begin] = 0;
        ++i;
        continue;
      }
      // Front test: Comp(−M, −N)·e' + max_i n_i·p_i' <= 0; keeping is always safe, no margin.
      const double front = -(ex > 0.0 ? t.n[0] : t.m[0]) * ex - (ey > 0.0 ? t.n[1] : t.m[1]) * ey -
                           (ez > 0.0 ? t.n[2] : t.m[2]) * ez + node.front_d;
      if (front <= 0.0) {
        std::memset(out + node.leaf_begin, 0, node.leaf_end - node.leaf_begin);
        i = node.skip;
        continue;
      }
      ++i;
    }
  }

 private:
  // §2.1 test (8) of every leaf, kLanes at a time: Comp_e'(N, M)·e' is Σ_c max(N^c·e'^c, M^c·e'^c)
  // (N <= M, so the larger product is the one Comp picks); no branch, one pass.
  void cullFlat(const BackfaceView& view, std::span<uint8_t> unit_culled) const {
    const glm::dvec3 e = view.eye - origin_;
    const double e1 = std::abs(e.x) + std::abs(e.y) + std::abs(e.z);
    uint8_t* out = unit_culled.data();
    const size_t units = unit_culled.size();
    if (!(e1 < kMaxFloatEye)) {
      std::memset(out, 0, units);
      return;
    }
    // Rounded up without nextafter (a libm call, a share of the pass on small meshes): the float
    // nearest to x·(1 + 2⁻²²) is at least x·(1 + 2⁻²²)(1 − 2⁻²⁴) > x.
    const float limit = -static_cast<float>(kFloatMargin * (e1 + float_scale_) * (1.0 + 0x1p-22));
    const float fx = static_cast<float>(e.x), fy = static_cast<float>(e.y), fz = static_cast<float>(e.z);
    const LeafBlock* blocks = blocks_.data();
#if defined(__SSE2__)
    if (simd_ == BackfaceSimd::kAvx2) {
      flatPassAvx2(blocks, blocks_.size(), fx, fy, fz, limit, out, units);
      return;
    }
#endif
    const size_t full = units / kLanes;
    // The path is chosen once per frame, not per block.
    auto pass = [&](auto blockBits) {
      for (size_t k = 0; k < blocks_.size(); ++k) {
        const uint64_t bytes = kSpread[blockBits(blocks[k], fx, fy, fz, limit)];
        std::memcpy(out + k * kLanes, &bytes, k < full ? kLanes : units - k * kLanes);
      }
    };
#if defined(__SSE2__)
    if (simd_ == BackfaceSimd::kSse2) {
      pass(blockBitsSse);
      return;
    }
#endif
    pass(blockBitsScalar);
  }

  void buildBlocks() {
    const size_t leaves = unitCount();
    blocks_.assign((leaves + kLanes - 1) / kLanes, LeafBlock{});
    for (LeafBlock& blk : blocks_) {
      for (size_t l = 0; l < kLanes; ++l) blk.d[l] = -1.0f;  // padding lanes: back = 1 > limit, never culled
    }
    for (size_t i = 0; i < nodes_.size(); ++i) {
      const Node& node = nodes_[i];
      if (node.leaf_end - node.leaf_begin != 1 || node.skip != i + 1) continue;
      LeafBlock& blk = blocks_[node.leaf_begin / kLanes];
      const size_t l = node.leaf_begin % kLanes;
      for (int c = 0; c < 3; ++c) {
        blk.n[c][l] = node.test.n[c];
        blk.m[c][l] = node.test.m[c];
        blk.b[c][l] = node.test.b[c];
      }
      blk.d[l] = node.test.d;
    }
  }

  // The best of the 9 origin candidates for the polygons `members` with statistics `s`.
  Choice choose(const Stats& s, std::span<const uint32_t> members) const {
    std::array<glm::dvec3, 9> candidates;
    for (int c = 0; c < 8; ++c) {
      candidates[static_cast<size_t>(c)] =
          glm::dvec3(c & 1 ? s.hi.x : s.lo.x, c & 2 ? s.hi.y : s.lo.y, c & 4 ? s.hi.z : s.lo.z);
    }
    candidates[8] = s.sum / s.count;
    Choice best;
    for (const glm::dvec3& candidate : candidates) {
      // The origin is stored in single precision: evaluate the origin that will be stored.
      const glm::dvec3 b_local(toFloatPrecision(candidate.x - origin_.x), toFloatPrecision(candidate.y - origin_.y),
                               toFloatPrecision(candidate.z - origin_.z));
      const glm::dvec3 b = origin_ + b_local;
      double d = INFINITY;
      for (uint32_t p : members) d = std::min(d, polys_[p].dd - glm::dot(polys_[p].n, b));
      const double prob = eye_box_ ? boxCullProbability(s.n_min, s.n_max, d, eye_lo_ - b, eye_hi_ - b)
                                   : nearFieldCullProbability(s.n_min, s.n_max, d, half_);
      if (prob > best.probability) best = {prob, b, b_local, d};
    }
    return best;
  }

  void formClusters(double tr) {
    const size_t count = polys_.size();
    std::vector<double> single(count);
    for (size_t i = 0; i < count; ++i) {
      Stats s;
      s.add(polys_[i]);
      const uint32_t id = static_cast<uint32_t>(i);
      single[i] = choose(s, std::span<const uint32_t>(&id, 1)).probability;
    }
    std::vector<uint32_t> seeds(count);
    std::iota(seeds.begin(), seeds.end(), 0u);
    std::stable_sort(seeds.begin(), seeds.end(), [&](uint32_t a, uint32_t b) { return single[a] > single[b]; });
    std::vector<uint8_t> alive(count, 1);
    std::vector<uint32_t> members, candidates, pool;
    std::vector<double> key(count);
    double offset_scale = 0.0;  // the largest plane offset difference: tie keys stay below kOffsetTieWeight
    {
      double lo = INFINITY, hi = -INFINITY;
      for (const PolyData& p : polys_) {
        lo = std::min(lo, p.dd);
        hi = std::max(hi, p.dd);
      }
      offset_scale = hi > lo ? hi - lo : 1.0;
    }
    size_t next_seed = 0;
    unit_begin_.push_back(0);
    for (size_t left = count; left > 0;) {
      while (!alive[seeds[next_seed]]) ++next_seed;
      const uint32_t seed = seeds[next_seed];
      alive[seed] = 0;
      --left;
      members.assign(1, seed);
      Stats stats;
      stats.add(polys_[seed]);
      double p_c = single[seed];
      // Candidates by decreasing n·n_seed, a batch at a time.
      pool.clear();
      for (size_t i = 0; i < count; ++i) {
        if (alive[i]) {
          pool.push_back(static_cast<uint32_t>(i));
          // Near-parallel normals (within ~4e-5 rad, where 1 − cos differs by < 1e-9) are taken
          // nearest plane first: coplanar polygons (a wall cut into BSP fragments) merge at no
          // loss, but a parallel plane at another offset ends the growth (the first failing
          // candidate stops it), so with ties broken by index a Doom level's axis-aligned walls
          // interleaved and stayed apart.
          key[i] = -glm::dot(polys_[i].n, polys_[seed].n) + kOffsetTieWeight * std::abs(polys_[i].dd - polys_[seed].dd) / offset_scale;
        }
      }
      size_t pool_pos = 0;
      bool growing = true;
      while (growing && members.size() < kMaxClusterPolygons && pool_pos < pool.size()) {
        const size_t batch_end = std::min(pool.size(), pool_pos + kCandidateBatch);
        auto by_key = [&](uint32_t a, uint32_t b) { return key[a] < key[b] || (key[a] == key[b] && a < b); };
        std::partial_sort(pool.begin() + static_cast<std::ptrdiff_t>(pool_pos),
                          pool.begin() + static_cast<std::ptrdiff_t>(batch_end), pool.end(), by_key);
        for (; pool_pos < batch_end && members.size() < kMaxClusterPolygons; ++pool_pos) {
          const uint32_t cand = pool[pool_pos];
          Stats merged = stats;
          merged.add(polys_[cand]);
          members.push_back(cand);
          const double p_merged = choose(merged, members).probability;
          const double c_a = stats.cost, c_b = polys_[cand].vertices;
          if (p_merged > (p_c * c_a + single[cand] * c_b - tr) / (c_a + c_b)) {
            stats = merged;
            p_c = p_merged;
            alive[cand] = 0;
            --left;
          } else {
            members.pop_back();
            growing = false;
            break;
          }
        }
      }
      unit_polygons_.insert(unit_polygons_.end(), members.begin(), members.end());
      unit_begin_.push_back(static_cast<uint32_t>(unit_polygons_.size()));
    }
  }

  // Leaf tests, then (with the hierarchy) a binary tree over the leaves by median splits of the
  // clusters' mean normals along their axis of widest spread; leaves are renumbered in preorder.
  void buildNodes() {
    const size_t clusters = unit_begin_.size() - 1;
    std::vector<uint32_t> order(clusters);
    std::iota(order.begin(), order.end(), 0u);
    std::vector<glm::dvec3> mean(clusters, glm::dvec3(0.0));
    for (size_t c = 0; c < clusters; ++c) {
      for (uint32_t k = unit_begin_[c]; k < unit_begin_[c + 1]; ++k) mean[c] += polys_[unit_polygons_[k]].n;
    }
    std::vector<uint32_t> new_begin{0}, new_polygons;
    new_polygons.reserve(unit_polygons_.size());
    if (hierarchy_ && clusters > 1) {
      buildTree(order, 0, clusters, mean, new_begin, new_polygons);
    } else {
      for (size_t c = 0; c < clusters; ++c) emitLeaf(static_cast<uint32_t>(c), new_begin, new_polygons);
    }
    unit_begin_ = std::move(new_begin);
    unit_polygons_ = std::move(new_polygons);
  }

  void emitLeaf(uint32_t cluster, std::vector<uint32_t>& new_begin, std::vector<uint32_t>& new_polygons) {
    const std::span<const uint32_t> members(unit_polygons_.data() + unit_begin_[cluster],
                                            unit_begin_[cluster + 1] - unit_begin_[cluster]);
    const uint32_t leaf = static_cast<uint32_t>(new_begin.size() - 1);
    nodes_.push_back(makeNode(members, leaf, leaf + 1));
    nodes_.back().skip = static_cast<uint32_t>(nodes_.size());
    new_polygons.insert(new_polygons.end(), members.begin(), members.end());
    new_begin.push_back(static_cast<uint32_t>(new_polygons.size()));
  }

  void buildTree(std::vector<uint32_t>& order, size_t begin, size_t end, const std::vector<glm::dvec3>& mean,
                 std::vector<uint32_t>& new_begin, std::vector<uint32_t>& new_polygons) {
    if (end - begin == 1) {
      emitLeaf(order[begin], new_begin, new_polygons);
      return;
    }
    const size_t at = nodes_.size();
    nodes_.emplace_back();
    const uint32_t first_leaf = static_cast<uint32_t>(new_begin.size() - 1);
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (size_t i = begin; i < end; ++i) {
      const glm::dvec3 m = glm::normalize(mean[order[i]]);
      lo = glm::min(lo, m);
      hi = glm::max(hi, m);
    }
    const glm::dvec3 ext = hi - lo;
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    const size_t mid = begin + (end - begin) / 2;
    std::nth_element(order.begin() + static_cast<std::ptrdiff_t>(begin), order.begin() + static_cast<std::ptrdiff_t>(mid),
                     order.begin() + static_cast<std::ptrdiff_t>(end), [&](uint32_t a, uint32_t b) {
                       return mean[a][axis] / glm::length(mean[a]) < mean[b][axis] / glm::length(mean[b]);
                     });
    buildTree(order, begin, mid, mean, new_begin, new_polygons);
    buildTree(order, mid, end, mean, new_begin, new_polygons);
    const uint32_t last_leaf = static_cast<uint32_t>(new_begin.size() - 1);
    const std::span<const uint32_t> members(new_polygons.data() + new_begin[first_leaf],
                                            new_begin[last_leaf] - new_begin[first_leaf]);
    nodes_[at] = makeNode(members, first_leaf, last_leaf);
    nodes_[at].skip = static_cast<uint32_t>(nodes_.size());
  }

  Node makeNode(std::span<const uint32_t> members, uint32_t leaf_begin, uint32_t leaf_end) const {
    Stats s;
    for (uint32_t p : members) s.add(polys_[p]);
    const Choice c = choose(s, members);
    Node node{};
    for (int k = 0; k < 3; ++k) {
      node.test.n[k] = floatDown(s.n_min[k]);
      node.test.m[k] = floatUp(s.n_max[k]);
      node.test.b[k] = static_cast<float>(c.b_local[k]);  // exact: rounded to float in choose()
    }
    double d_max = -INFINITY;
    for (uint32_t p : members) d_max = std::max(d_max, polys_[p].dd - glm::dot(polys_[p].n, c.b));
    node.test.d = floatDown(c.d);
    node.front_d = floatUp(d_max);
    node.leaf_begin = leaf_begin;
    node.leaf_end = leaf_end;
    return node;
  }

  bool hierarchy_;
  BackfaceSimd simd_;
  glm::dvec3 origin_{0.0};
  double float_scale_ = 0.0;
  std::vector<LeafBlock> blocks_;  // the leaves' tests, kLanes per block (flat cull)
  double half_ = 1.0;
  bool eye_box_ = false;
  glm::dvec3 eye_lo_{0.0}, eye_hi_{0.0};
  double max_dd_ = 0.0;
  double scale_ = 0.0;
  std::vector<PolyData> polys_;  // build time only
  std::vector<Node> nodes_;
};

}  // namespace

double clusterTrFor(size_t polygons, double requested) {
  if (!(requested >= 0.0) || !std::isfinite(requested)) throw Error("backface cluster: cluster_tr must be >= 0 and finite");
  if (requested > 0.0) return requested;
  if (polygons <= 4000) return 1.0;
  return std::max(0.25, std::sqrt(4000.0 / static_cast<double>(polygons)));
}

double nearFieldCullProbability(const glm::dvec3& n_min, const glm::dvec3& n_max, double d, double half) {
  // §3: eight octant cubes of edge half around b; in octant s the culling plane has normal
  // Comp_s(N, M), i.e. coefficient s_c·N^c where s_c < 0 and s_c·M^c where s_c > 0 on |e'^c|.
  double total = 0.0;
  for (int o = 0; o < 8; ++o) {
    std::array<double, 3> a{};
    for (int c = 0; c < 3; ++c) {
      const bool positive = (o >> c) & 1;
      a[static_cast<size_t>(c)] = positive ? n_max[c] : -n_min[c];
    }
    total += cubeFraction(a, d / half);
  }
  return total / 8.0;
}

double boxCullProbability(const glm::dvec3& n_min, const glm::dvec3& n_max, double d, const glm::dvec3& lo,
                          const glm::dvec3& hi) {
  // The box cut by the coordinate planes through b into up to eight boxes; in each the test is
  // linear, a·e' <= d with a = Comp(N, M) of that octant, and t = l + (u − l)·s maps it onto the
  // unit cube. An axis without extent contributes its constant only, and no factor to the measure.
  const glm::dvec3 width = hi - lo;
  double total = 0.0;
  for (int o = 0; o < 8; ++o) {
    std::array<double, 3> a{};
    double shift = d, measure = 1.0;
    bool empty = false;
    for (int c = 0; c < 3; ++c) {
      const bool positive = (o >> c) & 1;
      double l, u;
      if (width[c] > 0.0) {
        l = positive ? std::max(lo[c], 0.0) : lo[c];
        u = positive ? hi[c] : std::min(hi[c], 0.0);
        if (!(u > l)) {
          empty = true;
          break;
        }
        measure *= (u - l) / width[c];
      } else {
        // A flat axis lies in one octant: e'^c > 0 picks M, else N (as the test does).
        if ((lo[c] > 0.0) != positive) {
          empty = true;
          break;
        }
        l = u = lo[c];
      }
      const double coef = positive ? n_max[c] : n_min[c];
      shift -= coef * l;
      a[static_cast<size_t>(c)] = coef * (u - l);
    }
    if (!empty) total += measure * cubeFraction(a, shift);
  }
  return std::clamp(total, 0.0, 1.0);
}

std::unique_ptr<BackfaceCuller> makeClusterCuller(const BackfaceInput& input, const BackfaceOptions& options) {
  return std::make_unique<ClusterCuller>(input, options);
}

}  // namespace walkvis
