// Walking physics (movement.h): no pushing through a closed wall, however hard or from wherever;
// the eye follows the floor; steps up at most a step height, drops down any height; slides along
// walls; switches levels on the stairs of a Freedoom map.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <random>
#include <set>
#include <string>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "bsp/bsp.h"
#include "scenes/scene.h"
#include "walkthrough/movement.h"

// Allocations made on this thread while counting (the test binary's own operator new).
thread_local bool g_count_allocations = false;
thread_local size_t g_allocations = 0;

// Every unaligned form is replaced, not only the plain one: the library's std::stable_sort takes
// its buffer with the nothrow form and gives it back with plain delete, so a form left to the
// runtime (ASan's) would pair its allocation with this file's free(). GCC reads free() on what
// operator new returned as a mismatch; here operator new is malloc.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
static void* countedAllocation(size_t size) noexcept {
  if (g_count_allocations) ++g_allocations;
  return std::malloc(size ? size : 1);
}
void* operator new(size_t size) {
  if (void* p = countedAllocation(size)) return p;
  throw std::bad_alloc();
}
void* operator new[](size_t size) { return operator new(size); }
void* operator new(size_t size, const std::nothrow_t&) noexcept { return countedAllocation(size); }
void* operator new[](size_t size, const std::nothrow_t&) noexcept {
  return countedAllocation(size);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace walkvis {
namespace {

// Adds a quad facing the point `inside`.
void quad(Scene& s, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d, glm::dvec3 inside) {
  std::vector<glm::dvec3> v{a, b, c, d};
  const Plane p = newellPlane(v);
  if (glm::dot(p.n, inside) - p.d < 0) std::reverse(v.begin(), v.end());
  addFace(s, v, 0x808080, "test");
}

// A closed box room x, z in [-5, 5], y in [0, 3], every face facing in; the walkable region is far
// larger than the room, so only the walls keep the eye in.
Scene boxRoom() {
  Scene s;
  s.name = "box";
  const glm::dvec3 c{0, 1.5, 0};
  quad(s, {-5, 0, -5}, {5, 0, -5}, {5, 0, 5}, {-5, 0, 5}, c);  // floor
  quad(s, {-5, 3, -5}, {5, 3, -5}, {5, 3, 5}, {-5, 3, 5}, c);  // ceiling
  quad(s, {5, 0, -5}, {5, 3, -5}, {5, 3, 5}, {5, 0, 5}, c);
  quad(s, {-5, 0, -5}, {-5, 3, -5}, {-5, 3, 5}, {-5, 0, 5}, c);
  quad(s, {-5, 0, 5}, {5, 0, 5}, {5, 3, 5}, {-5, 3, 5}, c);
  // The -z wall in two pieces that meet at x = 1/3 (a seam that is not exactly representable).
  quad(s, {-5, 0, -5}, {1.0 / 3.0, 0, -5}, {1.0 / 3.0, 3, -5}, {-5, 3, -5}, c);
  quad(s, {1.0 / 3.0, 0, -5}, {5, 0, -5}, {5, 3, -5}, {1.0 / 3.0, 3, -5}, c);
  FloorLevel level;
  level.floor_y = 0.0;
  level.walkable.push_back({{-20, -20}, {-20, 20}, {20, 20}, {20, -20}});
  level.walkable_area = 1600;
  s.levels.push_back(level);
  s.eye_height = 1.7;
  s.start_eye = {0, 1.7, 0};
  return s;
}

// Brute force: does the segment a→b cross (or end on) a wall fragment?
bool crossesWall(const BspTree& bsp, const glm::dvec3& a, const glm::dvec3& b) {
  for (uint32_t f = 0; f < bsp.fragments.size(); ++f) {
    const Plane& pl = bsp.fragments[f].plane;
    if (std::abs(pl.n.y) >= kWallMaxNormalY) continue;
    const double sa = glm::dot(pl.n, a) - pl.d, sb = glm::dot(pl.n, b) - pl.d;
    if (sb != 0.0 && (sa > 0) == (sb > 0)) continue;
    if (sa == 0.0 && sb == 0.0) continue;
    const glm::dvec3 p = sb == 0.0 ? b : a + (sa / (sa - sb)) * (b - a);
    const auto v = bsp.fragmentVertices(f);
    bool inside = true;
    for (size_t i = 0; i < v.size() && inside; ++i)
      inside = glm::dot(glm::cross(v[(i + 1) % v.size()] - v[i], p - v[i]), pl.n) >= -1e-12;
    if (inside) return true;
  }
  return false;
}

TEST(Movement, NoPushGetsThroughAClosedWall) {
  const Scene scene = boxRoom();
  const BspTree bsp = buildBsp(scene);
  const Walker walker(scene, bsp);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), len_exp(-3.0, 2.0), pos(-4.9, 4.9);
  int moved = 0, blocked = 0;
  WalkState s = walker.place(scene.start_eye);
  ASSERT_EQ(s.level, 0);
  for (int i = 0; i < 20000; ++i) {
    if (i % 500 == 0) s = walker.place({pos(rng), 1.7, pos(rng)});  // new random start inside
    const double a = angle(rng), l = std::pow(10.0, len_exp(rng));  // pushes from 1 mm to 100 m
    const glm::dvec2 d{l * std::cos(a), l * std::sin(a)};
    const WalkState t = walker.move(s, d);
    ASSERT_LT(std::abs(t.eye.x), 5.0) << "push " << i;
    ASSERT_LT(std::abs(t.eye.z), 5.0) << "push " << i;
    ASSERT_FALSE(crossesWall(bsp, s.eye, t.eye)) << "push " << i;
    ASSERT_EQ(t.eye.y, 1.7);
    ASSERT_EQ(t.level, 0);
    (t.eye == s.eye ? blocked : moved)++;
    s = t;
  }
  std::printf("box: %d moves taken, %d refused entirely\n", moved, blocked);
  EXPECT_GT(moved, 10000);
  EXPECT_GT(blocked, 10);
}

TEST(Movement, KeepsRadiusFromWallsAndSlides) {
  const Scene scene = boxRoom();
  const BspTree bsp = buildBsp(scene);
  const Walker walker(scene, bsp);
  const double r = walker.radius();
  EXPECT_DOUBLE_EQ(r, 0.15 * 1.7);
  // Straight at the +x wall: stops short of the radius.
  WalkState s = walker.place({4.0, 1.7, 0.0});
  for (int i = 0; i < 100; ++i) s = walker.move(s, {0.05, 0.0});
  EXPECT_LE(s.eye.x, 5.0 - r);
  EXPECT_GT(s.eye.x, 5.0 - r - 0.05);
  // Diagonally into it: slides along +z with the tangential part of the push.
  const double z0 = s.eye.z;
  s = walker.move(s, {0.3, 0.2});
  EXPECT_NEAR(s.eye.z, z0 + 0.2, 1e-9);
  EXPECT_LE(s.eye.x, 5.0 - r);
  // Away from the wall is always possible.
  const WalkState away = walker.move(s, {-0.01, 0.0});
  EXPECT_LT(away.eye.x, s.eye.x);
  // Across the seam of the split -z wall: no gap.
  WalkState seam = walker.place({1.0 / 3.0, 1.7, -4.0});
  for (int i = 0; i < 200; ++i) seam = walker.move(seam, {0.0, -0.05});
  EXPECT_GT(seam.eye.z, -5.0 + r - 1e-9);
}

// Three floors side by side: x < 0 at y = 0, 0 <= x < 4 at y = 0.5 (a step), x >= 4 at y = 2 (a
// ledge too high to climb, 2 > 0.6 * 1.7); risers are walls up to each upper floor.
Scene steps() {
  Scene s;
  s.name = "steps";
  quad(s, {0, 0, -5}, {0, 0.5, -5}, {0, 0.5, 5}, {0, 0, 5}, {-1, 0, 0});
  quad(s, {4, 0.5, -5}, {4, 2, -5}, {4, 2, 5}, {4, 0.5, 5}, {3, 1, 0});
  quad(s, {-10, 0, -5}, {0, 0, -5}, {0, 0, 5}, {-10, 0, 5}, {-5, 1, 0});
  quad(s, {0, 0.5, -5}, {4, 0.5, -5}, {4, 0.5, 5}, {0, 0.5, 5}, {2, 1, 0});
  quad(s, {4, 2, -5}, {10, 2, -5}, {10, 2, 5}, {4, 2, 5}, {5, 3, 0});
  auto level = [&](double y, double x0, double x1) {
    FloorLevel l;
    l.floor_y = y;
    l.walkable.push_back({{x0, -5}, {x0, 5}, {x1, 5}, {x1, -5}});
    l.walkable_area = (x1 - x0) * 10;
    s.levels.push_back(l);
  };
  level(0.0, -10, 0);
  level(0.5, 0, 4);
  level(2.0, 4, 10);
  s.eye_height = 1.7;
  s.start_eye = {-5, 1.7, 0};
  return s;
}

TEST(Movement, StepsUpDropsDownRefusesLedges) {
  const Scene scene = steps();
  const BspTree bsp = buildBsp(scene);
  const Walker walker(scene, bsp);
  WalkState s = walker.place(scene.start_eye);
  ASSERT_EQ(s.level, 0);
  for (int i = 0; i < 200; ++i) s = walker.move(s, {0.05, 0.0});  // walks to x = 5 if it could
  EXPECT_EQ(s.level, 1);
  EXPECT_EQ(s.eye.y, 0.5 + 1.7);
  EXPECT_LE(s.eye.x, 4.0 + 1e-9);  // the 1.5 ledge stops it
  EXPECT_GT(s.eye.x, 3.7);  // the radius keeps it from the ledge's top edge (0.2 below the eye)
  // From the high floor it may drop down.
  WalkState high = walker.place({6, 2 + 1.7, 0});
  ASSERT_EQ(high.level, 2);
  for (int i = 0; i < 100; ++i) high = walker.move(high, {-0.05, 0.0});
  EXPECT_EQ(high.level, 1);
  EXPECT_EQ(high.eye.y, 0.5 + 1.7);
  // Off the walkable region: refused.
  WalkState edge = walker.place({-9.9, 1.7, 0});
  edge = walker.move(edge, {-1.0, 0.0});
  EXPECT_GE(edge.eye.x, -10.0);
}

// Also: the window moves the walker every frame, and a frame allocates nothing (the walls' BSP
// walk keeps its stack in the walker); a stack made per wall query fails this.
TEST(Movement, OfficeRandomWalkNeverCrossesAWall) {
  const Scene scene = loadScene("gen:office?rooms=12");
  const BspTree bsp = buildBsp(scene);
  const Walker walker(scene, bsp);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), len_exp(-2.0, 1.5);
  WalkState s = walker.place(scene.start_eye);
  ASSERT_GE(s.level, 0);
  double walked = 0.0;
  g_allocations = 0;
  for (int i = 0; i < 5000; ++i) {
    const double a = angle(rng), l = std::pow(10.0, len_exp(rng));
    g_count_allocations = true;
    const WalkState t = walker.move(s, {l * std::cos(a), l * std::sin(a)});
    g_count_allocations = false;
    ASSERT_FALSE(crossesWall(bsp, s.eye, {t.eye.x, s.eye.y, t.eye.z})) << "push " << i;
    ASSERT_EQ(t.eye.y, scene.levels[t.level].floor_y + scene.eye_height);
    walked += glm::length(t.eye - s.eye);
    s = t;
  }
  std::printf("office: walked %.1f m in 5000 pushes, %zu allocations in the moves\n", walked, g_allocations);
  EXPECT_GT(walked, 100.0);
  EXPECT_EQ(g_allocations, 0u);
}

TEST(Movement, FreedoomStairsSwitchLevels) {
  const Scene scene = loadScene("freedoom2.wad:MAP01");
  const BspTree bsp = buildBsp(scene);
  const Walker walker(scene, bsp);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  WalkState s = walker.place(scene.start_eye);
  ASSERT_GE(s.level, 0);
  int ups = 0, downs = 0;
  std::set<int> levels{s.level};
  glm::dvec2 dir{1, 0};
  for (int i = 0; i < 20000; ++i) {
    if (i % 40 == 0) {
      const double a = angle(rng);
      dir = {std::cos(a), std::sin(a)};
    }
    const WalkState t = walker.move(s, dir * 8.0);  // 8 units a step: a brisk Doom walk at 35 Hz
    ASSERT_FALSE(crossesWall(bsp, s.eye, {t.eye.x, s.eye.y, t.eye.z})) << "step " << i;
    ASSERT_GE(t.level, 0);
    const double fy = scene.levels[t.level].floor_y;
    ASSERT_EQ(t.eye.y, fy + scene.eye_height);
    ASSERT_EQ(walker.levelUnder(t.eye.x, t.eye.z, fy), std::optional<uint32_t>(t.level));
    if (t.level != s.level) {
      const double rise = fy - scene.levels[s.level].floor_y;
      ASSERT_LE(rise, walker.stepHeight()) << "step " << i;
      (rise > 0 ? ups : downs)++;
    }
    levels.insert(t.level);
    s = t;
  }
  std::printf("MAP01: %d steps up, %d down, %zu levels visited of %zu\n", ups, downs, levels.size(),
              scene.levels.size());
  EXPECT_GT(ups, 0);
  EXPECT_GT(downs, 0);
  EXPECT_GE(levels.size(), 3u);
}


// ---- Connections (walkable.h): stairs and ramps climbed patch by patch ----

Scene navmeshScene(const std::string& spec) {
  LoadOptions options;
  options.floors = "navmesh";
  return loadScene(spec, options);
}

// Walks from (x, z) along +x in steps of `step` up to x_end; returns the last state and checks on
// the way that the eye always stands on a floor (never rises more than a step at once).
WalkState walkAlongX(const Walker& walker, const Scene& scene, glm::dvec2 start, double x_end, double step) {
  WalkState s = walker.place({start.x, scene.eye_height, start.y});
  EXPECT_EQ(s.level, 0);
  for (int i = 0; i < 10000 && s.eye.x < x_end; ++i) {
    const WalkState next = walker.move(s, {step, 0.0});
    EXPECT_LE(next.eye.y - s.eye.y, walker.stepHeight() + 1e-9);
    if (next.eye.x == s.eye.x) break;  // stuck
    s = next;
  }
  return s;
}

TEST(Movement, ClimbsTheHouseStairToTheUpperLevel) {
  const Scene scene = navmeshScene("gen:house");
  ASSERT_EQ(scene.levels.size(), 2u);
  ASSERT_EQ(scene.connections.size(), 1u);
  const BspTree bsp = buildBsp(scene);
  const Walker walker(scene, bsp);
  // The stair rises along +x from x = 1 to 5.2 against the z = 0 wall, 1.2 m wide.
  const WalkState top = walkAlongX(walker, scene, {0.6, 0.6}, 6.5, 0.05);
  EXPECT_EQ(top.level, 1);
  EXPECT_GT(top.eye.x, 6.0);
  EXPECT_DOUBLE_EQ(top.eye.y, scene.levels[1].floor_y + scene.eye_height);
  // Half way up the eye is on a tread (a patch: level -1) at a tread's height.
  WalkState mid = walker.place({3.0, 10.0, 0.6});
  EXPECT_EQ(mid.level, -1);
  EXPECT_NEAR(mid.eye.y - scene.eye_height, 3.0 / 16.0 * 8.0, 1e-9);  // tread 8 of 15 (x in [2.96, 3.24])
  // And back down: walking along -x from the upper floor ends on the ground level.
  WalkState s = top;
  for (int i = 0; i < 400 && s.eye.x > 0.6; ++i) s = walker.move(s, {-0.05, 0.0});
  EXPECT_EQ(s.level, 0);
}

TEST(Movement, ClimbsTheRampToTheUpperFloor) {
  const Scene scene = navmeshScene("gen:ramp");
  ASSERT_EQ(scene.levels.size(), 2u);
  const BspTree bsp = buildBsp(scene);
  const Walker walker(scene, bsp);
  double last_y = 0.0;
  WalkState s = walker.place({1.0, scene.eye_height, 2.0});
  ASSERT_EQ(s.level, 0);
  bool on_ramp = false;
  for (int i = 0; i < 400 && s.eye.x < 9.0; ++i) {
    s = walker.move(s, {0.05, 0.0});
    EXPECT_GE(s.eye.y, last_y - 1e-12);  // up the ramp, never down
    last_y = s.eye.y;
    if (s.level < 0) {
      on_ramp = true;
      // On the ramp (x from 4 to 7, rising 0.9) the eye follows its plane.
      EXPECT_NEAR(s.eye.y - scene.eye_height, std::clamp((s.eye.x - 4.0) * 0.3, 0.0, 0.9), 1e-9);
    }
  }
  EXPECT_TRUE(on_ramp);
  EXPECT_EQ(s.level, 1);
  EXPECT_DOUBLE_EQ(s.eye.y, 0.9 + scene.eye_height);
}

TEST(Movement, NeverReachesTheTableTop) {
  const Scene scene = navmeshScene("gen:table_room");
  ASSERT_EQ(scene.levels.size(), 1u);
  const BspTree bsp = buildBsp(scene);
  const Walker walker(scene, bsp);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), len(0.01, 0.5);
  WalkState s = walker.place(scene.start_eye);
  ASSERT_EQ(s.level, 0);
  int moved = 0;
  for (int i = 0; i < 20000; ++i) {
    const double a = angle(rng), l = len(rng);
    const WalkState next = walker.move(s, {l * std::sin(a), l * std::cos(a)});
    if (next.eye != s.eye) ++moved;
    s = next;
    ASSERT_EQ(s.level, 0);
    ASSERT_EQ(s.eye.y, scene.eye_height);
    // The table (1.6 x 0.9 m, centred in the 6 x 5 room) is never under the eye.
    ASSERT_FALSE(std::abs(s.eye.x - 3.0) < 0.8 && std::abs(s.eye.z - 2.5) < 0.45);
  }
  EXPECT_GT(moved, 10000);
}

}  // namespace
}  // namespace walkvis
