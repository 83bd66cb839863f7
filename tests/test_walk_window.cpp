// The walkthrough window under a virtual X server (xvfb-run -a): it opens, follows a scripted
// camera path, quits at its end, records the path it showed, and its screenshots (ids style) equal
// the offscreen frames `walkvis render --ids` makes of the same views, pixel for pixel (tolerance:
// 0 differing pixels; both are Mesa's llvmpipe, one through GLX, one through OSMesa, and both
// draw with the same SceneDrawer code). The path ends on the start view, where the animated blob
// (a mesh object, animated on the path's clock in both) must show. Skipped where xvfb-run is missing.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bsp/bsp.h"
#include "command_test_util.h"
#include "png_test_util.h"
#include "scenes/scene.h"
#include "walkthrough/camera_path.h"

namespace walkvis {
namespace {

namespace fs = std::filesystem;

int run(const std::string& command) { return runCommand(command); }

bool haveXvfb() { return run("command -v xvfb-run >/dev/null 2>&1") == 0; }

std::string quote(const std::string& s) { return "'" + s + "'"; }

const std::string kBinary = WALKVIS_BINARY;
const std::string kScene = "gen:office?rooms=12&seed=4";

class WalkWindow : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("walkvis_test_walk_window_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  fs::path dir_;
};

// A tour of the office with some views looking up and down (mouse look), then the start view,
// which shows the animated blob (mesh_object.h) at the key's time: saved as a path file. Returns
// the BSP's fragment count (object ids start there).
uint32_t makePath(const std::string& file, uint32_t frames) {
  const Scene scene = loadScene(kScene);
  const BspTree bsp = buildBsp(scene);
  CameraPath path = automaticTour(scene, bsp, frames, 10.0, 3);
  for (size_t i = 0; i < path.keys.size(); ++i) path.keys[i].pitch = (i % 3 == 1) ? 0.4 : (i % 3 == 2 ? -0.3 : 0.0);
  const double t = path.keys.empty() ? 0.0 : path.keys.back().time + 0.7;
  path.keys.push_back(CameraKey{t, scene.start_eye, scene.start_yaw, -0.1});
  saveCameraPath(path, file);
  return static_cast<uint32_t>(bsp.fragments.size());
}

void compareModes(const fs::path& dir, const std::string& mode, uint32_t frames, uint32_t fragments) {
  SCOPED_TRACE("mode " + mode);
  const std::string path_file = (dir / "path.csv").string();
  const fs::path offscreen = dir / ("render_" + mode), window = dir / ("window_" + mode);
  const std::string record = (dir / ("recorded_" + mode + ".csv")).string();
  const std::string common = " --path " + path_file + " --size 240x160 --ids --mode " + mode;
  ASSERT_EQ(run(kBinary + " render " + quote(kScene) + common + " --out " + offscreen.string() + " >/dev/null 2>&1"),
            0);
  // The window is bounded by a timeout: it must close by itself at the end of the path.
  // In the sanitizer build, leak checking is off for the windowed process only: Mesa's GLX driver
  // is dlclose()d before LeakSanitizer runs, so its leftovers show as "<unknown module>" and no
  // suppression can name them. The same frame and drawing code is leak-checked under OSMesa in
  // test_frame and test_mesh_object.
  const std::string leak_env = std::getenv("WALKVIS_SANITIZER_BUILD") ? "ASAN_OPTIONS=detect_leaks=0 " : "";
  const std::string walk = leak_env + "timeout 120 xvfb-run -a -s '-screen 0 1024x768x24' " + kBinary + " walk " +
                           quote(kScene) + common + " --quit-at-end --screenshot-dir " + window.string() +
                           " --record " + record + " > " + (dir / "walk.log").string() + " 2>&1";
  ASSERT_EQ(run(walk), 0) << "see " << (dir / "walk.log");

  // It showed the path, key for key.
  const CameraPath shown = loadCameraPath(record);
  const CameraPath given = loadCameraPath(path_file);
  ASSERT_EQ(shown.keys.size(), given.keys.size());
  for (size_t i = 0; i < given.keys.size(); ++i) EXPECT_EQ(shown.keys[i].eye, given.keys[i].eye);

  size_t differing = 0, pixels = 0, moved = 0, object_pixels = 0;
  Image previous;
  std::set<uint32_t> ids;
  for (uint32_t k = 0; k < frames; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05u.png", k);
    const Image a = readPng((offscreen / name).string()), b = readPng((window / name).string());
    ASSERT_EQ(a.width, 240) << name;
    ASSERT_EQ(a.height, 160) << name;
    ASSERT_EQ(b.width, a.width) << name;
    ASSERT_EQ(b.height, a.height) << name;
    for (size_t p = 0; p < a.rgb.size(); p += 3) {
      ++pixels;
      if (a.rgb[p] != b.rgb[p] || a.rgb[p + 1] != b.rgb[p + 1] || a.rgb[p + 2] != b.rgb[p + 2]) ++differing;
      ids.insert(uint32_t(a.rgb[p]) << 16 | uint32_t(a.rgb[p + 1]) << 8 | a.rgb[p + 2]);
      // Ids images hold id + 1 little-endian in R, G, B (scene_drawer.h); 0 is nothing.
      const uint32_t v = uint32_t(a.rgb[p]) | uint32_t(a.rgb[p + 1]) << 8 | uint32_t(a.rgb[p + 2]) << 16;
      object_pixels += v != 0 && v - 1 >= fragments;
      if (!previous.rgb.empty() && previous.rgb[p] != a.rgb[p]) ++moved;
    }
    previous = a;
  }
  std::printf("%s: %u frames, %zu pixels, %zu differing, %zu distinct ids\n", mode.c_str(), frames, pixels, differing,
              ids.size());
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(ids.size(), 20u);
  EXPECT_GT(object_pixels, 100u) << "the last key, the start view, shows the blob";
  // The comparison has power: one key's view differs from the next in many pixels.
  EXPECT_GT(moved, pixels / 20);  // the frames show the building, not an empty screen
}

TEST_F(WalkWindow, ScreenshotsEqualOffscreenFrames) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  constexpr uint32_t kFrames = 12;
  const uint32_t fragments = makePath((dir_ / "path.csv").string(), kFrames);
  compareModes(dir_, "bsp", kFrames + 1, fragments);
  compareModes(dir_, "zbuffer", kFrames + 1, fragments);
  compareModes(dir_, "pfd", kFrames + 1, fragments);
}

TEST_F(WalkWindow, BadInputFailsBeforeAnyWindow) {
  // No display needed: these fail while reading the arguments.
  const std::string missing = (dir_ / "missing.csv").string();
  EXPECT_EQ(run(kBinary + " walk gen:office --path " + missing + " > " + (dir_ / "a.log").string() + " 2>&1"), 2);
  EXPECT_EQ(run(kBinary + " walk gen:office --quit-at-end >/dev/null 2>&1"), 2);
  EXPECT_EQ(run(kBinary + " walk gen:office --size 10 >/dev/null 2>&1"), 2);
  EXPECT_EQ(run(kBinary + " walk gen:office --mode fastest >/dev/null 2>&1"), 2);
}

}  // namespace
}  // namespace walkvis
