// Triangle soups into polygons: the faces of one input object (an assimp mesh instance, an OBJ
// `o`/`g` group, a glTF primitive of a node instance) that are adjacent and coplanar, and share a
// colour, become one face of convex polygons, before anything else sees them.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "scenes/scene.h"

namespace walkvis {

// A face colour meaning "no colour of its own": such faces merge with each other, and the face
// they become is coloured faceColor(face id), as loaders colour faces without a material.
constexpr uint32_t kFaceColorById = 0xFF000000u;

// Near-coplanar merging (reasons in mesh_merge.cpp). A face joins a merged face when every vertex is
// exactly coplanar with the seed face (exact orientation test) or within
// kMergePlaneUlps · 2^-24 · (largest |coordinate| of the object) of the seed's plane, AND its normal
// is within kMergeMaxAngle radians of the seed's normal. A face beyond either never merges.
constexpr double kMergePlaneUlps = 8.0;
constexpr double kMergeMaxAngle = 1e-4;

// One input object: faces as index loops into `positions` (`face_sizes[i]` indices each, in order;
// triangles are size 3), counter-clockwise seen from the front, with a colour per face (0xRRGGBB,
// or kFaceColorById).
struct MeshObjectInput {
  std::span<const glm::dvec3> positions;
  std::span<const uint32_t> indices;
  std::span<const uint32_t> face_sizes;
  std::span<const uint32_t> face_colors;
};

// Adds the object's faces to `scene`.
//
// Without `merge` every face goes through addFace(), in order.
//
// With `merge`: first, inside the object, a vertex of one face that lies on an edge of a
// merge-compatible face (same colour, normals within kMergeMaxAngle, on the edge within the plane
// tolerance) is inserted into that edge (counted in report.tjunctions_removed), so that the two
// faces share exact edges; edges between faces of different planes are never split. Then faces that
// share an edge (exactly equal endpoint positions, opposite directions), share a colour and lie in
// the seed face's plane (tolerance above) are grouped by flood fill from the largest faces down. A
// group's boundary (edges not cancelled by a reverse edge in the group) goes into convexPartition()
// in the group's plane; the pieces are lifted back onto the original vertex positions, with every
// boundary vertex the partition left out (straight-on corners) put back on its piece edge, so edges
// shared with faces outside the group stay watertight. The pieces become one face id with one plane
// (Newell's plane of the group); a piece whose vertices leave that plane by more than addFace's
// planarity tolerance becomes a fan of triangles with their own planes instead. A group whose
// pieces would not cover exactly its faces' area (overlapping faces) is not merged. Groups of one
// face, and faces that are degenerate, zero-area or non-planar on their own, go through addFace().
// Counts: report.input_faces counts every input face; a merged face counts once in kept_faces (one
// piece) or split_faces, and its faces in merged_input_faces (merged_faces counts merged faces).
//
// Returns, per input face in order, the face id it became (and appends the same to
// scene.report.input_to_face when merging). The object's faces get the next object number in
// scene.face_object. Face ids are given in order of each face's (group's)
// first input face. Throws Error (naming `context`) for non-finite coordinates, indices out of
// range or mismatched spans.
std::vector<uint32_t> addMeshObject(Scene& scene, const MeshObjectInput& object, bool merge,
                                    const std::string& context);

// Exact sign of the orientation of d against the plane through a, b, c (CGAL's filtered exact
// predicate, mesh_merge_cgal.cpp): +1, -1, or 0 when the four points are exactly coplanar.
int orient3dExact(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& d);

}  // namespace walkvis
