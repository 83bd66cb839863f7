// One level's PFD trees and its view cells (docs/DESIGN.md, "Height plane": a large level is cut
// into view cells with a tree each; the sizes that make this necessary are in "Sizes and
// errors"). A PFD level's cells are chosen before anything is built: a PFD tree's size grows with
// the square of the test-lines that cross its region (nodes ≈ 0.25–0.34·L²), so a cell is cut in
// four while that estimate exceeds the per-cell budget. An HFD tree does not grow that way (a
// hidden subtree gets no test-line, so its size follows what the region sees; the estimate is off
// by orders of magnitude on large levels, docs/hfd/README.md, "View cells"), while every cell
// tests every fragment of the level at its root again: an HFD level starts as one cell. Either
// way, a cell whose build passes the budget is abandoned at once (the builder checks after every
// node) and cut again. The cells of a level (and, through buildPfdLevels, the levels) are built in
// parallel (TBB); the result does not depend on thread order.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>

#include <glm/common.hpp>
#include <tbb/parallel_for.h>

#include "pfd_hfd/pfd.h"

namespace walkvis {
namespace {

// Bytes per crossing line squared: about 0.3·L² nodes of about 200 bytes each (node, list
// references, pooled runs and the build's memo), measured on gen:office and freedoom2 maps.
constexpr double kBytesPerLineSquared = 60.0;
// Progress lines of a cell's build come at most this often.
constexpr double kProgressSeconds = 10.0;

struct PlannedCell {
  std::optional<PfdBox> box;  // none: the whole level
  uint32_t depth = 0;
};

}  // namespace

namespace {

// buildPfdLevel with the budget shared by levels built at once.
PfdLevel buildLevel(const BspTree& bsp, const FloorLevel& level, uint32_t level_index, double eye_height,
                    const PfdLevelOptions& options, std::atomic<uint64_t>& used,
                    const std::function<void(const std::string&)>& progress) {
  PfdLevel out;
  out.level = level_index;
  out.floor_y = level.floor_y;
  out.height = level.floor_y + eye_height;
  const std::string where = "level " + std::to_string(level_index) + " (floor y=" + std::to_string(level.floor_y) + ")";
  std::mutex progress_mutex;
  auto say = [&](const std::string& line) {
    if (!progress) return;
    std::lock_guard<std::mutex> lock(progress_mutex);
    progress(line);
  };

  // The cell boxes are half-open [lo, hi): hi lies just above every walkable corner.
  PfdBox bounds{{HUGE_VAL, HUGE_VAL}, {-HUGE_VAL, -HUGE_VAL}};
  for (const auto& ring : level.walkable)
    for (const glm::dvec2& p : ring) {
      bounds.lo = glm::min(bounds.lo, p);
      bounds.hi = glm::max(bounds.hi, p);
    }
  if (!(bounds.lo.x <= bounds.hi.x)) return out;  // nothing walkable
  bounds.hi.x = std::nextafter(bounds.hi.x, HUGE_VAL);
  bounds.hi.y = std::nextafter(bounds.hi.y, HUGE_VAL);

  // The four quarters of a cell, or nothing when it cannot be cut (depth or floating point).
  auto quarters = [&](const PlannedCell& c, std::vector<PlannedCell>& q) {
    q.clear();
    const PfdBox b = c.box ? *c.box : bounds;
    const double mx = b.lo.x + 0.5 * (b.hi.x - b.lo.x), mz = b.lo.y + 0.5 * (b.hi.y - b.lo.y);
    if (c.depth >= options.max_cell_depth || !(mx > b.lo.x && mx < b.hi.x && mz > b.lo.y && mz < b.hi.y)) return;
    q.push_back({PfdBox{{b.lo.x, b.lo.y}, {mx, mz}}, c.depth + 1});
    q.push_back({PfdBox{{mx, b.lo.y}, {b.hi.x, mz}}, c.depth + 1});
    q.push_back({PfdBox{{b.lo.x, mz}, {mx, b.hi.y}}, c.depth + 1});
    q.push_back({PfdBox{{mx, mz}, {b.hi.x, b.hi.y}}, c.depth + 1});
  };
  const bool plan_by_lines = options.tree.visibility == nullptr && options.cell_memory != 0;  // PFD only
  PfdOptions tree_options = options.tree;
  if (options.object_extent > 0.0) tree_options.object_extent = options.object_extent * eye_height;
  if (!tree_options.drop_back_faces) tree_options.object_extent = 0.0;
  // Once per level: every planned cell counts its lines without the objects'.
  const std::vector<uint8_t> objects = pfdObjectNodes(bsp, tree_options.object_extent);

  // Plan: depth first, so that the cells keep a fixed quadrant order.
  std::vector<PlannedCell> planned;
  {
    std::vector<PlannedCell> stack{{std::nullopt, 0}}, q;
    while (!stack.empty()) {
      const PlannedCell c = stack.back();
      stack.pop_back();
      const PfdLineCount count = countPfdLines(bsp, level.walkable, out.height, c.box, objects);
      if (!(count.area > 0.0)) continue;  // nothing walkable in this cell
      const double estimate = kBytesPerLineSquared * static_cast<double>(count.crossing) * static_cast<double>(count.crossing);
      if (plan_by_lines && estimate > static_cast<double>(options.cell_memory)) quarters(c, q);
      else q.clear();
      if (q.empty()) {
        planned.push_back(c);
      } else {
        for (size_t k = q.size(); k-- > 0;) stack.push_back(q[k]);
      }
    }
  }
  if (planned.size() > 1) say(where + ": " + std::to_string(planned.size()) + " view cells planned");

  // Build, in rounds: a cell over its budget is replaced by its quarters and built again.
  // By how much: `need` bytes are a lower bound of what the trees need (those built and, when a
  // tree stopped, its bytes then); with the share of that tree's area done, an estimate of the
  // finished trees and that one at the rate it was filling (its bytes grow with the area built,
  // not exactly). Cells not yet begun are not in either figure.
  auto totalError = [&](uint64_t need, uint64_t stopped_bytes, double stopped_fraction) {
    const auto gib = [](double b) {  // in the largest binary unit under the value
      char t[32];
      if (b >= 0x1p30) std::snprintf(t, sizeof t, "%.2f GiB", b / 0x1p30);
      else if (b >= 0x1p20) std::snprintf(t, sizeof t, "%.1f MiB", b / 0x1p20);
      else std::snprintf(t, sizeof t, "%.0f KiB", b / 0x1p10);
      return std::string(t);
    };
    std::string msg = "pfd: " + where + ": the trees exceed the memory budget of " + std::to_string(options.max_memory) +
                      " bytes (" + gib(static_cast<double>(options.max_memory)) + "): they need at least " +
                      std::to_string(need) + " bytes (" + gib(static_cast<double>(need)) + ")";
    if (stopped_fraction > 0.0 && stopped_fraction < 1.0) {
      const double estimate = static_cast<double>(need - stopped_bytes) + stopped_bytes / stopped_fraction;
      char t[96];
      std::snprintf(t, sizeof t, "; the finished trees and the stopped one (%.1f%% of its area built) about %s",
                    100.0 * stopped_fraction, gib(estimate).c_str());
      msg += t;
    }
    return PfdBudgetError(msg + ", with cells not yet begun on top; raise --max-memory", need, 0.0);
  };
  std::vector<std::optional<PfdTree>> built;
  while (!planned.empty()) {
    built.assign(planned.size(), std::nullopt);
    std::vector<uint8_t> over(planned.size(), 0);
    std::vector<uint8_t> total_limited(planned.size(), 0);
    tbb::parallel_for(size_t{0}, planned.size(), [&](size_t i) {
      const uint64_t now = used.load();
      const uint64_t remaining = options.max_memory == 0 ? 0
                                 : now >= options.max_memory ? 1
                                                             : options.max_memory - now;
      PfdOptions o = tree_options;
      o.max_memory = options.cell_memory;
      if (remaining != 0 && (o.max_memory == 0 || remaining < o.max_memory)) {
        o.max_memory = remaining;
        total_limited[i] = 1;
      }
      const std::string cell_name = where + ": cell " + std::to_string(i) + "/" + std::to_string(planned.size());
      const auto start = std::chrono::steady_clock::now();
      double last_report = 0.0;
      o.progress = [&](double done) {
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (elapsed - last_report < kProgressSeconds || !(done > 0.0) || done >= 1.0) return;
        last_report = elapsed;
        char line[160];
        std::snprintf(line, sizeof line, ": %.1f%% of its area after %.0f s, about %.0f s to go (ETA by area)",
                      100.0 * done, elapsed, elapsed * (1.0 - done) / done);
        say(cell_name + line);
      };
      try {
        PfdTree tree = buildPfd(bsp, level.walkable, out.height, planned[i].box, o);
        const uint64_t after = used.fetch_add(tree.stats.bytes) + tree.stats.bytes;
        if (options.max_memory != 0 && after > options.max_memory) throw totalError(after, 0, 0.0);
        say(cell_name + ": " +
            std::to_string(tree.stats.nodes) + " nodes, " + std::to_string(tree.stats.list_entries) + " list entries, " +
            std::to_string(tree.stats.pool_entries) + " pooled ids, " + std::to_string(tree.stats.bytes) + " bytes, " +
            std::to_string(tree.stats.build_seconds) + " s");
        built[i] = std::move(tree);
      } catch (const PfdBudgetError& e) {
        if (total_limited[i] && options.max_memory != 0)
          throw totalError(used.load() + e.bytes, e.bytes, e.area_fraction);
        over[i] = 1;
      }
    });
    std::vector<PlannedCell> again, q;
    for (size_t i = 0; i < planned.size(); ++i) {
      if (built[i]) {
        if (!built[i]->region.empty()) out.cells.push_back(std::move(*built[i]));
        continue;
      }
      if (!over[i]) continue;
      quarters(planned[i], q);
      const PfdBox b = planned[i].box ? *planned[i].box : bounds;
      if (q.empty())
        throw PfdBudgetError("pfd: " + where + ": a view cell of " + std::to_string(b.hi.x - b.lo.x) + " x " +
                             std::to_string(b.hi.y - b.lo.y) + " still needs more than " +
                             std::to_string(options.cell_memory) + " bytes after " +
                             std::to_string(planned[i].depth) + " subdivisions; raise --cell-memory or --max-memory");
      say(where + ": a cell went over " + std::to_string(options.cell_memory) + " bytes, cut into 4");
      for (const PlannedCell& c : q)
        if (countPfdLines(bsp, level.walkable, out.height, c.box, objects).area > 0.0) again.push_back(c);
    }
    planned = std::move(again);
  }
  return out;
}

}  // namespace

PfdLevel buildPfdLevel(const BspTree& bsp, const FloorLevel& level, uint32_t level_index, double eye_height,
                       const PfdLevelOptions& options, uint64_t& used_bytes,
                       const std::function<void(const std::string&)>& progress) {
  std::atomic<uint64_t> used{used_bytes};
  PfdLevel out = buildLevel(bsp, level, level_index, eye_height, options, used, progress);
  used_bytes = used.load();
  return out;
}

std::vector<PfdLevel> buildPfdLevels(const BspTree& bsp, std::span<const FloorLevel> levels, double eye_height,
                                     const PfdLevelOptions& options, uint64_t& used_bytes,
                                     const std::function<void(const std::string&)>& progress,
                                     std::span<const uint32_t> only) {
  std::atomic<uint64_t> used{used_bytes};
  std::mutex progress_mutex;
  const std::function<void(const std::string&)> say = [&](const std::string& line) {
    if (!progress) return;
    std::lock_guard<std::mutex> lock(progress_mutex);
    progress(line);
  };
  std::vector<uint32_t> chosen(only.begin(), only.end());
  if (only.empty()) {
    chosen.resize(levels.size());
    for (size_t l = 0; l < levels.size(); ++l) chosen[l] = static_cast<uint32_t>(l);
  }
  std::vector<PfdLevel> out(chosen.size());
  tbb::parallel_for(size_t{0}, chosen.size(), [&](size_t i) {
    const uint32_t l = chosen[i];
    out[i] = buildLevel(bsp, levels[l], l, eye_height, options, used, say);
  });
  used_bytes = used.load();
  return out;
}

}  // namespace walkvis
