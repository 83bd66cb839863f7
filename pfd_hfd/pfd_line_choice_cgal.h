// The test-lines of one PFD or HFD build and the choice of which one a node tests
// (pfd_build_cgal.cpp's traversal asks; docs/DESIGN.md, "PFD tree"). PfdLines keeps the exact
// side of every line for the region being built, decided once on each root-to-node path and
// undone on the way back; PfdLineChoice picks the line a node tests among those that cross its
// region exactly: by the plan of an exhaustive search (pfd_search.h) where one holds, by a new
// search where the lines still to be tested are known and few, otherwise the candidate that splits
// the region's area most evenly (PfdOptions::heuristic, candidates, search_lines). The choice may
// use doubles (it only decides WHICH line is tested); every side the tree relies on is exact.
// Internal to pfd_hfd: it includes CGAL, so only *_cgal.cpp files include it.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>

#include "bsp/bsp.h"
#include "core/check.h"
#include "pfd_hfd/pfd.h"
#include "pfd_hfd/pfd_region_cgal.h"
#include "pfd_hfd/pfd_search.h"

namespace walkvis::pfd_exact {

// The lines a build tests: line i is BSP node i's plane on the height plane; where back faces are
// dropped, each degenerate fragment (orientation 0) has a line of its own after them, for its
// facing. Lines of one plane (either orientation) share a canonical id: they are one test. A line
// that does not cross the tree's whole region has one side everywhere in it, set once for good;
// only the others ("varying") are ever classified again, so the work per node follows them.
class PfdLines {
 public:
  // `objects`: per BSP node, nonzero inside a detail object (its lines are neither tested nor
  // varying: the query orders an object). `root`: the tree's whole region.
  PfdLines(const BspTree& bsp, double height, bool fragment_lines, const Region& root, std::span<const uint8_t> objects);

  size_t size() const { return lines_.size(); }
  const Line& line(uint32_t id) const { return lines_[id]; }
  uint32_t canon(uint32_t id) const { return lines_[id].canon; }
  // The plane that cuts line `id` from the height plane.
  const Plane& plane(uint32_t id) const;
  // Fragment f's own line; UINT32_MAX unless it is degenerate and back faces are dropped.
  uint32_t fragmentLine(uint32_t f) const { return frag_line_[f]; }
  bool varying(uint32_t id) const { return varying_[id] != 0; }

  // The region the next side() calls are about changed (a new node, or its region trimmed): the
  // crossings found so far no longer hold. Stamps cached by region (regionStamp) lapse with them.
  void enterRegion() { region_stamp_ = ++region_counter_; }
  uint32_t regionStamp() const { return region_stamp_; }

  // Line id's side of r, the current region: +1 or -1 (every corner on that side or on the line),
  // 0 (a constant-zero line: a horizontal plane in the height plane) or kCross. A side found holds
  // for every region below this one until undone; a crossing, for this region only.
  int side(uint32_t id, const Region& r);
  // The side of line id found or decided on the current path (-1, 0 or +1), where it no longer
  // crosses the current region (a line of a resolved subtree).
  int decidedSide(uint32_t id) const {
    WALKVIS_DCHECK(side_[id] != kUnknown);
    return side_[id];
  }
  // Sets the side of the line a node tests, for the child on that side (+1 front, -1 back).
  void decide(uint32_t id, int8_t s);
  // Undoes every side decided or found since mark() returned `mark`.
  size_t mark() const { return log_.size(); }
  void undo(size_t mark);

  // Every exact classification of the build's regions (the builder's clips count here too).
  Counters counters;

 private:
  static constexpr int8_t kUnknown = 5;
  const BspTree& bsp_;
  std::vector<Line> lines_;
  std::vector<uint32_t> frag_line_;
  std::vector<uint8_t> varying_;
  std::vector<int8_t> side_;          // decided side for the current region (and its ancestors)
  std::vector<uint32_t> log_;         // lines decided, in order, to undo on the way back up
  std::vector<uint32_t> cross_stamp_;  // == region_stamp_: crosses the current region
  uint32_t region_stamp_ = 0, region_counter_ = 0;
};

// Lines a node could test (the first one: the crossing line that stopped the traversal).
struct LineCandidates {
  std::vector<uint32_t> lines;
  bool complete = false;  // every line still to be tested in the region is among them
};

// What the root's exhaustive search did (PfdStats::tests_search_mean, tests_optimal,
// root_search_lines, root_search_work_done).
struct RootSearch {
  bool planned = false;    // it completed, and its plan was made the root's
  bool plan_left = false;  // the exact build left the plan's double model somewhere below the root
  double cost = 0.0;       // Σ over the model's leaves of area × tests
  double area = 0.0;       // the model's area
  uint32_t lines = 0;
  uint64_t work_done = 0;
};

class PfdLineChoice {
 public:
  // `sliver_tol`: the build's sliver width (kSliverTolerance × the root region's extent).
  PfdLineChoice(const PfdOptions& options, PfdLines& lines, double sliver_tol);

  // The line the plan of an earlier search gives the current node (region r, reached by testing
  // `path_lines`, canonical ids, with `path_sides`); nullopt where no plan holds here: a line the
  // plan did not see was tested, the model has no line crossing there, or its line does not cross
  // r exactly. A plan that does not hold ends.
  std::optional<uint32_t> plannedLine(const Region& r, std::span<const uint32_t> path_lines,
                                      std::span<const int8_t> path_sides);

  // At the root of a PFD tree (kBalanced, deep candidates, searching): every line still to be
  // tested in r (varying, crossing it other than in a sliver), `first` first, one per plane and
  // one per way of separating r's pieces (a line that cuts no piece is decided with every line
  // that separates them alike). Not complete where they are more than a search takes.
  LineCandidates rootCandidates(uint32_t first, const Region& r);

  // The line node `node` tests in r (rings: r's pieces in doubles; path_length: lines tested on
  // the way to it), among `cands` (cands.lines[0] is `first`, crossing r exactly): where cands is
  // complete, by exhaustive search, which then becomes the plan of the node's subtree (at the
  // root, node 0, with its own limits: PfdOptions::root_search_lines, root_search_work);
  // otherwise, or where the search gives up, the candidate splitting r's area most evenly.
  uint32_t choose(uint32_t first, const LineCandidates& cands, const Region& r,
                  std::span<const std::vector<glm::dvec2>> rings, int32_t node, size_t path_length);

  // Node `node`'s subtree is built: a plan made at it ends.
  void leaveNode(int32_t node) {
    if (plan_.active && plan_.owner == node) plan_.active = false;
  }

  const RootSearch& rootSearch() const { return root_; }

 private:
  // A completed search knows the best test order for the whole subtree below the node it was made
  // at (its memo holds the best line of every region it reached): the nodes below follow it
  // instead of searching again, as long as the exact build stays inside its double model.
  struct Plan {
    bool active = false;
    int32_t owner = -1;           // the node it was made at
    size_t path_start = 0;        // the path's length at that node
    std::vector<uint32_t> lines;  // the search's lines, by position
  };

  SearchLine searchLineOf(uint32_t id) const;
  void leavePlan();
  uint32_t searchLine(const std::vector<uint32_t>& cands, std::span<const std::vector<glm::dvec2>> rings,
                      int32_t node, size_t path_length);
  std::optional<uint64_t> pieceSides(const Line& l, const Region& r);

  const PfdOptions& options_;
  PfdLines& lines_;
  double sliver_tol_ = 0.0;
  CellSearch search_;
  Plan plan_;
  std::vector<std::pair<uint32_t, int8_t>> plan_path_;
  uint64_t search_work_ = 0;  // CellSearch::work spent by this tree's per-node searches
  RootSearch root_;
};

}  // namespace walkvis::pfd_exact
