// gen:campus — several furnished multi-storey office buildings on one site, for builds that
// outgrow one machine (docs/DESIGN.md, "Builds across processes and restarts").
//
// `buildings` gen:office buildings (each with `storeys` storeys of `rooms` room cells and
// `furniture` boxes per room, its own seed) stand on a square grid of sites `gap` metres apart.
// Storeys at the same height are one level across the site, as in a campus whose buildings share
// their floor heights; from inside a building the others are out of sight (its outer walls are
// closed from within), which is what HFD trees are for. Polygons ≈ buildings · storeys · rooms ·
// (13 + 3.5·furniture), about 24 per room cell and storey with the default 3:
//   gen:campus?buildings=4&storeys=5&rooms=420      ~200k polygons
//   gen:campus?buildings=10&storeys=10&rooms=420    ~1M polygons
#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include <glm/common.hpp>

#include "core/rng.h"
#include "scenes/generators.h"

namespace walkvis {

Scene generateCampus(GeneratorParams& params) {
  const int64_t buildings = params.getInt("buildings", 4, 1, 400);
  const int64_t storeys = params.getInt("storeys", 3, 1, 100);
  const int64_t rooms = params.getInt("rooms", 40, 1, 200000);
  const int64_t furniture = params.getInt("furniture", 3, 0, 40);
  const double gap = params.getDouble("gap", 20.0, 1.0, 1000.0);
  const uint64_t seed = params.seed();
  const double estimate = static_cast<double>(buildings) * static_cast<double>(storeys) * static_cast<double>(rooms) *
                          (14.0 + 5.0 * static_cast<double>(furniture));
  constexpr double kMaxPolygons = 8e6;  // memory stays bounded (an upper bound, as gen:office's)
  if (estimate > kMaxPolygons)
    throw Error(params.generator() + ": buildings·storeys·rooms·(14+5·furniture) = " +
                std::to_string(static_cast<int64_t>(estimate)) + " polygons, more than the limit of 8000000");
  const int64_t columns = static_cast<int64_t>(std::ceil(std::sqrt(static_cast<double>(buildings))));
  Scene campus;
  campus.name = "gen:campus";
  std::map<double, size_t> level_at;  // floor_y -> index into campus.levels
  double site = 0.0;                  // side of a site: the largest building's extent plus the gap
  std::vector<Scene> parts;
  for (int64_t b = 0; b < buildings; ++b) {
    GeneratorParams office("gen:campus", {{"rooms", std::to_string(rooms)},
                                          {"floors", std::to_string(storeys)},
                                          {"furniture", std::to_string(furniture)},
                                          {"seed", std::to_string(mixHash(seed, static_cast<uint64_t>(b)) >> 1)}});
    parts.push_back(generateOffice(office));
    glm::dvec3 lo(HUGE_VAL), hi(-HUGE_VAL);
    for (const glm::dvec3& v : parts.back().vertices) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    site = std::max(site, std::max(hi.x - lo.x, hi.z - lo.z) + gap);
  }
  for (int64_t b = 0; b < buildings; ++b) {
    Scene& part = parts[static_cast<size_t>(b)];
    const glm::dvec3 offset(site * static_cast<double>(b % columns), 0.0, site * static_cast<double>(b / columns));
    const uint32_t first_vertex = static_cast<uint32_t>(campus.vertices.size());
    const uint32_t first_face = static_cast<uint32_t>(campus.face_colors.size());
    for (const glm::dvec3& v : part.vertices) campus.vertices.push_back(v + offset);
    campus.face_colors.insert(campus.face_colors.end(), part.face_colors.begin(), part.face_colors.end());
    for (Polygon p : part.polygons) {
      p.first_vertex += first_vertex;
      p.face_id += first_face;
      // Moved along x and z only: the normal stays and n·x = d becomes n·(x + o) = d + n·o. Office
      // planes are axis-aligned, so d + n·o rounds exactly as the moved vertices' coordinate does.
      p.plane.d += p.plane.n.x * offset.x + p.plane.n.z * offset.z;
      campus.polygons.push_back(p);
    }
    for (const FloorLevel& l : part.levels) {
      auto [it, added] = level_at.try_emplace(l.floor_y, campus.levels.size());
      if (added) {
        campus.levels.push_back(FloorLevel{});
        campus.levels.back().floor_y = l.floor_y;
      }
      FloorLevel& to = campus.levels[it->second];
      for (auto ring : l.walkable) {
        for (glm::dvec2& p : ring) p += glm::dvec2(offset.x, offset.z);
        to.walkable.push_back(std::move(ring));
      }
      to.walkable_area += l.walkable_area;
    }
    for (uint64_t LoadReport::*count : {&LoadReport::input_faces, &LoadReport::kept_faces, &LoadReport::split_faces,
                                        &LoadReport::split_pieces, &LoadReport::dropped_zero_area,
                                        &LoadReport::dropped_degenerate})
      campus.report.*count += part.report.*count;
    if (b == 0) {
      campus.eye_height = part.eye_height;
      campus.start_eye = part.start_eye;
      campus.start_yaw = part.start_yaw;
    }
  }
  std::sort(campus.levels.begin(), campus.levels.end(),
            [](const FloorLevel& a, const FloorLevel& b) { return a.floor_y < b.floor_y; });
  return campus;
}

}  // namespace walkvis
