// walkvis plan SCENE [--ranks K] [--threads T] [--sample N] [--json] [build options]: what a build
// of SCENE would cost, from a sample of its view cells built here. The cells are planned as the
// build plans its first round (PFD: by the lines' estimate; HFD levels start whole there, so the
// plan cuts them by the same estimate, `--hfd-cells lines`, or takes them whole, `whole`). The
// sampled cells are chosen from the cells sorted by estimated cost, one from the middle of each
// of N strata of equal count, and each is built on one thread. Every cell is then given the
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
#include <queue>
#include <thread>

#include <sys/resource.h>

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include "build_runner.h"
#include "build_setup.h"
#include "commands.h"
#include "pfd_hfd/pfd.h"

namespace walkvis {
namespace {

struct PlanArgs {
  BuildArgs build;
  uint32_t ranks = 1;
  uint32_t threads = 1;  // slots per rank
  uint32_t sample = 12;
  std::string hfd_cells = "lines";
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

int runPlan(const PlanArgs& args) {
  if (args.ranks == 0 || args.threads == 0 || args.sample == 0)
    throw Error("--ranks, --threads and --sample: expected at least 1");
  auto progress = [](const std::string& line) {
    std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  };
  const auto t0 = std::chrono::steady_clock::now();
  const std::unique_ptr<BuildSetup> setup = prepareBuild(args.build, progress);
  const double setup_seconds = secondsSince(t0);
  const double setup_rss = peakRssBytes();
  const bool by_lines = !setup->hfd || args.hfd_cells == "lines";
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
    bool over = false;
  };
  std::vector<Sampled> sampled(m);
  const PfdCellContext context{&setup->file.bsp, setup->scene.levels, setup->scene.eye_height, setup->options};
  tbb::task_arena one_thread(1);
  for (size_t k = 0; k < m; ++k) {
    const size_t lo = first[k], hi = first[k + 1];
    Sampled& s = sampled[k];
    const double middle = 0.5 * (cumulative[lo] + cumulative[hi]);
    s.index = std::clamp<size_t>(static_cast<size_t>(std::upper_bound(cumulative.begin() + lo, cumulative.begin() + hi + 1, middle) -
                                                     cumulative.begin()) - 1, lo, hi - 1);
    const auto c0 = std::chrono::steady_clock::now();
    PfdCellOutcome outcome;
    // As the build's slots do: the tree, then its query timing for the report.
    one_thread.execute([&] {
      outcome = buildPfdCell(context, jobs[s.index]);
      if (outcome.tree)
        outcome.tree->stats.query_timing = timePfdQueries(setup->file.bsp, *outcome.tree, queryTimingEyes(args.build.stat_eyes, n));
    });
    s.seconds = secondsSince(c0);
    s.over = !outcome.tree;
    s.bytes = outcome.tree ? static_cast<double>(outcome.tree->stats.bytes) : static_cast<double>(outcome.stopped_bytes);
    s.rays = outcome.tree ? static_cast<double>(outcome.tree->stats.visibility_rays) : 0.0;
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
                                                 [](double a, const Sampled& s) { return a + s.seconds; });
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
  std::printf("%s: %zu polygons, %zu fragments, %s trees of %zu view cells (planned by %s); %zu sampled in %.1f s\n",
              setup->scene.name.c_str(), setup->scene.polygons.size(), setup->file.bsp.fragments.size(),
              args.build.tree.c_str(), n, by_lines ? "lines" : "whole levels", m, sampled_seconds);
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
                  "hfd: plan the cells by the lines' estimate (lines, default) or take whole levels as the build's "
                  "first round does (whole)")
      ->check(CLI::IsMember({"lines", "whole"}));
  sub->add_flag("--json", args->json, "Print one JSON object");
  sub->callback([args, &runner] { runner = [args] { return runPlan(*args); }; });
}

}  // namespace walkvis
