// Backface culling inside priority lists (list_cull.h; docs/DESIGN.md, "Facing at emission").
// The methods are those of backface.h, each citing its paper in its own file:
//   polygon, region  the plane test per polygon (polygon_cull.cpp)
//   mask             Zhang & Hoff 1997 normal masks (normal_mask.cpp, normal_mask.h)
//   cluster          Johannsen & Carter 1998 clustered backface test (clustered.cpp)
//   hierarchy        Kumar et al. 1996 hierarchical back-face computation (hierarchical_kumar.cpp)
//
// A range must come out in its own order (it is a priority list: painter's order), so per range the
// per-frame state is laid out by position in the range:
//   polygon/region (and mask's plane-test chunks): the distinct planes of the listed polygons, in
//     double, and each polygon's plane id; per call each distinct plane is tested once, exactly as
//     isFrontFacing(), and each position looks its byte up (see "The batched per-frame passes");
//   mask (MaskCone kView, the default here): Zhang & Hoff §3.1, one mask per call from the view
//     cone (view_dir, fov) over the clusters the positions use, and a one-byte cluster code per
//     position (see "mask with the view cone" below). It never culls a front face with a point
//     inside the view cone; one wholly outside it may be culled, and draws nothing in a frustum
//     the cone holds (what the walkthrough passes, frame.cpp). That is the paper's method, and
//     the only mask that pays here: a cone that holds every direction from an eye inside the
//     building to the polygons is the whole sphere;
//   mask (MaskCone kGroups): the 2-byte cluster id per position and one bounding sphere per chunk
//     of the range (the paper's per-group view cone, §3.2; chunks of mask_group_size positions,
//     0 = the whole range); per frame one table per chunk from the cone from the eye around its
//     sphere, conservative for every polygon. A chunk of fewer than mask_list_min_chunk positions
//     gets the plane test instead (so on PFD lists, whose runs are far shorter than the default
//     512, it IS the plane test; the bench prints the share of positions a table culls): a table
//     costs far more to build than the plane test on a run, and a table per run can never pay
//     there (docs/backface/README.md, "Lists (list_cull)"). An eye inside a group's bounding sphere
//     culls nothing in it (so one group of a whole building culls nothing for eyes inside it);
//   cluster/hierarchy: the method's own culler built over the range's polygons (its clusters are
//     formed per range) and the unit of each position, so that the unit flags map back in order.
//     cluster's culling probability is taken over the box of all input vertices (the eyes of a
//     walkthrough are inside it) unless the options name an eye box: with the paper's box around
//     each cluster's origin, a building's walls merge into one cluster per orientation, and an eye
//     inside culls none of them (backface.h; docs/backface/README.md, "Clustered backface test").
// cullRanges takes all runs of a query in one call (the method picked once, one resize of `out`,
// survivors written through a raw cursor without a branch per element); cullRange is its one-run
// case.
#include "backface/list_cull.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>

#include <glm/geometric.hpp>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define WALKVIS_LIST_CULL_X86 1
#endif

#include "backface/normal_mask.h"
#include "backface/spread_bits.h"

namespace walkvis {

std::string_view listCullMethodName(ListCullMethod method) {
  switch (method) {
    case ListCullMethod::kNone: return "none";
    case ListCullMethod::kPolygon: return "polygon";
    case ListCullMethod::kMask: return "mask";
    case ListCullMethod::kCluster: return "cluster";
    case ListCullMethod::kHierarchy: return "hierarchy";
    case ListCullMethod::kRegion: return "region";
  }
  return "?";
}

ListCullMethod parseListCullMethod(std::string_view name) {
  for (ListCullMethod m : {ListCullMethod::kNone, ListCullMethod::kPolygon, ListCullMethod::kMask,
                           ListCullMethod::kCluster, ListCullMethod::kHierarchy, ListCullMethod::kRegion}) {
    if (listCullMethodName(m) == name) return m;
  }
  throw Error("backface list method '" + std::string(name) +
                   "': expected none, polygon, mask, cluster, hierarchy or region");
}

namespace {

struct MaskChunk {
  uint32_t begin = 0, end = 0;  // positions into the index array
  glm::dvec3 center{0.0};
  double radius = -1.0;  // < 0: empty chunk
  bool planes = false;   // too small for a table: the plane test (planes of Impl::nx.. at its positions)
};

// Per range, besides its IndexRange (Impl::spans).
struct RangeState {
  uint32_t chunk_begin = 0, chunk_end = 0;  // mask: chunks of this range
  std::unique_ptr<BackfaceCuller> culler;   // cluster, hierarchy
  uint32_t unit_of = 0;                     // cluster, hierarchy: offset into Impl::unit_of
};

// The bounding sphere of the polygons at positions [begin, end), grown as in normal_mask.cpp so
// that it holds the nearest plane point of every vertex (the cone test then speaks of planes).
MaskChunk boundChunk(const BackfaceInput& input, std::span<const uint32_t> indices, uint32_t begin, uint32_t end) {
  MaskChunk c;
  c.begin = begin;
  c.end = end;
  if (begin == end) return c;
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (uint32_t i = begin; i < end; ++i) {
    const Polygon& poly = input.polygons[indices[i]];
    for (uint32_t k = 0; k < poly.vertex_count; ++k) {
      lo = glm::min(lo, input.vertices[poly.first_vertex + k]);
      hi = glm::max(hi, input.vertices[poly.first_vertex + k]);
    }
  }
  c.center = 0.5 * (lo + hi);
  double r = 0.0;
  for (uint32_t i = begin; i < end; ++i) {
    const Polygon& poly = input.polygons[indices[i]];
    for (uint32_t k = 0; k < poly.vertex_count; ++k) {
      const glm::dvec3& v = input.vertices[poly.first_vertex + k];
      const double residual = std::abs(glm::dot(poly.plane.n, v) - poly.plane.d);
      r = std::max(r, glm::length(v - c.center) + residual);
    }
  }
  const double scale = std::max({std::abs(c.center.x), std::abs(c.center.y), std::abs(c.center.z), r});
  c.radius = r + kMaskSphereGrowth * scale;
  return c;
}

// ---- The batched per-frame passes (cullRanges). A PFD query lists a small share of its tree's
// positions in short runs, and its fragments lie on far fewer distinct planes (a Doom level's
// walls, floors and ceilings; docs/backface/README.md, "Lists (list_cull)"). So per call each
// distinct plane is tested once, SIMD where the CPU has it (the same double expression as
// isFrontFacing(), so the same result bit for bit), into a byte per plane, and every listed
// position looks its polygon's plane's byte up: no per-position plane data (the index array is
// read anyway), two lookups in tables that sit in L1. A call listing few positions against many
// planes (or more planes than the stack table holds) tests each listed position's plane directly.
// The unculled copy (none) moves 8 entries per step (the index array carries kPad trailing
// entries, the output kListCullOutSlack spare ones for the overshoot).

constexpr uint32_t kPad = 8;  // trailing entries of the index and plane arrays: one 8-lane step
static_assert(kListCullOutSlack >= kPad);
constexpr uint32_t kMaxTablePlanes = 1u << 14;  // a 16 KiB byte table on the stack

// The distinct planes (structure of arrays, kPad trailing zero planes: 0 > 0, never front), the
// plane id of each polygon and the index array (kPad trailing zeros).
struct PlaneArrays {
  const double* x;
  const double* y;
  const double* z;
  const double* d;
  uint32_t planes;
  const uint32_t* poly_plane;  // by polygon index
  const uint32_t* idx;
};

// Range ids[k] of `spans` for k < n, unculled.
uint32_t* copyRuns(const uint32_t* idx, const IndexRange* spans, const uint32_t* ids, size_t n, uint32_t* dst) {
  for (size_t k = 0; k < n; ++k) {
    const IndexRange s = spans[ids[k]];
    const uint32_t* src = idx + s.first;
    uint32_t left = s.count;
    for (;;) {
      std::memcpy(dst, src, 8 * sizeof(uint32_t));
      if (left <= 8) {
        dst += left;
        break;
      }
      dst += 8;
      src += 8;
      left -= 8;
    }
  }
  return dst;
}

// Appends idx[i] for every position i of the runs ids[0, n) of `spans` with keep(i), in order,
// through the raw cursor `dst` without a branch per element; returns the cursor after them. Every
// scalar pass below is this with its own test.
template <typename Keep>
uint32_t* appendKept(const uint32_t* idx, const IndexRange* spans, const uint32_t* ids, size_t n, uint32_t* dst,
                     Keep keep) {
  for (size_t k = 0; k < n; ++k) {
    const IndexRange s = spans[ids[k]];
    for (uint32_t i = s.first, end = s.first + s.count; i < end; ++i) {
      *dst = idx[i];
      dst += keep(i) ? 1 : 0;
    }
  }
  return dst;
}

// isFrontFacing() of plane p: the same expression as glm::dot, (x + y) + z (the baseline target
// has no FMA to contract it into).
inline bool planeFront(const PlaneArrays& a, uint32_t p, double ex, double ey, double ez) {
  return (a.x[p] * ex + a.y[p] * ey) + a.z[p] * ez > a.d[p];
}

// The direct test: each listed position's plane, scalar.
uint32_t* directRuns(const PlaneArrays& a, const IndexRange* spans, const uint32_t* ids, size_t n,
                     const glm::dvec3& eye, uint32_t* dst) {
  return appendKept(a.idx, spans, ids, n, dst,
                    [&](uint32_t i) { return planeFront(a, a.poly_plane[a.idx[i]], eye.x, eye.y, eye.z); });
}

// front[p] = 1 where plane p is front-facing, else 0, for p < a.planes.
void frontTableScalar(const PlaneArrays& a, const glm::dvec3& eye, uint8_t* front) {
  for (uint32_t p = 0; p < a.planes; ++p) front[p] = planeFront(a, p, eye.x, eye.y, eye.z) ? 1 : 0;
}

// The lookups: per position its polygon's plane's byte (both tables in L1), a branch-free append.
// The scalar and AVX2 paths (AVX-512 and AVX2 gathers of the same two lookups measured no faster
// and slower: docs/backface/README.md, "Lists (list_cull)").
uint32_t* tableRuns(const PlaneArrays& a, const uint8_t* front, const IndexRange* spans, const uint32_t* ids,
                    size_t n, uint32_t* dst) {
  return appendKept(a.idx, spans, ids, n, dst, [&](uint32_t i) { return front[a.poly_plane[a.idx[i]]] != 0; });
}

#ifdef WALKVIS_LIST_CULL_X86
// AVX2 without FMA (the target names none, so mul + add cannot be contracted): per lane the same
// double operations in the same order as isFrontFacing().
[[gnu::target("avx2,popcnt")]] void frontTableAvx2(const PlaneArrays& a, const glm::dvec3& eye, uint8_t* front) {
  const __m256d ex = _mm256_set1_pd(eye.x), ey = _mm256_set1_pd(eye.y), ez = _mm256_set1_pd(eye.z);
  for (uint32_t p = 0; p < a.planes; p += 8) {
    uint32_t bits = 0;
    for (uint32_t h = 0; h < 8; h += 4) {
      const __m256d v = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(a.x + p + h), ex),
                                                    _mm256_mul_pd(_mm256_loadu_pd(a.y + p + h), ey)),
                                      _mm256_mul_pd(_mm256_loadu_pd(a.z + p + h), ez));
      bits |= static_cast<uint32_t>(_mm256_movemask_pd(_mm256_cmp_pd(v, _mm256_loadu_pd(a.d + p + h), _CMP_GT_OQ))) << h;
    }
    std::memcpy(front + p, &kSpread[bits], 8);
  }
}

// AVX-512F has FMA, so plain mul + add could be fused (rounding differently from
// isFrontFacing()): the explicit-rounding forms (round to nearest, the default) are never fused.
// Their zero-masking variants with a full mask: GCC 12's unmasked ones warn (an undefined source).
[[gnu::target("avx512f,avx512vl,popcnt")]] void frontTableAvx512(const PlaneArrays& a, const glm::dvec3& eye,
                                                                 uint8_t* front) {
  constexpr int kRound = _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC;
  constexpr __mmask8 kAll = 0xFF;
  const __m512d ex = _mm512_set1_pd(eye.x), ey = _mm512_set1_pd(eye.y), ez = _mm512_set1_pd(eye.z);
  for (uint32_t p = 0; p < a.planes; p += 8) {
    const __m512d x = _mm512_maskz_mul_round_pd(kAll, _mm512_loadu_pd(a.x + p), ex, kRound);
    const __m512d y = _mm512_maskz_mul_round_pd(kAll, _mm512_loadu_pd(a.y + p), ey, kRound);
    const __m512d z = _mm512_maskz_mul_round_pd(kAll, _mm512_loadu_pd(a.z + p), ez, kRound);
    const __m512d v = _mm512_maskz_add_round_pd(kAll, _mm512_maskz_add_round_pd(kAll, x, y, kRound), z, kRound);
    const uint32_t bits = _mm512_cmp_pd_mask(v, _mm512_loadu_pd(a.d + p), _CMP_GT_OQ);
    std::memcpy(front + p, &kSpread[bits], 8);
  }
}


// The same lookups eight positions at a time into a lane mask, then one vpcompressd (register
// form) of their indices: one store per eight positions instead of one per position.
[[gnu::target("avx512f,avx512vl,popcnt")]] uint32_t* tableRunsAvx512(const PlaneArrays& a, const uint8_t* front,
                                                                     const IndexRange* spans, const uint32_t* ids,
                                                                     size_t n, uint32_t* dst) {
  for (size_t k = 0; k < n; ++k) {
    const IndexRange s = spans[ids[k]];
    uint32_t at = s.first, left = s.count;
    for (;;) {
      const uint32_t* idx = a.idx + at;
      uint32_t bits = 0;
      for (uint32_t j = 0; j < 8; ++j) bits |= static_cast<uint32_t>(front[a.poly_plane[idx[j]]]) << j;
      const __mmask8 keep = static_cast<__mmask8>(bits & ((1u << std::min(left, 8u)) - 1u));
      const __m256i id = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(idx));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst), _mm256_maskz_compress_epi32(keep, id));
      dst += _mm_popcnt_u32(keep);
      if (left <= 8) break;
      left -= 8;
      at += 8;
    }
  }
  return dst;
}
#endif

// ---- mask with the view cone (BackfaceOptions::MaskCone::kView, the default in lists): Zhang &
// Hoff §3.1. Per call one mask from the view cone (view_dir, fov) over the clusters the culler's
// positions use (a Doom level uses few of the grid's clusters: walls' normals lie on the cube's
// equator; docs/backface/README.md, "Lists (list_cull)"), then per position one lookup of its
// cluster's flag. Clusters are numbered densely at build time (their `codes`), so a position stores
// one byte where there are at most 256 of them, and with AVX-512 VBMI sixteen positions' flags are
// two byte permutes (vpermi2b over 128-entry halves) and a blend; their ids are then compressed out
// in one vpcompressd.

constexpr uint32_t kMaxByteCodes = 256;
static_assert(kListCullOutSlack >= 16);  // viewMaskRunsVbmi's 16-lane store

// The view cone's cap test per code: flags[k] = 1 when all four corners of code k's cluster
// satisfy c·axis > lim, else 0, for k < codes (corner q of code k at q·stride + k; codes past the
// clusters have zero corners, never in the cap). Baseline code, no target attribute: the float
// operations are never contracted, so every path reads the same flags.
void viewFlags(const float* cx, const float* cy, const float* cz, uint32_t stride, uint32_t codes,
               const glm::vec3& axis, float lim, uint8_t* flags) {
  for (uint32_t k = 0; k < codes; ++k) flags[k] = 1;
  for (uint32_t q = 0; q < 4; ++q) {
    const float* x = cx + q * stride;
    const float* y = cy + q * stride;
    const float* z = cz + q * stride;
    for (uint32_t k = 0; k < codes; ++k) flags[k] &= (x[k] * axis.x + y[k] * axis.y) + z[k] * axis.z > lim ? 1 : 0;
  }
}

// Runs ids[0, n) by the flags of their positions' codes (Code: uint8_t or uint16_t), scalar.
template <typename Code>
uint32_t* viewMaskRuns(const uint32_t* idx, const Code* code, const uint8_t* flags, const IndexRange* spans,
                       const uint32_t* ids, size_t n, uint32_t* dst) {
  return appendKept(idx, spans, ids, n, dst, [&](uint32_t i) { return flags[code[i]] == 0; });
}

#ifdef WALKVIS_LIST_CULL_X86
// Sixteen positions from `at` of viewMaskRunsVbmi, the first `count` (0..16) of them real.
template <uint32_t kCodes>
[[gnu::target("avx512f,avx512bw,avx512vl,avx512vbmi,popcnt,bmi2"), gnu::always_inline]] inline uint32_t* viewMaskStep(
    const uint32_t* idx, const uint8_t* code, __m512i t0, __m512i t1, __m512i t2, __m512i t3, uint32_t at,
    uint32_t count, uint32_t* dst) {
  const __mmask16 lanes = static_cast<__mmask16>(_bzhi_u32(0xFFFFu, count));
  const __m512i c = _mm512_zextsi128_si512(_mm_maskz_loadu_epi8(lanes, code + at));
  __m512i f;
  if constexpr (kCodes <= 64) {
    (void)t1, (void)t2, (void)t3;
    f = _mm512_maskz_permutexvar_epi8(~__mmask64{0}, c, t0);  // GCC 12 warns on the unmasked form
  } else if constexpr (kCodes <= 128) {
    (void)t2, (void)t3;
    f = _mm512_permutex2var_epi8(t0, c, t1);
  } else {
    f = _mm512_mask_blend_epi8(_mm512_movepi8_mask(c), _mm512_permutex2var_epi8(t0, c, t1),
                               _mm512_permutex2var_epi8(t2, c, t3));
  }
  const __mmask16 keep = static_cast<__mmask16>(lanes & ~static_cast<uint32_t>(_mm512_test_epi8_mask(f, f)));
  const __m512i id = _mm512_maskz_loadu_epi32(lanes, idx + at);
  _mm512_storeu_si512(dst, _mm512_maskz_compress_epi32(keep, id));
  return dst + _mm_popcnt_u32(keep);
}

// The same with AVX-512 VBMI, sixteen positions per step (masked loads: nothing is read past a
// run; the full 16-lane store may write kListCullOutSlack entries past the survivors). `flags`:
// 256 entries (codes past the culler's are 0); kCodes (64, 128 or 256) bounds the culler's codes:
// one vpermb, one vpermi2b, or two and a blend on the top bit.
template <uint32_t kCodes>
[[gnu::target("avx512f,avx512bw,avx512vl,avx512vbmi,popcnt,bmi2")]] uint32_t* viewMaskRunsVbmi(
    const uint32_t* idx, const uint8_t* code, const uint8_t* flags, const IndexRange* spans, const uint32_t* ids,
    size_t n, uint32_t* dst) {
  const __m512i t0 = _mm512_loadu_si512(flags), t1 = _mm512_loadu_si512(flags + 64);
  const __m512i t2 = _mm512_loadu_si512(flags + 128), t3 = _mm512_loadu_si512(flags + 192);
  for (size_t k = 0; k < n; ++k) {
    const IndexRange s = spans[ids[k]];
    // Most runs are at most 32 positions: two steps without a branch on the count (the second may
    // have no lanes), which a loop's exit would mispredict from run to run.
    dst = viewMaskStep<kCodes>(idx, code, t0, t1, t2, t3, s.first, std::min(s.count, 16u), dst);
    dst = viewMaskStep<kCodes>(idx, code, t0, t1, t2, t3, s.first + 16, s.count > 16 ? std::min(s.count - 16, 16u) : 0u, dst);
    for (uint32_t at = s.first + 32, left = s.count > 32 ? s.count - 32 : 0; left > 0;) {
      const uint32_t count = std::min(left, 16u);
      dst = viewMaskStep<kCodes>(idx, code, t0, t1, t2, t3, at, count, dst);
      at += count;
      left -= count;
    }
  }
  return dst;
}
#endif

enum class PlanePath : uint8_t { kScalar, kAvx2, kAvx512 };

// The widest path the CPU has, at most what `simd` names (kAuto: AVX-512 where present; the
// option has no AVX-512 value, so kAvx2 pins AVX2 and kSse2 and kScalar the scalar loops).
PlanePath resolvePlanePath(BackfaceSimd simd) {
#ifdef WALKVIS_LIST_CULL_X86
  const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
  const bool avx512 = avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  if (simd == BackfaceSimd::kAuto) return avx512 ? PlanePath::kAvx512 : avx2 ? PlanePath::kAvx2 : PlanePath::kScalar;
  if (simd == BackfaceSimd::kAvx2 && avx2) return PlanePath::kAvx2;
#else
  (void)simd;
#endif
  return PlanePath::kScalar;
}

using FrontTable = std::array<uint8_t, kMaxTablePlanes + 8>;  // + 8: the 8-plane steps write past a.planes

// The plane bytes for a call listing `listed` positions, in `storage`; nullptr where the call
// should test each position's plane directly instead (see planeTestRuns).
const uint8_t* frontTableFor(PlanePath path, const PlaneArrays& a, uint64_t listed, const glm::dvec3& eye,
                             FrontTable& storage) {
  if (a.planes > kMaxTablePlanes || 4 * listed < a.planes) return nullptr;
  switch (path) {
#ifdef WALKVIS_LIST_CULL_X86
    case PlanePath::kAvx512: frontTableAvx512(a, eye, storage.data()); break;
    case PlanePath::kAvx2: frontTableAvx2(a, eye, storage.data()); break;
#endif
    default: frontTableScalar(a, eye, storage.data()); break;
  }
  return storage.data();
}

// Runs ids[0, n) by the plane bytes `front` (frontTableFor), or directly where it is nullptr.
uint32_t* planeRuns(PlanePath path, const PlaneArrays& a, const uint8_t* front, const IndexRange* spans,
                    const uint32_t* ids, size_t n, const glm::dvec3& eye, uint32_t* dst) {
  if (!front) return directRuns(a, spans, ids, n, eye, dst);
#ifdef WALKVIS_LIST_CULL_X86
  if (path == PlanePath::kAvx512) return tableRunsAvx512(a, front, spans, ids, n, dst);
#endif
  (void)path;
  return tableRuns(a, front, spans, ids, n, dst);
}

// The plane test of runs ids[0, n), `listed` positions in all: the plane table where the call
// lists at least a quarter as many positions as there are planes (a table entry costs about what
// a direct test does; the lookups are far cheaper) and the table fits the stack, else direct.
uint32_t* planeTestRuns(PlanePath path, const PlaneArrays& a, uint64_t listed, const IndexRange* spans,
                        const uint32_t* ids, size_t n, const glm::dvec3& eye, uint32_t* dst) {
  FrontTable storage;
  return planeRuns(path, a, frontTableFor(path, a, listed, eye, storage), spans, ids, n, eye, dst);
}

}  // namespace

struct ListCuller::Impl {
  ListCullMethod method = ListCullMethod::kNone;
  std::vector<uint32_t> indices;  // kPad trailing zeros
  std::vector<RangeState> ranges;
  std::vector<IndexRange> spans;  // per range, packed for the batched passes
  uint32_t planes = 0;            // distinct planes (polygon, region, mask)
  PlanePath path = PlanePath::kScalar;
  // polygon, region, mask (its plane-test chunks): the distinct planes of the listed polygons
  // (kPad trailing zero planes) and the plane of each position (kPad trailing zeros)
  std::vector<double> nx, ny, nz, d;
  std::vector<uint32_t> poly_plane;  // by polygon index, up to the largest listed
  // mask
  std::unique_ptr<NormalMaskGrid> grid;
  std::vector<uint16_t> cell;
  std::vector<MaskChunk> chunks;
  std::vector<uint8_t> table_range;  // per range: 1 where a chunk of it uses a table
  uint64_t table_positions = 0;
  // mask with the view cone (view_mask): the clusters its positions use, numbered densely (codes),
  // their four float corners (corner q of code k at q * code_stride + k, zero past `codes`), and
  // each position's code (code8 where there are at most kMaxByteCodes, else code16)
  bool view_mask = false;
  bool vbmi = false;  // viewMaskRunsVbmi: AVX-512 VBMI and BW present, byte codes, simd kAuto
  uint32_t codes = 0, code_stride = 0;
  std::vector<float> code_x, code_y, code_z;
  std::vector<uint8_t> code8;
  std::vector<uint16_t> code16;
  // cluster, hierarchy
  std::vector<uint32_t> unit_of;
  mutable std::vector<uint8_t> unit_flags;  // scratch of the largest range's unit count
  uint64_t bytes = 0;

  // The distinct planes (equal bit for bit: the same test result) and each position's.
  void storePlanes(const BackfaceInput& input, std::span<const uint32_t> idx) {
    using Key = std::array<uint64_t, 4>;
    auto key = [&](uint32_t i) {
      const Plane& p = input.polygons[idx[i]].plane;
      return Key{std::bit_cast<uint64_t>(p.n.x), std::bit_cast<uint64_t>(p.n.y), std::bit_cast<uint64_t>(p.n.z),
                 std::bit_cast<uint64_t>(p.d)};
    };
    std::vector<uint32_t> by_plane(idx.size());
    for (uint32_t i = 0; i < by_plane.size(); ++i) by_plane[i] = i;
    std::sort(by_plane.begin(), by_plane.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    uint32_t max_index = 0;
    for (uint32_t i : idx) max_index = std::max(max_index, i);
    poly_plane.assign(static_cast<size_t>(max_index) + 1, 0);
    nx.clear();
    ny.clear();
    nz.clear();
    d.clear();
    for (size_t k = 0; k < by_plane.size(); ++k) {
      if (k == 0 || key(by_plane[k]) != key(by_plane[k - 1])) {
        const Plane& p = input.polygons[idx[by_plane[k]]].plane;
        nx.push_back(p.n.x);
        ny.push_back(p.n.y);
        nz.push_back(p.n.z);
        d.push_back(p.d);
      }
      poly_plane[idx[by_plane[k]]] = static_cast<uint32_t>(nx.size() - 1);
    }
    planes = static_cast<uint32_t>(nx.size());
    for (std::vector<double>* v : {&nx, &ny, &nz, &d}) v->resize(planes + kPad, 0.0);
  }

  void buildViewMask(const BackfaceInput& input, std::span<const uint32_t> idx, const BackfaceOptions& options);
  uint32_t* viewMaskCall(const BackfaceView& view, const uint32_t* ids, size_t n, uint32_t* dst) const;

  PlaneArrays arrays() const {
    return {nx.data(), ny.data(), nz.data(), d.data(), planes, poly_plane.data(), indices.data()};
  }

  // mask, one range with a table chunk: per chunk the table or (a small chunk) the plane test.
  // `front`: the call's plane bytes for the plane-test chunks (frontTableFor; nullptr: direct).
  uint32_t* maskRange(const RangeState& rs, const glm::dvec3& eye, const uint8_t* front, NormalMaskGrid::Table& table,
                      uint32_t* dst) const;
};

ListCuller ListCuller::build(const BackfaceInput& input, std::span<const uint32_t> indices,
                             std::span<const IndexRange> ranges, ListCullMethod method,
                             const BackfaceOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->method = method;
  if (indices.size() > UINT32_MAX - kPad) {
    throw Error("backface list: " + std::to_string(indices.size()) + " indices; positions are 32-bit");
  }
  impl->indices.assign(indices.begin(), indices.end());
  for (size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= input.polygons.size()) {
      throw Error("backface list: index " + std::to_string(i) + " names polygon " + std::to_string(indices[i]) +
                       " of " + std::to_string(input.polygons.size()));
    }
    const Polygon& p = input.polygons[indices[i]];
    if (!std::isfinite(p.plane.n.x) || !std::isfinite(p.plane.n.y) || !std::isfinite(p.plane.n.z) ||
        !std::isfinite(p.plane.d)) {
      throw Error("backface list: polygon " + std::to_string(indices[i]) + " has a non-finite plane");
    }
    if (static_cast<size_t>(p.first_vertex) + p.vertex_count > input.vertices.size() || p.vertex_count < 3) {
      throw Error("backface list: polygon " + std::to_string(indices[i]) + " has vertices outside the vertex array");
    }
  }
  for (size_t r = 0; r < ranges.size(); ++r) {
    if (static_cast<uint64_t>(ranges[r].first) + ranges[r].count > indices.size()) {
      throw Error("backface list: range " + std::to_string(r) + " [" + std::to_string(ranges[r].first) + ", +" +
                       std::to_string(ranges[r].count) + ") lies outside the " + std::to_string(indices.size()) +
                       " indices");
    }
  }
  impl->ranges.resize(ranges.size());
  impl->spans.assign(ranges.begin(), ranges.end());
  impl->path = resolvePlanePath(options.simd);
  const size_t n = indices.size();
  impl->indices.resize(n + kPad, 0);
  switch (method) {
    case ListCullMethod::kNone: break;
    case ListCullMethod::kPolygon:
    case ListCullMethod::kRegion: {
      impl->storePlanes(input, indices);
      impl->bytes = impl->poly_plane.size() * sizeof(uint32_t) + uint64_t{impl->planes} * 4 * sizeof(double);
      break;
    }
    case ListCullMethod::kMask: {
      if (options.mask_cone != BackfaceOptions::MaskCone::kGroups) {
        impl->buildViewMask(input, indices, options);
        break;
      }
      impl->grid = std::make_unique<NormalMaskGrid>(maskResolutionFor(n, options.mask_resolution));
      impl->cell.resize(n);
      for (size_t i = 0; i < n; ++i) impl->cell[i] = impl->grid->cell(input.polygons[indices[i]].plane.n);
      std::vector<uint8_t> plane_at(n, 0);
      uint64_t table_chunks = 0;
      impl->table_range.assign(impl->ranges.size(), 0);
      for (size_t r = 0; r < impl->ranges.size(); ++r) {
        RangeState& rs = impl->ranges[r];
        const IndexRange span = impl->spans[r];
        rs.chunk_begin = static_cast<uint32_t>(impl->chunks.size());
        const uint32_t size = options.mask_group_size == 0 ? std::max<uint32_t>(span.count, 1) : options.mask_group_size;
        for (uint32_t at = 0; at < span.count; at += size) {
          const uint32_t begin = span.first + at, end = span.first + std::min(span.count, at + size);
          if (end - begin < options.mask_list_min_chunk) {
            MaskChunk c;
            c.begin = begin;
            c.end = end;
            c.planes = true;
            impl->chunks.push_back(c);
            std::fill(plane_at.begin() + begin, plane_at.begin() + end, uint8_t{1});
          } else {
            impl->chunks.push_back(boundChunk(input, indices, begin, end));
            ++table_chunks;
          }
        }
        rs.chunk_end = static_cast<uint32_t>(impl->chunks.size());
        for (uint32_t c = rs.chunk_begin; c < rs.chunk_end; ++c) {
          if (!impl->chunks[c].planes) impl->table_range[r] = 1;
        }
      }
      for (const MaskChunk& c : impl->chunks) impl->table_positions += c.planes ? 0 : c.end - c.begin;
      impl->storePlanes(input, indices);
      uint64_t plane_positions = 0, cell_positions = 0;
      for (size_t i = 0; i < n; ++i) (plane_at[i] ? plane_positions : cell_positions) += 1;
      impl->bytes = cell_positions * sizeof(uint16_t) + (plane_positions ? impl->poly_plane.size() * sizeof(uint32_t) : 0) +
                    uint64_t{impl->planes} * 4 * sizeof(double) +
                    table_chunks * (sizeof(glm::dvec3) + sizeof(double));
      break;
    }
    case ListCullMethod::kCluster:
    case ListCullMethod::kHierarchy: {
      const BackfaceMethod inner = method == ListCullMethod::kCluster ? BackfaceMethod::kCluster : BackfaceMethod::kHierarchy;
      // Lists are drawn from eyes inside the scene: cluster by the culling probability over the
      // scene's box, not over the paper's box around each cluster (backface.h, cluster_eye_lo).
      BackfaceOptions inner_options = options;
      if (!(options.cluster_eye_lo.x <= options.cluster_eye_hi.x) && !input.vertices.empty()) {
        glm::dvec3 lo(INFINITY), hi(-INFINITY);
        for (const glm::dvec3& v : input.vertices) {
          lo = glm::min(lo, v);
          hi = glm::max(hi, v);
        }
        if (lo != hi) {
          inner_options.cluster_eye_lo = lo;
          inner_options.cluster_eye_hi = hi;
        }
      }
      std::vector<Polygon> local;
      std::vector<glm::dvec3> local_vertices;
      size_t max_units = 0;
      for (size_t r = 0; r < impl->ranges.size(); ++r) {
        RangeState& rs = impl->ranges[r];
        const IndexRange span = impl->spans[r];
        if (span.count == 0) continue;
        // The range's polygons with their own vertices only (a method may scan its whole vertex
        // array, e.g. for a bounding box).
        local.clear();
        local_vertices.clear();
        for (uint32_t i = 0; i < span.count; ++i) {
          Polygon poly = input.polygons[indices[span.first + i]];
          const auto v = input.vertices.subspan(poly.first_vertex, poly.vertex_count);
          poly.first_vertex = static_cast<uint32_t>(local_vertices.size());
          local_vertices.insert(local_vertices.end(), v.begin(), v.end());
          local.push_back(poly);
        }
        rs.culler = makeBackfaceCuller(inner, BackfaceInput{local_vertices, local}, inner_options);
        // unit_of: per position of the range, the unit holding its local polygon. Units of these
        // methods are disjoint and cover every polygon (checked: a polygon in no unit is kept).
        rs.unit_of = static_cast<uint32_t>(impl->unit_of.size());
        impl->unit_of.resize(impl->unit_of.size() + span.count, UINT32_MAX);
        const size_t units = rs.culler->unitCount();
        for (size_t u = 0; u < units; ++u) {
          for (uint32_t local_p : rs.culler->unitPolygons(u)) impl->unit_of[rs.unit_of + local_p] = static_cast<uint32_t>(u);
        }
        max_units = std::max(max_units, units + 1);
        impl->bytes += rs.culler->stateBytes() + span.count * sizeof(uint32_t);
      }
      // The extra flag at index max_units - 1 and beyond stays 0: a position in no unit maps to
      // units (the range's own count), whose flag cullRange clears.
      impl->unit_flags.assign(max_units, 0);
      break;
    }
  }
  return ListCuller(std::move(impl));
}

ListCuller::ListCuller(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ListCuller::ListCuller(ListCuller&&) noexcept = default;
ListCuller& ListCuller::operator=(ListCuller&&) noexcept = default;
ListCuller::~ListCuller() = default;

ListCullMethod ListCuller::method() const { return impl_->method; }
size_t ListCuller::rangeCount() const { return impl_->ranges.size(); }
uint64_t ListCuller::bytes() const { return impl_->bytes; }

uint64_t ListCuller::maskTablePositions() const { return impl_->table_positions; }

uint32_t* ListCuller::Impl::maskRange(const RangeState& rs, const glm::dvec3& eye, const uint8_t* front,
                                      NormalMaskGrid::Table& table, uint32_t* dst) const {
  for (uint32_t c = rs.chunk_begin; c < rs.chunk_end; ++c) {
    const MaskChunk& chunk = chunks[c];
    const uint32_t* idx = indices.data() + chunk.begin;
    const uint32_t count = chunk.end - chunk.begin;
    const IndexRange span{chunk.begin, count};  // the chunk as the one run of the passes below
    const uint32_t zero = 0;
    if (chunk.planes) {
      dst = planeRuns(path, arrays(), front, &span, &zero, 1, eye, dst);
      continue;
    }
    glm::dvec3 axis;
    double sin_theta = 0.0;
    if (!sphereCone(eye, chunk.center, chunk.radius, axis, sin_theta)) {
      std::memcpy(dst, idx, count * sizeof(uint32_t));
      dst += count;
      continue;
    }
    grid->backTable(axis, sin_theta, table);
    dst = appendKept(indices.data(), &span, &zero, 1, dst, [&](uint32_t i) { return table[cell[i]] == 0; });
  }
  return dst;
}

void ListCuller::Impl::buildViewMask(const BackfaceInput& input, std::span<const uint32_t> idx,
                                     const BackfaceOptions& options) {
  view_mask = true;
  const size_t n = idx.size();
  grid = std::make_unique<NormalMaskGrid>(maskResolutionFor(n, options.mask_resolution));
  std::vector<uint16_t> cell_at(n);
  for (size_t i = 0; i < n; ++i) cell_at[i] = grid->cell(input.polygons[idx[i]].plane.n);
  std::vector<uint16_t> used = cell_at;
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  codes = static_cast<uint32_t>(used.size());
  code_stride = (codes + 15) / 16 * 16;
  for (std::vector<float>* v : {&code_x, &code_y, &code_z}) v->assign(4 * size_t{code_stride}, 0.0f);
  for (uint32_t k = 0; k < codes; ++k) {
    const std::array<glm::vec3, 4> c = grid->cellCorners(used[k]);
    for (uint32_t q = 0; q < 4; ++q) {
      code_x[q * code_stride + k] = c[q].x;
      code_y[q * code_stride + k] = c[q].y;
      code_z[q * code_stride + k] = c[q].z;
    }
  }
  auto codeOf = [&](uint16_t c) {
    return static_cast<uint32_t>(std::lower_bound(used.begin(), used.end(), c) - used.begin());
  };
  if (codes <= kMaxByteCodes) {
    code8.resize(n);
    for (size_t i = 0; i < n; ++i) code8[i] = static_cast<uint8_t>(codeOf(cell_at[i]));
  } else {
    code16.resize(n);
    for (size_t i = 0; i < n; ++i) code16[i] = static_cast<uint16_t>(codeOf(cell_at[i]));
  }
#ifdef WALKVIS_LIST_CULL_X86
  vbmi = codes <= kMaxByteCodes && options.simd == BackfaceSimd::kAuto && path == PlanePath::kAvx512 &&
         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vbmi") &&
         __builtin_cpu_supports("bmi2");
#endif
  table_positions = n;
  bytes = n * (code8.empty() ? sizeof(uint16_t) : sizeof(uint8_t)) + 12 * uint64_t{code_stride} * sizeof(float);
}

uint32_t* ListCuller::Impl::viewMaskCall(const BackfaceView& view, const uint32_t* ids, size_t n, uint32_t* dst) const {
  const double len = glm::length(view.view_dir);
  if (!(len > 0.0) || !std::isfinite(len) || !(view.fov > 0.0) || !(view.fov < M_PI)) {
    return copyRuns(indices.data(), spans.data(), ids, n, dst);  // no cone: nothing can be culled
  }
  // One flag per code; zero up to kMaxByteCodes for the VBMI lookups' unused entries.
  std::array<uint8_t, 2048> flags;
  static_assert(6 * NormalMaskGrid::kMaxResolution * NormalMaskGrid::kMaxResolution + 1 <= 2048);
  std::memset(flags.data() + codes, 0, codes < kMaxByteCodes ? kMaxByteCodes - codes : 0);
  const glm::vec3 axis(view.view_dir / len);
  const float lim = static_cast<float>(std::sin(0.5 * view.fov) + kMaskCapMargin);
  viewFlags(code_x.data(), code_y.data(), code_z.data(), code_stride, codes, axis, lim, flags.data());
#ifdef WALKVIS_LIST_CULL_X86
  if (vbmi) {
    auto* run = codes <= 64 ? &viewMaskRunsVbmi<64> : codes <= 128 ? &viewMaskRunsVbmi<128> : &viewMaskRunsVbmi<256>;
    return run(indices.data(), code8.data(), flags.data(), spans.data(), ids, n, dst);
  }
#endif
  if (!code8.empty()) return viewMaskRuns(indices.data(), code8.data(), flags.data(), spans.data(), ids, n, dst);
  return viewMaskRuns(indices.data(), code16.data(), flags.data(), spans.data(), ids, n, dst);
}

uint32_t ListCuller::cullRange(uint32_t range, const BackfaceView& view, std::vector<uint32_t>& out) const {
  return cullRanges(std::span<const uint32_t>(&range, 1), view, out);
}

uint32_t ListCuller::cullRanges(std::span<const uint32_t> range_ids, const BackfaceView& view,
                                std::vector<uint32_t>& out) const {
  const Impl& m = *impl_;
  const size_t range_count = m.spans.size();
  uint64_t total = 0;
  for (uint32_t r : range_ids) {
    if (r >= range_count) {
      throw Error("backface list: range " + std::to_string(r) + " of " + std::to_string(range_count));
    }
    total += m.spans[r].count;
  }
  // One resize for the whole call (std::vector has no way to grow without value-initialising);
  // the kernels then write through a raw cursor and may run kListCullOutSlack entries ahead.
  const size_t base = out.size();
  out.resize(base + total + kListCullOutSlack);
  uint32_t* const start = out.data() + base;
  uint32_t* dst = start;
  const uint32_t* ids = range_ids.data();
  const size_t n = range_ids.size();
  switch (m.method) {
    case ListCullMethod::kNone:
      dst = copyRuns(m.indices.data(), m.spans.data(), ids, n, dst);
      break;
    case ListCullMethod::kPolygon:
    case ListCullMethod::kRegion:
      dst = planeTestRuns(m.path, m.arrays(), total, m.spans.data(), ids, n, view.eye, dst);
      break;
    case ListCullMethod::kMask: {
      if (m.view_mask) {
        dst = m.viewMaskCall(view, ids, n, dst);
        break;
      }
      // The plane bytes once per call, for every chunk below mask_list_min_chunk (all of them
      // where no chunk has a table).
      FrontTable storage;
      const uint8_t* front = frontTableFor(m.path, m.arrays(), total, view.eye, storage);
      if (m.table_positions == 0) {
        dst = planeRuns(m.path, m.arrays(), front, m.spans.data(), ids, n, view.eye, dst);
        break;
      }
      NormalMaskGrid::Table table;
      for (size_t k = 0; k < n; ++k) {
        dst = m.table_range[ids[k]] ? m.maskRange(m.ranges[ids[k]], view.eye, front, table, dst)
                                    : planeRuns(m.path, m.arrays(), front, m.spans.data(), ids + k, 1, view.eye, dst);
      }
      break;
    }
    case ListCullMethod::kCluster:
    case ListCullMethod::kHierarchy:
      // The method's own culler per range (its clusters are per range): one call each.
      for (size_t k = 0; k < n; ++k) {
        const RangeState& rs = m.ranges[ids[k]];
        const IndexRange span = m.spans[ids[k]];
        if (span.count == 0) continue;
        const size_t units = rs.culler->unitCount();
        rs.culler->cull(view, std::span<uint8_t>(m.unit_flags.data(), units));
        m.unit_flags[units] = 0;  // positions in no unit map here
        const uint32_t* unit_of = m.unit_of.data() + rs.unit_of;  // by position in the range
        const uint8_t* f = m.unit_flags.data();
        dst = appendKept(m.indices.data(), m.spans.data(), ids + k, 1, dst, [&](uint32_t i) {
          const uint32_t u = unit_of[i - span.first];
          return f[u < units ? u : units] == 0;
        });
      }
      break;
  }
  const size_t kept = static_cast<size_t>(dst - start);
  out.resize(base + kept);
  return static_cast<uint32_t>(total - kept);
}

}  // namespace walkvis
