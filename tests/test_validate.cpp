// Validation of the BSP back-to-front order against exact ray casting: zero order-error pixels on
// random scenes and generated scenes (office, ninefacet, the cases of docs/DESIGN.md, "Hard
// cases"), and the `walkvis validate` command's JSON.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <memory>
#include <random>

#include <nlohmann/json.hpp>

#include "bsp/bsp.h"
#include "scenes/generators.h"
#include "walkthrough/validate.h"

namespace walkvis {
namespace {

ValidationResult validateBsp(const Scene& scene, int eyes, int size, double off_plane, uint64_t seed = 1) {
  const BspTree tree = buildBsp(scene);
  ValidationOptions options;
  options.eyes = eyes;
  options.size = size;
  options.seed = seed;
  options.zbits = {24};
  options.off_plane_fraction = off_plane;
  return runValidation(
      scene, tree.vertices, tree.fragments,
      [&](const glm::dvec3& eye, std::vector<uint32_t>& out) { backToFront(tree, eye, out, true); }, options);
}

// Random triangles crossing each other in a box around a walkable square, both facings.
Scene randomScene(uint64_t seed, int count) {
  Scene scene;
  scene.name = "random";
  scene.eye_height = 1.0;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  for (int k = 0; k < count; ++k) {
    const glm::dvec3 c(u(rng), u(rng) * 0.5, u(rng));
    std::array<glm::dvec3, 3> tri;
    for (auto& v : tri) v = c + 0.3 * glm::dvec3(u(rng), u(rng), u(rng));
    addFace(scene, tri, faceColor(static_cast<uint32_t>(k)), "random");
  }
  FloorLevel level;
  level.floor_y = -1.0;
  level.walkable.push_back({{-3, -3}, {-3, 3}, {3, 3}, {3, -3}});
  level.walkable_area = 36.0;
  scene.levels.push_back(level);
  return scene;
}

TEST(Validate, BspOrderHasNoOrderErrorsOnRandomScenes) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    const Scene scene = randomScene(seed, 120);
    const ValidationResult r = validateBsp(scene, 4, 64, 0.5, seed);
    EXPECT_EQ(r.views, 24u);
    EXPECT_GT(r.exact_pixels, r.pixels / 20) << "seed " << seed;
    EXPECT_EQ(r.painter.order_error, 0u) << "seed " << seed;
    // Coverage differences are rare: pixel-centre sampling is shared by GL and the rays.
    EXPECT_LT(r.painter.edge, r.pixels / 200) << "seed " << seed;
  }
}

// With a clearance, no eye stands nearer a wall than it: a 4 x 4 room whose walls span the eye
// height keeps every eye in [c, 4 - c]^2, and without one some eyes fall outside that square.
TEST(Validate, EyesKeepTheirClearanceFromWalls) {
  Scene scene;
  scene.eye_height = 1.5;
  auto quad = [&](glm::dvec3 a, glm::dvec3 b, glm::dvec3 c3, glm::dvec3 d) {
    const std::vector<glm::dvec3> v{a, b, c3, d};
    addFace(scene, v, 0x808080, "test");
  };
  quad({0, 0, 0}, {0, 0, 4}, {4, 0, 4}, {4, 0, 0});
  quad({0, 0, 0}, {0, 3, 0}, {0, 3, 4}, {0, 0, 4});
  quad({4, 0, 0}, {4, 0, 4}, {4, 3, 4}, {4, 3, 0});
  quad({0, 0, 0}, {4, 0, 0}, {4, 3, 0}, {0, 3, 0});
  quad({0, 0, 4}, {0, 3, 4}, {4, 3, 4}, {4, 0, 4});
  scene.levels.push_back({0.0, {{{0, 0}, {4, 0}, {4, 4}, {0, 4}}}, 16.0});
  const double c = 0.4;
  auto outside = [&](const std::vector<ValidationEye>& eyes) {
    int n = 0;
    for (const auto& e : eyes)
      n += e.position.x < c || e.position.x > 4 - c || e.position.z < c || e.position.z > 4 - c;
    return n;
  };
  const auto clear = sampleEyes(scene, 300, 7, 0.0, c);
  const auto plain = sampleEyes(scene, 300, 7, 0.0);
  ASSERT_EQ(clear.size(), 300u);
  EXPECT_EQ(outside(clear), 0);
  EXPECT_GT(outside(plain), 50);  // about 36% of the room lies within c of a wall
}

TEST(Validate, EyesAreSampledInTheWalkableRegion) {
  const Scene scene = randomScene(1, 3);
  const auto eyes = sampleEyes(scene, 40, 5, 0.25);
  ASSERT_EQ(eyes.size(), 40u);
  int off = 0;
  for (const auto& e : eyes) {
    EXPECT_GE(e.position.x, -3.0);
    EXPECT_LE(e.position.x, 3.0);
    EXPECT_GE(e.position.z, -3.0);
    EXPECT_LE(e.position.z, 3.0);
    if (e.on_height_plane) EXPECT_EQ(e.position.y, 0.0);
    else ++off;
  }
  EXPECT_EQ(off, 10);
}

TEST(Validate, BspOrderHasNoOrderErrorsOnGeneratedScenes) {
  std::vector<std::string> specs{"gen:office?rooms=6", "gen:ninefacet"};
  for (const std::string& name : hardCaseNames()) {
    if (name == "hard:nan" || name == "hard:infinite") continue;  // bad input, rejected by the loader
    specs.push_back("gen:" + name);
  }
  for (const std::string& spec : specs) {
    Scene scene;
    try {
      scene = loadScene(spec);
    } catch (const Error& e) {
      ADD_FAILURE() << spec << ": " << e.what();
      continue;
    }
    const ValidationResult r = validateBsp(scene, 3, 48, 0.34);
    EXPECT_EQ(r.painter.order_error, 0u) << spec;
    EXPECT_EQ(r.views, 18u) << spec;
    EXPECT_GT(r.exact_pixels, 0u) << spec;
    std::printf("%-40s %llu exact pixels, %llu ties, %llu edge\n", spec.c_str(),
                static_cast<unsigned long long>(r.exact_pixels), static_cast<unsigned long long>(r.painter.tie),
                static_cast<unsigned long long>(r.painter.edge));
  }
}

std::string runCommand(const std::string& command, int& status) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) {
    status = -1;
    return out;
  }
  char buffer[4096];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  status = pclose(pipe);
  return out;
}

TEST(ValidateCommand, JsonHasTheReportedKeys) {
  int status = 0;
  const std::string out = runCommand(std::string(WALKVIS_BINARY) +
                                         " validate 'gen:office?rooms=4' --views 2 --size 32 --zbits 16,32 --json "
                                         "2>/dev/null",
                                     status);
  ASSERT_EQ(status, 0) << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j.at("views").get<int>(), 12);
  EXPECT_EQ(j.at("pixels").get<int>(), 12 * 32 * 32);
  EXPECT_EQ(j.at("order_error_pixels").get<int>(), 0);
  for (const char* key : {"edge_pixels", "tie_pixels", "uncovered_pixels", "tie_tolerance_relative",
                          "edge_margin_pixels", "worst_views", "seconds"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_TRUE(j.at("zbuffer_error_pixels").contains("16"));
  EXPECT_TRUE(j.at("zbuffer_error_pixels").contains("32"));
  EXPECT_FALSE(j.at("zbuffer_error_pixels").contains("24"));
  // Each precision's own drawing time, a part of the whole render time.
  double zbuffer_seconds = 0.0;
  for (const char* bits : {"16", "32"}) {
    const double s = j.at("zbuffer").at(bits).at("render_seconds").get<double>();
    EXPECT_GT(s, 0.0) << bits;
    zbuffer_seconds += s;
  }
  EXPECT_LE(zbuffer_seconds, j.at("seconds").at("render").get<double>());

  runCommand(std::string(WALKVIS_BINARY) + " validate gen:office --zbits 12 2>/dev/null", status);
  EXPECT_EQ(WEXITSTATUS(status), 2);
}

}  // namespace
}  // namespace walkvis
