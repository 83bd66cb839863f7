// Loop subdivision of an animated control mesh with Möller & Séquin's heuristic backface culling
// [MollerSequin]; implementation in
// subdivision_moller.cpp.
//
// Classes of a triangle at each level, for an eye e (a triangle (a, b, c) is front-facing when
// ((b − a) × (c − a))·(e − a) > 0, back-facing otherwise):
//   back    not front-facing;
//   strong  back, and every triangle sharing a vertex with it (its v- and e-neighbours) is back;
//   total   strong, and every such neighbour is strong.
// Totally back-facing triangles are neither subdivided further nor drawn; strongly back-facing
// ones are subdivided (their children feed the Loop stencils of the front side). Triangles whose
// neighbours are all front-facing ("totally front") pass that on to their children, whose status
// is then not computed (the paper's frontface shortcut).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

namespace walkvis {

// A closed, oriented 2-manifold triangle mesh: every edge is used once in each direction.
// Triangles are counter-clockwise seen from outside. Vertices need not all be used.
struct ControlMesh {
  std::vector<glm::dvec3> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
};

// The connectivity of every subdivision level; it does not depend on the positions, so an
// animated mesh builds it once. Level L+1 has the vertices of level L (same indices) followed by
// one per edge of level L; triangle t = (a, b, c) of level L has the children 4t..4t+3:
// (a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca).
class LoopTopology {
 public:
  // Throws Error when `triangles` is not a closed oriented manifold over vertex_count
  // vertices, or max_levels is outside [0, 6].
  LoopTopology(std::span<const std::array<uint32_t, 3>> triangles, size_t vertex_count, int max_levels);

  struct Level {
    std::vector<std::array<uint32_t, 3>> triangles;
    size_t vertex_count = 0;
    std::vector<std::array<uint32_t, 4>> edges;      // a, b (a < b), the opposite vertices c and d
    std::vector<std::array<uint32_t, 3>> tri_edges;  // edges of (v0v1, v1v2, v2v0)
    std::vector<uint32_t> ring_begin, ring;          // vertex neighbours (CSR, ascending)
    std::vector<uint32_t> fan_begin, fan;            // triangles around each vertex (CSR)
  };
  int maxLevels() const { return static_cast<int>(levels_.size()) - 1; }
  const Level& level(int l) const { return levels_[static_cast<size_t>(l)]; }

 private:
  std::vector<Level> levels_;
};

enum class FacingClass : uint8_t { kFront, kTotalFront, kBack, kStrong, kTotal };

struct SubdivisionResult {
  // Final-level positions, indexed as LoopTopology::Level::vertex_count; a vertex that was not
  // computed (culling) is NaN.
  std::vector<glm::dvec3> vertices;
  // The final-level triangles drawn: every one computed (with culling, the totally back-facing
  // ones were dropped a level earlier, with their parents; the final level's own back faces are
  // left to the per-triangle test), with their class at the final level (front / total front /
  // back: strong and total are not computed there, they would decide nothing).
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<FacingClass> classes;
  // Per level 0..levels: triangles and vertices computed (level 0 is the control mesh).
  std::vector<uint64_t> triangles_computed;
  std::vector<uint64_t> vertices_computed;
  // Triangles of a subdivided parent that could not be computed because a Loop stencil reached a
  // culled region (the heuristic's blind spot); they are dropped. Summed over the levels.
  uint64_t incomplete = 0;
};

// Subdivides `levels` times (<= topology.maxLevels()) with the given control positions (one per
// control vertex, finite). culling = false is plain Loop subdivision of the whole mesh; both modes
// compute every vertex they compute with the same arithmetic, so they agree bit for bit.
SubdivisionResult subdivide(const LoopTopology& topology, std::span<const glm::dvec3> control_positions, int levels,
                            const glm::dvec3& eye, bool culling);
// The same, building the topology on the way (throws Error as LoopTopology does, and for a
// non-finite position).
SubdivisionResult subdivide(const ControlMesh& mesh, int levels, const glm::dvec3& eye, bool culling);

// The test and bench mesh: an icosahedron refined `refine` times (20·4^refine triangles) whose
// vertices move radially with time t (a smooth, closed, deforming blob of radius about 1).
ControlMesh animatedBlob(double t, int refine = 1);

}  // namespace walkvis
