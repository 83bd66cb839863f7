// Backface culling (backface/): no method ever culls a front-facing polygon (eye strictly in the
// front half-space, isFrontFacing), over 10,000 random perspective eyes per mesh; every method
// culls something from far away; the near-field probability integral of Johannsen & Carter.
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "backface/backface.h"
#include "backface/normal_mask.h"
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
  BackfaceOptions tree;
  tree.cluster_hierarchy = true;
  out.push_back({"cluster/tree", BackfaceMethod::kCluster, tree});
  BackfaceOptions flat;
  flat.cluster_hierarchy = false;
  flat.cluster_tr = 4.0;
  out.push_back({"cluster/flat/TR4", BackfaceMethod::kCluster, flat});
  out.push_back({"cone", BackfaceMethod::kCone, {}});
  return out;
}

void expectConservative(const Scene& s, uint64_t seed) {
  ASSERT_FALSE(s.polygons.empty());
  const Frame f = frameOf(s);
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
      view.eye = randomEye(s, rng, f);
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
TEST(Backface, FarFromOriginNoFrontFaceCulled) { expectConservative(backface_test::farFromOriginSphere(), 15); }

// The flat cluster pass evaluates in float relative to the model's centre: far from the world
// origin it still resolves a 0.01-radius sphere (in world floats its ulp there is 0.06).
TEST(Backface, ClusterFlatCullsFarFromOrigin) {
  const Scene s = backface_test::farFromOriginSphere();
  const Frame f = frameOf(s);
  const auto culler = makeBackfaceCuller(BackfaceMethod::kCluster, backfaceInput(s), {});
  std::vector<uint8_t> units(culler->unitCount()), culled(s.polygons.size());
  std::mt19937_64 rng(21);
  uint64_t culled_total = 0, back_total = 0, false_culls = 0;
  for (int e = 0; e < 200; ++e) {
    BackfaceView view;
    view.eye = f.center + 3.0 * f.radius * randomUnit(rng);
    culler->cull(view, units);
    expandToPolygons(*culler, units, culled);
    for (size_t p = 0; p < s.polygons.size(); ++p) {
      const bool front = isFrontFacing(s.polygons[p].plane, view.eye);
      culled_total += culled[p];
      back_total += !front;
      false_culls += culled[p] && front;
    }
  }
  EXPECT_EQ(false_culls, 0u);
  EXPECT_GT(static_cast<double>(culled_total), 0.5 * static_cast<double>(back_total));
}

TEST(Backface, SphereCullsFromFarAway) { expectEffectiveFarAway(loadScene("gen:sphere")); }
TEST(Backface, DomeCullsFromFarAway) { expectEffectiveFarAway(loadScene("gen:dome")); }
TEST(Backface, SoupCullsFromFarAway) { expectEffectiveFarAway(randomSoup(16, 400), true); }

// The peer's only "false culls" are zero-area polygons (points, segments: BSP fragments of Freedoom
// MAP01 are like that): meshoptimizer skips their triangles and trivially rejects a meshlet of only
// such, for every eye. coneInvisiblePolygons names exactly those; every cone cull of a front face
// is one of them, and the meshlets of the sphere's real triangles cull no front face.
TEST(Backface, ConeCullsFrontFacesOnlyOfZeroArea) {
  Scene s = loadScene("gen:sphere?tris=300");
  const size_t real = s.polygons.size();
  std::mt19937_64 rng(71);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int i = 0; i < 40; ++i) {
    const glm::dvec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    Polygon p;
    p.first_vertex = static_cast<uint32_t>(s.vertices.size());
    p.vertex_count = 3 + static_cast<uint32_t>(i % 2);
    // Even: a point; odd: a segment a-b-b-a. Any plane through a.
    for (uint32_t k = 0; k < p.vertex_count; ++k) s.vertices.push_back(i % 2 == 0 || k == 0 || k == 3 ? a : b);
    p.plane.n = randomUnit(rng);
    p.plane.d = glm::dot(p.plane.n, a);
    s.polygons.push_back(p);
  }
  const BackfaceInput input = backfaceInput(s);
  std::vector<uint8_t> invisible(s.polygons.size());
  coneInvisiblePolygons(input, invisible);
  for (size_t p = 0; p < s.polygons.size(); ++p) EXPECT_EQ(invisible[p], p >= real ? 1 : 0) << p;
  std::vector<uint8_t> too_short(1);
  EXPECT_THROW(coneInvisiblePolygons(input, too_short), Error);

  const auto culler = makeBackfaceCuller(BackfaceMethod::kCone, input);
  std::vector<uint8_t> units(culler->unitCount()), culled(s.polygons.size());
  const Frame f = frameOf(s);
  uint64_t visible_false = 0, invisible_false = 0;
  for (int e = 0; e < 2000; ++e) {
    const glm::dvec3 eye = randomEye(s, rng, f);
    culler->cull(BackfaceView{eye}, units);
    expandToPolygons(*culler, units, culled);
    for (size_t p = 0; p < s.polygons.size(); ++p) {
      const bool wrong = culled[p] && isFrontFacing(s.polygons[p].plane, eye);
      (invisible[p] ? invisible_false : visible_false) += wrong;
    }
  }
  EXPECT_EQ(visible_false, 0u);
  // The library's trivial reject: some zero-area polygon is culled while its plane faces the eye.
  EXPECT_GT(invisible_false, 0u);
}

// The paper's §3.1 view cone is conservative for polygons inside the view cone.
TEST(Backface, MaskViewConeKeepsFrontFacesInsideTheCone) {
  const Scene s = loadScene("gen:sphere");
  BackfaceOptions options;
  options.mask_cone = BackfaceOptions::MaskCone::kView;
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

// The probability over a fixed eye box (walkthroughs), boxes on both sides of b, straddling it,
// and flat (an eye height plane): against sampling, and equal to the paper's near field for the
// cube [-half, half]³.
TEST(Backface, BoxProbabilityMatchesMonteCarlo) {
  EXPECT_NEAR(boxCullProbability({0, 0, 1}, {0, 0, 1}, 0.0, {-1, -1, -1}, {1, 1, 1}), 0.5, 1e-12);
  EXPECT_NEAR(boxCullProbability({0, 0, 1}, {0, 0, 1}, 0.0, {-1, -1, 1}, {1, 1, 3}), 0.0, 1e-12);
  EXPECT_NEAR(boxCullProbability({1, 0, 0}, {1, 0, 0}, 0.0, {-3, 0, 0}, {1, 0, 2}), 0.75, 1e-12);  // flat in y
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 30; ++trial) {
    glm::dvec3 n1 = randomUnit(rng), n2 = randomUnit(rng);
    n2 = glm::normalize(n1 + 0.5 * n2);
    const glm::dvec3 nlo = glm::min(n1, n2), nhi = glm::max(n1, n2);
    const double d = 0.5 * u(rng);
    glm::dvec3 lo(u(rng), u(rng), u(rng)), hi(u(rng), u(rng), u(rng));
    const glm::dvec3 a = glm::min(lo, hi), b = glm::max(lo, hi);
    lo = a;
    hi = b;
    if (trial % 3 == 0) hi.y = lo.y;  // flat
    if (trial % 5 == 0) {
      lo = glm::dvec3(-0.7);
      hi = glm::dvec3(0.7);
      EXPECT_NEAR(boxCullProbability(nlo, nhi, d, lo, hi), nearFieldCullProbability(nlo, nhi, d, 0.7), 1e-9) << trial;
    }
    std::uniform_real_distribution<double> ux(lo.x, hi.x), uz(lo.z, hi.z);
    std::uniform_real_distribution<double> uy(lo.y, hi.y > lo.y ? hi.y : std::nextafter(lo.y, INFINITY));
    int hits = 0;
    constexpr int kSamples = 40000;
    for (int k = 0; k < kSamples; ++k) {
      const glm::dvec3 e(ux(rng), hi.y > lo.y ? uy(rng) : lo.y, uz(rng));
      double lhs = -d;
      for (int c = 0; c < 3; ++c) lhs += (e[c] > 0.0 ? nhi[c] : nlo[c]) * e[c];
      hits += lhs <= 0.0;
    }
    EXPECT_NEAR(boxCullProbability(nlo, nhi, d, lo, hi), static_cast<double>(hits) / kSamples, 0.01) << trial;
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
  EXPECT_THROW(makeBackfaceCuller(BackfaceMethod::kMask, backfaceInput(s), bad), Error);
  bad = {};
  bad.cluster_tr = -1.0;
  EXPECT_THROW(makeBackfaceCuller(BackfaceMethod::kCluster, backfaceInput(s), bad), Error);
  EXPECT_THROW(parseBackfaceMethod("nope"), Error);
  EXPECT_EQ(parseBackfaceMethod("cluster"), BackfaceMethod::kCluster);
}

}  // namespace
}  // namespace walkvis

namespace walkvis {
TEST(Backface, MaskResolutionFollowsThePolygonCount) {
  EXPECT_EQ(maskResolutionFor(10, 0), 4);
  EXPECT_EQ(maskResolutionFor(2000, 0), 8);
  EXPECT_EQ(maskResolutionFor(1882, 0), 7);
  EXPECT_EQ(maskResolutionFor(70000, 0), 16);
  EXPECT_EQ(maskResolutionFor(2000, 12), 12);
  int last = 0;
  for (size_t polygons = 0; polygons < 200000; polygons = polygons * 3 / 2 + 1) {
    const int n = maskResolutionFor(polygons, 0);
    EXPECT_GE(n, last);
    EXPECT_TRUE(n == 4 || 6.0 * n * n <= polygons / 5.0) << polygons;
    last = n;
  }
}
}  // namespace walkvis

namespace walkvis {
namespace {

// The flat cluster pass has scalar, SSE2 and AVX2 paths (a path the CPU lacks falls back to the
// widest it has): they must give the same flags, eye by eye, including eyes within 1e-12 of a
// plane where the float margin decides.
TEST(Backface, ClusterSimdPathsAgree) {
  for (const Scene& s : {loadScene("gen:sphere?tris=3000"), backface_test::randomSoup(31, 500),
                         backface_test::farFromOriginSphere()}) {
    SCOPED_TRACE(s.name);
    std::vector<std::unique_ptr<BackfaceCuller>> cullers;
    for (BackfaceSimd simd : {BackfaceSimd::kScalar, BackfaceSimd::kSse2, BackfaceSimd::kAvx2}) {
      BackfaceOptions options;
      options.simd = simd;
      cullers.push_back(makeBackfaceCuller(BackfaceMethod::kCluster, backfaceInput(s), options));
    }
    const size_t units = cullers[0]->unitCount();
    ASSERT_GT(units, 8u);
    for (const auto& c : cullers) ASSERT_EQ(c->unitCount(), units);
    const Frame f = frameOf(s);
    std::mt19937_64 rng(32);
    std::vector<std::vector<uint8_t>> flags(cullers.size(), std::vector<uint8_t>(units));
    uint64_t culled = 0;
    for (int e = 0; e < 2000; ++e) {
      BackfaceView view;
      view.eye = randomEye(s, rng, f);
      for (size_t k = 0; k < cullers.size(); ++k) cullers[k]->cull(view, flags[k]);
      ASSERT_EQ(flags[1], flags[0]) << "eye " << e;
      ASSERT_EQ(flags[2], flags[0]) << "eye " << e;
      for (uint8_t x : flags[0]) culled += x;
    }
    EXPECT_GT(culled, 0u);
  }
}

// Coplanar fragments of one wall merge at no loss of culling probability; parallel walls at other
// offsets do not. With the polygons interleaved (fragment 0 of every wall, then fragment 1, ...)
// the candidates of equal normal must still be taken nearest plane first, or the first other wall
// ends a cluster's growth (80 clusters of one quad each instead of one per wall).
TEST(Backface, CoplanarFragmentsShareACluster) {
  Scene s;
  s.name = "parallel walls";
  constexpr int kWalls = 10, kFragments = 8;
  for (int f = 0; f < kFragments; ++f) {
    for (int w = 0; w < kWalls; ++w) {
      const double x = w, z0 = f, z1 = f + 1.0;
      const glm::dvec3 quad[] = {{x, 0.0, z0}, {x, 1.0, z0}, {x, 1.0, z1}, {x, 0.0, z1}};
      addFace(s, quad, 0, "wall");
    }
  }
  BackfaceOptions options;
  const Bounds b = sceneBounds(s);
  options.cluster_eye_lo = b.lo - glm::dvec3(1.0);
  options.cluster_eye_hi = b.hi + glm::dvec3(1.0);
  const auto culler = makeBackfaceCuller(BackfaceMethod::kCluster, backfaceInput(s), options);
  EXPECT_EQ(culler->unitCount(), static_cast<size_t>(kWalls));
  for (size_t u = 0; u < culler->unitCount(); ++u) {
    const auto polys = culler->unitPolygons(u);
    for (uint32_t p : polys) EXPECT_EQ(s.polygons[p].plane.d, s.polygons[polys[0]].plane.d) << "unit " << u;
  }
}

TEST(Backface, ClusterTrFollowsThePolygonCount) {
  EXPECT_EQ(clusterTrFor(2000, 0.0), 1.0);
  EXPECT_EQ(clusterTrFor(4000, 0.0), 1.0);
  EXPECT_NEAR(clusterTrFor(16000, 0.0), 0.5, 1e-12);
  EXPECT_EQ(clusterTrFor(1000000, 0.0), 0.25);
  EXPECT_EQ(clusterTrFor(70000, 2.5), 2.5);
  EXPECT_THROW(clusterTrFor(100, -1.0), Error);
  EXPECT_THROW(clusterTrFor(100, NAN), Error);
  double last = 2.0;
  for (size_t n = 1; n < 10000000; n = n * 3 / 2 + 1) {
    const double tr = clusterTrFor(n, 0.0);
    EXPECT_LE(tr, last);
    last = tr;
  }
}

}  // namespace
}  // namespace walkvis
