// build_setup.h: the build's options and inputs, shared by `walkvis build` and `walkvis plan`.
#include "build_setup.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "bsp/bsp.h"

namespace walkvis {

std::string formatSize(uint64_t bytes) {
  for (const auto& [shift, suffix] : {std::pair{30, "G"}, {20, "M"}, {10, "k"}})
    if (bytes != 0 && bytes % (1ull << shift) == 0) return std::to_string(bytes >> shift) + suffix;
  return std::to_string(bytes);
}

namespace {

// "1G", "512M", "64k", "123456": bytes (binary multiples).
uint64_t parseSize(const std::string& text, const std::string& option) {
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (...) {
    throw Error(option + ": '" + text + "' is not a size (e.g. 512M, 2G)");
  }
  std::string suffix = text.substr(used);
  double mult = 1.0;
  if (suffix == "k" || suffix == "K" || suffix == "KiB") mult = 1024.0;
  else if (suffix == "m" || suffix == "M" || suffix == "MiB") mult = 1024.0 * 1024.0;
  else if (suffix == "g" || suffix == "G" || suffix == "GiB") mult = 1024.0 * 1024.0 * 1024.0;
  else if (!suffix.empty() && suffix != "B") throw Error(option + ": unknown size suffix in '" + text + "'");
  if (!(value >= 0.0) || !std::isfinite(value) || value * mult > 1e18)
    throw Error(option + ": '" + text + "' is out of range");
  return static_cast<uint64_t>(value * mult);
}

// "R,P,REFINE": region samples, polygon samples, refinement rays (VisibilityOptions).
VisibilityOptions parseSamples(const std::string& text, VisibilityOptions options) {
  if (text.empty()) return options;
  std::vector<uint32_t> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    size_t used = 0;
    unsigned long x = 0;
    try {
      x = std::stoul(item, &used);
    } catch (...) {
      used = 0;
    }
    if (used == 0 || used != item.size() || x > 1000000)
      throw Error("--samples: '" + text + "' is not R,P,REFINE (three counts up to 1000000)");
    v.push_back(static_cast<uint32_t>(x));
  }
  if (v.size() != 3 || v[0] == 0 || v[1] == 0)
    throw Error("--samples: '" + text + "' is not R,P,REFINE (R and P at least 1)");
  options.region_samples = v[0];
  options.polygon_samples = v[1];
  options.refine_rays = v[2];
  return options;
}

}  // namespace

void addBuildOptions(CLI::App& sub_app, BuildArgs& build_args) {
  CLI::App* sub = &sub_app;
  BuildArgs* args = &build_args;
  sub->add_option("--tree", args->tree, "Tree kind: pfd, or hfd (hidden fragments rejected by sampled visibility)")
      ->check(CLI::IsMember({"pfd", "hfd"}));
  sub->add_option("--samples", args->samples,
                  "hfd: R,P,REFINE = region samples, polygon samples, refinement rays per visibility test (default " +
                      std::to_string(VisibilityOptions{}.region_samples) + "," +
                      std::to_string(VisibilityOptions{}.polygon_samples) + "," +
                      std::to_string(VisibilityOptions{}.refine_rays) + ")");
  sub->add_option("--visibility-seed", args->visibility_seed, "hfd: seed of the visibility sampling");
  sub->add_option("--visibility", args->visibility_mode,
                  "hfd: sampled (reject what no sampled ray sees) or conservative (reject only what is proved hidden)")
      ->check(CLI::IsMember({"sampled", "conservative"}));
  sub->add_option("--sampled-region-max", args->sampled_region_max,
                  "hfd, sampled: take sampled verdicts only from regions of at most this area, as the side of a square in "
                  "eye heights; larger regions reject only what is proved hidden (0: any region)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--no-fuse-occluders", args->no_fuse_occluders,
                "hfd: the hiddenness proof uses single blockers only, never patches of joined ones (for comparison)");
  sub->add_flag("--keep-back-faces", args->keep_back_faces,
                "List back-facing fragments too (for run-time backface methods); default: dropped at build");
  sub->add_option("--levels", args->levels,
                  "Build only these levels (indices as walkvis info lists them, comma-separated; default: all); "
                  "elsewhere the walkthrough uses the BSP order")
      ->delimiter(',');
  sub->add_option("--max-memory", args->max_memory,
                  "Budget for all trees together (e.g. 512M, 2G; default " + args->max_memory + ")");
  sub->add_option("--cell-memory", args->cell_memory,
                  "A tree over this many bytes is cut into four view cells (default " + args->cell_memory +
                      "; 0: never). PFD levels are planned into cells by an estimate first; an HFD level starts as one cell");
  sub->add_option("--heuristic", args->heuristic, "Which undecided test-line first: balanced or traversal");
  sub->add_option("--object-extent", args->object_extent,
                  "Detail objects: BSP subtrees whose fragments fit in a box of this many eye heights are listed "
                  "whole and ordered at query time by their own planes, never test-lines (0: none; default " +
                      std::to_string(PfdLevelOptions{}.object_extent) + ")");
  sub->add_flag("--no-object-boxes", args->no_object_boxes,
                "HFD: test detail objects by their fragments only, not first by the faces of their bounding box");
  sub->add_flag("--no-dedup", args->no_dedup, "Store every emitted run, not each distinct one once");
  sub->add_option("--share-min", args->share_min,
                  "Orders of at least this many ids are stored as sequences of their sub-orders (less memory, more "
                  "runs per query); 4294967295: flat runs only");
  sub->add_option("--stat-eyes", args->stat_eyes,
                  "Random eyes per tree for tests_mean / tests_max (default " + std::to_string(args->stat_eyes) + ")");
  sub->add_option("--search-lines", args->search_lines,
                  "pfd: optimal choice of the next tests where at most this many lines remain (0: off, also at "
                  "the root)")
      ->check(CLI::Range(0u, kPfdMaxSearchLines));
  sub->add_option("--search-work", args->search_work,
                  "pfd: work one tree may spend on those searches (classes × lines of the regions expanded; ~8 ns each)")
      ->check(CLI::Range(uint64_t{0}, uint64_t{1} << 40));
  sub->add_option("--root-search-lines", args->root_search_lines,
                  "pfd: optimal choice of the whole tree where at most this many lines cross the root region")
      ->check(CLI::Range(0u, kPfdMaxSearchLines));
  sub->add_option("--root-search-work", args->root_search_work,
                  "pfd: work the root's search may spend (its own budget)")
      ->check(CLI::Range(uint64_t{0}, uint64_t{1} << 40));
}

std::unique_ptr<BuildSetup> prepareBuild(const BuildArgs& args, const std::function<void(const std::string&)>& progress) {
  if (args.tree != "pfd" && args.tree != "hfd") throw Error("--tree: expected pfd or hfd, got '" + args.tree + "'");
  auto setup = std::make_unique<BuildSetup>();
  const bool hfd = setup->hfd = args.tree == "hfd";
  if (!hfd && !args.samples.empty()) throw Error("--samples: only for --tree hfd");
  VisibilityOptions vis_options;
  vis_options.seed = args.visibility_seed;
  vis_options = parseSamples(args.samples, vis_options);
  vis_options.fuse_occluders = !args.no_fuse_occluders;
  vis_options.conservative = args.visibility_mode == "conservative";
  PfdLevelOptions& options = setup->options;
  options.tree.drop_back_faces = !args.keep_back_faces;
  options.max_memory = parseSize(args.max_memory, "--max-memory");
  options.cell_memory = parseSize(args.cell_memory, "--cell-memory");
  if (args.heuristic == "balanced") options.tree.heuristic = PfdHeuristic::kBalanced;
  else if (args.heuristic == "traversal") options.tree.heuristic = PfdHeuristic::kTraversal;
  else throw Error("--heuristic: expected balanced or traversal, got '" + args.heuristic + "'");
  options.tree.dedup = !args.no_dedup;
  options.tree.object_boxes = !args.no_object_boxes;
  options.tree.share_min = args.share_min;
  options.tree.stat_eyes = args.stat_eyes;
  options.tree.search_lines = args.search_lines;
  options.tree.search_work = args.search_work;
  options.tree.root_search_lines = args.root_search_lines;
  options.tree.root_search_work = args.root_search_work;
  options.object_extent = args.object_extent;
  if (!(args.object_extent >= 0.0)) throw Error("--object-extent: expected a number >= 0");

  const auto load0 = std::chrono::steady_clock::now();
  setup->scene = loadScene(args.scene.scene, args.scene.loadOptions());
  setup->load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - load0).count();
  const Scene& scene = setup->scene;
  if (args.sampled_region_max > 0.0) {
    const double side = args.sampled_region_max * scene.eye_height;
    vis_options.sampled_max_area = side * side;
  }
  progress("loaded " + scene.name + ": " + std::to_string(scene.polygons.size()) + " polygons, " +
           std::to_string(scene.levels.size()) + " levels");
  std::vector<uint32_t>& only = setup->only;
  only = args.levels;
  std::sort(only.begin(), only.end());
  only.erase(std::unique(only.begin(), only.end()), only.end());
  for (uint32_t l : only) {
    if (l >= scene.levels.size()) {
      throw Error(scene.name + ": --levels names level " + std::to_string(l) + ", but the scene has " +
                       std::to_string(scene.levels.size()) + " (walkvis info lists them)");
    }
  }
  TreeFile& file = setup->file;
  file.eye_height = scene.eye_height;
  file.bsp = buildBsp(scene);
  progress("bsp: " + std::to_string(file.bsp.stats.fragments) + " fragments, " + std::to_string(file.bsp.stats.nodes) +
           " nodes, " + std::to_string(file.bsp.stats.build_seconds) + " s");
  std::optional<VisibilityScene>& visibility = setup->visibility;
  double& visibility_seconds = setup->visibility_seconds;
  if (hfd) {
    const auto v0 = std::chrono::steady_clock::now();
    visibility = VisibilityScene::build(file.bsp, vis_options);
    visibility_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - v0).count();
    options.tree.visibility = &*visibility;
    file.kind = TreeKind::kHfd;
    file.visibility = vis_options;
    progress("visibility scene: " + std::to_string(file.bsp.fragments.size()) + " blockers, samples " +
             std::to_string(vis_options.region_samples) + "," + std::to_string(vis_options.polygon_samples) + "," +
             std::to_string(vis_options.refine_rays) + ", " + std::to_string(visibility_seconds) + " s");
  }
  return setup;
}

}  // namespace walkvis
