// Walkable floors the way a navmesh finds them: Recast's voxel pipeline (Mikko Mononen, Recast
// Navigation, https://github.com/recastnavigation/recastnavigation; the solid heightfield, its
// ledge / low-hanging / headroom filters, the compact open heightfield with its climb-aware
// neighbour links and the erosion by the agent radius) decides which cells a walker can stand on.
// On top of the cells (walkable.h):
//  * candidate floor heights are the scene's exact upward horizontal faces; a walkable cell whose
//    floor lies within a cell height or so of one takes it; cells linked by Recast's neighbour
//    links at one candidate height form an area;
//  * a level is an area of at least min_level_area linked (through any walkable cells, stairs and
//    ramps included) to the largest area of the scene; one FloorLevel per such height;
//  * walkable cells linked to that largest area but on no level (treads, ramps, small landings)
//    are grouped into connections;
//  * regions are the exact faces clipped to the cells: cells merged into maximal rectangles (row
//    runs stacked while they repeat), each face clipped to each rectangle (Sutherland–Hodgman
//    against axis-aligned lines), so the pieces stay convex and on the scene's own faces.
#include "scenes/walkable.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <unordered_map>
#include <unordered_set>
#include <string>
#include <tuple>
#include <vector>

#include <Recast.h>

namespace walkvis {
namespace {

// Recast wants a column per cell; 4M columns (a 2000 × 2000 grid, ~100 MB of Recast memory at
// most for a few spans per column) is where the cell size is coarsened instead.
constexpr double kMaxColumns = 4.0e6;
// A piece of a face clipped to a cell rectangle with less than this fraction of a cell's area
// is a sliver where a face edge runs along a cell line: nothing to stand on.
constexpr double kMinPieceCellFraction = 1e-3;

struct Rect {
  int x0, x1, z0, z1;  // cells [x0, x1] × [z0, z1], inclusive
  int tag = -1;        // for connection rectangles: a level whose own faces are left out (-1 none)
};


// Sutherland–Hodgman against one axis-aligned line: keeps coord[axis] * sign >= value * sign.
// The cut point is computed from the edge's two ends in one order (lower end first) so that
// neighbouring pieces cut along one line get the same vertex.
void clipAxis(const std::vector<glm::dvec2>& in, std::vector<glm::dvec2>& out, int axis, double value, double sign) {
  out.clear();
  const size_t n = in.size();
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2& a = in[i];
    const glm::dvec2& b = in[(i + 1) % n];
    const double sa = (a[axis] - value) * sign, sb = (b[axis] - value) * sign;
    if (sa >= 0.0) out.push_back(a);
    if ((sa >= 0.0) != (sb >= 0.0) && sa != 0.0 && sb != 0.0) {
      const bool a_first = a[axis] < b[axis];
      const glm::dvec2& p = a_first ? a : b;
      const glm::dvec2& q = a_first ? b : a;
      const double t = (value - p[axis]) / (q[axis] - p[axis]);
      glm::dvec2 c = p + t * (q - p);
      c[axis] = value;
      out.push_back(c);
    }
  }
}

std::vector<glm::dvec2> clipToBox(const std::vector<glm::dvec2>& poly, double x0, double x1, double z0, double z1) {
  std::vector<glm::dvec2> a = poly, b;
  clipAxis(a, b, 0, x0, 1.0);
  clipAxis(b, a, 0, x1, -1.0);
  clipAxis(a, b, 1, z0, 1.0);
  clipAxis(b, a, 1, z1, -1.0);
  // Repeated vertices (a corner on a clip line) carry no shape.
  std::vector<glm::dvec2> out;
  for (const auto& p : a)
    if (out.empty() || out.back() != p) out.push_back(p);
  while (out.size() > 1 && out.back() == out.front()) out.pop_back();
  return out;
}

// Cells (z, x) sorted by row, merged into maximal rectangles: runs per row, a run extended
// downwards while the next row has exactly the same run.
std::vector<Rect> cellsToRects(std::vector<std::pair<int, int>> cells) {
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  std::vector<Rect> done;
  std::map<std::pair<int, int>, Rect> open;  // (x0, x1) -> rectangle still growing
  size_t i = 0;
  while (i < cells.size()) {
    const int z = cells[i].first;
    std::map<std::pair<int, int>, Rect> next;
    while (i < cells.size() && cells[i].first == z) {
      const int x0 = cells[i].second;
      int x1 = x0;
      ++i;
      while (i < cells.size() && cells[i].first == z && cells[i].second == x1 + 1) x1 = cells[i++].second;
      auto it = open.find({x0, x1});
      if (it != open.end() && it->second.z1 == z - 1) {
        Rect r = it->second;
        r.z1 = z;
        next[{x0, x1}] = r;
        open.erase(it);
      } else {
        next[{x0, x1}] = Rect{x0, x1, z, z};
      }
    }
    for (auto& [k, r] : open) done.push_back(r);
    open = std::move(next);
  }
  for (auto& [k, r] : open) done.push_back(r);
  return done;
}

struct FaceXz {
  uint32_t polygon;
  double lo_x, hi_x, lo_z, hi_z;
  std::vector<glm::dvec2> ring;
};

FaceXz faceXz(const Scene& scene, uint32_t i) {
  FaceXz f{i, std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
           std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(), {}};
  for (const auto& v : scene.polygonVertices(i)) {
    f.ring.emplace_back(v.x, v.z);
    f.lo_x = std::min(f.lo_x, v.x), f.hi_x = std::max(f.hi_x, v.x);
    f.lo_z = std::min(f.lo_z, v.z), f.hi_z = std::max(f.hi_z, v.z);
  }
  return f;
}

struct RecastFree {
  void operator()(rcHeightfield* h) const { rcFreeHeightField(h); }
  void operator()(rcCompactHeightfield* h) const { rcFreeCompactHeightfield(h); }
};

std::string fmt(const char* format, double a, double b = 0.0, double c = 0.0, double d = 0.0, double e = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c, d, e);
  return buf;
}

}  // namespace

void deriveWalkableLevels(Scene& scene, const WalkableOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const double eye = scene.eye_height;
  if (!(eye > 0.0) || !std::isfinite(eye)) throw Error(scene.name + ": the eye height must be positive");
  const double agent_height = options.agent_height < 0.0 ? 1.2 * eye : options.agent_height;
  const double radius = options.agent_radius < 0.0 ? 0.15 * eye : options.agent_radius;
  const double climb = options.max_climb < 0.0 ? 0.2 * eye : options.max_climb;
  const double slope = options.max_slope_deg;
  const double min_area = options.min_level_area < 0.0 ? 0.35 * eye * eye : options.min_level_area;
  if (!(agent_height > 0.0) || !std::isfinite(agent_height))
    throw Error(scene.name + ": the agent height must be a positive finite number");
  if (!(radius >= 0.0) || !std::isfinite(radius) || radius > 10.0 * agent_height)
    throw Error(scene.name + ": the agent radius must be in [0, 10 x agent height]");
  if (!(climb >= 0.0) || !(climb < agent_height))
    throw Error(scene.name + ": the maximum climb must be in [0, agent height)");
  if (!(slope > 0.0 && slope < 90.0)) throw Error(scene.name + ": the maximum slope must be in (0, 90) degrees");
  if (!(min_area >= 0.0) || !std::isfinite(min_area))
    throw Error(scene.name + ": the minimum level area must be a finite number >= 0");

  scene.levels.clear();
  scene.connections.clear();
  if (scene.polygons.empty()) return;
  const Bounds b = sceneBounds(scene);
  const glm::dvec3 origin = b.lo;  // Recast works in floats: coordinates relative to the bounds
  const glm::dvec3 size = b.hi - b.lo;

  // Cell size: a third of the radius (Recast's advice: erosion of ~3 cells), the grid kept under
  // kMaxColumns. Cell height: an eighth of the climb, kept under Recast's 13-bit span heights.
  // Headroom is what the height costs: a floor's top rounds up and a ceiling's underside down to
  // whole voxels, and the agent's height up, so a gap reads up to 3 cell heights lower than it is
  // (0.13 m at a 1.7 m eye; at a quarter of the climb it was 0.26 m, which shut stairs whose
  // slab edge leaves the walker a few centimetres). Spans are solid runs, so a finer height costs
  // hardly any memory, only Recast's 13 bits.
  double cs = radius > 0.0 ? radius / 3.0 : 0.05 * eye;
  cs = std::max(cs, std::sqrt(std::max(size.x, 1e-300) * std::max(size.z, 1e-300) / kMaxColumns));
  cs = std::max({cs, size.x / 4000.0, size.z / 4000.0});  // also under 4000 cells on a side
  double ch = climb > 0.0 ? climb / 8.0 : agent_height / 40.0;
  ch = std::max(ch, (size.y + agent_height) / (RC_SPAN_MAX_HEIGHT - 64));
  const int walk_height = std::max(3, static_cast<int>(std::ceil(agent_height / ch)));
  const int walk_climb = static_cast<int>(std::floor(climb / ch + 1e-9));  // 1e-9: climb = 8 ch exactly
  const int walk_radius = std::min(254, static_cast<int>(std::ceil(radius / cs - 1e-9)));
  const int width = static_cast<int>(std::ceil(size.x / cs)) + 2;  // a cell of margin on each side
  const int depth = static_cast<int>(std::ceil(size.z / cs)) + 2;

  rcContext ctx(false);
  std::unique_ptr<rcHeightfield, RecastFree> hf(rcAllocHeightfield());
  std::unique_ptr<rcCompactHeightfield, RecastFree> chf(rcAllocCompactHeightfield());
  const float bmin[3] = {static_cast<float>(-cs), 0.0f, static_cast<float>(-cs)};
  const float bmax[3] = {static_cast<float>(-cs + width * cs), static_cast<float>(size.y + agent_height + ch),
                         static_cast<float>(-cs + depth * cs)};
  if (!hf || !chf || !rcCreateHeightfield(&ctx, *hf, width, depth, bmin, bmax, static_cast<float>(cs),
                                          static_cast<float>(ch)))
    throw Error(scene.name + ": out of memory for the walkable heightfield");
  {
    std::vector<float> verts(scene.vertices.size() * 3);
    for (size_t i = 0; i < scene.vertices.size(); ++i) {
      const glm::dvec3 p = scene.vertices[i] - origin;
      verts[3 * i] = static_cast<float>(p.x), verts[3 * i + 1] = static_cast<float>(p.y),
                verts[3 * i + 2] = static_cast<float>(p.z);
    }
    std::vector<int> tris;
    for (const auto& p : scene.polygons) {
      for (uint32_t k = 1; k + 1 < p.vertex_count; ++k) {
        tris.push_back(static_cast<int>(p.first_vertex));
        tris.push_back(static_cast<int>(p.first_vertex + k));
        tris.push_back(static_cast<int>(p.first_vertex + k + 1));
      }
    }
    const int nt = static_cast<int>(tris.size() / 3);
    std::vector<unsigned char> areas(nt, RC_NULL_AREA);
    rcMarkWalkableTriangles(&ctx, static_cast<float>(slope), verts.data(), static_cast<int>(scene.vertices.size()),
                            tris.data(), nt, areas.data());
    if (!rcRasterizeTriangles(&ctx, verts.data(), static_cast<int>(scene.vertices.size()), tris.data(), areas.data(),
                              nt, *hf, walk_climb))
      throw Error(scene.name + ": Recast could not rasterize the scene");
  }
  rcFilterLowHangingWalkableObstacles(&ctx, walk_climb, *hf);
  rcFilterLedgeSpans(&ctx, walk_height, walk_climb, *hf);
  rcFilterWalkableLowHeightSpans(&ctx, walk_height, *hf);
  if (!rcBuildCompactHeightfield(&ctx, walk_height, walk_climb, *hf, *chf))
    throw Error(scene.name + ": Recast could not build the compact heightfield");
  if (walk_radius > 0 && !rcErodeWalkableArea(&ctx, walk_radius, *chf))
    throw Error(scene.name + ": Recast could not erode the walkable area");

  const int span_count = chf->spanCount;
  std::vector<int> span_x(span_count), span_z(span_count);
  for (int z = 0; z < depth; ++z)
    for (int x = 0; x < width; ++x) {
      const rcCompactCell& c = chf->cells[x + z * width];
      for (int i = static_cast<int>(c.index), e = i + static_cast<int>(c.count); i < e; ++i) span_x[i] = x, span_z[i] = z;
    }
  const auto walkable = [&](int i) { return chf->areas[i] != RC_NULL_AREA; };
  const auto spanFloor = [&](int i) { return origin.y + chf->spans[i].y * ch; };
  // Neighbours through Recast's links (they already respect the climb and the headroom).
  const auto forNeighbours = [&](int i, auto&& f) {
    const rcCompactSpan& s = chf->spans[i];
    for (int dir = 0; dir < 4; ++dir) {
      const int con = rcGetCon(s, dir);
      if (con == RC_NOT_CONNECTED) continue;
      const int nx = span_x[i] + rcGetDirOffsetX(dir), nz = span_z[i] + rcGetDirOffsetY(dir);
      const int j = static_cast<int>(chf->cells[nx + nz * width].index) + con;
      if (walkable(j)) f(j);
    }
  };

  // Candidate heights: exact upward horizontal faces, grouped as deriveFloorLevels groups them.
  std::vector<double> cand_y;
  std::vector<std::vector<uint32_t>> cand_faces;
  std::vector<int> poly_cand(scene.polygons.size(), -1);
  for (FloorHeight& height : upwardFloorHeights(scene)) {
    for (uint32_t idx : height.polygons) poly_cand[idx] = static_cast<int>(cand_y.size());
    cand_y.push_back(height.y);
    cand_faces.push_back(std::move(height.polygons));
  }
  // Cell rectangles are in grid coordinates; one formula turns them into scene coordinates so
  // that neighbouring rectangles share their edges exactly.
  const auto cellX = [&](int x) { return origin.x - cs + x * cs; };
  const auto cellZ = [&](int z) { return origin.z - cs + z * cs; };
  const double cell_area = cs * cs;
  const double min_piece = kMinPieceCellFraction * cell_area;
  // Which cells each candidate's faces cover (a piece of more than min_piece): a voxel floor
  // at a candidate's height is that floor only where one of its faces is (the foot of a ramp
  // rounds to the height of the floor before it).
  const int64_t ncols = static_cast<int64_t>(width) * depth;
  std::unordered_set<int64_t> covered;
  {
    std::vector<glm::dvec2> band, tmp;
    for (int c = 0; c < static_cast<int>(cand_y.size()); ++c) {
      for (uint32_t f : cand_faces[c]) {
        const FaceXz face = faceXz(scene, f);
        const int z_lo = std::max(0, static_cast<int>(std::floor((face.lo_z - cellZ(0)) / cs)));
        const int z_hi = std::min(depth - 1, static_cast<int>(std::floor((face.hi_z - cellZ(0)) / cs)));
        for (int z = z_lo; z <= z_hi; ++z) {
          clipAxis(face.ring, tmp, 1, cellZ(z), 1.0);
          clipAxis(tmp, band, 1, cellZ(z + 1), -1.0);
          if (band.size() < 3 || std::abs(signedArea(band)) <= min_piece) continue;
          double lo = band[0].x, hi = band[0].x;
          for (const auto& p : band) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
          const int x_lo = std::max(0, static_cast<int>(std::floor((lo - cellX(0)) / cs)));
          const int x_hi = std::min(width - 1, static_cast<int>(std::ceil((hi - cellX(0)) / cs)) - 1);
          for (int x = x_lo; x <= x_hi; ++x) covered.insert(c * ncols + static_cast<int64_t>(z) * width + x);
        }
      }
    }
  }
  // A span's floor is the top of the solid voxels, rounded up to a cell height: a face at h
  // gives a floor in [h, h + ch); half a cell height more either way covers float rounding.
  // The highest candidate in that range whose faces cover the cell is the span's.
  std::vector<int> span_cand(span_count, -1);
  for (int i = 0; i < span_count; ++i) {
    if (!walkable(i) || cand_y.empty()) continue;
    const double f = spanFloor(i);
    const int64_t col = static_cast<int64_t>(span_z[i]) * width + span_x[i];
    for (int c = static_cast<int>(std::upper_bound(cand_y.begin(), cand_y.end(), f + 0.5 * ch) - cand_y.begin()) - 1;
         c >= 0 && f - cand_y[c] <= 1.5 * ch; --c) {
      if (covered.count(c * ncols + col)) {
        span_cand[i] = c;
        break;
      }
    }
  }

  // Areas: spans linked at one candidate height.
  std::vector<int> span_area(span_count, -1);
  std::vector<int> area_cand, area_spans;
  std::vector<int> stack;
  for (int i = 0; i < span_count; ++i) {
    if (span_cand[i] < 0 || span_area[i] >= 0) continue;
    const int id = static_cast<int>(area_cand.size());
    area_cand.push_back(span_cand[i]);
    area_spans.push_back(0);
    span_area[i] = id;
    stack.assign(1, i);
    while (!stack.empty()) {
      const int s = stack.back();
      stack.pop_back();
      area_spans[id]++;
      forNeighbours(s, [&](int j) {
        if (span_area[j] < 0 && span_cand[j] == span_cand[i]) {
          span_area[j] = id;
          stack.push_back(j);
        }
      });
    }
  }
  // Regions: spans linked at all (stairs and ramps included).
  std::vector<int> span_region(span_count, -1);
  int regions = 0;
  for (int i = 0; i < span_count; ++i) {
    if (!walkable(i) || span_region[i] >= 0) continue;
    span_region[i] = regions;
    stack.assign(1, i);
    while (!stack.empty()) {
      const int s = stack.back();
      stack.pop_back();
      forNeighbours(s, [&](int j) {
        if (span_region[j] < 0) {
          span_region[j] = regions;
          stack.push_back(j);
        }
      });
    }
    ++regions;
  }
  int largest = -1;
  for (int a = 0; a < static_cast<int>(area_spans.size()); ++a)
    if (largest < 0 || area_spans[a] > area_spans[largest]) largest = a;
  std::vector<int> area_region(area_spans.size(), -1);
  for (int i = 0; i < span_count; ++i)
    if (span_area[i] >= 0) area_region[span_area[i]] = span_region[i];
  // Seed regions: the one of the largest area, and that of every area of at least the minimum
  // that is walled rather than a ledge. Walking outwards from each edge of the area (through its
  // own eroded rim) over the solid heightfield, the first column without standing room at the
  // area's height decides: open space at that height over a floor more than a climb below, or
  // over nothing, is a drop (the edge of a table top or a bed, a roof); solid there, or headroom
  // too low to stand, is a wall (a wall, a closed door: rooms of real models are often shut by
  // their door leaves). The solid heightfield, not the open one: beside a bed the floor's column
  // holds the bed's side face, rasterized over the cell it touches, so that column has no open
  // span; the open field would show only the storey above there and call it a wall.
  std::vector<char> region_seed(regions, 0);
  if (largest >= 0) region_seed[area_region[largest]] = 1;
  {
    std::vector<int64_t> drops(area_spans.size(), 0), walls(area_spans.size(), 0);
    const int reach = walk_radius + static_cast<int>(std::ceil(1.0 / cs)) + 2;  // the rim and a 1 m wall
    for (int i = 0; i < span_count; ++i) {
      const int a = span_area[i];
      if (a < 0 || area_spans[a] * cell_area < min_area) continue;
      const int f = chf->spans[i].y;
      for (int dir = 0; dir < 4; ++dir) {
        const int con = rcGetCon(chf->spans[i], dir);
        const int dx = rcGetDirOffsetX(dir), dz = rcGetDirOffsetY(dir);
        if (con != RC_NOT_CONNECTED && span_area[chf->cells[(span_x[i] + dx) + (span_z[i] + dz) * width].index + con] >= 0)
          continue;  // inside the area, or linked to another walkable area
        for (int k = 1; k <= reach; ++k) {
          const int x = span_x[i] + k * dx, z = span_z[i] + k * dz;
          if (x < 0 || z < 0 || x >= width || z >= depth) break;
          const rcSpan* column = hf->spans[x + z * width];
          // Open to nothing below the lowest solid (or in an empty column) counts as a drop too.
          bool level_here = false, below = column == nullptr || static_cast<int>(column->smin) > f;
          for (const rcSpan* sp = column; sp; sp = sp->next) {
            const int bot = static_cast<int>(sp->smax);  // a gap from this solid's top to the next's bottom
            const int top = sp->next ? static_cast<int>(sp->next->smin) : INT32_MAX;
            if (std::abs(bot - f) <= walk_climb) level_here = level_here || top - bot >= walk_height;
            else if (bot < f - walk_climb && top > f) below = true;  // open down to a lower floor
          }
          if (level_here) continue;
          (below ? drops : walls)[a]++;
          break;
        }
      }
    }
    for (size_t a = 0; a < area_spans.size(); ++a)
      if (area_spans[a] * cell_area >= min_area && walls[a] > drops[a]) region_seed[area_region[a]] = 1;
  }
  hf.reset();
  const auto seeded = [&](int a) { return area_region[a] >= 0 && region_seed[area_region[a]]; };

  // Levels: big areas in seeded regions; one level per candidate height.
  const int ncand = static_cast<int>(cand_y.size());
  std::vector<int> cand_level(ncand, -1);
  std::vector<char> cand_seen(ncand, 0), cand_big(ncand, 0);
  for (size_t a = 0; a < area_spans.size(); ++a) {
    const int c = area_cand[a];
    cand_seen[c] = 1;
    if (area_spans[a] * cell_area >= min_area) {
      cand_big[c] = 1;
      if (seeded(static_cast<int>(a))) cand_level[c] = 0;
    }
  }
  std::vector<int> level_cand;
  for (int c = 0; c < ncand; ++c) {
    if (cand_level[c] < 0) continue;
    cand_level[c] = static_cast<int>(level_cand.size());
    level_cand.push_back(c);
  }
  int no_span = 0, too_small = 0, unreachable = 0;
  for (int c = 0; c < ncand; ++c) {
    if (cand_level[c] >= 0) continue;
    if (!cand_seen[c]) ++no_span;
    else if (!cand_big[c]) ++too_small;
    else ++unreachable;
  }
  std::vector<int> span_level(span_count, -1);
  for (int i = 0; i < span_count; ++i) {
    const int a = span_area[i];
    if (a >= 0 && area_spans[a] * cell_area >= min_area && seeded(a))
      span_level[i] = cand_level[area_cand[a]];
  }

  const size_t nlevels = level_cand.size();
  std::vector<std::vector<std::pair<int, int>>> level_cells(nlevels);
  for (int i = 0; i < span_count; ++i)
    if (span_level[i] >= 0) level_cells[span_level[i]].emplace_back(span_z[i], span_x[i]);
  scene.levels.resize(nlevels);
  std::vector<glm::dvec2> piece;
  for (size_t l = 0; l < nlevels; ++l) {
    FloorLevel& level = scene.levels[l];
    level.floor_y = cand_y[level_cand[l]];
    const std::vector<Rect> rects = cellsToRects(std::move(level_cells[l]));
    for (uint32_t f : cand_faces[level_cand[l]]) {
      const FaceXz face = faceXz(scene, f);
      for (const Rect& r : rects) {
        const double x0 = cellX(r.x0), x1 = cellX(r.x1 + 1), z0 = cellZ(r.z0), z1 = cellZ(r.z1 + 1);
        if (face.hi_x <= x0 || face.lo_x >= x1 || face.hi_z <= z0 || face.lo_z >= z1) continue;
        piece = clipToBox(face.ring, x0, x1, z0, z1);
        if (piece.size() >= 3 && std::abs(signedArea(piece)) > min_piece) level.walkable.push_back(piece);
      }
    }
  }
  // A level whose cells kept no piece (only slivers) is none: its cells join the connections.
  {
    std::vector<int> remap(nlevels, -1);
    std::vector<FloorLevel> kept;
    std::vector<int> kept_cand;
    for (size_t l = 0; l < nlevels; ++l) {
      if (scene.levels[l].walkable.empty()) continue;
      remap[l] = static_cast<int>(kept.size());
      kept.push_back(std::move(scene.levels[l]));
      kept_cand.push_back(level_cand[l]);
    }
    for (int& l : span_level)
      if (l >= 0) l = remap[l];
    scene.levels = std::move(kept);
    level_cand = std::move(kept_cand);
  }
  // placeStartEye sorts levels by height; candidates are sorted already, so indices stay.

  // Connections: walkable spans of seeded regions on no level.
  std::vector<int> span_conn(span_count, -1);
  struct ConnCells {
    std::vector<std::pair<int, int>> own;       // (z, x)
    std::vector<Rect> borders;  // level cells beside it, tagged with their level
    std::vector<uint32_t> levels;
    int spans = 0;
  };
  std::vector<ConnCells> conns;
  for (int i = 0; i < span_count; ++i) {
    if (!walkable(i) || span_level[i] >= 0 || !region_seed[span_region[i]] || span_conn[i] >= 0) continue;
    const int id = static_cast<int>(conns.size());
    conns.emplace_back();
    span_conn[i] = id;
    stack.assign(1, i);
    while (!stack.empty()) {
      const int s = stack.back();
      stack.pop_back();
      ConnCells& cc = conns[id];
      cc.own.emplace_back(span_z[s], span_x[s]);
      cc.spans++;
      forNeighbours(s, [&](int j) {
        if (span_level[j] >= 0) {
          cc.levels.push_back(static_cast<uint32_t>(span_level[j]));
          // The level cell beside it may hold the foot of the ramp or the last tread.
          cc.borders.push_back(Rect{span_x[j], span_x[j], span_z[j], span_z[j], span_level[j]});
        } else if (span_conn[j] < 0) {
          span_conn[j] = id;
          stack.push_back(j);
        }
      });
    }
  }
  // Walkable-slope upward faces, for patches.
  const double min_ny = std::cos(slope * M_PI / 180.0);
  std::vector<FaceXz> up_faces;
  std::vector<int> up_face_cand;
  for (uint32_t i = 0; i < scene.polygons.size(); ++i) {
    if (scene.polygons[i].plane.n.y < min_ny) continue;
    up_faces.push_back(faceXz(scene, i));
    up_face_cand.push_back(poly_cand[i]);
  }
  // Span floor per cell for the height test of a patch piece (the cell its centroid lies in).
  std::unordered_map<int64_t, double> conn_floor;
  for (int i = 0; i < span_count; ++i)
    if (span_conn[i] >= 0) conn_floor[static_cast<int64_t>(span_z[i]) * width + span_x[i]] = spanFloor(i);
  int dropped_conns = 0;
  for (ConnCells& cc : conns) {
    WalkableConnection conn;
    std::sort(cc.levels.begin(), cc.levels.end());
    cc.levels.erase(std::unique(cc.levels.begin(), cc.levels.end()), cc.levels.end());
    conn.levels = cc.levels;
    conn.area = cc.spans * cell_area;
    std::vector<Rect> rects = cellsToRects(cc.own);
    std::sort(cc.borders.begin(), cc.borders.end(), [](const Rect& a, const Rect& c) {
      return std::tie(a.z0, a.x0, a.tag) < std::tie(c.z0, c.x0, c.tag);
    });
    cc.borders.erase(std::unique(cc.borders.begin(), cc.borders.end(),
                                 [](const Rect& a, const Rect& c) {
                                   return a.z0 == c.z0 && a.x0 == c.x0 && a.tag == c.tag;
                                 }),
                     cc.borders.end());
    rects.insert(rects.end(), cc.borders.begin(), cc.borders.end());
    int bx0 = width, bx1 = -1, bz0 = depth, bz1 = -1;
    for (const Rect& r : rects)
      bx0 = std::min(bx0, r.x0), bx1 = std::max(bx1, r.x1), bz0 = std::min(bz0, r.z0), bz1 = std::max(bz1, r.z1);
    for (size_t f = 0; f < up_faces.size(); ++f) {
      const FaceXz& face = up_faces[f];
      if (face.hi_x <= cellX(bx0) || face.lo_x >= cellX(bx1 + 1) || face.hi_z <= cellZ(bz0) ||
          face.lo_z >= cellZ(bz1 + 1))
        continue;
      const Plane& plane = scene.polygons[face.polygon].plane;
      for (const Rect& r : rects) {
        if (r.tag >= 0 && up_face_cand[f] == level_cand[r.tag]) continue;  // already on that level
        const double x0 = cellX(r.x0), x1 = cellX(r.x1 + 1), z0 = cellZ(r.z0), z1 = cellZ(r.z1 + 1);
        if (face.hi_x <= x0 || face.lo_x >= x1 || face.hi_z <= z0 || face.lo_z >= z1) continue;
        piece = clipToBox(face.ring, x0, x1, z0, z1);
        if (piece.size() < 3 || std::abs(signedArea(piece)) <= min_piece) continue;
        // Keep surfaces at the cell's floor or within a climb below it (the lower tread beside a
        // riser that shares a cell with the upper one), not floors far under or ceilings over.
        glm::dvec2 c(0.0);
        for (const auto& p : piece) c += p;
        c /= static_cast<double>(piece.size());
        double floor_here;
        if (r.tag >= 0) {
          floor_here = scene.levels[r.tag].floor_y;
        } else {
          const int cx = std::clamp(static_cast<int>(std::floor((c.x - cellX(0)) / cs)), r.x0, r.x1);
          const int cz = std::clamp(static_cast<int>(std::floor((c.y - cellZ(0)) / cs)), r.z0, r.z1);
          auto it = conn_floor.find(static_cast<int64_t>(cz) * width + cx);
          if (it == conn_floor.end()) continue;
          floor_here = it->second;
        }
        const double y = (plane.d - plane.n.x * c.x - plane.n.z * c.y) / plane.n.y;
        if (y > floor_here + 1.5 * ch || y < floor_here - climb - 1.5 * ch) continue;
        conn.patches.push_back({piece, plane});
      }
    }
    if (conn.patches.empty()) {
      ++dropped_conns;
      continue;
    }
    scene.connections.push_back(std::move(conn));
  }

  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto& notes = scene.report.notes;
  notes.push_back(fmt("navmesh (Recast): agent height %.4g, radius %.4g, climb %.4g, slope %.4g deg, "
                      "min level area %.4g",
                      agent_height, radius, climb, slope, min_area));
  notes.push_back(fmt("navmesh: cell %.4g x %.4g (height), grid %.0f x %.0f, ", cs, ch, width, depth) +
                  std::to_string(span_count) + " open spans, " + fmt("%.3f s", seconds));
  notes.push_back("navmesh: " + std::to_string(ncand) + " candidate floor heights, " + std::to_string(scene.levels.size()) +
                  " levels; filtered " + std::to_string(no_span) + " with no walkable cell, " +
                  std::to_string(too_small) + " too small, " + std::to_string(unreachable) + " unreachable");
  notes.push_back("navmesh: " + std::to_string(scene.connections.size()) + " connections (stairs, ramps)" +
                  (dropped_conns ? ", " + std::to_string(dropped_conns) + " without a face left out" : ""));
}

}  // namespace walkvis
