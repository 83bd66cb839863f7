// One level's PFD trees and its view cells: a level whose tree would exceed the per-cell budget is
// cut into four boxes, recursively, each with its own tree (DESIGN.md, "Height plane": "a large
// level is divided into view cells rather than given one giant tree"; the sizes that make this
// necessary are in "What is already known").
#include <cmath>
#include <limits>

#include <glm/common.hpp>

#include "pfd_hfd/pfd.h"

namespace walkvis {

PfdLevel buildPfdLevel(const BspTree& bsp, const FloorLevel& level, uint32_t level_index, double eye_height,
                       const PfdLevelOptions& options, uint64_t& used_bytes,
                       const std::function<void(const std::string&)>& progress) {
  PfdLevel out;
  out.level = level_index;
  out.floor_y = level.floor_y;
  out.height = level.floor_y + eye_height;
  const std::string where = "level " + std::to_string(level_index) + " (floor y=" + std::to_string(level.floor_y) + ")";

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

  auto buildCell = [&](auto& self, const std::optional<PfdBox>& box, uint32_t depth) -> void {
    const uint64_t remaining = options.max_memory == 0 ? 0
                               : used_bytes >= options.max_memory ? 1
                                                                  : options.max_memory - used_bytes;
    PfdOptions o = options.tree;
    o.max_memory = options.cell_memory;
    bool total_limits = false;
    if (remaining != 0 && (o.max_memory == 0 || remaining < o.max_memory)) {
      o.max_memory = remaining;
      total_limits = true;
    }
    PfdTree tree;
    try {
      tree = buildPfd(bsp, level.walkable, out.height, box, o);
    } catch (const PfdBudgetError& e) {
      if (total_limits)
        throw PfdBudgetError("pfd: " + where + ": the trees exceed the memory budget of " +
                             std::to_string(options.max_memory) + " bytes; raise --max-memory");
      const PfdBox b = box ? *box : bounds;
      const double mx = b.lo.x + 0.5 * (b.hi.x - b.lo.x), mz = b.lo.y + 0.5 * (b.hi.y - b.lo.y);
      if (depth >= options.max_cell_depth || !(mx > b.lo.x && mx < b.hi.x && mz > b.lo.y && mz < b.hi.y))
        throw PfdBudgetError("pfd: " + where + ": a view cell of " + std::to_string(b.hi.x - b.lo.x) + " x " +
                             std::to_string(b.hi.y - b.lo.y) + " still needs more than " +
                             std::to_string(options.cell_memory) + " bytes after " + std::to_string(depth) +
                             " subdivisions; raise --max-memory");
      if (progress) progress(where + ": cell over " + std::to_string(options.cell_memory) + " bytes, cut into 4");
      self(self, PfdBox{{b.lo.x, b.lo.y}, {mx, mz}}, depth + 1);
      self(self, PfdBox{{mx, b.lo.y}, {b.hi.x, mz}}, depth + 1);
      self(self, PfdBox{{b.lo.x, mz}, {mx, b.hi.y}}, depth + 1);
      self(self, PfdBox{{mx, mz}, {b.hi.x, b.hi.y}}, depth + 1);
      return;
    }
    if (tree.region.empty()) return;  // no walkable area in this cell
    used_bytes += tree.stats.bytes;
    if (options.max_memory != 0 && used_bytes > options.max_memory)
      throw PfdBudgetError("pfd: " + where + ": the trees exceed the memory budget of " +
                           std::to_string(options.max_memory) + " bytes; raise --max-memory");
    if (progress)
      progress(where + ": cell " + std::to_string(out.cells.size()) + ": " + std::to_string(tree.stats.nodes) +
               " nodes, " + std::to_string(tree.stats.bytes) + " bytes, " +
               std::to_string(tree.stats.build_seconds) + " s");
    out.cells.push_back(std::move(tree));
  };
  buildCell(buildCell, std::nullopt, 0);
  return out;
}

}  // namespace walkvis
