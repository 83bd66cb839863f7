// One walkthrough frame, independent of where it is drawn (the window, offscreen frames, `bench
// frames`): which polygons to draw for a camera, in which order, after which culling, and what it
// cost. Drawing itself is scene_drawer.h.
//
//   zbuffer  all fragments, any order, depth test on (the baseline; GL back-face culling on)
//   bsp      backToFront over the BSP (any eye), depth test off
//   pfd      the PFD tree of the level under the eye (pfdQueryRuns), BSP order where no tree
//            covers the eye (off the height plane, stairs), depth test off
//   hfd      the same with an HFD tree file
// Each mode then applies the backface method (list_cull.h) per run (pfd, hfd) or over all
// fragments (bsp, zbuffer).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "backface/list_cull.h"
#include "bsp/bsp.h"
#include "pfd_hfd/pfd.h"
#include "scenes/scene.h"
#include "walkthrough/camera.h"
#include "walkthrough/mesh_object.h"
#include "walkthrough/occlusion_buffer.h"

namespace walkvis {

enum class OrderMode : uint8_t { kZBuffer, kBsp, kPfd, kHfd };
std::string_view orderModeName(OrderMode mode);  // "zbuffer", "bsp", "pfd", "hfd"
OrderMode parseOrderMode(std::string_view name);  // Error otherwise

struct WorldOptions {
  LoadOptions load;              // for a scene spec
  // For a tree file: the scene it was built from (colours; checked against the BSP's scene hash).
  // Empty: a scene is derived from the tree file itself: its BSP fragments as polygons, the trees'
  // walkable regions as levels, faceColor(face_id) as colours (a tree file holds no colours).
  std::string scene;
  bool build_pfd = false;        // a scene spec: also build PFD trees (default options) in memory
  ListCullMethod cull = ListCullMethod::kNone;  // list cullers are built for this method
  BackfaceOptions backface;
  // Mesh objects (mesh_object.h): kAuto puts the animated blob in the default scene (gen:office).
  // For a tree file the spec checked is `scene` when given.
  ObjectSet objects = ObjectSet::kAuto;
  bool frustum_culling = true;   // World::frustum_culling
  bool occlusion_culling = true; // World::occlusion_culling
  OcclusionOptions occlusion;
};

// Everything frames need, built once: the scene, its BSP, the trees when there are any (a tree
// file made by `walkvis build`, or built in memory), and the list cullers.
struct World {
  Scene scene;
  TreeFile trees;          // trees.bsp is THE BSP; trees.levels empty when no trees
  std::string source;      // what it was opened from
  // Per level and cell, the list culler over that tree's runs (empty when cull is kNone/kRegion).
  std::vector<std::vector<ListCuller>> run_cullers;
  std::unique_ptr<ListCuller> all_culler;  // over all BSP fragments (bsp and zbuffer modes)
  ListCullMethod cull = ListCullMethod::kNone;
  std::vector<uint32_t> all_fragments;     // 0..N-1, the index array all_culler was built over
  // Drawn after the scene in every mode; their ids start at N (the fragment count).
  std::vector<MeshObject> objects;
  bool object_culling = true;              // Möller–Séquin culling while subdividing (else full Loop)
  // Per BSP fragment, a ball around it (one per fragment whenever frustum_culling is on): a fragment
  // whose ball lies outside the view frustum is left out of the frame (FrameStats::outside). The
  // image stays the same: GL would have clipped it away, after transforming its corners and
  // setting up its triangles.
  std::vector<Ball> fragment_balls;
  bool frustum_culling = true;
  // The painter's modes (bsp, pfd, hfd) then leave out what a few large fragments of the frame's
  // own list hide from this eye (occlusion_buffer.h; FrameStats::occluded). The image stays the
  // same: a painter's order paints over a hidden fragment wherever it would show. The z-buffer
  // baseline draws what the frustum holds.
  bool occlusion_culling = true;
  OcclusionOptions occlusion;
  // The level whose height plane the eye is on (|eye.y − height| within 1e-9 of the height's scale:
  // camera paths store heights in decimal), if any: an index into trees.levels (and run_cullers).
  std::optional<uint32_t> levelAt(const glm::dvec3& eye) const;
};

// A scene spec (loadScene) or a tree file (detected by its magic). Error naming the file
// otherwise. `progress` may be empty.
World openWorld(const std::string& source, const WorldOptions& options,
                const std::function<void(const std::string&)>& progress = {});

struct FrameStats {
  uint32_t scene_polygons = 0;  // BSP fragments N
  uint32_t listed = 0;          // from the order source, before culling
  uint32_t culled = 0;          // by the backface method
  uint32_t outside = 0;         // of what the backface method kept: wholly outside the view frustum
  uint32_t occluded = 0;        // of the rest: hidden behind the frame's occluders (occlusion_buffer.h)
  uint32_t occluders = 0;       // fragments that covered some cell of the occlusion buffer
  uint32_t occluded_pixels = 0; // the occluded fragments' reach: pixels of the cells their tests looked at
  bool occlusion_rested = false;  // occlusion culling on, but this frame rested (OcclusionOptions)
  uint32_t drawn = 0;           // listed - culled - outside - occluded
  uint32_t tests = 0;           // plane tests (PFD/HFD: the path's and the detail objects'; BSP: nodes visited)
  double order_ms = 0.0;        // query + culling
  double draw_ms = 0.0;         // filled by the drawer's caller
  double object_ms = 0.0;       // subdividing the mesh objects (not in order_ms)
  uint32_t object_triangles = 0;           // final-level object triangles drawn (front-facing)
  uint64_t object_triangles_computed = 0;  // object triangles computed over all subdivision levels
  int level = -1;               // the level tree used, -1 for none
  OrderMode used = OrderMode::kBsp;  // what actually produced the order (pfd falls back to bsp)
};

// Per-thread scratch; no allocation per frame once warmed up. It also paces occlusion culling by the
// frames it built before, per mode (OcclusionOptions), so that a walk's counts depend on its path.
class FrameBuilder {
 public:
  // Fills `draw` with BSP fragment indices, first drawn first (back to front for painter's modes),
  // and tessellates world.objects for the eye at `time` (seconds; the animation clock), kept in
  // objects() until the next build.
  FrameStats build(const World& world, const FreeCamera& camera, OrderMode mode, std::vector<uint32_t>& draw,
                   double time = 0.0);
  // One per world.objects entry, from the last build.
  const std::vector<ObjectTriangles>& objects() const { return objects_; }

 private:
  std::vector<uint32_t> run_indices_;  // the PFD path's runs, as indices into PfdTree::runs
  std::vector<uint32_t> scratch_;
  std::vector<uint8_t> keep_;          // per fragment, for culling a BSP order with a list culler
  std::vector<ObjectTriangles> objects_;
  OcclusionBuffer occlusion_;
  // Occlusion culling's pacing per order mode (OcclusionOptions::min_occluded_pixels): frames left to
  // rest, and the rest after the next test that finds little.
  struct OcclusionPace {
    uint32_t rest = 0;
    uint32_t next_rest = 1;
  };
  std::array<OcclusionPace, 4> pace_{};
  std::vector<std::pair<double, uint32_t>> candidates_;  // apparent size, fragment
  // Leaves out of `draw` (order kept) what the occlusion buffer hides: stats.occluded, occluders.
  void cullOccluded(const World& world, const FreeCamera& camera, std::vector<uint32_t>& draw, FrameStats& stats);
};

}  // namespace walkvis
