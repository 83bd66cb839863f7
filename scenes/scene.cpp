// Building scenes: input faces become convex planar polygons; floor levels and the start eye.
#include "scenes/scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <unordered_map>

#include <glm/geometric.hpp>

#include "core/hash.h"

namespace walkvis {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

double extentOf(std::span<const glm::dvec3> v) {
  glm::dvec3 lo = v[0], hi = v[0];
  for (const auto& p : v) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::dvec3 e = hi - lo;
  return std::max({e.x, e.y, e.z});
}

// Two unit vectors spanning the plane with u × v = n, so counter-clockwise about n stays
// counter-clockwise in (u, v).
void planeAxes(const glm::dvec3& n, glm::dvec3& u, glm::dvec3& v) {
  const glm::dvec3 a = std::abs(n.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  u = glm::normalize(glm::cross(a, n));
  v = glm::cross(n, u);
}

double cross2(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Strictly convex or with collinear corners, simple (turns once), counter-clockwise.
bool isConvexCcw(const std::vector<glm::dvec2>& p) {
  const size_t n = p.size();
  double turning = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2& a = p[i];
    const glm::dvec2& b = p[(i + 1) % n];
    const glm::dvec2& c = p[(i + 2) % n];
    if (cross2(a, b, c) < 0.0) return false;
    const glm::dvec2 e0 = b - a, e1 = c - b;
    turning += std::atan2(e0.x * e1.y - e0.y * e1.x, glm::dot(e0, e1));
  }
  // A simple convex loop turns by exactly 2π; a star turns 4π or more. The margin only has to
  // separate 2π from 4π.
  return turning < 3.0 * M_PI;
}

}  // namespace

uint32_t appendPolygon(Scene& scene, std::span<const glm::dvec3> verts, uint32_t face_id, const Plane& plane) {
  Polygon poly;
  poly.first_vertex = static_cast<uint32_t>(scene.vertices.size());
  poly.vertex_count = static_cast<uint32_t>(verts.size());
  poly.face_id = face_id;
  poly.plane = plane;
  scene.vertices.insert(scene.vertices.end(), verts.begin(), verts.end());
  scene.polygons.push_back(poly);
  return static_cast<uint32_t>(scene.polygons.size() - 1);
}

bool insideConvexRing(std::span<const glm::dvec2> ring, const glm::dvec2& p) {
  bool pos = false, neg = false;
  for (size_t i = 0; i < ring.size() && !(pos && neg); ++i) {
    const glm::dvec2 a = ring[i], b = ring[(i + 1) % ring.size()];
    const double c = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
    pos = pos || c > 0.0;
    neg = neg || c < 0.0;
  }
  return ring.size() >= 3 && !(pos && neg);
}

double signedArea(std::span<const glm::dvec2> p) {
  double a = 0.0;
  for (size_t k = 1; k + 1 < p.size(); ++k) {
    const glm::dvec2 s = p[k] - p[0], t = p[k + 1] - p[0];
    a += s.x * t.y - t.x * s.y;
  }
  return 0.5 * a;
}

namespace {

uint32_t newFace(Scene& scene, uint32_t color) {
  scene.face_colors.push_back(color);
  scene.report.input_faces++;
  return static_cast<uint32_t>(scene.face_colors.size() - 1);
}

struct Vec2Less {
  bool operator()(const glm::dvec2& a, const glm::dvec2& b) const {
    return a.x < b.x || (a.x == b.x && a.y < b.y);
  }
};

}  // namespace

Plane newellPlane(std::span<const glm::dvec3> v) {
  Plane plane;
  if (v.size() < 3) return Plane{glm::dvec3(0.0), 0.0};
  // A face whose vertices share one y is exactly horizontal: give it an exact normal so that
  // floors and ceilings never need a test on a height plane (docs/DESIGN.md, "PFD tree").
  bool flat = true;
  for (const auto& p : v) flat = flat && p.y == v[0].y;
  glm::dvec3 n(0.0), c(0.0);
  for (size_t i = 0; i < v.size(); ++i) {
    const glm::dvec3& a = v[i];
    const glm::dvec3& b = v[(i + 1) % v.size()];
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
    c += a;
  }
  const double len = glm::length(n);
  if (!(len > 0.0)) return Plane{glm::dvec3(0.0), 0.0};
  if (flat) {
    plane.n = glm::dvec3(0.0, n.y > 0.0 ? 1.0 : -1.0, 0.0);
    plane.d = plane.n.y * v[0].y;
    return plane;
  }
  plane.n = n / len;
  plane.d = glm::dot(plane.n, c / static_cast<double>(v.size()));
  return plane;
}

uint32_t faceColor(uint32_t face_id) {
  // A hash spread over hue-like values; mid-range channels keep faces distinguishable when lit.
  uint32_t h = face_id * 2654435761u;
  h ^= h >> 15;
  h *= 2246822519u;
  h ^= h >> 13;
  const uint32_t r = 64 + (h & 0xff) % 176, g = 64 + ((h >> 8) & 0xff) % 176, b = 64 + ((h >> 16) & 0xff) % 176;
  return (r << 16) | (g << 8) | b;
}

uint32_t addFace(Scene& scene, std::span<const glm::dvec3> input, uint32_t color, const std::string& context) {
  const uint32_t face_id = newFace(scene, color);
  for (const auto& p : input) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      throw Error(context + ": face " + std::to_string(face_id) + " has a non-finite coordinate (" +
                       std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")");
    }
  }
  // Repeated consecutive vertices (including last == first) carry no shape.
  std::vector<glm::dvec3> v;
  v.reserve(input.size());
  for (const auto& p : input) {
    if (v.empty() || v.back() != p) v.push_back(p);
  }
  while (v.size() > 1 && v.back() == v.front()) v.pop_back();
  if (v.size() < 3) {
    scene.report.dropped_degenerate++;
    return face_id;
  }
  const Plane plane = newellPlane(v);
  const double extent = extentOf(v);
  // Newell's sum carries a rounding error of about (vertices · eps · extent²); an area below a
  // small multiple of that cannot be told from zero. Slivers far thinner than any pixel (the
  // 1e-9 hard case) stay well above it.
  const double area_floor = 16.0 * static_cast<double>(v.size()) * kEps * extent * extent;
  double area2 = 0.0;
  {
    glm::dvec3 n(0.0);
    for (size_t i = 0; i < v.size(); ++i) n += glm::cross(v[i], v[(i + 1) % v.size()]);
    area2 = glm::length(n);
  }
  if (glm::length(plane.n) == 0.0 || 0.5 * area2 <= area_floor) {
    scene.report.dropped_zero_area++;
    return face_id;
  }
  // Planarity: exported files round coordinates to ~7 significant digits, so a deviation up to
  // 1e-6 of the face's size is rounding, not shape. The BSP projects vertices exactly onto the
  // plane, so such a deviation never makes a classification contradict itself.
  double off = 0.0;
  for (const auto& p : v) off = std::max(off, std::abs(glm::dot(plane.n, p) - plane.d));
  const bool planar = off <= 1e-6 * extent;

  glm::dvec3 u_axis, v_axis;
  planeAxes(plane.n, u_axis, v_axis);
  std::vector<glm::dvec2> flat2;
  flat2.reserve(v.size());
  for (const auto& p : v) flat2.emplace_back(glm::dot(p, u_axis), glm::dot(p, v_axis));

  if (planar && isConvexCcw(flat2)) {
    appendPolygon(scene, v, face_id, plane);
    scene.report.kept_faces++;
    return face_id;
  }

  // Split: convex pieces of the projected loop, lifted back onto the original vertices where a
  // piece corner is an input vertex (so shared edges with neighbours stay exact) and onto the
  // plane elsewhere (corners CGAL made at self-intersections).
  std::map<glm::dvec2, glm::dvec3, Vec2Less> lift;
  for (size_t i = 0; i < v.size(); ++i) lift.emplace(flat2[i], v[i]);
  const auto pieces = convexPartition({flat2});
  uint64_t made = 0;
  for (const auto& piece : pieces) {
    std::vector<glm::dvec3> p3;
    p3.reserve(piece.size());
    for (const auto& q : piece) {
      auto it = lift.find(q);
      p3.push_back(it != lift.end() ? it->second : plane.n * plane.d + u_axis * q.x + v_axis * q.y);
    }
    if (planar) {
      appendPolygon(scene, p3, face_id, plane);
      ++made;
      continue;
    }
    // Non-planar: a fan of triangles, each planar by construction.
    for (size_t i = 1; i + 1 < p3.size(); ++i) {
      const glm::dvec3 tri[3] = {p3[0], p3[i], p3[i + 1]};
      const Plane tp = newellPlane(tri);
      if (glm::length(tp.n) == 0.0) continue;
      appendPolygon(scene, tri, face_id, tp);
      ++made;
    }
  }
  if (made == 0) {
    scene.report.dropped_zero_area++;
  } else {
    scene.report.split_faces++;
    scene.report.split_pieces += made;
  }
  return face_id;
}

uint32_t addPlanarRegion(Scene& scene, const std::vector<std::vector<glm::dvec2>>& rings, const glm::dvec3& origin,
                         const glm::dvec3& u_axis, const glm::dvec3& v_axis, uint32_t color,
                         const std::string& context) {
  const uint32_t face_id = newFace(scene, color);
  for (const auto& ring : rings) {
    for (const auto& p : ring) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
        throw Error(context + ": region " + std::to_string(face_id) + " has a non-finite coordinate");
      }
    }
  }
  const auto pieces = convexPartition(rings);
  uint64_t made = 0;
  Plane plane;
  bool have_plane = false;
  for (const auto& piece : pieces) {
    std::vector<glm::dvec3> p3;
    p3.reserve(piece.size());
    for (const auto& q : piece) p3.push_back(origin + u_axis * q.x + v_axis * q.y);
    if (!have_plane) {
      // One plane for all pieces: they are one face, and the BSP then keeps them coplanar.
      plane = newellPlane(p3);
      if (glm::length(plane.n) == 0.0) continue;
      have_plane = true;
    }
    appendPolygon(scene, p3, face_id, plane);
    ++made;
  }
  if (made == 0) {
    scene.report.dropped_zero_area++;
  } else if (made == 1) {
    scene.report.kept_faces++;
  } else {
    scene.report.split_faces++;
    scene.report.split_pieces += made;
  }
  return face_id;
}

namespace {

bool insideConvexXz(const std::vector<glm::dvec2>& p, const glm::dvec2& q) {
  // Pieces are normalised to negative shoelace area: inside means every cross product <= 0.
  for (size_t i = 0; i < p.size(); ++i) {
    if (cross2(p[i], p[(i + 1) % p.size()], q) > 0.0) return false;
  }
  return true;
}

}  // namespace

std::vector<FloorHeight> upwardFloorHeights(const Scene& scene) {
  std::vector<FloorHeight> out;
  if (scene.polygons.empty()) return out;
  const Bounds b = sceneBounds(scene);
  const double extent = std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z, 1e-300});
  const double height_tol = 1e-6 * extent;
  std::vector<std::pair<double, uint32_t>> floors;
  for (uint32_t i = 0; i < scene.polygons.size(); ++i) {
    const Polygon& p = scene.polygons[i];
    if (p.plane.n.y >= 1.0 - 1e-9) floors.emplace_back(p.plane.d, i);
  }
  std::sort(floors.begin(), floors.end());
  for (const auto& [h, idx] : floors) {
    if (out.empty() || h - out.back().y > height_tol) out.push_back(FloorHeight{h, {}});
    out.back().polygons.push_back(idx);
  }
  return out;
}

void deriveFloorLevels(Scene& scene) {
  if (scene.polygons.empty()) return;
  scene.levels.clear();
  for (const FloorHeight& height : upwardFloorHeights(scene)) {
    FloorLevel level;
    level.floor_y = height.y;
    for (uint32_t idx : height.polygons) {
      std::vector<glm::dvec2> piece;
      for (const auto& v : scene.polygonVertices(idx)) piece.emplace_back(v.x, v.z);
      level.walkable.push_back(std::move(piece));
    }
    scene.levels.push_back(std::move(level));
  }
}

void transformScene(Scene& scene, bool z_up, double scale) {
  // z-up to y-up is a permutation with one negation, exact in doubles; a scale rounds each
  // coordinate once, and planes are scaled the same way (n is unchanged by a uniform scale).
  const auto point = [&](const glm::dvec3& p) {
    const glm::dvec3 q = z_up ? glm::dvec3(p.x, p.z, -p.y) : p;
    return q * scale;
  };
  for (auto& v : scene.vertices) v = point(v);
  for (auto& p : scene.polygons) {
    p.plane.n = z_up ? glm::dvec3(p.plane.n.x, p.plane.n.z, -p.plane.n.y) : p.plane.n;
    p.plane.d *= scale;
  }
  if (scene.start_eye != glm::dvec3(0.0)) scene.start_eye = point(scene.start_eye);
  scene.levels.clear();
  scene.connections.clear();
}

void placeStartEye(Scene& scene) {
  for (auto& level : scene.levels) {
    level.walkable_area = 0.0;
    for (auto& piece : level.walkable) {
      if (signedArea(piece) > 0.0) std::reverse(piece.begin(), piece.end());
      level.walkable_area += -signedArea(piece);
    }
  }
  std::sort(scene.levels.begin(), scene.levels.end(),
            [](const FloorLevel& a, const FloorLevel& b) { return a.floor_y < b.floor_y; });
  const bool given = std::isfinite(scene.start_eye.x) && std::isfinite(scene.start_eye.y) &&
                     std::isfinite(scene.start_eye.z);
  if (scene.levels.empty()) {
    const Bounds b = sceneBounds(scene);
    if (!given || (!scene.polygons.empty() && scene.start_eye == glm::dvec3(0.0)))
      scene.start_eye = 0.5 * (b.lo + b.hi);
    return;
  }
  // Keep the loader's start if it stands above a walkable piece: choose the highest floor at or
  // below it (Doom starts stand on their sector's floor).
  const glm::dvec2 q(scene.start_eye.x, scene.start_eye.z);
  const FloorLevel* best = nullptr;
  if (given) {
    for (const auto& level : scene.levels) {
      if (level.floor_y > scene.start_eye.y + 1e-9 * std::abs(scene.start_eye.y)) continue;
      for (const auto& piece : level.walkable) {
        if (insideConvexXz(piece, q)) best = &level;
      }
    }
  }
  if (best) {
    scene.start_eye.y = best->floor_y + scene.eye_height;
    return;
  }
  // The lowest level that has a walkable piece (a loader may keep a level without one).
  const FloorLevel* low = nullptr;
  for (const auto& level : scene.levels) {
    if (!level.walkable.empty()) {
      low = &level;
      break;
    }
  }
  if (!low) {
    const Bounds b = sceneBounds(scene);
    scene.start_eye = glm::dvec3(0.5 * (b.lo.x + b.hi.x), scene.levels.front().floor_y + scene.eye_height,
                                 0.5 * (b.lo.z + b.hi.z));
    return;
  }
  const std::vector<glm::dvec2>* largest = nullptr;
  double largest_area = -1.0;
  for (const auto& piece : low->walkable) {
    const double a = -signedArea(piece);
    if (a > largest_area) {
      largest_area = a;
      largest = &piece;
    }
  }
  glm::dvec2 c(0.0);
  for (const auto& p : *largest) c += p;
  c /= static_cast<double>(largest->size());
  scene.start_eye = glm::dvec3(c.x, low->floor_y + scene.eye_height, c.y);
}

Bounds sceneBounds(const Scene& scene) {
  Bounds b;
  if (scene.vertices.empty()) return b;
  b.lo = b.hi = scene.vertices[0];
  for (const auto& v : scene.vertices) {
    b.lo = glm::min(b.lo, v);
    b.hi = glm::max(b.hi, v);
  }
  return b;
}

uint64_t triangleCount(const Scene& scene) {
  uint64_t t = 0;
  for (const auto& p : scene.polygons) t += p.vertex_count - 2;
  return t;
}

bool isClosed(const Scene& scene) {
  if (scene.polygons.empty()) return false;
  struct Key {
    glm::dvec3 a, b;
    bool operator==(const Key& o) const { return a == o.a && b == o.b; }
  };
  struct Hash {
    size_t operator()(const Key& k) const {
      return static_cast<size_t>(fnv1aDoubles({k.a.x, k.a.y, k.a.z, k.b.x, k.b.y, k.b.z}));
    }
  };
  std::unordered_map<Key, int64_t, Hash> edges;
  edges.reserve(scene.vertices.size() * 2);
  for (const auto& poly : scene.polygons) {
    const auto v = scene.polygonVertices(poly);
    for (size_t i = 0; i < v.size(); ++i) {
      const glm::dvec3& a = v[i];
      const glm::dvec3& b = v[(i + 1) % v.size()];
      // Count a→b as +1 on the key (min, max) direction and -1 the other way.
      if (Vec2Less{}(glm::dvec2(a.x, a.y), glm::dvec2(b.x, b.y)) ||
          (a.x == b.x && a.y == b.y && a.z < b.z)) {
        edges[Key{a, b}] += 1;
      } else {
        edges[Key{b, a}] -= 1;
      }
    }
  }
  for (const auto& [k, count] : edges) {
    if (count != 0) return false;
  }
  return true;
}

}  // namespace walkvis
