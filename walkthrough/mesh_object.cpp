// Mesh objects (mesh_object.h): Loop subdivision with Möller & Séquin's heuristic backface culling
// (T. Möller, C. H. Séquin, "Heuristic backface culling of animated subdivision surfaces"
// [MollerSequin];
// backface/subdivision.h) of the animated blob (animatedBlob), placed in the start room.
#include "walkthrough/mesh_object.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

namespace walkvis {
namespace {

constexpr double kBlobMaxRadius = 1.45;  // animatedBlob's radius bound (subdivision_moller.cpp)

// Signed clearance of q inside a convex (x, z) piece: the smallest distance to an edge's line,
// negative outside. Orientation-free (the sign of the shoelace area says which side is in).
double clearance(const std::vector<glm::dvec2>& piece, const glm::dvec2& q) {
  double area2 = 0.0;
  for (size_t k = 0; k < piece.size(); ++k) {
    const glm::dvec2 &a = piece[k], &b = piece[(k + 1) % piece.size()];
    area2 += a.x * b.y - b.x * a.y;
  }
  const double orient = area2 >= 0.0 ? 1.0 : -1.0;
  double best = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < piece.size(); ++k) {
    const glm::dvec2 &a = piece[k], &b = piece[(k + 1) % piece.size()];
    const glm::dvec2 e = b - a;
    const double len = std::hypot(e.x, e.y);
    if (len == 0.0) continue;
    best = std::min(best, orient * (e.x * (q.y - a.y) - e.y * (q.x - a.x)) / len);
  }
  return best;
}

bool front(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& eye) {
  return glm::dot(glm::cross(b - a, c - a), eye - a) > 0.0;
}

}  // namespace

ObjectSet parseObjectSet(std::string_view name) {
  for (ObjectSet s : {ObjectSet::kAuto, ObjectSet::kNone, ObjectSet::kBlob})
    if (objectSetName(s) == name) return s;
  throw Error("objects '" + std::string(name) + "': expected auto, none or blob");
}

std::string_view objectSetName(ObjectSet set) {
  switch (set) {
    case ObjectSet::kAuto: return "auto";
    case ObjectSet::kNone: return "none";
    case ObjectSet::kBlob: return "blob";
  }
  return "?";
}

uint32_t MeshObject::finalTriangles() const {
  return topology ? static_cast<uint32_t>(topology->level(topology->maxLevels()).triangles.size()) : 0u;
}

std::optional<MeshObject> placeBlob(const Scene& scene) {
  if (scene.levels.empty()) return std::nullopt;
  // The level under the start eye (the highest floor at or below it), else the lowest.
  const FloorLevel* level = &scene.levels.front();
  for (const FloorLevel& l : scene.levels)
    if (l.floor_y <= scene.start_eye.y) level = &l;
  const glm::dvec2 start(scene.start_eye.x, scene.start_eye.z);
  const std::vector<glm::dvec2>* piece = nullptr;
  double piece_area = -1.0;
  for (const auto& p : level->walkable) {
    if (p.size() < 3) continue;
    double area2 = 0.0;
    for (size_t k = 0; k < p.size(); ++k) area2 += p[k].x * p[(k + 1) % p.size()].y - p[(k + 1) % p.size()].x * p[k].y;
    if (clearance(p, start) >= 0.0) {
      piece = &p;
      break;
    }
    if (std::abs(area2) > piece_area) piece_area = std::abs(area2), piece = &p;
  }
  if (!piece) return std::nullopt;
  glm::dvec2 origin = start;
  if (clearance(*piece, start) < 0.0) {
    origin = glm::dvec2(0.0);
    for (const glm::dvec2& v : *piece) origin += v;
    origin /= static_cast<double>(piece->size());
  }
  const double e = scene.eye_height;
  // Ahead along the start yaw (camera_path.h: yaw 0 looks along -z, positive turns towards -x).
  const glm::dvec2 ahead(-std::sin(scene.start_yaw), -std::cos(scene.start_yaw));
  const double want_radius = 0.45 * e;
  double best_t = 0.0, best_clear = clearance(*piece, origin);
  for (double t = 2.5 * e; t >= 1.0 * e; t -= 0.25 * e) {
    const double c = clearance(*piece, origin + t * ahead);
    if (c >= 1.1 * want_radius) {
      best_t = t, best_clear = c;
      break;
    }
    if (c > best_clear) best_t = t, best_clear = c;
  }
  if (!(best_clear > 0.0)) return std::nullopt;
  const double radius = std::min(want_radius, best_clear / 1.1);
  MeshObject object;
  const glm::dvec2 c = origin + best_t * ahead;
  object.center = {c.x, level->floor_y + 0.75 * e, c.y};
  object.scale = radius / kBlobMaxRadius;
  const ControlMesh control = animatedBlob(0.0, object.refine);
  object.topology = std::make_shared<const LoopTopology>(control.triangles, control.positions.size(), object.levels);
  return object;
}

std::vector<MeshObject> makeObjects(ObjectSet set, const std::string& spec, const Scene& scene, uint32_t first_id) {
  std::vector<MeshObject> objects;
  const bool blob = set == ObjectSet::kBlob || (set == ObjectSet::kAuto && spec.rfind("gen:office", 0) == 0);
  if (blob) {
    if (std::optional<MeshObject> o = placeBlob(scene)) {
      o->first_id = first_id;
      objects.push_back(std::move(*o));
    } else if (set == ObjectSet::kBlob) {
      throw Error(spec + ": no walkable level to place the blob in");
    }
  }
  return objects;
}

void tessellateObject(const MeshObject& object, double time, const glm::dvec3& eye, bool culling,
                      ObjectTriangles& out) {
  out.corners.clear();
  out.ids.clear();
  out.color = object.color;
  out.computed = 0;
  if (!object.topology) return;
  ControlMesh control = animatedBlob(time, object.refine);
  for (glm::dvec3& p : control.positions) p = object.center + object.scale * p;
  const SubdivisionResult r = subdivide(*object.topology, control.positions, object.levels, eye, culling);
  for (uint64_t c : r.triangles_computed) out.computed += c;
  const LoopTopology::Level& final_level = object.topology->level(object.levels);
  for (const auto& t : r.triangles) {
    const glm::dvec3 &a = r.vertices[t[0]], &b = r.vertices[t[1]], &c = r.vertices[t[2]];
    if (!front(a, b, c, eye)) continue;
    // The triangle's index: the one around vertex t[0] with the same corners (subdivide copies
    // the level's triangles as they are).
    uint32_t index = UINT32_MAX;
    for (uint32_t f = final_level.fan_begin[t[0]]; f < final_level.fan_begin[t[0] + 1]; ++f) {
      if (final_level.triangles[final_level.fan[f]] == t) {
        index = final_level.fan[f];
        break;
      }
    }
    if (index == UINT32_MAX) continue;
    out.corners.push_back(a);
    out.corners.push_back(b);
    out.corners.push_back(c);
    out.ids.push_back(object.first_id + index);
  }
}

}  // namespace walkvis
