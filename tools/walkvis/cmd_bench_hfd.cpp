// walkvis bench hfd SCENE and walkvis bench rays SCENE (docs/DESIGN.md, "Speed against error").
//
//   bench hfd SCENE [--region-samples LIST] [--polygon-samples LIST] [--refine-rays LIST]
//                   [--views N] [--res PIXELS] [--max-levels K] [--max-seconds S] [--csv FILE] [--png FILE]
//     Sweeps the HFD sampling knobs: per point the HFD trees of the scene's levels are built
//     (buildPfdLevel with a VisibilityScene) and measured with computeHfdStats: build seconds, rays
//     cast, ray rate, tree bytes, mean listed, pixel_error_ratio, missed fragments, eyes with a
//     miss, the histogram of per-eye pixel error. Writes a CSV (through a temporary file) and a
//     speed-against-error plot (PNG: build seconds across; up, log10 pixel error in the top panel
//     and log10 of the share of eyes with a miss below; each point numbered by its CSV row).
//   bench rays SCENE [--rays N]
//     Occlusion-ray throughput of the same Embree scene (VisibilityScene::occluded): random
//     incoherent segments from walkable points at eye height to points of random fragments, on 1
//     and 2 threads. The build's rays / build seconds is given as a fraction of it.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <tbb/global_control.h>

#include "bsp/bsp.h"
#include "commands.h"
#include "plot.h"
#include "core/byte_io.h"
#include "core/rng.h"
#include "core/sample.h"
#include "pfd_hfd/pfd.h"
#include "pfd_hfd/visibility.h"
#include "walkthrough/hfd_stats.h"
#include "walkthrough/validate.h"

namespace walkvis {
namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}


// ---- bench rays ----

struct RayRate {
  double rays_per_second_1 = 0.0;
  double rays_per_second_2 = 0.0;
  double occluded_fraction = 0.0;
};

RayRate measureRays(const Scene& scene, const BspTree& bsp, const VisibilityScene& vis, uint64_t count) {
  // Eyes: a random level (by walkable area), a random piece by area, at eye height.
  struct Piece {
    std::span<const glm::dvec2> v;
    double y, area;
  };
  std::vector<Piece> pieces;
  double total = 0.0;
  for (const FloorLevel& level : scene.levels)
    for (const auto& p : level.walkable) {
      if (p.size() < 3) continue;
      double a = 0.0;
      for (size_t k = 1; k + 1 < p.size(); ++k) a += twiceTriangleArea(p[0], p[k], p[k + 1]);
      if (!(a > 0.0)) continue;
      pieces.push_back({p, level.floor_y + scene.eye_height, a});
      total += a;
    }
  if (pieces.empty() || bsp.fragments.empty()) throw Error(scene.name + ": no walkable region or no polygons");
  std::vector<std::pair<glm::dvec3, glm::dvec3>> rays(count);
  uint64_t rng = 12345;
  for (auto& r : rays) {
    double pick = uniform01(rng) * total;
    size_t i = 0;
    while (i + 1 < pieces.size() && pick > pieces[i].area) pick -= pieces[i++].area;
    const glm::dvec2 e = uniformPointInConvex<glm::dvec2>(pieces[i].v, rng);
    const uint32_t f = static_cast<uint32_t>(splitmix64(rng) % bsp.fragments.size());
    const auto fv = bsp.fragmentVertices(f);
    const glm::dvec3 p = fv.size() >= 3 ? uniformPointInConvex<glm::dvec3>(fv, rng) : fv[0];
    r = {glm::dvec3(e.x, pieces[i].y, e.y), p};
  }
  RayRate out;
  for (int threads : {1, 2}) {
    std::vector<uint64_t> blocked(threads, 0);
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
      pool.emplace_back([&, t] {
        for (size_t k = t; k < rays.size(); k += threads) blocked[t] += vis.occluded(rays[k].first, rays[k].second);
      });
    for (auto& th : pool) th.join();
    const double s = secondsSince(t0);
    uint64_t b = 0;
    for (uint64_t x : blocked) b += x;
    (threads == 1 ? out.rays_per_second_1 : out.rays_per_second_2) = static_cast<double>(count) / s;
    out.occluded_fraction = static_cast<double>(b) / static_cast<double>(count);
  }
  return out;
}

struct RaysArgs {
  SceneArgs scene;
  uint64_t rays = 2000000;
};

int runRaysBench(const RaysArgs& args) {
  const Scene scene = loadScene(args.scene.scene, args.scene.loadOptions());
  const BspTree bsp = buildBsp(scene);
  const VisibilityScene vis = VisibilityScene::build(bsp);
  const RayRate r = measureRays(scene, bsp, vis, args.rays);
  std::printf("%s\n", vis.deviceInfo().c_str());
  std::printf("%s: %zu fragments, %llu random eye-to-fragment segments (%.1f%% occluded)\n", scene.name.c_str(),
              bsp.fragments.size(), static_cast<unsigned long long>(args.rays), 100.0 * r.occluded_fraction);
  std::printf("occlusion rays/s: 1 thread %.3g, 2 threads %.3g (speed-up %.2f)\n", r.rays_per_second_1,
              r.rays_per_second_2, r.rays_per_second_2 / r.rays_per_second_1);
  return 0;
}

// ---- bench hfd ----

struct HfdBenchArgs {
  SceneArgs scene;
  std::vector<uint32_t> region_samples{16, 32, 64};
  std::vector<uint32_t> polygon_samples{4, 8, 16};
  std::vector<uint32_t> refine_rays{0, 1024};
  std::vector<uint32_t> proof_rays{VisibilityOptions{}.proof_rays};
  int threads = 0;  // 0: TBB's default
  uint32_t views = 50;
  int res = 64;
  uint32_t max_levels = 0;  // 0: all
  double max_seconds = 600.0;
  uint64_t ray_rate_rays = 500000;
  std::string csv = "bench_hfd.csv";
  std::string png = "bench_hfd.png";
};

struct HfdPoint {
  VisibilityOptions vis;
  double build_seconds = 0.0;
  uint64_t rays = 0, tests = 0, rejected = 0, bytes = 0;
  HfdSummary stats;
};

// Top: pixel error ratio (1e-7 to 1); bottom: the share of eyes with a miss (1e-4 to 1), which
// average pixel error hides. Both against build seconds.
// Each point labelled with its row number, red where refinement was on.
void drawPlot(const std::vector<HfdPoint>& points, const std::string& path) {
  double smax = 0.0;
  for (const auto& p : points) smax = std::max(smax, p.build_seconds);
  const PlotAxis seconds{0.0, smax > 0.0 ? smax * 1.05 : 1.0, false, "s"};
  std::vector<PlotPoint> error, missing;
  for (size_t i = 0; i < points.size(); ++i) {
    const Rgb c = points[i].vis.refine_rays ? Rgb{200, 30, 30} : Rgb{30, 30, 200};
    error.push_back({points[i].build_seconds, points[i].stats.pixel_error_ratio, c, std::to_string(i + 1)});
    missing.push_back({points[i].build_seconds, points[i].stats.eyes_with_miss, c, std::to_string(i + 1)});
  }
  Canvas cv(640, 900);
  drawPanel(cv, error, 60, 620, 20, 430, seconds, PlotAxis{-7.0, 0.0, true, ""});
  drawPanel(cv, missing, 60, 620, 490, 850, seconds, PlotAxis{-4.0, 0.0, true, ""});
  cv.write(path);
}

int runHfdBench(const HfdBenchArgs& args) {
  // The build's threads (TBB) for the parallel speed-up; bench rays' own 1- and 2-thread figures
  // use plain threads and are not limited by it.
  std::unique_ptr<tbb::global_control> limit;
  if (args.threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  static_cast<size_t>(args.threads));
  const auto t_all = std::chrono::steady_clock::now();
  const Scene scene = loadScene(args.scene.scene, args.scene.loadOptions());
  const BspTree bsp = buildBsp(scene);
  std::fprintf(stderr, "bench hfd: %s: %zu polygons, %zu fragments, %zu levels\n", scene.name.c_str(),
               scene.polygons.size(), bsp.fragments.size(), scene.levels.size());
  const uint32_t levels = args.max_levels ? std::min<uint32_t>(args.max_levels, scene.levels.size())
                                          : static_cast<uint32_t>(scene.levels.size());
  RayRate rate;
  {
    const VisibilityScene vis = VisibilityScene::build(bsp);
    rate = measureRays(scene, bsp, vis, args.ray_rate_rays);
  }
  std::vector<HfdPoint> points;
  bool stopped = false;
  for (uint32_t rs : args.region_samples)
    for (uint32_t ps : args.polygon_samples)
      for (uint32_t rr : args.refine_rays)
      for (uint32_t pr : args.proof_rays) {
        if (secondsSince(t_all) > args.max_seconds) {
          stopped = true;
          continue;
        }
        HfdPoint pt;
        pt.vis.region_samples = rs;
        pt.vis.polygon_samples = ps;
        pt.vis.refine_rays = rr;
        pt.vis.proof_rays = pr;
        const auto t0 = std::chrono::steady_clock::now();
        const VisibilityScene vis = VisibilityScene::build(bsp, pt.vis);
        TreeFile file;
        file.kind = TreeKind::kHfd;
        file.visibility = pt.vis;
        file.eye_height = scene.eye_height;
        PfdLevelOptions lo;
        lo.tree.visibility = &vis;
        lo.tree.stat_eyes = 0;
        uint64_t used = 0;
        file.levels = buildPfdLevels(bsp, std::span<const FloorLevel>(scene.levels.data(), levels), scene.eye_height,
                                     lo, used);
        pt.build_seconds = secondsSince(t0);
        for (const PfdLevel& level : file.levels)
          for (const PfdTree& t : level.cells) {
            pt.rays += t.stats.visibility_rays;
            pt.tests += t.stats.visibility_tests;
            pt.rejected += t.stats.hidden_rejected;
            pt.bytes += t.stats.bytes;
          }
        file.bsp = bsp;
        HfdStatsOptions so;
        so.views = args.views;
        so.res = args.res;
        pt.stats = computeHfdStats(file, so).overall;
        std::fprintf(stderr,
                     "  %zu: region %u polygon %u refine %u proof %u: build %.2f s, %llu rays (%.3g/s), %llu bytes, listed %.1f, "
                     "pixel error %.3g, missed %.3f (%.1f%% of eyes)\n",
                     points.size() + 1, rs, ps, rr, pr, pt.build_seconds, static_cast<unsigned long long>(pt.rays),
                     pt.rays / std::max(pt.build_seconds, 1e-9), static_cast<unsigned long long>(pt.bytes),
                     pt.stats.listed_mean, pt.stats.pixel_error_ratio, pt.stats.missed_mean,
                     100.0 * pt.stats.eyes_with_miss);
        points.push_back(pt);
      }
  std::ostringstream csv;
  csv << "point,scene,region_samples,polygon_samples,refine_rays,proof_rays,threads,build_seconds,vis_tests,rays,"
         "rays_per_second,ray_rate_fraction_1thread,ray_rate_fraction_2threads,rejected,tree_bytes,listed_mean,visible_mean,missed_mean,missed_max,"
         "eyes_with_miss,pixel_error_ratio,pixel_error_ratio_max,rejection_ratio,overestimation,eyes,res";
  // The histogram of per-eye pixel error as eye counts, one column per bin of kPixelErrorBins
  // (hfd_stats.h) named for a CSV: "<=1e-6" is eyes_error_1e-6, ">1e-2" eyes_error_over_1e-2.
  for (const std::string_view bin : kPixelErrorBins) {
    csv << ",eyes_error_";
    if (bin.starts_with("<=")) csv << bin.substr(2);
    else if (bin.starts_with(">")) csv << "over_" << bin.substr(1);
    else csv << bin;
  }
  csv << '\n';
  std::printf("%s: %zu fragments, %u levels; Embree occlusion rays/s: %.3g (1 thread), %.3g (2 threads)\n",
              scene.name.c_str(), bsp.fragments.size(), levels, rate.rays_per_second_1, rate.rays_per_second_2);
  std::printf("%3s %6s %6s %6s %5s %9s %11s %8s %8s %11s %9s %10s %9s %6s %6s\n", "pt", "region", "poly", "refine",
              "proof", "build_s", "rays", "rate%1t", "rate%2t", "bytes", "listed", "pixel_err", "missed", "miss%", "overest");
  for (size_t i = 0; i < points.size(); ++i) {
    const HfdPoint& p = points[i];
    const double rps = p.rays / std::max(p.build_seconds, 1e-9);
    csv << i + 1 << ',' << scene.name << ',' << p.vis.region_samples << ',' << p.vis.polygon_samples << ','
        << p.vis.refine_rays << ',' << p.vis.proof_rays << ',' << args.threads << ',' << p.build_seconds << ','
        << p.tests << ',' << p.rays << ',' << rps << ',' << rps / rate.rays_per_second_1 << ','
        << rps / rate.rays_per_second_2 << ',' << p.rejected << ',' << p.bytes << ',' << p.stats.listed_mean << ','
        << p.stats.visible_mean << ',' << p.stats.missed_mean << ',' << p.stats.missed_max << ','
        << p.stats.eyes_with_miss << ',' << p.stats.pixel_error_ratio << ',' << p.stats.pixel_error_ratio_max << ','
        << p.stats.rejection_ratio << ',' << p.stats.overestimation << ',' << p.stats.eyes << ',' << args.res;
    for (uint64_t n : p.stats.pixel_error_histogram) csv << ',' << n;
    csv << '\n';
    std::printf("%3zu %6u %6u %6u %5u %9.2f %11llu %7.1f%% %7.1f%% %11llu %9.1f %10.3g %9.3f %5.1f%% %6.2f\n", i + 1,
                p.vis.region_samples, p.vis.polygon_samples, p.vis.refine_rays, p.vis.proof_rays, p.build_seconds,
                static_cast<unsigned long long>(p.rays), 100.0 * rps / rate.rays_per_second_1,
                100.0 * rps / rate.rays_per_second_2,
                static_cast<unsigned long long>(p.bytes), p.stats.listed_mean, p.stats.pixel_error_ratio,
                p.stats.missed_mean, 100.0 * p.stats.eyes_with_miss, p.stats.overestimation);
  }
  writeTextFileAtomically(args.csv, csv.str(), "the sweep table");
  if (!args.png.empty() && !points.empty()) drawPlot(points, args.png);
  if (stopped) std::printf("(stopped after %.0f s: --max-seconds; later points skipped)\n", args.max_seconds);
  std::printf("wrote %s, %s\n", args.csv.c_str(), args.png.c_str());
  return 0;
}

}  // namespace

void addBenchHfd(CLI::App& bench, CommandRunner& runner) {
  {
    auto args = std::make_shared<HfdBenchArgs>();
    CLI::App* sub = bench.add_subcommand("hfd", "HFD sampling knobs swept: build cost against pixel error (CSV, PNG)");
    addSceneArgs(*sub, args->scene);
    sub->add_option("--region-samples", args->region_samples, "Region samples per test (list)")->delimiter(',');
    sub->add_option("--polygon-samples", args->polygon_samples, "Polygon samples per test (list)")->delimiter(',');
    sub->add_option("--refine-rays", args->refine_rays, "Refinement rays per test (list)")->delimiter(',');
    sub->add_option("--proof-rays", args->proof_rays, "Rays per test spent proving it hidden (list; 0: off)")
        ->delimiter(',');
    sub->add_option("--threads", args->threads, "Build threads (0: TBB's default)")->check(CLI::Range(0, 256));
    sub->add_option("--views", args->views, "Stats eyes per level")->check(CLI::Range(1u, 100000u));
    sub->add_option("--res", args->res, "Stats cube face pixels per side")->check(CLI::Range(1, 4096));
    sub->add_option("--max-levels", args->max_levels, "Only the first K levels (0: all)");
    sub->add_option("--max-seconds", args->max_seconds, "Skip the remaining points after this long");
    sub->add_option("--csv", args->csv, "CSV output");
    sub->add_option("--png", args->png, "Plot output (empty: none)");
    sub->callback([args, &runner] { runner = [args] { return runHfdBench(*args); }; });
  }
  {
    auto args = std::make_shared<RaysArgs>();
    CLI::App* sub = bench.add_subcommand("rays", "Embree occlusion rays/s on the scene, 1 and 2 threads");
    addSceneArgs(*sub, args->scene);
    sub->add_option("--rays", args->rays, "Segments cast per thread count")->check(CLI::Range(1ull, 1000000000ull));
    sub->callback([args, &runner] { runner = [args] { return runRaysBench(*args); }; });
  }
}

}  // namespace walkvis
