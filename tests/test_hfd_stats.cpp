// Hidden-polygon rejection statistics (walkthrough/hfd_stats.h): a PFD tree misses nothing; a tree
// whose lists lose a fragment that is always seen is charged for it, pixel by pixel; an HFD tree
// rejects hidden fragments and, on a door scene, misses nothing at the default sampling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "bsp/bsp.h"
#include "pfd_hfd/pfd.h"
#include "pfd_hfd/visibility.h"
#include "scenes/scene.h"
#include "walkthrough/hfd_stats.h"

namespace walkvis {
namespace {

uint32_t addQuad(Scene& scene, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d, glm::dvec3 facing) {
  std::vector<glm::dvec3> v{a, b, c, d};
  if (glm::dot(newellPlane(v).n, facing) < 0.0) std::reverse(v.begin(), v.end());
  const uint32_t index = static_cast<uint32_t>(scene.polygons.size());
  addFace(scene, v, 0x808080, "test");
  return index;
}

// Two 10 x 10 rooms side by side (x in [0, 20]), 3 high, a 1-wide door between them; a ceiling.
Scene twoRooms(uint32_t& floor_polygon) {
  Scene s;
  const double top = 3.0;
  floor_polygon = addQuad(s, {0, 0, 0}, {20, 0, 0}, {20, 0, 10}, {0, 0, 10}, {0, 1, 0});
  addQuad(s, {0, top, 0}, {20, top, 0}, {20, top, 10}, {0, top, 10}, {0, -1, 0});
  addQuad(s, {0, 0, 0}, {0, 0, 10}, {0, top, 10}, {0, top, 0}, {1, 0, 0});
  addQuad(s, {20, 0, 0}, {20, 0, 10}, {20, top, 10}, {20, top, 0}, {-1, 0, 0});
  addQuad(s, {0, 0, 0}, {20, 0, 0}, {20, top, 0}, {0, top, 0}, {0, 0, 1});
  addQuad(s, {0, 0, 10}, {20, 0, 10}, {20, top, 10}, {0, top, 10}, {0, 0, -1});
  for (const glm::dvec3 facing : {glm::dvec3(-1, 0, 0), glm::dvec3(1, 0, 0)}) {
    addQuad(s, {10, 0, 0}, {10, 0, 4.5}, {10, top, 4.5}, {10, top, 0}, facing);
    addQuad(s, {10, 0, 5.5}, {10, 0, 10}, {10, top, 10}, {10, top, 5.5}, facing);
    addQuad(s, {10, 2.2, 4.5}, {10, 2.2, 5.5}, {10, top, 5.5}, {10, top, 4.5}, facing);
  }
  // Clutter in room B: boxes; the one in the corner next to the door wall is hidden from room A's
  // walkable part (x <= 9).
  for (double x : {10.5, 13.0, 16.0})
    for (double z : {0.5, 7.0}) {
      addQuad(s, {x, 0, z}, {x + 1, 0, z}, {x + 1, 1, z}, {x, 1, z}, {0, 0, -1});
      addQuad(s, {x, 0, z + 1}, {x + 1, 0, z + 1}, {x + 1, 1, z + 1}, {x, 1, z + 1}, {0, 0, 1});
      addQuad(s, {x, 0, z}, {x, 0, z + 1}, {x, 1, z + 1}, {x, 1, z}, {-1, 0, 0});
      addQuad(s, {x + 1, 0, z}, {x + 1, 0, z + 1}, {x + 1, 1, z + 1}, {x + 1, 1, z}, {1, 0, 0});
      addQuad(s, {x, 1, z}, {x + 1, 1, z}, {x + 1, 1, z + 1}, {x, 1, z + 1}, {0, 1, 0});
    }
  FloorLevel level;
  level.floor_y = 0.0;
  level.walkable = {{{0.2, 0.2}, {9, 0.2}, {9, 9.8}, {0.2, 9.8}}, {{11.7, 1.7}, {19.8, 1.7}, {19.8, 9.8}, {11.7, 9.8}}};
  level.walkable_area = 8.8 * 9.6 + 8.1 * 8.1;
  s.levels.push_back(level);
  s.eye_height = 1.5;
  return s;
}

TreeFile makeTree(const Scene& scene, const VisibilityScene* vis) {
  TreeFile file;
  file.bsp = buildBsp(scene);
  file.eye_height = scene.eye_height;
  file.kind = vis ? TreeKind::kHfd : TreeKind::kPfd;
  PfdLevelOptions options;
  options.tree.stat_eyes = 100;
  options.tree.visibility = vis;
  uint64_t used = 0;
  file.levels.push_back(buildPfdLevel(file.bsp, scene.levels[0], 0, scene.eye_height, options, used));
  return file;
}

TEST(HfdStats, PfdTreeMissesNothing) {
  uint32_t floor_polygon;
  const Scene scene = twoRooms(floor_polygon);
  const TreeFile file = makeTree(scene, nullptr);
  HfdStatsOptions opt;
  opt.views = 20;
  opt.res = 32;
  const HfdStats stats = computeHfdStats(file, opt);
  ASSERT_EQ(stats.eyes.size(), 20u);
  ASSERT_EQ(stats.levels.size(), 1u);
  EXPECT_EQ(stats.overall.missed_max, 0u);
  EXPECT_EQ(stats.overall.error_pixels, 0u);
  EXPECT_EQ(stats.overall.pixel_error_ratio, 0.0);
  EXPECT_EQ(stats.overall.pixels, 20u * 6 * 32 * 32);
  EXPECT_GE(stats.overall.overestimation, 1.0);
  EXPECT_EQ(stats.overall.missed_histogram[0], 20u);
  for (const HfdEyeStats& e : stats.eyes) {
    EXPECT_GE(e.listed, e.visible);
    EXPECT_GT(e.visible, 3u);  // floor, ceiling and walls at least
  }
  // Deterministic in the seed.
  const HfdStats again = computeHfdStats(file, opt);
  EXPECT_EQ(again.eyes[7].eye, stats.eyes[7].eye);
  EXPECT_EQ(again.overall.listed_mean, stats.overall.listed_mean);
}

TEST(HfdStats, ChargesAMissingFragment) {
  uint32_t floor_polygon;
  const Scene scene = twoRooms(floor_polygon);
  TreeFile file = makeTree(scene, nullptr);
  // Drop the floor from every list (point its ids at the ceiling's first fragment): every eye
  // looks straight down at it, so every eye misses it and the down face is mostly error.
  uint32_t other = 0;
  while (file.bsp.fragment_polygon[other] == floor_polygon) ++other;
  uint64_t replaced = 0;
  for (PfdTree& t : file.levels[0].cells)
    for (uint32_t& f : t.fragment_ids)
      if (file.bsp.fragment_polygon[f] == floor_polygon) f = other, ++replaced;
  ASSERT_GT(replaced, 0u);
  HfdStatsOptions opt;
  opt.views = 10;
  opt.res = 16;
  const HfdStats stats = computeHfdStats(file, opt);
  EXPECT_EQ(stats.overall.missed_histogram[0], 0u);
  EXPECT_GE(stats.overall.missed_mean, 1.0);
  EXPECT_DOUBLE_EQ(stats.overall.eyes_with_miss, 1.0);
  // The down face (1/6 of the pixels) sees floor at least in its middle half.
  EXPECT_GT(stats.overall.pixel_error_ratio, 1.0 / 24.0);
  EXPECT_LT(stats.overall.pixel_error_ratio, 1.0 / 3.0);
  for (const HfdEyeStats& e : stats.eyes) EXPECT_EQ(e.missed + std::min(e.listed, e.visible - e.missed), e.visible);
}

TEST(HfdStats, HfdTreeRejectsHiddenAndMissesLittle) {
  uint32_t floor_polygon;
  const Scene scene = twoRooms(floor_polygon);
  const BspTree bsp = buildBsp(scene);
  const VisibilityScene vis = VisibilityScene::build(bsp);
  const TreeFile hfd = makeTree(scene, &vis);
  if (hfd.levels[0].cells[0].stats.visibility_tests == 0)
    GTEST_SKIP() << "PfdOptions::visibility is not used by buildPfd yet";
  const TreeFile pfd = makeTree(scene, nullptr);
  HfdStatsOptions opt;
  opt.views = 30;
  opt.res = 64;
  const HfdStats h = computeHfdStats(hfd, opt);
  const HfdStats p = computeHfdStats(pfd, opt);
  uint64_t rejected = 0;
  for (const PfdTree& t : hfd.levels[0].cells) rejected += t.stats.hidden_rejected;
  EXPECT_GT(rejected, 0u);
  EXPECT_LT(h.overall.listed_mean, p.overall.listed_mean);
  EXPECT_GT(h.overall.rejection_ratio, p.overall.rejection_ratio);
  EXPECT_EQ(h.overall.missed_max, 0u);
  EXPECT_EQ(h.overall.pixel_error_ratio, 0.0);
}

// Eyes closer to a wall than any sensible near plane (5e-6 to 2e-5 units from the door wall of a
// 22.6-unit scene, away from the door), with room B dropped from every list as an HFD tree would
// drop it: the exact reference sees the wall, not room B behind it. With the near plane at 1e-6 of
// the extent (2.3e-5) it saw through the wall and charged the lists for room B.
TEST(HfdStats, EyeBesideAWallDoesNotSeeThroughIt) {
  uint32_t floor_polygon;
  Scene scene = twoRooms(floor_polygon);
  FloorLevel& level = scene.levels[0];
  level.walkable = {{{10 - 2e-5, 1.0}, {10 - 5e-6, 1.0}, {10 - 5e-6, 3.0}, {10 - 2e-5, 3.0}}};
  level.walkable_area = 1.5e-5 * 2.0;
  TreeFile file = makeTree(scene, nullptr);
  // A fragment wholly beyond the door wall (x >= 10, not in its plane) is room B's.
  const auto in_room_b = [&](uint32_t f) {
    const Polygon& p = file.bsp.fragments[f];
    bool beyond = false;
    for (uint32_t k = 0; k < p.vertex_count; ++k) {
      const double x = file.bsp.vertices[p.first_vertex + k].x;
      if (!(x >= 10.0)) return false;
      beyond = beyond || x > 10.0;
    }
    return beyond;
  };
  uint32_t other = 0;
  while (in_room_b(other)) ++other;
  uint64_t replaced = 0;
  for (PfdTree& t : file.levels[0].cells)
    for (uint32_t& f : t.fragment_ids)
      if (in_room_b(f)) f = other, ++replaced;
  ASSERT_GT(replaced, 10u);
  HfdStatsOptions opt;
  opt.views = 20;
  opt.res = 32;
  const HfdStats h = computeHfdStats(file, opt);
  ASSERT_EQ(h.eyes.size(), 20u);
  EXPECT_EQ(h.overall.missed_max, 0u);
  EXPECT_EQ(h.overall.error_pixels, 0u);
  for (const HfdEyeStats& e : h.eyes) EXPECT_GT(e.visible, 3u);
}

// Two levels of unequal area, the small one missing the floor at every eye: the overall share of
// eyes with a miss is the small level's share of the area, whether the eyes are split by area (the
// default: the counts follow the areas) or the same number per level (an unweighted mean would
// say one half).
TEST(HfdStats, OverallFiguresWeighEyesByArea) {
  uint32_t floor_polygon;
  Scene scene = twoRooms(floor_polygon);
  TreeFile file = makeTree(scene, nullptr);
  FloorLevel strip = scene.levels[0];
  strip.walkable = {{{0.2, 0.2}, {3.2, 0.2}, {3.2, 9.8}, {0.2, 9.8}}};
  strip.walkable_area = 3.0 * 9.6;
  PfdLevelOptions options;
  options.tree.stat_eyes = 100;
  uint64_t used = 0;
  file.levels.push_back(buildPfdLevel(file.bsp, strip, 1, scene.eye_height, options, used));
  uint32_t other = 0;
  while (file.bsp.fragment_polygon[other] == floor_polygon) ++other;
  for (PfdTree& t : file.levels[1].cells)
    for (uint32_t& f : t.fragment_ids)
      if (file.bsp.fragment_polygon[f] == floor_polygon) f = other;
  double area[2] = {0.0, 0.0};
  for (int l = 0; l < 2; ++l)
    for (const PfdTree& t : file.levels[l].cells) area[l] += t.stats.region_area;
  ASSERT_GT(area[0], 2.0 * area[1]);
  const double share = area[1] / (area[0] + area[1]);

  HfdStatsOptions opt;
  opt.views = 30;
  opt.res = 16;
  for (const bool per_level : {false, true}) {
    SCOPED_TRACE(per_level ? "per level" : "by area");
    opt.per_level = per_level;
    const HfdStats h = computeHfdStats(file, opt);
    ASSERT_EQ(h.levels.size(), 2u);
    for (int l = 0; l < 2; ++l) {
      const uint32_t want = per_level ? 30u
                                      : std::max(kMinLevelEyes, static_cast<uint32_t>(std::llround(
                                                                    60.0 * area[l] / (area[0] + area[1]))));
      EXPECT_EQ(h.levels[l].summary.eyes, want);
    }
    EXPECT_EQ(h.levels[0].summary.eyes_with_miss, 0.0);
    EXPECT_EQ(h.levels[1].summary.eyes_with_miss, 1.0);
    EXPECT_NEAR(h.overall.eyes_with_miss, share, 1e-12);
    const double listed = (1.0 - share) * h.levels[0].summary.listed_mean + share * h.levels[1].summary.listed_mean;
    EXPECT_NEAR(h.overall.listed_mean, listed, 1e-9 * listed);
    EXPECT_EQ(h.overall.missed_histogram[0], h.levels[0].summary.eyes);  // histograms count eyes
    double weights = 0.0;
    for (const HfdEyeStats& e : h.eyes) weights += e.weight;
    EXPECT_NEAR(weights, static_cast<double>(h.eyes.size()), 1e-9 * h.eyes.size());
  }
}
}  // namespace
}  // namespace walkvis
