// Run-time backface culling of a polygon set: one interface, several methods. Papers (keys of
// docs/REFERENCES.md): [ZhangHoff1997], [JohannsenCarter1998], [Kumar1996]; library [meshoptimizer].
//
//   polygon  plane test per polygon, the baseline                       (polygon_cull.cpp)
//   mask     normal masks, Zhang & Hoff 1997                             (normal_mask.cpp)
//   cluster  clustered backface test, Johannsen & Carter 1998            (clustered.cpp)
//   cone     meshoptimizer meshlet normal cones, the modern peer         (meshlet_cone.cpp)
//   hierarchy  hierarchical back-face computation, Kumar et al. 1996    (hierarchical_kumar.cpp, kumar.h)
//
// Facing (docs/DESIGN.md, "Facing at emission"): a polygon with plane n·x = d is front-facing for
// an eye e exactly when e is strictly in its front half-space, n·e > d, evaluated as
// isFrontFacing() below. Every method is conservative: it never culls a polygon that
// isFrontFacing() calls front-facing, for any eye (view direction and field of view only sharpen a
// method; they never make it cull a front face, except the mask's view cone,
// BackfaceOptions::MaskCone::kView, which may cull front faces wholly outside the view cone:
// documented where it is declared).
//
// Usage: build once (makeBackfaceCuller), then per frame cull(view, unit_culled) into a buffer of
// unitCount() bytes that the caller owns; cull() allocates nothing. A method culls *units*: a unit
// is one polygon (polygon, mask), a cluster (cluster) or a meshlet (cone). unitPolygons(u) lists
// the polygons of unit u; expandToPolygons() turns unit flags into per-polygon flags.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "scenes/scene.h"

namespace walkvis {

// The ground truth every method is checked against: eye strictly in the front half-space.
inline bool isFrontFacing(const Plane& plane, const glm::dvec3& eye) { return glm::dot(plane.n, eye) > plane.d; }

// The polygons to cull: `polygons` index into `vertices` (Polygon::first_vertex, vertex_count), as
// in Scene. Planes are taken from Polygon::plane (unit normal). May be empty.
struct BackfaceInput {
  std::span<const glm::dvec3> vertices;
  std::span<const Polygon> polygons;
};
inline BackfaceInput backfaceInput(const Scene& scene) { return {scene.vertices, scene.polygons}; }

// One frame's view. view_dir need not be unit length; fov is the full apex angle of the circular
// view cone in radians (0, pi). Methods that do not use them ignore them.
struct BackfaceView {
  glm::dvec3 eye{0.0};
  glm::dvec3 view_dir{0.0, 0.0, -1.0};
  double fov = 1.0471975511965976;  // 60 degrees
};

enum class BackfaceMethod { kPolygon, kMask, kCluster, kCone, kHierarchy };

// The widest vector instructions a per-frame pass may use (cluster's flat pass). The paths compute
// the same results; a level the CPU lacks falls back to the widest it has (checked at build).
enum class BackfaceSimd : uint8_t { kScalar, kSse2, kAvx2, kAuto };
// "polygon", "mask", "cluster", "cone", "hierarchy"; parseBackfaceMethod throws Error for anything else.
std::string_view backfaceMethodName(BackfaceMethod method);
BackfaceMethod parseBackfaceMethod(std::string_view name);

struct BackfaceOptions {
  // mask: cells per cube-face side (the paper's N; 6·N² <= 2048 clusters, so N in [1, 18]);
  // 0 = chosen from the polygon count (maskResolutionFor in normal_mask.h).
  int mask_resolution = 0;
  // mask: polygons per spatial group, each with its own view cone (paper §3.2); 0 = one group.
  uint32_t mask_group_size = 0;
  // mask: which cone of directions a table is built for.
  //   kGroups  each spatial group's cone, from the eye around the group's bounding sphere (§3.2):
  //            conservative for every polygon, for any eye; an eye inside a group's sphere culls
  //            nothing in that group.
  //   kView    the paper's §3.1 cone (view_dir, fov), one table per frame for everything: it never
  //            culls a front face that has a point inside the view cone. A front face wholly
  //            outside the cone may be culled; it lies outside any frustum the cone holds, so it
  //            draws nothing (walkthrough/frame.cpp passes the cone through the image's corners).
  //   kAuto    kGroups for a whole mesh (makeBackfaceCuller: eyes around an object), kView in
  //            priority lists (list_cull.h: eyes inside a building, whose group cones hold every
  //            direction, so that kGroups culls nothing there; see list_cull.cpp).
  enum class MaskCone : uint8_t { kAuto, kGroups, kView };
  MaskCone mask_cone = MaskCone::kAuto;
  // mask in priority lists with kGroups (list_cull.h): a chunk of fewer positions than this is
  // tested by the exact plane test instead of a table: one table costs about as much to build as the
  // plane test on a long run of listed polygons, and PFD runs are far shorter (docs/backface/README.md,
  // "Lists (list_cull)"); 1 = tables only.
  uint32_t mask_list_min_chunk = 512;
  // cluster: T/R, the time of one cluster test over the time to render one vertex (paper §3);
  // 0 = chosen from the polygon count (clusterTrFor below).
  double cluster_tr = 0.0;
  // cluster: side R of the near-field box, as a multiple of the model's bounding-box diagonal.
  double cluster_near_field = 10.0;
  // cluster: the box the eyes are in, for the culling probability that drives clustering (world
  // coordinates). Empty (lo > hi, the default): the paper's near-field box of side R =
  // cluster_near_field × the model's diagonal around each cluster's own origin b, i.e. a model seen
  // from around it. For eyes inside a building set it (list_cull.h does, to the box of all
  // vertices): with the box around b, parallel walls at any offsets score as well as one wall (b
  // moves to the outermost plane), so Algorithm 1 merges each wall orientation into one cluster,
  // which an eye inside the building never culls (docs/backface/README.md, "Clustered backface test").
  // A flat box (an eye height plane) is allowed: the probability is then over its area.
  glm::dvec3 cluster_eye_lo{INFINITY};
  glm::dvec3 cluster_eye_hi{-INFINITY};
  // cluster: arrange the cluster tests in a hierarchy with front-face tests at inner nodes (§2.3).
  // false (default): every leaf test, eight clusters per SIMD block, no branch (clustered.cpp):
  // cheaper per frame than the tree's branchy traversal (docs/backface/README.md, "Hierarchy").
  bool cluster_hierarchy = false;
  // cluster: the flat pass's vector path (kAuto: AVX2 where the CPU has it, else SSE2); the others
  // exist so that tests can check that the paths agree.
  BackfaceSimd simd = BackfaceSimd::kAuto;
  // cone: meshlet limits (64 / 124, docs/DESIGN.md, "Targets") and meshoptimizer's cone_weight.
  uint32_t cone_max_vertices = 64;
  uint32_t cone_max_triangles = 124;
  float cone_weight = 0.5f;
  // hierarchy (Kumar et al.): polygons per leaf cluster (the paper's 20), top-level normal cells
  // per cube-face side, and the eye move (share of the model diagonal) that skips tracking.
  // Its cull() updates tracking state: one culler per thread.
  uint32_t hierarchy_leaf_size = 20;
  int hierarchy_top_grid = 2;
  double hierarchy_jump = 0.5;
};

class BackfaceCuller {
 public:
  virtual ~BackfaceCuller() = default;
  virtual BackfaceMethod method() const = 0;
  // Writes unit_culled[u] = 1 when every polygon of unit u is back-facing (not front-facing) for
  // view.eye, 0 when it may not be. unit_culled.size() must be unitCount(). No allocation.
  virtual void cull(const BackfaceView& view, std::span<uint8_t> unit_culled) const = 0;
  // Bytes of per-frame test state (what the cull step reads besides the eye); the unit → polygon
  // lists are not counted: a renderer stores its polygons in that order instead.
  virtual size_t stateBytes() const = 0;

  size_t polygonCount() const { return polygon_count_; }
  size_t unitCount() const { return unit_begin_.empty() ? 0 : unit_begin_.size() - 1; }
  std::span<const uint32_t> unitPolygons(size_t unit) const {
    return {unit_polygons_.data() + unit_begin_[unit], unit_begin_[unit + 1] - unit_begin_[unit]};
  }

 protected:
  size_t polygon_count_ = 0;
  std::vector<uint32_t> unit_begin_;     // unitCount() + 1 offsets into unit_polygons_
  std::vector<uint32_t> unit_polygons_;  // polygon indices; a polygon may be in several units (cone)
};

// Builds a culler. Throws Error when an option is out of range or a polygon has a
// non-finite plane.
std::unique_ptr<BackfaceCuller> makeBackfaceCuller(BackfaceMethod method, const BackfaceInput& input,
                                                   const BackfaceOptions& options = {});

// polygon_culled[p] = 1 when every unit that holds polygon p is culled (a polygon in no unit is
// kept). polygon_culled.size() must be culler.polygonCount(). No allocation.
void expandToPolygons(const BackfaceCuller& culler, std::span<const uint8_t> unit_culled,
                      std::span<uint8_t> polygon_culled);

// cluster's T/R: `requested` when > 0; for 0, from the polygon count: min(1, max(0.25, √(4000/n))),
// the paper's peak T/R = 1 up to 4,000 polygons. Why: at a fixed T/R the clusters get larger as a
// mesh gets finer, so the per-frame pass shrinks to a vanishing share while effectiveness falls
// behind the meshlet cones'; T/R ∝ 1/√n keeps the cluster count growing with the mesh, and with it
// the effectiveness (docs/backface/README.md, "Clustered backface test"). Negative or non-finite: Error.
double clusterTrFor(size_t polygons, double requested);

// Per-method builders (one file each).
std::unique_ptr<BackfaceCuller> makePolygonCuller(const BackfaceInput& input);
std::unique_ptr<BackfaceCuller> makeNormalMaskCuller(const BackfaceInput& input, const BackfaceOptions& options);
std::unique_ptr<BackfaceCuller> makeClusterCuller(const BackfaceInput& input, const BackfaceOptions& options);
std::unique_ptr<BackfaceCuller> makeConeCuller(const BackfaceInput& input, const BackfaceOptions& options);
std::unique_ptr<BackfaceCuller> makeHierarchyCuller(const BackfaceInput& input, const BackfaceOptions& options);

// cone: polygon_invisible[p] = 1 when polygon p has no area at single precision: meshoptimizer
// finds no triangle of it with nonzero area in the float positions the cone culler gives it (a
// meshlet of only such polygons is culled for every eye by the documented test: the library's
// "trivial reject"), or its area is below what rounding its vertices to float can create or erase
// (its float normal is then noise). Such a polygon has no pixels; this lets a report tell those
// culls apart from culls of polygons that have area (meshlet_cone.cpp). Throws Error unless
// polygon_invisible.size() == input.polygons.size().
void coneInvisiblePolygons(const BackfaceInput& input, std::span<uint8_t> polygon_invisible);

// Johannsen & Carter's near-field culling probability of one cluster test (exposed for tests):
// the fraction of the cube [-half, half]³ (local coordinates around the origin b) in which
// Comp_e(N, M)·e − d <= 0.
double nearFieldCullProbability(const glm::dvec3& n_min, const glm::dvec3& n_max, double d, double half);
// The same over the box [lo, hi] (local coordinates around b; lo <= hi, an axis may be flat): the
// share of the box's volume (of its area or length over the axes with extent) where the test culls.
double boxCullProbability(const glm::dvec3& n_min, const glm::dvec3& n_max, double d, const glm::dvec3& lo,
                          const glm::dvec3& hi);

}  // namespace walkvis
