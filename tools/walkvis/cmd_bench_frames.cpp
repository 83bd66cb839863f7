// walkvis bench frames SCENE|FILE: the same tour rendered offscreen (OSMesa, llvmpipe) in one run
// by the z-buffer baseline (all fragments, depth test and GL back-face culling on), painter's BSP
// (back faces skipped in the traversal), painter's PFD (trees of a PFD tree file, or built in
// memory for a scene), and painter's HFD with each backface method (an HFD tree file: the source or
// --hfd). Every mode leaves out the fragments wholly outside the view frustum (FrameBuilder; not
// with --no-frustum-culling). Per mode: median frame time (order + draw + glFinish), median
// polygons drawn, speedup over the z-buffer, and the fraction of the ideal it reaches. Two
// reference runs frame every mode's time: the floor (the same frames with nothing drawn: clear, the
// eye-relative vertex upload, glFinish), and the ideal (drawing exactly the fragments the z-buffer
// frame shows, in BSP order, with no order cost: what a perfect visibility method would draw; the
// mesh objects' subdivision, the same in every mode, is timed in the ideal as in the modes).
// ideal_fraction = ideal time / mode time, so 1 means the mode is as fast as drawing only what is
// seen; ideal_fraction_paired is the median over frames of that ratio frame by frame, and its
// halves the same from the even and the odd rounds alone, whose distance tells its noise. Every
// mode, the floor and the ideal run the whole tour once per round, rounds in rotated order, and the
// medians are over all rounds; frame_ms_round_spread (the range of the rounds' medians over their
// median) tells how far the noise reaches, to compare with the differences between modes. Order
// check: on every --check-every'th frame the painter's ids image is compared with the z-buffer's
// (24-bit depth, GL culling on) pixel by pixel; both rasterise the same triangles from the same
// float positions, so a differing pixel is an order error or a depth tie of the z-buffer itself.
// The exact ray-cast comparison is `walkvis validate`.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "frames_common.h"
#include "walkthrough/osmesa_context.h"

namespace walkvis {
namespace {

struct FramesBenchArgs {
  std::string source;
  std::string scene;
  std::string hfd;
  LoadOptions load;
  uint32_t frames = 120;
  std::string size = "320x240";
  uint32_t check_every = 10;
  uint32_t rounds = 3;
  std::string objects = "auto";
  bool frustum_culling = true;
  bool occlusion_culling = true;
  OcclusionOptions occlusion;
  bool json = false;
};

double medianOf(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// Some of a run's rounds: those whose index r has r % step == first.
struct RoundSet {
  uint32_t first = 0, step = 1;
};
// All rounds, then the even and the odd ones alone (all rounds for both when there is one).
std::array<RoundSet, 3> roundSets(uint32_t rounds) {
  if (rounds < 2) return {RoundSet{0, 1}, RoundSet{0, 1}, RoundSet{0, 1}};
  return {RoundSet{0, 1}, RoundSet{0, 2}, RoundSet{1, 2}};
}

// Per frame of the tour, the median of its times over the rounds of `set`. frame_ms holds round
// after round, `frames` times each.
std::vector<double> perFrameMedians(const std::vector<double>& frame_ms, size_t frames, RoundSet set) {
  std::vector<double> medians(frames), times;
  for (size_t k = 0; k < frames; ++k) {
    times.clear();
    for (size_t r = set.first; (r + 1) * frames <= frame_ms.size(); r += set.step)
      times.push_back(frame_ms[r * frames + k]);
    medians[k] = medianOf(times);
  }
  return medians;
}

// The median over the frames of the ideal's time over the mode's, both per-frame medians of the
// same rounds: a paired figure, so that a frame dear for every mode (a wide view of big walls)
// weighs the same in both.
double pairedIdealFraction(const std::vector<double>& ideal, const std::vector<double>& mode) {
  std::vector<double> ratios;
  for (size_t k = 0; k < mode.size(); ++k)
    if (mode[k] > 0.0) ratios.push_back(ideal[k] / mode[k]);
  return medianOf(ratios);
}

enum class RunKind : uint8_t { kMode, kFloor, kIdeal };

struct ModeRun {
  std::string name;
  OrderMode mode;
  const World* world;
  RunKind kind = RunKind::kMode;
};

struct ModeSamples {
  std::vector<double> frame_ms, order_ms, draw_ms, drawn, listed, tests, culled, outside, occluded, occluders, occluded_pixels,
      object_triangles, round_medians;
  uint64_t bsp_fallbacks = 0;
  uint64_t occlusion_rests = 0;  // frames in which occlusion culling rested (its pacing)
};

int runFramesBench(const FramesBenchArgs& args) {
  const ImageSize size = parseImageSize(args.size, "--size");
  auto progress = [&](const std::string& line) {
    if (!args.json) std::fprintf(stderr, "%s\n", line.c_str());
  };
  WorldOptions base;
  base.load = args.load;
  base.scene = args.scene;
  // The source without culling (z-buffer) and with the exact region method (bsp, pfd); PFD trees
  // in memory when the source is a scene.
  base.build_pfd = true;
  base.cull = ListCullMethod::kRegion;
  base.objects = parseObjectSet(args.objects);
  base.frustum_culling = args.frustum_culling;
  base.occlusion_culling = args.occlusion_culling;
  base.occlusion = args.occlusion;
  std::vector<std::unique_ptr<World>> worlds;
  worlds.push_back(std::make_unique<World>(openWorld(args.source, base, progress)));
  const World& main = *worlds.back();
  // The z-buffer world: the same scene and BSP, no trees, no list culler.
  auto zworld = std::make_unique<World>();
  zworld->scene = main.scene;
  zworld->trees.bsp = main.trees.bsp;
  zworld->trees.eye_height = main.trees.eye_height;
  zworld->source = main.source;
  zworld->objects = main.objects;
  zworld->fragment_balls = main.fragment_balls;
  zworld->frustum_culling = main.frustum_culling;
  zworld->occlusion_culling = false;  // the baseline, and the ideal's list below: what the frustum holds
  worlds.push_back(std::move(zworld));
  const World& zbuffer_world = *worlds.back();

  std::vector<ModeRun> runs = {{"zbuffer", OrderMode::kZBuffer, &zbuffer_world}, {"bsp", OrderMode::kBsp, &main}};
  const bool main_has_trees = !main.trees.levels.empty();
  if (main_has_trees && main.trees.kind == TreeKind::kPfd) runs.push_back({"pfd", OrderMode::kPfd, &main});
  std::string hfd_file = args.hfd;
  if (hfd_file.empty() && main_has_trees && main.trees.kind == TreeKind::kHfd) hfd_file = args.source;
  if (!hfd_file.empty()) {
    for (ListCullMethod m : {ListCullMethod::kNone, ListCullMethod::kPolygon, ListCullMethod::kMask,
                             ListCullMethod::kCluster, ListCullMethod::kHierarchy, ListCullMethod::kRegion}) {
      WorldOptions o = base;
      o.cull = m;
      o.build_pfd = false;
      worlds.push_back(std::make_unique<World>(openWorld(hfd_file, o, progress)));
      if (worlds.back()->trees.kind != TreeKind::kHfd || worlds.back()->trees.levels.empty())
        throw Error(hfd_file + ": not an HFD tree file (make one with `walkvis build --tree hfd`)");
      if (worlds.back()->trees.bsp.fragments.size() != main.trees.bsp.fragments.size())
        throw Error(hfd_file + ": its BSP differs from the source's");
      worlds.back()->objects = main.objects;  // the same objects whatever the tree file's spec
      runs.push_back({"hfd+" + std::string(listCullMethodName(m)), OrderMode::kHfd, worlds.back().get()});
    }
  }

  const CameraPath path = framesPath(main, "", args.frames);
  std::string why;
  auto context = OsMesaContext::create(size.width, size.height, 24, &why);
  if (!context) throw std::runtime_error("offscreen GL: " + why);
  auto drawer = SceneDrawer::create(OsMesaContext::loader(), &why);
  if (!drawer) throw std::runtime_error("offscreen GL: " + why);
  drawer->upload(main.trees.bsp, main.scene);

  // The z-buffer truth, once: the ids images of the checked frames, and per frame the ideal list
  // (the BSP order kept to the fragments the z-buffer frame shows).
  FrameBuilder builder;
  std::vector<uint32_t> draw, ids;
  std::vector<std::vector<uint32_t>> truth, ideal(path.keys.size());
  const uint32_t every = std::max(args.check_every, 1u);
  std::vector<uint8_t> shown(main.trees.bsp.fragments.size());
  for (size_t k = 0; k < path.keys.size(); ++k) {
    const FreeCamera camera = cameraAt(path.keys[k], size);
    timedFrame(zbuffer_world, builder, *drawer, camera, OrderMode::kZBuffer, DrawStyle::kIds, draw, path.keys[k].time);
    drawer->readIds(size.width, size.height, ids);
    std::fill(shown.begin(), shown.end(), uint8_t{0});
    for (uint32_t id : ids)
      if (id < shown.size()) shown[id] = 1;
    builder.build(zbuffer_world, camera, OrderMode::kBsp, draw, path.keys[k].time);
    for (uint32_t f : draw)
      if (f < shown.size() && shown[f]) ideal[k].push_back(f);
    if (k % every == 0) truth.push_back(ids);
  }
  const size_t zbuffer_run = 0, floor_run = runs.size(), ideal_run = runs.size() + 1;
  runs.push_back({"floor", OrderMode::kBsp, &main, RunKind::kFloor});
  // The ideal places the objects through a BSP frame of the z-buffer world: without occlusion
  // culling, so it leaves the pacing of the BSP mode's occlusion culling alone.
  runs.push_back({"ideal", OrderMode::kBsp, &zbuffer_world, RunKind::kIdeal});

  // One frame of a run: a mode's own frame, the empty frame or the ideal list, timed the same way.
  auto runFrame = [&](const ModeRun& run, size_t k, DrawStyle style) {
    const FreeCamera camera = cameraAt(path.keys[k], size);
    if (run.kind == RunKind::kMode) return timedFrame(*run.world, builder, *drawer, camera, run.mode, style, draw, path.keys[k].time);
    const bool objects = run.kind == RunKind::kIdeal && !run.world->objects.empty();
    FrameStats stats;
    if (objects) {
      // The build places the mesh objects the ideal draws after its list. Its order costs nothing
      // (what a perfect visibility method would spend); the objects' subdivision is the same work
      // in every mode, so the ideal pays it too (object_ms).
      stats = builder.build(*run.world, camera, OrderMode::kBsp, draw, path.keys[k].time);
      stats.order_ms = 0.0;
      stats.tests = stats.culled = stats.outside = stats.occluded = stats.occluders = stats.occluded_pixels = 0;
    }
    const std::span<const uint32_t> list =
        run.kind == RunKind::kIdeal ? std::span<const uint32_t>(ideal[k]) : std::span<const uint32_t>();
    stats.listed = stats.drawn = static_cast<uint32_t>(list.size());
    const DrawSettings settings = settingsFor(OrderMode::kBsp, style, objects);
    const auto t0 = std::chrono::steady_clock::now();
    drawer->draw(camera, list, settings);
    if (objects) drawObjects(builder, *drawer, camera, settings);
    drawer->finish();
    stats.draw_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return stats;
  };

  const uint32_t rounds = std::max(args.rounds, 1u);
  std::vector<ModeSamples> samples(runs.size());
  for (uint32_t r = 0; r < rounds; ++r) {
    for (size_t q = 0; q < runs.size(); ++q) {
      const size_t i = (q + r) % runs.size();  // rotated, so no mode always follows the same one
      ModeSamples& m = samples[i];
      std::vector<double> round_ms;
      for (size_t k = 0; k < path.keys.size(); ++k) {
        const FrameStats st = runFrame(runs[i], k, DrawStyle::kShaded);
        const double ms = st.order_ms + st.object_ms + st.draw_ms;
        round_ms.push_back(ms);
        m.frame_ms.push_back(ms);
        m.object_triangles.push_back(st.object_triangles);
        m.order_ms.push_back(st.order_ms);
        m.draw_ms.push_back(st.draw_ms);
        m.drawn.push_back(st.drawn);
        m.listed.push_back(st.listed);
        m.tests.push_back(st.tests);
        m.culled.push_back(st.culled);
        m.outside.push_back(st.outside);
        m.occluded.push_back(st.occluded);
        m.occluders.push_back(st.occluders);
        m.occluded_pixels.push_back(st.occluded_pixels);
        m.occlusion_rests += st.occlusion_rested;
        if (r == 0 && runs[i].kind == RunKind::kMode && runs[i].mode != OrderMode::kZBuffer && st.used != runs[i].mode)
          ++m.bsp_fallbacks;
      }
      m.round_medians.push_back(medianOf(round_ms));
    }
    progress("round " + std::to_string(r + 1) + "/" + std::to_string(rounds) + " done");
  }

  nlohmann::ordered_json out;
  out["bench"] = "frames";
  out["source"] = args.source;
  out["hfd"] = hfd_file;
  out["frames"] = path.keys.size();
  out["size"] = args.size;
  out["scene_polygons"] = main.trees.bsp.fragments.size();
  out["objects"] = main.objects.size();
  out["checked_frames"] = truth.size();
  out["rounds"] = rounds;
  out["frustum_culling"] = main.frustum_culling;
  out["occlusion_culling"] = main.occlusion_culling;
  out["occlusion_cell_pixels"] = main.occlusion.cell_pixels;
  out["max_occluders"] = main.occlusion.max_occluders;
  out["occlusion_min_target_pixels"] = main.occlusion.min_target_pixels;
  out["occlusion_min_occluded_pixels"] = main.occlusion.min_occluded_pixels;
  out["occlusion_max_rest_frames"] = main.occlusion.max_rest_frames;
  const double zbuffer_ms = medianOf(samples[zbuffer_run].frame_ms);
  const double floor_ms = medianOf(samples[floor_run].frame_ms);
  const double ideal_ms = medianOf(samples[ideal_run].frame_ms);
  out["floor_ms_median"] = floor_ms;
  out["ideal_ms_median"] = ideal_ms;
  out["ideal_drawn_median"] = medianOf(samples[ideal_run].drawn);
  out["ideal_speedup"] = ideal_ms > 0.0 ? zbuffer_ms / ideal_ms : 0.0;
  auto rows = nlohmann::ordered_json::array();
  if (!args.json)
    std::printf("%-15s %9s %9s %9s %8s %8s %8s %8s %8s %8s %9s %7s %7s %11s\n", "mode", "frame_ms", "order_ms",
                "draw_ms", "drawn", "listed", "tests", "culled", "outside", "occluded", "speedup", "ideal", "spread",
                "diff_pixels");
  // The ideal's per-frame medians over all rounds, the even and the odd ones, for the paired
  // figures of every mode.
  const size_t frames = path.keys.size();
  const std::array<RoundSet, 3> sets = roundSets(rounds);
  std::array<std::vector<double>, 3> ideal_frames;
  for (size_t h = 0; h < sets.size(); ++h) ideal_frames[h] = perFrameMedians(samples[ideal_run].frame_ms, frames, sets[h]);
  for (size_t i = 0; i < runs.size(); ++i) {
    const ModeRun& run = runs[i];
    const ModeSamples& m = samples[i];
    uint64_t diff_pixels = 0;
    if (run.kind != RunKind::kFloor && run.mode != OrderMode::kZBuffer) {
      size_t t = 0;
      for (size_t k = 0; k < path.keys.size(); k += every, ++t) {
        runFrame(run, k, DrawStyle::kIds);
        drawer->readIds(size.width, size.height, ids);
        for (size_t p = 0; p < ids.size(); ++p) diff_pixels += ids[p] != truth[t][p];
      }
    }
    const double med = medianOf(m.frame_ms);
    const double speedup = med > 0.0 ? zbuffer_ms / med : 0.0;
    const double ideal_fraction = med > 0.0 ? ideal_ms / med : 0.0;
    // All rounds, then the even and the odd ones alone: how far apart those two fall tells the
    // noise of the paired figure.
    std::array<double, 3> paired{};
    for (size_t h = 0; h < sets.size(); ++h)
      paired[h] = pairedIdealFraction(ideal_frames[h], perFrameMedians(m.frame_ms, frames, sets[h]));
    const auto [lo, hi] = std::minmax_element(m.round_medians.begin(), m.round_medians.end());
    const double spread = med > 0.0 ? (*hi - *lo) / med : 0.0;
    rows.push_back({{"mode", run.name},
                    {"frame_ms_median", med},
                    {"frame_ms_round_spread", spread},
                    {"order_ms_median", medianOf(m.order_ms)},
                    {"draw_ms_median", medianOf(m.draw_ms)},
                    {"drawn_median", medianOf(m.drawn)},
                    {"listed_median", medianOf(m.listed)},
                    {"tests_median", medianOf(m.tests)},
                    {"culled_median", medianOf(m.culled)},
                    {"outside_median", medianOf(m.outside)},
                    {"occluded_median", medianOf(m.occluded)},
                    {"occluders_median", medianOf(m.occluders)},
                    {"occluded_pixels_median", medianOf(m.occluded_pixels)},
                    {"occlusion_rested_fraction",
                     m.frame_ms.empty() ? 0.0 : static_cast<double>(m.occlusion_rests) / static_cast<double>(m.frame_ms.size())},
                    {"object_triangles_median", medianOf(m.object_triangles)},
                    {"speedup_vs_zbuffer", speedup},
                    {"ideal_fraction", ideal_fraction},
                    {"ideal_fraction_paired", paired[0]},
                    {"ideal_fraction_paired_halves", {paired[1], paired[2]}},
                    {"bsp_fallback_frames", m.bsp_fallbacks},
                    {"pixels_differing_from_zbuffer", diff_pixels}});
    if (!args.json)
      std::printf("%-15s %9.3f %9.3f %9.3f %8.0f %8.0f %8.0f %8.0f %8.0f %8.0f %9.2f %6.0f%% %6.1f%% %11llu\n",
                  run.name.c_str(), med, medianOf(m.order_ms), medianOf(m.draw_ms), medianOf(m.drawn),
                  medianOf(m.listed), medianOf(m.tests), medianOf(m.culled), medianOf(m.outside),
                  medianOf(m.occluded), speedup,
                  100.0 * ideal_fraction, 100.0 * spread, static_cast<unsigned long long>(diff_pixels));
  }
  out["modes"] = rows;
  if (args.json) {
    std::printf("%s\n", out.dump(2).c_str());
  } else {
    std::printf("%zu frames %dx%d of %s, %zu fragments, %zu mesh objects, %u rounds; floor %.3f ms, ideal %.3f ms "
                "(%.2fx the z-buffer); ideal: ideal time over the mode's; spread: range of the rounds' medians; "
                "diff_pixels: ids differing from the 24-bit z-buffer on %zu checked frames (%zu pixels each)\n",
                path.keys.size(), size.width, size.height, args.source.c_str(), main.trees.bsp.fragments.size(),
                main.objects.size(), rounds, floor_ms, ideal_ms, ideal_ms > 0.0 ? zbuffer_ms / ideal_ms : 0.0,
                truth.size(), static_cast<size_t>(size.width) * size.height);
  }
  return 0;
}

}  // namespace

void addBenchFrames(CLI::App& bench, CommandRunner& runner) {
  auto args = std::make_shared<FramesBenchArgs>();
  CLI::App* sub = bench.add_subcommand(
      "frames", "Walkthrough frame times: z-buffer versus painter's BSP, PFD and HFD with each backface method");
  sub->add_option("source", args->source, "A scene or a tree file made by `walkvis build`")->required();
  sub->add_option("--scene", args->scene, "For a tree file: the scene it was built from (its colours)");
  sub->add_option("--hfd", args->hfd, "An HFD tree file of the same scene (`walkvis build --tree hfd`)");
  addLoadOptions(*sub, args->load);
  sub->add_option("--frames", args->frames, "Frames of the automatic tour")->check(CLI::Range(1u, 100000u));
  sub->add_option("--size", args->size, "Image size WxH");
  sub->add_option("--check-every", args->check_every, "Compare ids with the z-buffer on every k-th frame")
      ->check(CLI::Range(1u, 100000u));
  sub->add_option("--rounds", args->rounds, "Times every mode runs the whole tour (medians over all rounds)")
      ->check(CLI::Range(1u, 1000u));
  sub->add_option("--objects", args->objects,
                  "Mesh objects: auto (the animated blob in gen:office) | none | blob (in the start room)");
  sub->add_flag("!--no-frustum-culling", args->frustum_culling,
                "Give GL every listed fragment, also those wholly outside the view frustum (every mode)");
  sub->add_flag("!--no-occlusion-culling", args->occlusion_culling,
                "Painter's modes: keep the fragments that the frame's largest fragments hide from the eye");
  sub->add_option("--occlusion-cell", args->occlusion.cell_pixels, "Occlusion culling: pixels per cell side")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  sub->add_option("--occluders", args->occlusion.max_occluders, "Occlusion culling: occluders per frame")
      ->check(CLI::Range(0u, 4096u))
      ->capture_default_str();
  sub->add_option("--occlusion-min-pixels", args->occlusion.min_target_pixels,
                  "Occlusion culling: test fragments whose ball looks at least this many pixels in radius")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--occlusion-min-occluded-pixels", args->occlusion.min_occluded_pixels,
                  "Occlusion culling: a test that leaves out less (pixels reached) makes the mode rest a while")
      ->check(CLI::Range(0u, 1000000000u))
      ->capture_default_str();
  sub->add_option("--occlusion-max-rest", args->occlusion.max_rest_frames,
                  "Occlusion culling: the longest rest in frames (0: test every frame)")
      ->check(CLI::Range(0u, 1000000u))
      ->capture_default_str();
  sub->add_flag("--json", args->json, "Print JSON");
  sub->callback([args, &runner] { runner = [args] { return runFramesBench(*args); }; });
}

}  // namespace walkvis
