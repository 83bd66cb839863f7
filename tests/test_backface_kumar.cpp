// Kumar et al. hierarchical back-face computation (backface/kumar.h, method `hierarchy`): no front
// face is ever culled over 10,000 random eyes per mesh; view-point tracking gives the full region
// membership test's verdict for every cluster along random paths with small steps and large jumps;
// the verdicts agree with the polygons' own facing; rigid motion; the regions' geometry.
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "backface/backface.h"
#include "backface/kumar.h"
#include "backface_test_util.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

using backface_test::Frame;
using backface_test::frameOf;
using backface_test::randomEye;
using backface_test::randomSoup;
using backface_test::randomUnit;

constexpr int kEyes = 10000;

// No front face culled at kEyes random eyes; returns culled / back-facing.
double expectConservative(const Scene& s, uint64_t seed) {
  const auto culler = makeBackfaceCuller(BackfaceMethod::kHierarchy, backfaceInput(s));
  EXPECT_EQ(culler->polygonCount(), s.polygons.size());
  const Frame f = frameOf(s);
  std::vector<uint8_t> units(culler->unitCount()), culled(s.polygons.size());
  std::mt19937_64 rng(seed);
  uint64_t false_culls = 0, culled_total = 0, back_total = 0;
  glm::dvec3 last(0.0);
  for (int e = 0; e < kEyes; ++e) {
    BackfaceView view;
    // Every other eye is a small step from the last one, so that tracking is exercised too.
    view.eye = e % 2 ? last + 0.01 * f.radius * randomUnit(rng) : randomEye(s, rng, f);
    last = view.eye;
    culler->cull(view, units);
    expandToPolygons(*culler, units, culled);
    for (size_t p = 0; p < s.polygons.size(); ++p) {
      const bool front = isFrontFacing(s.polygons[p].plane, view.eye);
      false_culls += culled[p] && front;
      culled_total += culled[p];
      back_total += !front;
    }
  }
  EXPECT_EQ(false_culls, 0u) << s.name;
  EXPECT_GT(culled_total, 0u) << s.name;
  return static_cast<double>(culled_total) / static_cast<double>(back_total);
}

TEST(BackfaceKumar, SphereNoFrontFaceCulled) {
  const double eff = expectConservative(loadScene("gen:sphere"), 21);
  RecordProperty("effectiveness", std::to_string(eff));
  EXPECT_GT(eff, 0.3);
}
TEST(BackfaceKumar, DomeNoFrontFaceCulled) { expectConservative(loadScene("gen:dome"), 22); }
TEST(BackfaceKumar, InwardDomeNoFrontFaceCulled) { expectConservative(loadScene("gen:dome?inside=1&tris=600"), 23); }
TEST(BackfaceKumar, SoupNoFrontFaceCulled) { expectConservative(randomSoup(24, 400), 24); }
TEST(BackfaceKumar, FarFromOriginNoFrontFaceCulled) { expectConservative(backface_test::farFromOriginSphere(), 25); }

// Per node: the verdict is true of the node's polygons (Back: none front-facing, Front: all).
void expectVerdictHolds(const Scene& s, const KumarHierarchy& h, size_t node, KumarVerdict v, const glm::dvec3& eye,
                        uint64_t& wrong) {
  if (v == KumarVerdict::kMixed) return;
  for (uint32_t p : h.nodePolygons(node)) {
    wrong += isFrontFacing(s.polygons[p].plane, eye) != (v == KumarVerdict::kFront);
  }
}

// Random paths: steps of 0.1–3% of the radius, and every 50th step a jump anywhere (randomEye).
void expectTrackingMatchesFull(const Scene& s, uint64_t seed, int steps) {
  KumarHierarchy h(backfaceInput(s), {});
  KumarHierarchy per_frame(backfaceInput(s), {});  // used as a renderer would: cull() once per frame
  std::vector<uint8_t> leaves(per_frame.leafCount()), expected(per_frame.leafCount());
  uint64_t leaf_mismatches = 0;
  const Frame f = frameOf(s);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  glm::dvec3 eye = randomEye(s, rng, f);
  uint64_t mismatches = 0, wrong = 0, back = 0, front = 0, queries = 0;
  for (int step = 0; step < steps; ++step) {
    if (step % 50 == 49) {
      eye = randomEye(s, rng, f);
    } else {
      eye += f.radius * (0.001 + 0.03 * u(rng)) * randomUnit(rng);
      if (glm::length(eye - f.center) > 6.0 * f.radius) eye = f.center + 0.5 * (eye - f.center);
    }
    // cull(): nodes below a decided one are skipped, so their tracking state goes stale.
    per_frame.cull(eye, leaves);
    std::fill(expected.begin(), expected.end(), uint8_t{0});
    for (size_t node = 0; node < per_frame.nodeCount(); ++node) {
      if (per_frame.classifyFull(node, eye) != KumarVerdict::kBack) continue;
      const auto [first, last] = per_frame.nodeLeafRange(node);
      for (uint32_t l = first; l < last; ++l) expected[l] = 1;
    }
    leaf_mismatches += leaves != expected;
    h.beginFrame();
    // Every node every frame (not only those the hierarchy would visit): the most checks.
    for (size_t node = 0; node < h.nodeCount(); ++node) {
      const KumarVerdict tracked = h.track(node, eye);
      const KumarVerdict full = h.classifyFull(node, eye);
      mismatches += tracked != full;
      back += tracked == KumarVerdict::kBack;
      front += tracked == KumarVerdict::kFront;
      ++queries;
      expectVerdictHolds(s, h, node, tracked, eye, wrong);
    }
  }
  EXPECT_EQ(mismatches, 0u) << s.name;
  EXPECT_EQ(leaf_mismatches, 0u) << s.name;
  EXPECT_EQ(wrong, 0u) << s.name;
  EXPECT_GT(back, queries / 10) << s.name;
  EXPECT_GT(front, queries / 10) << s.name;
  const KumarStats& st = h.stats();
  // Tracking does the work: most queries end without the full scan.
  EXPECT_LT(st.full_tests, st.queries / 4) << s.name;
  EXPECT_GT(st.inscribed_hits, 0u) << s.name;
  testing::Test::RecordProperty(s.name + "_walk_steps_per_query", std::to_string(double(st.walk_steps) / double(st.queries)));
  testing::Test::RecordProperty(s.name + "_full_test_share", std::to_string(double(st.full_tests) / double(st.queries)));
}

TEST(BackfaceKumar, TrackingMatchesFullTestSphere) { expectTrackingMatchesFull(loadScene("gen:sphere"), 31, 600); }
TEST(BackfaceKumar, TrackingMatchesFullTestDome) { expectTrackingMatchesFull(loadScene("gen:dome"), 32, 600); }
TEST(BackfaceKumar, TrackingMatchesFullTestSoup) { expectTrackingMatchesFull(randomSoup(33, 400), 33, 600); }

// §7: a rotated and moved copy culls with the regions of the original.
TEST(BackfaceKumar, RigidMotion) {
  const Scene s = loadScene("gen:sphere?tris=1000");
  KumarHierarchy h(backfaceInput(s), {});
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<uint8_t> leaves(h.leafCount());
  uint64_t false_culls = 0, culled = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const glm::dmat3 rot(glm::rotate(glm::dmat4(1.0), 3.0 * u(rng), randomUnit(rng)));
    const glm::dvec3 move(5 * u(rng), 5 * u(rng), 5 * u(rng));
    const glm::dvec3 eye = move + (1.2 + 3.0 * (u(rng) + 1.0)) * randomUnit(rng);
    h.cullRigid(rot, move, eye, leaves);
    for (size_t l = 0; l < leaves.size(); ++l) {
      if (!leaves[l]) continue;
      for (uint32_t p : h.leafPolygons(l)) {
        ++culled;
        const Plane& pl = s.polygons[p].plane;
        const glm::dvec3 n = rot * pl.n;
        const double d = pl.d + glm::dot(n, move);  // a point x on the plane moves to R·x + t
        false_culls += glm::dot(n, eye) > d + 1e-9;
      }
    }
  }
  EXPECT_EQ(false_culls, 0u);
  EXPECT_GT(culled, 200u * 100u);
}

// The regions themselves: the centre is inside with the stated clearance, every boundary plane
// is one of the cluster's, and a cluster whose polygons all face away from an eye far behind it
// reports Back there.
TEST(BackfaceKumar, RegionsAreSound) {
  const Scene s = loadScene("gen:sphere");
  KumarHierarchy h(backfaceInput(s), {});
  ASSERT_GT(h.nodeCount(), h.leafCount());
  for (size_t node = 0; node < h.nodeCount(); ++node) {
    for (int side = 0; side < 2; ++side) {
      const KumarRegion& r = side ? h.frontRegion(node) : h.backRegion(node);
      ASSERT_TRUE(r.has_interior) << node;
      for (uint32_t p : h.nodePolygons(node)) {
        const Plane& pl = s.polygons[p].plane;
        const double g = side ? glm::dot(pl.n, r.center) - pl.d : pl.d - glm::dot(pl.n, r.center);
        EXPECT_GE(g, r.g_min * (1 - 1e-12)) << node;
      }
      EXPECT_FALSE(r.dual.empty());
      EXPECT_EQ(r.adj_begin.size(), r.dual.size() + 1);
      EXPECT_LE(r.dual.size(), h.nodePolygons(node).size());
      EXPECT_EQ(h.classifyFull(node, r.center), side ? KumarVerdict::kFront : KumarVerdict::kBack);
    }
  }
}

// LP + dual hull on a hand-made region: the unit cube's six inward faces.
TEST(BackfaceKumar, CubeRegion) {
  std::vector<Plane> planes;
  for (int a = 0; a < 3; ++a) {
    for (double sgn : {-1.0, 1.0}) {
      Plane p;
      p.n = glm::dvec3(0.0);
      p.n[a] = sgn;
      p.d = 1.0;  // |x_a| <= 1
      planes.push_back(p);
    }
  }
  planes.push_back({glm::dvec3(1, 0, 0), 5.0});  // redundant
  const KumarRegion r = buildKumarRegion(planes, glm::dvec3(-3.0), glm::dvec3(3.0));
  ASSERT_TRUE(r.has_interior);
  EXPECT_NEAR(r.g_min, 1.0, 1e-12);
  EXPECT_NEAR(glm::length(r.center), 0.0, 1e-12);
  EXPECT_EQ(r.dual.size(), 6u);  // the redundant plane is not on the boundary
  for (size_t k = 0; k < 6; ++k) EXPECT_EQ(r.adj_begin[k + 1] - r.adj_begin[k], 4u);  // an octahedron
  // Empty intersection: x <= -1 and -x <= -1.
  const std::vector<Plane> empty = {{glm::dvec3(1, 0, 0), -1.0}, {glm::dvec3(-1, 0, 0), -1.0}};
  EXPECT_FALSE(buildKumarRegion(empty, glm::dvec3(-3.0), glm::dvec3(3.0)).has_interior);
}

TEST(BackfaceKumar, EmptyInputAndBadOptions) {
  const Scene empty;
  const auto culler = makeBackfaceCuller(BackfaceMethod::kHierarchy, backfaceInput(empty));
  EXPECT_EQ(culler->polygonCount(), 0u);
  std::vector<uint8_t> units(culler->unitCount());
  culler->cull(BackfaceView{}, units);
  const Scene s = loadScene("gen:sphere?tris=80");
  BackfaceOptions bad;
  bad.hierarchy_leaf_size = 0;
  EXPECT_THROW(makeBackfaceCuller(BackfaceMethod::kHierarchy, backfaceInput(s), bad), Error);
  EXPECT_EQ(parseBackfaceMethod("hierarchy"), BackfaceMethod::kHierarchy);
}

}  // namespace
}  // namespace walkvis
