// Query time of the PFD tree (James & Day 1998 [JamesDay1998]; docs/DESIGN.md, "PFD tree") against
// the BSP back-to-front traversal it replaces (Fuchs, Kedem & Naylor 1980 [FuchsKedemNaylor1980]),
// on one level of a scene with
// pre-sampled eyes on its height plane, both with back faces skipped (the same sequence of
// fragment ids). Counters: plane_tests = plane tests per query (PFD: internal nodes on the path;
// BSP: one side test per node visited, i.e. every node), ids = fragment ids per query, runs =
// runs per query (pfdQueryRuns), ref_ranges = ranges of run_refs per query (pfdQueryRefs: the
// walk alone, its answer unexpanded).
//
//   bench_pfd [--scenes=gen:office,freedoom2.wad:MAP01] [--level=largest|INDEX] [--eyes=4096]
//             [--share-min=64 (PfdOptions::share_min; 4294967295: flat runs only)] [--build]
//             [google benchmark flags, e.g. --benchmark_min_time=0.2]
// --build adds the build of the level's trees with the optimal test-order searches
// (PfdOptions::search_lines, root_search_lines) and without (the greedy even split), each
// iteration a whole buildPfdLevel; counters: tests_mean = area-weighted exact mean tests over the
// cells, optimal = cells flagged tests_optimal.
// The tree is built as `walkvis build` builds it (buildPfdLevel: view cells above 64 MiB); each
// eye is queried in the cell that holds it (resolved once, before timing, as a walkthrough does
// when it changes cells).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bsp/bsp.h"
#include "pfd_hfd/pfd.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

struct BenchLevel {
  std::string name;
  BspTree bsp;
  FloorLevel floor;  // the level's walkable region, for the build benchmark
  uint32_t level_index = 0;
  double eye_height = 0.0;
  PfdLevel level;
  std::vector<glm::dvec3> eyes;         // random eyes of the level's region
  std::vector<const PfdTree*> trees;    // the cell tree of each eye
  std::vector<glm::dvec3> walk;         // a path of small steps (frame coherence)
  std::vector<const PfdTree*> walk_trees;
};

std::shared_ptr<BenchLevel> prepare(const std::string& spec, const std::string& level_choice, uint32_t eye_count,
                                    uint32_t share_min) {
  auto b = std::make_shared<BenchLevel>();
  const Scene scene = loadScene(spec);
  if (scene.levels.empty()) throw Error(spec + ": no walkable level");
  size_t li = 0;
  if (level_choice == "largest") {
    for (size_t l = 1; l < scene.levels.size(); ++l)
      if (scene.levels[l].walkable_area > scene.levels[li].walkable_area) li = l;
  } else {
    li = std::stoul(level_choice);
    if (li >= scene.levels.size()) throw Error(spec + ": no level " + level_choice);
  }
  b->bsp = buildBsp(scene);
  b->floor = scene.levels[li];
  b->level_index = static_cast<uint32_t>(li);
  b->eye_height = scene.eye_height;
  PfdLevelOptions options;
  options.tree.stat_eyes = 0;
  options.tree.share_min = share_min;
  uint64_t used = 0;
  b->level = buildPfdLevel(b->bsp, scene.levels[li], static_cast<uint32_t>(li), scene.eye_height, options, used);
  uint64_t state = 42;
  while (b->eyes.size() < eye_count) {
    const glm::dvec3 e = samplePfdLevel(b->level, state).value();
    if (const PfdTree* t = findPfdCell(b->level, e)) {
      b->eyes.push_back(e);
      b->trees.push_back(t);
    }
  }
  // A walk: steps of 1/200 of the way to the next random eye, while they stay in one cell.
  glm::dvec3 at = b->eyes[0];
  const PfdTree* at_tree = b->trees[0];
  for (size_t k = 1; b->walk.size() < eye_count; k = (k + 1) % b->eyes.size()) {
    const glm::dvec3 to = b->eyes[k];
    for (int s = 1; s <= 200 && b->walk.size() < eye_count; ++s) {
      const glm::dvec3 p = at + (to - at) * (s / 200.0);
      const PfdTree* t = findPfdCell(b->level, p);
      if (!t || !strictlyInsidePfdRegion(*t, p)) break;
      b->walk.push_back(p);
      b->walk_trees.push_back(t);
    }
    if (b->walk.empty()) {  // the first step already left the region: start from an eye
      b->walk.push_back(b->eyes[k]);
      b->walk_trees.push_back(b->trees[k]);
    }
    at = b->walk.back();
    at_tree = b->walk_trees.back();
  }
  (void)at_tree;
  uint64_t bytes = 0;
  for (const PfdTree& t : b->level.cells) bytes += t.stats.bytes;
  std::fprintf(stderr, "%s level %zu: N = %zu fragments, %zu BSP nodes, %zu view cells, %llu tree bytes (share_min %u)\n",
               spec.c_str(), li, b->bsp.fragments.size(), b->bsp.nodes.size(), b->level.cells.size(),
               static_cast<unsigned long long>(bytes), share_min);
  b->name = spec + "/level" + std::to_string(li);
  return b;
}

void setCounters(benchmark::State& state, double tests, double ids, const BenchLevel& b) {
  state.counters["plane_tests"] = benchmark::Counter(tests, benchmark::Counter::kAvgIterations);
  state.counters["ids"] = benchmark::Counter(ids, benchmark::Counter::kAvgIterations);
  state.counters["N"] = static_cast<double>(b.bsp.fragments.size());
}

void benchPfdQuery(benchmark::State& state, std::shared_ptr<BenchLevel> b) {
  std::vector<uint32_t> order;
  order.reserve(b->bsp.fragments.size());
  size_t k = 0;
  double tests = 0, ids = 0;
  for (auto _ : state) {
    const PfdQueryResult q = pfdQuery(*b->trees[k], b->eyes[k], order);
    benchmark::DoNotOptimize(order.data());
    tests += q.tests;
    ids += static_cast<double>(order.size());
    k = k + 1 == b->eyes.size() ? 0 : k + 1;
  }
  setCounters(state, tests, ids, *b);
}

void benchPfdQueryRuns(benchmark::State& state, std::shared_ptr<BenchLevel> b) {
  std::vector<PfdRun> runs;
  runs.reserve(b->bsp.fragments.size());
  size_t k = 0;
  double tests = 0, ids = 0, run_count = 0;
  for (auto _ : state) {
    const PfdQueryResult q = pfdQueryRuns(*b->trees[k], b->eyes[k], runs);
    benchmark::DoNotOptimize(runs.data());
    tests += q.tests;
    run_count += static_cast<double>(runs.size());
    for (const PfdRun& r : runs) ids += r.count;
    k = k + 1 == b->eyes.size() ? 0 : k + 1;
  }
  setCounters(state, tests, ids, *b);
  state.counters["runs"] = benchmark::Counter(run_count, benchmark::Counter::kAvgIterations);
}

// The walk alone (pfdQueryRefs): the ranges of run_refs on the path, nothing expanded
// (ref_ranges = ranges per query; ids is left 0: the order they describe is pfdQueryRuns' ids).
// walk = true: the eyes of the small-step walk (nodes near the path stay in cache, as in a
// walkthrough); false: independent random eyes over all cells (each step down is mostly a cache
// miss: the office's 64 cell trees hold ~0.5 GB).
void benchPfdQueryRefs(benchmark::State& state, std::shared_ptr<BenchLevel> b, bool walk) {
  const auto& eyes = walk ? b->walk : b->eyes;
  const auto& trees = walk ? b->walk_trees : b->trees;
  std::vector<PfdRefRange> lists;
  lists.reserve(256);
  size_t k = 0;
  double tests = 0, ranges = 0;
  for (auto _ : state) {
    const PfdQueryResult q = pfdQueryRefs(*trees[k], eyes[k], lists);
    benchmark::DoNotOptimize(lists.data());
    tests += q.tests;
    ranges += static_cast<double>(lists.size());
    k = k + 1 == eyes.size() ? 0 : k + 1;
  }
  setCounters(state, tests, 0.0, *b);
  state.counters["ref_ranges"] = benchmark::Counter(ranges, benchmark::Counter::kAvgIterations);
}

// walk = true: consecutive eyes a small step apart (the case frame coherence is for); false:
// independent random eyes (its worst case).
void benchPfdQueryCoherent(benchmark::State& state, std::shared_ptr<BenchLevel> b, bool walk) {
  const auto& eyes = walk ? b->walk : b->eyes;
  const auto& trees = walk ? b->walk_trees : b->trees;
  std::vector<uint32_t> order;
  order.reserve(b->bsp.fragments.size());
  PfdCursor cursor;
  size_t k = 0;
  double tests = 0, ids = 0;
  for (auto _ : state) {
    const PfdQueryResult q = pfdQueryCoherent(*trees[k], eyes[k], cursor, order);
    benchmark::DoNotOptimize(order.data());
    tests += q.tests;
    ids += static_cast<double>(order.size());
    k = k + 1 == eyes.size() ? 0 : k + 1;
  }
  setCounters(state, tests, ids, *b);
}

void benchBsp(benchmark::State& state, std::shared_ptr<BenchLevel> b) {
  std::vector<uint32_t> order;
  order.reserve(b->bsp.fragments.size());
  size_t k = 0;
  double ids = 0;
  for (auto _ : state) {
    backToFront(b->bsp, b->eyes[k], order, true);
    benchmark::DoNotOptimize(order.data());
    ids += static_cast<double>(order.size());
    k = k + 1 == b->eyes.size() ? 0 : k + 1;
  }
  // The traversal decides the side of every node's plane once per query.
  setCounters(state, static_cast<double>(state.iterations()) * static_cast<double>(b->bsp.nodes.size()), ids, *b);
}

// The level's trees built as `walkvis build` builds them, with the searches (search = true) or
// with the greedy even split alone.
void benchBuild(benchmark::State& state, std::shared_ptr<BenchLevel> b, bool search) {
  PfdLevelOptions options;
  options.tree.stat_eyes = 0;
  if (!search) options.tree.search_lines = 0;
  double area_tests = 0.0, area = 0.0, optimal = 0.0;
  for (auto _ : state) {
    uint64_t used = 0;
    const PfdLevel level = buildPfdLevel(b->bsp, b->floor, b->level_index, b->eye_height, options, used);
    area_tests = area = optimal = 0.0;
    for (const PfdTree& t : level.cells) {
      area_tests += t.stats.tests_area_mean * t.stats.region_area;
      area += t.stats.region_area;
      optimal += t.stats.tests_optimal;
    }
  }
  state.counters["tests_mean"] = area > 0.0 ? area_tests / area : 0.0;
  state.counters["optimal"] = optimal;
  state.counters["N"] = static_cast<double>(b->bsp.fragments.size());
}

}  // namespace
}  // namespace walkvis

int main(int argc, char** argv) {
  using namespace walkvis;
  std::string scenes = "gen:office,freedoom2.wad:MAP01";
  std::string level = "largest";
  uint32_t eyes = 4096;
  uint32_t share_min = PfdOptions{}.share_min;
  bool build = false;
  std::vector<char*> rest{argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--scenes=", 9) == 0) scenes = argv[i] + 9;
    else if (std::strncmp(argv[i], "--level=", 8) == 0) level = argv[i] + 8;
    else if (std::strncmp(argv[i], "--eyes=", 7) == 0) eyes = static_cast<uint32_t>(std::max(1l, std::atol(argv[i] + 7)));
    else if (std::strncmp(argv[i], "--share-min=", 12) == 0)
      share_min = static_cast<uint32_t>(std::strtoul(argv[i] + 12, nullptr, 10));
    else if (std::strcmp(argv[i], "--build") == 0) build = true;
    else rest.push_back(argv[i]);
  }
  int rest_argc = static_cast<int>(rest.size());
  benchmark::Initialize(&rest_argc, rest.data());
  std::stringstream ss(scenes);
  std::string spec;
  try {
    while (std::getline(ss, spec, ',')) {
      const auto b = prepare(spec, level, eyes, share_min);
      benchmark::RegisterBenchmark((b->name + "/pfdQuery").c_str(), benchPfdQuery, b);
      benchmark::RegisterBenchmark((b->name + "/pfdQueryRuns").c_str(), benchPfdQueryRuns, b);
      benchmark::RegisterBenchmark((b->name + "/pfdQueryRefs/random").c_str(), benchPfdQueryRefs, b, false);
      benchmark::RegisterBenchmark((b->name + "/pfdQueryRefs/walk").c_str(), benchPfdQueryRefs, b, true);
      benchmark::RegisterBenchmark((b->name + "/pfdQueryCoherent/random").c_str(), benchPfdQueryCoherent, b, false);
      benchmark::RegisterBenchmark((b->name + "/pfdQueryCoherent/walk").c_str(), benchPfdQueryCoherent, b, true);
      benchmark::RegisterBenchmark((b->name + "/bspBackToFront").c_str(), benchBsp, b);
      if (build) {
        benchmark::RegisterBenchmark((b->name + "/pfdBuild/greedy").c_str(), benchBuild, b, false)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark((b->name + "/pfdBuild/search").c_str(), benchBuild, b, true)
            ->Unit(benchmark::kMillisecond);
      }
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_pfd: %s\n", e.what());
    return 2;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
