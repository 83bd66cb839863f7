// Kumar, Manocha, Garrett & Lin 1996, "Hierarchical back-face computation" [Kumar1996] (method
// `hierarchy`):
// the pieces below BackfaceCuller, exposed so that tests can compare view-point tracking with the
// full region membership test. Implementation: hierarchical_kumar.cpp (clusters, tracking) and
// kumar_regions_cgal.cpp (the CGAL step: LP for an interior point, convex hull in the dual).
//
// A region is an intersection of closed half-spaces n_i·x <= d_i (|n_i| = 1): the BackRegion of a
// cluster uses its polygons' planes, the FrontRegion the same planes negated. About an interior
// point c (the paper's CB) with g_i = d_i − n_i·c > 0, the dual point of plane i is p_i = n_i / g_i
// and x = c + y is in the region iff max_i p_i·y <= 1. Only the vertices of the convex hull of the
// p_i can attain that maximum (the paper's boundary planes h^b), and a vertex whose p·y is not below
// any hull neighbour's attains it (a linear function on a convex polytope has no other local
// maxima). The cone of y where vertex k attains it is the paper's Query cell of boundary face k;
// its side planes are the planes p_k·y = p_j·y through c and the edge of faces k and j.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "backface/backface.h"
#include "scenes/scene.h"

namespace walkvis {

// One region in plain form (what kumar_regions_cgal.cpp hands back).
struct KumarRegion {
  // False when no interior point was found (the region is empty or flat): then no eye is
  // ever reported inside it, which errs toward "not inside" (conservative).
  bool has_interior = false;
  glm::dvec3 center{0.0};          // c, strictly inside
  double g_min = 0.0;              // distance from c to the nearest plane: the inscribed ball's radius
  double scale = 0.0;              // |c|₁ + max_i |d_i|: the magnitude plane evaluations round at
  double p_max = 0.0;              // max_k |p_k|₁
  std::vector<glm::dvec3> dual;    // p_k of the boundary planes (hull vertices)
  std::vector<uint32_t> plane;     // for each boundary plane, the index of its input half-space
  // The boundary planes and the input half-spaces merged into them (near-equal dual points): what
  // a parent cluster's region must consider of this one.
  std::vector<uint32_t> members;
  std::vector<uint32_t> adj_begin; // dual.size() + 1 offsets into adj: hull neighbours of k
  std::vector<uint32_t> adj;
};

// Builds the region of the half-spaces n·x <= d of `planes` (|n| = 1, finite). The interior point
// is the centre of the largest ball inside the region and inside the box [box_lo, box_hi] (an LP,
// solved exactly by CGAL); the boundary planes come from the convex hull of the dual points (CGAL,
// exact predicates). Never throws for finite input; an empty `planes` gives has_interior = false.
KumarRegion buildKumarRegion(std::span<const Plane> planes, const glm::dvec3& box_lo, const glm::dvec3& box_hi);

enum class KumarVerdict : uint8_t {
  kMixed = 0,  // neither region holds the eye (or it is too close to a boundary to tell)
  kBack = 1,   // the eye is in the BackRegion: every polygon of the cluster is back-facing
  kFront = 2,  // the eye is in the FrontRegion: every polygon is front-facing
};

struct KumarOptions {
  uint32_t leaf_size = 20;  // the paper's threshold: clusters are subdivided down to this size
  int top_grid = 2;         // top-level clusters: top_grid² normal cells per cube face
  // A move of the eye longer than this share of the model's bounding-box diagonal since the last
  // frame skips the walk and runs the full test (which also re-seeds the tracked cells).
  double jump_fraction = 0.5;
};

struct KumarStats {
  uint64_t queries = 0;         // region queries (two per Mixed node at most)
  uint64_t walk_steps = 0;      // Query cells walked to
  uint64_t full_tests = 0;      // queries answered by a scan of every boundary plane
  uint64_t inscribed_hits = 0;  // queries answered by the inscribed ball or cone
};

// The cluster hierarchy with its regions and the per-node tracking state (last Query cell of each
// region, last verdict, visit counters). Tracking mutates that state: one instance per thread.
class KumarHierarchy {
 public:
  KumarHierarchy(const BackfaceInput& input, const KumarOptions& options);

  size_t nodeCount() const { return nodes_.size(); }
  size_t leafCount() const { return leaf_begin_.empty() ? 0 : leaf_begin_.size() - 1; }
  // Node 0.. are in preorder; roots are the nodes with no parent. Polygons of a node's subtree.
  std::span<const uint32_t> nodePolygons(size_t node) const;
  std::span<const uint32_t> leafPolygons(size_t leaf) const {
    return {leaf_polygons_.data() + leaf_begin_[leaf], leaf_begin_[leaf + 1] - leaf_begin_[leaf]};
  }
  // Leaves [first, second) of a node's subtree.
  std::pair<uint32_t, uint32_t> nodeLeafRange(size_t node) const { return {nodes_[node].leaf_begin, nodes_[node].leaf_end}; }
  const KumarRegion& backRegion(size_t node) const { return nodes_[node].back; }
  const KumarRegion& frontRegion(size_t node) const { return nodes_[node].front; }

  // Starts a frame: visit counters of earlier frames stop matching. cull() calls it.
  void beginFrame();
  // Verdict for one node by view-point tracking (eye in the model's own frame): inscribed cone
  // first when the eye was inside that region last time, then a walk from the last Query cell, a
  // full test after a large jump or a long walk. Equal to classifyFull() (tests check it).
  KumarVerdict track(size_t node, const glm::dvec3& eye);
  // The same verdict from a scan of every boundary plane of both regions (no state used).
  KumarVerdict classifyFull(size_t node, const glm::dvec3& eye) const;

  // One frame (beginFrame, then track() down the hierarchy): leaf_culled[l] = 1 when leaf l is all back-facing (found at the leaf or above).
  // leaf_culled.size() must be leafCount(). No allocation.
  void cull(const glm::dvec3& eye, std::span<uint8_t> leaf_culled);
  // Rigid motion (paper §7): the model is drawn with world = rotation·object + translation; the
  // eye is taken back into the object's frame and the regions are reused unchanged.
  void cullRigid(const glm::dmat3& rotation, const glm::dvec3& translation, const glm::dvec3& eye_world,
                 std::span<uint8_t> leaf_culled);

  size_t stateBytes() const;  // what cull() reads: regions, node links, tracking state
  const KumarStats& stats() const { return stats_; }

 private:
  struct RegionState {
    uint32_t cell = 0;  // last Query cell (index into the region's dual)
  };
  struct Node {
    KumarRegion back, front;
    RegionState back_state, front_state;
    glm::dvec3 back_axis{0.0};    // inscribed cone of the BackRegion: apex c, axis, cos of half-angle
    double back_cos = 2.0;        // > 1: no cone
    glm::dvec3 front_axis{0.0};
    double front_cos = 2.0;
    uint32_t back_offset = 0;     // into visit_ (one counter per boundary plane)
    uint32_t front_offset = 0;
    uint32_t leaf_begin = 0, leaf_end = 0;
    uint32_t skip = 0;            // preorder: the node after this subtree
    KumarVerdict last = KumarVerdict::kMixed;
    glm::dvec3 last_eye{0.0};
    bool seen = false;
  };

  bool inRegion(const KumarRegion& region, RegionState& state, uint32_t visit_offset, const glm::dvec3& axis,
                double cos_half, bool try_cone, const glm::dvec3& eye, bool jumped);
  static bool inRegionFull(const KumarRegion& region, const glm::dvec3& eye, uint32_t* best);

  std::vector<Node> nodes_;
  std::vector<uint32_t> leaf_begin_, leaf_polygons_;
  std::vector<uint32_t> visit_;  // visit counters of the boundary planes: the frame they were last tested
  uint32_t frame_ = 0;
  double jump_ = 0.0;
  KumarStats stats_;
};

}  // namespace walkvis
