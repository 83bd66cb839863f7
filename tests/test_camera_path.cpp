// Camera paths: view directions, the CSV format (round trip, every kind of bad line) and the
// automatic tour (deterministic, walking speed, on height planes, never through a wall).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <set>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "bsp/bsp.h"
#include "scenes/scene.h"
#include "walkthrough/camera_path.h"

namespace walkvis {
namespace {

std::string tempFile(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("walkvis_test_camera_path_" + name)).string();
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

TEST(ViewDirection, Conventions) {
  const auto near = [](glm::dvec3 a, glm::dvec3 b) { return glm::length(a - b) < 1e-12; };
  EXPECT_TRUE(near(viewDirection(0.0, 0.0), {0, 0, -1}));
  EXPECT_TRUE(near(viewDirection(std::numbers::pi / 2, 0.0), {-1, 0, 0}));  // positive yaw turns towards -x
  EXPECT_TRUE(near(viewDirection(std::numbers::pi, 0.0), {0, 0, 1}));
  EXPECT_TRUE(near(viewDirection(0.0, std::numbers::pi / 4), {0, std::sqrt(0.5), -std::sqrt(0.5)}));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> yaw(-10, 10), pitch(-1.5, 1.5);
  for (int i = 0; i < 1000; ++i) EXPECT_NEAR(glm::length(viewDirection(yaw(rng), pitch(rng))), 1.0, 1e-12);
}

TEST(CameraPathCsv, RoundTripIsBitExact) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1e6, 1e6), p(-1.5, 1.5);
  CameraPath path;
  double t = 0.0;
  for (int i = 0; i < 200; ++i) {
    t += std::abs(u(rng)) * 1e-7;
    path.keys.push_back({t, {u(rng), u(rng) * 1e-9, u(rng)}, u(rng), p(rng)});
  }
  const std::string file = tempFile("roundtrip.csv");
  saveCameraPath(path, file);
  const CameraPath back = loadCameraPath(file);
  ASSERT_EQ(back.keys.size(), path.keys.size());
  for (size_t i = 0; i < path.keys.size(); ++i) {
    EXPECT_EQ(back.keys[i].time, path.keys[i].time);
    EXPECT_EQ(back.keys[i].eye, path.keys[i].eye);
    EXPECT_EQ(back.keys[i].yaw, path.keys[i].yaw);
    EXPECT_EQ(back.keys[i].pitch, path.keys[i].pitch);
  }
  EXPECT_FALSE(std::filesystem::exists(file + ".tmp"));
  std::filesystem::remove(file);
}

TEST(CameraPathCsv, AcceptsCrlfSpacesAndBlankLines) {
  const std::string file = tempFile("crlf.csv");
  writeText(file, "time,x,y,z,yaw,pitch\r\n0, 1,2,3 ,0.5,0\r\n\r\n1,4,5,6,-0.5,0.25\r\n");
  const CameraPath path = loadCameraPath(file);
  ASSERT_EQ(path.keys.size(), 2u);
  EXPECT_EQ(path.keys[1].eye, glm::dvec3(4, 5, 6));
  EXPECT_EQ(path.keys[1].pitch, 0.25);
  std::filesystem::remove(file);
}

TEST(CameraPathCsv, BadFilesNameFileAndLine) {
  const std::string file = tempFile("bad.csv");
  const std::string header = "time,x,y,z,yaw,pitch\n";
  struct Case {
    std::string text, expect;
  };
  const Case cases[] = {
      {"", "empty file"},
      {"t,x,y,z\n0,0,0,0\n", ":1: expected the header"},
      {header + "0,1,2,3,0\n", ":2: expected 6"},
      {header + "0,1,2,3,0,0,7\n", ":2: expected 6"},
      {header + "0,1,2,x,0,0\n", ":2: not a number"},
      {header + "0,1,2,,0,0\n", ":2: not a number"},
      {header + "0,1,2,3e,0,0\n", ":2: not a number"},
      {header + "0,1,nan,3,0,0\n", ":2: not a finite"},
      {header + "0,1,2,inf,0,0\n", ":2: not a finite"},
      {header + "0,1,2,1e999,0,0\n", ":2: not a number"},
      {header + "1,0,0,0,0,0\n0.5,0,0,0,0,0\n", ":3: time goes back"},
      {header + "0,0,0,0,0,1.5707963267948966\n", ":2: |pitch|"},
      {header + "0,0,0,0,0,-2\n", ":2: |pitch|"},
      {header, "no camera keys"},
      {header + std::string(5000, '1') + "\n", ":2: line too long"},
  };
  for (const Case& c : cases) {
    writeText(file, c.text);
    try {
      loadCameraPath(file);
      ADD_FAILURE() << "accepted: " << c.text.substr(0, 80);
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(file), std::string::npos) << msg;
      EXPECT_NE(msg.find(c.expect), std::string::npos) << msg << " (expected " << c.expect << ")";
      EXPECT_EQ(msg.find('\n'), std::string::npos);
    }
  }
  std::filesystem::remove(file);
  EXPECT_THROW(loadCameraPath(tempFile("does_not_exist.csv")), Error);
  EXPECT_THROW(saveCameraPath({}, "/nonexistent_dir_walkvis/x.csv"), Error);
}

// Brute force: does the segment a→b cross any non-horizontal fragment (inside it)?
bool crossesWall(const BspTree& bsp, const glm::dvec3& a, const glm::dvec3& b) {
  for (uint32_t f = 0; f < bsp.fragments.size(); ++f) {
    const Plane& pl = bsp.fragments[f].plane;
    if (std::abs(pl.n.y) > 0.9) continue;
    const double sa = glm::dot(pl.n, a) - pl.d, sb = glm::dot(pl.n, b) - pl.d;
    if ((sa > 0) == (sb > 0) || sa == 0.0 || sb == 0.0) continue;
    const glm::dvec3 p = a + (sa / (sa - sb)) * (b - a);
    const auto v = bsp.fragmentVertices(f);
    bool inside = true;
    for (size_t i = 0; i < v.size() && inside; ++i)
      inside = glm::dot(glm::cross(v[(i + 1) % v.size()] - v[i], p - v[i]), pl.n) >= 0.0;
    if (inside) return true;
  }
  return false;
}

bool onSomeHeightPlane(const Scene& scene, double y) {
  for (const auto& l : scene.levels)
    if (y == l.floor_y + scene.eye_height) return true;
  return false;
}

void checkTour(const Scene& scene, const BspTree& bsp, uint32_t frames, double fps, uint64_t seed) {
  const CameraPath tour = automaticTour(scene, bsp, frames, fps, seed);
  ASSERT_EQ(tour.keys.size(), frames);
  const double step = 2.0 * scene.eye_height / fps;  // the tour's walking speed
  double walked = 0.0;
  for (size_t i = 0; i < tour.keys.size(); ++i) {
    const CameraKey& k = tour.keys[i];
    EXPECT_DOUBLE_EQ(k.time, i / fps);
    EXPECT_TRUE(onSomeHeightPlane(scene, k.eye.y)) << "key " << i << " y " << k.eye.y;
    EXPECT_EQ(k.pitch, 0.0);
    if (i == 0) continue;
    const CameraKey& p = tour.keys[i - 1];
    const double d = std::hypot(k.eye.x - p.eye.x, k.eye.z - p.eye.z);
    EXPECT_LE(d, step * (1 + 1e-9)) << "key " << i;
    walked += d;
    EXPECT_FALSE(crossesWall(bsp, p.eye, {k.eye.x, p.eye.y, k.eye.z})) << "key " << i;
  }
  std::set<double> heights;
  for (const auto& k : tour.keys) heights.insert(k.eye.y);
  std::printf("%s: %u frames walked %.1f (max %.1f), %zu height planes\n", scene.name.c_str(), frames, walked,
              step * frames, heights.size());
  // It does walk: at least a third of the time at full speed.
  EXPECT_GT(walked, step * frames / 3.0) << scene.name;
  // Deterministic for a seed, different for another.
  const CameraPath again = automaticTour(scene, bsp, frames, fps, seed);
  for (size_t i = 0; i < frames; ++i) ASSERT_EQ(again.keys[i].eye, tour.keys[i].eye);
  const CameraPath other = automaticTour(scene, bsp, frames, fps, seed + 1);
  bool differs = false;
  for (size_t i = 0; i < frames; ++i) differs = differs || other.keys[i].eye != tour.keys[i].eye;
  EXPECT_TRUE(differs);
}

TEST(AutomaticTour, OfficeWalksAtEyeHeightAndNeverThroughAWall) {
  const Scene scene = loadScene("gen:office?rooms=12&floors=2");
  const BspTree bsp = buildBsp(scene);
  checkTour(scene, bsp, 300, 30.0, 1);
  const CameraPath tour = automaticTour(scene, bsp, 1, 30.0, 1);
  EXPECT_EQ(tour.keys[0].eye, scene.start_eye);
  EXPECT_EQ(tour.keys[0].yaw, scene.start_yaw);
}

TEST(AutomaticTour, FreedoomMapWalks) {
  const Scene scene = loadScene("freedoom2.wad:MAP01");
  const BspTree bsp = buildBsp(scene);
  checkTour(scene, bsp, 300, 30.0, 5);
}

TEST(AutomaticTour, EmptyCases) {
  const Scene scene = loadScene("gen:office?rooms=2");
  const BspTree bsp = buildBsp(scene);
  EXPECT_TRUE(automaticTour(scene, bsp, 0).keys.empty());
  Scene no_levels = scene;
  no_levels.levels.clear();
  EXPECT_TRUE(automaticTour(no_levels, bsp, 10).keys.empty());
}

}  // namespace
}  // namespace walkvis
