// The scene model: what addFace keeps, splits and drops; planes; levels; the scene argument.
#include <cmath>
#include <random>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "scenes/generators.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

double polygonArea(const Scene& s, const Polygon& p) {
  const auto v = s.polygonVertices(p);
  glm::dvec3 n(0.0);
  for (size_t i = 0; i < v.size(); ++i) n += glm::cross(v[i], v[(i + 1) % v.size()]);
  return 0.5 * glm::dot(n, p.plane.n);  // signed: positive when counter-clockwise about the normal
}

void expectConvexPlanar(const Scene& s, const Polygon& p) {
  const auto v = s.polygonVertices(p);
  ASSERT_GE(v.size(), 3u);
  EXPECT_NEAR(glm::length(p.plane.n), 1.0, 1e-12);
  for (const auto& q : v) EXPECT_NEAR(glm::dot(p.plane.n, q), p.plane.d, 1e-9);
  for (size_t i = 0; i < v.size(); ++i) {
    const glm::dvec3 t = glm::cross(v[(i + 1) % v.size()] - v[i], v[(i + 2) % v.size()] - v[(i + 1) % v.size()]);
    EXPECT_GE(glm::dot(t, p.plane.n), -1e-12) << "reflex corner";
  }
}

TEST(AddFace, ConvexPlanarFaceIsKeptWithItsPlane) {
  Scene s;
  const glm::dvec3 quad[] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  addFace(s, quad, 0xff0000, "t");
  ASSERT_EQ(s.polygons.size(), 1u);
  EXPECT_EQ(s.report.kept_faces, 1u);
  EXPECT_EQ(s.polygons[0].plane.n, glm::dvec3(0, 0, 1));
  EXPECT_NEAR(polygonArea(s, s.polygons[0]), 1.0, 1e-15);
}

TEST(AddFace, HorizontalFacesGetExactNormals) {
  Scene s;
  const glm::dvec3 floor[] = {{0.1, 2.3, 0.7}, {0.1, 2.3, 5.9}, {3.3, 2.3, 5.9}, {3.7, 2.3, 0.2}};
  addFace(s, floor, 0, "t");
  ASSERT_EQ(s.polygons.size(), 1u);
  EXPECT_EQ(s.polygons[0].plane.n, glm::dvec3(0, 1, 0));
  EXPECT_EQ(s.polygons[0].plane.d, 2.3);
}

TEST(AddFace, NonConvexFaceIsSplitIntoConvexPiecesOfTheSameArea) {
  Scene s;
  // An L shape, counter-clockwise about +z: area 3.
  const glm::dvec3 ell[] = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
  const uint32_t id = addFace(s, ell, 0, "t");
  EXPECT_EQ(s.report.split_faces, 1u);
  EXPECT_GE(s.polygons.size(), 2u);
  double area = 0.0;
  for (const auto& p : s.polygons) {
    EXPECT_EQ(p.face_id, id);
    EXPECT_EQ(p.plane.n, glm::dvec3(0, 0, 1));
    expectConvexPlanar(s, p);
    area += polygonArea(s, p);
  }
  EXPECT_NEAR(area, 3.0, 1e-12);
}

TEST(AddFace, NonPlanarFaceBecomesPlanarTriangles) {
  Scene s;
  const glm::dvec3 bent[] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.3}, {0, 1, 0}};
  addFace(s, bent, 0, "t");
  EXPECT_EQ(s.report.split_faces, 1u);
  ASSERT_EQ(s.polygons.size(), 2u);
  for (const auto& p : s.polygons) {
    EXPECT_EQ(p.vertex_count, 3u);
    expectConvexPlanar(s, p);
    EXPECT_GT(p.plane.n.z, 0.9);
  }
}

TEST(AddFace, DegenerateAndZeroAreaFacesAreDroppedAndCounted) {
  Scene s;
  const glm::dvec3 two[] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {0, 0, 0}};
  const glm::dvec3 line[] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  addFace(s, two, 0, "t");
  addFace(s, line, 0, "t");
  EXPECT_EQ(s.polygons.size(), 0u);
  EXPECT_EQ(s.report.input_faces, 2u);
  EXPECT_EQ(s.report.dropped_degenerate, 1u);
  EXPECT_EQ(s.report.dropped_zero_area, 1u);
}

TEST(AddFace, SliverOfAreaOneBillionthIsKept) {
  Scene s;
  // A 1 × 1e-9 triangle: thin, but real (docs/DESIGN.md, "Hard cases").
  const glm::dvec3 sliver[] = {{0, 0, 0}, {1, 0, 0}, {0.5, 1e-9, 0}};
  addFace(s, sliver, 0, "t");
  EXPECT_EQ(s.polygons.size(), 1u);
}

TEST(AddFace, NonFiniteCoordinatesAreAnErrorNamingTheContext) {
  Scene s;
  const glm::dvec3 bad[] = {{0, 0, 0}, {1, 0, 0}, {0, NAN, 0}};
  try {
    addFace(s, bad, 0, "model.obj:7");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("model.obj:7"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos);
  }
  const glm::dvec3 inf[] = {{0, 0, 0}, {INFINITY, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(addFace(s, inf, 0, "t"), Error);
}

TEST(AddFace, RandomSimplePolygonsKeepTheirAreaWhenSplit) {
  // Star-shaped polygons (simple by construction) with random radii: the pieces must cover the
  // same area and each be convex.
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    Scene s;
    const int n = 5 + static_cast<int>(rng() % 12);
    std::vector<glm::dvec3> v;
    for (int i = 0; i < n; ++i) {
      const double a = 2.0 * M_PI * i / n;
      const double r = 0.3 + (rng() % 1000) / 1000.0;
      v.emplace_back(r * std::cos(a), 5.0, -r * std::sin(a));  // counter-clockwise seen from +y
    }
    addFace(s, v, 0, "t");
    double expected = 0.0;
    for (int i = 0; i < n; ++i) {
      const auto& p = v[i];
      const auto& q = v[(i + 1) % n];
      expected += 0.5 * (p.z * q.x - p.x * q.z);
    }
    double area = 0.0;
    for (const auto& p : s.polygons) {
      expectConvexPlanar(s, p);
      EXPECT_EQ(p.plane.n, glm::dvec3(0, 1, 0));
      area += polygonArea(s, p);
    }
    EXPECT_NEAR(area, expected, 1e-9) << "trial " << trial;
  }
}

Scene unitCube() {
  Scene s;
  const glm::dvec3 c[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3}};
  for (const auto& f : faces) {
    const glm::dvec3 q[4] = {c[f[0]], c[f[1]], c[f[2]], c[f[3]]};
    addFace(s, q, 0, "cube");
  }
  return s;
}

TEST(Scene, CubeIsClosedAndOutwardFacing) {
  Scene s = unitCube();
  EXPECT_TRUE(isClosed(s));
  for (const auto& p : s.polygons) {
    glm::dvec3 c(0.0);
    for (const auto& v : s.polygonVertices(p)) c += v;
    c /= 4.0;
    EXPECT_GT(glm::dot(p.plane.n, c - glm::dvec3(0.5)), 0.0);
  }
  s.polygons.pop_back();
  EXPECT_FALSE(isClosed(s));
}

TEST(Scene, FloorLevelsComeFromUpwardFacingHorizontalFaces) {
  Scene s = unitCube();  // its top faces up at y = 1; its bottom faces down
  const glm::dvec3 second[] = {{5, 3, 5}, {5, 3, 7}, {7, 3, 7}, {7, 3, 5}};
  addFace(s, second, 0, "t");
  deriveFloorLevels(s);
  placeStartEye(s);
  ASSERT_EQ(s.levels.size(), 2u);
  EXPECT_EQ(s.levels[0].floor_y, 1.0);
  EXPECT_EQ(s.levels[1].floor_y, 3.0);
  EXPECT_NEAR(s.levels[1].walkable_area, 4.0, 1e-12);
  EXPECT_DOUBLE_EQ(s.start_eye.y, 1.0 + s.eye_height);
}

TEST(GeneratorParamsTest, RangesAndUnknownKeysAreErrorsNamingTheGenerator) {
  GeneratorParams p("gen:test", {{"rooms", "-3"}, {"size", "abc"}, {"extra", "1"}});
  try {
    p.getInt("rooms", 4, 1, 100);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("gen:test: parameter rooms=-3 is out of range"), std::string::npos);
  }
  EXPECT_THROW(p.getDouble("size", 1.0, 0.0, 10.0), Error);
  EXPECT_THROW(p.checkAllUsed(), Error);
  GeneratorParams q("gen:test", {{"seed", "12"}});
  EXPECT_EQ(q.seed(), 12u);
  EXPECT_NO_THROW(q.checkAllUsed());
}

TEST(LoadScene, UnknownFormatAndMissingFileAreErrors) {
  EXPECT_THROW(loadScene("model.xyz"), Error);
  try {
    loadScene("/nonexistent/model.obj");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/model.obj"), std::string::npos);
  }
}

}  // namespace
}  // namespace walkvis
