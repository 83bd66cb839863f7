// The geometric records every stage shares: a plane and a convex polygon indexing a vertex array.
//
// Conventions (docs/DESIGN.md, "Conventions"): right-handed, y up. A polygon is convex and planar
// with >= 3 vertices, counter-clockwise seen from its front; its plane is n·x = d with |n| = 1 and
// the front half-space n·x > d.
#pragma once

#include <cstdint>

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

}  // namespace walkvis
