// Small buildings whose floors the navmesh (walkable.h) derives: they leave Scene::levels empty.
//  gen:table_room  one room with a table on four legs and chairs (solid seats with a back)
//  gen:house       two storeys; a straight solid stair along the z = 0 wall rises through an
//                  opening in the upper floor, as long as the stair unless `opening` (m, measured
//                  back from the top riser) is shorter: then the slab covers the lower treads
//  gen:ramp        a low floor and a high floor joined by a ramp over the room's full width
// Metres, y up. As in gen:office only what is seen from inside is modelled (docs/DESIGN.md, "Model only
// what a scene needs"): floors facing up, ceilings down, walls into the room, furniture and stair
// blocks outwards, so the inside is closed to every eye while T-junctions remain where a wall
// meets a floor.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "scenes/generators.h"

namespace walkvis {
namespace {

constexpr uint32_t kFloorColor = 0x8a6f55;
constexpr uint32_t kCeilingColor = 0xf0f0ec;
constexpr uint32_t kWallColor = 0xd8d0c0;
constexpr uint32_t kTableColor = 0xa0703c;
constexpr uint32_t kChairColor = 0x6c7a8a;
constexpr uint32_t kStairColor = 0xb09070;
constexpr uint32_t kSlabColor = 0x9a9a9a;

class Out {
 public:
  Out(Scene& scene, std::string context) : scene_(scene), context_(std::move(context)) {}

  // A planar polygon wound to face `facing` (its Newell normal is turned towards it).
  void face(std::vector<glm::dvec3> v, const glm::dvec3& facing, uint32_t color) {
    if (glm::dot(newellPlane(v).n, facing) < 0.0) std::reverse(v.begin(), v.end());
    addFace(scene_, v, color, context_);
  }

  // An axis-aligned rectangle given by two opposite corners that differ in two coordinates; the
  // one they share is the axis of `facing`. Nothing when it is thinner than 1e-9 m (an opening
  // flush with a side).
  void rect(const glm::dvec3& a, const glm::dvec3& c, const glm::dvec3& facing, uint32_t color) {
    const glm::dvec3 e = c - a;
    glm::dvec3 b = a, d = a;
    if (facing.x != 0.0) {
      if (std::abs(e.y) < 1e-9 || std::abs(e.z) < 1e-9) return;
      b.y = c.y, d.z = c.z;
    } else if (facing.y != 0.0) {
      if (std::abs(e.x) < 1e-9 || std::abs(e.z) < 1e-9) return;
      b.x = c.x, d.z = c.z;
    } else {
      if (std::abs(e.x) < 1e-9 || std::abs(e.y) < 1e-9) return;
      b.x = c.x, d.y = c.y;
    }
    face({a, b, c, d}, facing, color);
  }

  // A box seen from outside: four sides, the top when asked and the bottom when asked.
  void box(double x0, double x1, double y0, double y1, double z0, double z1, bool top, bool bottom, uint32_t color) {
    rect({x0, y0, z0}, {x0, y1, z1}, {-1, 0, 0}, color);
    rect({x1, y0, z0}, {x1, y1, z1}, {1, 0, 0}, color);
    rect({x0, y0, z0}, {x1, y1, z0}, {0, 0, -1}, color);
    rect({x0, y0, z1}, {x1, y1, z1}, {0, 0, 1}, color);
    if (top) rect({x0, y1, z0}, {x1, y1, z1}, {0, 1, 0}, color);
    if (bottom) rect({x0, y0, z0}, {x1, y0, z1}, {0, -1, 0}, color);
  }

  // A room's four walls from y0 to y1, facing in.
  void walls(double x0, double x1, double z0, double z1, double y0, double y1) {
    rect({x0, y0, z0}, {x0, y1, z1}, {1, 0, 0}, kWallColor);
    rect({x1, y0, z0}, {x1, y1, z1}, {-1, 0, 0}, kWallColor);
    rect({x0, y0, z0}, {x1, y1, z0}, {0, 0, 1}, kWallColor);
    rect({x0, y0, z1}, {x1, y1, z1}, {0, 0, -1}, kWallColor);
  }

 private:
  Scene& scene_;
  std::string context_;
};

}  // namespace

Scene generateTableRoom(GeneratorParams& params) {
  const double w = params.getDouble("width", 6.0, 3.0, 50.0);
  const double d = params.getDouble("depth", 5.0, 3.0, 50.0);
  const double h = params.getDouble("height", 2.7, 2.2, 10.0);
  const double th = params.getDouble("table_height", 0.75, 0.3, 1.5);
  const int64_t chairs = params.getInt("chairs", 2, 0, 4);
  Scene scene;
  Out out(scene, params.generator());
  out.rect({0, 0, 0}, {w, 0, d}, {0, 1, 0}, kFloorColor);
  out.rect({0, h, 0}, {w, h, d}, {0, -1, 0}, kCeilingColor);
  out.walls(0, w, 0, d, 0, h);
  // The table: 1.6 × 0.9 m, centred; a 4 cm top on 6 cm legs set 5 cm in from its corners.
  const double tx0 = 0.5 * w - 0.8, tx1 = 0.5 * w + 0.8, tz0 = 0.5 * d - 0.45, tz1 = 0.5 * d + 0.45;
  out.box(tx0, tx1, th - 0.04, th, tz0, tz1, true, true, kTableColor);
  for (double lx : {tx0 + 0.05, tx1 - 0.11})
    for (double lz : {tz0 + 0.05, tz1 - 0.11}) out.box(lx, lx + 0.06, 0.0, th - 0.04, lz, lz + 0.06, false, false, kTableColor);
  // Chairs: a solid 45 cm seat with a back, 35 cm from the table's long sides.
  for (int64_t c = 0; c < chairs; ++c) {
    const double cx = (c / 2 == 0 ? 0.5 * w - 0.4 : 0.5 * w + 0.4) - 0.225;
    const bool north = c % 2 == 0;
    const double cz0 = north ? tz0 - 0.35 - 0.45 : tz1 + 0.35;
    out.box(cx, cx + 0.45, 0.0, 0.45, cz0, cz0 + 0.45, true, false, kChairColor);
    const double bz0 = north ? cz0 : cz0 + 0.4;
    out.box(cx, cx + 0.45, 0.45, 0.9, bz0, bz0 + 0.05, true, false, kChairColor);
  }
  scene.start_eye = {0.8, scene.eye_height, d - 0.8};
  scene.start_yaw = 0.0;
  return scene;
}

Scene generateHouse(GeneratorParams& params) {
  const double w = params.getDouble("width", 8.0, 6.0, 40.0);
  const double d = params.getDouble("depth", 6.0, 5.0, 40.0);
  const double storey = params.getDouble("storey", 3.0, 2.6, 5.0);  // floor to floor
  const double slab = params.getDouble("slab", 0.2, 0.1, 0.5);
  const double sw = params.getDouble("stair_width", 1.2, 0.8, 3.0);
  const int64_t steps = params.getInt("steps", 16, 4, 40);  // risers
  const double tread = params.getDouble("tread", 0.28, 0.2, 0.5);
  const std::string& g = params.generator();
  const double xs = 1.0;                                     // first riser
  const double xe = xs + static_cast<double>(steps - 1) * tread;  // last riser, top of the stair
  if (xe > w - 1.0) throw Error(g + ": the stair (" + std::to_string(xe - xs) + " m) does not fit the width");
  if (sw > d - 2.0) throw Error(g + ": the stair is too wide for the depth");
  // Up to the stair's length; a shorter opening leaves the lower treads under the slab, with
  // less headroom the further up they are (FZK-Haus's spiral stair is built that way).
  const double opening = params.getDouble("opening", xe - xs, 0.5, xe - xs);
  const double xc = xs + ((xe - xs) - opening);  // the slab's edge over the stair; xs exactly by default
  const double r = storey / static_cast<double>(steps);
  const double ceil0 = storey - slab, ceil1 = 2.0 * storey - slab;
  Scene scene;
  Out out(scene, g);
  // Ground floor and its ceiling, the upper floor and its ceiling; the stair's footprint is cut
  // out of the ground floor (the stair block is solid) and of the slab (the opening).
  // The slab's pieces are the ground floor's but for the one before the stair, which reaches to xc.
  using Rects = std::array<std::array<double, 4>, 3>;
  const Rects ground = {{{0, w, sw, d}, {0, xs, 0, sw}, {xe, w, 0, sw}}};
  const Rects slab_around = {{{0, w, sw, d}, {0, xc, 0, sw}, {xe, w, 0, sw}}};
  for (size_t i = 0; i < ground.size(); ++i) {
    const auto& q = ground[i];
    const auto& u = slab_around[i];
    out.rect({q[0], 0, q[2]}, {q[1], 0, q[3]}, {0, 1, 0}, kFloorColor);
    out.rect({u[0], ceil0, u[2]}, {u[1], ceil0, u[3]}, {0, -1, 0}, kCeilingColor);
    out.rect({u[0], storey, u[2]}, {u[1], storey, u[3]}, {0, 1, 0}, kFloorColor);
  }
  out.rect({0, ceil1, 0}, {w, ceil1, d}, {0, -1, 0}, kCeilingColor);
  out.walls(0, w, 0, d, 0, ceil1);
  // The opening's edges (the one at x = xe is the last riser).
  out.rect({xc, ceil0, 0}, {xc, storey, sw}, {1, 0, 0}, kSlabColor);
  out.rect({xc, ceil0, sw}, {xe, storey, sw}, {0, 0, -1}, kSlabColor);
  // The stair: treads, risers and the open side, then the block's back under the slab.
  for (int64_t k = 1; k <= steps; ++k) {
    const double x0 = xs + static_cast<double>(k - 1) * tread, x1 = x0 + tread;
    const double y0 = static_cast<double>(k - 1) * r, y1 = k == steps ? storey : static_cast<double>(k) * r;
    out.rect({x0, y0, 0}, {x0, y1, sw}, {-1, 0, 0}, kStairColor);
    if (k == steps) break;
    out.rect({x0, y1, 0}, {x1, y1, sw}, {0, 1, 0}, kStairColor);
    out.rect({x0, 0, sw}, {x1, y1, sw}, {0, 0, 1}, kStairColor);
  }
  out.rect({xe, 0, 0}, {xe, ceil0, sw}, {1, 0, 0}, kStairColor);
  scene.start_eye = {0.5 * w, scene.eye_height, 0.5 * (sw + d)};
  scene.start_yaw = 0.0;
  return scene;
}

Scene generateRamp(GeneratorParams& params) {
  const double wz = params.getDouble("width", 4.0, 2.0, 40.0);
  const double l1 = params.getDouble("low_length", 4.0, 2.0, 40.0);
  const double l2 = params.getDouble("ramp_length", 3.0, 1.0, 40.0);
  const double l3 = params.getDouble("high_length", 3.0, 2.0, 40.0);
  const double rise = params.getDouble("rise", 0.9, 0.05, 5.0);
  const double h = params.getDouble("height", 3.5, 2.2, 20.0);
  const std::string& g = params.generator();
  // The walker takes faces steeper than acos(kWallMaxNormalY = 0.9) ≈ 25.8° for walls; 24° keeps
  // the ramp a floor with a margin.
  if (std::atan2(rise, l2) > 24.0 * M_PI / 180.0) throw Error(g + ": the ramp is steeper than 24 degrees");
  if (h - rise < 2.2) throw Error(g + ": the height leaves less than 2.2 m over the high floor");
  const double xa = l1, xb = l1 + l2, xc = l1 + l2 + l3;
  Scene scene;
  Out out(scene, g);
  out.rect({0, 0, 0}, {xa, 0, wz}, {0, 1, 0}, kFloorColor);
  out.face({{xa, 0, 0}, {xa, 0, wz}, {xb, rise, wz}, {xb, rise, 0}}, {0, 1, 0}, kFloorColor);
  out.rect({xb, rise, 0}, {xc, rise, wz}, {0, 1, 0}, kFloorColor);
  out.rect({0, h, 0}, {xc, h, wz}, {0, -1, 0}, kCeilingColor);
  out.rect({0, 0, 0}, {0, h, wz}, {1, 0, 0}, kWallColor);
  out.rect({xc, rise, 0}, {xc, h, wz}, {-1, 0, 0}, kWallColor);
  for (const double z : {0.0, wz}) {
    const glm::dvec3 in(0, 0, z == 0.0 ? 1.0 : -1.0);
    out.rect({0, 0, z}, {xa, h, z}, in, kWallColor);
    out.face({{xa, 0, z}, {xb, rise, z}, {xb, h, z}, {xa, h, z}}, in, kWallColor);
    out.rect({xb, rise, z}, {xc, h, z}, in, kWallColor);
  }
  scene.start_eye = {1.0, scene.eye_height, 0.5 * wz};
  scene.start_yaw = -0.5 * M_PI;  // looking along +x, up the ramp
  return scene;
}

}  // namespace walkvis
