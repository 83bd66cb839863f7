// gen:hard:<name> — one small building-like scene per hard case of docs/DESIGN.md, "Hard
// cases": a 10 m × 10 m × 3 m room (floor with a level, inward walls, ceiling)
// around the hard feature, so BSP/PFD/HFD tests can validate orders on it. Each case's comment
// says what it stresses. All are deterministic and take no parameters.
//
// Every case loads except hard:nan and hard:infinite, whose loading throws Error naming
// the generator and the face ("gen:hard:nan: face N has a non-finite coordinate (...)").
// hard:zero-area loads with its degenerate faces dropped and counted in scene.report.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "scenes/generators.h"

namespace walkvis {
namespace {

using glm::dvec2;
using glm::dvec3;

constexpr double kHalf = 5.0;    // the room is [-5, 5]² in plan
constexpr double kHeight = 3.0;  // floor to ceiling

class Hard {
 public:
  Hard(Scene& scene, std::string context, dvec3 origin = dvec3(0.0))
      : scene_(scene), context_(std::move(context)), o_(origin) {}

  // A face exactly as given (after the origin shift): for the hard features themselves.
  void raw(std::vector<dvec3> v, uint32_t color = 0xc04040) {
    for (auto& p : v) p += o_;
    addFace(scene_, v, color, context_);
  }
  // A planar loop wound counter-clockwise about `facing` (reversed if it is not).
  void face(std::vector<dvec3> v, const dvec3& facing, uint32_t color = 0xc0c0c0) {
    dvec3 n(0.0);
    for (size_t i = 0; i < v.size(); ++i) n += glm::cross(v[i], v[(i + 1) % v.size()]);
    if (glm::dot(n, facing) < 0.0) std::reverse(v.begin(), v.end());
    raw(std::move(v), color);
  }
  // A vertical quad over the plan segment p → q from y0 to y1, facing towards the side of `facing`.
  void wall(dvec2 p, dvec2 q, double y0, double y1, const dvec3& facing, uint32_t color = 0xd8d0c0) {
    face({{p.x, y0, p.y}, {q.x, y0, q.y}, {q.x, y1, q.y}, {p.x, y1, p.y}}, facing, color);
  }
  // A horizontal rectangle at height y.
  void horizontal(double x0, double x1, double z0, double z1, double y, bool up, uint32_t color) {
    face({{x0, y, z0}, {x1, y, z0}, {x1, y, z1}, {x0, y, z1}}, dvec3(0, up ? 1 : -1, 0), color);
  }
  // Outward sides and top of a box standing on y0.
  void box(double x0, double x1, double z0, double z1, double y0, double y1, uint32_t color = 0xa0703c) {
    wall({x0, z0}, {x0, z1}, y0, y1, {-1, 0, 0}, color);
    wall({x1, z0}, {x1, z1}, y0, y1, {1, 0, 0}, color);
    wall({x0, z0}, {x1, z0}, y0, y1, {0, 0, -1}, color);
    wall({x0, z1}, {x1, z1}, y0, y1, {0, 0, 1}, color);
    horizontal(x0, x1, z0, z1, y1, true, color);
  }
  // The four inward walls and the ceiling of the room; the floor is left to the case.
  void roomShell() {
    wall({-kHalf, -kHalf}, {kHalf, -kHalf}, 0, kHeight, {0, 0, 1});
    wall({-kHalf, kHalf}, {kHalf, kHalf}, 0, kHeight, {0, 0, -1});
    wall({-kHalf, -kHalf}, {-kHalf, kHalf}, 0, kHeight, {1, 0, 0});
    wall({kHalf, -kHalf}, {kHalf, kHalf}, 0, kHeight, {-1, 0, 0});
    horizontal(-kHalf, kHalf, -kHalf, kHalf, kHeight, false, 0xf0f0ec);
  }
  void room() {
    roomShell();
    horizontal(-kHalf, kHalf, -kHalf, kHalf, 0.0, true, 0x8a6f55);
  }
  // The level at the room's floor: these plan rectangles (x0, x1, z0, z1), shifted by the origin.
  void level(const std::vector<std::array<double, 4>>& rects) {
    FloorLevel lv;
    lv.floor_y = o_.y;
    for (const auto& r : rects) {
      const double x0 = r[0] + o_.x, x1 = r[1] + o_.x, z0 = r[2] + o_.z, z1 = r[3] + o_.z;
      lv.walkable.push_back({{x0, z0}, {x0, z1}, {x1, z1}, {x1, z0}});  // counter-clockwise from above
      lv.walkable_area += (r[1] - r[0]) * (r[3] - r[2]);
    }
    scene_.levels.push_back(std::move(lv));
  }
  void start(double x, double z, double yaw = 0.0) {
    scene_.start_eye = o_ + dvec3(x, scene_.eye_height, z);
    scene_.start_yaw = yaw;
  }

 private:
  Scene& scene_;
  std::string context_;
  dvec3 o_;
};

const std::array<double, 4> kWholeFloor{-kHalf, kHalf, -kHalf, kHalf};

// Coplanar and overlapping polygons in both orientations: a poster on a wall facing the same
// way, one in the wall's plane facing the other way, a free-standing partition made of two
// coincident faces back to back, two panels overlapping half-way, and a rug on the floor. The
// BSP keeps coplanar polygons at one node; ties in the exact image are tie_pixels.
void coplanar(Hard& h) {
  h.room();
  h.face({{-1, 1, -kHalf}, {1, 1, -kHalf}, {1, 2, -kHalf}, {-1, 2, -kHalf}}, {0, 0, 1}, 0x4060c0);
  h.face({{2, 1, -kHalf}, {4, 1, -kHalf}, {4, 2, -kHalf}, {2, 2, -kHalf}}, {0, 0, -1}, 0x40c060);
  h.wall({0, -1}, {0, 2}, 0, 2.5, {1, 0, 0}, 0xc06040);
  h.wall({0, -1}, {0, 2}, 0, 2.5, {-1, 0, 0}, 0x6040c0);
  h.wall({-3, 2}, {-1, 2}, 0, 2, {0, 0, -1}, 0xc0c040);
  h.wall({-2, 2}, {0, 2}, 0.5, 2.5, {0, 0, -1}, 0x40c0c0);
  h.horizontal(1, 3, 1, 3, 0.0, true, 0x803030);
  h.level({kWholeFloor});
  h.start(2.5, 4);
}

// T-junctions: wall pieces and floor tiles whose corners lie on the edges of their neighbours
// (no shared vertex), a pillar whose sides are cut at different heights, and a wall face with
// an extra vertex in the middle of an edge (a collinear corner). Rasterizers leave cracks at
// T-junctions; the exact image must not.
void tJunctions(Hard& h) {
  h.wall({-kHalf, -kHalf}, {0, -kHalf}, 0, kHeight, {0, 0, 1});
  h.wall({0, -kHalf}, {kHalf, -kHalf}, 0, 1, {0, 0, 1}, 0xc8c0b0);
  h.wall({0, -kHalf}, {kHalf, -kHalf}, 1, kHeight, {0, 0, 1}, 0xb8b0a0);
  h.wall({-kHalf, kHalf}, {kHalf, kHalf}, 0, kHeight, {0, 0, -1});
  h.wall({-kHalf, -kHalf}, {-kHalf, kHalf}, 0, kHeight, {1, 0, 0});
  // East wall: a pentagon with a vertex in the middle of its bottom edge.
  h.face({{kHalf, 0, -kHalf}, {kHalf, 0, 0}, {kHalf, 0, kHalf}, {kHalf, kHeight, kHalf}, {kHalf, kHeight, -kHalf}},
         {-1, 0, 0});
  h.horizontal(-kHalf, kHalf, -kHalf, kHalf, kHeight, false, 0xf0f0ec);
  h.horizontal(-kHalf, 0, -kHalf, kHalf, 0.0, true, 0x8a6f55);
  h.horizontal(0, kHalf, -kHalf, 0, 0.0, true, 0x7a5f45);
  h.horizontal(0, kHalf, 0, kHalf, 0.0, true, 0x9a7f65);
  // A pillar at [1.5, 2] × [1.5, 2]: each side in strips cut at different heights.
  const double cuts[4][3] = {{0, 1, 3}, {0, 1.5, 3}, {0, 2, 3}, {0, 0.5, 3}};
  const dvec2 c[4] = {{1.5, 1.5}, {2, 1.5}, {2, 2}, {1.5, 2}};
  const dvec3 out[4] = {{0, 0, -1}, {1, 0, 0}, {0, 0, 1}, {-1, 0, 0}};
  for (int s = 0; s < 4; ++s) {
    for (int k = 0; k < 2; ++k) {
      h.wall(c[s], c[(s + 1) % 4], cuts[s][k], cuts[s][k + 1], out[s], 0x909090 + 0x101010 * k);
    }
  }
  h.level({{-kHalf, 0, -kHalf, kHalf}, {0, kHalf, -kHalf, 0}, {0, kHalf, 0, kHalf}});
  h.start(-2, 2);
}

// Slivers with an area of 1e-9 of the scene's (10 m)² = 1e-7 m²: a 4 m needle 5e-8 m high, a
// 3 m high strip 3.3e-8 m wide seen edge-on from most eyes, a skew needle, and a horizontal
// needle at table height. They must neither crash the splitter nor be lost by it while visible.
void slivers(Hard& h) {
  h.room();
  h.face({{-2, 1, 0}, {2, 1, 0}, {0, 1 + 5e-8, 0}}, {0, 0, 1}, 0xff0000);
  h.wall({1, -2}, {1, -2 + 1e-7 / 3.0}, 0, 3, {1, 0, 0}, 0x00ff00);
  const dvec3 a(-3, 0.5, -3), b(3, 2, -2);
  const dvec3 along = b - a, across = glm::normalize(glm::cross(along, dvec3(0, 1, 0)));
  const dvec3 apex = 0.5 * (a + b) + (2e-7 / glm::length(along)) * glm::cross(across, glm::normalize(along));
  h.face({a, b, apex}, across, 0x0000ff);
  h.face({{-3, 0.75, 2}, {3, 0.75, 2}, {0, 0.75, 2 + 3.3e-8}}, {0, 1, 0}, 0xffff00);
  h.level({kWholeFloor});
  h.start(0, 3);
}

// Planes within 1e-12 rad of parallel: two walls end to end in planes 1e-12 rad apart (B's
// plane passes through A's end); two parallel-looking walls 0.5 m apart whose planes meet 5e11 m
// away; a table top tilted 1e-12 rad from horizontal (is it horizontal, and on which side of the
// height plane?); two overlapping walls rotated 1e-12 rad against each other about their middle,
// so their planes cross inside the scene.
void nearParallel(Hard& h) {
  h.room();
  const double tilt = std::tan(1e-12);
  h.wall({-4, -1}, {0, -1}, 0, 2.5, {0, 0, 1}, 0xc04040);
  h.wall({0, -1}, {4, -1 + 4 * tilt}, 0, 2.5, {0, 0, 1}, 0x40c040);
  h.wall({-4, 1}, {4, 1}, 0, 1, {0, 0, 1}, 0x4040c0);
  h.wall({-4, 1.5 - 4 * tilt}, {4, 1.5 + 4 * tilt}, 0, 2, {0, 0, 1}, 0xc0c040);
  // Table top at 0.75 m tilted about z; the legs are left out, the sides follow the tilt.
  const double x0 = 2, x1 = 4, z0 = 2.5, z1 = 3.5;
  const double y0 = 0.75, y1 = 0.75 + (x1 - x0) * tilt;
  h.face({{x0, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x0, y0, z1}}, {0, 1, 0}, 0xa0703c);
  h.face({{x0, 0, z0}, {x1, 0, z0}, {x1, y1, z0}, {x0, y0, z0}}, {0, 0, -1}, 0xa0703c);
  h.face({{x0, 0, z1}, {x1, 0, z1}, {x1, y1, z1}, {x0, y0, z1}}, {0, 0, 1}, 0xa0703c);
  h.wall({x0, z0}, {x0, z1}, 0, y0, {-1, 0, 0}, 0xa0703c);
  h.wall({x1, z0}, {x1, z1}, 0, y1, {1, 0, 0}, 0xa0703c);
  // Two walls over the same segment, one rotated 1e-12 rad about its middle (x = -2, z = 3).
  h.wall({-4, 3}, {0, 3}, 0, 2, {0, 0, -1}, 0x40c0c0);
  h.wall({-4, 3 - 2 * tilt}, {0, 3 + 2 * tilt}, 0, 2, {0, 0, -1}, 0xc040c0);
  h.level({kWholeFloor});
  h.start(-2, 4.5);
}

// A plane through many vertices: eight walls radiating from one vertical edge (every wall's
// plane holds two vertices of every other, and opposite walls are coplanar), and six boxes whose
// -z sides lie in the plane z = -3 of a wall elsewhere in the room (48 vertices on that plane,
// coplanar faces in the opposite orientation). Classification must be exactly "on" for all.
void planeThroughVertices(Hard& h) {
  h.room();
  // Directions with exact coordinates, so that opposite walls are exactly coplanar.
  const dvec2 dirs[8] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
  for (int k = 0; k < 8; ++k) {
    const dvec2 p(-2, 1), q = p + 1.5 * dirs[k];
    const dvec3 facing(-dirs[k].y, 0, dirs[k].x);  // towards the counter-clockwise neighbour
    h.wall(p, q, 0, 2.2, facing, 0x404040 + 0x101010 * static_cast<uint32_t>(k));
  }
  h.wall({-4.5, -3}, {-3.5, -3}, 0, 2.5, {0, 0, 1}, 0xc04040);
  for (int k = 0; k < 6; ++k) {
    const double x = -2.5 + 1.0 * k;
    h.box(x, x + 0.5, -3, -2.5, 0, 0.5 + 0.25 * k);
  }
  h.level({kWholeFloor});
  h.start(3, 3);
}

// Polygons in the height plane y = floor + eye height (1.7): a shelf top facing up and its
// underside facing down at exactly 1.7, a hanging panel whose bottom edge and a low panel whose
// top edge lie in the plane, a sign at 1.7 over the middle of the walkable region (eyes inside
// its polygon), and a sloped triangle touching the plane at one vertex. Seen edge-on from every
// eye: the test-line of a horizontal plane is not a line.
void heightPlanePolygons(Hard& h) {
  const double e = 1.7;
  h.room();
  h.horizontal(-4, -2, -4.5, -3.5, e, true, 0xc04040);
  h.horizontal(-4, -2, -4.5, -3.5, e, false, 0x40c040);
  h.wall({1, -2}, {3, -2}, e, kHeight, {0, 0, 1}, 0x4040c0);
  h.wall({1, 2}, {3, 2}, 0, e, {0, 0, -1}, 0xc0c040);
  h.horizontal(-1, 1, -1, 1, e, false, 0x40c0c0);
  h.face({{-4, 0.5, 1}, {-2, 0.5, 1}, {-3, e, 3}}, {0, 1, -1}, 0xc040c0);
  h.level({kWholeFloor});
  h.start(3, 3);
}

// Test-lines through region corners: an L-shaped walkable region in two pieces, walls on the
// lines z = 0 and x = 0 that run through piece corners, and walls on the diagonals x = z and
// x = -z that pass (mathematically) through corners (-5,-5), (0,0), (5,5) and (-5,5). Deciding
// the side of a region whose corner lies on the line needs exact arithmetic (docs/DESIGN.md,
// "Sizes and errors": 1–16% of decisions in Doom maps).
void cornerTestLines(Hard& h) {
  h.wall({-kHalf, -kHalf}, {0, -kHalf}, 0, kHeight, {0, 0, 1});
  h.wall({0, -kHalf}, {0, 0}, 0, kHeight, {-1, 0, 0});
  h.wall({0, 0}, {kHalf, 0}, 0, kHeight, {0, 0, 1});
  h.wall({kHalf, 0}, {kHalf, kHalf}, 0, kHeight, {-1, 0, 0});
  h.wall({-kHalf, kHalf}, {kHalf, kHalf}, 0, kHeight, {0, 0, -1});
  h.wall({-kHalf, -kHalf}, {-kHalf, kHalf}, 0, kHeight, {1, 0, 0});
  h.horizontal(-kHalf, 0, -kHalf, kHalf, 0.0, true, 0x8a6f55);
  h.horizontal(0, kHalf, 0, kHalf, 0.0, true, 0x8a6f55);
  h.horizontal(-kHalf, 0, -kHalf, kHalf, kHeight, false, 0xf0f0ec);
  h.horizontal(0, kHalf, 0, kHalf, kHeight, false, 0xf0f0ec);
  h.wall({-4, 0}, {-2, 0}, 0, 2, {0, 0, 1}, 0xc04040);
  h.wall({0, 2}, {0, 3}, 0, 2, {1, 0, 0}, 0x40c040);
  h.wall({-3, -3}, {-1, -1}, 0, 2, {1, 0, -1}, 0x4040c0);
  h.wall({-4, 4}, {-3, 3}, 0, 2, {1, 0, 1}, 0xc0c040);
  h.wall({3, 3}, {4, 4}, 0, 2, {-1, 0, 1}, 0x40c0c0);
  h.level({{-kHalf, 0, -kHalf, kHalf}, {0, kHalf, 0, kHalf}});
  h.start(-2.5, 3.5);
}

// Vertical walls whose plane contains the eye path: the eye starts on x = 0 and looks (and
// walks) along -z, straight at a free-standing two-sided wall in the plane x = 0 and under a
// beam in the same plane; the walkable region is split along x = 0 as well; and a wall on the
// diagonal x = z lies on the path from corner to corner. Every eye on the path sees these walls
// edge-on and is "on" their test-lines.
void wallContainsEyePath(Hard& h) {
  h.roomShell();
  h.horizontal(-kHalf, 0, -kHalf, kHalf, 0.0, true, 0x8a6f55);
  h.horizontal(0, kHalf, -kHalf, kHalf, 0.0, true, 0x7a5f45);
  h.wall({0, -4}, {0, -2}, 0, 2.5, {1, 0, 0}, 0xc04040);
  h.wall({0, -4}, {0, -2}, 0, 2.5, {-1, 0, 0}, 0x40c040);
  h.wall({0, 0}, {0, 2}, 2.2, kHeight, {1, 0, 0}, 0x4040c0);
  h.wall({2, 2}, {3, 3}, 0, 2.5, {1, 0, -1}, 0xc0c040);
  h.level({{-kHalf, 0, -kHalf, kHalf}, {0, kHalf, -kHalf, kHalf}});
  h.start(0, 4);
}

// Coordinates near 1e6 with features of 1e-3: the whole room sits at (1e6, 1e6, 1e6); inside it
// a wall 1 mm thick (two faces 1e-3 apart with end caps and a top), two panels 1 mm apart in one
// plane, and a platform 1 mm high. Floats cannot hold these (their step at 1e6 is 0.0625), so
// renderers must subtract an origin; doubles have ~1e-10 to spare.
void farCoordinates(Hard& h) {
  h.room();
  const double mm = 1e-3;
  h.wall({-2, 0}, {2, 0}, 0, 2, {0, 0, -1}, 0xc04040);
  h.wall({-2, mm}, {2, mm}, 0, 2, {0, 0, 1}, 0x40c040);
  h.wall({-2, 0}, {-2, mm}, 0, 2, {-1, 0, 0}, 0x4040c0);
  h.wall({2, 0}, {2, mm}, 0, 2, {1, 0, 0}, 0x4040c0);
  h.horizontal(-2, 2, 0, mm, 2, true, 0x4040c0);
  h.wall({-4, -3}, {-1, -3}, 0, 2.5, {0, 0, 1}, 0xc0c040);
  h.wall({-1 + mm, -3}, {2, -3}, 0, 2.5, {0, 0, 1}, 0x40c0c0);
  h.box(1, 3, 1, 3, 0, mm, 0xc040c0);
  h.level({kWholeFloor});
  h.start(-3, 4);
}

// Non-planar and non-convex input faces, which addFace splits: a U-shaped floor and ceiling
// (the room has a notch), a north wall with a niche cut out of it (one concave face), a twisted
// quad whose corner is 0.3 m out of plane, and a warped star.
void nonplanarNonconvex(Hard& h) {
  const double n0 = -2, n1 = 2;  // the notch [-2, 2] × [0, 5] is outside the room
  const std::vector<dvec3> u_floor{{-kHalf, 0, -kHalf}, {kHalf, 0, -kHalf}, {kHalf, 0, kHalf}, {n1, 0, kHalf},
                                   {n1, 0, 0},          {n0, 0, 0},         {n0, 0, kHalf},    {-kHalf, 0, kHalf}};
  h.face(u_floor, {0, 1, 0}, 0x8a6f55);
  std::vector<dvec3> u_ceiling = u_floor;
  for (auto& p : u_ceiling) p.y = kHeight;
  h.face(u_ceiling, {0, -1, 0}, 0xf0f0ec);
  // North wall with a niche opening [-1, 1] × [0, 2.1]: one concave face.
  h.face({{-kHalf, 0, -kHalf},
          {-1, 0, -kHalf},
          {-1, 2.1, -kHalf},
          {1, 2.1, -kHalf},
          {1, 0, -kHalf},
          {kHalf, 0, -kHalf},
          {kHalf, kHeight, -kHalf},
          {-kHalf, kHeight, -kHalf}},
         {0, 0, 1});
  h.wall({-1, -6}, {1, -6}, 0, 2.1, {0, 0, 1}, 0xb8b0a0);
  h.wall({-1, -6}, {-1, -kHalf}, 0, 2.1, {1, 0, 0}, 0xb8b0a0);
  h.wall({1, -6}, {1, -kHalf}, 0, 2.1, {-1, 0, 0}, 0xb8b0a0);
  h.horizontal(-1, 1, -6, -kHalf, 2.1, false, 0xb8b0a0);
  h.horizontal(-1, 1, -6, -kHalf, 0.0, true, 0x8a6f55);
  h.wall({-kHalf, -kHalf}, {-kHalf, kHalf}, 0, kHeight, {1, 0, 0});
  h.wall({kHalf, -kHalf}, {kHalf, kHalf}, 0, kHeight, {-1, 0, 0});
  h.wall({-kHalf, kHalf}, {n0, kHalf}, 0, kHeight, {0, 0, -1});
  h.wall({n1, kHalf}, {kHalf, kHalf}, 0, kHeight, {0, 0, -1});
  h.wall({n0, 0}, {n0, kHalf}, 0, kHeight, {-1, 0, 0});
  h.wall({n1, 0}, {n1, kHalf}, 0, kHeight, {1, 0, 0});
  h.wall({n0, 0}, {n1, 0}, 0, kHeight, {0, 0, -1});
  // Twisted quad: the top right corner is pushed 0.3 m off the plane z = -2.
  h.raw({{1, 0, -2}, {3, 0, -2}, {3, 2, -2.3}, {1, 2, -2}}, 0xc04040);
  // Warped star: 5 points, alternate radii, the inner corners 0.1 m off the plane x = -4.
  std::vector<dvec3> star;
  for (int k = 0; k < 10; ++k) {
    const double a = M_PI / 5.0 * k, r = k % 2 == 0 ? 1.0 : 0.4;
    star.push_back({-4 + (k % 2 == 0 ? 0.0 : 0.1), 1.5 + r * std::sin(a), -2 + r * std::cos(a)});
  }
  h.raw(star, 0x40c040);
  h.level({{-kHalf, n0, -kHalf, kHalf}, {n1, kHalf, -kHalf, kHalf}, {n0, n1, -kHalf, 0}});
  h.start(-3.5, 3);
}

// Zero-area faces next to valid ones: three collinear points, four equal points, a face of two
// vertices, a back-and-forth loop (a, b, a, b), four collinear points, and a valid triangle with
// a repeated vertex (kept). addFace drops and counts the degenerate ones (report.dropped_*).
void zeroArea(Hard& h) {
  h.room();
  h.raw({{0, 0, 0}, {0, 1, 0}, {0, 2, 0}});
  h.raw({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}, {1, 1, 1}});
  h.raw({{1, 0, 1}, {1, 2, 1}});
  h.raw({{2, 0, 2}, {2, 2, 2}, {2, 0, 2}, {2, 2, 2}});
  h.raw({{-1, 0.5, -1}, {0, 0.5, 0}, {1, 0.5, 1}, {2, 0.5, 2}});
  h.raw({{-3, 0, -3}, {-3, 0, -3}, {-2, 0, -3}, {-2, 2, -3}}, 0x40c040);
  h.level({kWholeFloor});
  h.start(3, 3);
}

// Non-finite input: a valid room and one face with a NaN (or an infinite) coordinate. Loading
// must throw Error that names the generator and the face, never crash or produce a scene.
void nonFinite(Hard& h, double bad) {
  h.room();
  h.raw({{0, 0, 0}, {1, 0, 0}, {1, bad, 0}});
  h.level({kWholeFloor});
  h.start(3, 3);
}

}  // namespace

std::vector<std::string> hardCaseNames() {
  return {"hard:coplanar",         "hard:t-junctions",       "hard:slivers",
          "hard:near-parallel",    "hard:plane-through-vertices", "hard:height-plane-polygons",
          "hard:corner-test-lines", "hard:wall-contains-eye-path", "hard:far-coordinates",
          "hard:nonplanar-nonconvex", "hard:zero-area",      "hard:nan",
          "hard:infinite"};
}

Scene generateHardCase(const std::string& name, GeneratorParams& params) {
  const std::string base = name.rfind("hard:", 0) == 0 ? name.substr(5) : name;
  const std::string context = params.generator();
  Scene scene;
  scene.name = "gen:hard:" + base;
  const bool far = base == "far-coordinates";
  Hard h(scene, context, far ? dvec3(1e6) : dvec3(0.0));
  if (base == "coplanar") {
    coplanar(h);
  } else if (base == "t-junctions") {
    tJunctions(h);
  } else if (base == "slivers") {
    slivers(h);
  } else if (base == "near-parallel") {
    nearParallel(h);
  } else if (base == "plane-through-vertices") {
    planeThroughVertices(h);
  } else if (base == "height-plane-polygons") {
    heightPlanePolygons(h);
  } else if (base == "corner-test-lines") {
    cornerTestLines(h);
  } else if (base == "wall-contains-eye-path") {
    wallContainsEyePath(h);
  } else if (far) {
    farCoordinates(h);
  } else if (base == "nonplanar-nonconvex") {
    nonplanarNonconvex(h);
  } else if (base == "zero-area") {
    zeroArea(h);
  } else if (base == "nan") {
    nonFinite(h, std::numeric_limits<double>::quiet_NaN());
  } else if (base == "infinite") {
    nonFinite(h, std::numeric_limits<double>::infinity());
  } else {
    std::string known;
    for (const auto& n : hardCaseNames()) known += (known.empty() ? "" : ", ") + n;
    throw Error(context + ": unknown hard case '" + base + "' (known: " + known + ")");
  }
  return scene;
}

}  // namespace walkvis
