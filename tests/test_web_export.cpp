// `walkvis export FILE --web DIR` and the page it writes (walkthrough/web_export.h, docs/web/README.md):
//  - the folder is whole (walkvis.bin, one file per view cell) and the same bytes every time; bad
//    sources fail before writing anything;
//  - the viewer's ported rules (viewer.js under Node) give the C++ library's frame orders, walker
//    moves and placements on an office cut into several view cells and on a house with a stair;
//  - headless Chromium (SwiftShader WebGL2) draws 24 tour frames whose ids images equal
//    `walkvis render --ids` of the same keys, with no console errors. Tolerance: a differing pixel
//    must be an edge pixel of the reference (its 3×3 neighbourhood holds two ids or more: the two
//    rasterisers may round an edge differently), and at most 1% of all pixels may differ;
//  - served, the page fetches only the view cell its eye stands in; until a cell is in it draws the
//    BSP order, whose ids images equal `walkvis render --mode bsp --ids`;
//  - a truncated or corrupted export or view cell shows one clear message on the page, not a
//    blank canvas.
// Node and Chromium steps are skipped where those are missing (scripts/install-deps installs both).
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "command_test_util.h"
#include "core/byte_io.h"
#include "core/hash.h"
#include "core/rng.h"
#include "png_test_util.h"
#include "walkthrough/frame.h"
#include "walkthrough/movement.h"
#include "walkthrough/web_export.h"

namespace walkvis {
namespace {

namespace fs = std::filesystem;

const std::string kBinary = WALKVIS_BINARY;
const std::string kOffice = "gen:office?rooms=12&seed=4";
const std::string kHouse = "gen:house";
constexpr int kWidth = 160, kHeight = 120;

int run(const std::string& command) { return runCommand(command); }
std::string quote(const std::string& s) { return "'" + s + "'"; }
bool have(const char* tool) { return run(std::string("command -v ") + tool + " > /dev/null 2>&1") == 0; }

// An export's binaries: walkvis.bin and every cells/K.bin, in bytes.
uint64_t binaryBytes(const fs::path& web) {
  uint64_t total = fs::file_size(web / "walkvis.bin");
  for (const auto& e : fs::directory_iterator(web / "cells"))
    if (e.path().extension() == ".bin") total += fs::file_size(e.path());
  return total;
}

// The view cells of a tree file, all levels together.
size_t viewCells(const fs::path& tree) {
  WorldOptions options;
  options.objects = ObjectSet::kNone;
  size_t cells = 0;
  for (const PfdLevel& l : openWorld(tree.string(), options).trees.levels) cells += l.cells.size();
  return cells;
}

std::string chromium(const fs::path& dir) {
  // Headless, software WebGL2 (ANGLE on SwiftShader), no sandbox as root, a profile of its own, one
  // CSS pixel per image pixel and sRGB untouched so that ids survive the screenshot bit-exact.
  return "timeout 120 chromium --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader "
         "--disable-dev-shm-usage --force-device-scale-factor=1 --force-color-profile=srgb --hide-scrollbars "
         "--user-data-dir=" + (dir / "chrome-profile").string() + " ";
}

class WebExport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("walkvis_test_web_export_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // The office cut into several view cells (findCell is part of the port), the house whole.
    build(kOffice, "office", "--cell-memory 16k");
    build(kHouse, "house", "");
  }
  static void TearDownTestSuite() {
    if (!::testing::UnitTest::GetInstance()->Failed()) fs::remove_all(dir_);
  }
  static void build(const std::string& scene, const std::string& name, const std::string& options) {
    const fs::path tree = dir_ / (name + ".hfd"), web = dir_ / name;
    const std::string log = (dir_ / (name + ".log")).string();
    ASSERT_EQ(run(kBinary + " build " + quote(scene) + " --tree hfd " + options + " -o " + tree.string() + " > " + log +
                  " 2>&1"),
              0)
        << readText(log);
    ASSERT_EQ(run(kBinary + " export " + tree.string() + " --scene " + quote(scene) + " --frames 40 --web " +
                  web.string() + " > " + log + " 2>&1"),
              0)
        << readText(log);
  }
  static fs::path dir_;
};
fs::path WebExport::dir_;

TEST_F(WebExport, FolderIsWholeAndReproducible) {
  const fs::path web = dir_ / "office";
  for (const char* f : {"index.html", "viewer.js", "page.js", "walkvis.bin", "walkvis-data.js"})
    EXPECT_TRUE(fs::exists(web / f)) << f;
  for (const fs::path& d : {web, web / "cells"})
    for (const auto& e : fs::directory_iterator(d)) EXPECT_NE(e.path().extension(), ".tmp") << e.path();
  const std::vector<uint8_t> bin = readFileBytes((web / "walkvis.bin").string());
  ASSERT_GE(bin.size(), 40u);
  EXPECT_EQ(std::string(bin.begin(), bin.begin() + 8), "WALKVISW");
  EXPECT_EQ(readText(web / "walkvis-data.js"), webDataScript(bin));
  // One file and one script per view cell of the tree (the office is cut into several), no more.
  const size_t cells = viewCells(dir_ / "office.hfd");
  ASSERT_GT(cells, 3u);
  EXPECT_EQ(static_cast<size_t>(std::distance(fs::directory_iterator(web / "cells"), fs::directory_iterator())),
            2 * cells);
  std::vector<std::vector<uint8_t>> cell_bytes;
  for (uint32_t k = 0; k < cells; ++k) {
    cell_bytes.push_back(readFileBytes((web / "cells" / (std::to_string(k) + ".bin")).string()));
    EXPECT_EQ(std::string(cell_bytes.back().begin(), cell_bytes.back().begin() + 8), "WALKVISW") << k;
    EXPECT_EQ(readText(web / "cells" / (std::to_string(k) + ".js")), webCellScript(k, cell_bytes.back())) << k;
  }
  // The same bytes from a second run, into a folder that holds cells of a larger export: those go.
  const fs::path again = dir_ / "office_again";
  fs::create_directories(again / "cells");
  for (const char* f : {"99.bin", "99.js"}) writeTextFileAtomically((again / "cells" / f).string(), "old", "test");
  writeTextFileAtomically((again / "cells" / "notes.txt").string(), "not ours", "test");
  ASSERT_EQ(run(kBinary + " export " + (dir_ / "office.hfd").string() + " --scene " + quote(kOffice) +
                " --frames 40 --web " + again.string() + " > /dev/null 2>&1"),
            0);
  EXPECT_EQ(readFileBytes((again / "walkvis.bin").string()), bin);
  for (uint32_t k = 0; k < cells; ++k)
    EXPECT_EQ(readFileBytes((again / "cells" / (std::to_string(k) + ".bin")).string()), cell_bytes[k]) << k;
  EXPECT_FALSE(fs::exists(again / "cells" / "99.bin"));
  EXPECT_FALSE(fs::exists(again / "cells" / "99.js"));
  EXPECT_TRUE(fs::exists(again / "cells" / "notes.txt")) << "only cell files are removed";
  // The page names no network address.
  for (const char* f : {"index.html", "viewer.js", "page.js"})
    EXPECT_EQ(readText(web / f).find("http"), std::string::npos) << f;
}

TEST_F(WebExport, BadSourcesFailBeforeWriting) {
  const fs::path out = dir_ / "bad_out";
  const std::string err = (dir_ / "bad.err").string();
  // A scene, not a tree file.
  EXPECT_EQ(run(kBinary + " export " + quote(kOffice) + " --web " + out.string() + " 2> " + err), 2);
  EXPECT_NE(readText(err).find("not a tree file"), std::string::npos) << readText(err);
  // A PFD tree file.
  const fs::path pfd = dir_ / "office.pfd";
  ASSERT_EQ(run(kBinary + " build " + quote(kOffice) + " --tree pfd -o " + pfd.string() + " > /dev/null 2>&1"), 0);
  EXPECT_EQ(run(kBinary + " export " + pfd.string() + " --web " + out.string() + " 2> " + err), 2);
  EXPECT_NE(readText(err).find("--tree hfd"), std::string::npos) << readText(err);
  // A truncated tree file.
  const std::vector<uint8_t> tree = readFileBytes((dir_ / "office.hfd").string());
  const fs::path cut = dir_ / "cut.hfd";
  writeFileAtomically(cut.string(), std::span(tree.data(), tree.size() / 2), "test");
  EXPECT_EQ(run(kBinary + " export " + cut.string() + " --web " + out.string() + " 2> " + err), 2);
  EXPECT_NE(readText(err).find(cut.string()), std::string::npos) << readText(err);
  EXPECT_FALSE(fs::exists(out / "walkvis.bin"));
}

// The C++ answers the port must reproduce, written as JSON for tests/web/parity.js.
nlohmann::json expectedAnswers(const std::string& tree, const std::string& scene_spec) {
  WorldOptions options;
  options.scene = scene_spec;
  options.objects = ObjectSet::kNone;
  World world = openWorld(tree, options);
  // The orders themselves: the viewer leaves what lies outside the view to WebGL's clipping and
  // what lies behind nearer fragments to the painter's order.
  world.frustum_culling = false;
  world.occlusion_culling = false;
  const Walker walker(world.scene, world.trees.bsp);
  FrameBuilder builder;
  std::vector<uint32_t> draw;
  nlohmann::json out;
  const Bounds b = sceneBounds(world.scene);
  out["scale"] = std::max({std::abs(b.lo.x), std::abs(b.lo.y), std::abs(b.lo.z), std::abs(b.hi.x),
                           std::abs(b.hi.y), std::abs(b.hi.z)});
  uint64_t rng = 7;
  auto order = [&](const glm::dvec3& eye) {
    FreeCamera camera;
    camera.eye = eye;
    const FrameStats s = builder.build(world, camera, OrderMode::kHfd, draw);
    out["orders"].push_back({{"eye", {eye.x, eye.y, eye.z}}, {"ids", draw}, {"used", orderModeName(s.used)}});
  };
  for (const PfdLevel& level : world.trees.levels)
    for (int k = 0; k < 150; ++k)
      if (const auto eye = samplePfdLevel(level, rng)) {
        order(*eye);
        if (k % 5 == 0) order(*eye + glm::dvec3(0.0, 0.37 * world.scene.eye_height, 0.0));  // off the plane
      }
  // Walks: random headings and step lengths from the start, each move recorded from its state.
  WalkState state = walker.place(world.scene.start_eye);
  out["moves"] = nlohmann::json::array();
  for (int k = 0; k < 1500; ++k) {
    const double heading = 6.283185307179586 * uniform01(rng);
    const double length = world.scene.eye_height * (k % 7 == 0 ? 1.5 : 0.25) * uniform01(rng);
    const glm::dvec2 d(length * std::sin(heading), length * std::cos(heading));
    const WalkState to = walker.move(state, d);
    out["moves"].push_back({{"from", {{"eye", {state.eye.x, state.eye.y, state.eye.z}}, {"level", state.level}}},
                            {"d", {d.x, d.y}},
                            {"to", {{"eye", {to.eye.x, to.eye.y, to.eye.z}}, {"level", to.level}}}});
    state = to;
    if (k % 300 == 299) state = walker.place(world.scene.start_eye);
    // Now and then restart on a stair patch, so that the walks step onto and off connections.
    if (k % 10 == 9 && !world.scene.connections.empty()) {
      const auto& patches = world.scene.connections[splitmix64(rng) % world.scene.connections.size()].patches;
      if (!patches.empty()) {
        const WalkablePatch& p = patches[splitmix64(rng) % patches.size()];
        glm::dvec2 c(0.0);
        for (const glm::dvec2& v : p.piece) c += v / static_cast<double>(p.piece.size());
        const double y = (p.plane.d - p.plane.n.x * c.x - p.plane.n.z * c.y) / p.plane.n.y;
        state = walker.place(glm::dvec3(c.x, y + world.scene.eye_height, c.y));
      }
    }
  }
  out["places"] = nlohmann::json::array();
  for (int k = 0; k < 200; ++k) {
    const glm::dvec3 eye(b.lo.x + (b.hi.x - b.lo.x) * uniform01(rng), b.lo.y + (b.hi.y - b.lo.y) * uniform01(rng),
                         b.lo.z + (b.hi.z - b.lo.z) * uniform01(rng));
    const WalkState to = walker.place(eye);
    out["places"].push_back({{"eye", {eye.x, eye.y, eye.z}}, {"to", {{"eye", {to.eye.x, to.eye.y, to.eye.z}}, {"level", to.level}}}});
  }
  return out;
}

TEST_F(WebExport, ViewerRulesEqualTheLibrary) {
  if (!have("node")) GTEST_SKIP() << "node is not installed";
  for (const auto& [name, spec] : {std::pair{std::string("office"), kOffice}, std::pair{std::string("house"), kHouse}}) {
    SCOPED_TRACE(name);
    const nlohmann::json expected = expectedAnswers((dir_ / (name + ".hfd")).string(), spec);
    size_t level_changes = 0, hfd = 0;
    for (const auto& m : expected["moves"]) level_changes += m["from"]["level"] != m["to"]["level"];
    for (const auto& o : expected["orders"]) hfd += o["used"] == "hfd";
    EXPECT_GT(hfd, 100u);
    EXPECT_LT(hfd, expected["orders"].size()) << "some eyes must take the BSP order";
    if (name == "house") {
      EXPECT_GT(level_changes, 20u) << "the walks must use the stair";
    }
    const fs::path file = dir_ / (name + "_expected.json");
    std::ofstream(file) << expected.dump();
    const std::string log = (dir_ / (name + "_parity.log")).string();
    EXPECT_EQ(run("node " + std::string(WALKVIS_SOURCE_DIR) + "/tests/web/parity.js " + (dir_ / name).string() + " " +
                  file.string() + " > " + log + " 2>&1"),
              0)
        << readText(log);
    std::printf("%s: %s", name.c_str(), readText(log).c_str());
  }
}

TEST_F(WebExport, DeflatedReadsAsRaw) {
  if (!have("node")) GTEST_SKIP() << "node is not installed";
  const fs::path raw = dir_ / "office_raw";
  ASSERT_EQ(run(kBinary + " export " + (dir_ / "office.hfd").string() + " --scene " + quote(kOffice) +
                " --frames 40 --raw --web " + raw.string() + " > /dev/null 2>&1"),
            0);
  const uint64_t deflated = binaryBytes(dir_ / "office"), whole = binaryBytes(raw);
  std::printf("office: walkvis.bin and cells %llu bytes deflated, %llu raw\n", static_cast<unsigned long long>(deflated),
              static_cast<unsigned long long>(whole));
  EXPECT_LT(3 * deflated, whole) << "the deflated export must be under a third of the raw one";
  const std::string log = (dir_ / "same_scene.log").string();
  EXPECT_EQ(run("node " + std::string(WALKVIS_SOURCE_DIR) + "/tests/web/same_scene.js " + (dir_ / "office").string() +
                " " + raw.string() + " > " + log + " 2>&1"),
            0)
      << readText(log);
  std::printf("%s", readText(log).c_str());
}

// Ids images hold id + 1 little-endian in R, G, B (scene_drawer.h); 0 is nothing.
uint32_t idAt(const Image& image, int x, int y) {
  const size_t p = 3 * (static_cast<size_t>(y) * image.width + x);  // any image width: a screenshot is cropped
  return uint32_t(image.rgb[p]) | uint32_t(image.rgb[p + 1]) << 8 | uint32_t(image.rgb[p + 2]) << 16;
}

bool edgePixel(const Image& image, int x, int y) {
  const uint32_t id = idAt(image, x, y);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int u = x + dx, v = y + dy;
      if (u >= 0 && v >= 0 && u < image.width && v < image.height && idAt(image, u, v) != id) return true;
    }
  return false;
}

// Screenshots of tour keys 0..frames-1 of the office page (`query` added to each URL) against the
// ids images `walkvis render --ids` (with `render_options`) writes into `ref`: a differing pixel
// off every edge of the reference is a failure (the first five are named).
struct IdsComparison {
  size_t pixels = 0, differing = 0, inner_differing = 0;
  std::set<uint32_t> ids;  // of the reference
};
IdsComparison compareWithRender(const fs::path& dir, const fs::path& ref, const std::string& render_options, int frames,
                                const std::string& query, const std::string& shot_prefix) {
  IdsComparison c;
  const std::string size = std::to_string(kWidth) + "x" + std::to_string(kHeight);
  if (run(kBinary + " render " + (dir / "office.hfd").string() + " --scene " + quote(kOffice) + " " + render_options +
          " --ids --objects none --frames " + std::to_string(frames) + " --size " + size + " --out " + ref.string() +
          " > /dev/null 2>&1") != 0) {
    ADD_FAILURE() << "walkvis render failed";
    return c;
  }
  for (int k = 0; k < frames; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", k);
    const fs::path shot = dir / (shot_prefix + name);
    // The window is larger than the canvas (headless Chromium lays a window below about 300 pixels
    // wide out oddly); the canvas is the screenshot's top-left corner.
    if (run(chromium(dir) + "--virtual-time-budget=10000 --window-size=400,300 --screenshot=" + shot.string() +
            " 'file://" + (dir / "office" / "index.html").string() + "?frame=" + std::to_string(k) + "&ids=1&size=" +
            size + query + "' > /dev/null 2>&1") != 0) {
      ADD_FAILURE() << name << ": chromium failed";
      return c;
    }
    const Image a = readPng((ref / name).string()), b = readPng(shot.string());
    if (a.width != kWidth || b.width < kWidth || b.height < kHeight) {
      ADD_FAILURE() << name << ": image sizes " << a.width << " and " << b.width << "x" << b.height;
      return c;
    }
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        ++c.pixels;
        c.ids.insert(idAt(a, x, y));
        if (idAt(a, x, y) == idAt(b, x, y)) continue;
        ++c.differing;
        if (!edgePixel(a, x, y) && ++c.inner_differing <= 5)
          ADD_FAILURE() << name << " (" << x << ", " << y << "): page id " << idAt(b, x, y) << ", render id "
                        << idAt(a, x, y) << " away from any edge";
      }
  }
  return c;
}

TEST_F(WebExport, PageDrawsWhatRenderDraws) {
  if (!have("chromium")) GTEST_SKIP() << "chromium is not installed";
  constexpr int kFrames = 24;
  const fs::path web = dir_ / "office";
  const std::string size = std::to_string(kWidth) + "x" + std::to_string(kHeight);
  // Loads with no console message at all (errors, warnings, logs) and says it drew.
  const fs::path dom = dir_ / "dom.html", err = dir_ / "chromium.err";
  ASSERT_EQ(run(chromium(dir_) + "--enable-logging=stderr --v=0 --virtual-time-budget=10000 --dump-dom 'file://" +
                (web / "index.html").string() + "?frame=3&ids=1&size=" + size + "' > " + dom.string() + " 2> " +
                err.string()),
            0);
  EXPECT_NE(readText(dom).find("data-drawn=\"1\""), std::string::npos) << readText(dom);
  EXPECT_EQ(readText(err).find("CONSOLE"), std::string::npos) << readText(err);

  const IdsComparison c = compareWithRender(dir_, dir_ / "render", "", kFrames, "", "page_");
  std::printf("page against render: %d frames, %zu pixels, %zu differing (%zu off edges), %zu distinct ids\n",
              kFrames, c.pixels, c.differing, c.inner_differing, c.ids.size());
  EXPECT_EQ(c.inner_differing, 0u);
  EXPECT_LE(c.differing, c.pixels / 100);
  EXPECT_GT(c.ids.size(), 30u) << "the frames must show the building";
}

// `bin` with one byte flipped in its largest deflated section and every checksum made to agree
// again (docs/web/README.md, "Format"), so that only the inflate can tell.
std::vector<uint8_t> brokenDeflate(std::vector<uint8_t> bin) {
  auto at = [&](size_t offset) { return ByteReader(std::span(bin).subspan(offset), "walkvis.bin"); };
  auto put = [&](size_t offset, uint64_t v) { std::memcpy(bin.data() + offset, &v, sizeof v); };
  const uint32_t count = at(12).get<uint32_t>();
  size_t entry = 0;
  uint64_t largest = 0;
  for (uint32_t k = 0; k < count; ++k) {
    ByteReader r = at(40 + 40 * k + 4);
    const uint32_t encoding = r.get<uint32_t>();
    r.get<uint64_t>();
    const uint64_t stored = r.get<uint64_t>();
    if (encoding == 1 && stored > largest) entry = 40 + 40 * k, largest = stored;
  }
  EXPECT_GT(largest, 0u) << "the export has no deflated section";
  const uint64_t offset = at(entry + 8).get<uint64_t>();
  bin[offset + largest / 2] ^= 0x40;
  put(entry + 32, fnv1a(bin.data() + offset, largest));
  put(24, fnv1a(bin.data() + 40, 40 * size_t{count}));
  return bin;
}

// The page fetches walkvis.bin from a server (from file:// it runs walkvis-data.js), then only the
// view cell its eye stands in: the same view from a local static server is the same image, pixel
// for pixel, drawn from the HFD tree of the one cell fetched; a missing walkvis.bin or cell file
// there is a message naming it and the server's answer.
TEST_F(WebExport, PageLoadsFromAServer) {
  if (!have("chromium") || !have("python3")) GTEST_SKIP() << "chromium or python3 is not installed";
  const fs::path log = dir_ / "server.log", pid = dir_ / "server.pid";
  fs::create_directories(dir_ / "served_missing");
  fs::create_directories(dir_ / "served_no_cells");
  for (const char* f : {"index.html", "viewer.js", "page.js"}) {
    fs::copy_file(dir_ / "office" / f, dir_ / "served_missing" / f, fs::copy_options::overwrite_existing);
    fs::copy_file(dir_ / "office" / f, dir_ / "served_no_cells" / f, fs::copy_options::overwrite_existing);
  }
  fs::copy_file(dir_ / "office" / "walkvis.bin", dir_ / "served_no_cells" / "walkvis.bin",
                fs::copy_options::overwrite_existing);
  // Port 0: the system picks a free one, which the server prints ("... port N ...").
  ASSERT_EQ(run("python3 -u -m http.server 0 --bind 127.0.0.1 --directory " + dir_.string() + " > " + log.string() +
                " 2>&1 & echo $! > " + pid.string()),
            0);
  std::string port;
  for (int i = 0; i < 100 && port.empty(); ++i) {
    const std::string text = readText(log);
    const size_t at = text.find(" port ");
    if (at != std::string::npos) port = text.substr(at + 6, text.find_first_not_of("0123456789", at + 6) - at - 6);
    else ::usleep(100000);
  }
  const std::string stop = "kill " + readText(pid);
  if (port.empty()) run(stop);
  ASSERT_FALSE(port.empty()) << readText(log);
  const std::string view = "/index.html?frame=5&ids=1&size=160x120", url = "'http://127.0.0.1:" + port;
  const fs::path served = dir_ / "served.png", local = dir_ / "local.png", dom = dir_ / "served.html",
                 missing = dir_ / "served_missing.html", no_cells = dir_ / "served_no_cells.html";
  const std::string shot = chromium(dir_) + "--virtual-time-budget=10000 --window-size=400,300 --screenshot=";
  const std::string dump = chromium(dir_) + "--virtual-time-budget=10000 --dump-dom ";
  const int a = run(shot + served.string() + " " + url + "/office" + view + "' > /dev/null 2>&1");
  const std::string fetched = readText(log);  // what the screenshot's page asked for
  const int b = run(shot + local.string() + " 'file://" + (dir_ / "office").string() + view + "' > /dev/null 2>&1");
  const int c = run(dump + url + "/office" + view + "' > " + dom.string() + " 2> /dev/null");
  const int d = run(dump + url + "/served_missing" + view + "' > " + missing.string() + " 2> /dev/null");
  const int e = run(dump + url + "/served_no_cells" + view + "' > " + no_cells.string() + " 2> /dev/null");
  run(stop);
  ASSERT_EQ(a, 0);
  ASSERT_EQ(b, 0);
  ASSERT_EQ(c, 0);
  ASSERT_EQ(d, 0);
  ASSERT_EQ(e, 0);
  const Image from_server = readPng(served.string()), from_file = readPng(local.string());
  EXPECT_EQ(from_server.width, from_file.width);
  EXPECT_EQ(from_server.height, from_file.height);
  EXPECT_TRUE(from_server.rgb == from_file.rgb) << "the served page must draw what the local one draws";
  std::set<uint32_t> ids;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) ids.insert(idAt(from_server, x, y));
  EXPECT_GT(ids.size(), 5u) << "the view must show the building";
  EXPECT_NE(fetched.find("GET /office/walkvis.bin"), std::string::npos) << "the page must fetch the binary";
  // One cell of the office's several fetched, and its tree drew the view.
  std::vector<std::string> cells_fetched;
  for (size_t at = fetched.find("GET /office/cells/"); at != std::string::npos;
       at = fetched.find("GET /office/cells/", at + 1))
    cells_fetched.push_back(fetched.substr(at + 18, fetched.find(' ', at + 18) - at - 18));
  ASSERT_EQ(cells_fetched.size(), 1u) << fetched;
  const std::string page = readText(dom);
  EXPECT_NE(page.find("data-used=\"hfd\""), std::string::npos) << page.substr(0, 400);
  const std::string k = cells_fetched[0].substr(0, cells_fetched[0].find('.'));
  EXPECT_EQ(cells_fetched[0], k + ".bin");
  EXPECT_NE(page.find("data-cells-loaded=\"" + k + "\""), std::string::npos) << page.substr(0, 400);
  for (const auto& [file, message] : {std::pair{missing, std::string("walkvis.bin: 404")},
                                      std::pair{no_cells, "cells/" + k + ".bin: 404"}}) {
    const std::string text = readText(file);
    EXPECT_NE(text.find(message), std::string::npos) << text.substr(0, 400);
    EXPECT_EQ(text.find("data-drawn"), std::string::npos);
  }
}

// Until its view cell is in, the page draws the BSP order (&cells=none keeps every cell out): the
// ids images equal `walkvis render --mode bsp --ids` of the same keys, within the edge tolerance of
// PageDrawsWhatRenderDraws.
TEST_F(WebExport, WithoutItsCellThePageDrawsTheBspOrder) {
  if (!have("chromium")) GTEST_SKIP() << "chromium is not installed";
  constexpr int kFrames = 4;
  const fs::path web = dir_ / "office";
  const std::string size = std::to_string(kWidth) + "x" + std::to_string(kHeight);
  const fs::path dom = dir_ / "bsp_dom.html";
  ASSERT_EQ(run(chromium(dir_) + "--virtual-time-budget=10000 --dump-dom 'file://" + (web / "index.html").string() +
                "?frame=2&cells=none&size=" + size + "' > " + dom.string() + " 2> /dev/null"),
            0);
  const std::string page = readText(dom);
  EXPECT_NE(page.find("data-used=\"bsp\""), std::string::npos) << page.substr(0, 400);
  EXPECT_EQ(page.find("data-cells-loaded"), std::string::npos) << page.substr(0, 400);
  const IdsComparison c = compareWithRender(dir_, dir_ / "render_bsp", "--mode bsp", kFrames, "&cells=none", "bsp_page_");
  std::printf("BSP page against render --mode bsp: %d frames, %zu pixels, %zu differing (%zu off edges)\n", kFrames,
              c.pixels, c.differing, c.inner_differing);
  EXPECT_EQ(c.inner_differing, 0u);
  EXPECT_LE(c.differing, c.pixels / 100);
  EXPECT_GT(c.ids.size(), 10u) << "the frames must show the building";
}

TEST_F(WebExport, BrokenExportShowsAMessage) {
  if (!have("chromium")) GTEST_SKIP() << "chromium is not installed";
  const std::vector<uint8_t> bin = readFileBytes((dir_ / "office" / "walkvis.bin").string());
  const size_t cells = viewCells(dir_ / "office.hfd");
  // What each cell's script holds in a case: the cell as exported, nothing, the cell with one byte
  // flipped, or a cell of another export (the house's first) under the same name.
  enum class Cells { kIntact, kMissing, kFlipped, kForeign };
  struct Case {
    const char* name;
    std::string script;  // walkvis-data.js
    Cells cells;
    const char* message;
  };
  std::vector<uint8_t> flipped = bin;
  flipped[flipped.size() / 2] ^= 0x40;
  const std::string whole = webDataScript(bin);
  const std::vector<Case> cases = {
      {"truncated_script", whole.substr(0, whole.size() / 2), Cells::kIntact, "truncated or malformed"},
      {"truncated_binary", webDataScript(std::span(bin.data(), bin.size() - 1000)), Cells::kIntact, "truncated"},
      {"flipped_byte", webDataScript(flipped), Cells::kIntact, "checksum mismatch"},
      {"bad_deflate", webDataScript(brokenDeflate(bin)), Cells::kIntact, "does not inflate"},
      {"not_an_export", webDataScript(std::vector<uint8_t>(100, 7)), Cells::kIntact, "not a walkvis web export"},
      {"missing", "", Cells::kIntact, "walkvis-data.js: missing or unreadable"},
      {"cell_missing", whole, Cells::kMissing, ".js: missing or unreadable"},
      {"cell_flipped", whole, Cells::kFlipped, ".bin: checksum mismatch"},
      {"cell_foreign", whole, Cells::kForeign, "not this export's view cell"},
  };
  const std::vector<uint8_t> foreign = readFileBytes((dir_ / "house" / "cells" / "0.bin").string());
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path web = dir_ / (std::string("broken_") + c.name);
    fs::create_directories(web / "cells");
    for (const char* f : {"index.html", "viewer.js", "page.js"})
      fs::copy_file(dir_ / "office" / f, web / f, fs::copy_options::overwrite_existing);
    if (!c.script.empty()) writeTextFileAtomically((web / "walkvis-data.js").string(), c.script, "test");
    for (uint32_t k = 0; k < cells && c.cells != Cells::kMissing; ++k) {
      std::vector<uint8_t> cell = readFileBytes((dir_ / "office" / "cells" / (std::to_string(k) + ".bin")).string());
      if (c.cells == Cells::kFlipped) cell[cell.size() / 2] ^= 0x40;
      if (c.cells == Cells::kForeign) cell = foreign;
      writeTextFileAtomically((web / "cells" / (std::to_string(k) + ".js")).string(), webCellScript(k, cell), "test");
    }
    const fs::path dom = web / "dom.html";
    ASSERT_EQ(run(chromium(dir_) + "--virtual-time-budget=10000 --dump-dom 'file://" + (web / "index.html").string() +
                  "?frame=0' > " + dom.string() + " 2> /dev/null"),
              0);
    const std::string text = readText(dom);
    EXPECT_NE(text.find("data-error=\""), std::string::npos) << text.substr(0, 400);
    EXPECT_NE(text.find(c.message), std::string::npos) << text.substr(0, 400);
    EXPECT_EQ(text.find("data-drawn"), std::string::npos);
  }
}

}  // namespace
}  // namespace walkvis
