// Mesh objects in the walkthrough: an animated Loop subdivision surface (backface/subdivision.h,
// Möller & Séquin's heuristic culling [MollerSequin])
// placed in a scene's start room and tessellated per frame for the eye and the frame's time.
//
// Objects are not part of the BSP or the trees: painter's frames draw them after the scene with a
// depth test against the depth the painter's pass left behind (scene_drawer.h, drawTriangles; why
// that is exact is explained in frames_common.h / settingsFor).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "backface/subdivision.h"
#include "scenes/scene.h"

namespace walkvis {

// Which objects a world gets: kAuto = the blob for the default scene (a gen:office spec), none
// otherwise; kNone; kBlob = the blob in any scene with a walkable level.
enum class ObjectSet : uint8_t { kAuto, kNone, kBlob };
ObjectSet parseObjectSet(std::string_view name);  // "auto", "none", "blob"; Error otherwise
std::string_view objectSetName(ObjectSet set);

struct MeshObject {
  glm::dvec3 center{0.0};  // world coordinates
  double scale = 1.0;      // world units per blob unit (the blob's radius is within [0.55, 1.45])
  int refine = 1;          // animatedBlob's control mesh refinement (80 control triangles)
  int levels = 3;          // Loop levels drawn (80·4^3 = 5120 final triangles)
  uint32_t color = 0xE0A040;
  uint32_t first_id = 0;   // ids drawn are first_id + final-level triangle index
  std::shared_ptr<const LoopTopology> topology;  // of the control mesh, `levels` levels
  uint32_t finalTriangles() const;  // final-level triangle count
};

// The animated blob standing in the room of the scene's start eye: the convex walkable piece of
// the lowest level under the start eye (else the largest one), up to 2.5 eye heights ahead along the
// start yaw, far enough from that piece's edges that the blob (its largest animated radius) stays
// inside; its size about half the eye height, floating at about eye height above the floor.
// nullopt when the scene has no walkable level. first_id is left 0 (the World sets it).
std::optional<MeshObject> placeBlob(const Scene& scene);

// The objects of `set` for a scene opened from `spec`, with ids from first_id on (the BSP's
// fragment count, so object ids never collide with fragment ids).
std::vector<MeshObject> makeObjects(ObjectSet set, const std::string& spec, const Scene& scene, uint32_t first_id);

// One frame of one object: front-facing final-level triangles for the eye, as corners in world
// coordinates (3 per triangle, counter-clockwise seen from the eye) and their ids.
struct ObjectTriangles {
  std::vector<glm::dvec3> corners;
  std::vector<uint32_t> ids;       // one per triangle: first_id + final-level triangle index
  uint32_t color = 0;
  uint64_t computed = 0;           // triangles computed over all levels (the control mesh included)
  uint32_t drawn() const { return static_cast<uint32_t>(ids.size()); }
};

// Subdivides the object at `time` (seconds) for `eye`. culling = true: Möller–Séquin (totally
// back-facing triangles are neither subdivided further nor drawn); false: full Loop subdivision.
// Either way the triangles kept are the final-level ones that face the eye (the exact double
// test), so both give the same triangles, bit for bit (test_subdivision.cpp's property), and only
// `computed` differs. `out` is overwritten (its capacity reused).
void tessellateObject(const MeshObject& object, double time, const glm::dvec3& eye, bool culling,
                      ObjectTriangles& out);

}  // namespace walkvis
