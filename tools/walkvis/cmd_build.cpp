// walkvis build SCENE -o FILE [--tree pfd|hfd]: the BSP and one PFD or HFD tree per floor level
// (cut into view cells where a tree would be too large), their statistics, and one tree file
// holding them all. HFD trees (James & Day 1998 [JamesDay1998HFD], docs/DESIGN.md, "HFD tree") test
// each fragment for visibility from the node's region with a VisibilityScene of the whole BSP
// (pfd_hfd/visibility.h).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "bsp/bsp.h"
#include "build_runner.h"
#include "build_setup.h"
#include "commands.h"
#include "pfd_hfd/pfd.h"
#include "pfd_hfd/pfd_journal.h"

namespace walkvis {
namespace {

// The HFD visibility counters of a tree's statistics, by their JSON names (per tree and summed).
constexpr std::pair<const char*, uint64_t PfdStats::*> kVisibilityFields[] = {
    {"visibility_tests", &PfdStats::visibility_tests},
    {"visibility_rays", &PfdStats::visibility_rays},
    {"hidden_rejected", &PfdStats::hidden_rejected},
    {"visibility_witnessed", &PfdStats::visibility_witnessed},
    {"objects_box_rejected", &PfdStats::objects_box_rejected},
    {"visibility_hidden_rays", &PfdStats::visibility_hidden_rays},
    {"visibility_proved_hidden", &PfdStats::visibility_proved_hidden},
    {"visibility_proof_rays", &PfdStats::visibility_proof_rays},
    {"visibility_refine_rays", &PfdStats::visibility_refine_rays},
    {"visibility_refined_visible", &PfdStats::visibility_refined_visible},
    {"visibility_patch_covers", &PfdStats::visibility_patch_covers},
    {"visibility_kept_unproven", &PfdStats::visibility_kept_unproven},
};

int runBuild(const BuildArgs& args, const MpiWorld& world, bool& distributing);

int runBuild(const BuildArgs& args) {
  MpiWorld world;
  bool distributing = false;  // set once the ranks exchange jobs
  try {
    return runBuild(args, world, distributing);
  } catch (const Error& e) {
    if (!world.active() || world.size() == 1) throw;
    // Before the ranks exchange jobs every rank meets the same bad input: rank 0 says it once.
    if (!distributing) {
      if (world.rank() == 0) throw;
      return kExitBadInput;
    }
    // Afterwards the other ranks may be waiting on this one, or this one on them: end them all.
    std::fprintf(stderr, "walkvis: %s\n", e.what());
    std::fflush(stderr);
    world.abort(kExitBadInput);
  }
}

int runBuild(const BuildArgs& args, const MpiWorld& world, bool& distributing) {
  const bool leader = world.rank() == 0;
  // Threads per process: --threads, or under MPI the machine's cores shared by its ranks.
  uint32_t threads = args.threads;
  if (threads == 0 && world.active())
    threads = std::max(1u, std::thread::hardware_concurrency() / static_cast<unsigned>(world.localSize()));
  std::optional<tbb::global_control> thread_limit;
  if (threads > 0) thread_limit.emplace(tbb::global_control::max_allowed_parallelism, threads);
  const uint32_t slots = threads > 0 ? threads : std::max(1u, std::thread::hardware_concurrency());
  auto progress = [leader](const std::string& line) {
    if (!leader) return;  // the others' progress is in rank 0's lines
    std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  };
  const std::unique_ptr<BuildSetup> setup = prepareBuild(args, progress);
  const bool hfd = setup->hfd;
  const Scene& scene = setup->scene;
  TreeFile& file = setup->file;
  const PfdLevelOptions& options = setup->options;
  const VisibilityOptions& vis_options = setup->file.visibility;
  const std::vector<uint32_t>& only = setup->only;
  const double visibility_seconds = setup->visibility_seconds;
  const PfdCellContext context{&file.bsp, scene.levels, scene.eye_height, options};
  distributing = world.size() > 1;
  if (!leader) {
    serveCells(context, world, slots);
    return 0;
  }
  std::string note;
  PfdJournal journal(args.output + ".journal", pfdBuildFingerprint(file, scene.levels, only, options), args.fresh, note);
  if (!note.empty()) progress(note);
  uint64_t used = 0;
  const auto build0 = std::chrono::steady_clock::now();
  std::string ranks;
  {
    CellScheduler scheduler(context, world, slots, &journal, progress);
    progress(std::to_string(only.empty() ? scene.levels.size() : only.size()) + " levels on " +
             std::to_string(world.size()) + (world.size() == 1 ? " process" : " ranks") + " of " +
             std::to_string(slots) + (slots == 1 ? " thread" : " threads") + "...");
    file.levels = buildPfdLevels(file.bsp, scene.levels, scene.eye_height, options, used, progress, only,
                                 scheduler.runner());
    ranks = scheduler.summary();
  }
  distributing = false;  // the other ranks have stopped
  const double trees_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - build0).count();
  saveTreeFile(file, args.output);
  journal.remove();
  progress("wrote " + args.output + " (" + ranks + ")");

  const double n = static_cast<double>(file.bsp.stats.fragments);
  const double log43 = n > 1 ? std::log(n) / std::log(4.0 / 3.0) : 0.0;
  // The paper's size bound, N^1.5 · log_{4/3} n (N fragments, n input polygons).
  const double n_input = static_cast<double>(file.bsp.stats.input_polygons);
  const double entries_bound = std::pow(n, 1.5) * (n_input > 1 ? std::log(n_input) / std::log(4.0 / 3.0) : 0.0);
  nlohmann::ordered_json j;
  j["scene"] = scene.name;
  j["file"] = args.output;
  j["tree"] = args.tree;
  j["eye_height"] = scene.eye_height;
  j["fragments"] = file.bsp.stats.fragments;
  j["bsp_nodes"] = file.bsp.stats.nodes;
  j["bsp_build_seconds"] = file.bsp.stats.build_seconds;
  j["input_polygons"] = file.bsp.stats.input_polygons;
  j["log43_fragments"] = log43;
  j["log43_N"] = log43;
  j["entries_bound"] = entries_bound;
  j["drop_back_faces"] = options.tree.drop_back_faces;
  if (hfd) {
    j["samples"] = {{"region", vis_options.region_samples},
                    {"polygon", vis_options.polygon_samples},
                    {"refine", vis_options.refine_rays},
                    {"seed", vis_options.seed}};
    j["fuse_occluders"] = vis_options.fuse_occluders;
    j["visibility_mode"] = args.visibility_mode;
    j["sampled_region_max"] = args.sampled_region_max;
    j["visibility_scene_seconds"] = visibility_seconds;
  }
  j["trees_seconds"] = trees_seconds;
  j["ranks"] = world.size();
  j["threads_per_rank"] = slots;
  j["max_memory"] = options.max_memory;
  j["cell_memory"] = options.cell_memory;
  j["heuristic"] = args.heuristic;
  j["dedup"] = !args.no_dedup;
  j["object_boxes"] = !args.no_object_boxes;
  j["share_min"] = args.share_min;
  j["search_lines"] = args.search_lines;
  j["search_work"] = args.search_work;
  j["root_search_lines"] = args.root_search_lines;
  j["root_search_work"] = args.root_search_work;
  j["total_bytes"] = used;
  uint64_t total_cells = 0, over_bound = 0;
  PfdStats total;  // the visibility counters summed over the trees
  auto trees = nlohmann::ordered_json::array();
  // Every cell's query timing was measured by the slot that built it (build_runner.cpp,
  // buildTimedPfdCell) and came back with it, from another rank or the journal too.
  for (const PfdLevel& level : file.levels) {
    for (size_t c = 0; c < level.cells.size(); ++c) {
      const PfdTree& t = level.cells[c];
      const PfdStats& s = t.stats;
      nlohmann::ordered_json e;
      e["level"] = level.level;
      e["floor_y"] = level.floor_y;
      e["height"] = level.height;
      e["cell"] = c;
      if (t.cell) e["cell_box"] = {t.cell->lo.x, t.cell->lo.y, t.cell->hi.x, t.cell->hi.y};
      e["fragments"] = s.fragments;
      e["tests_mean"] = s.tests_mean;
      e["tests_max"] = s.tests_max;
      e["tests_entropy_bound"] = s.tests_entropy_bound;
      e["tests_huffman_bound"] = s.tests_huffman_bound;
      e["tests_cell_bound"] = s.tests_cell_bound;
      e["tests_area_mean"] = s.tests_area_mean;
      e["tests_search_mean"] = s.tests_search_mean;
      e["tests_optimal"] = s.tests_optimal;
      e["root_search_lines"] = s.root_search_lines;
      e["root_search_work_done"] = s.root_search_work_done;
      e["nodes"] = s.nodes;
      e["list_entries"] = s.list_entries;
      e["list_fragments"] = s.list_fragments;
      e["pool_entries"] = s.pool_entries;
      e["runs"] = s.runs;
      e["seqs"] = s.seqs;
      e["seq_items"] = s.seq_items;
      e["objects"] = s.objects;
      e["object_nodes"] = s.object_nodes;
      e["object_fragments"] = s.object_fragments;
      e["bytes"] = s.bytes;
      e["view_cells"] = level.cells.size();
      e["build_seconds"] = s.build_seconds;
      e["log43_N"] = log43;
      e["entries_bound"] = entries_bound;
      // Entries stored: references in the lists and sequences plus fragment ids in the run pool.
      const uint64_t stored = s.list_entries + s.pool_entries + s.seq_items;
      e["stored_entries"] = stored;
      e["within_entries_bound"] = static_cast<double>(stored) <= entries_bound;
      if (static_cast<double>(stored) > entries_bound) ++over_bound;
      for (const auto& [name, field] : kVisibilityFields) {
        if (hfd) e[name] = s.*field;
        total.*field += s.*field;
      }
      ++total_cells;
      const PfdQueryTiming& qt = t.stats.query_timing;
      e["query_ns"] = qt.pfd_ns;
      e["query_runs_ns"] = qt.runs_ns;
      e["runs_per_query"] = qt.runs_mean;
      e["query_refs_ns"] = qt.refs_ns;
      e["ref_ranges_per_query"] = qt.refs_mean;
      e["object_tests_per_query"] = qt.object_tests_mean;
      e["bsp_query_ns"] = qt.bsp_ns;
      e["bsp_tests"] = file.bsp.stats.nodes;
      e["region_area"] = s.region_area;
      e["touching_decisions"] = s.touching;
      e["decisions"] = s.decisions;
      e["exact_fallbacks"] = s.exact_fallbacks;
      trees.push_back(e);
    }
  }
  j["trees"] = trees;
  j["view_cells"] = total_cells;
  j["trees_over_entries_bound"] = over_bound;
  if (hfd) {
    for (const auto& [name, field] : kVisibilityFields) j[name] = total.*field;
    j["rays_per_second"] = trees_seconds > 0 ? static_cast<double>(total.visibility_rays) / trees_seconds : 0.0;
  }
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("scene %s: %s trees, N = %llu fragments, log_{4/3} N = %.1f, N^1.5 log_{4/3} n = %.3g; wrote %s "
              "(%llu bytes of trees in %llu view cells, %.1f s)\n",
              scene.name.c_str(), args.tree.c_str(), static_cast<unsigned long long>(file.bsp.stats.fragments), log43,
              entries_bound, args.output.c_str(), static_cast<unsigned long long>(used),
              static_cast<unsigned long long>(total_cells), trees_seconds);
  if (hfd)
    std::printf("hfd: %llu visibility tests, %llu rays (%.3g rays/s over the tree builds), %llu fragments rejected\n",
                static_cast<unsigned long long>(total.visibility_tests),
                static_cast<unsigned long long>(total.visibility_rays),
                trees_seconds > 0 ? static_cast<double>(total.visibility_rays) / trees_seconds : 0.0,
                static_cast<unsigned long long>(total.hidden_rejected));
  if (over_bound > 0)
    std::printf("warning: %llu trees store more than N^1.5 log_{4/3} n entries\n",
                static_cast<unsigned long long>(over_bound));
  std::printf("%5s %4s %9s %9s %6s %8s %8s %10s %11s %12s %12s %8s %9s %8s %9s\n", "level", "cell", "height", "tests",
              "max", "entropy", "huffman", "nodes", "list_refs", "pool", "bytes", "seconds", "query_ns", "refs_ns",
              "bsp_ns");
  for (const auto& e : trees)
    std::printf("%5d %4d %9.6g %9.2f %6d %8.2f %8.2f %10llu %11llu %12llu %12llu %8.3f %9.0f %8.0f %9.0f\n",
                e["level"].get<int>(), e["cell"].get<int>(), e["height"].get<double>(), e["tests_mean"].get<double>(),
                e["tests_max"].get<int>(), e["tests_entropy_bound"].get<double>(),
                e["tests_huffman_bound"].get<double>(), e["nodes"].get<unsigned long long>(),
                e["list_entries"].get<unsigned long long>(), e["pool_entries"].get<unsigned long long>(),
                e["bytes"].get<unsigned long long>(), e["build_seconds"].get<double>(), e["query_ns"].get<double>(),
                e["query_refs_ns"].get<double>(), e["bsp_query_ns"].get<double>());
  return 0;
}

}  // namespace

void addBuildCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<BuildArgs>();
  auto* sub = app.add_subcommand(
      "build",
      "Build the BSP and a PFD or HFD tree per floor level (view cells where a tree exceeds --cell-memory) into one "
      "tree file (versioned, checksummed, written atomically). Default memory budget: 1 GiB for all trees together, "
      "64 MiB per view cell; exceeding the budget is an error (exit 2) naming the level and the bytes its trees "
      "need at least, never an out-of-memory crash. Progress on stderr.");
  addSceneArgs(*sub, args->scene);
  sub->add_option("-o,--output", args->output, "Tree file to write")->required();
  addBuildOptions(*sub, *args);
  sub->add_option("--threads", args->threads,
                  "Threads per process (default: all cores; under mpirun the cores shared by the ranks on a machine)");
  sub->add_flag("--fresh", args->fresh,
                "Start over: discard the journal (OUTPUT.journal) of an interrupted build of the same command, "
                "which a rerun otherwise goes on from");
  sub->add_flag("--json", args->json, "Print one JSON object");
  sub->callback([args, &runner] { runner = [args] { return runBuild(*args); }; });
}

}  // namespace walkvis
