// walkvis bench backface [--mesh SCENE ...] [--lists WAD:MAP] [--eyes K] [--runs K] [--only ROW,...] [--json]: every
// backface method of backface/ and meshoptimizer's meshlet cone culling on the same meshes and the same eyes
// (--only: just the named rows; the lists table always runs none, for its over_none column). --tr 0 (default):
// cluster's T/R from the polygon count (clusterTrFor).
//
// Eyes: uniformly random directions at 1.5–4 bounding radii from the centre of the mesh's box,
// looking at the centre with a 60° cone (Johannsen & Carter measure from a sphere around the
// model). Per mesh and method: culled_ratio (culled / polygons), effectiveness (culled /
// back-facing), ns_per_polygon (time of the per-frame cull step over all eyes divided by eyes ×
// polygons; median over --runs; the unit → polygon expansion is not timed), bytes_per_polygon
// (per-frame test state / polygons) and false_culls (front faces culled, summed over the eyes:
// must be 0 for our methods; cluster is the flat SIMD pass over every cluster, cluster-tree the §2.3
// hierarchy), of which false_culls_zero_area are of polygons meshoptimizer sees
// no area in (coneInvisiblePolygons: the cone peer culls those by design; they have no pixels).
// Exit status 1 when any of our methods culls a front face.
// hierarchy (Kumar et al.) tracks the eye from frame to frame, so it is timed twice: on the eyes in
// their random order (every frame a jump: full tests) and as hierarchy-tour, the same eyes in the
// order of a greedy nearest-neighbour tour (same culled figures, coherent motion).
//
// Meshes: --mesh (any scene: OBJ, glTF, gen:...), plus the Stanford bunny when scripts/fetch-bunny
// has fetched it (--bunny PATH, --no-bunny; a note says when it is skipped).
// --lists WAD:MAP (default freedoom2.wad:MAP01; "" for none): the level of the start eye built as
// PFD trees with drop_back_faces = false; every run of every tree is a range of a ListCuller
// (backface/list_cull.h) per method none/polygon/mask/mask-groups/cluster/hierarchy/region, and
// meshoptimizer cones built per run; random eyes on the height plane; per eye the runs of its query
// are culled in order (timed: one cullRanges call over the query's run ids with the order written
// out, as a frame does; none too; cone: cull, expansion and order). Figures are per listed
// polygon; over_none is ns/poly minus none's (the same call writing the runs out unculled), the
// cost the culling adds. mask is Zhang & Hoff's mask from each eye's view cone (60 degrees here),
// one per query; it may also drop front faces wholly outside the cone (no pixels in a frustum the
// cone holds): those are counted apart (culled_outside_view, a line under the row), not as false
// culls nor in culled_ratio and effectiveness. mask-groups and mask-tables are the per-group
// sphere cones (conservative for every polygon): a table on chunks of at least
// mask_list_min_chunk positions and the plane test on smaller ones (nearly every PFD run; a line
// under each row says what share of the pool a table culls); mask-tables builds a table for every
// run. Then the BSP path: every fragment of the level's BSP
// with eyes anywhere in the scene's box, the same table as for meshes, its cluster rows clustered
// for eyes in that box and cluster-paper with the paper's near field around each cluster.
// Any scene with floor levels works for --lists (e.g. gen:office: eyes inside a building). Each table ends with the
// target line (docs/DESIGN.md, "Targets"): cluster effectiveness >= cone's at no more ns per
// polygon (JSON: cluster_vs_cone). --subdivision adds Möller & Séquin's culled Loop subdivision of
// the animated blob (backface/subdivision.h) at 1..3 levels: triangles computed over the levels
// (full / culled), the final level's, and the time per frame, over --eyes random eyes at 2–10 radii
// and times. With --json the output is then {"meshes": [...], "subdivision": [...]}.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "backface/backface.h"
#include "backface/list_cull.h"
#include "backface/subdivision.h"
#include "bsp/bsp.h"
#include "pfd_hfd/pfd.h"
#include "commands.h"

namespace walkvis {
namespace {

struct BackfaceBenchArgs {
  std::vector<std::string> meshes{"gen:sphere", "gen:sphere?tris=70000", "gen:dome"};
  int eyes = 200;
  int runs = 5;
  uint64_t seed = 1;
  double tr = 0.0;  // 0: clusterTrFor's choice from the polygon count
  int mask_resolution = 0;
  uint32_t mask_group = 256;
  bool json = false;
  bool subdivision = false;
  int subdivision_refine = 2;
  std::string bunny;     // empty: the cache path of scripts/fetch-bunny
  bool no_bunny = false;
  std::string lists = "freedoom2.wad:MAP01";  // empty: no priority lists
  std::vector<std::string> only;  // row labels to run; empty: all
};

bool rowSelected(const BackfaceBenchArgs& args, const std::string& label) {
  return args.only.empty() || std::find(args.only.begin(), args.only.end(), label) != args.only.end();
}

struct Variant {
  std::string label;
  BackfaceMethod method;
  BackfaceOptions options;
  bool tour = false;  // eyes in nearest-neighbour tour order
};

// eye_box: where the eyes are, when they are inside the scene (the BSP path): cluster then
// clusters by the culling probability over that box, and cluster-paper shows the paper's box
// around each cluster's origin (backface.h, cluster_eye_lo).
std::vector<Variant> variants(const BackfaceBenchArgs& args, const Bounds* eye_box) {
  BackfaceOptions base;
  base.mask_resolution = args.mask_resolution;
  base.cluster_tr = args.tr;
  std::vector<Variant> out;
  if (eye_box) {
    out.push_back({"cluster-paper", BackfaceMethod::kCluster, base});
    base.cluster_eye_lo = eye_box->lo;
    base.cluster_eye_hi = eye_box->hi;
  }
  out.push_back({"polygon", BackfaceMethod::kPolygon, base});
  out.push_back({"mask", BackfaceMethod::kMask, base});
  BackfaceOptions grouped = base;
  grouped.mask_group_size = args.mask_group;
  out.push_back({"mask-groups", BackfaceMethod::kMask, grouped});
  out.push_back({"cluster", BackfaceMethod::kCluster, base});
  BackfaceOptions tree = base;
  tree.cluster_hierarchy = true;
  out.push_back({"cluster-tree", BackfaceMethod::kCluster, tree});
  out.push_back({"cone", BackfaceMethod::kCone, base});
  out.push_back({"hierarchy", BackfaceMethod::kHierarchy, base});
  out.push_back({"hierarchy-tour", BackfaceMethod::kHierarchy, base, true});
  return out;
}

double medianOf(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.empty() ? 0.0 : (v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]));
}

// The same views, reordered into a greedy nearest-neighbour tour from the first.
std::vector<BackfaceView> tourOrder(const std::vector<BackfaceView>& views) {
  std::vector<BackfaceView> out;
  std::vector<uint8_t> used(views.size(), 0);
  size_t at = 0;
  for (size_t k = 0; k < views.size(); ++k) {
    used[at] = 1;
    out.push_back(views[at]);
    double best = INFINITY;
    size_t next = at;
    for (size_t j = 0; j < views.size(); ++j) {
      const double dist = glm::length(views[j].eye - views[at].eye);
      if (!used[j] && dist < best) {
        best = dist;
        next = j;
      }
    }
    at = next;
  }
  return out;
}

nlohmann::ordered_json runSubdivisionBench(const BackfaceBenchArgs& args) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  const ControlMesh shape = animatedBlob(0.0, args.subdivision_refine);
  const LoopTopology topology(shape.triangles, shape.positions.size(), 3);
  std::mt19937_64 rng(args.seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<ControlMesh> meshes;
  std::vector<glm::dvec3> eyes;
  for (int e = 0; e < args.eyes; ++e) {
    meshes.push_back(animatedBlob(20.0 * u(rng), args.subdivision_refine));
    eyes.push_back((2.0 + 8.0 * u(rng)) * glm::normalize(glm::dvec3(g(rng), g(rng), g(rng))));
  }
  if (!args.json) {
    std::printf("subdivision: animated blob, %zu control triangles, %d eyes at 2-10 radii\n", shape.triangles.size(),
                args.eyes);
    std::printf("  %6s %12s %12s %7s %11s %11s %7s %10s %10s\n", "levels", "computed", "culled", "fewer%",
                "last_full", "last_culled", "fewer%", "ms_full", "ms_culled");
  }
  for (int levels = 1; levels <= 3; ++levels) {
    double computed[2] = {0, 0}, last[2] = {0, 0}, ms[2] = {0, 0};
    for (int mode = 0; mode < 2; ++mode) {
      std::vector<double> times;
      for (int r = 0; r < args.runs; ++r) {
        double c = 0, lst = 0;
        const auto t0 = std::chrono::steady_clock::now();
        for (size_t e = 0; e < eyes.size(); ++e) {
          const SubdivisionResult res = subdivide(topology, meshes[e].positions, levels, eyes[e], mode == 1);
          for (int l = 1; l <= levels; ++l) c += static_cast<double>(res.triangles_computed[static_cast<size_t>(l)]);
          lst += static_cast<double>(res.triangles_computed[static_cast<size_t>(levels)]);
        }
        times.push_back(1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() /
                        static_cast<double>(eyes.size()));
        computed[mode] = c / static_cast<double>(eyes.size());
        last[mode] = lst / static_cast<double>(eyes.size());
      }
      ms[mode] = medianOf(times);
    }
    const double fewer = 1.0 - computed[1] / computed[0], fewer_last = 1.0 - last[1] / last[0];
    out.push_back({{"levels", levels},
                   {"triangles_computed_full", computed[0]},
                   {"triangles_computed_culled", computed[1]},
                   {"fewer_ratio", fewer},
                   {"final_level_full", last[0]},
                   {"final_level_culled", last[1]},
                   {"final_level_fewer_ratio", fewer_last},
                   {"ms_per_frame_full", ms[0]},
                   {"ms_per_frame_culled", ms[1]}});
    if (!args.json) {
      std::printf("  %6d %12.1f %12.1f %7.1f %11.1f %11.1f %7.1f %10.4f %10.4f\n", levels, computed[0], computed[1],
                  100.0 * fewer, last[0], last[1], 100.0 * fewer_last, ms[0], ms[1]);
    }
  }
  return out;
}

// meshoptimizer's false culls of zero-area polygons are its documented handling of degenerate
// triangles (meshlet_cone.cpp), not a rounding error of the cone test: say so under the table.
void printZeroAreaNote(uint64_t count) {
  std::printf("  note: %llu of cone's false culls are of polygons with no area at float precision (meshoptimizer\n"
              "        rejects meshlets of zero-area triangles; a sliver's float normal is rounding noise); no pixels\n",
              static_cast<unsigned long long>(count));
}

// Every variant on one polygon set and one list of eyes; appends the JSON rows to `methods`.
nlohmann::ordered_json benchInput(const std::string& label, const BackfaceInput& input, uint64_t triangles,
                                  const std::vector<BackfaceView>& views, const BackfaceBenchArgs& args, bool& ok,
                                  const Bounds* eye_box = nullptr) {
  const size_t n = input.polygons.size();
  if (n == 0) throw Error(label + ": no polygons to cull");
  const std::vector<BackfaceView> tour_views = tourOrder(views);
  uint64_t back_total = 0;
  for (const BackfaceView& v : views) {
    for (const Polygon& p : input.polygons) back_total += !isFrontFacing(p.plane, v.eye);
  }
  nlohmann::ordered_json mesh;
  mesh["mesh"] = label;
  mesh["polygons"] = n;
  mesh["triangles"] = triangles;
  mesh["back_facing_ratio"] = static_cast<double>(back_total) / (static_cast<double>(n) * views.size());
  nlohmann::ordered_json methods = nlohmann::ordered_json::array();
  if (!args.json) {
    std::printf("%s: %zu polygons, %.1f%% back-facing over %zu eyes\n", label.c_str(), n,
                100.0 * mesh["back_facing_ratio"].get<double>(), views.size());
    std::printf("  timed per frame, same for all: cull() into unit flags (mask: the view-cone table(s) and the\n"
                "  lookups; cluster: every cluster test; cone: every meshlet test); unit->polygon expansion untimed\n");
    std::printf("  %-13s %8s %8s %9s %8s %8s %7s %9s\n", "method", "culled%", "effect%", "ns/poly", "B/poly", "units",
                "false", "build_s");
  }
  uint64_t zero_area_note = 0;
  // Polygons meshoptimizer sees no area in (coneInvisiblePolygons): a cone cull of one is the
  // library's trivial reject of an invisible meshlet, counted apart.
  std::vector<uint8_t> invisible(n);
  coneInvisiblePolygons(input, invisible);
  for (const Variant& variant : variants(args, eye_box)) {
    if (!rowSelected(args, variant.label)) continue;
    const auto t0 = std::chrono::steady_clock::now();
    const auto culler = makeBackfaceCuller(variant.method, input, variant.options);
    const double build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::vector<uint8_t> units(culler->unitCount()), culled(n);
    uint64_t culled_total = 0, false_culls = 0, false_invisible = 0;
    const std::vector<BackfaceView>& eyes = variant.tour ? tour_views : views;
    for (const BackfaceView& v : eyes) {
      culler->cull(v, units);
      expandToPolygons(*culler, units, culled);
      for (size_t p = 0; p < n; ++p) {
        culled_total += culled[p];
        const bool wrong = culled[p] && isFrontFacing(input.polygons[p].plane, v.eye);
        false_culls += wrong;
        false_invisible += wrong && invisible[p];
      }
    }
    std::vector<double> ns;
    uint64_t sink = 0;
    for (int r = 0; r < args.runs; ++r) {
      const auto t1 = std::chrono::steady_clock::now();
      for (const BackfaceView& v : eyes) {
        culler->cull(v, units);
        sink += units.empty() ? 0 : units[0];
      }
      const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      ns.push_back(1e9 * sec / (static_cast<double>(views.size()) * static_cast<double>(n)));
    }
    if (sink == uint64_t(-1)) std::printf(" ");  // keeps the timed loop's results alive
    const double culled_ratio = static_cast<double>(culled_total) / (static_cast<double>(n) * views.size());
    const double effectiveness = back_total ? static_cast<double>(culled_total) / static_cast<double>(back_total) : 0.0;
    const double ns_per_polygon = medianOf(ns);
    const double bytes_per_polygon = static_cast<double>(culler->stateBytes()) / static_cast<double>(n);
    if (variant.method != BackfaceMethod::kCone && false_culls > 0) ok = false;
    methods.push_back({{"method", variant.label},
                       {"culled_ratio", culled_ratio},
                       {"effectiveness", effectiveness},
                       {"ns_per_polygon", ns_per_polygon},
                       {"bytes_per_polygon", bytes_per_polygon},
                       {"false_culls", false_culls},
                       {"false_culls_zero_area", false_invisible},
                       {"units", culler->unitCount()},
                       {"build_seconds", build_seconds}});
    if (!args.json) {
      std::printf("  %-13s %8.1f %8.1f %9.3f %8.2f %8zu %7llu %9.3f\n", variant.label.c_str(), 100.0 * culled_ratio,
                  100.0 * effectiveness, ns_per_polygon, bytes_per_polygon, culler->unitCount(),
                  static_cast<unsigned long long>(false_culls), build_seconds);
    }
    if (variant.method == BackfaceMethod::kCone) zero_area_note = std::max(zero_area_note, false_invisible);
  }
  if (!args.json && zero_area_note > 0) printZeroAreaNote(zero_area_note);
  mesh["methods"] = methods;
  return mesh;
}

// The target (docs/DESIGN.md, "Targets"): the clustered test's effectiveness at least the cone's,
// at no more cost per polygon. Adds "cluster_vs_cone" to the mesh and prints a line.
void checkClusterVsCone(nlohmann::ordered_json& mesh, bool json) {
  const nlohmann::ordered_json* cluster = nullptr;
  const nlohmann::ordered_json* cone = nullptr;
  for (const auto& m : mesh["methods"]) {
    if (m["method"] == "cluster") cluster = &m;
    if (m["method"] == "cone") cone = &m;
  }
  if (!cluster || !cone) return;
  const double ce = (*cluster)["effectiveness"], ke = (*cone)["effectiveness"];
  const double cn = (*cluster)["ns_per_polygon"], kn = (*cone)["ns_per_polygon"];
  const bool eff_ok = ce >= ke, cost_ok = cn <= kn;
  mesh["cluster_vs_cone"] = {{"effectiveness_met", eff_ok}, {"cost_met", cost_ok}};
  if (!json) {
    std::printf("  target cluster >= cone effectiveness (%.1f%% vs %.1f%%): %s; cost <= cone's (%.3f vs %.3f ns/poly): %s\n",
                100.0 * ce, 100.0 * ke, eff_ok ? "met" : "NOT met", cn, kn, cost_ok ? "met" : "NOT met");
  }
}

// Eyes around a mesh: uniformly random directions at 1.5–4 bounding radii from the box centre,
// looking at the centre with a 60° cone.
std::vector<BackfaceView> eyesAround(const Bounds& b, int count, uint64_t seed) {
  const glm::dvec3 center = 0.5 * (b.lo + b.hi);
  const double radius = std::max(0.5 * glm::length(b.hi - b.lo), 1e-9);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(1.5, 4.0);
  std::vector<BackfaceView> views(static_cast<size_t>(count));
  for (BackfaceView& v : views) {
    glm::dvec3 dir(g(rng), g(rng), g(rng));
    dir = glm::normalize(dir);
    v.eye = center + u(rng) * radius * dir;
    v.view_dir = -dir;
    v.fov = M_PI / 3.0;
  }
  return views;
}

std::string defaultBunnyPath() {
  if (const char* data = std::getenv("WALKVIS_DATA")) return std::string(data) + "/bunny.obj";
  if (const char* cache = std::getenv("XDG_CACHE_HOME")) return std::string(cache) + "/walkvis/bunny.obj";
  if (const char* home = std::getenv("HOME")) return std::string(home) + "/.cache/walkvis/bunny.obj";
  return "";
}

struct ListRow {
  std::string label;
  ListCullMethod method = ListCullMethod::kNone;
  bool cone = false;  // meshoptimizer cones per run instead (not a ListCuller method)
  BackfaceOptions options;
};

// Priority lists of a WAD level: the start eye's level built as PFD trees with drop_back_faces =
// false; every run of every tree is a range; the eyes are random points of the level's region on
// its height plane; per eye the runs pfdQueryRuns yields are culled in order. Then the BSP path:
// all fragments, eyes anywhere in the level's box (off the height plane).
std::vector<nlohmann::ordered_json> benchLists(const std::string& spec, const BackfaceBenchArgs& args, bool& ok) {
  std::vector<nlohmann::ordered_json> out;
  const Scene scene = loadScene(spec);
  if (scene.levels.empty()) throw Error(spec + ": no floor levels to build priority lists on");
  size_t level = 0;
  for (size_t l = 0; l < scene.levels.size(); ++l) {
    const double dy = std::abs(scene.levels[l].floor_y + scene.eye_height - scene.start_eye.y);
    if (dy < std::abs(scene.levels[level].floor_y + scene.eye_height - scene.start_eye.y)) level = l;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const BspTree bsp = buildBsp(scene);
  PfdLevelOptions options;
  options.tree.drop_back_faces = false;
  options.tree.stat_eyes = 0;
  uint64_t used = 0;
  const PfdLevel trees = buildPfdLevel(bsp, scene.levels[level], static_cast<uint32_t>(level), scene.eye_height, options, used);
  const double tree_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const BackfaceInput input{bsp.vertices, bsp.fragments};

  // Ranges per tree (its runs) and, per eye, the ranges its query yields.
  std::vector<std::vector<IndexRange>> ranges(trees.cells.size());
  uint64_t pool = 0;
  for (size_t t = 0; t < trees.cells.size(); ++t) {
    // Range r is run r of the tree, so a query's run indices are range indices.
    for (const PfdRun& run : trees.cells[t].runs) ranges[t].push_back({run.first, run.count});
    pool += trees.cells[t].fragment_ids.size();
  }
  struct Eye {
    BackfaceView view;
    uint32_t tree = 0;
    std::vector<uint32_t> ranges;
  };
  std::vector<Eye> eyes;
  uint64_t rng_state = args.seed;
  std::mt19937_64 rng(args.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  uint64_t listed = 0, back_total = 0, max_listed = 0;
  for (int e = 0; e < args.eyes; ++e) {
    const std::optional<glm::dvec3> at = samplePfdLevel(trees, rng_state);
    if (!at) break;  // the level has no region area
    const PfdTree* found = findPfdCell(trees, *at);
    if (!found) continue;  // exactly on the outer upper side of the cells
    const PfdTree& tree = *found;
    Eye eye;
    eye.tree = static_cast<uint32_t>(found - trees.cells.data());
    eye.view.eye = *at;
    const double yaw = 2.0 * M_PI * u(rng);
    eye.view.view_dir = glm::dvec3(std::cos(yaw), 0.0, std::sin(yaw));
    eye.view.fov = M_PI / 3.0;
    pfdQueryRunIds(tree, eye.view.eye, eye.ranges);
    uint64_t eye_listed = 0;
    for (uint32_t r : eye.ranges) eye_listed += tree.runs[r].count;
    max_listed = std::max(max_listed, eye_listed);
    for (uint32_t r : eye.ranges) {
      const PfdRun& run = tree.runs[r];
      listed += run.count;
      for (uint32_t k = 0; k < run.count; ++k) {
        back_total += !isFrontFacing(bsp.fragments[tree.fragment_ids[run.first + k]].plane, eye.view.eye);
      }
    }
    eyes.push_back(std::move(eye));
  }
  if (listed == 0) throw Error(spec + ": the priority lists of level " + std::to_string(level) + " are empty");

  nlohmann::ordered_json lists;
  lists["mesh"] = spec + " pfd lists (level " + std::to_string(level) + ")";
  lists["polygons"] = pool;
  lists["trees"] = trees.cells.size();
  lists["runs"] = [&] {
    size_t r = 0;
    for (const auto& v : ranges) r += v.size();
    return r;
  }();
  lists["listed_per_eye"] = static_cast<double>(listed) / static_cast<double>(eyes.size());
  lists["back_facing_ratio"] = static_cast<double>(back_total) / static_cast<double>(listed);
  lists["tree_build_seconds"] = tree_seconds;
  if (!args.json) {
    std::printf("%s: %zu trees, %llu runs, %.1f listed per eye, %.1f%% of them back-facing, %zu eyes (BSP+trees %.1f s)\n",
                lists["mesh"].get<std::string>().c_str(), trees.cells.size(),
                static_cast<unsigned long long>(lists["runs"].get<uint64_t>()), lists["listed_per_eye"].get<double>(),
                100.0 * lists["back_facing_ratio"].get<double>(), eyes.size(), tree_seconds);
    // over_none: ns/poly minus none's (which writes the same runs out unculled), i.e. what the
    // culling adds to a frame's list walk; the runs average a few polygons, so the walk itself
    // (a call and an append per run) is a floor no method can go below.
    std::printf("  %-13s %8s %8s %9s %8s %9s %7s %9s\n", "method", "culled%", "effect%", "ns/poly", "B/poly", "over_none",
                "false", "build_s");
  }
  BackfaceOptions base;
  base.mask_resolution = args.mask_resolution;
  base.cluster_tr = args.tr;
  BackfaceOptions chunked = base;
  chunked.mask_cone = BackfaceOptions::MaskCone::kGroups;
  chunked.mask_group_size = args.mask_group;
  std::vector<ListRow> rows;
  for (ListCullMethod m : {ListCullMethod::kNone, ListCullMethod::kPolygon, ListCullMethod::kMask, ListCullMethod::kCluster,
                           ListCullMethod::kHierarchy, ListCullMethod::kRegion}) {
    rows.push_back({std::string(listCullMethodName(m)), m, false, base});
  }
  rows.insert(rows.begin() + 3, ListRow{"mask-groups", ListCullMethod::kMask, false, chunked});
  // mask is Zhang & Hoff's mask from the view cone (the default in lists); mask-groups and
  // mask-tables the per-group sphere cones (kGroups), conservative for every polygon:
  // mask-tables with a table for every chunk however small (kGroups uses the plane test on
  // chunks under mask_list_min_chunk positions, where a table cannot pay; list_cull.cpp).
  BackfaceOptions tables = base;
  tables.mask_cone = BackfaceOptions::MaskCone::kGroups;
  tables.mask_list_min_chunk = 1;
  rows.insert(rows.begin() + 4, ListRow{"mask-tables", ListCullMethod::kMask, false, tables});
  rows.push_back({"cone", ListCullMethod::kNone, true, base});

  nlohmann::ordered_json methods = nlohmann::ordered_json::array();
  std::vector<uint32_t> order;
  order.reserve(max_listed + kListCullOutSlack);  // cullRanges allocates nothing then
  double none_ns = NAN;  // none's ns per polygon (first row), for over_none
  for (const ListRow& row : rows) {
    if (!rowSelected(args, row.label) && row.label != "none") continue;
    const auto t1 = std::chrono::steady_clock::now();
    std::vector<ListCuller> cullers;
    // cone: one meshoptimizer culler per run, over the run's own vertices.
    std::vector<std::vector<std::unique_ptr<BackfaceCuller>>> cones(trees.cells.size());
    std::vector<std::vector<std::vector<uint8_t>>> cone_invisible(trees.cells.size());  // per run, per position
    size_t max_units = 1, max_count = 1;
    uint64_t bytes = 0;
    for (size_t t = 0; t < trees.cells.size(); ++t) {
      const PfdTree& tree = trees.cells[t];
      if (!row.cone) {
        cullers.push_back(ListCuller::build(input, tree.fragment_ids, ranges[t], row.method, row.options));
        bytes += cullers.back().bytes();
        continue;
      }
      std::vector<Polygon> local;
      std::vector<glm::dvec3> local_vertices;
      for (const IndexRange& r : ranges[t]) {
        local.clear();
        local_vertices.clear();
        for (uint32_t k = 0; k < r.count; ++k) {
          Polygon poly = bsp.fragments[tree.fragment_ids[r.first + k]];
          const auto v = bsp.fragmentVertices(tree.fragment_ids[r.first + k]);
          poly.first_vertex = static_cast<uint32_t>(local_vertices.size());
          local_vertices.insert(local_vertices.end(), v.begin(), v.end());
          local.push_back(poly);
        }
        cones[t].push_back(makeBackfaceCuller(BackfaceMethod::kCone, BackfaceInput{local_vertices, local}, row.options));
        cone_invisible[t].emplace_back(local.size());
        coneInvisiblePolygons(BackfaceInput{local_vertices, local}, cone_invisible[t].back());
        bytes += cones[t].back()->stateBytes();
        max_units = std::max(max_units, cones[t].back()->unitCount());
        max_count = std::max<size_t>(max_count, r.count);
      }
    }
    const double build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    uint64_t table_positions = 0;  // mask: positions a Zhang & Hoff table culls (the rest: plane test)
    for (const ListCuller& c : cullers) table_positions += c.maskTablePositions();
    std::vector<uint8_t> unit_flags(max_units), poly_flags(max_count);
    // Culls one eye's lists into `order`; returns the number culled.
    auto cullEye = [&](const Eye& eye) {
      order.clear();
      uint64_t culled = 0;
      const PfdTree& tree = trees.cells[eye.tree];
      // What a frame does (walkthrough/frame.cpp): one cullRanges call over the query's runs.
      if (!row.cone) return static_cast<uint64_t>(cullers[eye.tree].cullRanges(eye.ranges, eye.view, order));
      for (uint32_t r : eye.ranges) {
        const BackfaceCuller& c = *cones[eye.tree][r];
        const IndexRange& range = ranges[eye.tree][r];
        c.cull(eye.view, std::span<uint8_t>(unit_flags.data(), c.unitCount()));
        expandToPolygons(c, std::span<const uint8_t>(unit_flags.data(), c.unitCount()),
                         std::span<uint8_t>(poly_flags.data(), range.count));
        for (uint32_t k = 0; k < range.count; ++k) {
          if (!poly_flags[k]) order.push_back(tree.fragment_ids[range.first + k]);
          culled += poly_flags[k];
        }
      }
      return culled;
    };
    // The view-cone mask may cull front faces wholly outside the view cone (list_cull.h): those
    // whose unit normal n̂ has n̂·a > sin θ (their front half-space misses the cone) are counted as
    // culled_outside_view, not as false culls, and not in the effectiveness (back faces culled).
    const bool view_mask = row.method == ListCullMethod::kMask && !row.cone &&
                           row.options.mask_cone != BackfaceOptions::MaskCone::kGroups;
    uint64_t culled_total = 0, false_culls = 0, front_kept = 0, false_invisible = 0, outside_view = 0;
    for (const Eye& eye : eyes) {
      culled_total += cullEye(eye);
      if (row.cone) {  // which culled front faces the library sees no area in
        const PfdTree& tree = trees.cells[eye.tree];
        for (uint32_t r : eye.ranges) {
          const BackfaceCuller& c = *cones[eye.tree][r];
          const IndexRange& range = ranges[eye.tree][r];
          c.cull(eye.view, std::span<uint8_t>(unit_flags.data(), c.unitCount()));
          expandToPolygons(c, std::span<const uint8_t>(unit_flags.data(), c.unitCount()),
                           std::span<uint8_t>(poly_flags.data(), range.count));
          for (uint32_t k = 0; k < range.count; ++k) {
            false_invisible += poly_flags[k] && cone_invisible[eye.tree][r][k] &&
                               isFrontFacing(bsp.fragments[tree.fragment_ids[range.first + k]].plane, eye.view.eye);
          }
        }
      }
      // Front faces listed minus front faces kept = front faces culled.
      uint64_t front_listed = 0;
      const PfdTree& tree = trees.cells[eye.tree];
      for (uint32_t r : eye.ranges) {
        const IndexRange& range = ranges[eye.tree][r];
        for (uint32_t k = 0; k < range.count; ++k) {
          front_listed += isFrontFacing(bsp.fragments[tree.fragment_ids[range.first + k]].plane, eye.view.eye);
        }
      }
      front_kept = 0;
      for (uint32_t f : order) front_kept += isFrontFacing(bsp.fragments[f].plane, eye.view.eye);
      uint64_t front_culled = front_listed - front_kept;
      if (view_mask && front_culled > 0) {
        // Which front faces went: the survivors are an in-order subsequence of the runs.
        const glm::dvec3 axis = glm::normalize(eye.view.view_dir);
        const double sin_half = std::sin(0.5 * eye.view.fov);
        size_t at = 0;
        for (uint32_t r : eye.ranges) {
          const IndexRange& range = ranges[eye.tree][r];
          for (uint32_t k = 0; k < range.count; ++k) {
            const uint32_t f = tree.fragment_ids[range.first + k];
            if (at < order.size() && order[at] == f) {
              ++at;
              continue;
            }
            const Plane& plane = bsp.fragments[f].plane;
            if (isFrontFacing(plane, eye.view.eye) && glm::dot(glm::normalize(plane.n), axis) > sin_half) {
              ++outside_view;
              --front_culled;
            }
          }
        }
      }
      culled_total -= front_listed - front_kept - front_culled;  // effectiveness: back faces only
      false_culls += front_culled;
    }
    std::vector<double> ns;
    for (int run = 0; run < args.runs; ++run) {
      const auto t2 = std::chrono::steady_clock::now();
      uint64_t sink = 0;
      for (const Eye& eye : eyes) sink += cullEye(eye);
      const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t2).count();
      ns.push_back(1e9 * sec / static_cast<double>(listed));
      if (sink == uint64_t(-1)) std::printf(" ");
    }
    if (!row.cone && false_culls > 0) ok = false;
    if (row.method == ListCullMethod::kNone && !row.cone) none_ns = medianOf(ns);
    const double culled_ratio = static_cast<double>(culled_total) / static_cast<double>(listed);
    const double effectiveness = back_total ? static_cast<double>(culled_total) / static_cast<double>(back_total) : 0.0;
    const double bytes_per_polygon = static_cast<double>(bytes) / static_cast<double>(std::max<uint64_t>(pool, 1));
    methods.push_back({{"method", row.label},
                       {"culled_ratio", culled_ratio},
                       {"effectiveness", effectiveness},
                       {"ns_per_polygon", medianOf(ns)},
                       {"ns_per_polygon_over_none", medianOf(ns) - none_ns},
                       {"bytes_per_polygon", bytes_per_polygon},
                       {"false_culls", false_culls},
                       {"false_culls_zero_area", false_invisible},
                       {"build_seconds", build_seconds}});
    const double table_share = static_cast<double>(table_positions) / static_cast<double>(std::max<uint64_t>(pool, 1));
    if (row.method == ListCullMethod::kMask && !row.cone) methods.back()["table_positions_ratio"] = table_share;
    if (view_mask) methods.back()["culled_outside_view"] = static_cast<double>(outside_view) / static_cast<double>(listed);
    if (!args.json) {
      std::printf("  %-13s %8.1f %8.1f %9.3f %8.2f %9.3f %7llu %9.3f\n", row.label.c_str(), 100.0 * culled_ratio,
                  100.0 * effectiveness, medianOf(ns), bytes_per_polygon, medianOf(ns) - none_ns,
                  static_cast<unsigned long long>(false_culls), build_seconds);
      if (row.cone && false_invisible > 0) printZeroAreaNote(false_invisible);
      if (view_mask) {
        std::printf("    %s: Zhang & Hoff's mask from the view cone; besides the back faces it dropped %.1f%% of the\n"
                    "    listed polygons, front faces wholly outside the view cone (no pixels in the frustum)\n",
                    row.label.c_str(), 100.0 * static_cast<double>(outside_view) / static_cast<double>(listed));
      } else if (row.method == ListCullMethod::kMask && !row.cone) {
        std::printf("    %s: %.1f%% of the pool in chunks culled by a Zhang & Hoff table, the rest by the plane test\n",
                    row.label.c_str(), 100.0 * table_share);
      }
    }
  }
  lists["methods"] = methods;
  checkClusterVsCone(lists, args.json);
  out.push_back(lists);

  // The BSP path: every fragment, eyes anywhere in the level's box at any height.
  const Bounds b = sceneBounds(scene);
  std::vector<BackfaceView> views(static_cast<size_t>(args.eyes));
  for (BackfaceView& v : views) {
    v.eye = glm::dvec3(b.lo.x + u(rng) * (b.hi.x - b.lo.x), b.lo.y + u(rng) * (b.hi.y - b.lo.y), b.lo.z + u(rng) * (b.hi.z - b.lo.z));
    const double yaw = 2.0 * M_PI * u(rng);
    v.view_dir = glm::dvec3(std::cos(yaw), 0.0, std::sin(yaw));
    v.fov = M_PI / 3.0;
  }
  uint64_t tris = 0;
  for (const Polygon& p : bsp.fragments) tris += p.vertex_count - 2;
  nlohmann::ordered_json whole = benchInput(spec + " bsp fragments (eyes in the box)", input, tris, views, args, ok, &b);
  checkClusterVsCone(whole, args.json);
  out.push_back(whole);
  return out;
}

int runBackfaceBench(const BackfaceBenchArgs& args) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  bool ok = true;
  std::vector<std::string> meshes = args.meshes;
  if (!args.no_bunny) {
    const std::string bunny = args.bunny.empty() ? defaultBunnyPath() : args.bunny;
    if (!bunny.empty() && std::filesystem::exists(bunny)) {
      meshes.push_back(bunny);
    } else if (!args.json) {
      std::printf("bunny: not fetched (%s missing; run scripts/fetch-bunny) - skipped\n",
                  bunny.empty() ? "no path" : bunny.c_str());
    }
  }
  for (const std::string& spec : meshes) {
    const Scene scene = loadScene(spec);
    nlohmann::ordered_json mesh = benchInput(spec, backfaceInput(scene), triangleCount(scene),
                                             eyesAround(sceneBounds(scene), args.eyes, args.seed), args, ok);
    checkClusterVsCone(mesh, args.json);
    out.push_back(mesh);
  }
  if (!args.lists.empty()) {
    for (auto& m : benchLists(args.lists, args, ok)) out.push_back(std::move(m));
  }
  if (args.subdivision) {
    nlohmann::ordered_json sub = runSubdivisionBench(args);
    if (args.json) {
      nlohmann::ordered_json both;
      both["meshes"] = out;
      both["subdivision"] = sub;
      std::printf("%s\n", both.dump(2).c_str());
    }
  } else if (args.json) {
    std::printf("%s\n", out.dump(2).c_str());
  }
  return ok ? 0 : 1;
}

}  // namespace

void addBenchBackface(CLI::App& bench, CommandRunner& runner) {
  auto args = std::make_shared<BackfaceBenchArgs>();
  CLI::App* sub = bench.add_subcommand(
      "backface", "Backface methods (polygon, mask, cluster, hierarchy) and meshoptimizer cone culling on the same eyes");
  sub->add_option("--mesh", args->meshes, "Scene or mesh file, repeatable (default: gen:sphere ~2k and ~70k, gen:dome)");
  sub->add_option("--eyes", args->eyes, "Random eyes per mesh")->check(CLI::Range(1, 100000));
  sub->add_option("--runs", args->runs, "Timed passes over the eyes; the median is reported")->check(CLI::Range(1, 1000));
  sub->add_option("--seed", args->seed, "Seed of the eyes");
  sub->add_option("--tr", args->tr, "Johannsen-Carter T/R (cluster test time over vertex time); 0: from the polygon count (clusterTrFor)")->check(CLI::NonNegativeNumber);
  sub->add_option("--mask-n", args->mask_resolution, "Normal-mask cells per cube-face side (0: from the polygon count)")->check(CLI::Range(0, 18));
  sub->add_option("--mask-group", args->mask_group, "Polygons per view-cone group of mask-groups")->check(CLI::Range(1u, 1u << 30));
  sub->add_option("--bunny", args->bunny, "The bunny OBJ (default: where scripts/fetch-bunny puts it; skipped when missing)");
  sub->add_flag("--no-bunny", args->no_bunny, "Leave the bunny out");
  sub->add_option("--lists", args->lists,
                  "WAD level whose start level is built as PFD trees (drop_back_faces = false) and culled per run, "
                  "then its BSP fragments; empty string: none (default freedoom2.wad:MAP01)");
  sub->add_option("--only", args->only, "Run only these rows (method labels, e.g. cluster cone), repeatable")
      ->delimiter(',');
  sub->add_flag("--json", args->json, "Print JSON");
  sub->add_flag("--subdivision", args->subdivision,
                "Also Moller-Sequin culled Loop subdivision of the animated blob at 1..3 levels");
  sub->add_option("--subdivision-refine", args->subdivision_refine,
                  "Blob control mesh: icosahedron refined K times (20*4^K triangles; default 2: 320)")->check(CLI::Range(0, 4));
  sub->callback([args, &runner] { runner = [args] { return runBackfaceBench(*args); }; });
}

}  // namespace walkvis
