// Point-sampled area-to-area visibility (pfd_hfd/visibility.h): closed walls hide, a narrow door
// does not at the default sampling, hidden from a region => hidden from its sub-regions (property
// over seeds), and the answer is deterministic.
#include <gtest/gtest.h>
#include <optional>
#include <array>

#include <algorithm>
#include <random>
#include <cmath>

#include <glm/geometric.hpp>

#include "bsp/bsp.h"
#include "pfd_hfd/visibility.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

using Region = std::vector<std::vector<glm::dvec2>>;

// Adds an axis-aligned vertical rectangle or any quad, wound so that its front faces `facing`.
// Returns the index of the polygon it became.
uint32_t addQuad(Scene& scene, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d, glm::dvec3 facing) {
  std::vector<glm::dvec3> v{a, b, c, d};
  if (glm::dot(newellPlane(v).n, facing) < 0.0) std::reverse(v.begin(), v.end());
  const uint32_t index = static_cast<uint32_t>(scene.polygons.size());
  addFace(scene, v, 0x808080, "test");
  EXPECT_EQ(scene.polygons.size(), index + 1u);
  return index;
}

// A vertical wall in the plane x = x0 (z from z0 to z1, y from 0 to top), one face per side.
void wallX(Scene& scene, double x0, double z0, double z1, double y0, double y1) {
  addQuad(scene, {x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}, {-1, 0, 0});
  addQuad(scene, {x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}, {1, 0, 0});
}
void wallZ(Scene& scene, double z0, double x0, double x1, double y0, double y1) {
  addQuad(scene, {x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0}, {0, 0, -1});
  addQuad(scene, {x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0}, {0, 0, 1});
}

struct TwoRooms {
  Scene scene;
  uint32_t back_wall = 0;  // room B's far wall, facing room A
  uint32_t panel = 0;      // a small panel on room B's side wall, seen from A only through the door
};

// Room A = [0, 10] x [0, 10] (x, z), room B = [10, 20] x [0, 10], walls 3 high, the wall x = 10
// between them with a door of width `door` (0: none) centred at z = 5, 2.2 high.
TwoRooms twoRooms(double door) {
  TwoRooms r;
  Scene& s = r.scene;
  const double top = 3.0;
  addQuad(s, {0, 0, 0}, {20, 0, 0}, {20, 0, 10}, {0, 0, 10}, {0, 1, 0});          // floor
  addQuad(s, {0, top, 0}, {20, top, 0}, {20, top, 10}, {0, top, 10}, {0, -1, 0});  // ceiling
  addQuad(s, {0, 0, 0}, {0, 0, 10}, {0, top, 10}, {0, top, 0}, {1, 0, 0});        // A's far wall
  r.back_wall = addQuad(s, {20, 0, 0}, {20, 0, 10}, {20, top, 10}, {20, top, 0}, {-1, 0, 0});
  addQuad(s, {0, 0, 0}, {20, 0, 0}, {20, top, 0}, {0, top, 0}, {0, 0, 1});        // side z = 0
  addQuad(s, {0, 0, 10}, {14, 0, 10}, {14, top, 10}, {0, top, 10}, {0, 0, -1});   // side z = 10
  addQuad(s, {16, 0, 10}, {20, 0, 10}, {20, top, 10}, {16, top, 10}, {0, 0, -1});
  r.panel = addQuad(s, {14, 0, 10}, {16, 0, 10}, {16, top, 10}, {14, top, 10}, {0, 0, -1});
  if (door > 0.0) {
    wallX(s, 10, 0, 5 - door / 2, 0, top);
    wallX(s, 10, 5 + door / 2, 10, 0, top);
    wallX(s, 10, 5 - door / 2, 5 + door / 2, 2.2, top);
  } else {
    wallX(s, 10, 0, 10, 0, top);
  }
  return r;
}

uint32_t fragmentOf(const BspTree& bsp, uint32_t polygon) {
  for (uint32_t f = 0; f < bsp.fragments.size(); ++f)
    if (bsp.fragment_polygon[f] == polygon) return f;
  ADD_FAILURE() << "polygon " << polygon << " has no fragment";
  return 0;
}

const Region kRoomA{{{0, 0}, {10, 0}, {10, 10}, {0, 10}}};


// A random axis-aligned box region in the 30 × 30 room grid (x0 < x1, z0 < z1 in `bounds`), or
// nothing when a side is under 0.5. Draws four numbers from `rng` either way.
struct Box {
  std::array<double, 4> bounds;  // x0, x1, z0, z1
  Region region;
};
std::optional<Box> randomBox(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 30.0);
  double x0 = u(rng), x1 = u(rng), z0 = u(rng), z1 = u(rng);
  if (x0 > x1) std::swap(x0, x1);
  if (z0 > z1) std::swap(z0, z1);
  if (x1 - x0 < 0.5 || z1 - z0 < 0.5) return std::nullopt;
  return Box{{x0, x1, z0, z1}, Region{{{x0, z0}, {x1, z0}, {x1, z1}, {x0, z1}}}};
}

// `boxes` draws of randomBox, each (when not too thin) with `per_box` random fragments of
// `fragments`: visit(box, fragment), which may draw from `rng` too.
template <typename Visit>
void forRandomBoxFragments(std::mt19937_64& rng, int boxes, int per_box, size_t fragments, Visit&& visit) {
  for (int trial = 0; trial < boxes; ++trial) {
    const std::optional<Box> box = randomBox(rng);
    if (!box) continue;
    for (int k = 0; k < per_box; ++k) visit(*box, static_cast<uint32_t>(rng() % fragments));
  }
}

TEST(Visibility, ClosedWallHides) {
  const TwoRooms r = twoRooms(0.0);
  const BspTree bsp = buildBsp(r.scene);
  const VisibilityScene vis = VisibilityScene::build(bsp);
  VisibilityCounters c;
  for (uint32_t f = 0; f < bsp.fragments.size(); ++f) {
    if (bsp.fragment_polygon[f] != r.back_wall && bsp.fragment_polygon[f] != r.panel) continue;
    EXPECT_FALSE(vis.visibleFromRegion(f, kRoomA, 1.5, c)) << "fragment " << f;
  }
  EXPECT_GT(c.rays, 0u);
  EXPECT_EQ(c.visible, 0u);
  // Sanity: without the wall between them, the same fragments are seen.
  TwoRooms open = twoRooms(0.0);
  open.scene.polygons.resize(open.scene.polygons.size() - 2);
  const BspTree bsp2 = buildBsp(open.scene);
  const VisibilityScene vis2 = VisibilityScene::build(bsp2);
  EXPECT_TRUE(vis2.visibleFromRegion(fragmentOf(bsp2, r.back_wall), kRoomA, 1.5, c));
  EXPECT_TRUE(vis2.visibleFromRegion(fragmentOf(bsp2, r.panel), kRoomA, 1.5, c));
}

TEST(Visibility, NarrowDoorKeptAtDefaultSampling) {
  // The door is 1/50 of the wall's width.
  const TwoRooms r = twoRooms(0.2);
  const BspTree bsp = buildBsp(r.scene);
  const VisibilityScene vis = VisibilityScene::build(bsp);
  VisibilityCounters c;
  bool back = false, panel = false;
  for (uint32_t f = 0; f < bsp.fragments.size(); ++f) {
    if (bsp.fragment_polygon[f] == r.back_wall) back |= vis.visibleFromRegion(f, kRoomA, 1.5, c);
    if (bsp.fragment_polygon[f] == r.panel) panel |= vis.visibleFromRegion(f, kRoomA, 1.5, c);
  }
  EXPECT_TRUE(back);
  EXPECT_TRUE(panel);  // seen only from a thin wedge of room A through the door
  // And from several sub-regions of room A that see it through the door.
  const Region strip{{{0, 4}, {10, 4}, {10, 6}, {0, 6}}};
  const uint32_t f = fragmentOf(bsp, r.back_wall);
  EXPECT_TRUE(vis.visibleFromRegion(f, strip, 1.5, c));
}

// Rooms in a grid with doors of random widths and positions, and pillars.
Scene roomGrid(uint64_t seed, int n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Scene s;
  const double size = 10.0, top = 3.0, ext = n * size;
  addQuad(s, {0, 0, 0}, {ext, 0, 0}, {ext, 0, ext}, {0, 0, ext}, {0, 1, 0});
  addQuad(s, {0, 0, 0}, {0, 0, ext}, {0, top, ext}, {0, top, 0}, {1, 0, 0});
  addQuad(s, {ext, 0, 0}, {ext, 0, ext}, {ext, top, ext}, {ext, top, 0}, {-1, 0, 0});
  addQuad(s, {0, 0, 0}, {ext, 0, 0}, {ext, top, 0}, {0, top, 0}, {0, 0, 1});
  addQuad(s, {0, 0, ext}, {ext, 0, ext}, {ext, top, ext}, {0, top, ext}, {0, 0, -1});
  for (int i = 1; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      // wall x = i*size over z in [j*size, (j+1)*size] with a door, and the transposed one.
      for (int axis = 0; axis < 2; ++axis) {
        const double w = 0.3 + 2.0 * u01(rng);
        const double c = j * size + 1.5 + (size - 3.0) * u01(rng);
        const double a = j * size, b = (j + 1) * size, p = i * size;
        if (axis == 0) {
          wallX(s, p, a, c - w / 2, 0, top);
          wallX(s, p, c + w / 2, b, 0, top);
        } else {
          wallZ(s, p, a, c - w / 2, 0, top);
          wallZ(s, p, c + w / 2, b, 0, top);
        }
      }
    }
  return s;
}

TEST(Visibility, HiddenFromRegionIsHiddenFromSubRegions) {
  int hidden_pairs = 0, checked = 0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const Scene scene = roomGrid(seed, 3);
    const BspTree bsp = buildBsp(scene);
    VisibilityOptions opt;
    opt.seed = seed;
    const VisibilityScene vis = VisibilityScene::build(bsp, opt);
    std::mt19937_64 rng(seed * 77);
    VisibilityCounters c;
    forRandomBoxFragments(rng, 40, 10, bsp.fragments.size(), [&](const Box& box, uint32_t f) {
      const auto [x0, x1, z0, z1] = box.bounds;
      if (vis.visibleFromRegion(f, box.region, 1.5, c)) return;
      ++hidden_pairs;
      for (int sub = 0; sub < 4; ++sub) {
        std::uniform_real_distribution<double> ux(x0, x1), uz(z0, z1);
        double a = ux(rng), b = ux(rng), p = uz(rng), q = uz(rng);
        if (a > b) std::swap(a, b);
        if (p > q) std::swap(p, q);
        const Region subregion{{{a, p}, {b, p}, {b, q}, {a, q}}};
        ++checked;
        EXPECT_FALSE(vis.visibleFromRegion(f, subregion, 1.5, c))
            << "seed " << seed << " fragment " << f << " region [" << x0 << "," << x1 << "]x[" << z0 << "," << z1
            << "] sub [" << a << "," << b << "]x[" << p << "," << q << "]";
      }
    });
  }
  EXPECT_GT(hidden_pairs, 20);  // the property was exercised
  EXPECT_GT(checked, 80);
}

// Sixteen closed rooms in a row ([5k, 5k + 5] x [0, 5], no doors) and, in room 4, a cabinet in
// front of the side wall z = 5 that leaves only the wall's top 0.4 in view. Seen from the whole
// row (one region over all sixteen rooms), the wall is visible from a sixteenth of the region,
// over the cabinet (the office's misses, docs/DESIGN.md, "Sizes and errors": room grids). The
// refinement finds it here without the samples in front too (printed); the office figures in
// docs/hfd/README.md are where those samples show.
TEST(Visibility, WallOfOneRoomKeptFromTheWholeRow) {
  Scene s;
  const double top = 3.0, cab = 2.6;
  addQuad(s, {0, 0, 0}, {80, 0, 0}, {80, 0, 5}, {0, 0, 5}, {0, 1, 0});
  addQuad(s, {0, top, 0}, {80, top, 0}, {80, top, 5}, {0, top, 5}, {0, -1, 0});
  addQuad(s, {0, 0, 0}, {80, 0, 0}, {80, top, 0}, {0, top, 0}, {0, 0, 1});
  addQuad(s, {0, 0, 5}, {20, 0, 5}, {20, top, 5}, {0, top, 5}, {0, 0, -1});
  const uint32_t wall = addQuad(s, {20, 0, 5}, {25, 0, 5}, {25, top, 5}, {20, top, 5}, {0, 0, -1});
  addQuad(s, {25, 0, 5}, {80, 0, 5}, {80, top, 5}, {25, top, 5}, {0, 0, -1});
  addQuad(s, {0, 0, 0}, {0, 0, 5}, {0, top, 5}, {0, top, 0}, {1, 0, 0});
  addQuad(s, {80, 0, 0}, {80, 0, 5}, {80, top, 5}, {80, top, 0}, {-1, 0, 0});
  for (int k = 1; k < 16; ++k) wallX(s, 5.0 * k, 0, 5, 0, top);
  // The cabinet: [20.2, 24.8] x [4.2, 5], 2.6 high; its front, top and ends.
  addQuad(s, {20.2, 0, 4.2}, {24.8, 0, 4.2}, {24.8, cab, 4.2}, {20.2, cab, 4.2}, {0, 0, -1});
  addQuad(s, {20.2, cab, 4.2}, {24.8, cab, 4.2}, {24.8, cab, 5}, {20.2, cab, 5}, {0, 1, 0});
  addQuad(s, {20.2, 0, 4.2}, {20.2, 0, 5}, {20.2, cab, 5}, {20.2, cab, 4.2}, {-1, 0, 0});
  addQuad(s, {24.8, 0, 4.2}, {24.8, 0, 5}, {24.8, cab, 5}, {24.8, cab, 4.2}, {1, 0, 0});
  const BspTree bsp = buildBsp(s);
  Region row;
  for (int k = 0; k < 16; ++k) row.push_back({{5.0 * k, 0}, {5.0 * k + 5, 0}, {5.0 * k + 5, 5}, {5.0 * k, 5}});
  int kept = 0, kept_without = 0, fragments = 0;
  for (uint64_t seed = 1; seed <= 50; ++seed) {
    VisibilityOptions on, off;
    on.seed = off.seed = seed;
    off.near_samples = false;
    const VisibilityScene vis_on = VisibilityScene::build(bsp, on), vis_off = VisibilityScene::build(bsp, off);
    VisibilityCounters c;
    for (uint32_t f = 0; f < bsp.fragments.size(); ++f) {
      if (bsp.fragment_polygon[f] != wall) continue;
      ++fragments;
      const bool v = vis_on.visibleFromRegion(f, row, 1.5, c);
      EXPECT_TRUE(v) << "seed " << seed << " fragment " << f;
      kept += v;
      kept_without += vis_off.visibleFromRegion(f, row, 1.5, c);
    }
  }
  EXPECT_GT(fragments, 0);
  std::printf("wall kept %d / %d with samples in front, %d without\n", kept, fragments, kept_without);
}

TEST(Visibility, ProofRejectsAClosedWallWithFewRays) {
  const TwoRooms r = twoRooms(0.0);
  const BspTree bsp = buildBsp(r.scene);
  VisibilityOptions off;
  off.proof_rays = 0;
  const VisibilityScene with = VisibilityScene::build(bsp);
  const VisibilityScene without = VisibilityScene::build(bsp, off);
  ASSERT_GT(with.options().proof_rays, 0u);
  const uint32_t f = fragmentOf(bsp, r.back_wall);
  VisibilityCounters cw, co;
  EXPECT_FALSE(with.visibleFromRegion(f, kRoomA, 1.5, cw));
  EXPECT_FALSE(without.visibleFromRegion(f, kRoomA, 1.5, co));
  // One packet, then one blocker (the closed wall) covers the whole cone.
  EXPECT_LE(cw.rays, 16u + 3u);
  EXPECT_GT(co.rays, 100u);
}

// Room A = [0, 10] x [0, 10] and room B beyond x = 10 as in twoRooms, but the wall x = 10 is
// `panels` strips side by side, sharing their vertical edges; `hole` (when >= 0) is a strip
// with a window of 0.6 x 0.6 in it (four pieces around the opening). With `stacked`, every
// other strip is two halves one above the other, so the tall strips beside them meet them at
// T-junctions.
Scene stripWall(int panels, int hole, bool stacked, uint32_t* back_wall) {
  Scene s;
  const double top = 3.0;
  addQuad(s, {0, 0, 0}, {20, 0, 0}, {20, 0, 10}, {0, 0, 10}, {0, 1, 0});
  addQuad(s, {0, top, 0}, {20, top, 0}, {20, top, 10}, {0, top, 10}, {0, -1, 0});
  addQuad(s, {0, 0, 0}, {0, 0, 10}, {0, top, 10}, {0, top, 0}, {1, 0, 0});
  *back_wall = addQuad(s, {20, 0, 0}, {20, 0, 10}, {20, top, 10}, {20, top, 0}, {-1, 0, 0});
  addQuad(s, {0, 0, 0}, {20, 0, 0}, {20, top, 0}, {0, top, 0}, {0, 0, 1});
  addQuad(s, {0, 0, 10}, {20, 0, 10}, {20, top, 10}, {0, top, 10}, {0, 0, -1});
  const double w = 10.0 / panels;
  auto strip = [&](double z0, double z1, double y0, double y1) {
    addQuad(s, {10, y0, z0}, {10, y0, z1}, {10, y1, z1}, {10, y1, z0}, {-1, 0, 0});
  };
  for (int k = 0; k < panels; ++k) {
    const double z0 = k * w, z1 = (k + 1) * w;
    if (k == hole) {
      const double zm = 0.5 * (z0 + z1);
      strip(z0, z1, 0, 1.2);
      strip(z0, z1, 1.8, top);
      strip(z0, zm - 0.3, 1.2, 1.8);
      strip(zm + 0.3, z1, 1.2, 1.8);
    } else if (stacked && k % 2 == 1) {
      strip(z0, z1, 0, 1.4);
      strip(z0, z1, 1.4, top);
    } else {
      strip(z0, z1, 0, top);
    }
  }
  return s;
}

// The proof is exact: wherever it answers "hidden", sampling without it finds no unblocked ray
// either (over rooms with doors and random regions; seeds fixed; fused patches included).
TEST(Visibility, ProofNeverHidesWhatSamplingSees) {
  int proved = 0, hidden = 0, compared = 0;
  uint64_t patch_covers = 0;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const Scene scene = roomGrid(seed, 3);
    const BspTree bsp = buildBsp(scene);
    VisibilityOptions on, off;
    on.seed = off.seed = seed;
    off.proof_rays = 0;
    const VisibilityScene a = VisibilityScene::build(bsp, on);
    const VisibilityScene b = VisibilityScene::build(bsp, off);
    std::mt19937_64 rng(seed * 31);
    forRandomBoxFragments(rng, 30, 10, bsp.fragments.size(), [&](const Box& box, uint32_t f) {
      const auto [x0, x1, z0, z1] = box.bounds;
      VisibilityCounters ca, cb;
      const bool va = a.visibleFromRegion(f, box.region, 1.5, ca);
      const bool vb = b.visibleFromRegion(f, box.region, 1.5, cb);
      ++compared;
      if (!va) ++hidden;
      if (!va && ca.rays < cb.rays) ++proved;
      patch_covers += ca.patch_covers;
      // (The proof's centre rays may find a real opening sampling misses: visible only with it is fine.)
      EXPECT_FALSE(!va && vb) << "seed " << seed << " fragment " << f << " region [" << x0 << "," << x1 << "]x[" << z0
                              << "," << z1 << "]";
    });
  }
  EXPECT_GT(compared, 500);
  EXPECT_GT(hidden, 50);
  EXPECT_GT(proved, 10);  // the proof was exercised
  // The same over the strip walls (fused patches, T-junctions, a window), boxes inside room A and
  // every fragment.
  int fused_hidden = 0;
  for (int variant = 0; variant < 4; ++variant) {
    uint32_t back = 0;
    const Scene scene = stripWall(variant < 2 ? 20 : 7, variant % 2 == 0 ? -1 : 3, variant >= 2, &back);
    const BspTree bsp = buildBsp(scene);
    VisibilityOptions off;
    off.proof_rays = 0;
    const VisibilityScene a = VisibilityScene::build(bsp);
    const VisibilityScene b = VisibilityScene::build(bsp, off);
    std::mt19937_64 rng(variant + 100);
    std::uniform_real_distribution<double> u(0.0, 10.0);
    for (int trial = 0; trial < 12; ++trial) {
      double x0 = u(rng), x1 = u(rng), z0 = u(rng), z1 = u(rng);
      if (x0 > x1) std::swap(x0, x1);
      if (z0 > z1) std::swap(z0, z1);
      if (x1 - x0 < 0.5 || z1 - z0 < 0.5) continue;
      const Region region{{{x0, z0}, {x1, z0}, {x1, z1}, {x0, z1}}};
      for (uint32_t f = 0; f < bsp.fragments.size(); ++f) {
        VisibilityCounters ca, cb;
        const bool va = a.visibleFromRegion(f, region, 1.5, ca);
        const bool vb = b.visibleFromRegion(f, region, 1.5, cb);
        patch_covers += ca.patch_covers;
        if (!va && ca.patch_covers > 0) ++fused_hidden;
        EXPECT_FALSE(!va && vb) << "strip variant " << variant << " fragment " << f << " region [" << x0 << ","
                                << x1 << "]x[" << z0 << "," << z1 << "]";
      }
    }
  }
  EXPECT_GT(patch_covers, 10u);  // fused occluders were exercised
  EXPECT_GT(fused_hidden, 10);
}

// Occluder fusion: room B's far wall is hidden from room A by the wall x = 10 as a whole, though
// no one strip of it covers more than a sliver of the view. The proof joins the strips (across
// shared edges and across T-junctions) and rejects it with a packet and a ray or two; without
// fusion it takes the full sampling. With a window in one strip it stays visible.
TEST(Visibility, FusedStripsHideWhatNoOneStripHides) {
  for (const bool stacked : {false, true}) {
    SCOPED_TRACE(stacked ? "stacked strips" : "full-height strips");
    uint32_t back = 0;
    const Scene closed = stripWall(20, -1, stacked, &back);
    const BspTree bsp = buildBsp(closed);
    VisibilityOptions off;
    off.fuse_occluders = false;
    const VisibilityScene with = VisibilityScene::build(bsp);
    const VisibilityScene without = VisibilityScene::build(bsp, off);
    const uint32_t f = fragmentOf(bsp, back);
    VisibilityCounters cw, co;
    EXPECT_FALSE(with.visibleFromRegion(f, kRoomA, 1.5, cw));
    EXPECT_FALSE(without.visibleFromRegion(f, kRoomA, 1.5, co));
    EXPECT_EQ(cw.proved_hidden, 1u);
    EXPECT_GE(cw.patch_covers, 1u);
    EXPECT_LE(cw.rays, 16u + 3u);
    EXPECT_EQ(co.proved_hidden, 0u);
    EXPECT_GT(co.rays, 100u);

    const Scene open = stripWall(20, 7, stacked, &back);
    const BspTree bsp_open = buildBsp(open);
    const VisibilityScene vis_open = VisibilityScene::build(bsp_open);
    VisibilityCounters c;
    EXPECT_TRUE(vis_open.visibleFromRegion(fragmentOf(bsp_open, back), kRoomA, 1.5, c));
    EXPECT_EQ(c.proved_hidden, 0u);
  }
}

// Conservative mode: the closed strip wall is proved to hide the far wall; with a window it is
// kept; over random regions of room grids it rejects nothing that sampling sees, and what the
// proof cannot decide is kept without a witness.
TEST(Visibility, ConservativeRejectsOnlyWhatIsProved) {
  VisibilityOptions conservative;
  conservative.conservative = true;
  for (const bool stacked : {false, true}) {
    uint32_t back = 0;
    const Scene closed = stripWall(20, -1, stacked, &back);
    const BspTree bsp = buildBsp(closed);
    const VisibilityScene vis = VisibilityScene::build(bsp, conservative);
    VisibilityCounters c;
    EXPECT_FALSE(vis.visibleFromRegion(fragmentOf(bsp, back), kRoomA, 1.5, c));
    EXPECT_EQ(c.proved_hidden, 1u);
    const Scene open = stripWall(20, 7, stacked, &back);
    const BspTree bsp_open = buildBsp(open);
    const VisibilityScene vis_open = VisibilityScene::build(bsp_open, conservative);
    VisibilityCounters co;
    glm::dvec2 witness{0.0};
    EXPECT_TRUE(vis_open.visibleFromRegion(fragmentOf(bsp_open, back), kRoomA, 1.5, co, &witness));
  }
  // Over random regions of room grids: whatever the conservative mode rejects, sampling without
  // the proof rejects too, and a kept fragment's witness is a point of the region or NaN.
  int kept_unproven = 0, rejected = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    const Scene scene = roomGrid(seed, 3);
    const BspTree bsp = buildBsp(scene);
    VisibilityOptions off;
    off.proof_rays = 0;
    off.seed = seed;
    VisibilityOptions cons = conservative;
    cons.seed = seed;
    const VisibilityScene a = VisibilityScene::build(bsp, cons);
    const VisibilityScene b = VisibilityScene::build(bsp, off);
    std::mt19937_64 rng(seed * 77);
    forRandomBoxFragments(rng, 20, 10, bsp.fragments.size(), [&](const Box& box, uint32_t f) {
      VisibilityCounters ca, cb;
      glm::dvec2 w{0.0};
      const bool va = a.visibleFromRegion(f, box.region, 1.5, ca, &w);
      const bool vb = b.visibleFromRegion(f, box.region, 1.5, cb);
      EXPECT_FALSE(!va && vb) << "seed " << seed << " fragment " << f;
      if (!va) ++rejected;
      if (ca.kept_unproven > 0) {
        ++kept_unproven;
        EXPECT_TRUE(va);
        EXPECT_TRUE(std::isnan(w.x));
      } else if (va) {
        const auto [x0, x1, z0, z1] = box.bounds;
        EXPECT_TRUE(w.x >= x0 && w.x <= x1 && w.y >= z0 && w.y <= z1);
      }
    });
  }
  EXPECT_GT(rejected, 20);
  EXPECT_GT(kept_unproven, 0);
}

// A wall seen only along its top edge: the occluder in front of it stops 0.0007 below the sight
// line from the region's far edge to the wall's top, inside the band (1e-3 of the wall's size)
// that the samples' shrink leaves unsampled. Rays there do reach the wall; the conservative mode,
// whose proof covers the whole fragment, keeps it (a proof of the shrunk wall alone hid it).
TEST(Visibility, ConservativeKeepsAWallSeenOnlyAlongItsEdge) {
  Scene scene;
  const uint32_t target = addQuad(scene, {20, 0, 0}, {20, 0, 10}, {20, 3, 10}, {20, 3, 0}, {-1, 0, 0});
  // From x = 0 at height 1.5, the sight line to y = 2.9993 at x = 20 crosses x = 15 at this height.
  const double h = 1.5 + (2.9993 - 1.5) * 0.75;
  wallX(scene, 15, -10, 20, 0, h);
  const BspTree bsp = buildBsp(scene);
  VisibilityOptions conservative;
  conservative.conservative = true;
  const VisibilityScene vis = VisibilityScene::build(bsp, conservative);
  const glm::dvec3 eye{1e-3, 1.5, 5.0}, top{20.0, 2.99995, 5.0};
  ASSERT_FALSE(vis.occluded(eye, eye + (top - eye) * (1.0 - 1e-6)));  // the edge is seen
  const glm::dvec3 lower{20.0, 2.998, 5.0};
  ASSERT_TRUE(vis.occluded(eye, eye + (lower - eye) * (1.0 - 1e-6)));  // below the band it is not
  VisibilityCounters c;
  EXPECT_TRUE(vis.visibleFromRegion(fragmentOf(bsp, target), kRoomA, 1.5, c));
  EXPECT_EQ(c.proved_hidden, 0u);
}

// sampled_max_area: a test from a region larger than it answers as the conservative mode does,
// one from a smaller region as the sampled mode does, verdict and counters alike.
TEST(Visibility, SampledVerdictsOnlyFromSmallRegions) {
  int large = 0, small = 0, differ = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    const Scene scene = roomGrid(seed, 3);
    const BspTree bsp = buildBsp(scene);
    VisibilityOptions sampled, conservative, hybrid;
    sampled.seed = conservative.seed = hybrid.seed = seed;
    conservative.conservative = true;
    hybrid.sampled_max_area = 60.0;
    const VisibilityScene vs = VisibilityScene::build(bsp, sampled);
    const VisibilityScene vc = VisibilityScene::build(bsp, conservative);
    const VisibilityScene vh = VisibilityScene::build(bsp, hybrid);
    std::mt19937_64 rng(seed * 31);
    forRandomBoxFragments(rng, 30, 10, bsp.fragments.size(), [&](const Box& box, uint32_t f) {
      const auto [x0, x1, z0, z1] = box.bounds;
      const bool is_large = (x1 - x0) * (z1 - z0) > hybrid.sampled_max_area;
      VisibilityCounters ch, cr;
      const bool h = vh.visibleFromRegion(f, box.region, 1.5, ch);
      const bool r = (is_large ? vc : vs).visibleFromRegion(f, box.region, 1.5, cr);
      EXPECT_EQ(h, r) << "seed " << seed << " fragment " << f << (is_large ? " large" : " small");
      EXPECT_EQ(ch.rays, cr.rays);
      EXPECT_EQ(ch.proved_hidden, cr.proved_hidden);
      EXPECT_EQ(ch.kept_unproven, cr.kept_unproven);
      ++(is_large ? large : small);
      if (is_large) {
        VisibilityCounters cs;
        differ += vs.visibleFromRegion(f, box.region, 1.5, cs) != h;
      }
    });
  }
  EXPECT_GT(large, 50);
  EXPECT_GT(small, 50);
  EXPECT_GT(differ, 0);  // the large regions' answers are not the sampled mode's anyway
}

// A floor fragment whose corners repeat, each copy 1e-13 off the first (what BSP splits through a
// vertex leave: freedoom1 E1M1 had such a floor triangle beside the eye, 15.7% of its pixels): the
// copies make edges whose direction is rounding noise, and taken for sides of the target they cut
// through it, so that no sample ray was cast. Seen from beside it, in every direction of the
// noise, it must be visible, with rays cast and not only from the proof.
TEST(Visibility, FragmentWithRepeatedCornersIsSeen) {
  Scene scene;
  addQuad(scene, {0, 0, 0}, {10, 0, 0}, {10, 0, 4}, {0, 0, 4}, {0, 1, 0});
  const BspTree base = buildBsp(scene);
  ASSERT_EQ(base.fragments.size(), 1u);
  int checked = 0;
  for (int k = 0; k < 8; ++k) {
    const double angle = k * 0.785398163397448;
    const glm::dvec3 noise = 1e-13 * glm::dvec3(std::cos(angle), 0.0, std::sin(angle));
    BspTree bsp = base;
    Polygon& p = bsp.fragments[0];
    std::vector<glm::dvec3> corners(bsp.vertices.begin() + p.first_vertex,
                                    bsp.vertices.begin() + p.first_vertex + p.vertex_count);
    ASSERT_EQ(corners.size(), 4u);
    // a, b, b', c, d, a': five corners and two of them repeated.
    const std::vector<glm::dvec3> run{corners[0], corners[1], corners[1] + noise, corners[2], corners[3],
                                      corners[0] - noise};
    p.first_vertex = static_cast<uint32_t>(bsp.vertices.size());
    p.vertex_count = static_cast<uint32_t>(run.size());
    bsp.vertices.insert(bsp.vertices.end(), run.begin(), run.end());
    for (const bool conservative : {false, true}) {
      VisibilityOptions options;
      options.conservative = conservative;
      const VisibilityScene vis = VisibilityScene::build(bsp, options);
      const Region beside{{{12, 1}, {13, 1}, {13, 3}, {12, 3}}};
      VisibilityCounters c;
      EXPECT_TRUE(vis.visibleFromRegion(0, beside, 1.5, c)) << "noise direction " << k;
      EXPECT_GT(c.rays, 0u) << "noise direction " << k;
      EXPECT_EQ(c.kept_unproven, 0u) << "noise direction " << k;  // seen by a ray, not kept for want of a proof
      ++checked;
    }
  }
  EXPECT_EQ(checked, 16);
}

TEST(Visibility, Deterministic) {
  const Scene scene = roomGrid(5, 3);
  const BspTree bsp = buildBsp(scene);
  const VisibilityScene a = VisibilityScene::build(bsp);
  const VisibilityScene b = VisibilityScene::build(bsp);
  const Region region{{{1, 1}, {12, 1}, {12, 8}, {1, 8}}};
  for (uint32_t f = 0; f < bsp.fragments.size(); f += 3) {
    VisibilityCounters ca, cb, cc;
    const bool va = a.visibleFromRegion(f, region, 1.5, ca);
    const bool vb = b.visibleFromRegion(f, region, 1.5, cb);
    const bool vc = a.visibleFromRegion(f, region, 1.5, cc);
    EXPECT_EQ(va, vb);
    EXPECT_EQ(va, vc);
    EXPECT_EQ(ca.rays, cb.rays);
    EXPECT_EQ(ca.rays, cc.rays);
  }
  // Another seed may sample differently but counts the same way.
  VisibilityOptions other;
  other.seed = 99;
  const VisibilityScene d = VisibilityScene::build(bsp, other);
  EXPECT_EQ(d.options().seed, 99u);
}

// The witness of a "visible" answer is a point of the region, and the fragment is visible from a
// small square around it (the sub-regions the HFD build skips testing), over a room grid.
TEST(Visibility, WitnessLiesInTheRegionAndSeesTheFragment) {
  const Scene scene = roomGrid(5, 3);
  const BspTree bsp = buildBsp(scene);
  const VisibilityScene vis = VisibilityScene::build(bsp);
  const Region region{{{1, 1}, {12, 1}, {12, 8}, {1, 8}}};
  int visible = 0;
  for (uint32_t f = 0; f < bsp.fragments.size(); ++f) {
    VisibilityCounters c;
    glm::dvec2 w(-1e9);
    if (!vis.visibleFromRegion(f, region, 1.5, c, &w)) continue;
    ++visible;
    EXPECT_GE(w.x, 1.0) << f;
    EXPECT_LE(w.x, 12.0) << f;
    EXPECT_GE(w.y, 1.0) << f;
    EXPECT_LE(w.y, 8.0) << f;
    const double e = 1e-3;
    const Region around{{{w.x - e, w.y - e}, {w.x + e, w.y - e}, {w.x + e, w.y + e}, {w.x - e, w.y + e}}};
    EXPECT_TRUE(vis.visibleFromRegion(f, around, 1.5, c)) << "fragment " << f << " at (" << w.x << ", " << w.y << ")";
  }
  EXPECT_GT(visible, 10);
}

// A detail object's box (VisibilityScene::boxVisibleFromRegion): hidden behind a closed wall, seen
// through a door, never hidden from a region whose eyes may stand inside it; and over random boxes
// and regions of room grids, a box the conservative mode rejects has no clear ray to any point of
// its surface from any point of the region (brute force, 400 rays each).
TEST(Visibility, HiddenBoxHidesWhatItHolds) {
  const glm::dvec3 box_lo{12.0, 0.0, 3.0}, box_hi{13.5, 1.2, 6.0};  // in room B
  for (const bool conservative : {false, true}) {
    VisibilityOptions options;
    options.conservative = conservative;
    VisibilityCounters c;
    const TwoRooms closed = twoRooms(0.0);
    const BspTree bsp = buildBsp(closed.scene);
    const VisibilityScene vis = VisibilityScene::build(bsp, options);
    EXPECT_FALSE(vis.boxVisibleFromRegion(box_lo, box_hi, kRoomA, 1.5, c));
    EXPECT_GT(c.tests, 1u);  // face by face
    // A flat box (a panel) is tested by its two large faces.
    EXPECT_FALSE(vis.boxVisibleFromRegion({12.0, 0.0, 3.0}, {12.0, 1.2, 6.0}, kRoomA, 1.5, c));
    const Region room_b{{{10, 0}, {20, 0}, {20, 10}, {10, 10}}};
    EXPECT_TRUE(vis.boxVisibleFromRegion(box_lo, box_hi, room_b, 1.5, c));
    EXPECT_TRUE(vis.boxVisibleFromRegion({12.0, 0.0, 3.0}, {12.0, 1.2, 6.0}, room_b, 1.5, c));
    // The eye height inside the box and the region within its footprint: every eye stands behind
    // every face, so only the rule for eyes inside keeps the box.
    const Region inside{{{12.2, 3.2}, {13.3, 3.2}, {13.3, 5.8}, {12.2, 5.8}}};
    EXPECT_TRUE(vis.boxVisibleFromRegion({12.0, 0.0, 3.0}, {13.5, 2.0, 6.0}, inside, 1.5, c));
    const TwoRooms door = twoRooms(2.0);
    const BspTree bsp_door = buildBsp(door.scene);
    const VisibilityScene vis_door = VisibilityScene::build(bsp_door, options);
    EXPECT_TRUE(vis_door.boxVisibleFromRegion({12.0, 0.0, 4.0}, {13.0, 1.2, 6.0}, kRoomA, 1.5, c));
  }
  VisibilityOptions conservative;
  conservative.conservative = true;
  int rejected = 0, kept = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    const Scene scene = roomGrid(seed, 3);
    const BspTree bsp = buildBsp(scene);
    conservative.seed = seed;
    const VisibilityScene vis = VisibilityScene::build(bsp, conservative);
    std::mt19937_64 rng(seed * 91);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int trial = 0; trial < 40; ++trial) {
      const std::optional<Box> region = randomBox(rng);
      if (!region) continue;
      const glm::dvec3 lo{0.5 + 27.0 * u(rng), 0.0, 0.5 + 27.0 * u(rng)};
      const glm::dvec3 hi = lo + glm::dvec3{0.3 + 1.5 * u(rng), 0.3 + 1.0 * u(rng), 0.3 + 1.5 * u(rng)};
      VisibilityCounters c;
      if (vis.boxVisibleFromRegion(lo, hi, region->region, 1.5, c)) {
        ++kept;
        continue;
      }
      ++rejected;
      const auto [x0, x1, z0, z1] = region->bounds;
      for (int k = 0; k < 400; ++k) {
        const glm::dvec3 eye{x0 + (x1 - x0) * (0.01 + 0.98 * u(rng)), 1.5, z0 + (z1 - z0) * (0.01 + 0.98 * u(rng))};
        // A point of the box's surface: a random point inside pushed out to its nearest face.
        glm::dvec3 p = lo + (hi - lo) * glm::dvec3{u(rng), u(rng), u(rng)};
        int axis = 0;
        double best = 1e300;
        for (int a = 0; a < 3; ++a)
          for (const double side : {lo[a], hi[a]})
            if (std::abs(p[a] - side) < best) best = std::abs(p[a] - side), axis = a;
        p[axis] = std::abs(p[axis] - lo[axis]) < std::abs(p[axis] - hi[axis]) ? lo[axis] : hi[axis];
        // Stop just short of the surface, where a wall the box touches does not count.
        const glm::dvec3 to = eye + (p - eye) * (1.0 - 1e-6);
        ASSERT_TRUE(vis.occluded(eye, to)) << "seed " << seed << " trial " << trial << ": a clear ray to a rejected box";
      }
    }
  }
  EXPECT_GT(rejected, 5);
  EXPECT_GT(kept, 5);
}

TEST(Visibility, DegenerateRegionsAndBackFaces) {
  const TwoRooms r = twoRooms(0.2);
  const BspTree bsp = buildBsp(r.scene);
  const VisibilityScene vis = VisibilityScene::build(bsp);
  VisibilityCounters c;
  const uint32_t f = fragmentOf(bsp, r.back_wall);
  const Region empty_area{{{0, 0}, {5, 0}, {10, 0}}};
  EXPECT_FALSE(vis.visibleFromRegion(f, empty_area, 1.5, c));
  // Behind the back wall (x > 20) its front side cannot be seen.
  const Region behind{{{21, 0}, {30, 0}, {30, 10}, {21, 10}}};
  EXPECT_FALSE(vis.visibleFromRegion(f, behind, 1.5, c));
  EXPECT_FALSE(vis.visibleFromRegion(static_cast<uint32_t>(bsp.fragments.size()), kRoomA, 1.5, c));
}

}  // namespace
}  // namespace walkvis
