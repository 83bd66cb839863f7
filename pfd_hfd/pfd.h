// The PFD tree (James & Day, "The priority face determination tree for hidden surface removal",
// Computer Graphics Forum 17(1), 1998 [JamesDay1998]; our definition is docs/DESIGN.md, "PFD tree"):
// a binary decision tree over the walkable region W of one height plane y = h. Each node holds a
// test-line (a BSP plane cut by the height plane) and a priority list; for an eye v = (x, h, z) the
// concatenated lists on v's root-to-leaf path draw exactly what backToFront(bsp, v, order, true)
// draws.
//
// Built by partial evaluation of the BSP back-to-front traversal over regions of the height plane
// (pfd_build_cgal.cpp): wherever the side of the current plane is the same for all of the region,
// the traversal carries on without a test; where its test-line crosses the region, a node splits
// the region and both children carry on from the same point of the traversal. Region corners are
// exact rationals (CGAL), so a test-line through a corner is recognised as touching, not crossing.
//
// Layout: a node's list is a range of `run_refs`; each reference is a flat run (a range of
// `fragment_ids`) or a sequence (a range of `seq_items`, each again a run or an older sequence).
// The order of a fully resolved BSP subtree is the concatenation of its far child's order, its
// node's fragments and its near child's order; such orders repeat each other's sub-orders on
// every branch of the tree (docs/DESIGN.md, "Sizes and errors"), so an order of at least
// `share_min` ids is stored as a sequence of references to its children's orders, each distinct
// order once; shorter ones are stored flat. A query expands the references into flat runs.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "bsp/bsp.h"
#include "pfd_hfd/visibility.h"
#include "scenes/scene.h"

namespace walkvis {

enum class PfdHeuristic {
  kTraversal,  // test the first undecided line in BSP traversal order (the baseline)
  kBalanced,   // among up to `candidates` undecided lines ahead in the traversal, the one that
               // splits the region's area most evenly
};

// PfdOptions::search_lines and root_search_lines are capped at this many lines.
constexpr uint32_t kPfdMaxSearchLines = 128;

struct PfdOptions {
  PfdHeuristic heuristic = PfdHeuristic::kBalanced;
  // kBalanced: undecided lines examined per split (>= 1). Without HFD the leaves are the cells of
  // the crossing lines whatever the order (nodes and the entropy bound do not change), so the
  // mean tests exceed the entropy bound by Σ over nodes of the node's area fraction × (1 − the
  // binary entropy of its split): the more candidates, the more even the splits, up to about 128
  // (docs/pfd/README.md, "The knobs of the test-line choice").
  uint32_t candidates = 128;
  // kBalanced, PFD (not HFD): candidates are also taken from beneath undecided lines, not only from
  // the frontier of the traversal. Every BSP line that crosses a region is tested somewhere below
  // it whatever the order, so testing a deeper line first changes neither the leaves nor the nodes,
  // only how evenly the region is split (docs/pfd/README.md, "The knobs of the test-line choice").
  // Under HFD a subtree may turn out hidden below, and a line tested ahead of it would be a
  // needless node: HFD keeps the frontier.
  bool deep_candidates = true;
  // kBalanced, PFD with deep_candidates: where the lines still to be tested in a region are at
  // most this many, the whole order of the tests below it is chosen by an optimal search for the
  // least area-weighted mean tests (pfd_search.h: branch and bound over the sets of leaves a region
  // holds; in double precision, as it only picks which line to test: every classification stays
  // exact). 0 = off, also at the root. Small trees, whose few leaves are very unequal, are where the
  // greedy even split is furthest from the optimum. search_work bounds the work (CellSearch::work)
  // one tree may spend on such searches (then the greedy choice), so big trees pay a bounded
  // amount (docs/pfd/README.md, "What the search costs and gives").
  uint32_t search_lines = 16;
  uint64_t search_work = 4'000'000;
  // With search_lines > 0: the root's search applies where up to this many lines cross the whole
  // region (at most kPfdMaxSearchLines), with its own budget (not spent from search_work). A
  // completed search holds the best line for every region below it, which the nodes below then
  // follow (no search of their own), so a tree whose root search completes is optimal among trees
  // testing these lines (PfdStats::tests_optimal). Trees of more lines rarely complete within any
  // budget that is small beside their build (docs/pfd/README.md, "The knobs of the test-line
  // choice" and "What the search costs and gives").
  uint32_t root_search_lines = 80;
  uint64_t root_search_work = 25'000'000;
  // Clip off W the slivers (narrower than 1e-9 of the region's extent) that BSP lines cut from it
  // only because plane coefficients are rounded (pfd_region_cgal.h, trimSlivers): each would be
  // a test for a leaf of no area. Eyes that close to a wall's plane leave the region.
  bool trim_slivers = true;
  bool dedup = true;         // store each distinct emitted run once (false: one run per emission)
  // PFD with dedup: a resolved subtree's order of at least this many ids is stored as a sequence
  // referring to its children's orders; shorter ones flat. Smaller: less memory, more (shorter)
  // runs per query.
  uint32_t share_min = 64;
  // Bytes one tree may take while it is built (its arrays plus the dedup index); 0 = no limit.
  // Exceeding it throws PfdBudgetError.
  uint64_t max_memory = 0;
  uint32_t stat_eyes = 10000;  // random eyes in the region for tests_mean / tests_max (0: skip)
  uint64_t seed = 1;           // for those eyes
  // HFD tree when set (must outlive the build): a fragment about to join a node's list is first
  // tested with visibility->visibleFromRegion(fragment, node region) and dropped when hidden; a
  // fragment hidden from a region is not tested again below it (hidden from a region => hidden
  // from its sub-regions), and a BSP subtree whose fragments are all hidden gets no test-line.
  const VisibilityScene* visibility = nullptr;
  // true: lists hold only fragments front-facing for every eye of their region (facing is known at
  // emission, docs/DESIGN.md, "Facing at emission": the exact `region` backface method). false:
  // back-facing fragments are listed too, where backToFront(bsp, eye, order, false) puts them, for
  // run-time culling methods.
  bool drop_back_faces = true;
  // Detail objects (docs/DESIGN.md, "Detail objects in lists"): with drop_back_faces, every
  // maximal BSP subtree whose fragments fit in a box of largest side <= object_extent (scene
  // units; 0 = none) and lie in their nodes' planes (orientation ±1) is listed as ONE entry, an
  // object (PfdTree::objects), that a query expands by walking the subtree's own planes for the
  // eye, back to front. Its planes are never test-lines: a chair's dozens of small planes no longer
  // split every region they cross, at the cost of one plane test per object node in each query
  // that lists it (PfdQueryResult::object_tests). The order stays exactly backToFront's. HFD drops
  // an object whose fragments are all hidden from the region, else lists it whole.
  // PfdLevelOptions::object_extent sets it from the eye height.
  double object_extent = 0.0;
  // HFD: an object with at least a few fragments still to test is first tested by the faces of its
  // bounding box (VisibilityScene::boxVisibleFromRegion); a hidden box drops it whole, and its
  // fragments stay hidden in the sub-regions. false: its fragments only.
  bool object_boxes = true;
  // Called (may be empty) from the building thread after each leaf with the fraction of the
  // region's area that finished leaves cover, for progress and an ETA by area.
  std::function<void(double)> progress;
};

// The detail objects of `bsp` at `extent` (PfdOptions::object_extent): per BSP node 1 where an
// object is rooted, 2 strictly inside one, 0 elsewhere (the structure). All 0 for extent <= 0.
// `boxes` (may be null): per BSP node the bounding box (lo, hi) of its subtree's fragments; left
// empty for extent <= 0.
std::vector<uint8_t> pfdObjectNodes(const BspTree& bsp, double extent,
                                    std::vector<std::pair<glm::dvec3, glm::dvec3>>* boxes = nullptr);

enum class TreeKind : uint8_t { kPfd = 0, kHfd = 1 };
const char* treeKindName(TreeKind kind);  // "pfd", "hfd"

// Thrown when a build would exceed its memory budget. A tree that ran out records how far it got:
// its bytes when it stopped (a lower bound of what it needs) and the share of its region's area
// finished by then (0 when unknown), from which the level's message estimates the whole need.
struct PfdBudgetError : Error {
  using Error::Error;
  PfdBudgetError(const std::string& what, uint64_t bytes_when_stopped, double area_done)
      : Error(what), bytes(bytes_when_stopped), area_fraction(area_done) {}
  uint64_t bytes = 0;
  double area_fraction = 0.0;
};

// Mean wall time of one query at random eyes of a tree's region (timePfdQueries), for the build's
// report. Measured by whoever built the tree, right after, and carried with its outcome
// (pfdCellOutcomeBytes, the journal); never in tree files.
struct PfdQueryTiming {
  uint32_t eyes = 0;  // 0: not measured
  double pfd_ns = 0.0, runs_ns = 0.0, refs_ns = 0.0, bsp_ns = 0.0;
  double runs_mean = 0.0;          // runs per query
  double refs_mean = 0.0;          // ranges of run_refs per query (pfdQueryRefs)
  double object_tests_mean = 0.0;  // plane tests inside detail objects per query
};

struct PfdStats {
  uint64_t fragments = 0;         // N: fragments of the BSP
  uint64_t nodes = 0;             // PFD nodes (leaves included)
  uint64_t leaves = 0;
  uint64_t depth_max = 0;         // tests on the longest root-to-leaf path
  uint64_t list_entries = 0;      // run references stored in node lists
  uint64_t list_fragments = 0;    // fragment ids the lists would hold without runs (naive storage)
  uint64_t pool_entries = 0;      // fragment ids stored (each distinct run once)
  uint64_t runs = 0;              // distinct runs
  uint64_t seqs = 0;              // distinct sequences (orders stored as references to sub-orders)
  uint64_t seq_items = 0;         // references stored in sequences
  uint64_t test_planes = 0;       // distinct planes used as test-lines
  uint64_t exact_fallbacks = 0;   // corner-versus-line signs the double filter could not decide
  uint64_t touching = 0;          // line-versus-region decisions where a corner lay exactly on the line
  uint64_t decisions = 0;         // line-versus-region decisions in all
  double tests_mean = 0.0;        // over `stat_eyes` random eyes in the region
  uint64_t tests_max = 0;
  double tests_entropy_bound = 0.0;  // Σ −a·log2 a over leaf area fractions a
  // The least mean tests of ANY binary decision tree with these leaves (Huffman's code over the
  // leaf area fractions: no prefix code does better, and a decision tree is one). Between the
  // entropy bound and the entropy bound + 1: on a tree with a few leaves of very unequal area
  // (entropy below ~3 bits) no tree can reach 1.3 × the entropy, but it can reach this.
  double tests_huffman_bound = 0.0;
  // Another lower bound on mean tests, from the geometry: a leaf is reached only after testing
  // every line that bounds it (it would straddle an untested one), so Σ over leaves of the area
  // fraction × the tested lines on the leaf's boundary. Where a big leaf is bounded by several
  // lines (slivers and thin cells beside it), this exceeds 1.3 × the entropy and no order of the
  // tests can meet that target. Without HFD the leaves are the same for every order. Computed by
  // the build; not stored in the tree file (0 after loading).
  double tests_cell_bound = 0.0;
  // The exact mean tests: Σ over leaves of the area fraction × the tests on its path (tests_mean
  // samples it). Build-only, like tests_cell_bound.
  double tests_area_mean = 0.0;
  // The mean tests the exhaustive search at the root predicted (PfdOptions::search_lines; double
  // regions): 0 where no search completed there. Build-only.
  double tests_search_mean = 0.0;
  // The root's search: the lines it took (0: none, as more than root_search_lines cross the root
  // region, or HFD) and its work (CellSearch::work), whether it completed or gave up. Build-only.
  uint32_t root_search_lines = 0;
  uint64_t root_search_work_done = 0;
  // No decision tree testing the BSP lines that cross the region has fewer mean tests (so where
  // tests_area_mean > 1.3 × the entropy bound, reordering the tests cannot meet that target): the
  // whole test order came from one completed exhaustive search at the root, followed down to every
  // leaf, and tests_area_mean equals tests_search_mean (relative 1e-9); or tests_area_mean meets
  // tests_huffman_bound or tests_cell_bound; or the tree has no test. Build-only (false after
  // loading).
  bool tests_optimal = false;
  double region_area = 0.0;
  uint64_t visibility_tests = 0;   // HFD: fragment-versus-region queries
  uint64_t visibility_rays = 0;    // HFD: occlusion rays cast
  uint64_t hidden_rejected = 0;    // HFD: fragments dropped from a list as hidden
  uint64_t visibility_witnessed = 0;  // HFD: tests saved by an ancestor's witness (not in tree files)
  uint64_t objects_box_rejected = 0;  // HFD: objects dropped whole by their hidden box (not in tree files)
  uint64_t visibility_hidden_rays = 0;  // HFD: rays of the tests answered hidden (not in tree files)
  // HFD, where the rays went (VisibilityCounters; not in tree files): tests proved hidden (one
  // blocker or one patch per sub-cone), the proof's rays, the refinement's rays, tests it found visible,
  // sub-cones proved by a patch of joined outlines.
  uint64_t visibility_proved_hidden = 0;
  uint64_t visibility_proof_rays = 0;
  uint64_t visibility_refine_rays = 0;
  uint64_t visibility_refined_visible = 0;
  uint64_t visibility_patch_covers = 0;
  uint64_t visibility_kept_unproven = 0;  // conservative mode: tests kept for want of a proof
  uint64_t objects = 0;           // detail objects the lists refer to (PfdOptions::object_extent)
  uint64_t object_nodes = 0;      // their BSP nodes
  uint64_t object_fragments = 0;  // their fragments
  uint64_t bytes = 0;             // the tree's arrays
  double build_seconds = 0.0;
  PfdQueryTiming query_timing;
};

struct PfdNode {
  uint32_t plane = 0;       // test-line: index into PfdTree::planes (internal nodes only)
  int32_t front = -1;       // child for planeSide(plane, eye) > 0; -1 for a leaf
  int32_t back = -1;        // child for planeSide(plane, eye) < 0 (and == 0, see pfdQuery)
  uint32_t first_ref = 0;   // list: run_refs[first_ref, first_ref + ref_count)
  uint32_t ref_count = 0;
};

struct PfdRun {
  uint32_t first = 0;  // fragment_ids[first, first + count)
  uint32_t count = 0;
};

// A list entry or sequence item: a run index, kPfdSeqBit | a sequence index, or kPfdObjectBit | an
// object index (runs and sequences number below kPfdObjectBit).
constexpr uint32_t kPfdSeqBit = 0x80000000u;
constexpr uint32_t kPfdObjectBit = 0x40000000u;
constexpr uint32_t kPfdNoRun = UINT32_MAX;
// Sequences nest at most this deep (a sequence of depth d holds items of depth < d; a run has
// depth 0): a query expands them with a fixed stack.
constexpr uint32_t kPfdMaxSeqDepth = 16;

struct PfdSeq {
  uint32_t first = 0;   // seq_items[first, first + count): runs or sequences of smaller index
  uint32_t count = 0;
  uint32_t length = 0;  // fragment ids it expands to (an object counted with all its fragments)
};

// A node of a detail object: a BSP node's plane and its fragments by facing, as flat runs.
struct PfdObjectNode {
  uint32_t plane = 0;            // index into PfdTree::planes: exactly the BSP node's plane
  int32_t front = -1;            // children: indices into PfdTree::object_nodes, larger than this one
  int32_t back = -1;
  int32_t parent = -1;           // -1 at the object's root
  uint32_t front_run = kPfdNoRun;  // run (PfdTree::runs) of the fragments facing an eye in front
  uint32_t back_run = kPfdNoRun;   // and of those facing an eye behind; kPfdNoRun: none
};

// A BSP subtree listed as one entry (PfdOptions::object_extent).
struct PfdObject {
  uint32_t root = 0;       // PfdTree::object_nodes[root, root + nodes), root first
  uint32_t nodes = 0;
  uint32_t fragments = 0;  // all its fragments, both facings
};

// An axis-aligned box of the xz-plane: a view cell. The region of a tree is W clipped to it.
struct PfdBox {
  glm::dvec2 lo{0.0}, hi{0.0};
};

struct PfdTree {
  double height = 0.0;                          // the height plane y = height
  std::optional<PfdBox> cell;                   // the view cell, or none: the whole of W
  std::vector<std::vector<glm::dvec2>> region;  // W ∩ cell as convex (x, z) pieces (double approximations)
  std::vector<Plane> planes;                    // test-line planes (BSP or fragment planes)
  std::vector<PfdNode> nodes;                   // nodes[0] is the root; children have larger indices
  std::vector<uint32_t> run_refs;               // runs or sequences (kPfdSeqBit)
  std::vector<PfdRun> runs;
  std::vector<PfdSeq> seqs;
  std::vector<uint32_t> seq_items;              // runs or sequences (kPfdSeqBit)
  std::vector<uint32_t> fragment_ids;           // BSP fragment indices
  std::vector<PfdObject> objects;               // detail objects (kPfdObjectBit references)
  std::vector<PfdObjectNode> object_nodes;
  PfdStats stats;
};

// Builds the PFD tree of `bsp` over the convex pieces `walkable` ((x, z), any orientation; empty
// or zero-area pieces are ignored) clipped to `cell` if given, on the height plane y = height.
// Throws PfdBudgetError when options.max_memory is exceeded, Error for non-finite input.
PfdTree buildPfd(const BspTree& bsp, std::span<const std::vector<glm::dvec2>> walkable, double height,
                 const std::optional<PfdBox>& cell, const PfdOptions& options = {});

// The test-lines that cross W ∩ cell (BSP node planes only) and its area: a tree's size grows
// with the square of the crossing lines (docs/DESIGN.md, "Sizes and errors": nodes ≈ 0.25–0.34·L²),
// so view cells are
// chosen by this count before anything is built.
struct PfdLineCount {
  uint64_t crossing = 0;
  double area = 0.0;
};
// Lines inside detail objects (`objects`: pfdObjectNodes of this BSP, or empty for none) are not
// counted: they are never tested. With `candidates`, only those BSP nodes are tried (a line that
// misses a cell misses every part of it, so a parent cell's crossing lines serve its quarters);
// `crossing`, when given, gets the indices of the crossing nodes in the order tried.
PfdLineCount countPfdLines(const BspTree& bsp, std::span<const std::vector<glm::dvec2>> walkable, double height,
                           const std::optional<PfdBox>& cell, std::span<const uint8_t> objects = {},
                           const std::vector<uint32_t>* candidates = nullptr, std::vector<uint32_t>* crossing = nullptr);

struct PfdQueryResult {
  uint32_t tests = 0;     // plane tests made (= internal nodes on the path)
  uint32_t object_tests = 0;  // plane tests inside the detail objects expanded (one per object node)
  bool on_line = false;   // the eye lay exactly on a test-line (went to the back child; the order
                          // is then only guaranteed where the BSP also counts the eye as behind)
};

// Appends the fragment ids for `eye` (at y = tree.height, (x, z) in the region) to `order`
// (cleared first; no allocation once it has the capacity). Equal to backToFront(bsp, eye, order,
// true) for such eyes not on any test-line.
PfdQueryResult pfdQuery(const PfdTree& tree, const glm::dvec3& eye, std::vector<uint32_t>& order);

// The same walk, appending the runs to draw (ranges of tree.fragment_ids, in order) instead of
// copying the ids: what a renderer that keeps per-fragment draw ranges needs. Sequences are
// expanded: only flat runs are appended.
PfdQueryResult pfdQueryRuns(const PfdTree& tree, const glm::dvec3& eye, std::vector<PfdRun>& runs);
// The same walk, appending run indices (into tree.runs; sequences expanded) instead: for per-run
// structures such as the backface list cullers (backface/list_cull.h), built over tree.runs.
PfdQueryResult pfdQueryRunIds(const PfdTree& tree, const glm::dvec3& eye, std::vector<uint32_t>& run_ids);

// The walk alone, without expanding anything: per node on the eye's path whose list is not empty,
// the range of tree.run_refs holding its list, root first (cleared first; no allocation once it
// has the capacity, at most depth_max + 1 ranges). This is the query's answer in James & Day's
// sense, a handful of ranges: its cost is the tests, not the length of the order. Expanding the
// ranges with pfdExpandRefs gives exactly pfdQueryRunIds's run ids.
struct PfdRefRange {
  uint32_t first = 0;  // tree.run_refs[first, first + count)
  uint32_t count = 0;
};
PfdQueryResult pfdQueryRefs(const PfdTree& tree, const glm::dvec3& eye, std::vector<PfdRefRange>& lists);
// Appends the flat run indices (into tree.runs) that `lists` expand to for `eye` (the eye orders
// the detail objects), in order; returns the object plane tests made.
uint32_t pfdExpandRefs(const PfdTree& tree, std::span<const PfdRefRange> lists, const glm::dvec3& eye,
                       std::vector<uint32_t>& run_ids);

// Frame coherence: the path of the last query and where each node's list starts in `order`.
// A query re-tests the path from the root and re-walks only from the first test whose side
// changed, keeping the order before it.
// Lists from the first one holding a detail object on are walked again for every eye (an
// object's order depends on the eye).
struct PfdCursor {
  std::vector<uint32_t> path;        // node indices, root first
  std::vector<uint32_t> order_size;  // order.size() before each path node's list
  uint32_t fixed = 0;                // path[0, fixed) hold no object
  const PfdTree* tree = nullptr;
};
PfdQueryResult pfdQueryCoherent(const PfdTree& tree, const glm::dvec3& eye, PfdCursor& cursor,
                                std::vector<uint32_t>& order);

// A uniformly random point of the region's pieces (by area), for tests and statistics.
glm::dvec2 samplePfdRegion(const PfdTree& tree, uint64_t& rng_state);

// The PFD walk against the BSP traversal it replaces (both with back faces skipped), at `eyes`
// random eyes of the tree's region (a fixed seed): pfd_ns writes out the whole order (ids), runs_ns
// its flat runs, refs_ns only the handful of run_refs ranges on the path (pfdQueryRefs: the walk
// itself, whose cost does not grow with the length of the order). Zero eyes or an empty region:
// nothing measured (eyes == 0).
PfdQueryTiming timePfdQueries(const BspTree& bsp, const PfdTree& tree, uint32_t eyes);

// Recomputes stats.tests_mean / tests_max over `eyes` random eyes (seeded) and stats.bytes.
void measurePfd(PfdTree& tree, uint32_t eyes, uint64_t seed);

// The least mean depth of a binary tree whose leaves have these weights (Huffman 1952
// [Huffman1952]; weights >= 0, any scale: they are normalised; 0 for fewer than two positive
// weights). O(L log L).
double huffmanMeanDepth(std::span<const double> weights);

// ---- Levels, view cells and the tree file ----

struct PfdLevelOptions {
  PfdOptions tree;
  // Per view cell: a tree over more than this many bytes is discarded and its cell cut into four
  // (by the middle of the cell's region bounds), down to max_cell_depth. 0 = one cell per level.
  // PFD levels are first planned into cells by an estimate of their size (pfd_level.cpp); HFD
  // levels start as one cell.
  uint64_t cell_memory = 64ull << 20;
  uint32_t max_cell_depth = 8;
  uint64_t max_memory = 1ull << 30;  // all trees of all levels together; exceeded: PfdBudgetError
  // tree.object_extent = object_extent × the eye height when > 0 (else tree.object_extent as set).
  double object_extent = 1.0;
};

struct PfdLevel {
  uint32_t level = 0;     // index into Scene::levels
  double floor_y = 0.0;
  double height = 0.0;    // floor_y + eye height
  std::vector<PfdTree> cells;  // disjoint view cells covering the level's walkable region
};

// One view cell's build: the unit of work of buildPfdLevels, which may run anywhere (another
// thread, another process under MPI) as long as it is built with the same PfdCellContext.
struct PfdCellJob {
  uint32_t level = 0;          // index into PfdCellContext::levels
  std::optional<PfdBox> box;   // none: the whole level
  uint32_t depth = 0;          // times this cell was cut
  uint64_t budget = 0;         // bytes the tree may take while built (PfdOptions::max_memory; 0: none)
  bool total_limited = false;  // budget is what the whole build had left (going over is then an error)
  double cost = 0.0;           // estimate of its work, for the order jobs start in and the ETA
};

// A job's result: the tree, or none when the build passed the job's budget (with how far it got,
// as PfdBudgetError records it).
struct PfdCellOutcome {
  std::optional<PfdTree> tree;
  uint64_t stopped_bytes = 0;
  double stopped_fraction = 0.0;
};

// What every cell's build reads beside its job; equal on every process of one build.
struct PfdCellContext {
  const BspTree* bsp = nullptr;
  std::span<const FloorLevel> levels;
  double eye_height = 0.0;
  PfdLevelOptions options;
};

// Builds one job. The tree depends on the context and the job only (not on thread or process), so
// a job built twice gives equal trees. `progress` as PfdOptions::progress.
PfdCellOutcome buildPfdCell(const PfdCellContext& context, const PfdCellJob& job,
                            const std::function<void(double)>& progress = {});

// Builds jobs[i] into outcomes[i] for every i (outcomes.size() == jobs.size()), in any order and
// anywhere, each with buildPfdCell and the context buildPfdLevels was given.
using PfdCellRunner = std::function<void(std::span<const PfdCellJob> jobs, std::span<PfdCellOutcome> outcomes)>;

// The first round's jobs of buildPfdLevels (budget: cell_memory), or with `by_lines` (true) every
// level's cells planned by the lines' estimate as PFD levels are, HFD ones too: for sampling a
// build's cost (walkvis plan). `only` as for buildPfdLevels. `progress` (levels planned, levels,
// cells so far) is called as each level is planned, from any thread, one call at a time.
std::vector<PfdCellJob> planPfdCells(const BspTree& bsp, std::span<const FloorLevel> levels, double eye_height,
                                     const PfdLevelOptions& options, std::span<const uint32_t> only = {},
                                     bool by_lines = false,
                                     const std::function<void(size_t, size_t, size_t)>& progress = {});

// One level's trees, cutting it into view cells where one tree exceeds cell_memory. `used_bytes`
// counts towards options.max_memory across calls. `progress` (may be empty) gets one line per cell.
PfdLevel buildPfdLevel(const BspTree& bsp, const FloorLevel& level, uint32_t level_index, double eye_height,
                       const PfdLevelOptions& options, uint64_t& used_bytes,
                       const std::function<void(const std::string&)>& progress = {});

// Every level's trees (levels[k] gets level index k). The build goes in rounds: all levels' planned
// cells are the jobs of the first round; a cell whose tree passes cell_memory is cut into four,
// which are jobs of the next. A Freedoom map has up to a hundred levels of one cell each, whose own
// work comes in batches too small to keep two threads busy, so all levels' jobs run together.
// `runner` builds each round's jobs (empty: this process's threads, TBB); the result does not
// depend on the runner, on thread order or on the number of processes. `used_bytes` and `progress`
// as for buildPfdLevel. `only` (ascending level indices, each < levels.size()) builds just those
// levels; empty: all.
std::vector<PfdLevel> buildPfdLevels(const BspTree& bsp, std::span<const FloorLevel> levels, double eye_height,
                                     const PfdLevelOptions& options, uint64_t& used_bytes,
                                     const std::function<void(const std::string&)>& progress = {},
                                     std::span<const uint32_t> only = {}, const PfdCellRunner& runner = {});

// A tree as bytes (the tree file's layout of one tree) and back: for journals and messages between
// processes. pfdTreeFromBytes checks what loadTreeFile checks (Error with `context`); `fragments`
// is the BSP's fragment count.
std::vector<uint8_t> pfdTreeBytes(const PfdTree& tree);
PfdTree pfdTreeFromBytes(std::span<const uint8_t> bytes, size_t fragments, const std::string& context);
// A job and an outcome as bytes and back (ByteReader's Error with `context` on bad bytes).
std::vector<uint8_t> pfdCellJobBytes(const PfdCellJob& job);
PfdCellJob pfdCellJobFromBytes(std::span<const uint8_t> bytes, const std::string& context);
std::vector<uint8_t> pfdCellOutcomeBytes(const PfdCellOutcome& outcome);
PfdCellOutcome pfdCellOutcomeFromBytes(std::span<const uint8_t> bytes, size_t fragments, const std::string& context);

// The tree of the level's cell that holds (eye.x, eye.z), or null when none does (cells are
// half-open boxes [lo, hi)).
const PfdTree* findPfdCell(const PfdLevel& level, const glm::dvec3& eye);

// The level's region area: the sum over its cells (negative areas, never made, count as 0).
double pfdLevelArea(const PfdLevel& level);

// A uniformly random eye of the level (a cell by region area, then a point of its region) at the
// level's height, or nullopt when the level has no region area.
std::optional<glm::dvec3> samplePfdLevel(const PfdLevel& level, uint64_t& rng_state);

// True when (eye.x, eye.z) lies strictly inside one of the tree's convex region pieces (either
// winding), judged in doubles: for tests and benchmarks that step an eye and must stay where the
// tree's order is defined (a step across a non-convex walkable region may enter a wall).
bool strictlyInsidePfdRegion(const PfdTree& tree, const glm::dvec3& eye);

struct TreeFile {
  TreeKind kind = TreeKind::kPfd;
  VisibilityOptions visibility;  // kHfd: the sampling the trees were built with
  BspTree bsp;
  std::vector<PfdLevel> levels;
  double eye_height = 0.0;
};

// One file with the BSP and every tree: magic, version, FNV-1a 64 checksum over the payload;
// written to a temporary file next to `path` and renamed. Error naming the path on failure.
void saveTreeFile(const TreeFile& file, const std::string& path);
// Error naming the path for a missing file, wrong magic or version, checksum mismatch,
// truncation or any index out of range; never allocates more than the file's size implies.
TreeFile loadTreeFile(const std::string& path);
// True when the file at `path` starts with the tree file's magic (false when it cannot be read):
// how commands tell a tree file from a scene argument.
bool isTreeFile(const std::string& path);
TreeFile loadTreeFileFromMemory(std::span<const uint8_t> bytes, const std::string& context);

}  // namespace walkvis
