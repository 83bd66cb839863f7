// Helpers shared by the backface tests (test_backface.cpp, test_backface_kumar.cpp,
// test_list_cull.cpp): random test meshes and random eyes that exercise the hard places.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include <glm/geometric.hpp>

#include "scenes/scene.h"

namespace walkvis::backface_test {

// Random triangles and quads of every orientation in [-1, 1]³; every 7th is a parallelogram with
// its reverse (coplanar, both orientations).
inline Scene randomSoup(uint64_t seed, int count) {
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

inline glm::dvec3 randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return glm::normalize(glm::dvec3(g(rng), g(rng), g(rng)));
}

// The centre and half diagonal of a scene's bounding box.
struct Frame {
  glm::dvec3 center{0.0};
  double radius = 0.0;
};
inline Frame frameOf(const Scene& s) {
  const Bounds b = sceneBounds(s);
  return {0.5 * (b.lo + b.hi), 0.5 * glm::length(b.hi - b.lo)};
}

// A third inside the box, a third 1–3 radii out, a sixth 3–30 radii out, a sixth within
// 1e-12..1e-2 radii of a polygon's plane on either side (where the floating point decides).
inline glm::dvec3 randomEye(const Scene& s, std::mt19937_64& rng, const Frame& f) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double pick = u(rng);
  if (pick < 1.0 / 3.0) return f.center + f.radius * glm::dvec3(2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1);
  if (pick < 2.0 / 3.0) return f.center + f.radius * (1.0 + 2.0 * u(rng)) * randomUnit(rng);
  if (pick < 5.0 / 6.0) return f.center + f.radius * (3.0 + 27.0 * u(rng)) * randomUnit(rng);
  const Polygon& p = s.polygons[static_cast<size_t>(u(rng) * static_cast<double>(s.polygons.size())) % s.polygons.size()];
  glm::dvec3 c(0.0);
  for (const auto& v : s.polygonVertices(p)) c += v;
  c /= static_cast<double>(p.vertex_count);
  const double offset = std::pow(10.0, -12.0 + 10.0 * u(rng)) * (u(rng) < 0.5 ? -1.0 : 1.0);
  return c + offset * f.radius * p.plane.n;
}

// A scene far from the origin with small features: margins must scale with the coordinates.
inline Scene farFromOriginSphere() {
  Scene s = loadScene("gen:sphere?tris=500&radius=0.01");
  for (auto& v : s.vertices) v += glm::dvec3(1e6, -2e5, 3e5);
  for (auto& p : s.polygons) p.plane = newellPlane(s.polygonVertices(p));
  s.name = "sphere far from the origin";
  return s;
}

}  // namespace walkvis::backface_test
