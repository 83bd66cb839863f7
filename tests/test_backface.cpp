// Backface culling (backface/): no method ever culls a front-facing polygon (eye strictly in the
// front half-space, isFrontFacing), over 10,000 random perspective eyes per mesh; every method
// culls something from far away; the near-field probability integral of Johannsen & Carter.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "backface/backface.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

constexpr int kEyes = 10000;

// Random triangles and quads of every orientation in [-1, 1]³, some coplanar pairs facing
// opposite ways, some far from the origin.
Scene randomSoup(uint64_t seed, int count) {
  Scene s;
  s.name = "soup";
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < count; ++i) {
    const glm::dvec3 c(u(rng), u(rng), u(rng));
    const glm::dvec3 a = c + 0.2 * glm::dvec3(u(rng), u(rng), u(rng));
    const glm::dvec3 b = c + 0.2 * glm::dvec3(u(rng), u(rng), u(rng));
    const glm::dvec3 d = c + 0.2 * glm::dvec3(u(rng), u(rng), u(rng));
    if (i % 7 == 0) {
      // A parallelogram and its reverse: coplanar, both orientations.
      const glm::dvec3 quad[] = {a, b, b + d - a, d};
      const glm::dvec3 back[] = {d, b + d - a, b, a};
      addFace(s, quad, 0, "soup");
      addFace(s, back, 0, "soup");
    } else {
      const glm::dvec3 tri[] = {a, b, d};
      addFace(s, tri, 0, "soup");
    }
  }
  return s;
}

struct MethodSetup {
  std::string label;
  BackfaceMethod method;
  BackfaceOptions options;
};

std::vector<MethodSetup> methodSetups() {
  std::vector<MethodSetup> out;
  out.push_back({"polygon", BackfaceMethod::kPolygon, {}});
  out.push_back({"mask", BackfaceMethod::kMask, {}});
  BackfaceOptions grouped;
  grouped.mask_group_size = 64;
  grouped.mask_resolution = 8;
  out.push_back({"mask/groups64/N8", BackfaceMethod::kMask, grouped});
  out.push_back({"cluster", BackfaceMethod::kCluster, {}});
  BackfaceOptions flat;
  flat.cluster_hierarchy = false;
  flat.cluster_tr = 4.0;
  out.push_back({"cluster/flat/TR4", BackfaceMethod::kCluster, flat});
  out.push_back({"cone", BackfaceMethod::kCone, {}});
  return out;
}

glm::dvec3 randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  glm::dvec3 v(g(rng), g(rng), g(rng));
  return glm::normalize(v);
}

// Eyes: a third inside the bounding box, a third near (1–3 radii from the centre), a sixth far
// (3–30 radii), a sixth within 1e-12..1e-2 of a polygon's plane on either side (where the
// floating point decides).
glm::dvec3 randomEye(const Scene& s, std::mt19937_64& rng, const glm::dvec3& center, double radius) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double pick = u(rng);
  if (pick < 1.0 / 3.0) return center + radius * glm::dvec3(2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1);
  if (pick < 2.0 / 3.0) return center + radius * (1.0 + 2.0 * u(rng)) * randomUnit(rng);
  if (pick < 5.0 / 6.0) return center + radius * (3.0 + 27.0 * u(rng)) * randomUnit(rng);
  const Polygon& p = s.polygons[static_cast<size_t>(u(rng) * static_cast<double>(s.polygons.size())) % s.polygons.size()];
  glm::dvec3 c(0.0);
  for (const auto& v : s.polygonVertices(p)) c += v;
  c /= static_cast<double>(p.vertex_count);
  const double offset = std::pow(10.0, -12.0 + 10.0 * u(rng)) * (u(rng) < 0.5 ? -1.0 : 1.0);
  return c + offset * radius * p.plane.n;
}

void expectConservative(const Scene& s, uint64_t seed) {
  ASSERT_FALSE(s.polygons.empty());
  const Bounds b = sceneBounds(s);
  const glm::dvec3 center = 0.5 * (b.lo + b.hi);
  const double radius = 0.5 * glm::length(b.hi - b.lo);
  for (const MethodSetup& setup : methodSetups()) {
    SCOPED_TRACE(s.name + " " + setup.label);
    const auto culler = makeBackfaceCuller(setup.method, backfaceInput(s), setup.options);
    ASSERT_EQ(culler->polygonCount(), s.polygons.size());
    std::vector<uint8_t> units(culler->unitCount()), culled(s.polygons.size());
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    uint64_t false_culls = 0, culled_total = 0, back_total = 0;
    for (int e = 0; e < kEyes; ++e) {
      BackfaceView view;
      view.eye = randomEye(s, rng, center, radius);
      view.view_dir = randomUnit(rng);
      view.fov = (20.0 + 130.0 * u(rng)) * M_PI / 180.0;
      culler->cull(view, units);
      expandToPolygons(*culler, units, culled);
      for (size_t p = 0; p < s.polygons.size(); ++p) {
        const bool front = isFrontFacing(s.polygons[p].plane, view.eye);
        false_culls += culled[p] && front;
        culled_total += culled[p];
        back_total += !front;
      }
    }
    EXPECT_EQ(false_culls, 0u);
    EXPECT_LE(culled_total, back_total);
    if (setup.method == BackfaceMethod::kPolygon) {
      EXPECT_EQ(culled_total, back_total);
    }
  }
}

// Every method culls something for far eyes, and the baseline culls exactly the back faces.
// The peer (cone) may cull nothing: meshlets of random triangles have no useful normal cone.
void expectEffectiveFarAway(const Scene& s, bool cone_may_cull_nothing = false) {
  const Bounds b = sceneBounds(s);
  const glm::dvec3 center = 0.5 * (b.lo + b.hi);
  const double radius = 0.5 * glm::length(b.hi - b.lo);
  for (const MethodSetup& setup : methodSetups()) {
    SCOPED_TRACE(s.name + " " + setup.label);
    const auto culler = makeBackfaceCuller(setup.method, backfaceInput(s), setup.options);
    std::vector<uint8_t> units(culler->unitCount()), culled(s.polygons.size());
    std::mt19937_64 rng(7);
    uint64_t culled_total = 0, back_total = 0;
    for (int e = 0; e < 200; ++e) {
      BackfaceView view;
      view.eye = center + 10.0 * radius * randomUnit(rng);
      view.view_dir = center - view.eye;
      view.fov = 0.5;
      culler->cull(view, units);
      expandToPolygons(*culler, units, culled);
      for (size_t p = 0; p < s.polygons.size(); ++p) {
        culled_total += culled[p];
        back_total += !isFrontFacing(s.polygons[p].plane, view.eye);
      }
    }
    const double effectiveness = static_cast<double>(culled_total) / static_cast<double>(back_total);
    testing::Test::RecordProperty(setup.label + "_effectiveness", std::to_string(effectiveness));
    if (!(cone_may_cull_nothing && setup.method == BackfaceMethod::kCone)) {
      EXPECT_GT(effectiveness, 0.0);
    }
    if (setup.method == BackfaceMethod::kPolygon) {
      EXPECT_EQ(effectiveness, 1.0);
    }
  }
}

TEST(Backface, SphereNoFrontFaceCulled) { expectConservative(loadScene("gen:sphere"), 11); }
TEST(Backface, DomeNoFrontFaceCulled) { expectConservative(loadScene("gen:dome"), 12); }
TEST(Backface, InwardDomeNoFrontFaceCulled) { expectConservative(loadScene("gen:dome?inside=1&tris=600"), 13); }
TEST(Backface, SoupNoFrontFaceCulled) { expectConservative(randomSoup(14, 400), 14); }

// Far from the origin with small features: the margins must scale with the coordinates.
TEST(Backface, FarFromOriginNoFrontFaceCulled) {
  Scene s = loadScene("gen:sphere?tris=500&radius=0.01");
  for (auto& v : s.vertices) v += glm::dvec3(1e6, -2e5, 3e5);
  for (auto& p : s.polygons) p.plane = newellPlane(s.polygonVertices(p));
  s.name = "sphere far from the origin";
  expectConservative(s, 15);
}

TEST(Backface, SphereCullsFromFarAway) { expectEffectiveFarAway(loadScene("gen:sphere")); }
TEST(Backface, DomeCullsFromFarAway) { expectEffectiveFarAway(loadScene("gen:dome")); }
TEST(Backface, SoupCullsFromFarAway) { expectEffectiveFarAway(randomSoup(16, 400), true); }

// The paper's §3.1 view cone is conservative for polygons inside the view cone.
TEST(Backface, MaskViewConeKeepsFrontFacesInsideTheCone) {
  const Scene s = loadScene("gen:sphere");
  BackfaceOptions options;
  options.mask_use_view_cone = true;
  const auto culler = makeBackfaceCuller(BackfaceMethod::kMask, backfaceInput(s), options);
  std::vector<uint8_t> units(culler->unitCount()), culled(s.polygons.size());
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  uint64_t checked = 0, false_culls = 0, culled_inside = 0;
  for (int e = 0; e < kEyes; ++e) {
    BackfaceView view;
    view.eye = (1.05 + 5.0 * u(rng)) * randomUnit(rng);
    view.view_dir = glm::normalize(-view.eye + 0.5 * randomUnit(rng));
    view.fov = (20.0 + 100.0 * u(rng)) * M_PI / 180.0;
    culler->cull(view, units);
    expandToPolygons(*culler, units, culled);
    const double cos_half = std::cos(0.5 * view.fov - 1e-9);
    for (size_t p = 0; p < s.polygons.size(); ++p) {
      bool inside = true;
      for (const auto& v : s.polygonVertices(p)) inside &= glm::dot(glm::normalize(v - view.eye), view.view_dir) > cos_half;
      if (!inside) continue;
      ++checked;
      culled_inside += culled[p];
      false_culls += culled[p] && isFrontFacing(s.polygons[p].plane, view.eye);
    }
  }
  EXPECT_GT(checked, 100000u);
  EXPECT_GT(culled_inside, 0u);
  EXPECT_EQ(false_culls, 0u);
}

TEST(Backface, NearFieldProbabilityMatchesMonteCarlo) {
  // One plane through the origin: half the box.
  EXPECT_NEAR(nearFieldCullProbability({0, 0, 1}, {0, 0, 1}, 0.0, 1.0), 0.5, 1e-12);
  EXPECT_NEAR(nearFieldCullProbability({0.6, 0, 0.8}, {0.6, 0, 0.8}, 0.0, 1.0), 0.5, 1e-12);
  EXPECT_NEAR(nearFieldCullProbability({0, 0, 1}, {0, 0, 1}, 2.0, 1.0), 1.0, 1e-12);
  std::mt19937_64 rng(18);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    glm::dvec3 n1 = randomUnit(rng), n2 = randomUnit(rng);
    n2 = glm::normalize(n1 + 0.5 * n2);
    const glm::dvec3 lo = glm::min(n1, n2), hi = glm::max(n1, n2);
    const double d = 0.5 * u(rng);
    int hits = 0;
    constexpr int kSamples = 40000;
    for (int k = 0; k < kSamples; ++k) {
      const glm::dvec3 e(u(rng), u(rng), u(rng));
      double lhs = -d;
      for (int c = 0; c < 3; ++c) lhs += (e[c] > 0.0 ? hi[c] : lo[c]) * e[c];
      hits += lhs <= 0.0;
    }
    EXPECT_NEAR(nearFieldCullProbability(lo, hi, d, 1.0), static_cast<double>(hits) / kSamples, 0.01) << trial;
  }
}

TEST(Backface, EmptyInputAndBadOptions) {
  const Scene empty;
  for (const MethodSetup& setup : methodSetups()) {
    const auto culler = makeBackfaceCuller(setup.method, backfaceInput(empty), setup.options);
    EXPECT_EQ(culler->polygonCount(), 0u);
    std::vector<uint8_t> units(culler->unitCount());
    culler->cull(BackfaceView{}, units);
  }
  const Scene s = loadScene("gen:sphere?tris=80");
  BackfaceOptions bad;
  bad.mask_resolution = 19;
  EXPECT_THROW(makeBackfaceCuller(BackfaceMethod::kMask, backfaceInput(s), bad), SceneError);
  bad = {};
  bad.cluster_tr = -1.0;
  EXPECT_THROW(makeBackfaceCuller(BackfaceMethod::kCluster, backfaceInput(s), bad), SceneError);
  EXPECT_THROW(parseBackfaceMethod("nope"), SceneError);
  EXPECT_EQ(parseBackfaceMethod("cluster"), BackfaceMethod::kCluster);
}

}  // namespace
}  // namespace walkvis
