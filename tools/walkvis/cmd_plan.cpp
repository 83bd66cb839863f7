// walkvis plan SCENE [--ranks K] [--threads T] [--sample N] [--json] [build options]: what a build
// of SCENE would cost, from a sample of its view cells built here. The cells are planned as the
// build plans its first round (PFD: by the lines' estimate; HFD levels start whole there, so the
// plan cuts them by the same estimate, `--hfd-cells lines`, or takes them whole, `whole`, or
// takes them whole and estimates a sampled level from windows of it, `windows`, docs/DESIGN.md,
// "Builds across processes and restarts"). The sampled cells are chosen from the cells sorted by
// estimated cost, one from the middle of each of N strata of equal cost, and each is built (or
// estimated from its windows) on one thread. Every cell is then given the
// seconds and bytes per unit of estimated cost of its stratum's sample: the whole build's CPU
// seconds and tree bytes, the memory a rank needs, and the wall time on K ranks of T slots,
// scheduled as the build schedules (costliest first onto the next free slot) after the setup
// (load, BSP, visibility scene) that every rank does itself.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <optional>
#include <queue>
#include <thread>

#include <sys/resource.h>

#include <glm/common.hpp>
#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include "build_runner.h"
#include "build_setup.h"
#include "commands.h"
#include "core/rng.h"
#include "core/sample.h"
#include "pfd_hfd/pfd.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

struct PlanArgs {
  BuildArgs build;
  uint32_t ranks = 1;
  uint32_t threads = 1;  // slots per rank
  uint32_t sample = 12;
  std::string hfd_cells = "lines";
  uint32_t windows = 4;        // --hfd-cells windows: windows built per sampled level
  double window_share = 1.0 / 16.0;  // each window's side: sqrt(share x the level's walkable area)
  bool json = false;
};

double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The wall time of `seconds` (any order) on `slots` slots, the longest first onto the slot free
// first: what the build's scheduler does with jobs of these lengths.
double makespan(std::vector<double> seconds, uint64_t slots) {
  std::sort(seconds.begin(), seconds.end(), std::greater<>());
  std::priority_queue<double, std::vector<double>, std::greater<>> free_at;
  for (uint64_t k = 0; k < std::min<uint64_t>(slots, std::max<size_t>(seconds.size(), 1)); ++k) free_at.push(0.0);
  double end = 0.0;
  for (double s : seconds) {
    const double t = free_at.top() + s;
    free_at.pop();
    free_at.push(t);
    end = std::max(end, t);
  }
  return end;
}

double peakRssBytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) * 1024.0;  // Linux: KiB
}

std::string human(double bytes) {
  char t[32];
  if (bytes >= 0x1p30) std::snprintf(t, sizeof t, "%.2f GiB", bytes / 0x1p30);
  else if (bytes >= 0x1p20) std::snprintf(t, sizeof t, "%.1f MiB", bytes / 0x1p20);
  else std::snprintf(t, sizeof t, "%.0f KiB", bytes / 0x1p10);
  return t;
}

std::string hours(double seconds) {
  char t[32];
  if (seconds >= 3600) std::snprintf(t, sizeof t, "%.1f h", seconds / 3600);
  else if (seconds >= 60) std::snprintf(t, sizeof t, "%.1f min", seconds / 60);
  else std::snprintf(t, sizeof t, "%.1f s", seconds);
  return t;
}

// A uniformly random walkable point of `level` inside `box`: a point of the box kept when one of
// the walkable region's convex pieces holds it. nullopt when 1,000 tries miss.
std::optional<glm::dvec2> walkablePoint(const FloorLevel& level, const PfdBox& box, Rng& rng) {
  for (int tries = 0; tries < 1000; ++tries) {
    const glm::dvec2 p{rng.uniform(box.lo.x, box.hi.x), rng.uniform(box.lo.y, box.hi.y)};
    for (const auto& r : level.walkable)
      if (insideConvexRing(r, p)) return p;
  }
  return std::nullopt;
}

// What one job cost here on this thread: built and timed as the build's slots do
// (buildTimedPfdCell), or, past its budget, how many bytes it had when it stopped.
struct CellCost {
  double seconds = 0.0, bytes = 0.0, rays = 0.0;
  double area = 0.0;  // walkable area of its region (0 when over)
  bool over = false;  // the tree passed the job's budget
};

CellCost measureCell(const PfdCellContext& context, const PfdCellJob& job, uint32_t timing_eyes) {
  CellCost c;
  const auto t0 = std::chrono::steady_clock::now();
  const PfdCellOutcome outcome = buildTimedPfdCell(context, job, timing_eyes);
  c.seconds = secondsSince(t0);
  c.over = !outcome.tree;
  c.bytes = outcome.tree ? static_cast<double>(outcome.tree->stats.bytes) : static_cast<double>(outcome.stopped_bytes);
  c.rays = outcome.tree ? static_cast<double>(outcome.tree->stats.visibility_rays) : 0.0;
  c.area = outcome.tree ? outcome.tree->stats.region_area : 0.0;
  return c;
}

struct CellEstimate {
  CellCost cost;      // seconds, bytes and rays of the whole cell as estimated
  uint32_t windows = 0;
};

// An HFD cell's cost from windows of it, for a cell too dear to build whole as a sample. An HFD
// tree's time and bytes follow the area its leaves cover (docs/hfd/README.md: its tests are mostly
// from small regions), at a rate that varies over the level. The level is cut into kTiles x kTiles
// tiles; a tile is drawn with probability q in proportion to its walkable area times (1 + the lines
// crossing it, the planner's estimate of an HFD tree's cost), a square window of side
// sqrt(share x the level's walkable area) is built about a random walkable point of it, and its
// cost per unit of walkable area (the tree's region_area) stands for the tile's: the level is the
// fixed cost every tree pays (a window a hundredth of that side: classifying every line, the
// root's tests) plus the mean over the windows of rate x the tile's area / q (importance
// sampling, unbiased for the tiles' sum where a window's rate is its tile's). What the whole
// level's large top regions cost beyond the windows' is not counted.
CellEstimate estimateByWindows(const PfdCellContext& context, const PfdCellJob& cell, uint32_t count, double share,
                               uint32_t timing_eyes, uint64_t seed) {
  constexpr int kTiles = 4;
  const FloorLevel& level = context.levels[cell.level];
  CellEstimate e;
  const double side = std::sqrt(share * level.walkable_area);
  if (level.walkable.empty() || !(side > 0.0)) return e;
  glm::dvec2 lo = level.walkable[0][0], hi = lo;
  for (const auto& r : level.walkable)
    for (const glm::dvec2& v : r) lo = glm::min(lo, v), hi = glm::max(hi, v);
  const double height = level.floor_y + context.eye_height;
  struct Tile {
    PfdBox box;
    double area = 0.0, weight = 0.0;
  };
  std::vector<Tile> tiles;
  std::vector<double> cumulative;  // running sum of the tiles' weights, for pickByWeight
  const glm::dvec2 step = (hi - lo) / static_cast<double>(kTiles);
  for (int i = 0; i < kTiles; ++i)
    for (int k = 0; k < kTiles; ++k) {
      Tile t;
      t.box.lo = lo + step * glm::dvec2(i, k);
      t.box.hi = lo + step * glm::dvec2(i + 1, k + 1);
      const PfdLineCount c = countPfdLines(*context.bsp, level.walkable, height, t.box);
      t.area = c.area;
      t.weight = c.area * (1.0 + static_cast<double>(c.crossing));
      if (!(t.weight > 0.0)) continue;
      cumulative.push_back((cumulative.empty() ? 0.0 : cumulative.back()) + t.weight);
      tiles.push_back(t);
    }
  if (tiles.empty()) return e;
  const double total_weight = cumulative.back();
  Rng rng{mixHash(seed, cell.level)};
  auto window = [&](const glm::dvec2& c, double half) {
    PfdCellJob job = cell;
    job.box = PfdBox{c - glm::dvec2(half), c + glm::dvec2(half)};
    const CellCost w = measureCell(context, job, timing_eyes);
    e.cost.over |= w.over;
    return w;
  };
  std::optional<double> fixed_seconds;
  double sum_s = 0.0, sum_b = 0.0, sum_r = 0.0;
  for (uint32_t k = 0; k < count; ++k) {
    const Tile* tile = &tiles[pickByWeight(cumulative, rng.state)];
    const std::optional<glm::dvec2> c = walkablePoint(level, tile->box, rng);
    if (!c) continue;
    if (!fixed_seconds) fixed_seconds = window(*c, 0.005 * side).seconds;
    const CellCost w = window(*c, 0.5 * side);
    if (!(w.area > 0.0)) continue;
    const double scale = tile->area * total_weight / tile->weight / w.area;  // tile's area / q, per unit of window area
    sum_s += std::max(0.0, w.seconds - *fixed_seconds) * scale;
    sum_b += w.bytes * scale;
    sum_r += w.rays * scale;
    ++e.windows;
  }
  if (e.windows == 0) return e;
  e.cost.seconds = *fixed_seconds + sum_s / e.windows;
  e.cost.bytes = sum_b / e.windows;
  e.cost.rays = sum_r / e.windows;
  return e;
}

int runPlan(const PlanArgs& args) {
  if (args.ranks == 0 || args.threads == 0 || args.sample == 0)
    throw Error("--ranks, --threads and --sample: expected at least 1");
  if (args.windows == 0 || !(args.window_share > 0.0 && args.window_share <= 1.0))
    throw Error("--windows: expected at least 1; --window-share: expected a share in (0, 1]");
  auto progress = [](const std::string& line) {
    std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  };
  const auto t0 = std::chrono::steady_clock::now();
  const std::unique_ptr<BuildSetup> setup = prepareBuild(args.build, progress);
  const double setup_seconds = secondsSince(t0);
  const double setup_rss = peakRssBytes();
  const bool by_lines = !setup->hfd || args.hfd_cells == "lines";
  const bool by_windows = setup->hfd && args.hfd_cells == "windows";
  std::vector<PfdCellJob> jobs = planPfdCells(setup->file.bsp, setup->scene.levels, setup->scene.eye_height,
                                              setup->options, setup->only, by_lines,
                                              [&](size_t done, size_t levels, size_t cells) {
                                                // The ETA assumes the levels left cost what the planned ones did.
                                                const double spent = secondsSince(t0) - setup_seconds;
                                                char line[160];
                                                std::snprintf(line, sizeof line,
                                                              "plan: %zu of %zu levels planned (%zu cells) in %.0f s, ETA %.0f s",
                                                              done, levels, cells, spent,
                                                              spent * static_cast<double>(levels - done) / static_cast<double>(done));
                                                progress(line);
                                              });
  if (jobs.empty()) throw Error(setup->scene.name + ": nothing walkable to plan");
  std::stable_sort(jobs.begin(), jobs.end(), [](const PfdCellJob& a, const PfdCellJob& b) { return a.cost > b.cost; });
  const size_t n = jobs.size();
  const size_t m = std::min<size_t>(args.sample, n);
  progress("plan: " + std::to_string(n) + " view cells; building " + std::to_string(m) + " of them, one per stratum of cost");

  // Strata of equal estimated cost, not of equal count: the few costliest cells, which decide
  // most of a build, get strata (and samples) of their own. Stratum k holds the sorted cells
  // [first[k], first[k + 1]); its sample is the cell at the middle of its cost.
  std::vector<double> cumulative(n + 1, 0.0);
  for (size_t i = 0; i < n; ++i) cumulative[i + 1] = cumulative[i] + jobs[i].cost + 1.0;
  std::vector<size_t> first{0};
  for (size_t k = 1; k < m; ++k) {
    const double target = cumulative[n] * static_cast<double>(k) / static_cast<double>(m);
    size_t i = static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin()) - 1;
    i = std::clamp(i, first.back() + 1, n - (m - k));  // every stratum non-empty
    first.push_back(i);
  }
  first.push_back(n);
  struct Sampled {
    size_t index = 0;
    double seconds = 0.0, bytes = 0.0, rays = 0.0;
    double sampling_seconds = 0.0;  // what sampling it took here (windows: less than `seconds`)
    bool over = false;
  };
  std::vector<Sampled> sampled(m);
  const uint32_t timing_eyes = queryTimingEyes(args.build.stat_eyes, n);
  const PfdCellContext context{&setup->file.bsp, setup->scene.levels, setup->scene.eye_height, setup->options};
  tbb::task_arena one_thread(1);
  for (size_t k = 0; k < m; ++k) {
    const size_t lo = first[k], hi = first[k + 1];
    Sampled& s = sampled[k];
    const double middle = 0.5 * (cumulative[lo] + cumulative[hi]);
    s.index = std::clamp<size_t>(static_cast<size_t>(std::upper_bound(cumulative.begin() + lo, cumulative.begin() + hi + 1, middle) -
                                                     cumulative.begin()) - 1, lo, hi - 1);
    const auto c0 = std::chrono::steady_clock::now();
    CellCost cost;
    one_thread.execute([&] {
      if (by_windows && jobs[s.index].box == std::nullopt) {
        cost = estimateByWindows(context, jobs[s.index], args.windows, args.window_share, timing_eyes,
                                 setup->options.tree.seed)
                   .cost;
        cost.over |= setup->options.cell_memory != 0 && cost.bytes > static_cast<double>(setup->options.cell_memory);
      } else {
        cost = measureCell(context, jobs[s.index], timing_eyes);
      }
    });
    s.sampling_seconds = secondsSince(c0);
    s.seconds = cost.seconds;
    s.bytes = cost.bytes;
    s.rays = cost.rays;
    s.over = cost.over;
    char line[160];
    std::snprintf(line, sizeof line, "plan: sample %zu/%zu (cell %zu of %zu by cost): %.2f s, %s%s", k + 1, m, s.index + 1,
                  n, s.seconds, human(s.bytes).c_str(), s.over ? " (over --cell-memory: the build would cut it)" : "");
    progress(line);
  }
  // Every cell at its stratum's rates per unit of cost (+ 1: a cell of no lines still costs its setup).
  std::vector<double> seconds(n), bytes(n);
  double cpu = 0.0, tree_bytes = 0.0, largest = 0.0;
  for (size_t k = 0; k < m; ++k) {
    const Sampled& s = sampled[k];
    const double unit = jobs[s.index].cost + 1.0;
    for (size_t i = first[k]; i < first[k + 1]; ++i) {
      const double c = jobs[i].cost + 1.0;
      seconds[i] = s.seconds * c / unit;
      bytes[i] = std::min(s.bytes * c / unit, static_cast<double>(std::max<uint64_t>(setup->options.cell_memory, 1)));
      cpu += seconds[i];
      tree_bytes += bytes[i];
      largest = std::max(largest, bytes[i]);
    }
  }
  const size_t over = static_cast<size_t>(std::count_if(sampled.begin(), sampled.end(), [](const Sampled& s) { return s.over; }));
  const double sampled_seconds = std::accumulate(sampled.begin(), sampled.end(), 0.0,
                                                 [](double a, const Sampled& s) { return a + s.sampling_seconds; });
  const uint64_t slots = static_cast<uint64_t>(args.ranks) * args.threads;
  const double trees_wall = makespan(seconds, slots);
  const double wall = setup_seconds + trees_wall;
  // A rank holds the scene, the BSP and the visibility scene (measured here) and builds up to
  // `threads` cells at once; rank 0 also holds every finished tree until the file is written.
  const double rank_memory = setup_rss + args.threads * largest;
  const double rank0_memory = rank_memory + tree_bytes;

  nlohmann::ordered_json j;
  j["scene"] = setup->scene.name;
  j["polygons"] = setup->scene.polygons.size();
  j["fragments"] = setup->file.bsp.fragments.size();
  j["tree"] = args.build.tree;
  j["levels"] = setup->only.empty() ? setup->scene.levels.size() : setup->only.size();
  j["cells"] = n;
  j["cells_planned_by"] = by_lines ? "lines" : "whole levels";
  j["sampled_by"] = by_windows ? "windows" : "cells";
  if (by_windows) {
    j["windows"] = args.windows;
    j["window_share"] = args.window_share;
  }
  j["sampled"] = m;
  j["sampled_over_cell_memory"] = over;
  j["sample_seconds"] = sampled_seconds;
  j["setup_seconds"] = setup_seconds;
  j["bsp_seconds"] = setup->file.bsp.stats.build_seconds;
  j["ranks"] = args.ranks;
  j["threads_per_rank"] = args.threads;
  j["cpu_seconds"] = cpu + setup_seconds * args.ranks;
  j["trees_cpu_seconds"] = cpu;
  j["tree_bytes"] = tree_bytes;
  j["rank_memory_bytes"] = rank_memory;
  j["rank0_memory_bytes"] = rank0_memory;
  j["trees_wall_seconds"] = trees_wall;
  j["wall_seconds"] = wall;
  j["wall_seconds_one_slot"] = setup_seconds + makespan(seconds, 1);
  auto samples = nlohmann::ordered_json::array();
  for (const Sampled& s : sampled)
    samples.push_back({{"cell", s.index}, {"level", jobs[s.index].level}, {"cost", jobs[s.index].cost},
                       {"seconds", s.seconds}, {"bytes", s.bytes}, {"rays", s.rays}, {"over_cell_memory", s.over}});
  j["samples"] = samples;
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("%s: %zu polygons, %zu fragments, %s trees of %zu view cells (planned by %s); %zu sampled%s in %.1f s\n",
              setup->scene.name.c_str(), setup->scene.polygons.size(), setup->file.bsp.fragments.size(),
              args.build.tree.c_str(), n, by_lines ? "lines" : "whole levels", m, by_windows ? " by windows" : "",
              sampled_seconds);
  std::printf("  setup per rank (load, BSP, visibility scene)  %s\n", hours(setup_seconds).c_str());
  std::printf("  trees, CPU                                   %s\n", hours(cpu).c_str());
  std::printf("  tree bytes                                   %s\n", human(tree_bytes).c_str());
  std::printf("  memory per rank / rank 0                     %s / %s\n", human(rank_memory).c_str(), human(rank0_memory).c_str());
  std::printf("  wall on %u rank%s x %u thread%s                  %s (one slot: %s)\n", args.ranks, args.ranks == 1 ? "" : "s",
              args.threads, args.threads == 1 ? "" : "s", hours(wall).c_str(),
              hours(setup_seconds + makespan(seconds, 1)).c_str());
  if (over > 0)
    std::printf("  warning: %zu of %zu sampled cells went over --cell-memory; the build cuts them and builds their "
                "quarters, which this plan does not count\n", over, m);
  return 0;
}

}  // namespace

void addPlanCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<PlanArgs>();
  auto* sub = app.add_subcommand(
      "plan",
      "Estimate a build: plan its view cells, build a sample of them (one per stratum of estimated cost, one thread "
      "each), and estimate the whole build's CPU time, tree bytes, memory per rank and wall time on --ranks ranks of "
      "--threads slots. Takes the build's options.");
  addSceneArgs(*sub, args->build.scene);
  addBuildOptions(*sub, args->build);
  sub->add_option("--ranks", args->ranks, "MPI ranks to estimate the wall time for (default 1)");
  sub->add_option("--threads", args->threads, "Slots (threads) per rank (default 1)");
  sub->add_option("--sample", args->sample, "View cells to build as the sample (default 12)");
  sub->add_option("--hfd-cells", args->hfd_cells,
                  "hfd: plan the cells by the lines' estimate (lines, default), take whole levels as the build's "
                  "first round does (whole), or take whole levels and estimate each sampled one from windows of it "
                  "(windows)")
      ->check(CLI::IsMember({"lines", "whole", "windows"}));
  sub->add_option("--windows", args->windows,
                  "--hfd-cells windows: whole levels, each sampled one estimated from this many square windows of it "
                  "(default 4, drawn by tiles weighted by area and lines) and a tiny one for its fixed cost");
  sub->add_option("--window-share", args->window_share,
                  "--hfd-cells windows: a window's side squared against the level's walkable area (default 1/16)");
  sub->add_flag("--json", args->json, "Print one JSON object");
  sub->callback([args, &runner] { runner = [args] { return runPlan(*args); }; });
}

}  // namespace walkvis
