// The geometric records every stage shares: a plane and a convex polygon indexing a vertex array.
//
// Conventions (docs/DESIGN.md, "Conventions"): right-handed, y up. A polygon is convex and planar
// with >= 3 vertices, counter-clockwise seen from its front; its plane is n·x = d with |n| = 1 and
// the front half-space n·x > d.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace walkvis {

struct Plane {
  glm::dvec3 n{0.0, 1.0, 0.0};  // unit normal
  double d = 0.0;               // n·x = d on the plane
};

// A convex planar polygon: vertices [first_vertex, first_vertex + vertex_count) of the array it
// belongs to (Scene::vertices, BspTree::vertices).
struct Polygon {
  uint32_t first_vertex = 0;
  uint32_t vertex_count = 0;
  uint32_t face_id = 0;  // index into Scene::face_colors; fragments keep their input face's id
  Plane plane;
};

// A ball holding a polygon: its centre is the mean of the corners, its radius the farthest corner's
// distance. Not the smallest such ball, but one sum and one pass, and within twice its radius.
struct Ball {
  glm::dvec3 centre{0.0};
  double radius = 0.0;
};
// The polygon's corners must lie in `vertices`; one without corners gets the empty ball at 0.
inline Ball polygonBall(std::span<const glm::dvec3> vertices, const Polygon& polygon) {
  Ball ball;
  if (polygon.vertex_count == 0) return ball;
  const std::span<const glm::dvec3> corners = vertices.subspan(polygon.first_vertex, polygon.vertex_count);
  for (const glm::dvec3& v : corners) ball.centre += v;
  ball.centre /= static_cast<double>(corners.size());
  for (const glm::dvec3& v : corners) ball.radius = std::max(ball.radius, glm::length(v - ball.centre));
  return ball;
}

}  // namespace walkvis
