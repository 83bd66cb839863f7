// Backface culling inside priority lists (list_cull.h; issue 6, DESIGN.md "Facing at emission").
// The methods are those of backface.h, each citing its paper in its own file:
//   polygon, region  the plane test per polygon (polygon_cull.cpp)
//   mask             Zhang & Hoff 1997 normal masks (normal_mask.cpp, normal_mask.h)
//   cluster          Johannsen & Carter 1998 clustered backface test (clustered.cpp)
//   hierarchy        Kumar et al. 1996 hierarchical back-face computation (hierarchical_kumar.cpp)
//
// A range must come out in its own order (it is a priority list: painter's order), so per range the
// per-frame state is laid out by position in the range:
//   polygon/region: the plane (n, d) per position, in double, evaluated exactly as isFrontFacing();
//   mask: the 2-byte cluster id per position and one bounding sphere per chunk of the range (the
//     paper's per-group view cone, §3.2; chunks of mask_group_size positions, 0 = the whole range);
//     per frame one table per chunk from the cone from the eye around its sphere. A chunk of fewer
//     than mask_list_min_chunk positions gets the plane test instead: a table costs ~1 us, the
//     plane test ~1 ns per polygon, and PFD runs average under 2 fragments, so a table per run
//     (57 ns per listed polygon measured on Freedoom MAP01) can never pay there. No table can be
//     shared by the runs of a frame either: it needs one cone holding every direction from the
//     eye to the polygons it tests, and for an eye inside the building that is the whole sphere
//     (an empty mask). Zhang & Hoff's masks are a whole-object method: they pay on big groups;
//     an eye inside a group's bounding sphere culls nothing in it (gen:office in z-buffer mode, one
//     group of the whole building: 0 culled; see the bench);
//   cluster/hierarchy: the method's own culler built over the range's polygons (its clusters are
//     formed per range) and the unit of each position, so that the unit flags map back in order.
//     cluster's culling probability is taken over the box of all input vertices (the eyes of a
//     walkthrough are inside it) unless the options name an eye box: with the paper's box around
//     each cluster's origin, gen:office's walls merged into 6 clusters, one per orientation, and
//     an eye inside culled none of them (0 per frame in z-buffer mode; backface.h).
// Survivors are appended by a branch-free compaction into `out`.
#include "backface/list_cull.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>

#include "backface/normal_mask.h"

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
  throw SceneError("backface list method '" + std::string(name) +
                   "': expected none, polygon, mask, cluster, hierarchy or region");
}

namespace {

struct MaskChunk {
  uint32_t begin = 0, end = 0;  // positions into the index array
  glm::dvec3 center{0.0};
  double radius = -1.0;  // < 0: empty chunk
  bool planes = false;   // too small for a table: the plane test (planes of Impl::nx.. at its positions)
};

struct RangeState {
  uint32_t first = 0, count = 0;
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

}  // namespace

struct ListCuller::Impl {
  ListCullMethod method = ListCullMethod::kNone;
  std::vector<uint32_t> indices;
  std::vector<RangeState> ranges;
  // polygon, region
  std::vector<double> nx, ny, nz, d;
  // mask
  std::unique_ptr<NormalMaskGrid> grid;
  std::vector<uint16_t> cell;
  std::vector<MaskChunk> chunks;
  // cluster, hierarchy
  std::vector<uint32_t> unit_of;
  mutable std::vector<uint8_t> unit_flags;  // scratch of the largest range's unit count
  uint64_t bytes = 0;

  void storePlanes(const BackfaceInput& input, std::span<const uint32_t> idx) {
    nx.resize(idx.size());
    ny.resize(idx.size());
    nz.resize(idx.size());
    d.resize(idx.size());
    for (size_t i = 0; i < idx.size(); ++i) {
      const Plane& p = input.polygons[idx[i]].plane;
      nx[i] = p.n.x;
      ny[i] = p.n.y;
      nz[i] = p.n.z;
      d[i] = p.d;
    }
  }

  // The plane test of positions [first, first + count): survivors appended to out, culled returned.
  uint32_t planeTest(uint32_t first, uint32_t count, const glm::dvec3& eye, std::vector<uint32_t>& out) const {
    const double ex = eye.x, ey = eye.y, ez = eye.z;
    const double* px = nx.data() + first;
    const double* py = ny.data() + first;
    const double* pz = nz.data() + first;
    const double* pd = d.data() + first;
    // Same expression as glm::dot (x + y) + z: equal to isFrontFacing() bit for bit.
    return compact(indices.data() + first, count, out,
                   [&](uint32_t i) { return (px[i] * ex + py[i] * ey) + pz[i] * ez > pd[i]; });
  }

  // Appends indices[first + i] for every i with keep(i) true, without a branch per element.
  template <typename Keep>
  static uint32_t compact(const uint32_t* idx, uint32_t count, std::vector<uint32_t>& out, Keep keep) {
    const size_t base = out.size();
    out.resize(base + count);
    uint32_t* dst = out.data() + base;
    size_t k = 0;
    for (uint32_t i = 0; i < count; ++i) {
      dst[k] = idx[i];
      k += keep(i) ? 1 : 0;
    }
    out.resize(base + k);
    return count - static_cast<uint32_t>(k);
  }
};

ListCuller ListCuller::build(const BackfaceInput& input, std::span<const uint32_t> indices,
                             std::span<const IndexRange> ranges, ListCullMethod method,
                             const BackfaceOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->method = method;
  impl->indices.assign(indices.begin(), indices.end());
  for (size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= input.polygons.size()) {
      throw SceneError("backface list: index " + std::to_string(i) + " names polygon " + std::to_string(indices[i]) +
                       " of " + std::to_string(input.polygons.size()));
    }
    const Polygon& p = input.polygons[indices[i]];
    if (!std::isfinite(p.plane.n.x) || !std::isfinite(p.plane.n.y) || !std::isfinite(p.plane.n.z) ||
        !std::isfinite(p.plane.d)) {
      throw SceneError("backface list: polygon " + std::to_string(indices[i]) + " has a non-finite plane");
    }
    if (static_cast<size_t>(p.first_vertex) + p.vertex_count > input.vertices.size() || p.vertex_count < 3) {
      throw SceneError("backface list: polygon " + std::to_string(indices[i]) + " has vertices outside the vertex array");
    }
  }
  for (size_t r = 0; r < ranges.size(); ++r) {
    if (static_cast<uint64_t>(ranges[r].first) + ranges[r].count > indices.size()) {
      throw SceneError("backface list: range " + std::to_string(r) + " [" + std::to_string(ranges[r].first) + ", +" +
                       std::to_string(ranges[r].count) + ") lies outside the " + std::to_string(indices.size()) +
                       " indices");
    }
  }
  if (method == ListCullMethod::kMask && options.mask_use_view_cone) {
    throw SceneError("backface list: mask_use_view_cone may cull front faces outside the view cone; not allowed in lists");
  }

  impl->ranges.resize(ranges.size());
  for (size_t r = 0; r < ranges.size(); ++r) {
    impl->ranges[r].first = ranges[r].first;
    impl->ranges[r].count = ranges[r].count;
  }
  const size_t n = indices.size();
  switch (method) {
    case ListCullMethod::kNone: break;
    case ListCullMethod::kPolygon:
    case ListCullMethod::kRegion: {
      impl->storePlanes(input, indices);
      impl->bytes = n * 4 * sizeof(double);
      break;
    }
    case ListCullMethod::kMask: {
      impl->grid = std::make_unique<NormalMaskGrid>(maskResolutionFor(n, options.mask_resolution));
      impl->cell.resize(n);
      for (size_t i = 0; i < n; ++i) impl->cell[i] = impl->grid->cell(input.polygons[indices[i]].plane.n);
      std::vector<uint8_t> plane_at(n, 0);
      uint64_t table_chunks = 0;
      for (RangeState& rs : impl->ranges) {
        rs.chunk_begin = static_cast<uint32_t>(impl->chunks.size());
        const uint32_t size = options.mask_group_size == 0 ? std::max<uint32_t>(rs.count, 1) : options.mask_group_size;
        for (uint32_t at = 0; at < rs.count; at += size) {
          const uint32_t begin = rs.first + at, end = rs.first + std::min(rs.count, at + size);
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
      }
      impl->storePlanes(input, indices);
      uint64_t plane_positions = 0, cell_positions = 0;
      for (size_t i = 0; i < n; ++i) (plane_at[i] ? plane_positions : cell_positions) += 1;
      impl->bytes = cell_positions * sizeof(uint16_t) + plane_positions * 4 * sizeof(double) +
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
      for (RangeState& rs : impl->ranges) {
        if (rs.count == 0) continue;
        // The range's polygons with their own vertices only (a method may scan its whole vertex
        // array, e.g. for a bounding box).
        local.clear();
        local_vertices.clear();
        for (uint32_t i = 0; i < rs.count; ++i) {
          Polygon poly = input.polygons[indices[rs.first + i]];
          const auto v = input.vertices.subspan(poly.first_vertex, poly.vertex_count);
          poly.first_vertex = static_cast<uint32_t>(local_vertices.size());
          local_vertices.insert(local_vertices.end(), v.begin(), v.end());
          local.push_back(poly);
        }
        rs.culler = makeBackfaceCuller(inner, BackfaceInput{local_vertices, local}, inner_options);
        // unit_of: per position of the range, the unit holding its local polygon. Units of these
        // methods are disjoint and cover every polygon (checked: a polygon in no unit is kept).
        rs.unit_of = static_cast<uint32_t>(impl->unit_of.size());
        impl->unit_of.resize(impl->unit_of.size() + rs.count, UINT32_MAX);
        const size_t units = rs.culler->unitCount();
        for (size_t u = 0; u < units; ++u) {
          for (uint32_t local_p : rs.culler->unitPolygons(u)) impl->unit_of[rs.unit_of + local_p] = static_cast<uint32_t>(u);
        }
        max_units = std::max(max_units, units + 1);
        impl->bytes += rs.culler->stateBytes() + rs.count * sizeof(uint32_t);
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

uint32_t ListCuller::cullRange(uint32_t range, const BackfaceView& view, std::vector<uint32_t>& out) const {
  const Impl& m = *impl_;
  if (range >= m.ranges.size()) {
    throw SceneError("backface list: range " + std::to_string(range) + " of " + std::to_string(m.ranges.size()));
  }
  const RangeState& rs = m.ranges[range];
  const uint32_t* idx = m.indices.data() + rs.first;
  switch (m.method) {
    case ListCullMethod::kNone:
      out.insert(out.end(), idx, idx + rs.count);
      return 0;
    case ListCullMethod::kPolygon:
    case ListCullMethod::kRegion:
      return m.planeTest(rs.first, rs.count, view.eye, out);
    case ListCullMethod::kMask: {
      uint32_t culled = 0;
      NormalMaskGrid::Table table;
      for (uint32_t c = rs.chunk_begin; c < rs.chunk_end; ++c) {
        const MaskChunk& chunk = m.chunks[c];
        const uint32_t count = chunk.end - chunk.begin;
        if (chunk.planes) {
          culled += m.planeTest(chunk.begin, count, view.eye, out);
          continue;
        }
        glm::dvec3 axis;
        double sin_theta = 0.0;
        if (!sphereCone(view.eye, chunk.center, chunk.radius, axis, sin_theta)) {
          out.insert(out.end(), m.indices.data() + chunk.begin, m.indices.data() + chunk.end);
          continue;
        }
        m.grid->backTable(axis, sin_theta, table);
        const uint16_t* cell = m.cell.data() + chunk.begin;
        const uint8_t* t = table.data();
        culled += Impl::compact(m.indices.data() + chunk.begin, count, out, [&](uint32_t i) { return t[cell[i]] == 0; });
      }
      return culled;
    }
    case ListCullMethod::kCluster:
    case ListCullMethod::kHierarchy: {
      if (rs.count == 0) return 0;
      const size_t units = rs.culler->unitCount();
      std::span<uint8_t> flags(m.unit_flags.data(), units);
      rs.culler->cull(view, flags);
      m.unit_flags[units] = 0;  // positions in no unit map here
      const uint32_t* unit_of = m.unit_of.data() + rs.unit_of;
      const uint8_t* f = m.unit_flags.data();
      return Impl::compact(idx, rs.count, out, [&](uint32_t i) {
        const uint32_t u = unit_of[i];
        return f[u < units ? u : units] == 0;
      });
    }
  }
  return 0;
}

}  // namespace walkvis
