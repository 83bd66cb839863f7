// Tests of the seeded scene generators (scenes/gen_*.cpp): determinism, polygon counts, polygon
// validity, levels and start eyes, orientation of office walls and sphere triangles, hard cases
// and parameter errors.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <tuple>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "core/rng.h"
#include "scenes/generators.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

Scene gen(const std::string& name, std::map<std::string, std::string> values = {}) {
  GeneratorParams params("gen:" + name, std::move(values));
  Scene scene = generateScene(name, params);
  params.checkAllUsed();
  return scene;
}

double cross2(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Inside or on a convex piece of either orientation.
bool insideConvex(const std::vector<glm::dvec2>& piece, const glm::dvec2& q) {
  bool neg = false, pos = false;
  for (size_t i = 0; i < piece.size(); ++i) {
    const double c = cross2(piece[i], piece[(i + 1) % piece.size()], q);
    neg = neg || c < 0.0;
    pos = pos || c > 0.0;
  }
  return !(neg && pos);
}

const FloorLevel* levelUnder(const Scene& scene, const glm::dvec3& p, double tol) {
  for (const auto& level : scene.levels) {
    if (std::abs(p.y - level.floor_y) > tol) continue;
    return &level;
  }
  return nullptr;
}

bool onWalkable(const FloorLevel& level, const glm::dvec2& q) {
  for (const auto& piece : level.walkable) {
    if (insideConvex(piece, q)) return true;
  }
  return false;
}

glm::dvec3 centroid(const Scene& scene, const Polygon& p) {
  glm::dvec3 c(0.0);
  for (const auto& v : scene.polygonVertices(p)) c += v;
  return c / static_cast<double>(p.vertex_count);
}

// Every polygon has >= 3 vertices, a unit normal, lies in its plane and is convex and
// counter-clockwise about its normal.
void expectValidPolygons(const Scene& scene) {
  const Bounds b = sceneBounds(scene);
  const double extent = std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z});
  // Rounding: coordinates up to 1e6 (far-coordinates) carry ~1e-10, and the normal of a 1e-7 m²
  // needle is good to ~1e-8 rad; both stay below 1e-8 of the extent plus 1e-12 of the magnitude,
  // far below any out-of-plane feature a generator makes on purpose (1e-3 and up).
  const double magnitude = glm::length(glm::max(glm::abs(b.lo), glm::abs(b.hi)));
  const double tol = 1e-8 * extent + 1e-12 * magnitude;
  size_t bad = 0;
  for (const auto& p : scene.polygons) {
    const auto v = scene.polygonVertices(p);
    bool ok = v.size() >= 3 && std::abs(glm::length(p.plane.n) - 1.0) < 1e-12;
    for (const auto& q : v) ok = ok && std::abs(glm::dot(p.plane.n, q) - p.plane.d) <= tol;
    for (size_t i = 0; ok && i < v.size(); ++i) {
      const glm::dvec3 e0 = v[(i + 1) % v.size()] - v[i], e1 = v[(i + 2) % v.size()] - v[(i + 1) % v.size()];
      // A turn against the normal beyond rounding means non-convex or clockwise.
      ok = glm::dot(glm::cross(e0, e1), p.plane.n) >= -1e-9 * glm::length(e0) * glm::length(e1);
    }
    if (!ok && bad++ < 5) ADD_FAILURE() << scene.name << ": polygon of face " << p.face_id << " is invalid";
  }
  EXPECT_EQ(bad, 0u) << scene.name;
}

void expectStartOnWalkable(const Scene& scene) {
  ASSERT_FALSE(scene.levels.empty()) << scene.name;
  const FloorLevel* level = levelUnder(scene, scene.start_eye - glm::dvec3(0, scene.eye_height, 0),
                                       1e-9 * std::max(1.0, std::abs(scene.start_eye.y)));
  ASSERT_NE(level, nullptr) << scene.name << ": start eye not at floor + eye height";
  EXPECT_TRUE(onWalkable(*level, {scene.start_eye.x, scene.start_eye.z})) << scene.name;
}

TEST(Generators, OfficeIsDeterministicPerSeed) {
  const Scene a = gen("office", {{"seed", "7"}});
  const Scene b = gen("office", {{"seed", "7"}});
  const Scene c = gen("office", {{"seed", "8"}});
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  EXPECT_TRUE(a.vertices == b.vertices);
  EXPECT_TRUE(a.face_colors == b.face_colors);
  EXPECT_FALSE(a.vertices == c.vertices);
  for (const char* name : {"sphere", "dome", "ninefacet"}) {
    EXPECT_TRUE(gen(name).vertices == gen(name).vertices) << name;
  }
}

TEST(Generators, OfficePolygonCountsFollowTheDocumentedSizes) {
  struct Size {
    std::map<std::string, std::string> params;
    size_t lo, hi;
  };
  // The documented benchmark strings (gen_office.cpp) within about ±15%, other seeds included.
  const Size sizes[] = {{{}, 900, 1220},
                        {{{"seed", "2"}}, 900, 1220},
                        {{{"rooms", "415"}}, 9000, 11000},
                        {{{"rooms", "4200"}}, 90000, 110000},
                        {{{"rooms", "4200"}, {"seed", "9"}}, 90000, 110000},
                        {{{"rooms", "1050"}, {"floors", "4"}}, 90000, 110000}};
  for (const auto& s : sizes) {
    const auto t0 = std::chrono::steady_clock::now();
    const Scene scene = gen("office", s.params);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::string query;
    for (const auto& [k, v] : s.params) query += (query.empty() ? "?" : "&") + k + "=" + v;
    std::printf("gen:office%s: %zu polygons, %zu levels, %.1f ms\n", query.c_str(), scene.polygons.size(),
                scene.levels.size(), ms);
    EXPECT_GE(scene.polygons.size(), s.lo);
    EXPECT_LE(scene.polygons.size(), s.hi);
    EXPECT_EQ(scene.report.input_faces, scene.polygons.size()) << "every office face is one convex polygon";
  }
}

TEST(Generators, OfficePolygonsAreValidAndLevelsMatchFloors) {
  for (const auto& params : std::vector<std::map<std::string, std::string>>{
           {}, {{"floors", "3"}, {"rooms", "9"}, {"seed", "3"}}, {{"room_size", "3"}, {"thickness", "1"}}}) {
    const Scene scene = gen("office", params);
    expectValidPolygons(scene);
    expectStartOnWalkable(scene);
    const int64_t floors = params.count("floors") ? std::stoll(params.at("floors")) : 1;
    ASSERT_EQ(scene.levels.size(), static_cast<size_t>(floors));
    for (const auto& level : scene.levels) {
      // The walkable region is exactly the up-facing polygons at the floor's height.
      double floor_area = 0.0;
      for (const auto& p : scene.polygons) {
        if (p.plane.n.y != 1.0 || p.plane.d != level.floor_y) continue;
        const auto v = scene.polygonVertices(p);
        floor_area += std::abs((v[2].x - v[0].x) * (v[2].z - v[0].z));
      }
      EXPECT_NEAR(level.walkable_area, floor_area, 1e-6 * floor_area);
      EXPECT_GT(level.walkable_area, 0.0);
    }
  }
}

// Every vertical polygon faces walkable space: 2 cm in front of its centre is walkable floor.
// Full-height walls wider than a pillar have the wall's inside behind them: 2 cm behind is not
// walkable (a wall facing out of the building would fail one or the other).
void expectWallsFaceWalkableSpace(const Scene& scene, double height, size_t min_front, size_t min_back) {
  size_t checked_front = 0, checked_back = 0;
  for (const auto& p : scene.polygons) {
    const glm::dvec3 c = centroid(scene, p);
    if (std::abs(p.plane.n.y) > 1e-12) {
      // Floors face up at a level; everything else horizontal (ceilings, soffits) faces down,
      // except furniture tops below the eye.
      const bool at_level = levelUnder(scene, c, 1e-9) != nullptr;
      if (at_level) {
        EXPECT_EQ(p.plane.n.y, 1.0);
      } else if (p.plane.n.y > 0.0) {
        EXPECT_LT(c.y - std::floor(c.y / (height + 0.3)) * (height + 0.3), 2.0) << "only furniture tops face up";
      }
      continue;
    }
    auto v = scene.polygonVertices(p);
    double y0 = v[0].y, y1 = v[0].y;
    glm::dvec2 lo(v[0].x, v[0].z), hi = lo;
    for (const auto& q : v) {
      y0 = std::min(y0, q.y), y1 = std::max(y1, q.y);
      lo = glm::min(lo, glm::dvec2(q.x, q.z)), hi = glm::max(hi, glm::dvec2(q.x, q.z));
    }
    const FloorLevel* level = nullptr;
    for (const auto& l : scene.levels) {
      if (std::abs(y0 - l.floor_y) < 1e-9 || (y0 > l.floor_y && y1 <= l.floor_y + height + 1e-9)) level = &l;
    }
    ASSERT_NE(level, nullptr);
    const glm::dvec3 front = c + 0.02 * p.plane.n, back = c - 0.02 * p.plane.n;
    EXPECT_TRUE(onWalkable(*level, {front.x, front.z})) << "face " << p.face_id << " faces away from the floor";
    ++checked_front;
    const bool full_height = std::abs(y0 - level->floor_y) < 1e-9 && std::abs(y1 - level->floor_y - height) < 1e-9;
    if (full_height && glm::length(hi - lo) > 0.45) {
      EXPECT_FALSE(onWalkable(*level, {back.x, back.z})) << "face " << p.face_id << " has floor behind it";
      ++checked_back;
    }
  }
  EXPECT_GT(checked_front, min_front);
  EXPECT_GT(checked_back, min_back);
}

TEST(Generators, OfficeWallsFaceTheWalkableSpace) {
  {
    SCOPED_TRACE("rooms=40&floors=2&seed=5");
    expectWallsFaceWalkableSpace(gen("office", {{"rooms", "40"}, {"floors", "2"}, {"seed", "5"}}), 3.0, 1000, 200);
  }
  {
    SCOPED_TRACE("rooms=11&per_side=7&seed=11");  // one bay, the south row shorter than the north
    expectWallsFaceWalkableSpace(gen("office", {{"rooms", "11"}, {"per_side", "7"}, {"seed", "11"}}), 3.0, 100, 20);
  }
  {
    SCOPED_TRACE("room_size=3&thickness=1&corridor=1.2&height=2.4");
    expectWallsFaceWalkableSpace(gen("office", {{"room_size", "3"},
                                                {"thickness", "1"},
                                                {"corridor", "1.2"},
                                                {"height", "2.4"},
                                                {"seed", "3"}}),
                                 2.4, 300, 50);
  }
}

TEST(Generators, OfficeRejectsBadParameters) {
  EXPECT_THROW(gen("office", {{"rooms", "0"}}), Error);
  EXPECT_THROW(gen("office", {{"rooms", "ten"}}), Error);
  EXPECT_THROW(gen("office", {{"floors", "1000"}}), Error);
  EXPECT_THROW(gen("office", {{"height", "1"}}), Error);
  EXPECT_THROW(gen("office", {{"colour", "red"}}), Error);
  EXPECT_THROW(gen("office", {{"rooms", "200000"}, {"furniture", "40"}}), Error);  // size limit
  try {
    gen("office", {{"room_size", "-4"}});
    ADD_FAILURE() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("gen:office"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("room_size"), std::string::npos) << e.what();
  }
  EXPECT_THROW(gen("nosuch"), Error);
  EXPECT_THROW(gen("hard:nosuch"), Error);
  EXPECT_THROW(gen("sphere", {{"tris", "5"}}), Error);
  EXPECT_THROW(gen("dome", {{"cut", "1.5"}}), Error);
  EXPECT_THROW(gen("ninefacet", {{"seed", "1"}}), Error);
}

TEST(Generators, CampusIsDeterministicAndItsBuildingsStandApart) {
  const std::map<std::string, std::string> params{{"buildings", "5"}, {"storeys", "2"}, {"rooms", "12"}, {"seed", "4"}};
  const Scene a = gen("campus", params);
  const Scene b = gen("campus", params);
  auto other = params;
  other["seed"] = "5";
  const Scene c = gen("campus", other);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  EXPECT_TRUE(a.vertices == b.vertices);
  EXPECT_NE(a.vertices, c.vertices) << "another seed, other buildings";
  expectValidPolygons(a);
  expectStartOnWalkable(a);
  // Storeys at one height are one level across the site, each level's area the sum of its buildings'.
  ASSERT_EQ(a.levels.size(), 2u);
  EXPECT_LT(a.levels[0].floor_y, a.levels[1].floor_y);
  // Each building is the office of its own seed moved onto its site: same polygon count as that
  // office, and the sites' bounding boxes (x, z) do not overlap.
  size_t office_polygons = 0;
  double office_area = 0.0;
  for (uint64_t k = 0; k < 5; ++k) {
    const Scene office = gen("office", {{"rooms", "12"}, {"floors", "2"}, {"furniture", "3"},
                                        {"seed", std::to_string(mixHash(4, k) >> 1)}});
    office_polygons += office.polygons.size();
    for (const FloorLevel& l : office.levels) office_area += l.walkable_area;
  }
  EXPECT_EQ(a.polygons.size(), office_polygons);
  EXPECT_NEAR(a.levels[0].walkable_area + a.levels[1].walkable_area, office_area, 1e-9 * office_area);
  EXPECT_EQ(a.report.input_faces, a.polygons.size());
  // Faces of one building are consecutive: split the polygons into five runs by face id and check
  // that the runs' footprints are disjoint.
  std::vector<std::pair<glm::dvec2, glm::dvec2>> boxes;
  size_t start = 0;
  for (uint64_t k = 0; k < 5; ++k) {
    const size_t count = gen("office", {{"rooms", "12"}, {"floors", "2"}, {"furniture", "3"},
                                        {"seed", std::to_string(mixHash(4, k) >> 1)}}).polygons.size();
    glm::dvec2 lo(HUGE_VAL), hi(-HUGE_VAL);
    for (size_t i = start; i < start + count; ++i)
      for (const glm::dvec3& v : a.polygonVertices(a.polygons[i])) {
        lo = glm::min(lo, glm::dvec2(v.x, v.z));
        hi = glm::max(hi, glm::dvec2(v.x, v.z));
      }
    for (const auto& [blo, bhi] : boxes)
      EXPECT_TRUE(hi.x < blo.x || bhi.x < lo.x || hi.y < blo.y || bhi.y < lo.y) << "building " << k << " overlaps another";
    boxes.emplace_back(lo, hi);
    start += count;
  }
}

TEST(Generators, CampusPolygonCountsFollowTheDocumentedSizes) {
  // gen_campus.cpp's formula, about 24 polygons per room cell and storey with 3 boxes per room,
  // within ±20% over seeds and shapes (the 200k and 1M strings are timed by `walkvis plan`).
  for (const auto& [buildings, storeys, rooms] : std::vector<std::tuple<int, int, int>>{{1, 1, 40}, {3, 2, 60}, {4, 3, 100}}) {
    for (const char* seed : {"1", "2"}) {
      const Scene scene = gen("campus", {{"buildings", std::to_string(buildings)}, {"storeys", std::to_string(storeys)},
                                         {"rooms", std::to_string(rooms)}, {"seed", seed}});
      const double expected = 24.0 * buildings * storeys * rooms;
      EXPECT_NEAR(static_cast<double>(scene.polygons.size()), expected, 0.2 * expected)
          << buildings << " buildings, " << storeys << " storeys, " << rooms << " rooms";
      EXPECT_EQ(scene.levels.size(), static_cast<size_t>(storeys));
    }
  }
}

TEST(Generators, CampusRejectsBadParameters) {
  EXPECT_THROW(gen("campus", {{"buildings", "0"}}), Error);
  EXPECT_THROW(gen("campus", {{"storeys", "many"}}), Error);
  EXPECT_THROW(gen("campus", {{"gap", "0.5"}}), Error);
  try {
    gen("campus", {{"buildings", "400"}, {"storeys", "100"}, {"rooms", "1000"}});
    ADD_FAILURE() << "a campus over the size limit was made";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("gen:campus"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("limit"), std::string::npos) << e.what();
  }
}

TEST(Generators, SphereIsClosedWithOutwardTriangles) {
  struct Case {
    const char* tris;
    size_t expected;
  };
  for (const Case& c : {Case{"2000", 2000}, Case{"70000", 69620}, Case{"20", 20}}) {
    const Scene scene = gen("sphere", {{"tris", c.tris}, {"radius", "2.5"}});
    EXPECT_EQ(scene.polygons.size(), c.expected);
    EXPECT_TRUE(isClosed(scene));
    expectValidPolygons(scene);
    size_t inward = 0;
    for (const auto& p : scene.polygons) {
      EXPECT_EQ(p.vertex_count, 3u);
      if (!(glm::dot(p.plane.n, centroid(scene, p)) > 0.0)) ++inward;
      for (const auto& v : scene.polygonVertices(p)) EXPECT_NEAR(glm::length(v), 2.5, 1e-12);
    }
    EXPECT_EQ(inward, 0u);
  }
  EXPECT_EQ(gen("sphere").polygons.size(), 2000u);
}

TEST(Generators, DomeIsOpenBelowWithAFloor) {
  for (const char* cut : {"0", "0.3", "0.9"}) {
    const Scene scene = gen("dome", {{"cut", cut}});
    expectValidPolygons(scene);
    expectStartOnWalkable(scene);
    // With its floor disc the dome is a closed surface, but the floor faces into it.
    EXPECT_FALSE(isClosed(scene));
    const double floor_y = -std::stod(cut) * 10.0;
    size_t outward = 0, floors = 0;
    for (const auto& p : scene.polygons) {
      if (p.plane.n.y == 1.0) {
        ++floors;
        EXPECT_EQ(p.plane.d, floor_y);
        continue;
      }
      EXPECT_EQ(p.vertex_count, 3u);
      outward += glm::dot(p.plane.n, centroid(scene, p)) > 0.0;
      for (const auto& v : scene.polygonVertices(p)) EXPECT_GE(v.y, floor_y);
    }
    EXPECT_EQ(floors, 1u);
    EXPECT_EQ(outward, scene.polygons.size() - 1);
    EXPECT_GT(scene.polygons.size(), 1500u);
    EXPECT_LT(scene.polygons.size(), 2500u);
  }
  const Scene inside = gen("dome", {{"inside", "1"}});
  for (const auto& p : inside.polygons) {
    if (p.plane.n.y != 1.0) {
      EXPECT_LT(glm::dot(p.plane.n, centroid(inside, p)), 0.0);
    }
  }
}

TEST(Generators, NineFacetHasNineWallsOnAFloor) {
  const Scene scene = gen("ninefacet");
  ASSERT_EQ(scene.polygons.size(), 10u);
  size_t walls = 0;
  for (const auto& p : scene.polygons) walls += p.plane.n.y == 0.0;
  EXPECT_EQ(walls, 9u);
  expectValidPolygons(scene);
  expectStartOnWalkable(scene);
}

TEST(Generators, HardCasesLoadOrThrowClearly) {
  const auto names = hardCaseNames();
  EXPECT_GE(names.size(), 12u);
  for (const auto& name : names) {
    SCOPED_TRACE(name);
    if (name == "hard:nan" || name == "hard:infinite") {
      try {
        loadScene("gen:" + name);
        ADD_FAILURE() << "no throw";
      } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("gen:" + name), std::string::npos) << msg;
        EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;
      }
      continue;
    }
    const Scene direct = gen(name);
    expectStartOnWalkable(direct);  // the generator's own start, before loadScene places one
    const Scene scene = loadScene("gen:" + name);
    EXPECT_GT(scene.polygons.size(), 5u);
    expectValidPolygons(scene);
    expectStartOnWalkable(scene);
    EXPECT_EQ(scene.start_eye, direct.start_eye);
  }
}

TEST(Generators, HardCasesHaveTheirFeature) {
  const Scene zero = gen("hard:zero-area");
  EXPECT_EQ(zero.report.dropped_degenerate, 2u);
  EXPECT_EQ(zero.report.dropped_zero_area, 3u);

  const Scene slivers = gen("hard:slivers");
  EXPECT_EQ(slivers.report.dropped_zero_area + slivers.report.dropped_degenerate, 0u);
  size_t tiny = 0;
  for (const auto& p : slivers.polygons) {
    const auto v = slivers.polygonVertices(p);
    glm::dvec3 n(0.0);
    for (size_t i = 0; i < v.size(); ++i) n += glm::cross(v[i], v[(i + 1) % v.size()]);
    const double area = 0.5 * glm::length(n);
    if (area < 1e-6) {
      ++tiny;
      EXPECT_NEAR(area, 1e-7, 2e-8);
    }
  }
  EXPECT_EQ(tiny, 4u);

  const Scene bent = gen("hard:nonplanar-nonconvex");
  EXPECT_EQ(bent.report.split_faces, 5u);

  const Scene far = gen("hard:far-coordinates");
  const Bounds b = sceneBounds(far);
  EXPECT_GT(b.lo.x, 1e6 - 6);
  EXPECT_GT(b.lo.y, 1e6 - 1);

  // The tilted table top and three walls are turned 1e-12 rad off the axes: their normals have
  // an x component of that size (rounding noise elsewhere is ~1e-16).
  const Scene tilt = gen("hard:near-parallel");
  size_t tilted = 0;
  for (const auto& p : tilt.polygons) tilted += std::abs(p.plane.n.x) > 1e-13 && std::abs(p.plane.n.x) < 1e-11;
  EXPECT_EQ(tilted, 4u);

  // Height-plane polygons lie exactly in y = 1.7.
  const Scene hp = gen("hard:height-plane-polygons");
  size_t in_plane = 0;
  for (const auto& p : hp.polygons) in_plane += std::abs(p.plane.n.y) == 1.0 && std::abs(p.plane.d) == 1.7;
  EXPECT_EQ(in_plane, 3u);
}

}  // namespace
}  // namespace walkvis
