// `walkvis report`: the page and every image it names are written, and headless Chromium renders
// it: a screenshot that is not blank, no console message, every image loaded (the page's own
// script counts them into body[data-images-loaded]). Chromium steps are skipped where it is
// missing (scripts/install-deps installs it). Bad input: one line naming the file, exit 2.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "command_test_util.h"
#include "png_test_util.h"

namespace walkvis {
namespace {

namespace fs = std::filesystem;

int run(const std::string& command) { return runCommand(command); }

bool haveChromium() { return run("command -v chromium > /dev/null 2>&1") == 0; }

std::string chromium(const fs::path& dir) {
  // The flags this machine's headless Chromium needs (software GL, root without a sandbox, a
  // container's small /dev/shm left alone), and a profile of its own so that nothing outside the
  // test folder is touched.
  return "chromium --headless=new --no-sandbox --use-gl=swiftshader --enable-unsafe-swiftshader "
         "--disable-dev-shm-usage --user-data-dir=" + (dir / "chrome-profile").string() + " ";
}

TEST(Report, PageRendersInChromiumWithEveryImage) {
  const fs::path dir = fs::temp_directory_path() / ("walkvis_test_report_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const fs::path page = dir / "page";
  ASSERT_EQ(run(std::string(WALKVIS_BINARY) + " report \"gen:office?rooms=4\" -o " + page.string() +
                " --views 8 --frames 6 > /dev/null 2> " + (dir.string() + ".log")),
            0)
      << readText(dir.string() + ".log");
  const std::string html = readText(page / "index.html");
  ASSERT_FALSE(html.empty());
  EXPECT_FALSE(fs::exists(page / "index.html.tmp"));
  for (const char* section : {"The scene", "Build costs", "Validation", "Rejection", "Frame times"})
    EXPECT_NE(html.find(std::string("<h2>") + section + "</h2>"), std::string::npos) << section;
  // Every image the page names exists beside it; the frame, the plan and the two histograms at least.
  std::set<std::string> sources;
  const std::string tag = "<img src=\"";
  for (size_t at = html.find(tag); at != std::string::npos; at = html.find(tag, at + 1)) {
    const size_t begin = at + tag.size(), end = html.find('"', begin);
    if (end != std::string::npos) sources.insert(html.substr(begin, end - begin));
  }
  EXPECT_GE(sources.size(), 4u);
  EXPECT_EQ(sources.count("zbuffer-bits.png"), 1u) << "the depth precision's speed against error";
  for (const std::string& s : sources) EXPECT_TRUE(fs::exists(page / s)) << s;
  EXPECT_EQ(html.find("http"), std::string::npos) << "the page must not reach the network";

  if (!haveChromium()) GTEST_SKIP() << "chromium not installed";
  fs::create_directories(dir);
  const fs::path dom = dir / "dom.html", err = dir / "chromium.err", shot = dir / "shot.png";
  ASSERT_EQ(run("timeout 120 " + chromium(dir) + "--enable-logging=stderr --v=0 --virtual-time-budget=5000 "
                "--dump-dom file://" + (page / "index.html").string() + " > " + dom.string() + " 2> " + err.string()),
            0);
  const std::string loaded = "data-images-loaded=\"" + std::to_string(sources.size()) + "/" +
                             std::to_string(sources.size()) + "\"";
  EXPECT_NE(readText(dom).find(loaded), std::string::npos) << "expected " << loaded;
  EXPECT_EQ(readText(err).find("CONSOLE"), std::string::npos) << readText(err);
  ASSERT_EQ(run("timeout 120 " + chromium(dir) + "--window-size=1100,1600 --screenshot=" + shot.string() +
                " file://" + (page / "index.html").string() + " > /dev/null 2>&1"),
            0);
  const Image image = readPng(shot.string());
  ASSERT_GT(image.width, 0);
  // Not blank: many pixels that are not the page's white, in many colours (the frame, the plan).
  size_t coloured = 0;
  std::set<uint32_t> colours;
  for (size_t i = 0; i + 2 < image.rgb.size(); i += 3) {
    const uint32_t c = (image.rgb[i] << 16) | (image.rgb[i + 1] << 8) | image.rgb[i + 2];
    if (c != 0xffffff) ++coloured;
    if (colours.size() < 1000) colours.insert(c);
  }
  EXPECT_GT(coloured, image.rgb.size() / 3 / 10);
  EXPECT_GT(colours.size(), 100u);
  fs::remove_all(dir);
  fs::remove(dir.string() + ".log");
}

TEST(Report, MissingSceneIsNamed) {
  const fs::path dir = fs::temp_directory_path() / ("walkvis_test_report_bad_" + std::to_string(::getpid()));
  const fs::path err = dir.string() + ".err";
  EXPECT_EQ(run(std::string(WALKVIS_BINARY) + " report /nonexistent/house.ifc -o " + dir.string() + " 2> " +
                err.string()),
            2);
  const std::string text = readText(err);
  EXPECT_NE(text.find("/nonexistent/house.ifc"), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(dir / "index.html"));
  fs::remove_all(dir);
  fs::remove(err);
}

}  // namespace
}  // namespace walkvis
