// One level's PFD trees and its view cells (docs/DESIGN.md, "Height plane": a large level is cut
// into view cells with a tree each; the sizes that make this necessary are in "Sizes and
// errors"). A PFD level's cells are chosen before anything is built: a PFD tree's size grows with
// the square of the test-lines that cross its region (nodes ≈ 0.25–0.34·L²), so a cell is cut in
// four while that estimate exceeds the per-cell budget. An HFD tree does not grow that way (a
// hidden subtree gets no test-line, so its size follows what the region sees; the estimate is off
// by orders of magnitude on large levels, docs/hfd/README.md, "View cells"), while every cell
// tests every fragment of the level at its root again: an HFD level starts as one cell. Either
// way, a cell whose build passes the budget is abandoned at once (the builder checks after every
// node) and cut again. All levels' cells are jobs (PfdCellJob) built in rounds by a runner: this
// process's threads (TBB) or, under MPI, every rank's (tools/walkvis/build_runner.cpp). A job's tree
// is a function of the job alone, and the rounds place each outcome by its job's index, so the
// result depends neither on thread order nor on where a job ran.
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include "core/check.h"
#include "pfd_hfd/pfd.h"

namespace walkvis {
namespace {

// Bytes per crossing line squared: about 0.3·L² nodes of about 200 bytes each (node, list
// references, pooled runs and the build's memo), measured on gen:office and freedoom2 maps.
constexpr double kBytesPerLineSquared = 60.0;
// Progress lines of a cell's build come at most this often.
constexpr double kProgressSeconds = 10.0;

PfdOptions treeOptions(const PfdCellContext& context) {
  PfdOptions o = context.options.tree;
  if (context.options.object_extent > 0.0) o.object_extent = context.options.object_extent * context.eye_height;
  if (!o.drop_back_faces) o.object_extent = 0.0;
  return o;
}

// "level L (floor y=Y)", as progress and errors name a level.
std::string levelName(uint32_t level, const FloorLevel& floor) {
  return "level " + std::to_string(level) + " (floor y=" + std::to_string(floor.floor_y) + ")";
}

std::string cellName(const PfdCellContext& context, const PfdCellJob& job) {
  std::string name = levelName(job.level, context.levels[job.level]);
  if (job.box) {
    char t[128];
    std::snprintf(t, sizeof t, ": cell [%.6g, %.6g) x [%.6g, %.6g)", job.box->lo.x, job.box->hi.x, job.box->lo.y,
                  job.box->hi.y);
    name += t;
  }
  return name;
}

// The default runner: this process's threads, the costliest jobs first, one job per task.
void runLocally(const PfdCellContext& context, std::span<const PfdCellJob> jobs, std::span<PfdCellOutcome> outcomes,
                const std::function<void(const std::string&)>& say) {
  std::vector<size_t> order(jobs.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return jobs[a].cost > jobs[b].cost; });
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, order.size(), 1),
      [&](const tbb::blocked_range<size_t>& range) {
        for (size_t k = range.begin(); k != range.end(); ++k) {
          const size_t i = order[k];
          const std::string name = cellName(context, jobs[i]);
          const auto start = std::chrono::steady_clock::now();
          double last_report = 0.0;
          auto progress = [&](double done) {
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (elapsed - last_report < kProgressSeconds || !(done > 0.0) || done >= 1.0) return;
            last_report = elapsed;
            char line[160];
            std::snprintf(line, sizeof line, ": %.1f%% of its area after %.0f s, about %.0f s to go (ETA by area)",
                          100.0 * done, elapsed, elapsed * (1.0 - done) / done);
            say(name + line);
          };
          outcomes[i] = buildPfdCell(context, jobs[i], progress);
          if (const auto& t = outcomes[i].tree)
            say(name + ": " + std::to_string(t->stats.nodes) + " nodes, " + std::to_string(t->stats.list_entries) +
                " list entries, " + std::to_string(t->stats.pool_entries) + " pooled ids, " +
                std::to_string(t->stats.bytes) + " bytes, " + std::to_string(t->stats.build_seconds) + " s");
        }
      },
      tbb::simple_partitioner());
}

// One level's state between rounds.
struct LevelBuild {
  PfdBox bounds;                  // half-open [lo, hi): hi lies just above every walkable corner
  std::vector<PfdCellJob> cells;  // this round's
};

// Plans a level's view cells and makes their jobs.
class CellPlanner {
 public:
  CellPlanner(const BspTree& bsp, std::span<const FloorLevel> levels, double eye_height, const PfdLevelOptions& options)
      : bsp_(bsp), levels_(levels), eye_height_(eye_height), options_(options),
        // Once: every planned cell counts its lines without the objects'.
        objects_(pfdObjectNodes(bsp, treeOptions(PfdCellContext{&bsp, levels, eye_height, options}).object_extent)) {}

  // A cell's job; `count` gets its lines (area 0: nothing of the level is walkable in it), tried
  // among `candidates` (null: all) and listed in `crossing` when given (countPfdLines).
  PfdCellJob job(uint32_t l, std::optional<PfdBox> box, uint32_t depth, PfdLineCount& count,
                 const std::vector<uint32_t>* candidates = nullptr, std::vector<uint32_t>* crossing = nullptr) const {
    count = countPfdLines(bsp_, levels_[l].walkable, levels_[l].floor_y + eye_height_, box, objects_, candidates, crossing);
    PfdCellJob job;
    job.level = l;
    job.box = box;
    job.depth = depth;
    // A PFD tree's size and time grow with the square of its crossing lines; an HFD tree's time
    // less steeply (its hidden subtrees get no lines): on freedoom2 MAP01 (49 one-cell levels, one
    // thread) the ETA by lines² said 1 s with 10 s to go; by lines it was within a third of the
    // time left from 4 s on.
    const double lines = static_cast<double>(count.crossing);
    job.cost = options_.tree.visibility ? lines : lines * lines;
    return job;
  }

  // The four quarters of a cell, or nothing when it cannot be cut (depth or floating point).
  void quarters(const LevelBuild& b, const PfdCellJob& c, std::vector<PfdBox>& q) const {
    q.clear();
    const PfdBox x = c.box ? *c.box : b.bounds;
    const double mx = x.lo.x + 0.5 * (x.hi.x - x.lo.x), mz = x.lo.y + 0.5 * (x.hi.y - x.lo.y);
    if (c.depth >= options_.max_cell_depth || !(mx > x.lo.x && mx < x.hi.x && mz > x.lo.y && mz < x.hi.y)) return;
    q.push_back(PfdBox{{x.lo.x, x.lo.y}, {mx, mz}});
    q.push_back(PfdBox{{mx, x.lo.y}, {x.hi.x, mz}});
    q.push_back(PfdBox{{x.lo.x, mz}, {mx, x.hi.y}});
    q.push_back(PfdBox{{mx, mz}, {x.hi.x, x.hi.y}});
  }

  // Level l's bounds and first cells: the whole level, or with `by_lines` cut in four while the
  // estimate of a cell's tree passes cell_memory. Depth first, so that the cells keep a fixed
  // quadrant order.
  LevelBuild plan(uint32_t l, bool by_lines) const {
    LevelBuild b;
    b.bounds = PfdBox{{HUGE_VAL, HUGE_VAL}, {-HUGE_VAL, -HUGE_VAL}};
    for (const auto& ring : levels_[l].walkable)
      for (const glm::dvec2& p : ring) {
        b.bounds.lo = glm::min(b.bounds.lo, p);
        b.bounds.hi = glm::max(b.bounds.hi, p);
      }
    if (!(b.bounds.lo.x <= b.bounds.hi.x)) return b;  // nothing walkable
    b.bounds.hi.x = std::nextafter(b.bounds.hi.x, HUGE_VAL);
    b.bounds.hi.y = std::nextafter(b.bounds.hi.y, HUGE_VAL);
    // Each pending cell carries its parent's crossing lines, the only ones that can cross it:
    // a cell is counted against its parent's lines, not the whole BSP.
    using Lines = std::shared_ptr<const std::vector<uint32_t>>;
    std::vector<std::pair<PfdCellJob, Lines>> stack{{PfdCellJob{l, std::nullopt, 0, 0, false, 0.0}, nullptr}};
    std::vector<PfdBox> q;
    PfdLineCount count;
    std::vector<uint32_t> crossing;
    while (!stack.empty()) {
      const auto [c, candidates] = stack.back();
      stack.pop_back();
      crossing.clear();
      PfdCellJob next = job(l, c.box, c.depth, count, candidates.get(), by_lines ? &crossing : nullptr);
      if (!(count.area > 0.0)) continue;
      const double estimate = kBytesPerLineSquared * static_cast<double>(count.crossing) * static_cast<double>(count.crossing);
      if (by_lines && estimate > static_cast<double>(options_.cell_memory)) quarters(b, next, q);
      else q.clear();
      if (q.empty()) {
        b.cells.push_back(next);
      } else {
        const Lines lines = std::make_shared<const std::vector<uint32_t>>(crossing);
        for (size_t k = q.size(); k-- > 0;) stack.emplace_back(PfdCellJob{l, q[k], c.depth + 1, 0, false, 0.0}, lines);
      }
    }
    return b;
  }

 private:
  const BspTree& bsp_;
  std::span<const FloorLevel> levels_;
  double eye_height_;
  const PfdLevelOptions& options_;
  std::vector<uint8_t> objects_;
};

}  // namespace

PfdCellOutcome buildPfdCell(const PfdCellContext& context, const PfdCellJob& job,
                            const std::function<void(double)>& progress) {
  WALKVIS_DCHECK(job.level < context.levels.size());
  const FloorLevel& level = context.levels[job.level];
  PfdOptions o = treeOptions(context);
  o.max_memory = job.budget;
  o.progress = progress;
  PfdCellOutcome out;
  try {
    out.tree = buildPfd(*context.bsp, level.walkable, level.floor_y + context.eye_height, job.box, o);
  } catch (const PfdBudgetError& e) {
    out.stopped_bytes = e.bytes;
    out.stopped_fraction = e.area_fraction;
  }
  return out;
}

std::vector<PfdCellJob> planPfdCells(const BspTree& bsp, std::span<const FloorLevel> levels, double eye_height,
                                     const PfdLevelOptions& options, std::span<const uint32_t> only, bool by_lines,
                                     const std::function<void(size_t, size_t, size_t)>& progress) {
  const CellPlanner planner(bsp, levels, eye_height, options);
  const size_t count = only.empty() ? levels.size() : only.size();
  // Levels in parallel (a level's cells are planned one after another: each cut depends on the
  // last count), concatenated in level order so that the jobs do not depend on the threads.
  std::vector<LevelBuild> planned(count);
  std::mutex progress_mutex;
  size_t levels_done = 0, cells_done = 0;
  tbb::parallel_for(size_t{0}, count, [&](size_t i) {
    planned[i] = planner.plan(only.empty() ? static_cast<uint32_t>(i) : only[i], by_lines && options.cell_memory != 0);
    if (!progress) return;
    std::lock_guard<std::mutex> lock(progress_mutex);
    cells_done += planned[i].cells.size();
    progress(++levels_done, count, cells_done);
  });
  std::vector<PfdCellJob> jobs;
  for (const LevelBuild& b : planned) jobs.insert(jobs.end(), b.cells.begin(), b.cells.end());
  for (PfdCellJob& job : jobs) job.budget = options.cell_memory;
  return jobs;
}

PfdLevel buildPfdLevel(const BspTree& bsp, const FloorLevel& level, uint32_t level_index, double eye_height,
                       const PfdLevelOptions& options, uint64_t& used_bytes,
                       const std::function<void(const std::string&)>& progress) {
  std::vector<PfdLevel> out = buildPfdLevels(bsp, std::span<const FloorLevel>(&level, 1), eye_height, options,
                                             used_bytes, progress);
  out[0].level = level_index;
  return std::move(out[0]);
}

std::vector<PfdLevel> buildPfdLevels(const BspTree& bsp, std::span<const FloorLevel> levels, double eye_height,
                                     const PfdLevelOptions& options, uint64_t& used_bytes,
                                     const std::function<void(const std::string&)>& progress,
                                     std::span<const uint32_t> only, const PfdCellRunner& runner) {
  std::mutex progress_mutex;
  const std::function<void(const std::string&)> say = [&](const std::string& line) {
    if (!progress) return;
    std::lock_guard<std::mutex> lock(progress_mutex);
    progress(line);
  };
  PfdCellContext context{&bsp, levels, eye_height, options};
  std::vector<uint32_t> chosen(only.begin(), only.end());
  if (only.empty()) {
    chosen.resize(levels.size());
    std::iota(chosen.begin(), chosen.end(), uint32_t{0});
  }
  // PFD levels are planned by their lines; HFD levels start whole (the file's head comment).
  const CellPlanner planner(bsp, levels, eye_height, options);
  std::vector<PfdLevel> out(chosen.size());
  std::vector<LevelBuild> builds(chosen.size());
  for (size_t i = 0; i < chosen.size(); ++i) {
    const uint32_t l = chosen[i];
    out[i].level = l;
    out[i].floor_y = levels[l].floor_y;
    out[i].height = levels[l].floor_y + eye_height;
    builds[i] = planner.plan(l, options.tree.visibility == nullptr && options.cell_memory != 0);
    if (builds[i].cells.size() > 1)
      say(levelName(l, levels[l]) + ": " + std::to_string(builds[i].cells.size()) + " view cells planned");
  }

  // Over the budget: `need` bytes are a lower bound of what the trees need (those built and, when a
  // tree stopped, its bytes then); with the share of that tree's area done, an estimate of the
  // finished trees and that one at the rate it was filling (its bytes grow with the area built,
  // not exactly). Cells not yet begun are not in either figure.
  auto totalError = [&](const std::string& where, uint64_t need, uint64_t stopped_bytes, double stopped_fraction) {
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

  // Rounds. Every job of a round gets the budget left when the round starts: a build that fits
  // the total fits it whichever jobs finish first, so the trees do not depend on the order.
  uint64_t used = used_bytes;
  std::vector<PfdCellJob> jobs;
  std::vector<PfdCellOutcome> outcomes;
  while (true) {
    jobs.clear();
    const uint64_t remaining = options.max_memory == 0 ? 0 : used >= options.max_memory ? 1 : options.max_memory - used;
    for (const LevelBuild& b : builds)
      for (PfdCellJob job : b.cells) {
        job.budget = options.cell_memory;
        job.total_limited = false;
        if (remaining != 0 && (job.budget == 0 || remaining < job.budget)) {
          job.budget = remaining;
          job.total_limited = true;
        }
        jobs.push_back(job);
      }
    if (jobs.empty()) break;
    outcomes.assign(jobs.size(), PfdCellOutcome{});
    if (runner) runner(jobs, outcomes);
    else runLocally(context, jobs, outcomes, say);

    size_t k = 0;
    std::vector<PfdBox> q;
    PfdLineCount count;
    for (size_t i = 0; i < builds.size(); ++i) {
      LevelBuild& b = builds[i];
      const FloorLevel& floor = levels[chosen[i]];
      const std::string where = levelName(chosen[i], floor);
      std::vector<PfdCellJob> again;
      for (const PfdCellJob& job : b.cells) {
        PfdCellOutcome& r = outcomes[k];
        WALKVIS_DCHECK(jobs[k].level == job.level);
        const bool total_limited = jobs[k].total_limited;
        ++k;
        if (r.tree) {
          used += r.tree->stats.bytes;
          if (options.max_memory != 0 && used > options.max_memory) throw totalError(where, used, 0, 0.0);
          if (!r.tree->region.empty()) out[i].cells.push_back(std::move(*r.tree));
          continue;
        }
        if (total_limited && options.max_memory != 0)
          throw totalError(where, used + r.stopped_bytes, r.stopped_bytes, r.stopped_fraction);
        planner.quarters(b, job, q);
        const PfdBox x = job.box ? *job.box : b.bounds;
        if (q.empty())
          throw PfdBudgetError("pfd: " + where + ": a view cell of " + std::to_string(x.hi.x - x.lo.x) + " x " +
                               std::to_string(x.hi.y - x.lo.y) + " still needs more than " +
                               std::to_string(options.cell_memory) + " bytes after " + std::to_string(job.depth) +
                               " subdivisions; raise --cell-memory or --max-memory");
        say(where + ": a cell went over " + std::to_string(options.cell_memory) + " bytes, cut into 4");
        for (const PfdBox& c : q) {
          PfdCellJob next = planner.job(job.level, c, job.depth + 1, count);
          if (count.area > 0.0) again.push_back(next);
        }
      }
      b.cells = std::move(again);
    }
  }
  used_bytes = used;
  return out;
}

}  // namespace walkvis
