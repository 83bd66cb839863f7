// Tests of the exact BSP tree (bsp/bsp.h): completeness and order of the traversals against ray
// casting, area conservation, coplanar polygons of both orientations, nearly parallel planes,
// exact plane signs, save/load round trips and corrupt files, statistics and the heuristic.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <glm/geometric.hpp>

#include "bsp/bsp.h"
#include "core/byte_io.h"
#include "bsp/exact_sign.h"
#include "scenes/generators.h"
#include "scenes/loaders.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

constexpr uint32_t kColor = 0x808080;

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1p-53);
}

glm::dvec3 randomPoint(std::mt19937_64& rng, double half) {
  return {uniform(rng, -half, half), uniform(rng, -half, half), uniform(rng, -half, half)};
}

glm::dvec3 randomUnit(std::mt19937_64& rng) {
  for (;;) {
    const glm::dvec3 v = randomPoint(rng, 1.0);
    const double l = glm::length(v);
    if (l > 0.1 && l < 1.0) return v / l;
  }
}

// Random triangles and planar quads (rectangles) in a box of half-size 10; sizes up to ~8, so
// many straddle each other's planes.
Scene randomScene(uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  Scene scene;
  scene.name = "random" + std::to_string(seed);
  for (int i = 0; i < count; ++i) {
    const glm::dvec3 c = randomPoint(rng, 8.0);
    if (rng() % 2) {
      std::vector<glm::dvec3> tri = {c + randomPoint(rng, 4.0), c + randomPoint(rng, 4.0), c + randomPoint(rng, 4.0)};
      addFace(scene, tri, kColor, "test");
    } else {
      const glm::dvec3 n = randomUnit(rng);
      glm::dvec3 u = glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
      const glm::dvec3 v = glm::cross(n, u);
      const double a = uniform(rng, 0.5, 4.0), b = uniform(rng, 0.5, 4.0);
      std::vector<glm::dvec3> quad = {c - a * u - b * v, c + a * u - b * v, c + a * u + b * v, c - a * u + b * v};
      addFace(scene, quad, kColor, "test");
    }
  }
  return scene;
}

// Random axis-aligned vertical walls (rectangles) of random length in a 100 × 100 plan, facing
// ±x or ±z: a crude building whose long walls cross each other's planes.
Scene wallScene(uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  Scene scene;
  scene.name = "walls" + std::to_string(seed);
  for (int i = 0; i < count; ++i) {
    const double x = std::round(uniform(rng, 0, 100)), z = std::round(uniform(rng, 0, 100));
    const double len = std::round(uniform(rng, 2, 30));
    const bool along_x = rng() % 2;
    const bool flip = rng() % 2;
    std::vector<glm::dvec3> q;
    if (along_x) {
      q = {{x, 0, z}, {x + len, 0, z}, {x + len, 3, z}, {x, 3, z}};
    } else {
      q = {{x, 0, z}, {x, 3, z}, {x, 3, z + len}, {x, 0, z + len}};
    }
    if (flip) std::reverse(q.begin(), q.end());
    addFace(scene, q, kColor, "test");
  }
  return scene;
}

double polygonArea(std::span<const glm::dvec3> v) {
  glm::dvec3 s(0.0);
  for (size_t i = 1; i + 1 < v.size(); ++i) s += glm::cross(v[i] - v[0], v[i + 1] - v[0]);
  return 0.5 * glm::length(s);
}

// Double ray / convex polygon test: the ray parameter of the hit, or -1.
double rayHit(const BspTree& tree, uint32_t f, const glm::dvec3& o, const glm::dvec3& dir) {
  const Plane& pl = tree.fragments[f].plane;
  const double denom = glm::dot(pl.n, dir);
  if (std::abs(denom) < 1e-12) return -1.0;
  const double t = (pl.d - glm::dot(pl.n, o)) / denom;
  if (!(t > 0.0)) return -1.0;
  const glm::dvec3 p = o + t * dir;
  const auto v = tree.fragmentVertices(f);
  // Strictly inside every edge (relative to the polygon's winding seen along its normal); points
  // on an edge are no evidence of order.
  for (size_t i = 0; i < v.size(); ++i) {
    const glm::dvec3& a = v[i];
    const glm::dvec3& b = v[(i + 1) % v.size()];
    if (glm::dot(glm::cross(b - a, p - a), pl.n) <= 1e-12) return -1.0;
  }
  return t;
}

std::vector<glm::dvec3> randomEyes(uint64_t seed, int count, double half) {
  std::mt19937_64 rng(seed);
  std::vector<glm::dvec3> eyes;
  for (int i = 0; i < count; ++i) eyes.push_back(randomPoint(rng, half));
  return eyes;
}

void expectPermutation(const std::vector<uint32_t>& order, size_t n) {
  ASSERT_EQ(order.size(), n);
  std::vector<uint8_t> seen(n, 0);
  for (uint32_t f : order) {
    ASSERT_LT(f, n);
    ASSERT_EQ(seen[f], 0) << "fragment " << f << " listed twice";
    seen[f] = 1;
  }
}

struct RayCheck {
  int64_t compared = 0;    // ray/fragment pairs compared
  int64_t violations = 0;  // pairs where the nearer fragment comes first
  std::string first;       // description of the first violation
};

// Casts random rays from the eye and, on each, compares every pair of fragments it hits: the
// nearer one must come LATER in the back-to-front `order`. Pairs whose hit distances differ by
// less than 1e-9 (the scenes are ~20 units across, so that is ~1e-10 of their size) are skipped:
// split pieces of one polygon meet along a shared edge, and coplanar polygons of either
// orientation share a distance; the double ray test cannot order those.
RayCheck checkRays(const BspTree& tree, const glm::dvec3& eye, const std::vector<uint32_t>& order, uint64_t seed,
                   int rays) {
  std::vector<int64_t> rank(tree.fragments.size());
  for (size_t i = 0; i < order.size(); ++i) rank[order[i]] = static_cast<int64_t>(i);
  std::mt19937_64 rng(seed);
  RayCheck check;
  std::vector<std::pair<double, uint32_t>> hits;
  for (int r = 0; r < rays; ++r) {
    const glm::dvec3 dir = randomUnit(rng);
    hits.clear();
    for (uint32_t f = 0; f < tree.fragments.size(); ++f) {
      const double t = rayHit(tree, f, eye, dir);
      if (t > 0.0) hits.emplace_back(t, f);
    }
    std::sort(hits.begin(), hits.end());
    for (size_t i = 0; i < hits.size(); ++i) {
      for (size_t j = i + 1; j < hits.size(); ++j) {
        if (hits[j].first - hits[i].first < 1e-9) continue;
        ++check.compared;
        if (rank[hits[i].second] > rank[hits[j].second]) continue;
        if (check.violations++ == 0)
          check.first = "eye (" + std::to_string(eye.x) + ", " + std::to_string(eye.y) + ", " + std::to_string(eye.z) +
                        "): fragment " + std::to_string(hits[i].second) + " at " + std::to_string(hits[i].first) +
                        " drawn before fragment " + std::to_string(hits[j].second) + " at " +
                        std::to_string(hits[j].first);
      }
    }
  }
  return check;
}

TEST(Bsp, EveryFragmentOnceAndFrontToBackIsReverse) {
  for (uint64_t seed : {1, 2, 3}) {
    const Scene scene = randomScene(seed, 60);
    for (auto heuristic : {SplitHeuristic::kLeastCrossed, SplitHeuristic::kRandom}) {
      const BspTree tree = buildBsp(scene, BspOptions{heuristic, 8, seed});
      ASSERT_EQ(tree.fragments.size(), tree.stats.fragments);
      EXPECT_GT(tree.fragments.size(), scene.polygons.size()) << "the random scenes are meant to have straddlers";
      std::vector<uint32_t> b2f, f2b;
      for (const glm::dvec3& eye : randomEyes(seed + 100, 20, 12.0)) {
        backToFront(tree, eye, b2f);
        expectPermutation(b2f, tree.fragments.size());
        frontToBack(tree, eye, f2b);
        std::reverse(f2b.begin(), f2b.end());
        EXPECT_EQ(b2f, f2b);
      }
    }
  }
}

TEST(Bsp, BackToFrontAgreesWithRayCasting) {
  int64_t compared = 0, control_violations = 0;
  for (uint64_t seed : {11, 12, 13, 14}) {
    const Scene scene = randomScene(seed, 50);
    for (auto heuristic : {SplitHeuristic::kLeastCrossed, SplitHeuristic::kRandom}) {
      const BspTree tree = buildBsp(scene, BspOptions{heuristic, 8, seed});
      std::vector<uint32_t> order;
      uint64_t ray_seed = seed * 1000;
      for (const glm::dvec3& eye : randomEyes(seed + 7, 12, 12.0)) {
        backToFront(tree, eye, order);
        const RayCheck check = checkRays(tree, eye, order, ++ray_seed, 200);
        EXPECT_EQ(check.violations, 0) << check.first;
        compared += check.compared;
        // Control: the same check on front-to-back order must fail, or it proves nothing.
        frontToBack(tree, eye, order);
        control_violations += checkRays(tree, eye, order, ray_seed, 200).violations;
      }
    }
  }
  EXPECT_GT(compared, 2000) << "the rays should see many overlapping pairs";
  EXPECT_EQ(control_violations, compared) << "front-to-back order violates every compared pair";
}

TEST(Bsp, SkipBackFacesDropsExactlyTheBackFaces) {
  const Scene scene = randomScene(5, 60);
  const BspTree tree = buildBsp(scene);
  std::vector<uint32_t> all, culled, f2b;
  for (const glm::dvec3& eye : randomEyes(55, 20, 12.0)) {
    backToFront(tree, eye, all);
    backToFront(tree, eye, culled, true);
    std::vector<uint32_t> expected;
    for (uint32_t f : all)
      if (sideOfPlane(tree, f, eye) > 0) expected.push_back(f);
    EXPECT_EQ(culled, expected);
    frontToBack(tree, eye, f2b, true);
    std::reverse(f2b.begin(), f2b.end());
    EXPECT_EQ(f2b, expected);
  }
}

TEST(Bsp, FragmentAreasSumToInputAreas) {
  for (uint64_t seed : {21, 22}) {
    const Scene scene = randomScene(seed, 80);
    const BspTree tree = buildBsp(scene, BspOptions{SplitHeuristic::kRandom, 8, seed});
    std::vector<double> sums(scene.polygons.size(), 0.0);
    for (uint32_t f = 0; f < tree.fragments.size(); ++f) {
      sums[tree.fragment_polygon[f]] += polygonArea(tree.fragmentVertices(f));
      EXPECT_EQ(tree.fragments[f].face_id, scene.polygons[tree.fragment_polygon[f]].face_id);
    }
    for (size_t i = 0; i < scene.polygons.size(); ++i) {
      const double area = polygonArea(scene.polygonVertices(i));
      EXPECT_NEAR(sums[i], area, 1e-9 * area) << "polygon " << i;
    }
  }
}

// Every vertex of the front (back) subtree lies on the front (back) side of the node plane, up to
// the double rounding of the stored approximations.
TEST(Bsp, SubtreesLieOnTheirSide) {
  const Scene scene = randomScene(31, 80);
  const BspTree tree = buildBsp(scene);
  std::vector<std::vector<uint32_t>> under(tree.nodes.size());
  for (size_t i = tree.nodes.size(); i-- > 0;) {
    const BspNode& n = tree.nodes[i];
    for (uint32_t f = n.first_fragment; f < n.first_fragment + n.fragment_count; ++f) under[i].push_back(f);
    for (int32_t c : {n.front, n.back}) {
      if (c < 0) continue;
      const double sign = c == n.front ? 1.0 : -1.0;
      for (uint32_t f : under[static_cast<size_t>(c)])
        for (const glm::dvec3& v : tree.fragmentVertices(f))
          EXPECT_GE(sign * (glm::dot(n.plane.n, v) - n.plane.d), -1e-12) << "node " << i;
      under[i].insert(under[i].end(), under[static_cast<size_t>(c)].begin(), under[static_cast<size_t>(c)].end());
    }
  }
}

TEST(Bsp, CoplanarPolygonsOfBothOrientationsStayAtOneNode) {
  Scene scene;
  scene.name = "coplanar";
  // Two overlapping squares in x = 0, one facing +x and one facing -x, and a wall crossing them.
  const std::vector<glm::dvec3> plus = {{0, 0, 0}, {0, 2, 0}, {0, 2, 2}, {0, 0, 2}};     // n = +x
  const std::vector<glm::dvec3> minus = {{0, 1, 1}, {0, 1, 3}, {0, 3, 3}, {0, 3, 1}};    // n = -x
  const std::vector<glm::dvec3> cross = {{-2, 0, 1.5}, {2, 0, 1.5}, {2, 3, 1.5}, {-2, 3, 1.5}};
  addFace(scene, plus, 1, "test");
  addFace(scene, minus, 2, "test");
  addFace(scene, cross, 3, "test");
  ASSERT_EQ(scene.polygons.size(), 3u);
  ASSERT_EQ(scene.polygons[0].plane.n, glm::dvec3(1, 0, 0));
  ASSERT_EQ(scene.polygons[1].plane.n, glm::dvec3(-1, 0, 0));
  for (auto heuristic : {SplitHeuristic::kLeastCrossed, SplitHeuristic::kRandom}) {
    for (uint64_t seed = 1; seed <= 6; ++seed) {
      const BspTree tree = buildBsp(scene, BspOptions{heuristic, 8, seed});
      // Both x = 0 squares always sit at the node of the plane x = 0 (whichever one defines it).
      int x_nodes = 0;
      for (const BspNode& n : tree.nodes) {
        if (n.plane.n.x == 0.0) continue;
        ++x_nodes;
        std::vector<int> faces;
        for (uint32_t f = n.first_fragment; f < n.first_fragment + n.fragment_count; ++f) {
          faces.push_back(static_cast<int>(tree.fragment_polygon[f]));
          EXPECT_EQ(tree.fragment_orientation[f] * n.plane.n.x, tree.fragments[f].plane.n.x);
        }
        std::sort(faces.begin(), faces.end());
        faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
        EXPECT_EQ(faces, (std::vector<int>{0, 1}));
      }
      EXPECT_GE(x_nodes, 1);
      std::vector<uint32_t> order;
      backToFront(tree, {5, 1.5, 1.0}, order, true);
      for (uint32_t f : order) EXPECT_NE(tree.fragment_polygon[f], 1u) << "the -x square is a back face from +x";
      backToFront(tree, {-5, 1.5, 1.0}, order, true);
      for (uint32_t f : order) EXPECT_NE(tree.fragment_polygon[f], 0u) << "the +x square is a back face from -x";
      backToFront(tree, {0, 1.5, 1.0}, order, true);  // in the plane: both edge-on
      for (uint32_t f : order) EXPECT_EQ(tree.fragment_polygon[f], 2u);
    }
  }
}

// A fan of thin quads whose planes differ by ~1e-12 rad around a common line, far from the
// origin, crossed by other quads: classification must stay consistent (every fragment once,
// subtrees on their side, order agrees with rays).
TEST(Bsp, NearlyParallelPlanesStayConsistent) {
  Scene scene;
  scene.name = "fan";
  const glm::dvec3 base(1e3, 0, 0);
  for (int i = 0; i < 12; ++i) {
    const double a = (i - 6) * 1e-12;
    const glm::dvec3 dir(std::cos(a), 0, std::sin(a));
    const glm::dvec3 off = 1e-9 * static_cast<double>(i % 3) * glm::dvec3(0, 0, 1);
    std::vector<glm::dvec3> q = {base + off, base + off + 4.0 * dir, base + off + 4.0 * dir + glm::dvec3(0, 2, 0),
                                 base + off + glm::dvec3(0, 2, 0)};
    if (i % 2) std::reverse(q.begin(), q.end());
    addFace(scene, q, kColor, "fan");
  }
  for (int i = 0; i < 6; ++i) {
    const double x = 1e3 + 0.5 + 0.6 * i;
    std::vector<glm::dvec3> q = {{x, -1, -1}, {x, -1, 1}, {x + 0.1, 3, 1}, {x + 0.1, 3, -1}};
    addFace(scene, q, kColor, "fan");
  }
  ASSERT_GE(scene.polygons.size(), 12u);
  for (auto heuristic : {SplitHeuristic::kLeastCrossed, SplitHeuristic::kRandom}) {
    const BspTree tree = buildBsp(scene, BspOptions{heuristic, 8, 3});
    std::vector<uint32_t> order;
    std::mt19937_64 rng(77);
    for (int e = 0; e < 30; ++e) {
      const glm::dvec3 eye = base + glm::dvec3(uniform(rng, -1, 5), uniform(rng, -1, 3), uniform(rng, -1, 1) * 1e-9);
      backToFront(tree, eye, order);
      expectPermutation(order, tree.fragments.size());
      const RayCheck check = checkRays(tree, eye, order, 500 + static_cast<uint64_t>(e), 100);
      EXPECT_EQ(check.violations, 0) << check.first;
    }
  }
}

TEST(Bsp, ExactPlaneSignMatchesRationals) {
  std::mt19937_64 rng(99);
  int zeros = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const glm::dvec3 n = randomUnit(rng);
    const glm::dvec3 p = randomPoint(rng, std::pow(10.0, uniform(rng, -3, 6)));
    double d = glm::dot(n, p);
    // Nudge d by a few ulps so that many cases sit within the filter bound, some exactly on.
    const int ulps = static_cast<int>(rng() % 7) - 3;
    for (int k = 0; k < std::abs(ulps); ++k) d = std::nextafter(d, ulps > 0 ? INFINITY : -INFINITY);
    const int s = exact::planeSign(n.x, n.y, n.z, d, p.x, p.y, p.z);
    const int r = exact::planeSignRational(n.x, n.y, n.z, d, p.x, p.y, p.z);
    ASSERT_EQ(s, r) << i;
    zeros += r == 0;
    ++checked;
  }
  // Axis-aligned planes through the point: exactly zero, as walls through wall corners are.
  EXPECT_EQ(exact::planeSign(1, 0, 0, 5.1, 5.1, 3, -7), 0);
  EXPECT_EQ(exact::planeSign(0, 1, 0, 1e-300, 2, 1e-300, 3), 0);
  EXPECT_EQ(exact::planeSign(0.1, 0.2, 0.3, 0.1 * 3 + 0.2 * 5, 3, 5, 0), exact::planeSignRational(0.1, 0.2, 0.3, 0.1 * 3 + 0.2 * 5, 3, 5, 0));
  EXPECT_EQ(exact::planeSign(1, 0, 0, 0, NAN, 0, 0), 0);
  EXPECT_GT(checked, 0);
  (void)zeros;
}

TEST(Bsp, SaveLoadRoundTripsExactly) {
  const Scene scene = randomScene(41, 60);
  const BspTree tree = buildBsp(scene);
  const std::string path = testing::TempDir() + "/walkvis_test_bsp_roundtrip.bsp";
  saveBsp(tree, path);
  const BspTree loaded = loadBsp(path);
  ASSERT_EQ(loaded.vertices.size(), tree.vertices.size());
  EXPECT_EQ(std::memcmp(loaded.vertices.data(), tree.vertices.data(), tree.vertices.size() * sizeof(glm::dvec3)), 0);
  EXPECT_EQ(loaded.fragment_polygon, tree.fragment_polygon);
  EXPECT_EQ(loaded.fragment_orientation, tree.fragment_orientation);
  ASSERT_EQ(loaded.nodes.size(), tree.nodes.size());
  for (size_t i = 0; i < tree.nodes.size(); ++i) {
    EXPECT_EQ(loaded.nodes[i].plane.n, tree.nodes[i].plane.n);
    EXPECT_EQ(loaded.nodes[i].plane.d, tree.nodes[i].plane.d);
    EXPECT_EQ(loaded.nodes[i].front, tree.nodes[i].front);
    EXPECT_EQ(loaded.nodes[i].back, tree.nodes[i].back);
    EXPECT_EQ(loaded.nodes[i].polygon, tree.nodes[i].polygon);
  }
  for (size_t i = 0; i < tree.fragments.size(); ++i) {
    EXPECT_EQ(loaded.fragments[i].face_id, tree.fragments[i].face_id);
    EXPECT_EQ(loaded.fragments[i].plane.n, tree.fragments[i].plane.n);
    EXPECT_EQ(loaded.fragments[i].first_vertex, tree.fragments[i].first_vertex);
  }
  EXPECT_EQ(loaded.scene_hash, sceneHash(scene));
  EXPECT_NO_THROW(checkBspMatchesScene(loaded, scene, path));
  Scene other = scene;
  other.vertices[0].x += 1e-12;
  EXPECT_THROW(checkBspMatchesScene(loaded, other, path), Error);
  EXPECT_EQ(loaded.stats.ratio, tree.stats.ratio);
  EXPECT_EQ(loaded.stats.depth_max, tree.stats.depth_max);
  std::vector<uint32_t> a, b;
  for (const glm::dvec3& eye : randomEyes(42, 30, 12.0)) {
    backToFront(tree, eye, a, true);
    backToFront(loaded, eye, b, true);
    EXPECT_EQ(a, b);
  }
  std::filesystem::remove(path);
}

TEST(Bsp, CorruptFilesAreClearErrors) {
  const Scene scene = randomScene(43, 20);
  const BspTree tree = buildBsp(scene);
  const std::string path = testing::TempDir() + "/walkvis_test_bsp_corrupt.bsp";
  saveBsp(tree, path);
  const std::vector<uint8_t> good = readFileBytes(path);
  ASSERT_GT(good.size(), 100u);
  EXPECT_NO_THROW(loadBspFromMemory(good, "good"));
  // Every single flipped byte is caught (header fields by their checks, the rest by the checksum).
  for (size_t i = 0; i < good.size(); i += std::max<size_t>(1, good.size() / 97)) {
    std::vector<uint8_t> bad = good;
    bad[i] ^= 0x5a;
    EXPECT_THROW(loadBspFromMemory(bad, "flip"), Error) << "byte " << i;
  }
  for (size_t len : {size_t{0}, size_t{5}, size_t{20}, size_t{40}, good.size() / 2, good.size() - 1}) {
    std::vector<uint8_t> cut(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(len));
    EXPECT_THROW(loadBspFromMemory(cut, "cut"), Error) << "length " << len;
  }
  {
    std::vector<uint8_t> v2 = good;
    v2[8] = 2;  // version field
    try {
      loadBspFromMemory(v2, "v2.bsp");
      ADD_FAILURE() << "version 2 accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("version"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("v2.bsp"), std::string::npos) << e.what();
    }
  }
  {  // the file on disk, truncated
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(good.data()), static_cast<std::streamsize>(good.size() - 3));
  }
  EXPECT_THROW(loadBsp(path), Error);
  std::filesystem::remove(path);
  EXPECT_THROW(loadBsp(path), Error);
}

TEST(Bsp, StatisticsAndHeuristicBeatsRandomOnWalls) {
  const Scene scene = wallScene(7, 400);
  ASSERT_EQ(scene.polygons.size(), 400u);
  const BspTree good = buildBsp(scene, BspOptions{SplitHeuristic::kLeastCrossed, 8, 1});
  double random_ratio = 0.0;
  for (uint64_t seed = 1; seed <= 3; ++seed)
    random_ratio += buildBsp(scene, BspOptions{SplitHeuristic::kRandom, 8, seed}).stats.ratio / 3.0;
  const BspStats& s = good.stats;
  EXPECT_EQ(s.input_polygons, 400u);
  EXPECT_EQ(s.fragments, good.fragments.size());
  EXPECT_EQ(s.nodes, good.nodes.size());
  EXPECT_DOUBLE_EQ(s.ratio, static_cast<double>(s.fragments) / 400.0);
  EXPECT_GE(s.ratio, 1.0);
  EXPECT_GE(s.depth_max, 1u);
  EXPECT_GE(s.depth_mean, 1.0);
  EXPECT_LE(s.depth_mean, s.depth_max);
  EXPECT_GT(s.bytes, 0u);
  EXPECT_GE(s.build_seconds, 0.0);
  std::printf("walls: heuristic N/n %.3f depth %u/%.1f, random N/n %.3f\n", s.ratio, s.depth_max, s.depth_mean,
              random_ratio);
  EXPECT_LT(s.ratio, random_ratio);
}

// Walls standing on one floor that spans them all: every wall plane crosses the floor, the
// floor's plane crosses nothing (walls touch it with their bottom edges). With free_first the
// root must be the floor's plane, in both exact modes (lookahead for <= 128 fragments, full
// count above); the tree stays deterministic for its options.
TEST(Bsp, FreePlaneIsTakenFirst) {
  for (int walls : {60, 300}) {
    Scene scene = wallScene(11, walls);
    const std::vector<glm::dvec3> floor = {{-10, 0, -10}, {-10, 0, 140}, {140, 0, 140}, {140, 0, -10}};
    addFace(scene, floor, kColor, "test");
    ASSERT_EQ(scene.polygons.size(), static_cast<size_t>(walls) + 1);
    const uint32_t floor_poly = static_cast<uint32_t>(walls);
    for (bool free_first : {true, false}) {
      BspOptions options;
      options.free_first = free_first;
      const BspTree tree = buildBsp(scene, options);
      const Plane& root = tree.nodes[tree.root].plane;
      const bool root_is_floor = root.n.x == 0.0 && root.n.z == 0.0 && root.d == 0.0;
      if (free_first) {
        EXPECT_TRUE(root_is_floor) << walls << " walls: root plane from polygon " << tree.nodes[tree.root].polygon;
        EXPECT_EQ(tree.nodes[tree.root].polygon, floor_poly);
      }
      // Whatever the root, the result is exact and complete, and the same on a rebuild.
      const BspTree again = buildBsp(scene, options);
      ASSERT_EQ(again.fragments.size(), tree.fragments.size());
      ASSERT_EQ(again.nodes.size(), tree.nodes.size());
      for (size_t i = 0; i < tree.nodes.size(); ++i) EXPECT_EQ(again.nodes[i].polygon, tree.nodes[i].polygon);
      std::vector<uint32_t> order;
      backToFront(tree, glm::dvec3(50.5, 1.5, 50.5), order);
      expectPermutation(order, tree.fragments.size());
      std::printf("%d walls + floor, free_first %d: N/n %.3f, root polygon %u\n", walls, free_first ? 1 : 0,
                  tree.stats.ratio, tree.nodes[tree.root].polygon);
    }
  }
}

// Full counting (every distinct plane on the whole set) uses no random choice: where it covers
// every node bigger than lookahead_max the tree does not depend on the seed, while sampling does.
// Both stay exact and complete.
TEST(Bsp, FullCountIsSeedIndependent) {
  const Scene scene = wallScene(7, 400);
  for (uint64_t full_count_max : {uint64_t{64'000'000}, uint64_t{0}}) {
    BspOptions a;
    a.full_count_max = full_count_max;
    a.lookahead_max = 0;
    BspOptions b = a;
    b.seed = 2;
    const BspTree ta = buildBsp(scene, a), tb = buildBsp(scene, b);
    bool same = ta.nodes.size() == tb.nodes.size();
    for (size_t i = 0; same && i < ta.nodes.size(); ++i) same = ta.nodes[i].polygon == tb.nodes[i].polygon;
    std::printf("walls: full_count_max %llu: N/n %.3f (seed 1), %.3f (seed 2)\n",
                static_cast<unsigned long long>(full_count_max), ta.stats.ratio, tb.stats.ratio);
    EXPECT_EQ(same, full_count_max != 0);
    for (const BspTree* t : {&ta, &tb}) {
      std::vector<uint32_t> order;
      backToFront(*t, glm::dvec3(33.3, 1.5, 66.6), order);
      expectPermutation(order, t->fragments.size());
    }
  }
}

// Pilot method: the greedy's own first choice is among the candidates and every rollout uses the
// greedy, so on scenes where the choice is deterministic (full count and lookahead cover every
// node) and the double rollout sees the same sides as the exact build (integer coordinates), the
// pilot's tree never has more fragments than plain greedy. With no work budget it is plain greedy
// exactly. Both are deterministic, exact and complete.
TEST(Bsp, PilotNeverWorseThanGreedy) {
  uint64_t pilot_total = 0, greedy_total = 0;
  for (uint64_t seed : {3, 5, 8, 13}) {
    Scene scene = wallScene(seed, 250);
    // Floor and ceiling tiles: big horizontal polygons the vertical walls' planes cut.
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        const double x = 25.0 * i, z = 25.0 * j;
        addFace(scene, std::vector<glm::dvec3>{{x, 0, z}, {x, 0, z + 25}, {x + 25, 0, z + 25}, {x + 25, 0, z}},
                kColor, "test");
        addFace(scene, std::vector<glm::dvec3>{{x, 3, z}, {x + 25, 3, z}, {x + 25, 3, z + 25}, {x, 3, z + 25}},
                kColor, "test");
      }
    BspOptions greedy;
    greedy.pilot_candidates = 0;
    BspOptions pilot;
    pilot.pilot_candidates = 6;
    pilot.pilot_min_set = 16;
    pilot.pilot_depth_max = 64;
    BspOptions no_budget = pilot;
    no_budget.pilot_work_max = 0;
    const BspTree g = buildBsp(scene, greedy), p = buildBsp(scene, pilot), p2 = buildBsp(scene, pilot),
                  nb = buildBsp(scene, no_budget);
    std::printf("walls %llu + floors: greedy N/n %.3f, pilot N/n %.3f\n", static_cast<unsigned long long>(seed),
                g.stats.ratio, p.stats.ratio);
    EXPECT_LE(p.fragments.size(), g.fragments.size()) << "seed " << seed;
    pilot_total += p.fragments.size();
    greedy_total += g.fragments.size();
    auto sameTree = [](const BspTree& a, const BspTree& b) {
      if (a.nodes.size() != b.nodes.size() || a.fragments.size() != b.fragments.size()) return false;
      for (size_t i = 0; i < a.nodes.size(); ++i)
        if (a.nodes[i].polygon != b.nodes[i].polygon || a.nodes[i].front != b.nodes[i].front) return false;
      return true;
    };
    EXPECT_TRUE(sameTree(p, p2)) << "seed " << seed << ": pilot not deterministic";
    EXPECT_TRUE(sameTree(nb, g)) << "seed " << seed << ": pilot_work_max 0 is not plain greedy";
    std::vector<uint32_t> order;
    backToFront(p, glm::dvec3(50.5, 1.5, 50.5), order);
    expectPermutation(order, p.fragments.size());
  }
  std::printf("pilot %llu fragments, greedy %llu\n", static_cast<unsigned long long>(pilot_total),
              static_cast<unsigned long long>(greedy_total));
}

// Doom-like sloped walls: chains of collinear wall segments with integer ends (direction (3, 1),
// (2, 5), ...; each segment its own polygon and heights) and a floor and a ceiling triangle on each
// segment. Each polygon's plane is rounded on its own, so the other segments' ends and the
// triangles' corners lie a hair off it: the exact build splits a sliver off each of them that is
// still in the node's set when that plane is taken, unless the heuristic saw it coming.
Scene slopedWallScene(uint64_t seed) {
  std::mt19937_64 rng(seed);
  Scene scene;
  scene.name = "sloped" + std::to_string(seed);
  const int dirs[][2] = {{3, 1}, {2, 5}, {4, 3}, {1, 3}, {5, 2}, {3, -2}};
  for (int chain = 0; chain < 10; ++chain) {
    const int* dir = dirs[rng() % 6];
    glm::dvec3 p{static_cast<double>(rng() % 40), 0, static_cast<double>(rng() % 40)};
    const int segments = 2 + static_cast<int>(rng() % 3);
    for (int k = 0; k < segments; ++k) {
      const double len = 1.0 + static_cast<double>(rng() % 2);
      const glm::dvec3 q = p + len * glm::dvec3(dir[0], 0, dir[1]);
      const double lo = static_cast<double>(rng() % 2), hi = 2.0 + static_cast<double>(rng() % 2);
      std::vector<glm::dvec3> quad = {{p.x, lo, p.z}, {q.x, lo, q.z}, {q.x, hi, q.z}, {p.x, hi, p.z}};
      if (rng() % 2) std::reverse(quad.begin(), quad.end());
      addFace(scene, quad, kColor, "test");
      // A triangle on the segment's left side, its apex on the integer grid.
      const glm::dvec3 apex = 0.5 * (p + q) + glm::dvec3(-dir[1], 0, dir[0]);
      const glm::dvec3 r{std::round(apex.x), 0, std::round(apex.z)};
      addFace(scene, std::vector<glm::dvec3>{{p.x, lo, p.z}, {r.x, lo, r.z}, {q.x, lo, q.z}}, kColor, "test");
      addFace(scene, std::vector<glm::dvec3>{{p.x, hi, p.z}, {q.x, hi, q.z}, {r.x, hi, r.z}}, kColor, "test");
      p = q;
    }
  }
  return scene;
}

TEST(Bsp, ExactHeuristicSidesAvoidSlivers) {
  uint64_t exact_total = 0, tolerant_total = 0;
  for (uint64_t seed : {1, 2, 3, 4}) {
    const Scene scene = slopedWallScene(seed);
    BspOptions exact_sides;
    exact_sides.drop_slivers = false;  // what the heuristic's sides are for: builds that split every sliver
    BspOptions tolerant = exact_sides;
    tolerant.exact_heuristic_sides = false;
    const BspTree e = buildBsp(scene, exact_sides), e2 = buildBsp(scene, exact_sides), t = buildBsp(scene, tolerant);
    std::printf("sloped walls %llu (n %zu): exact sides N/n %.3f, tolerant %.3f\n", static_cast<unsigned long long>(seed),
                scene.polygons.size(), e.stats.ratio, t.stats.ratio);
    EXPECT_EQ(e.fragments.size(), e2.fragments.size()) << "seed " << seed << ": not deterministic";
    for (size_t i = 0; i < std::min(e.nodes.size(), e2.nodes.size()); ++i)
      ASSERT_EQ(e.nodes[i].polygon, e2.nodes[i].polygon) << "seed " << seed << ": not deterministic";
    std::vector<uint32_t> order;
    backToFront(e, glm::dvec3(10.5, 1.5, 9.5), order);
    expectPermutation(order, e.fragments.size());
    EXPECT_LE(e.fragments.size(), t.fragments.size()) << "seed " << seed;
    exact_total += e.fragments.size();
    tolerant_total += t.fragments.size();
  }
  std::printf("exact sides %llu fragments, tolerant %llu\n", static_cast<unsigned long long>(exact_total),
              static_cast<unsigned long long>(tolerant_total));
  EXPECT_LT(exact_total, tolerant_total);
}

TEST(Bsp, EmptySceneAndBadPlanes) {
  Scene empty;
  const BspTree tree = buildBsp(empty);
  EXPECT_EQ(tree.root, -1);
  std::vector<uint32_t> order{7};
  backToFront(tree, {0, 0, 0}, order);
  EXPECT_TRUE(order.empty());
  const std::string path = testing::TempDir() + "/walkvis_test_bsp_empty.bsp";
  saveBsp(tree, path);
  EXPECT_EQ(loadBsp(path).nodes.size(), 0u);
  std::filesystem::remove(path);

  Scene bad = randomScene(3, 3);
  bad.polygons[1].plane.n = glm::dvec3(0.0);
  EXPECT_THROW(buildBsp(bad), Error);
  bad.polygons[1].plane.n = glm::dvec3(NAN, 0, 0);
  EXPECT_THROW(buildBsp(bad), Error);
}

TEST(Bsp, OfficeScene) {
  const Scene scene = loadScene("gen:office?rooms=40");
  const BspTree tree = buildBsp(scene);
  std::printf("gen:office?rooms=40: n %zu N/n %.3f depth %u/%.1f build %.3f s exact fallbacks %llu\n",
              scene.polygons.size(), tree.stats.ratio, tree.stats.depth_max, tree.stats.depth_mean,
              tree.stats.build_seconds, static_cast<unsigned long long>(tree.stats.exact_fallbacks));
  std::vector<uint32_t> order;
  backToFront(tree, scene.start_eye, order);
  expectPermutation(order, tree.fragments.size());
  const RayCheck check = checkRays(tree, scene.start_eye, order, 3, 300);
  EXPECT_EQ(check.violations, 0) << check.first;
  EXPECT_GT(check.compared, 100);
  EXPECT_LT(tree.stats.ratio, 1.5);
  // Axis-aligned fragments stay exactly axis-aligned (floors and ceilings exactly horizontal).
  int64_t flat = 0;
  for (uint32_t f = 0; f < tree.fragments.size(); ++f) {
    const Plane& pl = tree.fragments[f].plane;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(pl.n[k]) != 1.0) continue;
      for (const glm::dvec3& v : tree.fragmentVertices(f)) EXPECT_EQ(v[k], pl.n[k] * pl.d) << "fragment " << f;
      ++flat;
    }
  }
  EXPECT_EQ(flat, static_cast<int64_t>(tree.fragments.size())) << "every office polygon is axis-aligned";
}

}  // namespace
}  // namespace walkvis

namespace walkvis {
namespace {

// The hard cases (docs/DESIGN.md, "Hard cases"): nothing crashes, every fragment is listed once,
// and the order agrees with ray casting from the start eye and from random eyes in the scene's box.
TEST(Bsp, HardCases) {
  for (const std::string& name : hardCaseNames()) {
    Scene scene;
    try {
      scene = loadScene("gen:" + name);
    } catch (const Error&) {
      continue;  // NaN / infinite input is rejected by the loader already
    }
    if (scene.polygons.empty()) continue;
    const Bounds b = sceneBounds(scene);
    for (auto heuristic : {SplitHeuristic::kLeastCrossed, SplitHeuristic::kRandom}) {
      const BspTree tree = buildBsp(scene, BspOptions{heuristic, 8, 5});
      std::vector<glm::dvec3> eyes = {scene.start_eye};
      std::mt19937_64 rng(17);
      for (int i = 0; i < 6; ++i) {
        const glm::dvec3 t(uniform(rng, 0, 1), uniform(rng, 0, 1), uniform(rng, 0, 1));
        eyes.push_back(b.lo + t * (b.hi - b.lo));
      }
      std::vector<uint32_t> order;
      int64_t compared = 0;
      for (size_t e = 0; e < eyes.size(); ++e) {
        backToFront(tree, eyes[e], order);
        expectPermutation(order, tree.fragments.size());
        const RayCheck check = checkRays(tree, eyes[e], order, 900 + e, 100);
        EXPECT_EQ(check.violations, 0) << name << ": " << check.first;
        compared += check.compared;
      }
      std::printf("%s (%s): n %zu N %zu compared %lld\n", name.c_str(),
                  heuristic == SplitHeuristic::kRandom ? "random" : "least-crossed", scene.polygons.size(),
                  tree.fragments.size(), static_cast<long long>(compared));
    }
  }
}

TEST(Bsp, FreedoomMap) {
  const char* wad = "/usr/share/games/doom/freedoom2.wad";
  if (!std::filesystem::exists(wad)) GTEST_SKIP() << wad << " not installed";
  const Scene scene = loadScene("freedoom2.wad:MAP01");
  const BspTree tree = buildBsp(scene);
  std::printf("freedoom2.wad:MAP01: n %zu N/n %.3f depth %u/%.1f\n", scene.polygons.size(), tree.stats.ratio,
              tree.stats.depth_max, tree.stats.depth_mean);
  EXPECT_LE(tree.stats.ratio, 1.5);
  std::vector<uint32_t> order;
  backToFront(tree, scene.start_eye, order);
  expectPermutation(order, tree.fragments.size());
  // Doom units: hits closer than 1e-9 apart are ties (see checkRays).
  const RayCheck check = checkRays(tree, scene.start_eye, order, 4, 200);
  EXPECT_EQ(check.violations, 0) << check.first;
  EXPECT_GT(check.compared, 100);
}

}  // namespace
}  // namespace walkvis

namespace walkvis {
namespace {

// ---- Detail (bsp.h, detail_extent) and slivers (drop_slivers) ----

// A box of half-sizes h about c, turned by `yaw` about the vertical, its six faces facing out,
// as one new object of scene.face_object. Returns the object.
uint32_t addBox(Scene& scene, const glm::dvec3& c, const glm::dvec3& h, double yaw) {
  const glm::dvec3 u(std::cos(yaw), 0.0, -std::sin(yaw)), w(std::sin(yaw), 0.0, std::cos(yaw)), up(0.0, 1.0, 0.0);
  const auto corner = [&](int sx, int sy, int sz) { return c + double(sx) * h.x * u + double(sy) * h.y * up + double(sz) * h.z * w; };
  const int faces[6][4][3] = {{{1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}},     {{-1, -1, -1}, {-1, -1, 1}, {-1, 1, 1}, {-1, 1, -1}},
                              {{-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}},     {{-1, -1, -1}, {1, -1, -1}, {1, -1, 1}, {-1, -1, 1}},
                              {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}},     {{-1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {1, -1, -1}}};
  uint32_t object = 0;
  for (uint32_t o : scene.face_object) object = std::max(object, o + 1);
  for (const auto& f : faces) {
    std::vector<glm::dvec3> q;
    for (const auto& s : f) q.push_back(corner(s[0], s[1], s[2]));
    glm::dvec3 centre(0.0), normal(0.0);
    for (size_t i = 0; i < 4; ++i) {
      centre += 0.25 * q[i];
      normal += glm::cross(q[i], q[(i + 1) % 4]);
    }
    if (glm::dot(normal, centre - c) < 0.0) std::reverse(q.begin(), q.end());
    const uint32_t face = addFace(scene, q, kColor, "test");
    scene.face_object.resize(face + 1, object);
    scene.face_object[face] = object;
  }
  return object;
}

// A 12 × 3 × 12 room (floor, ceiling and walls facing in, one object) split by an inner wall at
// x = 6 with a 1 m doorway (z in [5.5, 6.5]), furnished with `boxes` random boxes, some turned,
// and the hard cases of detail objects: a box whose face lies in a wall's plane (touching it), two
// interpenetrating boxes, and a box straddling the doorway.
Scene furnishedRoom(uint64_t seed, int boxes) {
  std::mt19937_64 rng(seed);
  Scene scene;
  scene.name = "furnished" + std::to_string(seed);
  const auto structure = [&](std::vector<glm::dvec3> q) {
    const uint32_t face = addFace(scene, q, kColor, "test");
    scene.face_object.resize(face + 1, 0);
  };
  structure({{0, 0, 0}, {0, 0, 12}, {12, 0, 12}, {12, 0, 0}});  // floor, facing up
  structure({{0, 3, 0}, {12, 3, 0}, {12, 3, 12}, {0, 3, 12}});  // ceiling, facing down
  structure({{0, 0, 0}, {12, 0, 0}, {12, 3, 0}, {0, 3, 0}});    // z = 0, facing +z
  structure({{0, 0, 12}, {0, 3, 12}, {12, 3, 12}, {12, 0, 12}});
  structure({{0, 0, 0}, {0, 3, 0}, {0, 3, 12}, {0, 0, 12}});    // x = 0, facing +x
  structure({{12, 0, 0}, {12, 0, 12}, {12, 3, 12}, {12, 3, 0}});
  // The inner wall, both faces, with its doorway.
  for (double side : {-1.0, 1.0}) {
    for (auto [z0, z1, y0] : {std::tuple{0.0, 5.5, 0.0}, std::tuple{6.5, 12.0, 0.0}, std::tuple{5.5, 6.5, 2.2}}) {
      std::vector<glm::dvec3> q = {{6, y0, z0}, {6, y0, z1}, {6, 3, z1}, {6, 3, z0}};
      if (side < 0) std::reverse(q.begin(), q.end());
      structure(q);
    }
  }
  addBox(scene, {1.0, 0.4, 3.0}, {1.0, 0.4, 0.5}, 0.0);               // touches the x = 0 wall
  addBox(scene, {9.0, 0.5, 9.0}, {0.6, 0.5, 0.6}, 0.0);               // two interpenetrating boxes
  addBox(scene, {9.3, 0.6, 9.2}, {0.5, 0.6, 0.4}, 0.7);
  addBox(scene, {6.0, 0.45, 6.0}, {0.8, 0.45, 0.3}, 0.2);             // straddles the doorway
  for (int i = 0; i < boxes; ++i) {
    const glm::dvec3 h(uniform(rng, 0.15, 0.7), uniform(rng, 0.15, 0.6), uniform(rng, 0.15, 0.7));
    const glm::dvec3 c(uniform(rng, 1.0, 11.0), h.y + (rng() % 3 == 0 ? uniform(rng, 0.0, 1.5) : 0.0), uniform(rng, 1.0, 11.0));
    addBox(scene, c, h, rng() % 2 ? 0.0 : uniform(rng, 0.0, 3.0));
  }
  scene.start_eye = {3.0, 1.7, 9.0};
  return scene;
}

BspOptions detailOn() {
  BspOptions options;
  options.detail_extent = 2.0;
  return options;
}

TEST(BspDetail, GroupsAreTheSmallConnectedPiecesOfEachObject) {
  const Scene scene = furnishedRoom(1, 20);
  const DetailGroups groups = detailGroups(scene, 2.0);
  EXPECT_EQ(groups.groups, 24u) << "each box is one group; the room is structure";
  EXPECT_EQ(groups.objects, 24u);
  EXPECT_EQ(groups.polygons, 24u * 6u);
  for (size_t i = 0; i < scene.polygons.size(); ++i)
    EXPECT_EQ(groups.group[i] == kStructureGroup, scene.face_object[scene.polygons[i].face_id] == 0) << i;
  // Off, and where everything is big, there is no detail at all.
  EXPECT_TRUE(detailGroups(scene, 0.0).group.empty());
  EXPECT_TRUE(detailGroups(scene, 0.01).group.empty());
}

// No structural fragment is ever cut by a detail plane or a separator: every node whose subtree
// holds a structural fragment takes a structural polygon's plane.
TEST(BspDetail, DetailNeverSplitsTheStructure) {
  for (uint64_t seed : {1, 2, 3}) {
    const Scene scene = furnishedRoom(seed, 30);
    const DetailGroups groups = detailGroups(scene, 2.0);
    const BspTree tree = buildBsp(scene, detailOn());
    std::vector<uint8_t> has_structure(tree.nodes.size(), 0);
    for (size_t i = tree.nodes.size(); i-- > 0;) {
      const BspNode& n = tree.nodes[i];
      for (uint32_t f = n.first_fragment; f < n.first_fragment + n.fragment_count; ++f)
        has_structure[i] |= groups.group[tree.fragment_polygon[f]] == kStructureGroup;
      for (int32_t c : {n.front, n.back})
        if (c >= 0) has_structure[i] |= has_structure[static_cast<size_t>(c)];
      if (!has_structure[i]) continue;
      ASSERT_NE(n.polygon, kSeparatorPolygon) << "seed " << seed << ": a separator above structure";
      EXPECT_EQ(groups.group[n.polygon], kStructureGroup) << "seed " << seed << ": node " << i;
    }
    EXPECT_GT(tree.stats.detail_separators, 0u);
    EXPECT_GE(tree.stats.detail_inseparable, 1u) << "the interpenetrating boxes have no separating plane";
    EXPECT_EQ(tree.stats.detail_groups, groups.groups);
    std::printf("furnished room %llu: n %zu (detail %llu in %llu groups), N %llu (structure %llu), separators %llu, "
                "inseparable sets %llu, cuts %llu\n",
                static_cast<unsigned long long>(seed), scene.polygons.size(),
                static_cast<unsigned long long>(tree.stats.detail_polygons),
                static_cast<unsigned long long>(tree.stats.detail_groups),
                static_cast<unsigned long long>(tree.stats.fragments),
                static_cast<unsigned long long>(tree.stats.structure_fragments),
                static_cast<unsigned long long>(tree.stats.detail_separators),
                static_cast<unsigned long long>(tree.stats.detail_inseparable),
                static_cast<unsigned long long>(tree.stats.detail_cuts));
  }
}

// The hard cases of detail: boxes touching a wall, interpenetrating, straddling a doorway, and
// random furniture: the order agrees with exact rays from eyes all over the room, and the
// reversed order fails every compared pair (the control).
TEST(BspDetail, OrderAgreesWithRayCasting) {
  int64_t compared = 0, control = 0;
  for (uint64_t seed : {4, 5, 6}) {
    const Scene scene = furnishedRoom(seed, 25);
    const BspTree tree = buildBsp(scene, detailOn());
    std::vector<uint32_t> order;
    std::mt19937_64 rng(seed);
    for (int e = 0; e < 10; ++e) {
      const glm::dvec3 eye(uniform(rng, 0.2, 11.8), uniform(rng, 0.1, 2.9), uniform(rng, 0.2, 11.8));
      backToFront(tree, eye, order);
      expectPermutation(order, tree.fragments.size());
      const RayCheck check = checkRays(tree, eye, order, seed * 100 + e, 300);
      EXPECT_EQ(check.violations, 0) << check.first;
      compared += check.compared;
      frontToBack(tree, eye, order);
      control += checkRays(tree, eye, order, seed * 100 + e, 300).violations;
    }
  }
  EXPECT_GT(compared, 3000);
  EXPECT_EQ(control, compared);
}

TEST(BspDetail, SeparatorsSurviveSaveAndLoad) {
  const Scene scene = furnishedRoom(7, 10);
  const BspTree tree = buildBsp(scene, detailOn());
  ASSERT_GT(tree.stats.detail_separators, 0u);
  const std::string path = (std::filesystem::temp_directory_path() / "walkvis_test_detail.bsp").string();
  saveBsp(tree, path);
  const BspTree back = loadBsp(path);
  std::filesystem::remove(path);
  ASSERT_EQ(back.nodes.size(), tree.nodes.size());
  for (size_t i = 0; i < tree.nodes.size(); ++i) {
    EXPECT_EQ(back.nodes[i].polygon, tree.nodes[i].polygon);
    EXPECT_EQ(back.nodes[i].fragment_count, tree.nodes[i].fragment_count);
    EXPECT_EQ(back.nodes[i].plane.d, tree.nodes[i].plane.d);
  }
}

// A triangulated sphere (its faces on rounded planes, so shared vertices lie a hair off their
// neighbours' planes) and a hollow tube: dropping slivers keeps the order exact against rays,
// makes far fewer fragments and loses no visible area.
Scene curvedScene(uint64_t seed) {
  std::mt19937_64 rng(seed);
  Scene scene;
  scene.name = "curved" + std::to_string(seed);
  const glm::dvec3 c(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
  const int rings = 6, segments = 10;
  const auto at = [&](int r, int s) {
    const double th = M_PI * r / rings, ph = 2.0 * M_PI * s / segments + 0.1 * static_cast<double>(seed);
    return c + 2.0 * glm::dvec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
  };
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const glm::dvec3 a = at(r, s), b = at(r + 1, s), d = at(r, s + 1), e = at(r + 1, s + 1);
      if (r > 0) addFace(scene, std::vector<glm::dvec3>{a, d, b}, kColor, "test");
      if (r + 1 < rings) addFace(scene, std::vector<glm::dvec3>{d, e, b}, kColor, "test");
    }
  // A tube of 12 sides around the y axis at x = 5, inner and outer faces (hollow, not convex).
  for (double radius : {0.5, 0.6}) {
    for (int s = 0; s < 12; ++s) {
      const double p0 = 2.0 * M_PI * s / 12, p1 = 2.0 * M_PI * (s + 1) / 12;
      std::vector<glm::dvec3> q = {{5 + radius * std::cos(p0), -2, radius * std::sin(p0)},
                                   {5 + radius * std::cos(p1), -2, radius * std::sin(p1)},
                                   {5 + radius * std::cos(p1), 2, radius * std::sin(p1)},
                                   {5 + radius * std::cos(p0), 2, radius * std::sin(p0)}};
      if (radius > 0.55) std::reverse(q.begin(), q.end());  // outer faces out, inner faces in
      addFace(scene, q, kColor, "test");
    }
  }
  return scene;
}

TEST(BspSlivers, DroppedNotSplitAndTheOrderStaysExact) {
  uint64_t kept_total = 0, split_total = 0;
  int64_t compared = 0;
  for (uint64_t seed : {1, 2}) {
    const Scene scene = curvedScene(seed);
    BspOptions split_all;
    split_all.drop_slivers = false;
    // The exact splits cost seconds here (every sliver's vertices need exact arithmetic): one seed.
    const BspTree tree = buildBsp(scene), exact = seed == 1 ? buildBsp(scene, split_all) : buildBsp(scene);
    if (seed == 1) {
      EXPECT_EQ(exact.stats.slivers_dropped, 0u);
    }
    EXPECT_GT(tree.stats.slivers_dropped, 0u) << "seed " << seed;
    kept_total += tree.fragments.size();
    split_total += exact.fragments.size();
    std::vector<double> sums(scene.polygons.size(), 0.0);
    for (uint32_t f = 0; f < tree.fragments.size(); ++f)
      sums[tree.fragment_polygon[f]] += polygonArea(tree.fragmentVertices(f));
    for (size_t i = 0; i < scene.polygons.size(); ++i) {
      // A dropped piece lies within 2^-30 of the extent (~6) of a plane, across a face < 2 long.
      const double area = polygonArea(scene.polygonVertices(i));
      EXPECT_NEAR(sums[i], area, 1e-6 * area + 1e-7) << "seed " << seed << " polygon " << i;
    }
    std::vector<uint32_t> order;
    for (const glm::dvec3& eye : randomEyes(seed + 40, 16, 4.0)) {
      backToFront(tree, eye, order);
      expectPermutation(order, tree.fragments.size());
      const RayCheck check = checkRays(tree, eye, order, seed * 10, 300);
      EXPECT_EQ(check.violations, 0) << check.first;
      compared += check.compared;
    }
    std::printf("curved %llu: n %zu, N %zu with slivers dropped (%llu), %zu split exactly (seed 1 only)\n",
                static_cast<unsigned long long>(seed), scene.polygons.size(), tree.fragments.size(),
                static_cast<unsigned long long>(tree.stats.slivers_dropped), exact.fragments.size());
  }
  EXPECT_LT(kept_total, split_total);
  EXPECT_GT(compared, 500);
}

}  // namespace
}  // namespace walkvis
