// The exact BSP tree (Fuchs, Kedem, Naylor, "On visible surface generation by a priori tree
// structures", SIGGRAPH 1980 [FuchsKedemNaylor1980]), built by autopartition, with back-to-front
// and front-to-back traversal for an eye anywhere in space, statistics and a versioned, checksummed
// file format.
//
// Exactness (docs/DESIGN.md, "Hard cases" and "Numerics"). Every node plane is the plane of one
// input polygon, taken as its double coefficients (n, d) read as exact rationals. Each fragment is
// represented exactly while the tree is built: an input polygon's double vertices are projected
// exactly onto its own plane (so every fragment is exactly planar), straddlers are split at exact
// plane/segment intersections, and every vertex is classified against every plane exactly
// (bsp_build_cgal.cpp). A straddler whose vertices on one side all lie within 2^-30 of the scene's
// extent of the plane loses that sliver instead of being split (drop_slivers). After the build
// only double approximations of the fragment vertices are kept, for drawing: the ORDER was decided
// exactly. At query time the side of a double eye against
// a double plane is an exact sign too (bsp/exact_sign.h). So no point or fragment is ever
// classified inconsistently, however thin or nearly parallel the input.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "scenes/scene.h"

namespace walkvis {

enum class SplitHeuristic {
  kLeastCrossed,  // per node: among `candidates` sampled polygons, the one whose plane crosses the fewest
                  // of (a sample of) the others, ties broken by balance
  kRandom,        // random-order autopartition: a random polygon of the node's set
};

struct BspOptions {
  SplitHeuristic heuristic = SplitHeuristic::kLeastCrossed;
  uint32_t candidates = 24;  // kLeastCrossed: candidate planes tried per node (>= 1)
  uint64_t seed = 1;        // both heuristics: the choice is deterministic for a seed
  // kLeastCrossed: each candidate is scored on up to `samples` polygons of the node's set (all of
  // them when fewer) as split_weight · crossed + |front − back|. (A bonus per coplanar polygon was
  // retired: docs/bsp/README.md.)
  uint32_t samples = 256;
  double split_weight = 20.0;
  // kLeastCrossed: a node set of at most this many fragments is scored exactly (every distinct
  // plane of the set a candidate, all fragments counted) with one level of lookahead: the best
  // next split on each side is added to a candidate's crossings (bsp_build_cgal.cpp). 0 = never.
  uint32_t lookahead_max = 128;
  // kLeastCrossed, sets bigger than lookahead_max: when (fragments × distinct planes of the set)
  // <= full_count_max, every distinct plane is counted on the whole set instead of sampling
  // `candidates` × `samples`. 0 = always sample.
  uint64_t full_count_max = 64'000'000;
  // kLeastCrossed, exact scoring (lookahead or full count): a plane that crosses none of the set's
  // fragments is taken before any plane that crosses some (the most balanced such plane); it also
  // turns the pilot method off. Off by default: it makes trees up to three times as deep, and what
  // that does to the PFD and HFD builds is measured in docs/bsp/README.md.
  bool free_first = false;
  // kLeastCrossed, exact scoring: the crossing count of a horizontal candidate plane (normal ±y,
  // a floor or ceiling) is multiplied by this. Below 1 it favours horizontal planes, which cut
  // only walls spanning their height and keep floors of other heights away from walls that would
  // cut them. With exact_heuristic_sides 1.0 is best on almost every scene (docs/bsp/README.md).
  double horizontal_weight = 1.0;
  // kLeastCrossed, exact scoring: a crossed HORIZONTAL fragment (a floor or ceiling cut by a
  // vertical plane) counts this much instead of 1 in a candidate's crossings (lookahead included).
  // Above 1 it keeps big floors whole, which are otherwise cut again and again down the tree.
  double horizontal_fragment_weight = 1.0;
  // kLeastCrossed, pilot method: at a node of at least pilot_min_set fragments and depth <=
  // pilot_depth_max (root = 1), the pilot_candidates best planes by the greedy score are each
  // completed by a greedy build of both subtrees (counted on double approximations, not kept),
  // and the plane whose subtree has the fewest fragments is taken. 0 or 1 = off (plain greedy);
  // also off with free_first.
  // Cost: up to pilot_candidates greedy builds of the node's set per pilot node, so the total is
  // bounded by pilot_work_max (fragments summed over the node sets of all rollouts): a node is
  // piloted only while its estimated cost (pilot_candidates · m · (log2 m + 1)) fits in what is
  // left; other nodes (in build order, front subtrees first) use plain greedy. What the defaults
  // buy and cost: docs/bsp/README.md.
  uint32_t pilot_candidates = 8;
  uint32_t pilot_min_set = 64;
  uint32_t pilot_depth_max = 12;
  uint64_t pilot_work_max = 6'000'000;
  // kLeastCrossed: the heuristic (scores and pilot rollouts) counts a vertex within its tolerance
  // (1e-9 of the scene's extent) of a candidate plane by the exact side of its double position,
  // as the build's exact classification will, instead of as on the plane. Plane coefficients are
  // rounded doubles, so a point on a sloped wall's line (a floor corner, a collinear wall's end)
  // lies a hair off that wall's plane and the exact build splits a sliver off its polygon; the
  // heuristic now sees such splits and avoids them. false = the old count (all such vertices on).
  // It matters only with drop_slivers off (docs/bsp/README.md).
  bool exact_heuristic_sides = true;
  // A straddler whose vertices on one side all lie within 2^-30 of the scene's extent of the plane
  // is not split: that side's piece, thinner than the float coordinates a frame is drawn with can
  // resolve (2^-24 of the extent), is dropped and counted (BspStats::slivers_dropped), and the rest
  // goes whole to the other side. Double plane coefficients are rounded, so a vertex shared by two
  // faces of a curved or sloped mesh lies a hair off its neighbour's plane, and an exact split
  // would cut a sliver off almost every neighbour of a chosen face (docs/DESIGN.md, "Slivers";
  // figures in docs/bsp/README.md). The order of every fragment kept
  // is still decided exactly. With it the heuristic counts such vertices as on the plane (whatever
  // exact_heuristic_sides says), as the build will.
  bool drop_slivers = true;
  // Detail (the idea of Quake's detail brushes, made exact; docs/DESIGN.md, "Detail"). A detail
  // group is a connected piece of one input object (polygons joined by exactly equal vertices;
  // without Scene::face_object the whole scene is one object) whose bounding box is small against
  // a storey: its largest side is below detail_extent × the scene's eye height (furniture, frames,
  // mullions, railings, stair treads). With detail_extent > 0:
  //  - every node whose set still holds a structural fragment takes its plane from a structural
  //    fragment: detail never splits walls, floors or slabs; the structure splits a detail group
  //    only where one of its planes crosses it;
  //  - a set of detail fragments only, from two or more groups, is divided by a separating plane
  //    that crosses none of them: an axis-aligned plane in a gap between the groups' bounding boxes,
  //    else the plane of one group's face with that group wholly behind it. Such a node holds no
  //    fragment (BspNode::polygon == kSeparatorPolygon); the groups' sides are proved exactly;
  //  - where no separating plane exists (interpenetrating groups), or inside one group, the set is
  //    autopartitioned as usual and the sets where separation failed are counted
  //    (BspStats::detail_inseparable).
  // Every order stays exact: a separating plane orders what lies on its two sides like any node.
  // 0 = every polygon is structure, the default: on the FZK-Haus house detail made the tree
  // larger, its curved furniture being split by its own planes either way (docs/DESIGN.md,
  // "Detail"; docs/bsp/README.md).
  double detail_extent = 0.0;
};

// BspNode::polygon of a separating node (a plane between detail groups, holding no fragment).
inline constexpr uint32_t kSeparatorPolygon = UINT32_MAX;

struct BspNode {
  Plane plane;                  // the node plane: exactly Scene::polygons[polygon].plane, or a separator's
  uint32_t polygon = 0;         // the input polygon (index into Scene::polygons) the plane comes from,
                                // or kSeparatorPolygon
  int32_t front = -1;           // child in n·x > d; -1 = none
  int32_t back = -1;            // child in n·x < d; -1 = none
  int32_t parent = -1;          // -1 for the root
  uint32_t first_fragment = 0;  // fragments [first_fragment, first_fragment + fragment_count) lie in
  uint32_t fragment_count = 0;  // the node plane (either orientation); >= 1 except at a separator (0)
  uint32_t depth = 1;           // root = 1
};

struct BspStats {
  uint64_t nodes = 0;
  uint64_t fragments = 0;       // N
  uint64_t input_polygons = 0;  // n (polygons of the scene)
  double ratio = 0.0;           // N / n (0 for an empty scene)
  uint32_t depth_max = 0;       // nodes on the longest root-to-leaf path
  double depth_mean = 0.0;      // mean over fragments of their node's depth (tests to reach it)
  double build_seconds = 0.0;   // wall time of buildBsp
  uint64_t bytes = 0;           // memory of the tree's arrays (vertices, fragments, nodes, indices)
  uint64_t exact_fallbacks = 0; // vertex classifications the double filter could not decide
  uint64_t detail_objects = 0;  // input objects with a detail group (BspOptions::detail_extent)
  uint64_t detail_groups = 0;   // detail groups (connected pieces kept out of the structure)
  uint64_t detail_polygons = 0; // their polygons (of input_polygons)
  uint64_t structure_fragments = 0;  // fragments of structural polygons (the rest are detail)
  uint64_t detail_separators = 0;    // separating nodes (no fragments) between detail groups
  uint64_t detail_inseparable = 0;   // detail sets of 2+ groups with no separating plane (split instead)
  uint64_t detail_cuts = 0;          // axis-aligned cutting nodes (no fragments) in detail sets
  uint64_t slivers_dropped = 0;      // sliver pieces not kept (BspOptions::drop_slivers)
};

struct BspTree {
  std::vector<glm::dvec3> vertices;        // double approximations of fragment vertices, consecutive per fragment
  std::vector<Polygon> fragments;          // face_id = input face id; plane = its input polygon's plane
  std::vector<uint32_t> fragment_polygon;  // index of the input polygon (Scene::polygons) each fragment came from
  // Per fragment, its plane relative to its node's plane: +1 the same coefficients, -1 exactly
  // negated, 0 otherwise (a degenerate fragment that lies in the node plane; ask sideOfPlane).
  std::vector<int8_t> fragment_orientation;
  std::vector<BspNode> nodes;              // nodes[root] is the root; children have larger indices
  int32_t root = -1;                       // -1 for an empty tree
  uint64_t scene_hash = 0;                 // sceneHash() of the scene it was built from
  BspStats stats;

  std::span<const glm::dvec3> fragmentVertices(uint32_t f) const {
    return {vertices.data() + fragments[f].first_vertex, fragments[f].vertex_count};
  }
};

// The detail groups of a scene (BspOptions::detail_extent): per polygon its group, numbered from 0
// in polygon order, or kStructureGroup. Empty `group` when there is no detail at all.
inline constexpr uint32_t kStructureGroup = UINT32_MAX;
struct DetailGroups {
  std::vector<uint32_t> group;
  uint64_t groups = 0;
  uint64_t objects = 0;   // input objects with at least one detail group
  uint64_t polygons = 0;  // polygons in detail groups
};
DetailGroups detailGroups(const Scene& scene, double detail_extent);

// Builds the tree over all polygons of the scene. Throws Error for a polygon whose plane is
// not finite or has a zero normal (Scene's loaders never make one). Deterministic for given options.
BspTree buildBsp(const Scene& scene, const BspOptions& options = {});

// Fragment indices for `eye`, appended to `order` (cleared first; no allocation once it has the
// capacity). Back-to-front: a fragment never comes after one that lies in front of it on a ray
// from the eye. skip_back_faces drops fragments whose front half-space does not contain the eye
// (eye on the plane counts as back: nothing to see edge-on). The eye may be anywhere in space.
void backToFront(const BspTree& tree, const glm::dvec3& eye, std::vector<uint32_t>& order,
                 bool skip_back_faces = false);
void frontToBack(const BspTree& tree, const glm::dvec3& eye, std::vector<uint32_t>& order,
                 bool skip_back_faces = false);

// Exact side of a point against a plane read as exact rationals: +1 in front (n·p > d), -1
// behind, 0 on it.
int planeSide(const Plane& plane, const glm::dvec3& point);
// Exact side of a point against a fragment's plane: +1 front, -1 back, 0 on.
int sideOfPlane(const BspTree& tree, uint32_t fragment, const glm::dvec3& point);

// A fingerprint of the scene's polygons (vertices, planes, face ids), so that a loaded tree can
// be checked against the scene it is used with.
uint64_t sceneHash(const Scene& scene);
// Throws Error("<context>: ...") when the tree was not built from this scene (its
// scene_hash differs), e.g. a saved tree loaded for another model or version of it.
void checkBspMatchesScene(const BspTree& tree, const Scene& scene, const std::string& context);

// Writes the tree atomically (a temporary file next to `path`, then rename). Error naming
// the path when it cannot be written.
void saveBsp(const BspTree& tree, const std::string& path);
// The bytes saveBsp writes (header and payload), for files that embed a BSP (pfd.h's tree files).
// Error naming `context` when the tree's fragment arrays disagree in length. with_timing false
// writes build_seconds as 0, so that the bytes depend only on the tree (reproducible builds).
std::vector<uint8_t> bspFileBytes(const BspTree& tree, const std::string& context, bool with_timing = true);
// Reads a tree written by saveBsp. Error naming the path for a missing file, a wrong magic
// or version, a checksum mismatch, a truncated file or any index out of range; never crashes
// or allocates more than the file's size implies.
BspTree loadBsp(const std::string& path);
// The same from bytes in memory (for tests and fuzzers); `context` names the source in messages.
BspTree loadBspFromMemory(std::span<const uint8_t> bytes, const std::string& context);

}  // namespace walkvis
