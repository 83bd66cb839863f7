// walkvis bench backface [--mesh SCENE ...] [--eyes K] [--runs K] [--json]: every backface method
// of backface/ and meshoptimizer's meshlet cone culling on the same meshes and the same eyes.
//
// Eyes: uniformly random directions at 1.5–4 bounding radii from the centre of the mesh's box,
// looking at the centre with a 60° cone (Johannsen & Carter measure from a sphere around the
// model). Per mesh and method: culled_ratio (culled / polygons), effectiveness (culled /
// back-facing), ns_per_polygon (time of the per-frame cull step over all eyes divided by eyes ×
// polygons; median over --runs; the unit → polygon expansion is not timed), bytes_per_polygon
// (per-frame test state / polygons) and false_culls (front faces culled, summed over the eyes:
// must be 0 for our methods). Exit status 1 when any of our methods culls a front face.
// hierarchy (Kumar et al.) tracks the eye from frame to frame, so it is timed twice: on the eyes in
// their random order (every frame a jump: full tests) and as hierarchy-tour, the same eyes in the
// order of a greedy nearest-neighbour tour (same culled figures, coherent motion).
//
// --subdivision adds Möller & Séquin's culled Loop subdivision of the animated blob
// (backface/subdivision.h) at 1..3 levels: triangles computed over the levels (full / culled),
// the final level's, and the time per frame, over --eyes random eyes at 2–10 radii and times. With
// --json the output is then {"meshes": [...], "subdivision": [...]}.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "backface/backface.h"
#include "backface/subdivision.h"
#include "commands.h"

namespace walkvis {
namespace {

struct BackfaceBenchArgs {
  std::vector<std::string> meshes{"gen:sphere", "gen:sphere?tris=70000", "gen:dome"};
  int eyes = 200;
  int runs = 5;
  uint64_t seed = 1;
  double tr = 1.0;
  int mask_resolution = 16;
  uint32_t mask_group = 256;
  bool json = false;
  bool subdivision = false;
  int subdivision_refine = 2;
};

struct Variant {
  std::string label;
  BackfaceMethod method;
  BackfaceOptions options;
  bool tour = false;  // eyes in nearest-neighbour tour order
};

std::vector<Variant> variants(const BackfaceBenchArgs& args) {
  BackfaceOptions base;
  base.mask_resolution = args.mask_resolution;
  base.cluster_tr = args.tr;
  std::vector<Variant> out;
  out.push_back({"polygon", BackfaceMethod::kPolygon, base});
  out.push_back({"mask", BackfaceMethod::kMask, base});
  BackfaceOptions grouped = base;
  grouped.mask_group_size = args.mask_group;
  out.push_back({"mask-groups", BackfaceMethod::kMask, grouped});
  out.push_back({"cluster", BackfaceMethod::kCluster, base});
  BackfaceOptions flat = base;
  flat.cluster_hierarchy = false;
  out.push_back({"cluster-flat", BackfaceMethod::kCluster, flat});
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

int runBackfaceBench(const BackfaceBenchArgs& args) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  bool ok = true;
  for (const std::string& spec : args.meshes) {
    const Scene scene = loadScene(spec);
    const size_t n = scene.polygons.size();
    if (n == 0) throw SceneError(spec + ": no polygons to cull");
    const Bounds b = sceneBounds(scene);
    const glm::dvec3 center = 0.5 * (b.lo + b.hi);
    const double radius = std::max(0.5 * glm::length(b.hi - b.lo), 1e-9);
    std::mt19937_64 rng(args.seed);
    std::normal_distribution<double> g;
    std::uniform_real_distribution<double> u(1.5, 4.0);
    std::vector<BackfaceView> views(static_cast<size_t>(args.eyes));
    for (BackfaceView& v : views) {
      glm::dvec3 dir(g(rng), g(rng), g(rng));
      dir = glm::normalize(dir);
      v.eye = center + u(rng) * radius * dir;
      v.view_dir = -dir;
      v.fov = M_PI / 3.0;
    }
    const std::vector<BackfaceView> tour_views = tourOrder(views);
    // Back-facing counts per eye, from the ground truth.
    uint64_t back_total = 0;
    for (const BackfaceView& v : views) {
      for (const Polygon& p : scene.polygons) back_total += !isFrontFacing(p.plane, v.eye);
    }
    nlohmann::ordered_json mesh;
    mesh["mesh"] = spec;
    mesh["polygons"] = n;
    mesh["triangles"] = triangleCount(scene);
    mesh["back_facing_ratio"] = static_cast<double>(back_total) / (static_cast<double>(n) * views.size());
    nlohmann::ordered_json methods = nlohmann::ordered_json::array();
    if (!args.json) {
      std::printf("%s: %zu polygons, %.1f%% back-facing over %d eyes\n", spec.c_str(), n,
                  100.0 * mesh["back_facing_ratio"].get<double>(), args.eyes);
      std::printf("  %-13s %8s %8s %9s %8s %8s %7s %9s\n", "method", "culled%", "effect%", "ns/poly", "B/poly",
                  "units", "false", "build_s");
    }
    for (const Variant& variant : variants(args)) {
      const auto t0 = std::chrono::steady_clock::now();
      const auto culler = makeBackfaceCuller(variant.method, backfaceInput(scene), variant.options);
      const double build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::vector<uint8_t> units(culler->unitCount()), culled(n);
      uint64_t culled_total = 0, false_culls = 0;
      const std::vector<BackfaceView>& eyes = variant.tour ? tour_views : views;
      for (const BackfaceView& v : eyes) {
        culler->cull(v, units);
        expandToPolygons(*culler, units, culled);
        for (size_t p = 0; p < n; ++p) {
          culled_total += culled[p];
          false_culls += culled[p] && isFrontFacing(scene.polygons[p].plane, v.eye);
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
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
        ns.push_back(1e9 * s / (static_cast<double>(views.size()) * static_cast<double>(n)));
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
                         {"units", culler->unitCount()},
                         {"build_seconds", build_seconds}});
      if (!args.json) {
        std::printf("  %-13s %8.1f %8.1f %9.3f %8.2f %8zu %7llu %9.3f\n", variant.label.c_str(), 100.0 * culled_ratio,
                    100.0 * effectiveness, ns_per_polygon, bytes_per_polygon, culler->unitCount(),
                    static_cast<unsigned long long>(false_culls), build_seconds);
      }
    }
    mesh["methods"] = methods;
    out.push_back(mesh);
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
  sub->add_option("--tr", args->tr, "Johannsen-Carter T/R (cluster test time over vertex time)")->check(CLI::NonNegativeNumber);
  sub->add_option("--mask-n", args->mask_resolution, "Normal-mask cells per cube-face side")->check(CLI::Range(1, 18));
  sub->add_option("--mask-group", args->mask_group, "Polygons per view-cone group of mask-groups")->check(CLI::Range(1u, 1u << 30));
  sub->add_flag("--json", args->json, "Print JSON");
  sub->add_flag("--subdivision", args->subdivision,
                "Also Moller-Sequin culled Loop subdivision of the animated blob at 1..3 levels");
  sub->add_option("--subdivision-refine", args->subdivision_refine,
                  "Blob control mesh: icosahedron refined K times (20*4^K triangles; default 2: 320)")->check(CLI::Range(0, 4));
  sub->callback([args, &runner] { runner = [args] { return runBackfaceBench(*args); }; });
}

}  // namespace walkvis
