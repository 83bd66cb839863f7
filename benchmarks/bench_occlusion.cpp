// What occlusion culling of a frame costs on the CPU (walkthrough/occlusion_buffer.h;
// docs/DESIGN.md, "Occlusion culling of a frame"): FrameBuilder::build over the automatic tour of a
// scene, without the occlusion buffer (cell:0) and with it at cells of 4, 8 and 16 pixels, tested
// on every frame (no pacing). The lists are a PFD tree's, built in memory (those of the exact
// priority order), or with --tree those of an HFD tree file. Counters: occluded and drawn per
// frame. Its price in a whole frame, against what GL then does not draw, is `walkvis bench frames`
// (docs/frames/).
//
//   bench_occlusion [--scene=gen:office] [--tree=FILE] [--frames=120] [google benchmark flags]
#include <benchmark/benchmark.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "walkthrough/camera_path.h"
#include "walkthrough/frame.h"

namespace walkvis {
namespace {

struct Setup {
  World world;
  std::vector<FreeCamera> cameras;
};

// With a tree file (`walkvis build SCENE --tree hfd`), its lists and the hfd mode; else PFD trees
// built in memory for the scene.
Setup makeSetup(const std::string& scene, const std::string& tree, uint32_t frames) {
  WorldOptions options;
  options.build_pfd = tree.empty();
  options.scene = tree.empty() ? "" : scene;
  options.cull = ListCullMethod::kRegion;
  options.objects = ObjectSet::kNone;
  Setup s{openWorld(tree.empty() ? scene : tree, options), {}};
  for (const CameraKey& key : automaticTour(s.world.scene, s.world.trees.bsp, frames).keys) {
    FreeCamera c;
    c.eye = key.eye;
    c.yaw = key.yaw;
    c.pitch = key.pitch;
    c.width = 320;
    c.height = 240;
    s.cameras.push_back(c);
  }
  return s;
}

void frames(benchmark::State& state, Setup* s, OrderMode mode, int cell_pixels) {
  s->world.occlusion_culling = cell_pixels > 0;
  if (cell_pixels > 0) s->world.occlusion.cell_pixels = cell_pixels;
  s->world.occlusion.max_rest_frames = 0;  // the buffer's cost on every frame, not its pacing
  FrameBuilder builder;
  std::vector<uint32_t> draw;
  size_t k = 0;
  double occluded = 0.0, drawn = 0.0, count = 0.0;
  for (auto _ : state) {
    const FrameStats st = builder.build(s->world, s->cameras[k], mode, draw);
    benchmark::DoNotOptimize(draw.data());
    occluded += st.occluded;
    drawn += st.drawn;
    count += 1.0;
    k = (k + 1) % s->cameras.size();
  }
  state.counters["occluded"] = occluded / count;
  state.counters["drawn"] = drawn / count;
}

}  // namespace
}  // namespace walkvis

int main(int argc, char** argv) {
  std::string scene = "gen:office", tree;
  uint32_t frame_count = 120;
  std::vector<char*> rest;
  for (int i = 0; i < argc; ++i) {
    if (std::strncmp(argv[i], "--scene=", 8) == 0) {
      scene = argv[i] + 8;
    } else if (std::strncmp(argv[i], "--tree=", 7) == 0) {
      tree = argv[i] + 7;
    } else if (std::strncmp(argv[i], "--frames=", 9) == 0) {
      frame_count = static_cast<uint32_t>(std::stoul(argv[i] + 9));
    } else {
      rest.push_back(argv[i]);
    }
  }
  int rest_count = static_cast<int>(rest.size());
  benchmark::Initialize(&rest_count, rest.data());
  auto setup = std::make_unique<walkvis::Setup>(walkvis::makeSetup(scene, tree, frame_count));
  if (setup->cameras.empty()) return 2;
  const auto listed = tree.empty() ? walkvis::OrderMode::kPfd : walkvis::OrderMode::kHfd;
  for (auto mode : {listed, walkvis::OrderMode::kBsp})
    for (int cell : {0, 4, 8, 16})
      benchmark::RegisterBenchmark(
          (std::string(walkvis::orderModeName(mode)) + "/cell:" + std::to_string(cell)).c_str(),
          [&, mode, cell](benchmark::State& st) { walkvis::frames(st, setup.get(), mode, cell); });
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
