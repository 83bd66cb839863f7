// Navmesh floors (walkable.h): a table top is no level, the floor around it is; a house's two
// storeys are levels joined by its stair, which joins only agents its headroom admits when it
// climbs out from under the slab; a ramp joins two floors; walkable pieces are convex, on
// the scene's floor faces and an agent radius from the walls; bad options are SceneErrors.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "scenes/scene.h"
#include "scenes/walkable.h"

namespace walkvis {
namespace {

constexpr double kEye = 1.7;
constexpr double kRadius = 0.15 * kEye;  // the default agent radius
constexpr double kCell = kRadius / 3.0;  // the default cell size (walkable.cpp)

Scene navmesh(const std::string& spec, const WalkableOptions& w = {}) {
  LoadOptions options;
  options.floors = "navmesh";
  options.walkable = w;
  return loadScene(spec, options);
}

bool insideConvex(const std::vector<glm::dvec2>& p, glm::dvec2 q, double tol = 1e-9) {
  bool neg = false, pos = false;
  for (size_t i = 0; i < p.size(); ++i) {
    const glm::dvec2 a = p[i], b = p[(i + 1) % p.size()];
    const double c = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
    if (c < -tol) neg = true;
    if (c > tol) pos = true;
  }
  return !(neg && pos);
}

bool walkableAt(const Scene& s, size_t level, glm::dvec2 q) {
  for (const auto& piece : s.levels[level].walkable)
    if (insideConvex(piece, q)) return true;
  return false;
}

bool isConvex(const std::vector<glm::dvec2>& p) {
  if (p.size() < 3) return false;
  int sign = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const glm::dvec2 a = p[i], b = p[(i + 1) % p.size()], c = p[(i + 2) % p.size()];
    const double x = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (std::abs(x) < 1e-12) continue;
    const int sg = x > 0 ? 1 : -1;
    if (sign != 0 && sg != sign) return false;
    sign = sg;
  }
  return true;
}

double distToSegment(glm::dvec2 p, glm::dvec2 a, glm::dvec2 b) {
  const glm::dvec2 e = b - a;
  const double ee = e.x * e.x + e.y * e.y;
  const double t = ee > 0 ? std::clamp(((p.x - a.x) * e.x + (p.y - a.y) * e.y) / ee, 0.0, 1.0) : 0.0;
  const glm::dvec2 q = a + t * e;
  return std::hypot(p.x - q.x, p.y - q.y);
}

// Properties every level of a navmesh scene has: convex pieces, each on an upward face at the
// level's height, every vertex at least the radius from every wall standing in the walker's
// headroom, up to two cells: the voxels round a wall out to whole cells (one cell diagonal), and
// Recast's erosion is a chamfer distance transform that comes short of the Euclidean distance
// diagonally off an obstacle's corner (measured: 1.6 cells at the corner of the house's stair).
void checkLevels(const Scene& s) {
  for (const auto& level : s.levels) {
    ASSERT_FALSE(level.walkable.empty());
    for (const auto& piece : level.walkable) {
      EXPECT_TRUE(isConvex(piece));
      glm::dvec2 c(0.0);
      for (const auto& p : piece) c += p;
      c /= static_cast<double>(piece.size());
      bool on_face = false;
      for (size_t i = 0; i < s.polygons.size() && !on_face; ++i) {
        const Polygon& poly = s.polygons[i];
        if (poly.plane.n.y < 1.0 - 1e-9 || std::abs(poly.plane.d - level.floor_y) > 1e-9) continue;
        std::vector<glm::dvec2> ring;
        for (const auto& v : s.polygonVertices(i)) ring.emplace_back(v.x, v.z);
        bool all = true;
        for (const auto& p : piece) all = all && insideConvex(ring, p, 1e-9);
        on_face = all;
      }
      EXPECT_TRUE(on_face) << "piece at (" << c.x << ", " << c.y << ") is on no floor face at " << level.floor_y;
      for (size_t i = 0; i < s.polygons.size(); ++i) {
        const Polygon& poly = s.polygons[i];
        if (std::abs(poly.plane.n.y) > 0.1) continue;
        const auto v = s.polygonVertices(i);
        double lo = v[0].y, hi = v[0].y;
        for (const auto& p : v) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
        // Walls that rise above a step from this floor and start below the agent's head.
        if (hi <= level.floor_y + 0.2 * kEye + 1e-9 || lo >= level.floor_y + 1.2 * kEye) continue;
        glm::dvec2 a(v[0].x, v[0].z), b = a;
        double best = -1.0;
        for (const auto& p : v)  // the wall's xz trace: its two farthest-apart points
          for (const auto& q : v) {
            const double d = std::hypot(p.x - q.x, p.z - q.z);
            if (d > best) best = d, a = {p.x, p.z}, b = {q.x, q.z};
          }
        for (const auto& p : piece) {
          EXPECT_GE(distToSegment(p, a, b), kRadius - 2.0 * kCell - 1e-9)
              << "piece vertex (" << p.x << ", " << p.y << ") near wall " << i;
        }
      }
    }
  }
}

TEST(Walkable, TableRoomHasOneLevelTheFloor) {
  const Scene s = navmesh("gen:table_room");
  ASSERT_EQ(s.levels.size(), 1u);
  EXPECT_EQ(s.levels[0].floor_y, 0.0);
  EXPECT_TRUE(s.connections.empty());  // the chairs and the table are too high to step onto
  checkLevels(s);
  // The room is 6 x 5; the table 1.6 x 0.9 centred, its top at 0.75.
  EXPECT_TRUE(walkableAt(s, 0, {1.0, 1.0}));
  EXPECT_TRUE(walkableAt(s, 0, {5.0, 4.0}));
  EXPECT_FALSE(walkableAt(s, 0, {0.1, 2.0}));  // within the radius of a wall
  // Under the table there is no headroom for a 2.04 m agent: not walkable with the defaults.
  EXPECT_FALSE(walkableAt(s, 0, {3.0, 2.5}));
  // Beside the table's end (x = 2.2), half a metre away, is walkable.
  EXPECT_TRUE(walkableAt(s, 0, {1.6, 2.5}));
}

TEST(Walkable, FloorUnderTheTableIsWalkableForALowAgentExceptNearTheLegs) {
  WalkableOptions w;
  w.agent_height = 0.5;  // well under the 0.71 m underside of the table top (in whole cells)
  const Scene s = navmesh("gen:table_room", w);
  ASSERT_EQ(s.levels.size(), 1u);  // the table top is still no level: no step reaches it
  EXPECT_EQ(s.levels[0].floor_y, 0.0);
  EXPECT_TRUE(walkableAt(s, 0, {3.0, 2.5}));  // the middle under the table
  // The legs: 6 cm squares at x in [2.25, 2.31] and [3.69, 3.75], z in [2.1, 2.16] and [2.84, 2.9].
  for (const glm::dvec2 leg : {glm::dvec2{2.28, 2.13}, glm::dvec2{3.72, 2.13}, glm::dvec2{2.28, 2.87},
                               glm::dvec2{3.72, 2.87}}) {
    EXPECT_FALSE(walkableAt(s, 0, leg));
    EXPECT_FALSE(walkableAt(s, 0, leg + glm::dvec2{0.03 + 0.5 * kRadius, 0.0}));
    EXPECT_FALSE(walkableAt(s, 0, leg - glm::dvec2{0.0, 0.03 + 0.5 * kRadius}));
    // Beyond the radius and a cell diagonal the floor is walkable again (towards the table's middle).
    const glm::dvec2 inwards{leg.x < 3.0 ? 1.0 : -1.0, leg.y < 2.5 ? 1.0 : -1.0};
    EXPECT_TRUE(walkableAt(s, 0, leg + inwards * (0.03 + kRadius + 2.0 * kCell)));
  }
}

TEST(Walkable, HouseHasTwoLevelsJoinedByItsStair) {
  const Scene s = navmesh("gen:house");
  ASSERT_EQ(s.levels.size(), 2u);
  EXPECT_EQ(s.levels[0].floor_y, 0.0);
  EXPECT_EQ(s.levels[1].floor_y, 3.0);
  checkLevels(s);
  // 8 x 6 m; the stair's footprint 4.2 x 1.2 m against the z = 0 wall (an opening above it).
  // Eroded by the radius from the walls and around the stair on its three free sides:
  const double r = kRadius;
  const double expected = (8.0 - 2 * r) * (6.0 - 2 * r) - (4.2 + 2 * r) * (1.2 + r);
  // Tolerance: half a cell along the perimeters (outer walls and stair), where the voxels round.
  const double tol = 0.5 * kCell * (2 * (8.0 + 6.0) + 2 * (4.2 + 1.2));
  for (const auto& level : s.levels) EXPECT_NEAR(level.walkable_area, expected, tol) << level.floor_y;
  ASSERT_EQ(s.connections.size(), 1u);
  const WalkableConnection& stair = s.connections[0];
  EXPECT_EQ(stair.levels, (std::vector<uint32_t>{0, 1}));
  EXPECT_GT(stair.area, 0.5 * 4.2 * (1.2 - 2 * r));
  EXPECT_LT(stair.area, 4.2 * 1.2);
  double lo = 1e300, hi = -1e300;
  for (const auto& patch : stair.patches) {
    EXPECT_TRUE(isConvex(patch.piece));
    EXPECT_GT(patch.plane.n.y, 0.0);
    lo = std::min(lo, patch.plane.d / patch.plane.n.y), hi = std::max(hi, patch.plane.d / patch.plane.n.y);
  }
  EXPECT_LT(lo, 0.2);             // the first tread (0.1875) or the ground beside it
  EXPECT_NEAR(hi, 2.8125, 1e-9);  // the last tread
  bool notes = false;
  for (const auto& n : s.report.notes) notes = notes || n.find("navmesh: cell") != std::string::npos;
  EXPECT_TRUE(notes);
}

// A stair that climbs out from under the slab (FZK-Haus's spiral stair does: its attic slab covers
// the treads up to 0.88 m, 1.62 m under the slab). gen:house?opening=2.52 leaves the slab over the
// first six treads (to x = 2.68, the sixth riser's top at 1.125 m); stepping onto the seventh
// tread (1.3125 m) beside the slab's edge (2.8 m) leaves 1.4875 m. An agent taller than that
// cannot pass, one lower by more than the voxels' 3 cell heights (0.13 m) can.
TEST(Walkable, StairOutFromUnderASlabJoinsOnlyAgentsItsHeadroomAdmits) {
  const auto joined = [](const Scene& s) {
    for (const auto& c : s.connections)
      if (c.levels == std::vector<uint32_t>{0, 1}) return true;
    return false;
  };
  for (const double h : {2.04, 1.6}) {
    WalkableOptions w;
    w.agent_height = h;
    const Scene s = navmesh("gen:house?opening=2.52", w);
    ASSERT_EQ(s.levels.size(), 2u) << h;
    EXPECT_FALSE(joined(s)) << "agent height " << h;
    EXPECT_FALSE(s.connections.empty()) << h;  // the treads at each end are still connections
  }
  WalkableOptions low;
  low.agent_height = 1.3;
  EXPECT_TRUE(joined(navmesh("gen:house?opening=2.52", low)));
  // With 2.24 m over the highest covered tread and 2.05 m at the edge (opening 3.5: the slab
  // ends over the third tread), the default 2.04 m agent is within the voxels' 0.13 m and may go
  // either way; 1.9 m must pass.
  WalkableOptions tall;
  tall.agent_height = 1.9;
  EXPECT_TRUE(joined(navmesh("gen:house?opening=3.5", tall)));
  EXPECT_TRUE(joined(navmesh("gen:house")));  // the whole opening: the default agent passes
}

TEST(Walkable, RampJoinsTwoFloors) {
  const Scene s = navmesh("gen:ramp");
  ASSERT_EQ(s.levels.size(), 2u);
  EXPECT_EQ(s.levels[0].floor_y, 0.0);
  EXPECT_EQ(s.levels[1].floor_y, 0.9);
  checkLevels(s);
  ASSERT_EQ(s.connections.size(), 1u);
  EXPECT_EQ(s.connections[0].levels, (std::vector<uint32_t>{0, 1}));
  // The ramp is 3 x 4 m; the side walls take the radius on both sides.
  EXPECT_NEAR(s.connections[0].area, 3.0 * (4.0 - 2 * kRadius), 0.5 * kCell * 2 * (3.0 + 4.0) + 2 * kCell * 4.0);
  bool sloped = false;
  for (const auto& patch : s.connections[0].patches) sloped = sloped || patch.plane.n.y < 1.0 - 1e-9;
  EXPECT_TRUE(sloped);
}

TEST(Walkable, AreasUnderTheMinimumAreNoLevels) {
  // The house's floors are about 34 m2 each: a 36 m2 minimum leaves no level, and says so.
  WalkableOptions w;
  w.min_level_area = 36.0;
  const Scene s = navmesh("gen:house", w);
  EXPECT_TRUE(s.levels.empty());
  bool noted = false;
  for (const auto& n : s.report.notes) noted = noted || n.find("0 levels") != std::string::npos;
  EXPECT_TRUE(noted);
  // Just under them both storeys are levels again.
  w.min_level_area = 30.0;
  EXPECT_EQ(navmesh("gen:house", w).levels.size(), 2u);
}

TEST(Walkable, OptionsOutOfRangeAreSceneErrors) {
  const auto bad = [](auto set) {
    WalkableOptions w;
    set(w);
    EXPECT_THROW(navmesh("gen:house", w), Error);
  };
  bad([](WalkableOptions& w) { w.max_slope_deg = 95.0; });
  bad([](WalkableOptions& w) { w.max_slope_deg = 0.0; });
  bad([](WalkableOptions& w) { w.agent_height = 0.0; });
  bad([](WalkableOptions& w) { w.agent_height = std::numeric_limits<double>::infinity(); });
  bad([](WalkableOptions& w) { w.agent_radius = std::numeric_limits<double>::quiet_NaN(); });
  bad([](WalkableOptions& w) { w.max_climb = 3.0; });  // not below the agent height (2.04)
  bad([](WalkableOptions& w) { w.min_level_area = std::numeric_limits<double>::infinity(); });
  try {
    WalkableOptions w;
    w.max_slope_deg = 95.0;
    navmesh("gen:house", w);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("gen:house"), std::string::npos);
  }
}

}  // namespace
}  // namespace walkvis
