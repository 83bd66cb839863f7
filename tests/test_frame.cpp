// Walkthrough frames: the offscreen drawer's readback is not blank, the four order modes draw the
// same ids image on gen:office's height plane (painter's against a 24-bit z-buffer), `walkvis
// render` writes N PNGs and a CSV, and a bad path file is named with exit status 2.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <random>
#include <set>

#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include "walkthrough/camera_path.h"
#include "walkthrough/frame.h"
#include "walkthrough/osmesa_context.h"
#include "walkthrough/scene_drawer.h"
#include "frame_test_util.h"

namespace walkvis {
namespace {

// Random eyes on the lowest level's height plane inside its walkable region, random yaw.
std::vector<FreeCamera> officeCameras(const World& world, int count, uint64_t seed) {
  std::vector<FreeCamera> cameras;
  const PfdLevel& level = world.trees.levels.at(0);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> yaw(-3.14159, 3.14159);
  uint64_t state = seed;
  for (int k = 0; k < count; ++k) {
    const PfdTree& tree = level.cells[k % level.cells.size()];
    const glm::dvec2 p = samplePfdRegion(tree, state);
    FreeCamera c;
    c.eye = {p.x, level.height, p.y};
    c.yaw = yaw(rng);
    c.width = kW;
    c.height = kH;
    cameras.push_back(c);
  }
  return cameras;
}

// `kept` is `all` with some fragments taken out in the same order, and draws the same ids image.
void expectKeptDrawsTheSame(Offscreen& o, const FreeCamera& camera, const DrawSettings& settings,
                            const std::vector<uint32_t>& kept, const std::vector<uint32_t>& all,
                            const std::string& what) {
  size_t at = 0;
  for (uint32_t f : all)
    if (at < kept.size() && kept[at] == f) ++at;
  EXPECT_EQ(at, kept.size()) << what << ": not a subsequence";
  std::vector<uint32_t> kept_ids, all_ids;
  o.drawer.draw(camera, kept, settings);
  o.drawer.readIds(kW, kH, kept_ids);
  o.drawer.draw(camera, all, settings);
  o.drawer.readIds(kW, kH, all_ids);
  size_t differing = 0;
  for (size_t p = 0; p < all_ids.size(); ++p) differing += kept_ids[p] != all_ids[p];
  EXPECT_EQ(differing, 0u) << what << " at yaw " << camera.yaw << ", pitch " << camera.pitch;
}

TEST(SceneDrawer, ReadbackIsNotBlank) {
  Offscreen o = makeOffscreen();
  const World& world = office();
  o.drawer.upload(world.trees.bsp, world.scene);
  FrameBuilder builder;
  std::vector<uint32_t> draw;
  FreeCamera camera = officeCameras(world, 1, 3)[0];
  builder.build(world, camera, OrderMode::kBsp, draw);
  ASSERT_FALSE(draw.empty());
  DrawSettings settings;
  o.drawer.draw(camera, draw, settings);
  std::vector<uint8_t> rgb;
  o.drawer.readRgb(kW, kH, rgb);
  ASSERT_EQ(rgb.size(), size_t(kW) * kH * 3);
  std::set<uint32_t> colours;
  for (size_t p = 0; p < rgb.size(); p += 3) colours.insert(uint32_t(rgb[p]) << 16 | uint32_t(rgb[p + 1]) << 8 | rgb[p + 2]);
  EXPECT_GT(colours.size(), 3u) << "a shaded office view shows several colours";
  // Nothing drawn: every id is kNoFragment.
  settings.style = DrawStyle::kIds;
  o.drawer.draw(camera, {}, settings);
  std::vector<uint32_t> ids;
  o.drawer.readIds(kW, kH, ids);
  EXPECT_EQ(std::count(ids.begin(), ids.end(), kNoFragment), kW * kH);
}

TEST(FrameBuilder, FourModesDrawTheSameIdsImage) {
  Offscreen o = makeOffscreen();
  const World& world = office();
  ASSERT_FALSE(world.trees.levels.empty());
  o.drawer.upload(world.trees.bsp, world.scene);
  FrameBuilder builder;
  std::vector<uint32_t> draw, truth, ids;
  uint64_t differing = 0, pixels = 0, tree_frames = 0;
  for (const FreeCamera& camera : officeCameras(world, 12, 7)) {
    DrawSettings z;
    z.style = DrawStyle::kIds;
    z.depth_test = true;
    z.cull_back_faces = true;
    const FrameStats zs = builder.build(world, camera, OrderMode::kZBuffer, draw);
    EXPECT_EQ(zs.listed, world.trees.bsp.fragments.size());
    o.drawer.draw(camera, draw, z);
    o.drawer.readIds(kW, kH, truth);
    EXPECT_LT(std::count(truth.begin(), truth.end(), kNoFragment), kW * kH) << "inside the office something shows";
    for (OrderMode mode : {OrderMode::kBsp, OrderMode::kPfd, OrderMode::kHfd}) {
      const FrameStats s = builder.build(world, camera, mode, draw);
      EXPECT_EQ(s.drawn, draw.size());
      EXPECT_EQ(s.listed, s.drawn + s.culled + s.outside + s.occluded);
      if (mode != OrderMode::kBsp) {
        EXPECT_EQ(s.used, mode) << "the eye is on the height plane inside the region";
        EXPECT_EQ(s.level, 0);
        tree_frames += s.used == mode;
      }
      DrawSettings p;
      p.style = DrawStyle::kIds;
      o.drawer.draw(camera, draw, p);
      o.drawer.readIds(kW, kH, ids);
      for (size_t k = 0; k < ids.size(); ++k) differing += ids[k] != truth[k];
      pixels += ids.size();
    }
  }
  EXPECT_EQ(tree_frames, 24u);
  // Same triangles, same float positions: only z-buffer depth ties (coplanar surfaces at 24 bits)
  // may differ. Tolerance: 0.1% of the pixels compared.
  EXPECT_LE(differing, pixels / 1000) << differing << " of " << pixels << " pixels differ";
}

// Frustum culling (World::frustum_culling) leaves out only what GL would clip: in every mode the ids
// image is bit-identical with and without it, the list is the unculled list with some fragments
// taken out (order kept), and it takes out many, also for cameras looking up and down.
TEST(FrameBuilder, FrustumCullingKeepsTheImage) {
  Offscreen o = makeOffscreen();
  WorldOptions options;
  options.build_pfd = true;
  options.cull = ListCullMethod::kRegion;
  World world = openWorld("gen:office", options);
  world.occlusion_culling = false;  // the frustum alone
  o.drawer.upload(world.trees.bsp, world.scene);
  FrameBuilder builder;
  std::vector<uint32_t> culled, all;
  uint64_t outside = 0, listed = 0;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> pitch(-1.2, 1.2);
  for (FreeCamera camera : officeCameras(world, 12, 9)) {
    camera.pitch = pitch(rng);
    for (OrderMode mode : {OrderMode::kZBuffer, OrderMode::kBsp, OrderMode::kPfd, OrderMode::kHfd}) {
      DrawSettings settings;
      settings.style = DrawStyle::kIds;
      settings.depth_test = mode == OrderMode::kZBuffer;
      settings.cull_back_faces = mode == OrderMode::kZBuffer;
      world.frustum_culling = true;
      const FrameStats s = builder.build(world, camera, mode, culled);
      world.frustum_culling = false;
      const FrameStats u = builder.build(world, camera, mode, all);
      EXPECT_EQ(u.outside, 0u);
      EXPECT_EQ(s.listed, u.listed);
      EXPECT_EQ(s.drawn + s.outside, u.drawn);
      outside += s.outside;
      listed += s.listed;
      expectKeptDrawsTheSame(o, camera, settings, culled, all, std::string(orderModeName(mode)));
    }
  }
  std::printf("%llu of %llu listed fragments outside the view\n", static_cast<unsigned long long>(outside),
              static_cast<unsigned long long>(listed));
  EXPECT_GT(outside, listed / 4) << "a 70-degree view leaves out much of what the order lists";
}

// Occlusion culling (World::occlusion_culling) leaves out only what the painter's order paints
// over: in the painter's modes the ids image is bit-identical with and without it, the list is the
// unoccluded list with some fragments taken out (order kept), and it takes out many; on the
// furnished office and on a room grid, for cameras looking up and down, at two cell sizes.
TEST(FrameBuilder, OcclusionCullingKeepsTheImage) {
  Offscreen o = makeOffscreen();
  WorldOptions options;
  options.build_pfd = true;
  options.cull = ListCullMethod::kRegion;
  options.objects = ObjectSet::kNone;
  uint64_t occluded = 0, drawn = 0, frames = 0;
  for (const char* spec : {"gen:office?rooms=12&furniture=4", "gen:office?rooms=6"}) {
    World world = openWorld(spec, options);
    o.drawer.upload(world.trees.bsp, world.scene);
    FrameBuilder builder;
    std::vector<uint32_t> kept, all;
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> pitch(-1.0, 1.0);
    int k = 0;
    for (FreeCamera camera : officeCameras(world, 10, 21)) {
      camera.pitch = pitch(rng);
      world.occlusion.cell_pixels = k++ % 2 ? 8 : 3;
      world.occlusion.max_rest_frames = 0;  // the buffer on every frame; pacing has its own test
      for (OrderMode mode : {OrderMode::kBsp, OrderMode::kPfd, OrderMode::kHfd}) {
        DrawSettings settings;
        settings.style = DrawStyle::kIds;
        world.occlusion_culling = true;
        const FrameStats s = builder.build(world, camera, mode, kept);
        world.occlusion_culling = false;
        const FrameStats u = builder.build(world, camera, mode, all);
        EXPECT_EQ(u.occluded, 0u);
        EXPECT_EQ(s.listed, u.listed);
        EXPECT_EQ(s.drawn + s.occluded, u.drawn);
        occluded += s.occluded;
        drawn += u.drawn;
        ++frames;
        expectKeptDrawsTheSame(o, camera, settings, kept, all, std::string(spec) + " " + std::string(orderModeName(mode)));
      }
    }
  }
  std::printf("%llu of %llu fragments in view occluded over %llu frames\n", static_cast<unsigned long long>(occluded),
              static_cast<unsigned long long>(drawn), static_cast<unsigned long long>(frames));
  EXPECT_GT(occluded, drawn / 10) << "inside a room most of the building lies behind its walls";
}

// Occlusion culling's pacing (OcclusionOptions): along a tour, each test whose occluded fragments
// reach fewer than min_occluded_pixels makes the mode rest for the next 1, 2, 4 ... frames, at most
// max_rest_frames, and one that leaves out more sets the rest back to 1; a resting frame draws the
// list without occlusion culling; max_rest_frames 0 never rests.
TEST(FrameBuilder, OcclusionPacingRestsAfterTestsThatFindLittle) {
  WorldOptions options;
  options.build_pfd = true;
  options.cull = ListCullMethod::kRegion;
  options.objects = ObjectSet::kNone;
  World world = openWorld("gen:office?rooms=12&furniture=4", options);
  const CameraPath tour = automaticTour(world.scene, world.trees.bsp, 150);
  ASSERT_GT(tour.keys.size(), 100u);
  for (const uint32_t min_occluded : {0u, 4096u, 1000000000u}) {
    for (const uint32_t most : {0u, 8u}) {
      world.occlusion.min_occluded_pixels = min_occluded;
      world.occlusion.max_rest_frames = most;
      FrameBuilder builder;
      std::vector<uint32_t> kept, all;
      uint32_t expected_rest = 0, next_rest = 1, rested = 0, tested = 0, short_tests = 0;
      for (const CameraKey& key : tour.keys) {
        FreeCamera camera;
        camera.eye = key.eye;
        camera.yaw = key.yaw;
        camera.width = kW;
        camera.height = kH;
        world.occlusion_culling = true;
        const FrameStats s = builder.build(world, camera, OrderMode::kPfd, kept);
        world.occlusion_culling = false;  // does not touch the pacing
        builder.build(world, camera, OrderMode::kPfd, all);
        ASSERT_EQ(s.occlusion_rested, expected_rest > 0) << "min " << min_occluded << " most " << most;
        if (s.occlusion_rested) {
          --expected_rest;
          ++rested;
          EXPECT_EQ(s.occluded, 0u);
          EXPECT_EQ(kept, all);
          continue;
        }
        ++tested;
        EXPECT_EQ(s.occluded > 0, s.occluded_pixels > 0);
        if (s.occluded_pixels < min_occluded) {
          ++short_tests;
          expected_rest = std::min(next_rest, most);
          next_rest = std::min(2 * next_rest, std::max(most, 1u));
        } else {
          next_rest = 1;
        }
      }
      if (most == 0 || min_occluded == 0) {
        EXPECT_EQ(rested, 0u) << "min " << min_occluded << " most " << most;
      } else {
        EXPECT_GT(short_tests, 0u) << "min " << min_occluded;
        EXPECT_GT(rested, 0u) << "min " << min_occluded;
      }
      if (min_occluded == 1000000000u && most == 8) {
        // Every test finds little: rests of 1, 2, 4, then 8 frames, so nearly 8 frames in 9 rest.
        EXPECT_GT(rested, 6 * tested) << rested << " rested, " << tested << " tested";
      }
    }
  }
}

// The normal mask culls from the view cone through the image's corners (list_cull.h): it may drop
// front faces, but only ones wholly outside that cone, which the frustum clips away. So with it the
// three order sources draw exactly the ids image of the exact plane test (GL back-face culling on
// in both: the mask leaves some back faces in), for cameras looking up and down as well as level.
TEST(FrameBuilder, MaskDrawsWhatThePlaneTestDraws) {
  Offscreen o = makeOffscreen();
  // A small office without the blob: two worlds are built (ASan runs these tests too).
  WorldOptions options;
  options.build_pfd = true;
  options.objects = ObjectSet::kNone;
  options.cull = ListCullMethod::kMask;
  const World mask_world = openWorld("gen:office?rooms=8", options);
  options.cull = ListCullMethod::kPolygon;
  const World plane_world = openWorld("gen:office?rooms=8", options);
  o.drawer.upload(mask_world.trees.bsp, mask_world.scene);
  FrameBuilder builder;
  std::vector<uint32_t> draw, want, got;
  uint64_t differing = 0, mask_culled = 0, plane_culled = 0;
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> pitch(-0.7, 0.7);
  DrawSettings z;
  z.style = DrawStyle::kIds;
  z.cull_back_faces = true;
  for (FreeCamera camera : officeCameras(mask_world, 16, 29)) {
    camera.pitch = pitch(rng);
    for (OrderMode mode : {OrderMode::kZBuffer, OrderMode::kBsp, OrderMode::kPfd}) {
      z.depth_test = mode == OrderMode::kZBuffer;
      plane_culled += builder.build(plane_world, camera, mode, draw).culled;
      o.drawer.draw(camera, draw, z);
      o.drawer.readIds(kW, kH, want);
      const FrameStats s = builder.build(mask_world, camera, mode, draw);
      EXPECT_EQ(s.used, mode);
      mask_culled += s.culled;
      o.drawer.draw(camera, draw, z);
      o.drawer.readIds(kW, kH, got);
      for (size_t k = 0; k < got.size(); ++k) differing += got[k] != want[k];
    }
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(mask_culled, plane_culled / 10) << "the mask culls a real share";
  RecordProperty("mask_culled", std::to_string(mask_culled));
  RecordProperty("plane_culled", std::to_string(plane_culled));
}

TEST(FrameBuilder, WrongOrderIsCaught) {
  // The check above can fail: drawing the BSP order reversed (front to back) differs a lot.
  Offscreen o = makeOffscreen();
  const World& world = office();
  o.drawer.upload(world.trees.bsp, world.scene);
  FrameBuilder builder;
  std::vector<uint32_t> draw, truth, ids;
  const FreeCamera camera = officeCameras(world, 1, 11)[0];
  builder.build(world, camera, OrderMode::kZBuffer, draw);
  DrawSettings z;
  z.style = DrawStyle::kIds;
  z.depth_test = z.cull_back_faces = true;
  o.drawer.draw(camera, draw, z);
  o.drawer.readIds(kW, kH, truth);
  builder.build(world, camera, OrderMode::kBsp, draw);
  std::reverse(draw.begin(), draw.end());
  DrawSettings p;
  p.style = DrawStyle::kIds;
  o.drawer.draw(camera, draw, p);
  o.drawer.readIds(kW, kH, ids);
  size_t differing = 0;
  for (size_t k = 0; k < ids.size(); ++k) differing += ids[k] != truth[k];
  EXPECT_GT(differing, ids.size() / 100);
}

int run(const std::string& args) { return std::system((std::string(WALKVIS_BINARY) + " " + args).c_str()); }

TEST(RenderCommand, WritesFramesAndCsv) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("walkvis_test_render_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const int status = run("render gen:office --frames 5 --size 64x48 --mode pfd --out " + dir.string() +
                         " > /dev/null 2>&1");
  ASSERT_EQ(status, 0);
  for (int k = 0; k < 5; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", k);
    EXPECT_TRUE(std::filesystem::exists(dir / name)) << name;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "frame_00005.png"));
  std::ifstream csv(dir / "frames.csv");
  std::string line;
  int lines = 0;
  std::getline(csv, line);
  EXPECT_EQ(line.rfind("frame,time,x,y,z,yaw,pitch,frame_ms", 0), 0u) << line;
  while (std::getline(csv, line)) ++lines;
  EXPECT_EQ(lines, 5);
  std::filesystem::remove_all(dir);
}

TEST(RenderCommand, BadPathFileIsNamed) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("walkvis_test_render_bad_" + std::to_string(::getpid()));
  const std::filesystem::path bad = std::filesystem::temp_directory_path() / ("walkvis_bad_path_" + std::to_string(::getpid()) + ".csv");
  { std::ofstream(bad) << "time,x,y,z,yaw,pitch\n0,1,2,oops,0,0\n"; }
  const std::filesystem::path err = std::filesystem::temp_directory_path() / ("walkvis_bad_path_" + std::to_string(::getpid()) + ".err");
  const int status = run("render gen:office --path " + bad.string() + " --out " + dir.string() + " 2> " + err.string());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream in(err);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find(bad.string()), std::string::npos) << text;
  std::filesystem::remove(bad);
  std::filesystem::remove(err);
  std::filesystem::remove_all(dir);
}

nlohmann::json benchFramesJson(const std::string& args, const std::filesystem::path& out) {
  EXPECT_EQ(run("bench frames " + args + " --json > " + out.string() + " 2> /dev/null"), 0) << args;
  std::ifstream in(out);
  return nlohmann::json::parse(in, nullptr, false);
}

// The floor (nothing drawn) and the ideal (exactly what the z-buffer shows) frame every mode: the
// ideal draws no more than any painter's mode, its image is the z-buffer's, and the fractions are
// the ratios of the medians printed beside them.
TEST(BenchFrames, FloorAndIdealFrameEveryMode) {
  const auto tmp = std::filesystem::temp_directory_path();
  const std::string id = std::to_string(::getpid());
  const std::filesystem::path tree = tmp / ("walkvis_test_bench_frames_" + id + ".wvt");
  const std::filesystem::path json = tmp / ("walkvis_test_bench_frames_" + id + ".json");
  ASSERT_EQ(run("build gen:table_room --tree hfd -o " + tree.string() + " > /dev/null 2>&1"), 0);
  // The tree file alone: no scene, so the tour starts where sceneFromTrees puts it.
  const nlohmann::json j = benchFramesJson(tree.string() + " --frames 8 --rounds 2 --check-every 2 --size 96x72", json);
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j["rounds"], 2);
  EXPECT_EQ(j["occlusion_culling"], true);
  const double floor_ms = j["floor_ms_median"], ideal_ms = j["ideal_ms_median"];
  EXPECT_GT(floor_ms, 0.0);
  EXPECT_GE(ideal_ms, 0.0);
  const double ideal_drawn = j["ideal_drawn_median"];
  EXPECT_GT(ideal_drawn, 0.0);
  const double checked_pixels = 4.0 * 96 * 72;
  bool saw_hfd = false, saw_ideal = false;
  for (const auto& m : j["modes"]) {
    const std::string mode = m["mode"];
    const double ms = m["frame_ms_median"];
    if (ms > 0.0) {
      EXPECT_NEAR(m["ideal_fraction"].get<double>(), ideal_ms / ms, 1e-9) << mode;
    }
    if (mode == "floor") {
      EXPECT_EQ(m["drawn_median"], 0.0);
      EXPECT_EQ(m["pixels_differing_from_zbuffer"], 0);
      continue;
    }
    if (mode == "ideal") {
      saw_ideal = true;
      // Paired frame by frame with itself: every ratio is 1.
      EXPECT_EQ(m["ideal_fraction_paired"].get<double>(), 1.0);
      EXPECT_EQ(m["ideal_fraction_paired_halves"], nlohmann::json::array({1.0, 1.0}));
    } else {
      EXPECT_GT(m["ideal_fraction_paired"].get<double>(), 0.0) << mode;
      EXPECT_EQ(m["ideal_fraction_paired_halves"].size(), 2u) << mode;
    }
    EXPECT_GE(m["outside_median"].get<double>(), 0.0) << mode;
    // Occlusion culling is the painter's modes' own: the baseline and the ideal draw what the
    // frustum holds.
    if (mode == "zbuffer" || mode == "ideal") {
      EXPECT_EQ(m["occluded_median"], 0.0) << mode;
    }
    if (mode != "zbuffer" && mode != "ideal") {
      EXPECT_LE(ideal_drawn, m["drawn_median"].get<double>()) << mode;
    }
    // Painter's order over exactly the visible fragments (or the HFD's lists): the same image
    // as the z-buffer but for edge and tie pixels and the HFD's sampled misses, a few in a
    // thousand at most. A start eye on a wall's plane once left a third of the image wrong.
    EXPECT_LE(m["pixels_differing_from_zbuffer"].get<double>(), 0.005 * checked_pixels) << mode;
    if (mode.rfind("hfd", 0) == 0) saw_hfd = true;
  }
  EXPECT_TRUE(saw_hfd);
  EXPECT_TRUE(saw_ideal);
  std::filesystem::remove(tree);
  std::filesystem::remove(json);
}

// A tree file alone (no scene) starts its walk strictly inside a region, on the level's height
// plane. On freedoom2 MAP01's level 22 the start was the origin, which lies on the edge of a
// region piece in the plane of a wall: the HFD tree's list there left a third of the image wrong.
TEST(BenchFrames, TreeFileAloneStartsInsideARegion) {
  const std::string wad = "/usr/share/games/doom/freedoom2.wad";
  if (!std::filesystem::exists(wad)) GTEST_SKIP() << wad << " not installed";
  const std::filesystem::path tree =
      std::filesystem::temp_directory_path() / ("walkvis_test_start_" + std::to_string(::getpid()) + ".wvt");
  ASSERT_EQ(run("build " + wad + ":MAP01 --tree pfd --levels 22 -o " + tree.string() + " > /dev/null 2>&1"), 0);
  const World world = openWorld(tree.string(), WorldOptions{}, nullptr);
  const glm::dvec3 start = world.scene.start_eye;
  const std::optional<uint32_t> level = world.levelAt(start);
  ASSERT_TRUE(level.has_value()) << start.x << " " << start.y << " " << start.z;
  const PfdTree* cell = findPfdCell(world.trees.levels[*level], start);
  ASSERT_NE(cell, nullptr);
  EXPECT_TRUE(strictlyInsidePfdRegion(*cell, start)) << start.x << " " << start.z;
  std::filesystem::remove(tree);
}

}  // namespace
}  // namespace walkvis
