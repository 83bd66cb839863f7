// walkvis bench frames SCENE|FILE: the same tour rendered offscreen (OSMesa, llvmpipe) in one run by
// the z-buffer baseline (all fragments, depth test and GL back-face culling on), painter's BSP
// (back faces skipped in the traversal), painter's PFD (trees of a PFD tree file, or built in memory
// for a scene), and painter's HFD with each backface method (an HFD tree file: the source or --hfd).
// Per mode: median frame time (order + draw + glFinish), median polygons drawn, speedup over the
// z-buffer. Order check: on every --check-every'th frame the painter's ids image is compared with
// the z-buffer's (24-bit depth, GL culling on) pixel by pixel; both rasterise the same triangles from
// the same float positions, so a differing pixel is an order error or a depth tie of the z-buffer
// itself. The exact ray-cast comparison is `walkvis validate`.
#include <algorithm>
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
  std::string objects = "auto";
  bool json = false;
};

double medianOf(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

struct ModeRun {
  std::string name;
  OrderMode mode;
  const World* world;
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

  // The z-buffer truth for the checked frames, once.
  FrameBuilder builder;
  std::vector<uint32_t> draw;
  std::vector<std::vector<uint32_t>> truth;
  const uint32_t every = std::max(args.check_every, 1u);
  for (size_t k = 0; k < path.keys.size(); k += every) {
    timedFrame(zbuffer_world, builder, *drawer, cameraAt(path.keys[k], size), OrderMode::kZBuffer, DrawStyle::kIds,
               draw, path.keys[k].time);
    drawer->readIds(size.width, size.height, truth.emplace_back());
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
  auto rows = nlohmann::ordered_json::array();
  double zbuffer_ms = 0.0;
  if (!args.json)
    std::printf("%-15s %9s %9s %9s %8s %8s %8s %8s %9s %11s\n", "mode", "frame_ms", "order_ms", "draw_ms", "drawn",
                "listed", "tests", "culled", "speedup", "diff_pixels");
  std::vector<uint32_t> ids;
  for (const ModeRun& run : runs) {
    std::vector<double> frame_ms, order_ms, draw_ms, drawn, listed, tests, culled, object_triangles;
    uint64_t bsp_fallbacks = 0;
    for (const CameraKey& key : path.keys) {
      const FrameStats s =
          timedFrame(*run.world, builder, *drawer, cameraAt(key, size), run.mode, DrawStyle::kShaded, draw, key.time);
      frame_ms.push_back(s.order_ms + s.object_ms + s.draw_ms);
      object_triangles.push_back(s.object_triangles);
      order_ms.push_back(s.order_ms);
      draw_ms.push_back(s.draw_ms);
      drawn.push_back(s.drawn);
      listed.push_back(s.listed);
      tests.push_back(s.tests);
      culled.push_back(s.culled);
      if (run.mode != OrderMode::kZBuffer && s.used != run.mode) ++bsp_fallbacks;
    }
    uint64_t diff_pixels = 0;
    if (run.mode != OrderMode::kZBuffer) {
      size_t t = 0;
      for (size_t k = 0; k < path.keys.size(); k += every, ++t) {
        timedFrame(*run.world, builder, *drawer, cameraAt(path.keys[k], size), run.mode, DrawStyle::kIds, draw,
                   path.keys[k].time);
        drawer->readIds(size.width, size.height, ids);
        for (size_t p = 0; p < ids.size(); ++p) diff_pixels += ids[p] != truth[t][p];
      }
    }
    const double med = medianOf(frame_ms);
    if (run.mode == OrderMode::kZBuffer) zbuffer_ms = med;
    const double speedup = med > 0.0 ? zbuffer_ms / med : 0.0;
    rows.push_back({{"mode", run.name},
                    {"frame_ms_median", med},
                    {"order_ms_median", medianOf(order_ms)},
                    {"draw_ms_median", medianOf(draw_ms)},
                    {"drawn_median", medianOf(drawn)},
                    {"listed_median", medianOf(listed)},
                    {"tests_median", medianOf(tests)},
                    {"culled_median", medianOf(culled)},
                    {"object_triangles_median", medianOf(object_triangles)},
                    {"speedup_vs_zbuffer", speedup},
                    {"bsp_fallback_frames", bsp_fallbacks},
                    {"pixels_differing_from_zbuffer", diff_pixels}});
    if (!args.json)
      std::printf("%-15s %9.3f %9.3f %9.3f %8.0f %8.0f %8.0f %8.0f %9.2f %11llu\n", run.name.c_str(), med,
                  medianOf(order_ms), medianOf(draw_ms), medianOf(drawn), medianOf(listed), medianOf(tests),
                  medianOf(culled), speedup, static_cast<unsigned long long>(diff_pixels));
  }
  out["modes"] = rows;
  if (args.json) {
    std::printf("%s\n", out.dump(2).c_str());
  } else {
    std::printf("%zu frames %dx%d of %s, %zu fragments, %zu mesh objects; diff_pixels: ids differing from the "
                "24-bit z-buffer on %zu checked frames (%zu pixels each)\n",
                path.keys.size(), size.width, size.height, args.source.c_str(), main.trees.bsp.fragments.size(),
                main.objects.size(), truth.size(), static_cast<size_t>(size.width) * size.height);
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
  sub->add_option("--objects", args->objects,
                  "Mesh objects: auto (the animated blob in gen:office) | none | blob (in the start room)");
  sub->add_flag("--json", args->json, "Print JSON");
  sub->callback([args, &runner] { runner = [args] { return runFramesBench(*args); }; });
}

}  // namespace walkvis
