// gen:office — a parametric office building, the default and main benchmark scene.
//
// Plan (per storey, in metres, y up): `rooms` room cells of room_size × room_size on a grid, in
// bays along +z. Each bay is a row of cells (north), a corridor along +x, and a row of cells
// (south); neighbouring bays share the wall between their rows. A lobby runs along z on the west
// side (x < 0) and every corridor opens into it over its full width. Walls are `thickness` thick
// and centred on the grid lines, so every space (room, corridor, lobby) is the rectangle between
// the inner wall faces. Neighbouring cells of a row are merged into open-plan rooms of 2–3 cells
// at random (pillars stand where the partition walls would be); each room has a door to its
// corridor and sometimes one to its neighbour in the row. Storeys repeat the plan (with their own
// random rooms, doors and furniture) every height + slab metres; there are no stairs.
//
// What is modelled is only what can be seen from the walkable side (docs/DESIGN.md, "Model only
// what a scene needs"): per space a floor (up), a ceiling (down) and its four inner wall faces (facing
// into the space) with gaps for openings; per opening the wall's thickness — two jambs (end
// caps), a threshold floor and a lintel soffit (or a ceiling piece for full-height openings);
// pillars as 4 outward sides; furniture boxes (desks, tables, cabinets) as a top and 4 outward
// sides. Every polygon is an axis-aligned rectangle, counter-clockwise from its front. From any
// eye in a space the model is closed; T-junctions occur where wall pieces meet floors, as in
// real models. The exterior faces of the outer walls are not modelled.
//
// Polygon counts (measured with seed=1; tests/test_generators.cpp checks the ranges): a room
// cell costs about 13 polygons per storey without furniture and about 3.5 more per furniture box
// asked for (furniture counts boxes per room, and open-plan rooms span 2–3 cells), so
//   polygons ≈ floors · rooms · (13 + 3.5·furniture)      (≈ 24 per cell with the default 3).
// Parameter strings for the benchmark sizes:
//   gen:office                   1,060 polygons (rooms=40, the default)
//   gen:office?rooms=415        10,223 polygons
//   gen:office?rooms=4200      100,165 polygons
//   gen:office?rooms=8300      199,671 polygons
// (or about the same totals with floors=N and rooms divided by N: rooms=1050&floors=4 gives
// 102,699). Generation is linear: ~0.1–0.2 s for 100k polygons in Release.
//
// Randomness: core/rng.h, so a seed gives the same building with every standard library.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "core/rng.h"
#include "scenes/generators.h"

namespace walkvis {
namespace {

// Material colours (0xRRGGBB); faces get a small deterministic shade so that neighbouring
// faces of one material stay distinguishable under flat shading.
constexpr uint32_t kWallColor = 0xd8d0c0;
constexpr uint32_t kFloorColor = 0x8a6f55;
constexpr uint32_t kCeilingColor = 0xf0f0ec;
constexpr uint32_t kJambColor = 0xb8b0a0;
constexpr uint32_t kPillarColor = 0x9a9a9a;
constexpr uint32_t kDeskColor = 0xa0703c;
constexpr uint32_t kCabinetColor = 0x6c7a8a;

uint32_t shade(uint32_t color, uint32_t salt) {
  const int delta = static_cast<int>((salt * 2654435761u) >> 28) - 8;  // -8..7
  uint32_t out = 0;
  for (int shift = 0; shift <= 16; shift += 8) {
    const int c = std::clamp(static_cast<int>((color >> shift) & 0xff) + delta, 0, 255);
    out |= static_cast<uint32_t>(c) << shift;
  }
  return out;
}

struct Rect {
  double x0, x1, z0, z1;
};

// Where the side of a space is open: [lo, hi] along the side, from the floor up to `height`.
struct Opening {
  double lo, hi, height;
};

// Sides of a space: 0 at x = x0 (faces +x), 1 at x = x1 (faces -x), 2 at z = z0 (faces +z),
// 3 at z = z1 (faces -z).
enum Side { kWest = 0, kEast = 1, kNorth = 2, kSouth = 3 };

struct Space {
  Rect r;
  std::array<std::vector<Opening>, 4> openings;
  std::vector<Rect> keep_clear;  // plan areas furniture must avoid (door swings, pillars)
  bool furnished = false;
};

class Builder {
 public:
  Builder(Scene& scene, std::string context) : scene_(scene), context_(std::move(context)) {}

  // An axis-aligned rectangle given by two opposite corners that differ in exactly two
  // coordinates, wound counter-clockwise about `facing`. Rectangles thinner than 1e-9 m come only
  // from an opening flush with the end of a side, where there is nothing to draw.
  void rect(const glm::dvec3& a, const glm::dvec3& c, const glm::dvec3& facing, uint32_t color) {
    const glm::dvec3 e = c - a;
    glm::dvec3 b = a, d = a;
    if (facing.x != 0.0) {
      if (std::abs(e.y) < 1e-9 || std::abs(e.z) < 1e-9) return;
      b.y = c.y;
      d.z = c.z;
    } else if (facing.y != 0.0) {
      if (std::abs(e.x) < 1e-9 || std::abs(e.z) < 1e-9) return;
      b.x = c.x;
      d.z = c.z;
    } else {
      if (std::abs(e.x) < 1e-9 || std::abs(e.y) < 1e-9) return;
      b.x = c.x;
      d.y = c.y;
    }
    std::array<glm::dvec3, 4> q{a, b, c, d};
    if (glm::dot(glm::cross(b - a, c - b), facing) < 0.0) std::swap(q[1], q[3]);
    addFace(scene_, q, shade(color, salt_++), context_);
  }

  // A box standing on the floor: outward sides, and the top unless it reaches the ceiling.
  void box(double x0, double x1, double z0, double z1, double y0, double y1, bool top, uint32_t color) {
    rect({x0, y0, z0}, {x0, y1, z1}, {-1, 0, 0}, color);
    rect({x1, y0, z0}, {x1, y1, z1}, {1, 0, 0}, color);
    rect({x0, y0, z0}, {x1, y1, z0}, {0, 0, -1}, color);
    rect({x0, y0, z1}, {x1, y1, z1}, {0, 0, 1}, color);
    if (top) rect({x0, y1, z0}, {x1, y1, z1}, {0, 1, 0}, color);
  }

 private:
  Scene& scene_;
  std::string context_;
  uint32_t salt_ = 0;
};

struct Config {
  int64_t rooms, floors, furniture, per_side;
  double room_size, height, corridor, thickness;
  uint64_t seed;
};

constexpr double kSlab = 0.3;        // storey slab thickness: floor-to-floor = height + slab
constexpr double kDoorWidth = 0.9;   // clear width of a door
constexpr double kDoorHeight = 2.1;  // clear height of a door (lower when the storey is low)

class OfficeBuilder {
 public:
  OfficeBuilder(Scene& scene, const Config& cfg, Rng& rng)
      : scene_(scene), cfg_(cfg), rng_(rng), out_(scene, "gen:office") {}

  void build() {
    const double s = cfg_.room_size, w = cfg_.corridor;
    bay_depth_ = 2.0 * s + w;
    per_side_ = cfg_.per_side > 0 ? cfg_.per_side
                                  : std::max<int64_t>(1, std::llround(std::sqrt(static_cast<double>(cfg_.rooms) *
                                                                                bay_depth_ / (2.0 * s))));
    bays_ = (cfg_.rooms + 2 * per_side_ - 1) / (2 * per_side_);
    for (int64_t storey = 0; storey < cfg_.floors; ++storey) buildStorey(storey * (cfg_.height + kSlab));

    const double t2 = 0.5 * cfg_.thickness;
    // Start in the first corridor, 1 m in from the lobby, looking along +x (yaw -π/2).
    scene_.start_eye = {t2 + 1.0, scene_.eye_height, s + 0.5 * w};
    scene_.start_yaw = -0.5 * M_PI;
  }

 private:
  void buildStorey(double floor_y) {
    const double s = cfg_.room_size, w = cfg_.corridor, t2 = 0.5 * cfg_.thickness;
    const double lobby_w = 2.0 * w;
    const double door_h = std::min(kDoorHeight, cfg_.height - 0.3);
    spaces_.clear();
    passages_.clear();

    // The lobby is spaces_[0].
    Space lobby;
    lobby.r = {-lobby_w + t2, -t2, t2, static_cast<double>(bays_) * bay_depth_ - t2};
    spaces_.push_back(lobby);
    // Pillars down the lobby's middle, opposite the room rows (never in a corridor mouth).
    std::vector<Rect> pillars;
    for (int64_t b = 0; b < bays_; ++b) {
      const double zb = static_cast<double>(b) * bay_depth_;
      for (double zc : {zb + 0.5 * s, zb + 1.5 * s + w}) {
        pillars.push_back({-0.5 * lobby_w - 0.2, -0.5 * lobby_w + 0.2, zc - 0.2, zc + 0.2});
      }
    }

    int64_t cells_left = cfg_.rooms;
    for (int64_t b = 0; b < bays_; ++b) {
      const double zb = static_cast<double>(b) * bay_depth_;
      const int64_t north_cells = std::min(per_side_, cells_left);
      cells_left -= north_cells;
      const int64_t south_cells = std::min(per_side_, cells_left);
      cells_left -= south_cells;
      const int64_t row_cells = std::max(north_cells, south_cells);

      const size_t corridor = spaces_.size();
      Space c;
      c.r = {t2, static_cast<double>(row_cells) * s - t2, zb + s + t2, zb + s + w - t2};
      spaces_.push_back(c);
      connect(0, kEast, corridor, kWest, c.r.z0, c.r.z1, cfg_.height);

      addRow(north_cells, zb + t2, zb + s - t2, corridor, kSouth, kNorth, door_h, pillars);
      addRow(south_cells, zb + s + w + t2, zb + 2.0 * s + w - t2, corridor, kNorth, kSouth, door_h, pillars);
    }

    for (size_t i = 0; i < spaces_.size(); ++i) emitSpace(spaces_[i], floor_y);
    for (const auto& p : passages_) emitPassage(p, floor_y);
    for (const auto& p : pillars) out_.box(p.x0, p.x1, p.z0, p.z1, floor_y, floor_y + cfg_.height, false, kPillarColor);
    for (auto& sp : spaces_) {
      if (sp.furnished) furnish(sp, floor_y);
    }

    FloorLevel level;
    level.floor_y = floor_y;
    auto walk = [&](const Rect& r) {
      // Counter-clockwise seen from above (+y): clockwise in the (x, z) plot.
      level.walkable.push_back({{r.x0, r.z0}, {r.x0, r.z1}, {r.x1, r.z1}, {r.x1, r.z0}});
      level.walkable_area += (r.x1 - r.x0) * (r.z1 - r.z0);
    };
    for (const auto& sp : spaces_) walk(sp.r);
    for (const auto& p : passages_) walk(p.r);
    scene_.levels.push_back(std::move(level));
  }

  // One row of room cells between z0 and z1 with the corridor on side `to_corridor`.
  void addRow(int64_t cells, double z0, double z1, size_t corridor, Side to_corridor, Side corridor_side,
              double door_h, std::vector<Rect>& pillars) {
    const double s = cfg_.room_size, t2 = 0.5 * cfg_.thickness;
    const double door_z = to_corridor == kSouth ? z1 : z0;
    size_t prev_room = 0;
    int64_t i = 0;
    while (i < cells) {
      // Open-plan rooms: merge with the next cell or two now and then.
      int64_t span = 1;
      if (rng_.chance(0.25)) span = rng_.chance(0.5) ? 3 : 2;
      span = std::min(span, cells - i);
      Space room;
      room.r = {static_cast<double>(i) * s + t2, static_cast<double>(i + span) * s - t2, z0, z1};
      room.furnished = true;
      const size_t idx = spaces_.size();
      spaces_.push_back(room);

      // A door to the corridor per started two cells, each within one cell, clear of the walls.
      for (int64_t k = 0; k < span; k += 2) {
        const double cx0 = static_cast<double>(i + k) * s + t2 + 0.3;
        const double cx1 = static_cast<double>(i + k + 1) * s - t2 - 0.3 - kDoorWidth;
        const double lo = rng_.uniform(cx0, cx1);
        connect(idx, to_corridor, corridor, corridor_side, lo, lo + kDoorWidth, door_h);
        const double swing_z0 = to_corridor == kSouth ? door_z - 1.0 : door_z;
        spaces_[idx].keep_clear.push_back({lo - 0.1, lo + kDoorWidth + 0.1, swing_z0, swing_z0 + 1.0});
      }
      for (int64_t k = 1; k < span; ++k) {
        const double px = static_cast<double>(i + k) * s, pz = 0.5 * (z0 + z1);
        const Rect p{px - 0.2, px + 0.2, pz - 0.2, pz + 0.2};
        pillars.push_back(p);
        spaces_[idx].keep_clear.push_back({p.x0 - 0.3, p.x1 + 0.3, p.z0 - 0.3, p.z1 + 0.3});
      }
      // Now and then a door to the previous room of the row.
      if (i > 0 && rng_.chance(0.2)) {
        const double lo = rng_.uniform(z0 + 0.3, z1 - 0.3 - kDoorWidth);
        connect(prev_room, kEast, idx, kWest, lo, lo + kDoorWidth, door_h);
        const double xl = spaces_[prev_room].r.x1, xr = spaces_[idx].r.x0;
        spaces_[prev_room].keep_clear.push_back({xl - 1.0, xl, lo - 0.1, lo + kDoorWidth + 0.1});
        spaces_[idx].keep_clear.push_back({xr, xr + 1.0, lo - 0.1, lo + kDoorWidth + 0.1});
      }
      prev_room = idx;
      i += span;
    }
  }

  struct Passage {
    Rect r;
    bool along_x;  // the opening runs along x (a wall between spaces stacked in z)
    double height;
  };

  // Opens [lo, hi] (along the common wall) up to `height` between side `sa` of space a and side
  // `sb` of space b, and records the passage through the wall's thickness.
  void connect(size_t a, Side sa, size_t b, Side sb, double lo, double hi, double height) {
    spaces_[a].openings[sa].push_back({lo, hi, height});
    spaces_[b].openings[sb].push_back({lo, hi, height});
    auto coord = [&](size_t i, Side side) {
      const Rect& r = spaces_[i].r;
      return side == kWest ? r.x0 : side == kEast ? r.x1 : side == kNorth ? r.z0 : r.z1;
    };
    const double ca = coord(a, sa), cb = coord(b, sb);
    Passage p;
    p.along_x = sa == kNorth || sa == kSouth;
    p.height = height;
    if (p.along_x) {
      p.r = {lo, hi, std::min(ca, cb), std::max(ca, cb)};
    } else {
      p.r = {std::min(ca, cb), std::max(ca, cb), lo, hi};
    }
    passages_.push_back(p);
  }

  void emitSpace(Space& sp, double f) {
    const double top = f + cfg_.height;
    const Rect& r = sp.r;
    out_.rect({r.x0, f, r.z0}, {r.x1, f, r.z1}, {0, 1, 0}, kFloorColor);
    out_.rect({r.x0, top, r.z0}, {r.x1, top, r.z1}, {0, -1, 0}, kCeilingColor);
    for (int side = 0; side < 4; ++side) {
      auto& ops = sp.openings[side];
      std::sort(ops.begin(), ops.end(), [](const Opening& a, const Opening& b) { return a.lo < b.lo; });
      const bool x_side = side == kWest || side == kEast;
      const double fixed = side == kWest ? r.x0 : side == kEast ? r.x1 : side == kNorth ? r.z0 : r.z1;
      const double u0 = x_side ? r.z0 : r.x0, u1 = x_side ? r.z1 : r.x1;
      const glm::dvec3 facing = side == kWest ? glm::dvec3(1, 0, 0)
                                : side == kEast ? glm::dvec3(-1, 0, 0)
                                : side == kNorth ? glm::dvec3(0, 0, 1)
                                                 : glm::dvec3(0, 0, -1);
      auto at = [&](double u, double y) { return x_side ? glm::dvec3(fixed, y, u) : glm::dvec3(u, y, fixed); };
      double cursor = u0;
      for (const auto& op : ops) {
        out_.rect(at(cursor, f), at(op.lo, top), facing, kWallColor);
        if (op.height < cfg_.height) out_.rect(at(op.lo, f + op.height), at(op.hi, top), facing, kWallColor);
        cursor = op.hi;
      }
      out_.rect(at(cursor, f), at(u1, top), facing, kWallColor);
    }
  }

  void emitPassage(const Passage& p, double f) {
    const Rect& r = p.r;
    const double top = f + p.height;
    out_.rect({r.x0, f, r.z0}, {r.x1, f, r.z1}, {0, 1, 0}, kFloorColor);
    out_.rect({r.x0, top, r.z0}, {r.x1, top, r.z1}, {0, -1, 0},
              p.height < cfg_.height ? kJambColor : kCeilingColor);
    if (p.along_x) {
      out_.rect({r.x0, f, r.z0}, {r.x0, top, r.z1}, {1, 0, 0}, kJambColor);
      out_.rect({r.x1, f, r.z0}, {r.x1, top, r.z1}, {-1, 0, 0}, kJambColor);
    } else {
      out_.rect({r.x0, f, r.z0}, {r.x1, top, r.z0}, {0, 0, 1}, kJambColor);
      out_.rect({r.x0, f, r.z1}, {r.x1, top, r.z1}, {0, 0, -1}, kJambColor);
    }
  }

  static bool overlaps(const Rect& a, const Rect& b) {
    return a.x0 < b.x1 && b.x0 < a.x1 && a.z0 < b.z1 && b.z0 < a.z1;
  }

  // Desks, tables and cabinets by rejection sampling; a box that finds no free place after a few
  // tries is left out, so the count per room can fall short in crowded rooms.
  void furnish(const Space& sp, double f) {
    constexpr double kGap = 0.05;  // furniture never touches a wall or another box: no coplanar faces
    std::vector<Rect> taken = sp.keep_clear;
    const Rect& r = sp.r;
    for (int64_t n = 0; n < cfg_.furniture; ++n) {
      const double kind = rng_.uniform();
      double a, b, h;
      uint32_t color;
      bool against_wall = false;
      if (kind < 0.5) {  // desk
        a = rng_.uniform(1.4, 1.8), b = rng_.uniform(0.7, 0.8), h = 0.75, color = kDeskColor;
      } else if (kind < 0.7) {  // table
        a = rng_.uniform(1.0, 2.0), b = rng_.uniform(0.8, 1.2), h = 0.74, color = kDeskColor;
      } else {  // cabinet, taller than the eye, against a wall
        a = rng_.uniform(0.8, 1.2), b = rng_.uniform(0.4, 0.5), h = std::min(1.95, cfg_.height - 0.2);
        color = kCabinetColor;
        against_wall = true;
      }
      for (int attempt = 0; attempt < 12; ++attempt) {
        const bool turned = rng_.chance(0.5);
        const double dx = turned ? b : a, dz = turned ? a : b;
        if (dx + 2 * kGap > r.x1 - r.x0 || dz + 2 * kGap > r.z1 - r.z0) continue;
        double x0 = rng_.uniform(r.x0 + kGap, r.x1 - kGap - dx);
        double z0 = rng_.uniform(r.z0 + kGap, r.z1 - kGap - dz);
        if (against_wall) {
          // Back to the nearer wall across its thin side.
          if (turned) {
            x0 = rng_.chance(0.5) ? r.x0 + kGap : r.x1 - kGap - dx;
          } else {
            z0 = rng_.chance(0.5) ? r.z0 + kGap : r.z1 - kGap - dz;
          }
        }
        const Rect box{x0, x0 + dx, z0, z0 + dz};
        const Rect padded{box.x0 - kGap, box.x1 + kGap, box.z0 - kGap, box.z1 + kGap};
        bool free = true;
        for (const auto& t : taken) free = free && !overlaps(padded, t);
        if (!free) continue;
        taken.push_back(box);
        out_.box(box.x0, box.x1, box.z0, box.z1, f, f + h, true, color);
        break;
      }
    }
  }

  Scene& scene_;
  const Config& cfg_;
  Rng& rng_;
  Builder out_;
  double bay_depth_ = 0.0;
  int64_t per_side_ = 1, bays_ = 1;
  std::vector<Space> spaces_;
  std::vector<Passage> passages_;
};

}  // namespace

Scene generateOffice(GeneratorParams& params) {
  Config cfg;
  cfg.rooms = params.getInt("rooms", 40, 1, 200000);
  cfg.floors = params.getInt("floors", 1, 1, 100);
  cfg.furniture = params.getInt("furniture", 3, 0, 40);
  cfg.per_side = params.getInt("per_side", 0, 0, 100000);  // room cells per corridor side; 0: near-square plan
  cfg.room_size = params.getDouble("room_size", 5.0, 3.0, 50.0);
  cfg.height = params.getDouble("height", 3.0, 2.4, 20.0);
  cfg.corridor = params.getDouble("corridor", 2.0, 1.2, 20.0);
  cfg.thickness = params.getDouble("thickness", 0.2, 0.05, 1.0);
  cfg.seed = params.seed();
  // Memory stays bounded: (14 + 5·furniture) polygons per room cell and storey is an upper bound.
  const double estimate = static_cast<double>(cfg.rooms) * static_cast<double>(cfg.floors) *
                          (14.0 + 5.0 * static_cast<double>(cfg.furniture));
  constexpr double kMaxPolygons = 4e6;
  if (estimate > kMaxPolygons) {
    throw Error(params.generator() + ": rooms·floors·(14+5·furniture) = " +
                     std::to_string(static_cast<int64_t>(estimate)) + " polygons, more than the limit of 4000000");
  }
  Scene scene;
  scene.name = "gen:office";
  const size_t est = static_cast<size_t>(estimate) + 1024;
  scene.polygons.reserve(est);
  scene.vertices.reserve(4 * est);
  scene.face_colors.reserve(est);
  Rng rng{cfg.seed};
  OfficeBuilder(scene, cfg, rng).build();
  return scene;
}

}  // namespace walkvis
