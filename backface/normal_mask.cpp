// Normal masks: Zhang & Hoff, "Fast Backface Culling Using Normal Masks", I3D 1997
// [ZhangHoff1997].
//
// §2: the normal sphere is cut by the N×N grids of the six faces of its bounding cube into 6·N²
// clusters; a polygon stores its cluster as (byte offset, bit), two bytes. §3: per frame a cluster
// is back-facing when all four corner normals are back-facing for every projection direction of
// the view cone; the back-facing clusters make the backface mask, and the test per polygon is one
// AND, BackMask[offset] & bit. §3.1: for a cone of directions of half-angle θ around axis a, a
// normal n is back-facing for all of them iff angle(n, a) < 90° − θ, i.e. n̂·a > sin θ. That cap
// is spherically convex and a cluster is the cone over a square of the cube face, so all four
// corners in the cap puts every normal of the cluster in it (a nonnegative combination of the
// corners): testing the corners is exact, not an approximation.
//
// Perspective (§3.1 vs §3.2): the paper's view cone (view direction, field of view) covers the
// directions to polygons inside the view cone only; a front face outside it (behind the eye, say)
// may be culled. That is BackfaceOptions::MaskCone::kView. By default each spatial group of polygons
// gets its own cone, the cone from the eye around the group's bounding sphere (§3.2, "a viewing
// cone to each object group"), which holds every direction from the eye to the group: conservative
// for every polygon. An eye inside a group's sphere culls nothing in that group.
//
// Speed (target <= 0.3 ns per polygon, docs/DESIGN.md, "Targets"): the per-frame loop reads a
// 2-byte cluster id per polygon and one byte of a 2048-byte table (normal_mask.h), no branch;
// within each group the polygons are stored sorted by cluster id (the unit order is free: a
// renderer stores its polygons in that order), so the table reads walk forward through the table.
#include "backface/normal_mask.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define WALKVIS_MASK_SHUFFLE 1
#elif defined(__SSE2__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <string>

#include "backface/backface.h"
#include "backface/spread_bits.h"
#include "core/check.h"

namespace walkvis {

int maskResolutionFor(size_t polygons, int requested) {
  if (requested != 0) return requested;
  int n = 4;
  while (n < 16 && 6.0 * (n + 1) * (n + 1) <= static_cast<double>(polygons) / 5.0) ++n;
  return n;
}

NormalMaskGrid::NormalMaskGrid(int n) : n_(n) {
  if (n_ < 1 || n_ > kMaxResolution) {
    throw Error("backface mask: mask_resolution must be in [1, 18], got " + std::to_string(n_));
  }
  const size_t m = static_cast<size_t>(n_) + 1;
  stride_ = (m + 3) / 4 * 4;
  for (int face = 0; face < 6; ++face) {
    const int k = face / 2;
    const double sign = face % 2 == 0 ? 1.0 : -1.0;
    const int a = k == 0 ? 1 : 0, b = k == 2 ? 1 : 2;
    // Rows padded to a multiple of 4 with zero vectors: 0 > limit (>= kMaskCapMargin) never hits.
    for (auto& axis : corner_[static_cast<size_t>(face)]) axis.assign(m * stride_, 0.0f);
    for (size_t i = 0; i < m; ++i) {
      for (size_t j = 0; j < m; ++j) {
        glm::dvec3 c(0.0);
        c[k] = sign;
        c[a] = -1.0 + 2.0 * static_cast<double>(i) / n_;
        c[b] = -1.0 + 2.0 * static_cast<double>(j) / n_;
        c /= glm::length(c);
        for (int x = 0; x < 3; ++x) {
          corner_[static_cast<size_t>(face)][static_cast<size_t>(x)][i * stride_ + j] = static_cast<float>(c[x]);
        }
      }
    }
  }
}

uint16_t NormalMaskGrid::cell(const glm::dvec3& n) const {
  const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
  int k = 0;
  if (ay > ax && ay >= az) k = 1;
  else if (az > ax && az > ay) k = 2;
  const int a = k == 0 ? 1 : 0, b = k == 2 ? 1 : 2;
  const double nk = n[k];
  if (!(std::abs(nk) > 0.0) || !std::isfinite(nk)) return kNeverCell;
  const int face = 2 * k + (nk < 0.0 ? 1 : 0);
  auto index = [&](double c) {
    const double t = (c / std::abs(nk) + 1.0) * 0.5 * n_;
    if (!(t >= 0.0)) return 0;
    return std::min(static_cast<int>(t), n_ - 1);
  };
  return static_cast<uint16_t>(face * n_ * n_ + index(n[a]) * n_ + index(n[b]));
}

std::array<glm::vec3, 4> NormalMaskGrid::cellCorners(uint16_t cell) const {
  std::array<glm::vec3, 4> out{};
  if (cell >= 6 * n_ * n_) return out;  // kNeverCell and beyond: zero vectors, never in a cap
  const int face = cell / (n_ * n_), i = cell / n_ % n_, j = cell % n_;
  const auto& c = corner_[static_cast<size_t>(face)];
  int k = 0;
  for (int di = 0; di < 2; ++di) {
    for (int dj = 0; dj < 2; ++dj) {
      const size_t q = static_cast<size_t>(i + di) * stride_ + static_cast<size_t>(j + dj);
      out[static_cast<size_t>(k++)] = glm::vec3(c[0][q], c[1][q], c[2][q]);
    }
  }
  return out;
}

// The cap n̂·axis > sin θ is spherically convex and a cluster is the cone over a square of the
// cube face, so all four corners in the cap puts every normal of the cluster in it.
void NormalMaskGrid::backTable(const glm::dvec3& axis, double sin_theta, Table& table) const {
  // Ids 6·N² .. 2046 are never given; a 16-byte load reads at most 15 entries past an id, so the
  // cells, 16 entries after them and kNeverCell with its padding are zeroed, not the whole 2 KB
  // (whose memset was a visible share of the per-frame cost of a small mesh: docs/backface/README.md,
  // "Normal masks").
  const size_t cell_count = static_cast<size_t>(6 * n_ * n_);
  std::memset(table.data(), 0, cell_count + kTablePadding);
  std::memset(table.data() + kNeverCell, 0, table.size() - kNeverCell);
  const size_t m = static_cast<size_t>(n_) + 1;
  const double limit = sin_theta + kMaskCapMargin;
  if (!(limit < 1.0)) return;  // the cap is empty
  // The cap's angular radius is ρ = acos(limit); a face's normals lie within 54.74° (acos(1/√3))
  // of its centre; the cap cannot hold a corner of a face whose centre is ρ + 54.74° or more
  // away from the axis: skip it (cheap; the corner test decides everything else).
  const double reach = std::acos(limit) + std::acos(1.0 / std::sqrt(3.0));
  const double min_cos = reach >= M_PI ? -2.0 : std::cos(reach);
  for (int face = 0; face < 6; ++face) {
    const int k = face / 2;
    const double centre_cos = (face % 2 == 0 ? 1.0 : -1.0) * axis[k];
    if (centre_cos <= min_cos) continue;
    const auto& c = corner_[static_cast<size_t>(face)];
    const float* cx = c[0].data();
    const float* cy = c[1].data();
    const float* cz = c[2].data();
    const float ax = static_cast<float>(axis.x), ay = static_cast<float>(axis.y), az = static_cast<float>(axis.z);
    const float lim = static_cast<float>(limit);
    // The cap holds the face's four outer corners: it holds the whole face (convex), every cell in.
    auto inCap = [&](size_t q) { return cx[q] * ax + cy[q] * ay + cz[q] * az > lim; };
    const size_t last = static_cast<size_t>(n_);
    if (inCap(0) && inCap(last) && inCap(last * stride_) && inCap(last * stride_ + last)) {
      std::memset(table.data() + face * n_ * n_, 1, static_cast<size_t>(n_ * n_));
      continue;
    }
    // Rows of corner bits, four corners per SSE compare and MOVMSKPS.
    std::array<uint32_t, kMaxResolution + 1> row{};
    uint32_t any = 0;
    for (size_t i = 0; i < m; ++i) {
      uint32_t bits = 0;
      const size_t r = i * stride_;
#if defined(__SSE2__)
      const __m128 vx = _mm_set1_ps(ax), vy = _mm_set1_ps(ay), vz = _mm_set1_ps(az), vl = _mm_set1_ps(lim);
      for (size_t j = 0; j < stride_; j += 4) {
        const __m128 dot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(cx + r + j), vx), _mm_mul_ps(_mm_loadu_ps(cy + r + j), vy)),
                                      _mm_mul_ps(_mm_loadu_ps(cz + r + j), vz));
        bits |= static_cast<uint32_t>(_mm_movemask_ps(_mm_cmpgt_ps(dot, vl))) << j;
      }
#else
      for (size_t j = 0; j < m; ++j) bits |= static_cast<uint32_t>(inCap(r + j)) << j;
#endif
      row[i] = bits;
      any |= bits;
    }
    if (!any) continue;
    uint8_t* out = table.data() + face * n_ * n_;
    for (size_t i = 0; i < static_cast<size_t>(n_); ++i) {
      // Bit j < N: cell (i, j); bit N and above are 0 (the row has N + 1 corner bits).
      const uint32_t cells = row[i] & (row[i] >> 1) & row[i + 1] & (row[i + 1] >> 1);
      // Eight entries at a time; the last write may run up to 7 bytes into the next row or face,
      // writing zeros there before that row is written (faces and rows go in order; the table
      // has room: 6·18² + 7 < 2048).
      for (size_t j = 0; j < static_cast<size_t>(n_); j += 8) {
        const uint64_t bytes = kSpread[(cells >> j) & 0xffu];
        std::memcpy(out + i * static_cast<size_t>(n_) + j, &bytes, 8);
      }
    }
  }
}

bool sphereCone(const glm::dvec3& eye, const glm::dvec3& center, double radius, glm::dvec3& axis, double& sin_theta) {
  const double eye_scale = kMaskSphereGrowth * std::max({std::abs(eye.x), std::abs(eye.y), std::abs(eye.z)});
  const glm::dvec3 to = center - eye;
  const double dist = glm::length(to);
  const double r = radius + eye_scale;
  if (!(dist > r) || !std::isfinite(dist)) return false;  // eye inside the sphere: every direction is possible
  axis = to / dist;
  sin_theta = r / dist;
  return true;
}

namespace {

// Mean polygons per run of one cluster id from which a group fills runs rather than reading the
// table per polygon (a fill costs about as much as kMinMeanRun single reads and stores), and
// with the byte shuffle (16 reads per operation), from which it fills rather than shuffles: runs of
// about kMinMeanRun cost more per polygon filled than shuffled (docs/backface/README.md, "Normal masks").
constexpr uint32_t kMinMeanRun = 8;
constexpr uint32_t kMinMeanRunShuffled = 32;

// Polygons per shuffle block: the 16 lanes of one SSSE3 byte shuffle.
constexpr uint32_t kBlock = 16;

// A block of kBlock consecutive units whose cluster ids (sorted within the group) lie in
// [base, base + kBlock): their table entries are one 16-byte load at `base`, shuffled by the
// per-unit offsets cell − base. Other blocks read the table once per unit.
struct Block {
  uint16_t base = 0;
  bool shuffle = false;
};

// The lookups of one group's blocks [u, end) (units), one load and one PSHUFB per shuffle block,
// one table read per unit elsewhere. The whole loop carries the target so the shuffle inlines (a
// call per 16 units was most of the per-frame cost of a small mesh: docs/backface/README.md,
// "Normal masks"). SSSE3 is not in the project's baseline flags: the caller checks the CPU first.
#ifdef WALKVIS_MASK_SHUFFLE
[[gnu::target("ssse3")]] void lookupBlocksSsse3(const uint8_t* t, const uint16_t* cell, const uint8_t* offset,
                                                const Block* blk, uint32_t begin, uint32_t end, uint8_t* out) {
  for (uint32_t u = begin; u < end; u += kBlock, ++blk) {
    const uint32_t stop = std::min(end, u + kBlock);
    if (!blk->shuffle) {
      for (uint32_t v = u; v < stop; ++v) out[v] = t[cell[v]];
      continue;
    }
    const __m128i entries = _mm_loadu_si128(reinterpret_cast<const __m128i*>(t + blk->base));
    if (stop - u == kBlock) {
      const __m128i lanes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(offset + u));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + u), _mm_shuffle_epi8(entries, lanes));
    } else {  // the group's last block: offsets past its end are 0, written to scratch
      alignas(16) uint8_t tail[kBlock];
      alignas(16) uint8_t lanes[kBlock] = {};
      std::memcpy(lanes, offset + u, stop - u);
      _mm_store_si128(reinterpret_cast<__m128i*>(tail),
                      _mm_shuffle_epi8(entries, _mm_load_si128(reinterpret_cast<const __m128i*>(lanes))));
      std::memcpy(out + u, tail, stop - u);
    }
  }
}
#endif

bool cpuHasShuffle() {
#ifdef WALKVIS_MASK_SHUFFLE
  return __builtin_cpu_supports("ssse3");
#else
  return false;
#endif
}

struct Run {
  uint32_t begin;  // first unit; the run ends where the next begins (or at its group's end)
  uint16_t cell;
};

struct Group {
  uint32_t begin = 0, end = 0;  // range of units (polygons in group order)
  glm::dvec3 center{0.0};
  double radius = 0.0;  // grown by kMaskSphereGrowth·(|center|∞ + radius) and the plane residuals
  uint32_t run_begin = 0, run_end = 0;  // runs_ of this group when use_runs
  bool use_runs = false;
  uint32_t block_begin = 0;  // blocks_ of this group (kBlock units each from g.begin) when !use_runs
};

class NormalMaskCuller final : public BackfaceCuller {
 public:
  NormalMaskCuller(const BackfaceInput& input, const BackfaceOptions& options)
      : grid_(maskResolutionFor(input.polygons.size(), options.mask_resolution)), use_view_cone_(options.mask_cone == BackfaceOptions::MaskCone::kView) {
    const size_t count = input.polygons.size();
    polygon_count_ = count;

    // Spatial groups (§3.2): median splits on the longest axis of the centroids' box.
    std::vector<glm::dvec3> centroid(count);
    for (size_t p = 0; p < count; ++p) {
      const Polygon& poly = input.polygons[p];
      glm::dvec3 s(0.0);
      for (uint32_t k = 0; k < poly.vertex_count; ++k) s += input.vertices[poly.first_vertex + k];
      centroid[p] = s / static_cast<double>(poly.vertex_count);
    }
    unit_polygons_.resize(count);
    std::iota(unit_polygons_.begin(), unit_polygons_.end(), 0u);
    const size_t group_size = options.mask_group_size == 0 ? std::max<size_t>(count, 1) : options.mask_group_size;
    split(0, static_cast<uint32_t>(count), group_size, centroid);
    if (groups_.empty()) groups_.push_back(Group{});
    std::vector<uint16_t> poly_cell(count);
    for (size_t p = 0; p < count; ++p) poly_cell[p] = grid_.cell(input.polygons[p].plane.n);
    for (Group& g : groups_) {
      bound(g, input);
      std::stable_sort(unit_polygons_.begin() + g.begin, unit_polygons_.begin() + g.end,
                       [&](uint32_t p, uint32_t q) { return poly_cell[p] < poly_cell[q]; });
    }
    unit_begin_.resize(count + 1);
    std::iota(unit_begin_.begin(), unit_begin_.end(), 0u);
    cell_.resize(count);
    for (size_t u = 0; u < count; ++u) cell_[u] = poly_cell[unit_polygons_[u]];
    shuffle_ = cpuHasShuffle();
    // Runs of one cluster id: where they are long, the per-polygon reads of one table entry are
    // one read and one fill (same flags, a fraction of the time).
    for (Group& g : groups_) {
      g.run_begin = static_cast<uint32_t>(runs_.size());
      for (uint32_t u = g.begin; u < g.end; ++u) {
        if (u == g.begin || cell_[u] != cell_[u - 1]) runs_.push_back({u, cell_[u]});
      }
      g.run_end = static_cast<uint32_t>(runs_.size());
      const uint32_t min_run = shuffle_ ? kMinMeanRunShuffled : kMinMeanRun;
      g.use_runs = g.run_end > g.run_begin && (g.end - g.begin) >= min_run * (g.run_end - g.run_begin);
      if (!g.use_runs) runs_.resize(g.run_begin);
      g.run_end = static_cast<uint32_t>(runs_.size());
    }
    runs_.shrink_to_fit();
    offset_.assign(count, 0);
    for (Group& g : groups_) {
      g.block_begin = static_cast<uint32_t>(blocks_.size());
      if (g.use_runs) continue;
      for (uint32_t u = g.begin; u < g.end; u += kBlock) {
        const uint32_t end = std::min(g.end, u + kBlock);
        Block blk;
        blk.base = cell_[u];
        blk.shuffle = shuffle_ && static_cast<uint32_t>(cell_[end - 1]) - cell_[u] < kBlock;
        if (blk.shuffle) {
          for (uint32_t v = u; v < end; ++v) offset_[v] = static_cast<uint8_t>(cell_[v] - blk.base);
          shuffled_units_ += end - u;
        }
        blocks_.push_back(blk);
      }
    }
  }

  BackfaceMethod method() const override { return BackfaceMethod::kMask; }
  size_t stateBytes() const override {
    // A group with runs reads its runs instead of its per-polygon ids.
    // A shuffled unit reads its 1-byte offset (and its block's 2-byte base) instead of its id.
    size_t ids = 0;
    for (const Group& g : groups_) ids += g.use_runs ? 0 : g.end - g.begin;
    ids -= shuffled_units_;
    return ids * sizeof(uint16_t) + shuffled_units_ * sizeof(uint8_t) + blocks_.size() * sizeof(uint16_t) +
           runs_.size() * (sizeof(uint32_t) + sizeof(uint16_t)) +
           groups_.size() * (sizeof(glm::dvec3) + sizeof(double));
  }

  void cull(const BackfaceView& view, std::span<uint8_t> unit_culled) const override {
    WALKVIS_DCHECK(unit_culled.size() == unitCount());
    NormalMaskGrid::Table table;
    if (use_view_cone_) {
      const double len = glm::length(view.view_dir);
      const bool usable = len > 0.0 && std::isfinite(len) && view.fov > 0.0 && view.fov < M_PI;
      if (usable) {
        grid_.backTable(view.view_dir / len, std::sin(0.5 * view.fov), table);
      } else {
        table.fill(0);
      }
      for (const Group& g : groups_) lookup(g, table, unit_culled);
      return;
    }
    for (const Group& g : groups_) {
      glm::dvec3 axis;
      double sin_theta = 0.0;
      if (!sphereCone(view.eye, g.center, g.radius, axis, sin_theta)) {
        std::fill(unit_culled.begin() + g.begin, unit_culled.begin() + g.end, uint8_t{0});
        continue;
      }
      grid_.backTable(axis, sin_theta, table);
      lookup(g, table, unit_culled);
    }
  }

 private:
  // §3: the test per polygon, one table read (per run of equal ids where the group has runs).
  void lookup(const Group& g, const NormalMaskGrid::Table& table, std::span<uint8_t> unit_culled) const {
    if (g.use_runs) {
      for (uint32_t r = g.run_begin; r < g.run_end; ++r) {
        const uint32_t end = r + 1 < g.run_end ? runs_[r + 1].begin : g.end;
        std::memset(unit_culled.data() + runs_[r].begin, table[runs_[r].cell], end - runs_[r].begin);
      }
      return;
    }
    const uint16_t* cell = cell_.data();
    const uint8_t* t = table.data();
    uint8_t* out = unit_culled.data();
#ifdef WALKVIS_MASK_SHUFFLE
    if (shuffle_) {
      lookupBlocksSsse3(t, cell, offset_.data(), blocks_.data() + g.block_begin, g.begin, g.end, out);
      return;
    }
#endif
    for (uint32_t u = g.begin; u < g.end; ++u) out[u] = t[cell[u]];
  }

  void split(uint32_t begin, uint32_t end, size_t group_size, const std::vector<glm::dvec3>& centroid) {
    if (end - begin <= group_size) {
      if (end > begin) groups_.push_back(Group{begin, end});
      return;
    }
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (uint32_t u = begin; u < end; ++u) {
      lo = glm::min(lo, centroid[unit_polygons_[u]]);
      hi = glm::max(hi, centroid[unit_polygons_[u]]);
    }
    const glm::dvec3 ext = hi - lo;
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(unit_polygons_.begin() + begin, unit_polygons_.begin() + mid, unit_polygons_.begin() + end,
                     [&](uint32_t p, uint32_t q) { return centroid[p][axis] < centroid[q][axis]; });
    split(begin, mid, group_size, centroid);
    split(mid, end, group_size, centroid);
  }

  // The group's bounding sphere, grown so that it holds, for every vertex v, the point of the
  // polygon's plane nearest to v (|n·v − d| away): the cone test then speaks of the planes.
  void bound(Group& g, const BackfaceInput& input) const {
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (uint32_t u = g.begin; u < g.end; ++u) {
      const Polygon& poly = input.polygons[unit_polygons_[u]];
      for (uint32_t k = 0; k < poly.vertex_count; ++k) {
        lo = glm::min(lo, input.vertices[poly.first_vertex + k]);
        hi = glm::max(hi, input.vertices[poly.first_vertex + k]);
      }
    }
    if (g.begin == g.end) return;
    g.center = 0.5 * (lo + hi);
    double r = 0.0;
    for (uint32_t u = g.begin; u < g.end; ++u) {
      const Polygon& poly = input.polygons[unit_polygons_[u]];
      for (uint32_t k = 0; k < poly.vertex_count; ++k) {
        const glm::dvec3& v = input.vertices[poly.first_vertex + k];
        const double residual = std::abs(glm::dot(poly.plane.n, v) - poly.plane.d);
        r = std::max(r, glm::length(v - g.center) + residual);
      }
    }
    const double scale = std::max({std::abs(g.center.x), std::abs(g.center.y), std::abs(g.center.z), r});
    g.radius = r + kMaskSphereGrowth * scale;
  }

  NormalMaskGrid grid_;
  bool use_view_cone_;
  std::vector<Group> groups_;
  std::vector<uint16_t> cell_;  // per unit: the 2-byte cluster id of §2.2
  std::vector<Run> runs_;
  bool shuffle_ = false;           // the CPU has SSSE3 (checked once, at build)
  std::vector<Block> blocks_;      // per group without runs, per kBlock units
  std::vector<uint8_t> offset_;    // per unit of a shuffle block: cluster id − block base
  size_t shuffled_units_ = 0;
};

}  // namespace

std::unique_ptr<BackfaceCuller> makeNormalMaskCuller(const BackfaceInput& input, const BackfaceOptions& options) {
  return std::make_unique<NormalMaskCuller>(input, options);
}

}  // namespace walkvis
