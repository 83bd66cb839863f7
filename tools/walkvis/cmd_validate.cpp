// walkvis validate SCENE|FILE [--order bsp|pfd|hfd] [--views N] [--seed S] [--size PIXELS]
//                             [--zbits 16,24,32] [--json] [--diff-dir DIR] [--compare-bsp N]
// Painter's images of a priority order and z-buffer images against exact ray casting, over eyes
// sampled in the walkable regions, six 90° faces each (docs/DESIGN.md, "Validation and statistics").
// On a tree file (walkvis build) the orders are the file's PFD or HFD trees (pfdQuery over the
// view cell under the eye) or its BSP. --compare-bsp checks the tree order against the BSP
// back-to-front order sequence by sequence instead of by images (docs/DESIGN.md,
// "PFD tree": correctness).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bsp/bsp.h"
#include "commands.h"
#include "pfd_hfd/pfd.h"
#include "walkthrough/validate.h"

namespace walkvis {
namespace {

struct ValidateArgs {
  SceneArgs scene;
  std::string order = "bsp";
  int views = 200;
  uint64_t seed = 1;
  int size = 256;
  std::string zbits = "16,24,32";
  double off_plane = 0.25;
  double near = -1.0;
  bool json = false;
  bool quiet = false;
  std::string diff_dir;
  uint32_t compare_bsp = 0;
  int max_print = 10;
};

std::vector<int> parseBits(const std::string& text) {
  std::vector<int> bits;
  if (text.empty() || text == "none") return bits;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item == "16" || item == "24" || item == "32") bits.push_back(std::stoi(item));
    else throw Error("validate: --zbits: '" + item + "' is not 16, 24 or 32");
  }
  return bits;
}

nlohmann::ordered_json countsJson(const PixelCounts& c) {
  return {{"order_error_pixels", c.order_error},
          {"missed_pixels", c.missed},
          {"tie_pixels", c.tie},
          {"edge_pixels", c.edge},
          {"uncovered_pixels", c.uncovered}};
}

// What runValidation needs of a scene, from a tree file: the fragments (bounds, face ids for the
// colours) and one level per tree level whose walkable region is the union of its cells' regions,
// so eyes land at floor_y + eye_height = the trees' height plane.
Scene sceneOfTreeFile(const TreeFile& file, const std::string& path) {
  Scene scene;
  scene.name = path;
  scene.eye_height = file.eye_height;
  scene.vertices = file.bsp.vertices;
  scene.polygons = file.bsp.fragments;
  for (const PfdLevel& level : file.levels) {
    FloorLevel f;
    f.floor_y = level.floor_y;
    for (const PfdTree& t : level.cells) {
      f.walkable.insert(f.walkable.end(), t.region.begin(), t.region.end());
      f.walkable_area += t.stats.region_area;
    }
    scene.levels.push_back(std::move(f));
  }
  return scene;
}

// The tree for an eye on a level's height plane (eyes are sampled exactly at floor_y + eye_height,
// the value buildPfdLevel stores as the level's height), or null.
const PfdTree* treeForEye(const TreeFile& file, const glm::dvec3& eye, int* level_out = nullptr) {
  for (size_t l = 0; l < file.levels.size(); ++l) {
    if (file.levels[l].height != eye.y) continue;
    if (const PfdTree* t = findPfdCell(file.levels[l], eye)) {
      if (level_out) *level_out = static_cast<int>(l);
      return t;
    }
  }
  return nullptr;
}

// Is `sub` a subsequence of `full`? (An HFD order is the BSP order with hidden fragments left out.)
bool isSubsequence(const std::vector<uint32_t>& sub, const std::vector<uint32_t>& full) {
  size_t j = 0;
  for (uint32_t id : full)
    if (j < sub.size() && sub[j] == id) ++j;
  return j == sub.size();
}

// --compare-bsp: per level, N eyes uniform over its cells' regions; the tree order (pfdQuery over
// findPfdCell's tree, and pfdQueryCoherent along the sequence of eyes) against
// backToFront(bsp, eye, order, true). PFD: the sequences must be equal (the build is a partial
// evaluation of that very traversal, so even the order of fragments within one BSP node is the
// same). HFD: the tree order must be a subsequence of the BSP order (hidden fragments dropped,
// nothing added or reordered). Eyes exactly on a test-line are counted and left out (the order is
// defined for eyes off the test-lines).
int runCompare(const ValidateArgs& args, const TreeFile& file, const std::string& path) {
  using Clock = std::chrono::steady_clock;
  const bool hfd = file.kind == TreeKind::kHfd;
  nlohmann::ordered_json j;
  j["file"] = path;
  j["order"] = treeKindName(file.kind);
  j["fragments"] = file.bsp.fragments.size();
  j["eyes_per_level"] = args.compare_bsp;
  j["seed"] = args.seed;
  j["check"] = hfd ? "subsequence of the bsp order" : "equal to the bsp order";
  auto levels = nlohmann::ordered_json::array();
  uint64_t total_eyes = 0, total_compared = 0, total_mismatch = 0, total_coherent_mismatch = 0, total_on_line = 0,
           total_no_cell = 0, printed = 0;
  double total_tests = 0.0, total_bsp_nodes = 0.0;
  std::vector<uint32_t> order, coherent, ref;
  const auto t0 = Clock::now();
  for (size_t l = 0; l < file.levels.size(); ++l) {
    const PfdLevel& level = file.levels[l];
    const double area_sum = pfdLevelArea(level);
    nlohmann::ordered_json lj;
    lj["level"] = level.level;
    lj["height"] = level.height;
    lj["view_cells"] = level.cells.size();
    if (!(area_sum > 0.0)) {
      lj["eyes"] = 0;
      levels.push_back(lj);
      continue;
    }
    uint64_t state = args.seed * 0x9E3779B97F4A7C15ull + l + 1;
    PfdCursor cursor;
    uint64_t compared = 0, mismatch = 0, coherent_mismatch = 0, on_line = 0, no_cell = 0, tests_max = 0;
    double tests = 0.0, object_tests = 0.0, listed = 0.0, bsp_listed = 0.0;
    for (uint32_t e = 0; e < args.compare_bsp; ++e) {
      const glm::dvec3 eye = *samplePfdLevel(level, state);  // area_sum > 0 was checked above
      const PfdTree* tree = findPfdCell(level, eye);
      if (!tree) {
        ++no_cell;
        if (printed++ < static_cast<uint64_t>(args.max_print))
          std::fprintf(stderr, "no view cell holds eye (%.17g, %.17g, %.17g) of level %u\n", eye.x, eye.y, eye.z,
                       level.level);
        continue;
      }
      const PfdQueryResult q = pfdQuery(*tree, eye, order);
      const PfdQueryResult qc = pfdQueryCoherent(*tree, eye, cursor, coherent);
      if (q.on_line || qc.on_line) {
        ++on_line;
        continue;
      }
      backToFront(file.bsp, eye, ref, true);
      ++compared;
      tests += q.tests;
      object_tests += q.object_tests;
      tests_max = std::max<uint64_t>(tests_max, q.tests);
      listed += static_cast<double>(order.size());
      bsp_listed += static_cast<double>(ref.size());
      const bool ok = hfd ? isSubsequence(order, ref) : order == ref;
      const bool ok_coherent = coherent == order;
      if (!ok) ++mismatch;
      if (!ok_coherent) ++coherent_mismatch;
      if ((!ok || !ok_coherent) && printed++ < static_cast<uint64_t>(args.max_print)) {
        size_t first = 0;
        while (first < order.size() && first < ref.size() && order[first] == ref[first]) ++first;
        std::fprintf(stderr,
                     "mismatch: level %u cell %td eye (%.17g, %.17g, %.17g): tree %zu ids, coherent %s, bsp %zu ids, "
                     "first difference at position %zu (tree: fragment %s, bsp: fragment %s)\n",
                     level.level, tree - level.cells.data(), eye.x, eye.y, eye.z, order.size(),
                     ok_coherent ? "same" : "DIFFERENT", ref.size(), first,
                     first < order.size() ? std::to_string(order[first]).c_str() : "none",
                     first < ref.size() ? std::to_string(ref[first]).c_str() : "none");
      }
    }
    lj["eyes"] = args.compare_bsp;
    lj["compared"] = compared;
    lj["on_line"] = on_line;
    lj["no_cell"] = no_cell;
    lj["mismatches"] = mismatch;
    lj["coherent_mismatches"] = coherent_mismatch;
    lj["tests_mean"] = compared ? tests / static_cast<double>(compared) : 0.0;
    lj["tests_max"] = tests_max;
    lj["object_tests_mean"] = compared ? object_tests / static_cast<double>(compared) : 0.0;
    lj["listed_mean"] = compared ? listed / static_cast<double>(compared) : 0.0;
    lj["bsp_listed_mean"] = compared ? bsp_listed / static_cast<double>(compared) : 0.0;
    levels.push_back(lj);
    total_eyes += args.compare_bsp;
    total_compared += compared;
    total_mismatch += mismatch;
    total_coherent_mismatch += coherent_mismatch;
    total_on_line += on_line;
    total_no_cell += no_cell;
    total_tests += tests;
    total_bsp_nodes += static_cast<double>(compared) * static_cast<double>(file.bsp.stats.nodes);
    if (!args.quiet) {
      std::fprintf(stderr, "\rcompare %s: level %zu/%zu, %llu eyes compared, %llu mismatches", path.c_str(), l + 1,
                   file.levels.size(), static_cast<unsigned long long>(total_compared),
                   static_cast<unsigned long long>(total_mismatch + total_coherent_mismatch + total_no_cell));
      if (l + 1 == file.levels.size()) std::fprintf(stderr, "\n");
      std::fflush(stderr);
    }
  }
  j["levels"] = levels;
  j["eyes"] = total_eyes;
  j["compared"] = total_compared;
  j["on_line"] = total_on_line;
  j["no_cell"] = total_no_cell;
  j["mismatches"] = total_mismatch;
  j["coherent_mismatches"] = total_coherent_mismatch;
  j["tests_mean"] = total_compared ? total_tests / static_cast<double>(total_compared) : 0.0;
  j["bsp_nodes"] = file.bsp.stats.nodes;
  j["seconds"] = std::chrono::duration<double>(Clock::now() - t0).count();
  const bool pass = total_mismatch == 0 && total_coherent_mismatch == 0 && total_no_cell == 0;
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("file                %s (%s trees, %zu BSP fragments, %zu levels)\n", path.c_str(), treeKindName(file.kind),
                file.bsp.fragments.size(), file.levels.size());
    std::printf("check               tree order %s at %u random eyes per level\n",
                hfd ? "is a subsequence of the BSP order" : "equals the BSP order", args.compare_bsp);
    std::printf("compared            %llu eyes (%llu on a test-line left out, %llu without a view cell)\n",
                static_cast<unsigned long long>(total_compared), static_cast<unsigned long long>(total_on_line),
                static_cast<unsigned long long>(total_no_cell));
    std::printf("mismatches          %llu (coherent query: %llu)\n", static_cast<unsigned long long>(total_mismatch),
                static_cast<unsigned long long>(total_coherent_mismatch));
    std::printf("tests per query     %.2f mean (BSP traversal: %llu nodes)\n", j["tests_mean"].get<double>(),
                static_cast<unsigned long long>(file.bsp.stats.nodes));
    std::printf("time                %.1f s\n", j["seconds"].get<double>());
    std::printf("result              %s\n", pass ? "PASS" : "FAIL");
  }
  (void)total_bsp_nodes;
  return pass ? 0 : 1;
}

int runValidate(const ValidateArgs& args) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const bool tree_file = isTreeFile(args.scene.scene);
  std::optional<TreeFile> file;
  Scene scene;
  if (tree_file) {
    file = loadTreeFile(args.scene.scene);
    if (args.scene.load.eye_height >= 0.0 && args.scene.load.eye_height != file->eye_height)
      throw Error(args.scene.scene + ": the trees were built for eye height " + std::to_string(file->eye_height) +
                       "; rebuild them for --eye-height " + std::to_string(args.scene.load.eye_height));
    if (args.order != "bsp" && args.order != treeKindName(file->kind))
      throw Error(args.scene.scene + ": holds " + std::string(treeKindName(file->kind)) + " trees, not " + args.order +
                       " (walkvis build --tree " + args.order + ")");
    scene = sceneOfTreeFile(*file, args.scene.scene);
  } else {
    if (args.order != "bsp")
      throw Error("validate: --order " + args.order + " needs a tree file (walkvis build SCENE -o FILE --tree " +
                       args.order + "), not the scene '" + args.scene.scene + "'");
    if (args.compare_bsp > 0) throw Error("validate: --compare-bsp needs a tree file");
    scene = loadScene(args.scene.scene, args.scene.loadOptions());
  }
  const double load_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (args.compare_bsp > 0) {
    if (args.order == "bsp") throw Error("validate: --compare-bsp compares --order pfd or hfd with the BSP");
    return runCompare(args, *file, args.scene.scene);
  }

  ValidationOptions options;
  options.eyes = args.views;
  options.seed = args.seed;
  options.size = args.size;
  options.zbits = parseBits(args.zbits);
  options.near = args.near;
  options.diff_dir = args.diff_dir;
  // Off the height planes only the BSP order is defined (PFD/HFD orders hold on the planes).
  options.off_plane_fraction = args.order == "bsp" ? args.off_plane : 0.0;
  options.eyes_clear_of_near = args.order == "hfd";
  const auto progress_start = Clock::now();
  if (!args.quiet) {
    options.progress = [&](int done, int total, uint64_t errors) {
      const double s = std::chrono::duration<double>(Clock::now() - progress_start).count();
      std::fprintf(stderr, "\rvalidate %s: eye %d/%d, %llu order error pixels, %.1f s", scene.name.c_str(), done,
                   total, static_cast<unsigned long long>(errors), s);
      if (done == total) std::fprintf(stderr, "\n");
      std::fflush(stderr);
    };
  }

  const auto t1 = Clock::now();
  std::optional<BspTree> built;
  if (!file) built = buildBsp(scene);
  const BspTree& tree = file ? file->bsp : *built;
  const double bsp_seconds = file ? 0.0 : std::chrono::duration<double>(Clock::now() - t1).count();
  uint64_t no_tree = 0, on_line = 0;
  OrderProvider order;
  if (args.order == "bsp") {
    order = [&](const glm::dvec3& eye, std::vector<uint32_t>& out) { backToFront(tree, eye, out, true); };
  } else {
    order = [&](const glm::dvec3& eye, std::vector<uint32_t>& out) {
      const PfdTree* t = treeForEye(*file, eye);
      if (!t) {
        ++no_tree;  // shows as uncovered pixels, and fails the run below
        out.clear();
        return;
      }
      if (pfdQuery(*t, eye, out).on_line) ++on_line;
    };
  }
  const ValidationResult r = runValidation(scene, tree.vertices, tree.fragments, order, options);

  nlohmann::ordered_json j;
  j["scene"] = scene.name;
  j["order"] = args.order;
  if (file) j["tree_kind"] = treeKindName(file->kind);
  j["polygons"] = file ? tree.stats.input_polygons : scene.polygons.size();
  j["fragments"] = tree.fragments.size();
  j["nonconvex_fragments"] = r.nonconvex_polygons;
  j["eyes"] = r.eyes;
  j["views"] = r.views;
  j["size"] = args.size;
  j["pixels"] = r.pixels;
  j["exact_pixels"] = r.exact_pixels;
  j["order_error_pixels"] = r.painter.order_error;
  j["missed_pixels"] = r.painter.missed;
  j["tie_pixels"] = r.painter.tie;
  j["edge_pixels"] = r.painter.edge;
  j["uncovered_pixels"] = r.painter.uncovered;
  j["listed_mean"] = r.listed_mean;
  if (args.order != "bsp") {
    j["eyes_without_tree"] = no_tree;
    j["eyes_on_test_line"] = on_line;
  }
  j["tie_tolerance_relative"] = r.tie_tolerance;
  j["edge_margin_pixels"] = kEdgeMarginPixels;
  j["near"] = r.near;
  j["off_plane_eyes"] = static_cast<int>(args.views * options.off_plane_fraction);
  auto zerr = nlohmann::ordered_json::object();
  auto zdetail = nlohmann::ordered_json::object();
  for (const ZBufferResult& z : r.zbuffer) {
    zerr[std::to_string(z.bits)] = z.counts.order_error;
    auto d = countsJson(z.counts);
    d["depth_format"] = z.depth_format;
    d["render_seconds"] = z.render_seconds;
    zdetail[std::to_string(z.bits)] = d;
  }
  j["zbuffer_error_pixels"] = zerr;
  j["zbuffer"] = zdetail;
  auto worst = nlohmann::ordered_json::array();
  for (const ViewReport& v : r.worst_views) {
    nlohmann::ordered_json w{{"eye_index", v.eye_index},
                               {"eye", {v.eye.x, v.eye.y, v.eye.z}},
                               {"face", v.face},
                               {"on_height_plane", v.on_height_plane}};
    const nlohmann::ordered_json counts = countsJson(v.painter);
    for (auto it = counts.begin(); it != counts.end(); ++it) w[it.key()] = it.value();
    auto zv = nlohmann::ordered_json::object();
    for (size_t z = 0; z < v.zbuffer_errors.size(); ++z) zv[std::to_string(r.zbuffer[z].bits)] = v.zbuffer_errors[z];
    w["zbuffer_error_pixels"] = zv;
    worst.push_back(w);
  }
  j["worst_views"] = worst;
  j["diff_images"] = r.diff_images;
  j["gl_renderer"] = r.gl_renderer;
  j["seconds"] = {{"load", load_seconds},
                  {"bsp", bsp_seconds},
                  {"validate", r.seconds},
                  {"order", r.order_seconds},
                  {"render", r.render_seconds},
                  {"raycast", r.raycast_seconds},
                  {"classify", r.classify_seconds}};

  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    auto pct = [&](uint64_t n) { return r.pixels ? 100.0 * static_cast<double>(n) / static_cast<double>(r.pixels) : 0.0; };
    std::printf("scene               %s (%s, %zu BSP fragments)\n", scene.name.c_str(),
                file ? (std::string(treeKindName(file->kind)) + " tree file").c_str()
                     : (std::to_string(scene.polygons.size()) + " polygons").c_str(),
                tree.fragments.size());
    if (r.nonconvex_polygons > 0)
      std::printf("warning             %llu of the drawn polygons are not convex\n",
                  static_cast<unsigned long long>(r.nonconvex_polygons));
    std::printf("views               %llu (%llu eyes x 6 faces, %d x %d, %d off the height planes)\n",
                static_cast<unsigned long long>(r.views), static_cast<unsigned long long>(r.eyes), args.size, args.size,
                static_cast<int>(args.views * options.off_plane_fraction));
    std::printf("pixels              %llu per image kind\n", static_cast<unsigned long long>(r.pixels));
    std::printf("order_error_pixels  %llu (painter's, %s order)\n", static_cast<unsigned long long>(r.painter.order_error),
                args.order.c_str());
    std::printf("missed_pixels       %llu (%.4f%%; nearest polygon not listed; %.1f listed per eye)\n",
                static_cast<unsigned long long>(r.painter.missed), pct(r.painter.missed), r.listed_mean);
    std::printf("tie_pixels          %llu (%.4f%%; tolerance %.0e of the depth)\n",
                static_cast<unsigned long long>(r.painter.tie), pct(r.painter.tie), r.tie_tolerance);
    std::printf("edge_pixels         %llu (%.4f%%; %llu uncovered; edge margin %.4f px)\n",
                static_cast<unsigned long long>(r.painter.edge), pct(r.painter.edge),
                static_cast<unsigned long long>(r.painter.uncovered), kEdgeMarginPixels);
    if (args.order != "bsp")
      std::printf("eyes                %llu without a tree, %llu on a test-line\n",
                  static_cast<unsigned long long>(no_tree), static_cast<unsigned long long>(on_line));
    for (const ZBufferResult& z : r.zbuffer)
      std::printf("zbuffer %2d bits     %llu error pixels, %llu tie, %llu edge (%s)\n", z.bits,
                  static_cast<unsigned long long>(z.counts.order_error), static_cast<unsigned long long>(z.counts.tie),
                  static_cast<unsigned long long>(z.counts.edge), z.depth_format.c_str());
    for (const ViewReport& v : r.worst_views)
      std::printf("worst view          eye %d (%.3f, %.3f, %.3f) face %d: %llu order errors, %llu missed, %llu edge\n",
                  v.eye_index, v.eye.x, v.eye.y, v.eye.z, v.face, static_cast<unsigned long long>(v.painter.order_error),
                  static_cast<unsigned long long>(v.painter.missed), static_cast<unsigned long long>(v.painter.edge));
    if (!args.diff_dir.empty())
      std::printf("diff images         %llu in %s\n", static_cast<unsigned long long>(r.diff_images), args.diff_dir.c_str());
    std::printf("time                %.1f s (bsp %.1f, render %.1f, raycast %.1f, classify %.1f)\n", r.seconds, bsp_seconds,
                r.render_seconds, r.raycast_seconds, r.classify_seconds);
  }
  // Missed pixels fail only orders that must list every front-facing polygon (bsp, pfd); for hfd
  // they are the measured approximation (walkvis stats).
  const bool missed_fails = args.order != "hfd" && r.painter.missed > 0;
  return r.painter.order_error == 0 && !missed_fails && no_tree == 0 ? 0 : 1;
}

}  // namespace

void addValidateCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<ValidateArgs>();
  auto* sub = app.add_subcommand(
      "validate",
      "Painter's order and z-buffer images against exact ray casting.\n"
      "Pixel classes of the painter's image (walkthrough/validate.h): order_error_pixels = the shown polygon\n"
      "is behind a LISTED polygon that solidly covers the pixel (an order error among listed polygons);\n"
      "missed_pixels = the exact nearest polygon is not in the order at all (HFD rejected a visible\n"
      "polygon; zero for bsp and pfd unless they are wrong); tie_pixels = nearest hits within 1e-6 of the\n"
      "depth; edge_pixels = coverage differences at edges and silhouettes (uncovered included).\n"
      "Exit status 1 on any order error (and, for bsp/pfd, any missed pixel).");
  addSceneArgs(*sub, args->scene);
  sub->get_option("scene")->description(
      "Scene (model.obj, freedoom2.wad:MAP07, gen:office...) for --order bsp, or a tree file from walkvis build "
      "for any order");
  sub->add_option("--order", args->order,
                  "Priority order to validate: bsp (a scene or a tree file's BSP), pfd or hfd (a tree file's trees: "
                  "eyes on each level's height plane, the order of the view cell under the eye)")
      ->check(CLI::IsMember({"bsp", "pfd", "hfd"}));
  sub->add_option("--views", args->views, "Eyes to sample (6 cube faces each)")->check(CLI::Range(1, 1000000));
  sub->add_option("--seed", args->seed, "Seed of the eye sampling");
  sub->add_option("--size", args->size, "Pixels per side of a cube face")->check(CLI::Range(8, 4096));
  sub->add_option("--zbits", args->zbits, "Z-buffer depth precisions to test: any of 16,24,32, or none");
  sub->add_option("--off-plane", args->off_plane,
                  "Fraction of eyes off the height planes (random y within the bounds; BSP order only)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--near", args->near, "Near plane distance (default: 0.05 x eye height)");
  sub->add_option("--compare-bsp", args->compare_bsp,
                  "Instead of images: N random eyes per level, the tree order against backToFront(bsp, eye, "
                  "skip back faces): pfd must be equal, hfd a subsequence; mismatches on stderr")
      ->check(CLI::Range(1u, 100000000u));
  sub->add_option("--max-print", args->max_print, "Mismatches printed by --compare-bsp")->check(CLI::Range(0, 1000000));
  sub->add_flag("--json", args->json, "Print one JSON object");
  sub->add_flag("--quiet", args->quiet, "No progress on stderr");
  sub->add_option("--diff-dir", args->diff_dir,
                  "Write PNGs of views with order errors, missed pixels or z-buffer errors (red: order error, orange: "
                  "missed, cyan: tie, yellow: edge, magenta: uncovered), at most 200");
  sub->callback([&runner, args] { runner = [args] { return runValidate(*args); }; });
}

}  // namespace walkvis
