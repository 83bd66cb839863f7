// walkvis build SCENE -o FILE: the BSP and one PFD tree per floor level (cut into view cells where
// a tree would be too large), their statistics, and one tree file holding them all.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "bsp/bsp.h"
#include "commands.h"
#include "pfd_hfd/pfd.h"

namespace walkvis {
namespace {

struct BuildArgs {
  SceneArgs scene;
  std::string output;
  std::string tree = "pfd";
  std::string max_memory = "1G";
  std::string cell_memory = "64M";
  std::string heuristic = "balanced";
  bool no_dedup = false;
  uint32_t stat_eyes = 10000;
  bool json = false;
};

// "1G", "512M", "64k", "123456": bytes (binary multiples).
uint64_t parseSize(const std::string& text, const std::string& option) {
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (...) {
    throw SceneError(option + ": '" + text + "' is not a size (e.g. 512M, 2G)");
  }
  std::string suffix = text.substr(used);
  double mult = 1.0;
  if (suffix == "k" || suffix == "K" || suffix == "KiB") mult = 1024.0;
  else if (suffix == "m" || suffix == "M" || suffix == "MiB") mult = 1024.0 * 1024.0;
  else if (suffix == "g" || suffix == "G" || suffix == "GiB") mult = 1024.0 * 1024.0 * 1024.0;
  else if (!suffix.empty() && suffix != "B") throw SceneError(option + ": unknown size suffix in '" + text + "'");
  if (!(value >= 0.0) || !std::isfinite(value) || value * mult > 1e18)
    throw SceneError(option + ": '" + text + "' is out of range");
  return static_cast<uint64_t>(value * mult);
}

struct QueryTiming {
  double pfd_ns = 0.0, runs_ns = 0.0, bsp_ns = 0.0;
  double runs_mean = 0.0;  // runs per query
};

// Mean wall time of one query at random eyes of the tree's region: the PFD walk against the BSP
// traversal it replaces (both with back faces skipped).
QueryTiming timeQueries(const BspTree& bsp, const PfdTree& tree, uint32_t eyes) {
  QueryTiming t;
  if (tree.region.empty() || eyes == 0) return t;
  std::vector<glm::dvec3> points;
  uint64_t state = 12345;
  for (uint32_t i = 0; i < eyes; ++i) {
    const glm::dvec2 p = samplePfdRegion(tree, state);
    points.emplace_back(p.x, tree.height, p.y);
  }
  std::vector<uint32_t> order;
  order.reserve(bsp.fragments.size());
  uint64_t sink = 0;
  auto t0 = std::chrono::steady_clock::now();
  for (const glm::dvec3& e : points) sink += pfdQuery(tree, e, order).tests + order.size();
  auto t1 = std::chrono::steady_clock::now();
  for (const glm::dvec3& e : points) {
    backToFront(bsp, e, order, true);
    sink += order.size();
  }
  auto t2 = std::chrono::steady_clock::now();
  std::vector<PfdRun> runs;
  uint64_t run_count = 0;
  for (const glm::dvec3& e : points) {
    sink += pfdQueryRuns(tree, e, runs).tests;
    run_count += runs.size();
  }
  auto t3 = std::chrono::steady_clock::now();
  t.runs_ns = std::chrono::duration<double, std::nano>(t3 - t2).count() / eyes;
  t.runs_mean = static_cast<double>(run_count) / eyes;
  t.pfd_ns = std::chrono::duration<double, std::nano>(t1 - t0).count() / eyes;
  t.bsp_ns = std::chrono::duration<double, std::nano>(t2 - t1).count() / eyes;
  if (sink == 42) std::fprintf(stderr, " ");  // keeps the loops from being optimised away
  return t;
}

int runBuild(const BuildArgs& args) {
  if (args.tree != "pfd") throw SceneError("--tree: only 'pfd' is built so far (got '" + args.tree + "')");
  PfdLevelOptions options;
  options.max_memory = parseSize(args.max_memory, "--max-memory");
  options.cell_memory = parseSize(args.cell_memory, "--cell-memory");
  if (args.heuristic == "balanced") options.tree.heuristic = PfdHeuristic::kBalanced;
  else if (args.heuristic == "traversal") options.tree.heuristic = PfdHeuristic::kTraversal;
  else throw SceneError("--heuristic: expected balanced or traversal, got '" + args.heuristic + "'");
  options.tree.dedup = !args.no_dedup;
  options.tree.stat_eyes = args.stat_eyes;

  auto progress = [](const std::string& line) {
    std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  };
  const Scene scene = loadScene(args.scene.scene, args.scene.loadOptions());
  progress("loaded " + scene.name + ": " + std::to_string(scene.polygons.size()) + " polygons, " +
           std::to_string(scene.levels.size()) + " levels");
  TreeFile file;
  file.eye_height = scene.eye_height;
  file.bsp = buildBsp(scene);
  progress("bsp: " + std::to_string(file.bsp.stats.fragments) + " fragments, " + std::to_string(file.bsp.stats.nodes) +
           " nodes, " + std::to_string(file.bsp.stats.build_seconds) + " s");
  uint64_t used = 0;
  for (size_t l = 0; l < scene.levels.size(); ++l) {
    progress("level " + std::to_string(l) + " of " + std::to_string(scene.levels.size()) + "...");
    file.levels.push_back(
        buildPfdLevel(file.bsp, scene.levels[l], static_cast<uint32_t>(l), scene.eye_height, options, used, progress));
  }
  saveTreeFile(file, args.output);

  const double n = static_cast<double>(file.bsp.stats.fragments);
  const double log43 = n > 1 ? std::log(n) / std::log(4.0 / 3.0) : 0.0;
  nlohmann::ordered_json j;
  j["scene"] = scene.name;
  j["file"] = args.output;
  j["eye_height"] = scene.eye_height;
  j["fragments"] = file.bsp.stats.fragments;
  j["bsp_nodes"] = file.bsp.stats.nodes;
  j["bsp_build_seconds"] = file.bsp.stats.build_seconds;
  j["log43_fragments"] = log43;
  j["max_memory"] = options.max_memory;
  j["cell_memory"] = options.cell_memory;
  j["heuristic"] = args.heuristic;
  j["dedup"] = !args.no_dedup;
  j["total_bytes"] = used;
  auto trees = nlohmann::ordered_json::array();
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
      e["nodes"] = s.nodes;
      e["list_entries"] = s.list_entries;
      e["list_fragments"] = s.list_fragments;
      e["pool_entries"] = s.pool_entries;
      e["runs"] = s.runs;
      e["bytes"] = s.bytes;
      e["view_cells"] = level.cells.size();
      e["build_seconds"] = s.build_seconds;
      const QueryTiming qt = timeQueries(file.bsp, t, std::min<uint32_t>(args.stat_eyes, 2000));
      e["query_ns"] = qt.pfd_ns;
      e["query_runs_ns"] = qt.runs_ns;
      e["runs_per_query"] = qt.runs_mean;
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
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("scene %s: N = %llu fragments, log_{4/3} N = %.1f; wrote %s (%llu bytes of trees)\n", scene.name.c_str(),
              static_cast<unsigned long long>(file.bsp.stats.fragments), log43, args.output.c_str(),
              static_cast<unsigned long long>(used));
  std::printf("%5s %4s %9s %9s %6s %8s %10s %11s %12s %12s %8s %9s %9s\n", "level", "cell", "height", "tests", "max",
              "entropy", "nodes", "list_refs", "pool", "bytes", "seconds", "query_ns", "bsp_ns");
  for (const auto& e : trees)
    std::printf("%5d %4d %9.6g %9.2f %6d %8.2f %10llu %11llu %12llu %12llu %8.3f %9.0f %9.0f\n", e["level"].get<int>(),
                e["cell"].get<int>(), e["height"].get<double>(), e["tests_mean"].get<double>(),
                e["tests_max"].get<int>(), e["tests_entropy_bound"].get<double>(),
                e["nodes"].get<unsigned long long>(), e["list_entries"].get<unsigned long long>(),
                e["pool_entries"].get<unsigned long long>(), e["bytes"].get<unsigned long long>(),
                e["build_seconds"].get<double>(), e["query_ns"].get<double>(), e["bsp_query_ns"].get<double>());
  return 0;
}

}  // namespace

void addBuildCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<BuildArgs>();
  auto* sub = app.add_subcommand("build", "Build the BSP and a PFD tree per floor level into one tree file");
  addSceneArgs(*sub, args->scene);
  sub->add_option("-o,--output", args->output, "Tree file to write")->required();
  sub->add_option("--tree", args->tree, "Tree kind: pfd");
  sub->add_option("--max-memory", args->max_memory, "Budget for all trees together (e.g. 512M, 2G; default 1G)");
  sub->add_option("--cell-memory", args->cell_memory,
                  "A tree over this many bytes is cut into four view cells (default 64M; 0: never)");
  sub->add_option("--heuristic", args->heuristic, "Which undecided test-line first: balanced or traversal");
  sub->add_flag("--no-dedup", args->no_dedup, "Store every emitted run, not each distinct one once");
  sub->add_option("--stat-eyes", args->stat_eyes, "Random eyes per tree for tests_mean / tests_max");
  sub->add_flag("--json", args->json, "Print one JSON object");
  sub->callback([args, &runner] { runner = [args] { return runBuild(*args); }; });
}

}  // namespace walkvis
