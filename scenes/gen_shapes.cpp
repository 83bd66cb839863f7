// Small shape generators: gen:ninefacet, gen:sphere, gen:dome.
//
// ninefacet follows the teaching example of James & Day (1998), "The hidden face determination
// tree" [JamesDay1998HFD], §4 and Figure 1: nine single-sided
// vertical facets around an open area, some facing each other, on a floor that gives the level.
// The paper's figure is not reproduced in its text, so the layout is ours (docs/DESIGN.md,
// "Corrections").
//
// sphere is a geodesic sphere: the icosahedron with each face cut into n² triangles and the
// vertices pushed onto the sphere, 20·n² triangles with n = round(sqrt(tris / 20)):
//   gen:sphere              2,000 triangles (n = 10)
//   gen:sphere?tris=70000  69,620 triangles (n = 59)
// Every vertex is computed from its icosahedron corners in one canonical order, so the copies a
// vertex has in neighbouring triangles are bit-identical and the mesh is closed (isClosed).
//
// dome is a UV sphere cut below its equator at y = -cut·radius and open at the bottom, with a
// floor disc (facing up) on the cut so that it has a level; ~`tris` triangles (2,000 by default:
// 1,881 triangles and the disc with cut=0.3). The dome's triangles face outward (inside=1 turns
// them inward). Both take at most tris=1000000.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>

#include "scenes/generators.h"

namespace walkvis {
namespace {

// Adds a triangle wound counter-clockwise about `facing`.
void addOrientedTriangle(Scene& scene, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                         const glm::dvec3& facing, uint32_t color, const std::string& context) {
  std::array<glm::dvec3, 3> t{a, b, c};
  if (glm::dot(glm::cross(b - a, c - a), facing) < 0.0) std::swap(t[1], t[2]);
  addFace(scene, t, color, context);
}

uint32_t shadeOf(uint32_t base, size_t i) {
  const uint32_t k = static_cast<uint32_t>((i * 2654435761u) >> 27) & 0x0f;  // 0..15
  const uint32_t r = std::min(255u, ((base >> 16) & 0xff) + k), g = std::min(255u, ((base >> 8) & 0xff) + k),
                 b = std::min(255u, (base & 0xff) + k);
  return (r << 16) | (g << 8) | b;
}

}  // namespace

Scene generateNineFacet(GeneratorParams& params) {
  const std::string context = params.generator();
  const double height = params.getDouble("height", 2.5, 0.5, 100.0);
  Scene scene;
  scene.name = "gen:ninefacet";
  // Floor [-5, 5]², facing up.
  const std::array<glm::dvec3, 4> floor{glm::dvec3(-5, 0, -5), glm::dvec3(-5, 0, 5), glm::dvec3(5, 0, 5),
                                        glm::dvec3(5, 0, -5)};
  addFace(scene, floor, 0x8a8a8a, context);

  // Facets a..i in plan: from (x0, z0) to (x1, z1), front towards the point (fx, fz).
  struct Facet {
    double x0, z0, x1, z1, fx, fz;
  };
  constexpr std::array<Facet, 9> kFacets{{
      {-4.0, -4.0, -1.0, -4.0, 0.0, 0.0},   // a: back left, faces the open area
      {1.0, -4.0, 4.0, -4.0, 0.0, 0.0},     // b: back right, in a's plane
      {4.5, -3.0, 4.5, 1.0, 0.0, 0.0},      // c: right side
      {2.0, 3.0, 4.0, 1.5, 0.0, 0.0},       // d: front right, diagonal
      {-3.0, 4.5, 1.0, 4.5, 0.0, 0.0},      // e: front, faces a and b across the area
      {-4.5, -2.0, -4.5, 2.0, 0.0, 0.0},    // f: left side, faces c
      {-1.0, 0.0, 1.0, 0.5, 0.0, -3.0},     // g: free-standing, faces a and b
      {-1.0, 1.5, 1.0, 2.0, 0.0, 4.0},      // h: free-standing behind g, faces e
      {-3.5, -2.0, -2.0, -3.0, 0.0, 0.0},   // i: back left corner, diagonal
  }};
  for (size_t k = 0; k < kFacets.size(); ++k) {
    const Facet& f = kFacets[k];
    const glm::dvec3 p(f.x0, 0.0, f.z0), q(f.x1, 0.0, f.z1), up(0.0, height, 0.0);
    std::array<glm::dvec3, 4> quad{p, q, q + up, p + up};
    const glm::dvec3 n = glm::cross(q - p, up);
    const glm::dvec3 to_front(f.fx - 0.5 * (f.x0 + f.x1), 0.0, f.fz - 0.5 * (f.z0 + f.z1));
    if (glm::dot(n, to_front) < 0.0) std::reverse(quad.begin(), quad.end());
    addFace(scene, quad, faceColor(static_cast<uint32_t>(k + 1)), context);
  }
  FloorLevel level;
  level.floor_y = 0.0;
  level.walkable.push_back({{-5, -5}, {-5, 5}, {5, 5}, {5, -5}});
  level.walkable_area = 100.0;
  scene.levels.push_back(level);
  scene.start_eye = {0.0, scene.eye_height, -2.0};
  scene.start_yaw = 0.0;  // looks along -z, at a and b
  return scene;
}

Scene generateSphere(GeneratorParams& params) {
  const std::string context = params.generator();
  const int64_t tris = params.getInt("tris", 2000, 20, 1000000);
  const double radius = params.getDouble("radius", 1.0, 1e-3, 1e6);
  const int64_t n = std::max<int64_t>(1, std::llround(std::sqrt(static_cast<double>(tris) / 20.0)));

  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const std::array<glm::dvec3, 12> corner{glm::dvec3(-1, t, 0), glm::dvec3(1, t, 0),  glm::dvec3(-1, -t, 0),
                                          glm::dvec3(1, -t, 0), glm::dvec3(0, -1, t), glm::dvec3(0, 1, t),
                                          glm::dvec3(0, -1, -t), glm::dvec3(0, 1, -t), glm::dvec3(t, 0, -1),
                                          glm::dvec3(t, 0, 1),  glm::dvec3(-t, 0, -1), glm::dvec3(-t, 0, 1)};
  constexpr std::array<std::array<int, 3>, 20> kFaces{{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}}};
  Scene scene;
  scene.name = "gen:sphere";
  const size_t count = static_cast<size_t>(20 * n * n);
  scene.polygons.reserve(count);
  scene.vertices.reserve(3 * count);
  std::vector<glm::dvec3> grid;
  for (size_t f = 0; f < kFaces.size(); ++f) {
    const auto& face = kFaces[f];
    // Point (i, j) of the face has weights (n-i-j, i, j) on its corners; summing in the order of
    // the corners' indices makes shared edge points identical in both faces (a zero weight adds
    // an exact zero).
    auto point = [&](int64_t i, int64_t j) {
      std::array<std::pair<int, double>, 3> w{{{face[0], static_cast<double>(n - i - j)},
                                               {face[1], static_cast<double>(i)},
                                               {face[2], static_cast<double>(j)}}};
      std::sort(w.begin(), w.end());
      glm::dvec3 p(0.0);
      for (const auto& [c, weight] : w) p += weight * corner[static_cast<size_t>(c)];
      return radius * (p / glm::length(p));
    };
    grid.assign(static_cast<size_t>((n + 1) * (n + 1)), glm::dvec3(0.0));
    for (int64_t i = 0; i <= n; ++i) {
      for (int64_t j = 0; i + j <= n; ++j) grid[static_cast<size_t>(i * (n + 1) + j)] = point(i, j);
    }
    auto at = [&](int64_t i, int64_t j) { return grid[static_cast<size_t>(i * (n + 1) + j)]; };
    const uint32_t color = shadeOf(0x4080c0, f);
    for (int64_t i = 0; i < n; ++i) {
      for (int64_t j = 0; i + j < n; ++j) {
        const glm::dvec3 a = at(i, j), b = at(i + 1, j), c = at(i, j + 1);
        addOrientedTriangle(scene, a, b, c, a + b + c, color, context);
        if (i + j + 1 < n) {
          const glm::dvec3 d = at(i + 1, j + 1);
          addOrientedTriangle(scene, b, d, c, b + d + c, color, context);
        }
      }
    }
  }
  // An object, not a building: no floor level; the eye starts outside, looking at it along -z.
  scene.start_eye = {0.0, 0.0, 3.0 * radius};
  scene.start_yaw = 0.0;
  return scene;
}

Scene generateDome(GeneratorParams& params) {
  const std::string context = params.generator();
  const int64_t tris = params.getInt("tris", 2000, 20, 1000000);
  const double radius = params.getDouble("radius", 10.0, 1e-3, 1e6);
  const double cut = params.getDouble("cut", 0.3, 0.0, 0.95);
  const bool inside = params.getInt("inside", 0, 0, 1) == 1;

  // Rings from the pole (k = 0) down to the cut (k = rings); triangles = slices·(2·rings − 1),
  // with slices chosen so that the triangles are about as wide as they are tall.
  const double theta_cut = std::acos(-cut);
  const int64_t rings = std::max<int64_t>(
      2, std::llround(std::sqrt(static_cast<double>(tris) * theta_cut / (4.0 * M_PI))));
  const int64_t slices =
      std::max<int64_t>(3, std::llround(2.0 * M_PI * static_cast<double>(rings) / theta_cut));

  std::vector<glm::dvec3> v(static_cast<size_t>((rings + 1) * slices));
  auto at = [&](int64_t k, int64_t j) -> glm::dvec3& {
    return v[static_cast<size_t>(k * slices + (j % slices))];
  };
  for (int64_t k = 0; k <= rings; ++k) {
    const double theta = theta_cut * static_cast<double>(k) / static_cast<double>(rings);
    // The last ring lies exactly on the cut so that the floor disc is exactly horizontal.
    const double y = k == rings ? -cut * radius : radius * std::cos(theta);
    const double rho = k == rings ? radius * std::sqrt(1.0 - cut * cut) : radius * std::sin(theta);
    for (int64_t j = 0; j < slices; ++j) {
      const double phi = 2.0 * M_PI * static_cast<double>(j) / static_cast<double>(slices);
      at(k, j) = k == 0 ? glm::dvec3(0.0, radius, 0.0) : glm::dvec3(rho * std::cos(phi), y, rho * std::sin(phi));
    }
  }
  Scene scene;
  scene.name = "gen:dome";
  const double sign = inside ? -1.0 : 1.0;
  const uint32_t color = 0xc08040;
  size_t i = 0;
  for (int64_t j = 0; j < slices; ++j) {
    const glm::dvec3 a = at(0, 0), b = at(1, j), c = at(1, j + 1);
    addOrientedTriangle(scene, a, b, c, sign * (a + b + c), shadeOf(color, i++), context);
  }
  for (int64_t k = 1; k < rings; ++k) {
    for (int64_t j = 0; j < slices; ++j) {
      const glm::dvec3 a = at(k, j), b = at(k, j + 1), c = at(k + 1, j), d = at(k + 1, j + 1);
      addOrientedTriangle(scene, a, c, b, sign * (a + b + c), shadeOf(color, i++), context);
      addOrientedTriangle(scene, b, c, d, sign * (b + c + d), shadeOf(color, i++), context);
    }
  }
  // The floor disc on the cut, facing up: one convex polygon over the bottom ring's vertices.
  std::vector<glm::dvec3> disc;
  for (int64_t j = slices - 1; j >= 0; --j) disc.push_back(at(rings, j));
  if (glm::dot(glm::cross(disc[1] - disc[0], disc[2] - disc[1]), glm::dvec3(0, 1, 0)) < 0.0) {
    std::reverse(disc.begin(), disc.end());
  }
  addFace(scene, disc, 0x707070, context);
  FloorLevel level;
  level.floor_y = -cut * radius;
  std::vector<glm::dvec2> piece;
  for (const auto& p : disc) piece.emplace_back(p.x, p.z);
  level.walkable.push_back(std::move(piece));
  scene.levels.push_back(std::move(level));
  scene.start_eye = {0.0, -cut * radius + scene.eye_height, 0.0};
  return scene;
}

}  // namespace walkvis
