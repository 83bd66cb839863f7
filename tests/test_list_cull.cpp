// Backface culling inside priority lists (backface/list_cull.h): for every method, cullRange keeps
// each range's order, returns the number it dropped, and never drops a front-facing polygon (mask
// with its default view cone: none that reaches into the view cone), over
// 10,000 random perspective eyes per mesh; ranges cut from random orders of meshes, from the BSP's
// back-to-front order (the BSP path, eyes anywhere) and from a PFD tree's runs built with
// drop_back_faces = false (eyes on its height plane, the runs its query yields).
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "backface/list_cull.h"
#include "backface/normal_mask.h"
#include "backface_test_util.h"
#include "bsp/bsp.h"
#include "pfd_hfd/pfd.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

using backface_test::Frame;
using backface_test::frameOf;
using backface_test::randomEye;
using backface_test::randomSoup;
using backface_test::randomUnit;

constexpr int kEyes = 10000;

struct CullSetup {
  std::string label;
  ListCullMethod method;
  BackfaceOptions options;
};

std::vector<CullSetup> cullSetups() {
  std::vector<CullSetup> out;
  for (ListCullMethod m : {ListCullMethod::kNone, ListCullMethod::kPolygon, ListCullMethod::kMask,
                           ListCullMethod::kCluster, ListCullMethod::kHierarchy, ListCullMethod::kRegion}) {
    out.push_back({std::string(listCullMethodName(m)), m, {}});
  }
  BackfaceOptions groups;
  groups.mask_cone = BackfaceOptions::MaskCone::kGroups;
  out.push_back({"mask/groups", ListCullMethod::kMask, groups});
  BackfaceOptions view_n8;
  view_n8.mask_resolution = 8;
  view_n8.mask_cone = BackfaceOptions::MaskCone::kView;
  out.push_back({"mask/view/N8", ListCullMethod::kMask, view_n8});
  BackfaceOptions tables = groups;
  tables.mask_list_min_chunk = 1;  // a table for every chunk, however small
  out.push_back({"mask/tables", ListCullMethod::kMask, tables});
  BackfaceOptions chunks = groups;
  chunks.mask_group_size = 16;
  chunks.mask_resolution = 8;
  chunks.mask_list_min_chunk = 1;
  out.push_back({"mask/chunks16/N8", ListCullMethod::kMask, chunks});
  BackfaceOptions mixed = groups;
  mixed.mask_group_size = 40;
  mixed.mask_list_min_chunk = 25;  // tables for full chunks, the plane test for most range tails
  out.push_back({"mask/chunks40/min25", ListCullMethod::kMask, mixed});
  BackfaceOptions tree;
  tree.cluster_hierarchy = true;
  out.push_back({"cluster/tree", ListCullMethod::kCluster, tree});
  BackfaceOptions flat;
  flat.cluster_hierarchy = false;
  flat.cluster_tr = 4.0;
  out.push_back({"cluster/flat/TR4", ListCullMethod::kCluster, flat});
  return out;
}

struct Counts {
  uint64_t false_culls = 0, culled = 0, back = 0, listed = 0;
  uint64_t culled_outside_view = 0;  // mask's view cone: front faces culled wholly outside the cone
};

bool viewConeMask(const CullSetup& setup) {
  return setup.method == ListCullMethod::kMask && setup.options.mask_cone != BackfaceOptions::MaskCone::kGroups;
}

// A front face that the view-cone mask may cull: its unit normal n̂ makes n̂·u > 0 for every
// direction u of the cone, i.e. n̂·a > sin θ (then its front half-space, where the polygon lies,
// misses the cone), checked in double; and, as a brute-force check beside that argument, none of
// its vertices and its centroid lies inside the cone.
bool outsideViewCone(const BackfaceInput& input, uint32_t p, const BackfaceView& view) {
  const Polygon& poly = input.polygons[p];
  const glm::dvec3 a = glm::normalize(view.view_dir);
  const double sin_half = std::sin(0.5 * view.fov), cos_half = std::cos(0.5 * view.fov);
  if (!(glm::dot(glm::normalize(poly.plane.n), a) > sin_half)) return false;
  glm::dvec3 centroid(0.0);
  for (uint32_t k = 0; k < poly.vertex_count; ++k) {
    const glm::dvec3& v = input.vertices[poly.first_vertex + k];
    centroid += v / static_cast<double>(poly.vertex_count);
    if (glm::dot(v - view.eye, a) > cos_half * glm::length(v - view.eye)) return false;
  }
  return !(glm::dot(centroid - view.eye, a) > cos_half * glm::length(centroid - view.eye));
}

// Checks `out` (after its first `base` entries) against the range: an in-order subsequence whose
// dropped entries are all back-facing (mask with the view cone: or wholly outside the view
// cone); polygon and region drop exactly the back faces, none drops nothing; `culled` = the
// number dropped.
void verify(const BackfaceInput& input, std::span<const uint32_t> range, const std::vector<uint32_t>& out, size_t base,
            uint32_t culled, const CullSetup& setup, const BackfaceView& view, Counts& counts) {
  ASSERT_EQ(out.size() - base + culled, range.size()) << setup.label;
  const glm::dvec3& eye = view.eye;
  size_t k = base;
  uint64_t back = 0;
  for (uint32_t p : range) {
    const bool front = isFrontFacing(input.polygons[p].plane, eye);
    back += !front;
    if (k < out.size() && out[k] == p) {
      ++k;
    } else {
      if (front && viewConeMask(setup) && outsideViewCone(input, p, view)) {
        ++counts.culled_outside_view;
      } else {
        counts.false_culls += front;
      }
      ++counts.culled;
    }
  }
  ASSERT_EQ(k, out.size()) << setup.label << ": the survivors are not an in-order subsequence of the range";
  counts.back += back;
  counts.listed += range.size();
  if (setup.method == ListCullMethod::kNone) {
    EXPECT_EQ(culled, 0u);
  }
  if (setup.method == ListCullMethod::kPolygon || setup.method == ListCullMethod::kRegion) {
    EXPECT_EQ(culled, back);
  }
}

// The polygons 0..n-1 in random order plus n / repeat_div repeats, cut into consecutive ranges of
// 0..count_mod-1 positions.
struct RandomLists {
  std::vector<uint32_t> indices;
  std::vector<IndexRange> ranges;
};
RandomLists randomLists(size_t n, uint32_t repeat_div, uint32_t count_mod, std::mt19937_64& rng) {
  RandomLists r;
  r.indices.resize(n);
  for (uint32_t i = 0; i < n; ++i) r.indices[i] = i;
  std::shuffle(r.indices.begin(), r.indices.end(), rng);
  for (uint32_t i = 0; i < n / repeat_div; ++i) r.indices.push_back(r.indices[rng() % n]);
  for (uint32_t at = 0; at < r.indices.size();) {
    const uint32_t count = std::min<uint32_t>(static_cast<uint32_t>(rng() % count_mod), static_cast<uint32_t>(r.indices.size()) - at);
    r.ranges.push_back({at, count});
    at += count;
  }
  return r;
}

// Random order of the polygons (some repeated), cut into ranges of 0..3·mean polygons, plus the
// whole array and one range overlapping two others. Per eye a few random ranges are culled.
void expectNoFrontFaceCulled(const Scene& s, uint64_t seed, uint32_t mean) {
  const BackfaceInput input = backfaceInput(s);
  std::mt19937_64 rng(seed);
  auto [indices, ranges] = randomLists(s.polygons.size(), 10, 3 * mean + 1, rng);
  ranges.push_back({0, static_cast<uint32_t>(indices.size())});
  ranges.push_back({static_cast<uint32_t>(indices.size() / 3), static_cast<uint32_t>(indices.size() / 3)});
  const Frame f = frameOf(s);
  for (const CullSetup& setup : cullSetups()) {
    SCOPED_TRACE(s.name + " " + setup.label);
    // Eyes around a mesh, not inside a building: tell cluster where most of them are (its default
    // box of the mesh itself would let it merge an inward dome into clusters no eye culls).
    BackfaceOptions options = setup.options;
    options.cluster_eye_lo = f.center - glm::dvec3(3.0 * f.radius);
    options.cluster_eye_hi = f.center + glm::dvec3(3.0 * f.radius);
    const ListCuller culler = ListCuller::build(input, indices, ranges, setup.method, options);
    ASSERT_EQ(culler.rangeCount(), ranges.size());
    std::mt19937_64 eye_rng(seed + 1);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<uint32_t> out;
    out.reserve(indices.size() + 1);
    Counts counts;
    for (int e = 0; e < kEyes; ++e) {
      BackfaceView view;
      view.eye = randomEye(s, eye_rng, f);
      view.view_dir = randomUnit(eye_rng);
      view.fov = (20.0 + 130.0 * u(eye_rng)) * M_PI / 180.0;
      for (int k = 0; k < 3; ++k) {
        // Every 100th eye the whole array, otherwise random ranges.
        const uint32_t r = k == 0 && e % 100 == 0 ? static_cast<uint32_t>(ranges.size() - 2)
                                                  : static_cast<uint32_t>(eye_rng() % ranges.size());
        out.assign(1, 0xDEADBEEFu);  // cullRange appends: what is there stays
        const uint32_t culled = culler.cullRange(r, view, out);
        ASSERT_EQ(out[0], 0xDEADBEEFu);
        verify(input, std::span<const uint32_t>(indices).subspan(ranges[r].first, ranges[r].count), out, 1, culled,
               setup, view, counts);
      }
    }
    EXPECT_EQ(counts.false_culls, 0u);
    if (setup.method != ListCullMethod::kNone) {
      EXPECT_GT(counts.culled, 0u);
    }
    if (viewConeMask(setup)) {
      testing::Test::RecordProperty(setup.label + "_culled_outside_view", std::to_string(counts.culled_outside_view));
    }
    testing::Test::RecordProperty(setup.label + "_effectiveness",
                   std::to_string(static_cast<double>(counts.culled) / static_cast<double>(std::max<uint64_t>(counts.back, 1))));
  }
}

TEST(ListCull, SphereNoFrontFaceCulled) { expectNoFrontFaceCulled(loadScene("gen:sphere?tris=1200"), 41, 60); }
TEST(ListCull, DomeNoFrontFaceCulled) { expectNoFrontFaceCulled(loadScene("gen:dome?tris=800"), 42, 40); }
TEST(ListCull, InwardDomeNoFrontFaceCulled) { expectNoFrontFaceCulled(loadScene("gen:dome?inside=1&tris=600"), 43, 30); }
TEST(ListCull, SoupNoFrontFaceCulled) { expectNoFrontFaceCulled(randomSoup(44, 300), 44, 20); }
TEST(ListCull, FarFromOriginNoFrontFaceCulled) { expectNoFrontFaceCulled(backface_test::farFromOriginSphere(), 45, 30); }

// A building: a floor, walls of both facings (some sharing planes), a ramp, boxes.
Scene building(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(0.0, 20.0);
  std::uniform_int_distribution<int> grid(0, 20);
  Scene scene;
  scene.name = "building-" + std::to_string(seed);
  scene.eye_height = 1.5;
  auto quad = [&](glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d) {
    const glm::dvec3 v[4] = {a, b, c, d};
    addFace(scene, v, 0x808080, scene.name);
  };
  quad({0, 0, 0}, {0, 0, 20}, {20, 0, 20}, {20, 0, 0});
  for (int i = 0; i < 24; ++i) {
    glm::dvec2 p, q;
    if (i % 2 == 0) {
      p = {grid(rng), grid(rng)};
      q = (rng() & 1) ? glm::dvec2{p.x, static_cast<double>(grid(rng))} : glm::dvec2{static_cast<double>(grid(rng)), p.y};
    } else {
      p = {coord(rng), coord(rng)};
      q = {coord(rng), coord(rng)};
    }
    if (p == q) continue;
    const double top = 2.0 + static_cast<double>(rng() % 3);
    quad({p.x, 0, p.y}, {q.x, 0, q.y}, {q.x, top, q.y}, {p.x, top, p.y});
    if (i % 3 == 0) quad({p.x, top, p.y}, {q.x, top, q.y}, {q.x, 0, q.y}, {p.x, 0, p.y});  // the other side too
  }
  quad({2, 0, 2}, {2, 0, 5}, {6, 1.5, 5}, {6, 1.5, 2});
  FloorLevel level;
  level.walkable = {{{0, 0}, {20, 0}, {20, 20}, {0, 20}}};
  level.walkable_area = 400.0;
  scene.levels.push_back(level);
  return scene;
}

// The BSP path: the back-to-front order of all fragments cut into ranges; eyes anywhere (off the
// height plane, inside and outside the building).
TEST(ListCull, BspOrderRangesNoFrontFaceCulled) {
  const Scene scene = building(51);
  const BspTree bsp = buildBsp(scene);
  const BackfaceInput input{bsp.vertices, bsp.fragments};
  std::vector<uint32_t> order;
  backToFront(bsp, glm::dvec3(10.0, 1.5, 10.0), order, false);
  ASSERT_EQ(order.size(), bsp.fragments.size());
  std::vector<IndexRange> ranges;
  for (uint32_t at = 0; at < order.size(); at += 7) ranges.push_back({at, std::min<uint32_t>(7, static_cast<uint32_t>(order.size()) - at)});
  ranges.push_back({0, static_cast<uint32_t>(order.size())});
  std::mt19937_64 rng(52);
  std::uniform_real_distribution<double> u(-5.0, 25.0);
  for (const CullSetup& setup : cullSetups()) {
    SCOPED_TRACE(setup.label);
    const ListCuller culler = ListCuller::build(input, order, ranges, setup.method, setup.options);
    std::vector<uint32_t> out;
    out.reserve(order.size());
    Counts counts;
    for (int e = 0; e < kEyes; ++e) {
      BackfaceView view;
      view.eye = glm::dvec3(u(rng), 0.3 * u(rng), u(rng));
      view.view_dir = randomUnit(rng);
      view.fov = (30.0 + 4.0 * (u(rng) + 5.0)) * M_PI / 180.0;  // 30..150 degrees
      const uint32_t r = e % 50 == 0 ? static_cast<uint32_t>(ranges.size() - 1) : static_cast<uint32_t>(rng() % (ranges.size() - 1));
      out.clear();
      const uint32_t culled = culler.cullRange(r, view, out);
      verify(input, std::span<const uint32_t>(order).subspan(ranges[r].first, ranges[r].count), out, 0, culled, setup,
             view, counts);
    }
    EXPECT_EQ(counts.false_culls, 0u);
    if (setup.method != ListCullMethod::kNone) {
      EXPECT_GT(counts.culled, 0u);
    }
  }
}

// The PFD path: a tree built with drop_back_faces = false; its runs are the ranges; eyes on the
// height plane; per eye the runs pfdQueryRuns yields are culled in order.
TEST(ListCull, PfdRunsNoFrontFaceCulled) {
  const Scene scene = building(61);
  const BspTree bsp = buildBsp(scene);
  PfdOptions options;
  options.drop_back_faces = false;
  options.stat_eyes = 0;
  const FloorLevel& level = scene.levels[0];
  const double height = level.floor_y + scene.eye_height;
  const PfdTree tree = buildPfd(bsp, level.walkable, height, std::nullopt, options);
  ASSERT_FALSE(tree.runs.empty());
  std::vector<IndexRange> ranges;
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> run_index;
  for (const PfdRun& run : tree.runs) {
    run_index.emplace(std::make_pair(run.first, run.count), static_cast<uint32_t>(ranges.size()));
    ranges.push_back({run.first, run.count});
  }
  const BackfaceInput input{bsp.vertices, bsp.fragments};
  uint64_t listed_back = 0;
  for (const CullSetup& setup : cullSetups()) {
    SCOPED_TRACE(setup.label);
    const ListCuller culler = ListCuller::build(input, tree.fragment_ids, ranges, setup.method, setup.options);
    uint64_t rng_state = 62;
    std::vector<PfdRun> runs;
    std::vector<uint32_t> out;
    out.reserve(tree.fragment_ids.size());
    Counts counts;
    for (int e = 0; e < kEyes; ++e) {
      const glm::dvec2 p = samplePfdRegion(tree, rng_state);
      BackfaceView view;
      view.eye = glm::dvec3(p.x, height, p.y);
      const double yaw = 2.0 * M_PI * static_cast<double>(rng_state % 4096) / 4096.0;
      view.view_dir = glm::dvec3(std::cos(yaw), 0.0, std::sin(yaw));
      pfdQueryRuns(tree, view.eye, runs);
      for (const PfdRun& run : runs) {
        const auto it = run_index.find({run.first, run.count});
        ASSERT_NE(it, run_index.end());
        const size_t base = out.size();
        const uint32_t culled = culler.cullRange(it->second, view, out);
        verify(input, std::span<const uint32_t>(tree.fragment_ids).subspan(run.first, run.count), out, base, culled,
               setup, view, counts);
      }
      out.clear();
    }
    EXPECT_EQ(counts.false_culls, 0u);
    // An eye inside the building is inside every group's sphere: the group masks cull nothing.
    if (setup.method != ListCullMethod::kNone && (setup.method != ListCullMethod::kMask || viewConeMask(setup))) {
      EXPECT_GT(counts.culled, 0u);
    }
    listed_back = counts.back;
  }
  // With drop_back_faces = false the lists hold back faces for the run-time methods to cull.
  RecordProperty("listed_back_faces", std::to_string(listed_back));
  // Until PfdOptions::drop_back_faces = false is implemented the lists hold front faces only and
  // the culling above had nothing to cull: say so rather than pass silently.
  if (listed_back == 0) GTEST_SKIP() << "PfdOptions::drop_back_faces = false lists no back face (not implemented yet?)";
}

// gen:office in z-buffer mode (one range of all fragments, eyes inside at eye height): clustered
// by the probability over the scene's box, the clustered test culls a real share of what the plane
// test culls (with the paper's box around each cluster it culled nothing: one cluster per wall
// orientation); the mask of one group culls nothing (the eye is inside its sphere: inherent), the
// mask from the view cone culls (the default in lists).
TEST(ListCull, OfficeEyesInsideClusterCulls) {
  const Scene scene = loadScene("gen:office");
  const BspTree bsp = buildBsp(scene);
  const BackfaceInput input{bsp.vertices, bsp.fragments};
  std::vector<uint32_t> all(bsp.fragments.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  const IndexRange range{0, static_cast<uint32_t>(all.size())};
  const Bounds b = sceneBounds(scene);
  const double height = scene.levels.at(0).floor_y + scene.eye_height;
  std::mt19937_64 rng(81);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> eyes;
  for (int e = 0; e < 200; ++e) {
    eyes.emplace_back(b.lo.x + u(rng) * (b.hi.x - b.lo.x), height, b.lo.z + u(rng) * (b.hi.z - b.lo.z));
  }
  auto culledPerEye = [&](ListCullMethod method, const BackfaceOptions& options) {
    Counts counts;
    const ListCuller culler = ListCuller::build(input, all, std::span<const IndexRange>(&range, 1), method, options);
    std::vector<uint32_t> out;
    const CullSetup setup{"office", method, options};
    for (const glm::dvec3& eye : eyes) {
      out.clear();
      BackfaceView view;
      view.eye = eye;
      const double yaw = 2.0 * M_PI * u(rng);
      view.view_dir = glm::dvec3(std::cos(yaw), 0.0, std::sin(yaw));
      const uint32_t culled = culler.cullRange(0, view, out);
      verify(input, all, out, 0, culled, setup, view, counts);
    }
    EXPECT_EQ(counts.false_culls, 0u);
    return static_cast<double>(counts.culled) / static_cast<double>(eyes.size());
  };
  const double plane = culledPerEye(ListCullMethod::kPolygon, {});
  const double cluster = culledPerEye(ListCullMethod::kCluster, {});
  RecordProperty("polygon_culled_per_eye", std::to_string(plane));
  RecordProperty("cluster_culled_per_eye", std::to_string(cluster));
  EXPECT_GT(plane, 100.0);
  EXPECT_GT(cluster, 0.25 * plane);
  BackfaceOptions groups;
  groups.mask_cone = BackfaceOptions::MaskCone::kGroups;
  EXPECT_EQ(culledPerEye(ListCullMethod::kMask, groups), 0.0);
  const double mask = culledPerEye(ListCullMethod::kMask, {});
  RecordProperty("mask_culled_per_eye", std::to_string(mask));
  EXPECT_GT(mask, 0.1 * plane);
}


// cullRanges (all runs of a query in one call) equals cullRange over the same ids one by one,
// concatenated after what `out` held, for every method and SIMD path, random eyes, calls of
// 0..40 ids drawn with repeats from ranges that include empty ones (the plane-table path for
// calls listing many positions, the direct test for few); polygon and region keep exactly the
// front faces.
void expectBatchEqualsSingles(const Scene& s, uint64_t seed) {
  SCOPED_TRACE(s.name);
  const BackfaceInput input = backfaceInput(s);
  std::mt19937_64 rng(seed);
  auto [indices, ranges] = randomLists(s.polygons.size(), 4, 40, rng);  // count 0 now and then: empty ranges
  ranges.push_back({static_cast<uint32_t>(indices.size()), 0});
  const Frame f = frameOf(s);
  std::vector<CullSetup> setups = cullSetups();
  for (BackfaceSimd simd : {BackfaceSimd::kScalar, BackfaceSimd::kAvx2}) {
    for (ListCullMethod m : {ListCullMethod::kPolygon, ListCullMethod::kMask}) {
      BackfaceOptions o;
      o.simd = simd;
      setups.push_back({std::string(listCullMethodName(m)) + (simd == BackfaceSimd::kScalar ? "/scalar" : "/avx2"), m, o});
    }
  }
  for (const CullSetup& setup : setups) {
    SCOPED_TRACE(setup.label);
    // Two cullers built alike: hierarchy tracks the eye from call to call, so each sees the same calls.
    const ListCuller batch = ListCuller::build(input, indices, ranges, setup.method, setup.options);
    const ListCuller single = ListCuller::build(input, indices, ranges, setup.method, setup.options);
    std::vector<uint32_t> got, want, ids;
    for (int e = 0; e < 300; ++e) {
      BackfaceView view;
      view.eye = randomEye(s, rng, f);
      ids.clear();
      const uint32_t calls = e % 10 == 0 ? static_cast<uint32_t>(ranges.size()) : static_cast<uint32_t>(rng() % 41);
      for (uint32_t k = 0; k < calls; ++k) ids.push_back(e % 10 == 0 ? k : static_cast<uint32_t>(rng() % ranges.size()));
      const std::vector<uint32_t> prefix{7u, 9u};  // appended after what out holds
      got = prefix;
      want = prefix;
      const uint32_t got_culled = batch.cullRanges(ids, view, got);
      uint32_t want_culled = 0;
      for (uint32_t r : ids) want_culled += single.cullRange(r, view, want);
      ASSERT_EQ(got, want) << "eye " << e;
      ASSERT_EQ(got_culled, want_culled) << "eye " << e;
      if (setup.method == ListCullMethod::kPolygon || setup.method == ListCullMethod::kRegion) {
        std::vector<uint32_t> front = prefix;
        for (uint32_t r : ids) {
          for (uint32_t k = 0; k < ranges[r].count; ++k) {
            const uint32_t p = indices[ranges[r].first + k];
            if (isFrontFacing(input.polygons[p].plane, view.eye)) front.push_back(p);
          }
        }
        ASSERT_EQ(got, front) << "eye " << e;
      }
    }
    std::vector<uint32_t> out{1u};
    const uint32_t bad = static_cast<uint32_t>(ranges.size());
    const std::vector<uint32_t> bad_ids{0u, bad};
    EXPECT_THROW(batch.cullRanges(bad_ids, BackfaceView{}, out), Error);
    EXPECT_EQ(out, std::vector<uint32_t>{1u});  // unchanged
  }
}

TEST(ListCull, CullRangesEqualsCullRangeSphere) { expectBatchEqualsSingles(loadScene("gen:sphere?tris=600"), 61); }
TEST(ListCull, CullRangesEqualsCullRangeSoup) { expectBatchEqualsSingles(randomSoup(62, 200), 62); }
TEST(ListCull, CullRangesEqualsCullRangeBuilding) { expectBatchEqualsSingles(building(63), 63); }

// The view-cone mask's paths (AVX-512 VBMI byte permutes where the CPU has them, else scalar; byte
// codes up to 256 clusters, two-byte codes beyond) give the same survivors, and the mask culls
// exactly the positions whose cluster's four corners lie in the view cone's cap: a reference
// computed here from the grid per position, on a building (few clusters) and a sphere at N = 16
// (more than 256 clusters), random eyes, directions and fields of view including degenerate ones.
TEST(ListCull, MaskViewPathsAgreeWithTheGrid) {
  for (const Scene& s : {building(91), loadScene("gen:sphere?tris=6000")}) {
    SCOPED_TRACE(s.name);
    const BackfaceInput input = backfaceInput(s);
    std::mt19937_64 rng(92);
    auto [indices, ranges] = randomLists(s.polygons.size(), 4, 60, rng);
    std::vector<uint32_t> all_ids(ranges.size());
    for (uint32_t r = 0; r < all_ids.size(); ++r) all_ids[r] = r;
    BackfaceOptions fast, scalar;
    fast.mask_resolution = scalar.mask_resolution = 16;
    scalar.simd = BackfaceSimd::kScalar;
    const ListCuller a = ListCuller::build(input, indices, ranges, ListCullMethod::kMask, fast);
    const ListCuller b = ListCuller::build(input, indices, ranges, ListCullMethod::kMask, scalar);
    // Byte codes on the building (a few dozen clusters), two-byte codes on the sphere (> 256):
    // bytes() is a code per position plus 48 bytes of corners per cluster (rounded up to 16).
    if (s.name.rfind("building", 0) == 0) {
      EXPECT_LE(a.bytes(), indices.size() + 48 * 256) << a.bytes();
    } else {
      EXPECT_GE(a.bytes(), 2 * indices.size() + 48 * 257) << a.bytes();
    }
    const NormalMaskGrid grid(16);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const Frame f = frameOf(s);
    uint64_t culled = 0;
    std::vector<uint32_t> got_a, got_b, want;
    for (int e = 0; e < 400; ++e) {
      BackfaceView view;
      view.eye = randomEye(s, rng, f);
      view.view_dir = e % 50 == 0 ? glm::dvec3(0.0) : (0.5 + 2.0 * u(rng)) * randomUnit(rng);
      view.fov = e % 50 == 1 ? M_PI : (5.0 + 170.0 * u(rng)) * M_PI / 180.0;
      got_a.assign(1, 5u);
      got_b.assign(1, 5u);
      const uint32_t ca = a.cullRanges(all_ids, view, got_a);
      const uint32_t cb = b.cullRanges(all_ids, view, got_b);
      ASSERT_EQ(got_a, got_b) << "eye " << e;
      ASSERT_EQ(ca, cb);
      want.assign(1, 5u);
      const bool usable = glm::length(view.view_dir) > 0.0 && view.fov < M_PI;
      const glm::vec3 axis = usable ? glm::vec3(glm::normalize(view.view_dir)) : glm::vec3(0.0f);
      const float lim = static_cast<float>(std::sin(0.5 * view.fov) + kMaskCapMargin);
      for (const IndexRange& r : ranges) {
        for (uint32_t k = 0; k < r.count; ++k) {
          const uint32_t p = indices[r.first + k];
          bool back = usable;
          for (const glm::vec3& c : grid.cellCorners(grid.cell(input.polygons[p].plane.n))) {
            back = back && (c.x * axis.x + c.y * axis.y) + c.z * axis.z > lim;
          }
          if (!back) want.push_back(p);
        }
      }
      ASSERT_EQ(got_a, want) << "eye " << e;
      culled += ca;
    }
    EXPECT_GT(culled, 0u);
  }
}

// The shared-plane table (each distinct plane tested once per call, SIMD) and the direct test
// against isFrontFacing() on hard cases: eyes a few ulps either side of a plane, exactly on it,
// and planes and eyes at huge coordinates (1e12); every SIMD path; a call listing all positions
// (the table) and one listing a single polygon (direct).
TEST(ListCull, PlaneTableExactOnHardCases) {
  std::mt19937_64 rng(71);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double scale : {1.0, 1e12}) {
    SCOPED_TRACE(scale);
    Scene s;
    s.name = "hard";
    // 60 random triangles, each with a copy moved within its plane (Newell's plane of the copy
    // may differ in the last bits: shared or near-shared planes).
    for (int i = 0; i < 60; ++i) {
      const glm::dvec3 c = scale * glm::dvec3(u(rng), u(rng), u(rng));
      const glm::dvec3 a = glm::normalize(glm::dvec3(u(rng), u(rng), u(rng)));
      const glm::dvec3 b = glm::normalize(glm::cross(a, glm::dvec3(u(rng), u(rng), u(rng))));
      for (int copy = 0; copy < 2; ++copy) {
        const glm::dvec3 o = c + static_cast<double>(copy) * 0.25 * a;
        const glm::dvec3 v[3] = {o, o + a, o + b};
        addFace(s, v, 0x808080, "hard");
      }
    }
    const BackfaceInput input = backfaceInput(s);
    std::vector<uint32_t> indices(s.polygons.size());
    for (uint32_t i = 0; i < indices.size(); ++i) indices[i] = i;
    const std::vector<IndexRange> ranges{{0, static_cast<uint32_t>(indices.size())}, {5, 1}};
    for (BackfaceSimd simd : {BackfaceSimd::kScalar, BackfaceSimd::kAvx2, BackfaceSimd::kAuto}) {
      BackfaceOptions o;
      o.simd = simd;
      const ListCuller culler = ListCuller::build(input, indices, ranges, ListCullMethod::kPolygon, o);
      std::vector<uint32_t> out;
      uint64_t near_front = 0, near_back = 0;
      for (size_t p = 0; p < s.polygons.size(); ++p) {
        const Plane& plane = s.polygons[p].plane;
        const glm::dvec3 on = s.vertices[s.polygons[p].first_vertex];
        for (int step = -4; step <= 4; ++step) {
          // A point of the polygon moved a few ulps of its coordinates along the normal.
          glm::dvec3 eye = on;
          for (int k = 0; k < 3; ++k) {
            double x = eye[k];
            const double toward = plane.n[k] * static_cast<double>(step) > 0 ? INFINITY : -INFINITY;
            for (int t = 0; t < std::abs(step); ++t) x = std::nextafter(x, toward);
            eye[k] = x;
          }
          BackfaceView view;
          view.eye = eye;
          for (uint32_t r : {0u, 1u}) {
            out.clear();
            culler.cullRange(r, view, out);
            std::vector<uint32_t> want;
            for (uint32_t k = 0; k < ranges[r].count; ++k) {
              const uint32_t q = indices[ranges[r].first + k];
              if (isFrontFacing(input.polygons[q].plane, eye)) want.push_back(q);
            }
            ASSERT_EQ(out, want) << "polygon " << p << " step " << step << " range " << r;
          }
          (isFrontFacing(plane, eye) ? near_front : near_back) += 1;
        }
      }
      EXPECT_GT(near_front, 0u);  // the cases do straddle the planes
      EXPECT_GT(near_back, 0u);
    }
  }
}

TEST(ListCull, BadInput) {
  const Scene s = loadScene("gen:sphere?tris=80");
  const BackfaceInput input = backfaceInput(s);
  const std::vector<uint32_t> indices{0, 1, 2};
  const std::vector<IndexRange> ok{{0, 3}, {3, 0}};
  const std::vector<IndexRange> outside{{2, 2}};
  EXPECT_THROW(ListCuller::build(input, indices, outside, ListCullMethod::kPolygon), Error);
  const std::vector<uint32_t> bad_index{0, static_cast<uint32_t>(s.polygons.size())};
  EXPECT_THROW(ListCuller::build(input, bad_index, ok, ListCullMethod::kPolygon), Error);
  BackfaceOptions bad_n;
  bad_n.mask_resolution = 19;
  EXPECT_THROW(ListCuller::build(input, indices, ok, ListCullMethod::kMask, bad_n), Error);
  EXPECT_THROW(parseListCullMethod("cone"), Error);
  EXPECT_EQ(parseListCullMethod("region"), ListCullMethod::kRegion);
  for (const CullSetup& setup : cullSetups()) {
    const ListCuller culler = ListCuller::build(input, indices, ok, setup.method, setup.options);
    std::vector<uint32_t> out;
    EXPECT_EQ(culler.cullRange(1, BackfaceView{}, out), 0u);
    EXPECT_TRUE(out.empty());
    EXPECT_THROW(culler.cullRange(2, BackfaceView{}, out), Error);
    const ListCuller empty = ListCuller::build(input, {}, {}, setup.method, setup.options);
    EXPECT_EQ(empty.rangeCount(), 0u);
  }
}

}  // namespace
}  // namespace walkvis
