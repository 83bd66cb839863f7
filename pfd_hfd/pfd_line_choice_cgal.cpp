// The test-lines of a PFD or HFD build and the choice of the line a node tests (contracts:
// pfd_line_choice_cgal.h). The greedy even split follows James & Day's construction
// [JamesDay1998]; the exhaustive search is pfd_search.h's (docs/DESIGN.md, "PFD tree";
// docs/REFERENCES.md).
#include "pfd_hfd/pfd_line_choice_cgal.h"

#include <algorithm>
#include <unordered_map>

#include "core/check.h"
#include "core/hash.h"

namespace walkvis::pfd_exact {
namespace {

// CellSearch keeps a class's sides in one LineBits.
static_assert(kPfdMaxSearchLines == kSearchMaxLines);
// A search's classes (leaves of the model; O(lines²) in one convex piece) and memo are bounded
// whatever its lines: a search given up costs the greedy choice, never the build. The memo (one per
// tree being built, freed with it) is outside PfdOptions::max_memory, which bounds what the tree
// keeps.
constexpr size_t kMaxSearchClasses = 4096;
constexpr size_t kSearchMemoBytes = size_t{64} << 20;
constexpr size_t kMaxRootCandidates = kSearchMaxLines;  // a search's most lines

// The plane with its sign chosen so that both orientations of one plane compare equal.
Plane unoriented(Plane q) {
  if (q.n.x < 0 || (q.n.x == 0 && q.n.z < 0)) {
    q.n = -q.n;
    q.d = -q.d;
  }
  return q;
}

}  // namespace

PfdLines::PfdLines(const BspTree& bsp, double height, bool fragment_lines, const Region& root,
                   std::span<const uint8_t> objects)
    : bsp_(bsp) {
  const size_t nn = bsp.nodes.size();
  WALKVIS_DCHECK(objects.size() == nn);
  lines_.reserve(nn);
  for (const BspNode& node : bsp.nodes) lines_.push_back(planeLine(node.plane, height));
  frag_line_.assign(bsp.fragments.size(), UINT32_MAX);
  for (size_t f = 0; f < bsp.fragments.size(); ++f) {
    // Only the facing of a degenerate fragment needs its own line; keeping back faces, no line.
    if (bsp.fragment_orientation[f] == 0 && fragment_lines) {
      frag_line_[f] = static_cast<uint32_t>(lines_.size());
      lines_.push_back(planeLine(bsp.fragments[f].plane, height));
    }
  }
  std::unordered_map<uint64_t, std::vector<uint32_t>> by_hash;
  for (uint32_t id = 0; id < lines_.size(); ++id) {
    const Plane q = unoriented(lines_[id].plane);
    auto& bucket = by_hash[fnv1aDoubles({q.n.x, q.n.y, q.n.z, q.d})];
    uint32_t canon = id;
    for (uint32_t other : bucket) {
      const Plane o = unoriented(lines_[other].plane);
      if (o.n == q.n && o.d == q.d) {
        canon = lines_[other].canon;
        break;
      }
    }
    if (canon == id) bucket.push_back(id);
    lines_[id].canon = canon;
  }
  side_.assign(lines_.size(), kUnknown);
  cross_stamp_.assign(lines_.size(), 0);
  varying_.assign(lines_.size(), 0);
  for (uint32_t id = 0; id < lines_.size(); ++id) {
    if (id < nn && objects[id] != 0) continue;
    const int s = classifyRegion(lines_[id], root, counters);
    if (s == kCross) {
      varying_[id] = 1;
    } else {
      side_[id] = static_cast<int8_t>(s);  // never logged, never undone
    }
  }
}

const Plane& PfdLines::plane(uint32_t id) const {
  WALKVIS_DCHECK(id < lines_.size());
  if (id < bsp_.nodes.size()) return bsp_.nodes[id].plane;
  // A fragment's line (rare: degenerate fragments only).
  const auto f = std::find(frag_line_.begin(), frag_line_.end(), id);
  return bsp_.fragments[static_cast<size_t>(f - frag_line_.begin())].plane;
}

int PfdLines::side(uint32_t id, const Region& r) {
  if (side_[id] != kUnknown) return side_[id];
  if (cross_stamp_[id] == region_stamp_) return kCross;
  const int s = classifyRegion(lines_[id], r, counters);
  if (s == kCross) {
    cross_stamp_[id] = region_stamp_;
  } else {
    side_[id] = static_cast<int8_t>(s);
    log_.push_back(id);
  }
  return s;
}

void PfdLines::decide(uint32_t id, int8_t s) {
  WALKVIS_DCHECK(s == 1 || s == -1);
  side_[id] = s;
  log_.push_back(id);
}

void PfdLines::undo(size_t mark) {
  WALKVIS_DCHECK(mark <= log_.size());
  while (log_.size() > mark) {
    side_[log_.back()] = kUnknown;
    log_.pop_back();
  }
}

PfdLineChoice::PfdLineChoice(const PfdOptions& options, PfdLines& lines, double sliver_tol)
    : options_(options), lines_(lines), sliver_tol_(sliver_tol) {}

// The search's model is in double precision: a line counts as crossing a double region where it
// leaves a vertex strictly on each side, except where one side is a sliver the build trims instead
// of testing (SearchLine::reach), so that the model costs the tree the build makes; where the two
// still differ (a touching line that rounding shows as crossing, a sliver's area) the tree's exact
// mean tests differs from the prediction and tests_optimal stays false.
SearchLine PfdLineChoice::searchLineOf(uint32_t id) const {
  const Line& l = lines_.line(id);
  return {l.a, l.b, l.c, options_.trim_slivers ? sliverReach(l, sliver_tol_) : 0.0};
}

void PfdLineChoice::leavePlan() {
  if (plan_.owner == 0) root_.plan_left = true;
  plan_.active = false;
}

std::optional<uint32_t> PfdLineChoice::plannedLine(const Region& r, std::span<const uint32_t> path_lines,
                                                   std::span<const int8_t> path_sides) {
  if (!plan_.active) return std::nullopt;
  WALKVIS_DCHECK(path_lines.size() == path_sides.size() && plan_.path_start <= path_lines.size());
  plan_path_.clear();
  for (size_t k = plan_.path_start; k < path_lines.size(); ++k) {
    uint32_t pos = 0;
    while (pos < plan_.lines.size() && lines_.canon(plan_.lines[pos]) != path_lines[k]) ++pos;
    if (pos == plan_.lines.size()) {
      leavePlan();
      return std::nullopt;
    }
    plan_path_.push_back({pos, path_sides[k]});
  }
  const std::optional<uint32_t> pos = search_.bestLine(plan_path_);
  if (pos && lines_.side(plan_.lines[*pos], r) == kCross) return plan_.lines[*pos];
  leavePlan();
  return std::nullopt;
}

// The line to test first among `cands` (all the lines still to be tested in the region) by
// exhaustive search, or UINT32_MAX when the search does not apply or its budget is spent.
uint32_t PfdLineChoice::searchLine(const std::vector<uint32_t>& cands, std::span<const std::vector<glm::dvec2>> rings,
                                   int32_t node, size_t path_length) {
  const bool root = node == 0;
  if (options_.search_lines == 0 || cands.empty() || (!root && search_work_ >= options_.search_work))
    return UINT32_MAX;
  const uint32_t max_lines =
      std::min(root ? std::max(options_.search_lines, options_.root_search_lines) : options_.search_lines,
               kSearchMaxLines);
  // One line per canonical plane: two BSP nodes on one plane are one test.
  std::vector<uint32_t> lines;
  for (uint32_t id : cands) {
    bool dup = false;
    for (uint32_t o : lines) dup |= lines_.canon(o) == lines_.canon(id);
    if (!dup) lines.push_back(id);
    if (lines.size() > max_lines) return UINT32_MAX;
  }
  DRegion dr;
  for (const auto& ring : rings) {
    dr.pts.insert(dr.pts.end(), ring.begin(), ring.end());
    dr.start.push_back(static_cast<uint32_t>(dr.pts.size()));
  }
  std::vector<SearchLine> model(lines.size());
  for (size_t i = 0; i < lines.size(); ++i) model[i] = searchLineOf(lines[i]);
  const uint64_t limit =
      root ? std::max(options_.root_search_work, options_.search_work) : options_.search_work - search_work_;
  std::optional<double> cost;
  if (search_.init(dr, model, kMaxSearchClasses)) cost = search_.solve(limit, kSearchMemoBytes);
  if (root) {
    root_.lines = static_cast<uint32_t>(lines.size());
    root_.work_done = search_.work();
  } else {
    search_work_ += search_.work();
  }
  if (!cost) {  // given up: the budget is spent, the greedy choice from here on
    if (!root && search_.work() > limit) search_work_ = options_.search_work;
    return UINT32_MAX;
  }
  const std::optional<uint32_t> first = search_.bestLine({});
  if (!first) return UINT32_MAX;
  plan_.active = true;
  plan_.owner = node;
  plan_.path_start = path_length;
  plan_.lines = std::move(lines);
  if (root) {
    root_.planned = true;
    root_.cost = *cost;
    root_.area = search_.area();
  }
  return plan_.lines[*first];
}

// Which pieces of r lie on the positive side of l, one bit each, where l cuts none of them (at
// most 64 pieces); nullopt where it cuts one.
std::optional<uint64_t> PfdLineChoice::pieceSides(const Line& l, const Region& r) {
  if (r.size() > 64) return std::nullopt;
  uint64_t bits = 0;
  for (size_t k = 0; k < r.size(); ++k) {
    bool pos = false, neg = false;
    for (const Corner& c : r[k].corners) {
      const int sg = cornerSign(l, c, lines_.counters);
      pos |= sg > 0;
      neg |= sg < 0;
    }
    if (pos && neg) return std::nullopt;
    if (pos) bits |= uint64_t{1} << k;
  }
  return bits;
}

// The traversal's walk (the builder's candidates) stops at a bound on the nodes it examines and the
// lines it keeps, which lines that only separate r's pieces fill (freedoom2 MAP27 level 23: 919
// lines cross its two pieces, 19 nodes), and kept such trees from their root search.
LineCandidates PfdLineChoice::rootCandidates(uint32_t first, const Region& r) {
  LineCandidates out;
  if (options_.visibility != nullptr || !options_.deep_candidates || options_.heuristic != PfdHeuristic::kBalanced ||
      options_.search_lines == 0)
    return out;
  std::vector<uint64_t> separations;
  // Whether `id` (a line crossing r exactly) is kept: not a plane already kept, not a separation
  // of the pieces already kept.
  auto keep = [&](uint32_t id) {
    for (uint32_t o : out.lines)
      if (lines_.canon(o) == lines_.canon(id)) return false;
    const std::optional<uint64_t> sides = pieceSides(lines_.line(id), r);
    if (sides) {
      if (std::find(separations.begin(), separations.end(), *sides) != separations.end()) return false;
      separations.push_back(*sides);
    }
    return true;
  };
  if (keep(first)) out.lines.push_back(first);
  for (uint32_t id = 0; id < lines_.size(); ++id) {
    if (!lines_.varying(id) || id == first) continue;
    if (options_.trim_slivers && sliverSide(r, lines_.line(id), sliver_tol_, true) != 0) continue;  // if it crosses
    if (lines_.side(id, r) != kCross || !keep(id)) continue;
    out.lines.push_back(id);
    if (out.lines.size() > kMaxRootCandidates) return LineCandidates{};
  }
  out.complete = true;
  return out;
}

uint32_t PfdLineChoice::choose(uint32_t first, const LineCandidates& found, const Region& r,
                               std::span<const std::vector<glm::dvec2>> rings, int32_t node, size_t path_length) {
  const std::vector<uint32_t>& cands = found.lines;
  WALKVIS_DCHECK(!cands.empty() && cands[0] == first);
  if (found.complete) {  // never under HFD: its candidates stop at the frontier
    const uint32_t searched = searchLine(cands, rings, node, path_length);
    if (searched != UINT32_MAX) return searched;
  }
  if (cands.size() == 1) return first;
  double total = 0.0;
  for (const Piece& p : r) total += pieceArea(p);
  uint32_t best = first;
  double best_score = -1.0;
  for (uint32_t id : cands) {
    const double a = positiveArea(r, lines_.line(id));
    const double score = std::min(a, total - a);
    if (score > best_score) {
      best_score = score;
      best = id;
    }
  }
  return best;
}

}  // namespace walkvis::pfd_exact
