// The scene model: convex planar polygons with input-face ids, planes and a colour per input
// face; floor levels with their walkable regions; an eye height and a start eye. Nothing else
// (docs/DESIGN.md, "Model only what a scene needs").
//
// Conventions (docs/DESIGN.md, "Conventions"): right-handed, y up, the scene's own units; Plane and
// Polygon are core/geometry.h's. Loading errors are core/error.h's Error, naming the file (and
// line, where there is one) and what is wrong.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "core/error.h"
#include "core/geometry.h"

namespace walkvis {

// A floor level: every distinct floor height gives the height plane y = floor_y + eye height.
// The walkable region is a union of convex polygons of the xz-plane, stored as (x, z) pairs.
// loadScene() normalises every piece to counter-clockwise seen from above (+y), which is a
// negative shoelace area in (x, z) coordinates; walkable_area is the (positive) total area.
struct FloorLevel {
  double floor_y = 0.0;
  std::vector<std::vector<glm::dvec2>> walkable;
  double walkable_area = 0.0;
};

// What the loader changed on the way in. Every input face is counted once in exactly one of
// kept_faces, split_faces and dropped_*, except that the input faces merged into one face count
// once together: input_faces == kept_faces + split_faces + dropped_zero_area + dropped_degenerate
// + (merged_input_faces - merged_faces), and there are face_colors.size() == input_faces -
// (merged_input_faces - merged_faces) face ids.
struct LoadReport {
  uint64_t input_faces = 0;
  uint64_t kept_faces = 0;             // convex and planar: one polygon each
  uint64_t split_faces = 0;            // non-convex or non-planar: split into convex pieces
  uint64_t split_pieces = 0;           // polygons those split faces became
  uint64_t dropped_zero_area = 0;      // area below the scene's tolerance
  uint64_t dropped_degenerate = 0;     // fewer than 3 distinct vertices
  // Triangle soups (mesh_merge.h): input faces merged with adjacent coplanar faces of their object
  // into one face each (counted in input_faces as themselves; kept/split count the merged faces).
  uint64_t merged_input_faces = 0;     // input faces that went into a merged face
  uint64_t merged_faces = 0;           // the faces they became
  uint64_t tjunctions_removed = 0;     // vertices inserted on an edge to match a neighbour's edge
  // For each input face (in file order), the face id it ended up in; filled only when faces were
  // merged (otherwise input face i is face id i). Lets tests and tools map ids back to input faces.
  std::vector<uint32_t> input_to_face;
  std::vector<std::string> notes;      // anything else the loader wants a user to know
};

// A walkable surface that joins levels (a stair's treads, a ramp, a landing under the minimum
// level area): convex xz pieces of the scene's upward faces (slope up to the maximum), each on its
// own plane (floor y at (x, z) is where the vertical line meets the plane). Pieces in the cells
// next to a level carry the foot of a ramp or the tread beside a riser, so that a walker finds a
// floor all the way; a piece may lie over a lower surface within a climb (stacked in one cell).
// The walkthrough climbs it and uses the BSP order there, as anywhere off a level's height plane.
struct WalkablePatch {
  std::vector<glm::dvec2> piece;  // (x, z), counter-clockwise seen from above like FloorLevel pieces
  Plane plane;                    // upward-facing (n.y > 0)
};
struct WalkableConnection {
  std::vector<uint32_t> levels;   // indices into Scene::levels that this surface touches, ascending
  std::vector<WalkablePatch> patches;
  double area = 0.0;              // xz area of its navmesh cells (cell size² × cells)
};

struct Scene {
  std::string name;                     // the scene argument it was loaded from
  std::vector<glm::dvec3> vertices;     // polygon vertices, consecutive per polygon
  std::vector<Polygon> polygons;
  std::vector<uint32_t> face_colors;    // one per input face id, 0xRRGGBB
  std::vector<FloorLevel> levels;       // sorted by floor_y, distinct heights
  std::vector<WalkableConnection> connections;  // stairs and ramps between levels (walkable.h)
  // Per face id, the input object it came from (a mesh instance, an OBJ group, a glTF primitive of
  // a node), numbered from 0 in load order; empty when the source has no objects (WAD maps,
  // generators). The BSP keeps small objects out of the structure (bsp.h, detail_extent).
  std::vector<uint32_t> face_object;
  double eye_height = 1.7;
  glm::dvec3 start_eye{0.0};            // on a height plane: floor under it + eye_height
  double start_yaw = 0.0;               // radians; 0 looks along -z, positive turns towards -x
  LoadReport report;

  std::span<const glm::dvec3> polygonVertices(const Polygon& p) const {
    return {vertices.data() + p.first_vertex, p.vertex_count};
  }
  std::span<const glm::dvec3> polygonVertices(size_t i) const { return polygonVertices(polygons[i]); }
};

// Walkable floors found the way a navmesh finds them (walkable.h, Recast). Lengths in scene units
// after unit scaling; < 0 means the default written beside it. Out of range (Error): agent
// height not positive or not finite, radius not in [0, 10 × agent height], climb not in
// [0, agent height), slope not in (0, 90), minimum area negative or not finite.
struct WalkableOptions {
  double agent_height = -1.0;   // headroom a walker needs; default eye height × 1.2
  double agent_radius = -1.0;   // kept from walls and ledges; default eye height × 0.15 (Walker's radius)
  double max_climb = -1.0;      // highest step; default eye height × 0.2 (0.34 m for a 1.7 m eye)
  double max_slope_deg = 45.0;  // steepest walkable slope
  double min_level_area = -1.0; // smaller connected floors are not levels; default (eye height)² × 0.35 (1 m² at 1.7)
};

struct LoadOptions {
  double eye_height = -1.0;  // < 0: the format's default (41 for WAD maps, 1.7 otherwise)
  // "" picks by extension (the project's own OBJ and glTF loaders); "assimp" reads any format
  // assimp knows, .obj and .gltf included.
  std::string loader;
  char up_axis = 0;          // 0: as the file states (assimp formats), else 'y' or 'z'
  double unit_scale = -1.0;  // metres per file unit; < 0: as the file states (assimp formats), else 1
  bool merge_faces = true;   // merge adjacent coplanar triangles of one object (mesh_merge.h)
  // assimp formats: how long assimp may take to read a file before it is refused as malformed or
  // too large (the read is tried first in a forked child with this alarm, scenes/assimp.cpp).
  // Fuzzers lower it so that a slow input is an error, not a libFuzzer timeout.
  unsigned import_seconds_max = 300;
  // "" picks: exact sector floors for WAD maps, the navmesh (walkable.h) for OBJ, glTF and assimp
  // scenes, each generator's own; "faces" every upward horizontal face height; "navmesh" Recast.
  std::string floors;
  WalkableOptions walkable;
};

// Loads a scene from one scene argument: `model.obj`, `model.gltf`, `model.glb`,
// `freedoom2.wad:MAP07` (a bare WAD name is also looked up in /usr/share/games/doom), or
// `gen:NAME?key=value&...` (generators, see generators.h). Throws Error on bad input.
Scene loadScene(const std::string& spec, const LoadOptions& options = {});

// ---- Building a scene (used by every loader and generator) ----

// Adds one input face and gives it a new face id (returned). Vertices are in order around the
// face, counter-clockwise seen from the front; any count. A convex planar face becomes one
// polygon; a non-convex or non-planar one is split into convex planar pieces (CGAL); a face with
// fewer than 3 distinct vertices or zero area is dropped and counted. Throws Error for NaN or
// infinite coordinates (context names the file or generator in the message).
uint32_t addFace(Scene& scene, std::span<const glm::dvec3> vertices, uint32_t color,
                 const std::string& context);

// Adds a planar region given as rings in a plane: rings[0] and any others may be outer boundaries
// or holes in any orientation; a point is inside when it is inside an odd number of rings. The
// region is cut into convex pieces that all get one new face id (returned), facing `normal`.
// `to3d` maps a ring point (u, v) to 3D. Used for Doom sector floors and ceilings.
uint32_t addPlanarRegion(Scene& scene, const std::vector<std::vector<glm::dvec2>>& rings,
                         const glm::dvec3& origin, const glm::dvec3& u_axis, const glm::dvec3& v_axis,
                         uint32_t color, const std::string& context);

// Convex pieces of an odd-winding region given as rings (any orientation, holes allowed),
// counter-clockwise. Implemented with a CGAL constrained triangulation and Hertel–Mehlhorn merging.
std::vector<std::vector<glm::dvec2>> convexPartition(const std::vector<std::vector<glm::dvec2>>& rings);

// Appends one convex planar polygon (vertices counter-clockwise about plane.n) with its face id;
// returns its index. For loaders that have already made convex pieces of a face.
uint32_t appendPolygon(Scene& scene, std::span<const glm::dvec3> vertices, uint32_t face_id, const Plane& plane);

// The signed area of a ring of 2D points, positive when counter-clockwise. Summed as a fan from
// the first point, so rounding scales with the ring's size rather than with its coordinates.
double signedArea(std::span<const glm::dvec2> ring);

// Whether p lies in the closed convex ring (either winding), by double orientation tests.
bool insideConvexRing(std::span<const glm::dvec2> ring, const glm::dvec2& p);

// The scene's upward horizontal polygons (n.y >= 1 - 1e-9) grouped by height, lowest first:
// heights within 1e-6 of the scene's size are one (files are level only up to their rounding).
// What floor levels are made of, by either method (deriveFloorLevels, walkable.h).
struct FloorHeight {
  double y = 0.0;                  // the lowest height of the group
  std::vector<uint32_t> polygons;  // indices into Scene::polygons
};
std::vector<FloorHeight> upwardFloorHeights(const Scene& scene);

// Derives floor levels from upward-facing horizontal polygons (OBJ, glTF, generators that do not
// set them): one level per distinct height, its walkable region the union of those polygons.
void deriveFloorLevels(Scene& scene);

// Turns a z-up scene y-up ((x, y, z) -> (x, z, -y), exact) and/or scales it by `scale`: vertices,
// planes and the start eye. For a scene whose levels are not derived yet (they are cleared).
void transformScene(Scene& scene, bool z_up, double scale);

// Sets start_eye (and level heights) after levels exist: the centre of the largest convex piece
// of the lowest level, at eye height, unless a loader already placed it above a walkable piece.
// A start that is not finite (NaN) means the source has none.
void placeStartEye(Scene& scene);

// Newell's plane of a polygon loop; n is zero when the loop has no area.
Plane newellPlane(std::span<const glm::dvec3> vertices);

// A stable colour for an input face id.
uint32_t faceColor(uint32_t face_id);

// ---- Summaries ----

struct Bounds {
  glm::dvec3 lo{0.0}, hi{0.0};
};
Bounds sceneBounds(const Scene& scene);
uint64_t triangleCount(const Scene& scene);  // sum over polygons of vertex_count - 2
// True when every polygon edge is matched by an edge of another polygon running the other way
// (vertex positions compared exactly).
bool isClosed(const Scene& scene);

}  // namespace walkvis
