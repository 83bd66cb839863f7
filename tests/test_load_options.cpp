// How a scene is loaded: the up axis and unit scale of files, the loader and floor choices, and
// their bad values.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "bsp/bsp.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

// Designated initializers would leave the other members to -Wmissing-field-initializers.
template <typename F>
LoadOptions optionsWith(F set) {
  LoadOptions o;
  set(o);
  return o;
}

const std::string kRoom = std::string(WALKVIS_SOURCE_DIR) + "/tests/data/models/room.obj";

// The room model turned z-up: (x, y, z) -> (x, -z, y), the inverse of the loader's z-up turn.
std::string writeZUpRoom(double file_units_per_metre) {
  const auto path = std::filesystem::temp_directory_path() / "walkvis_zup_room.obj";
  std::ifstream in(kRoom);
  std::ofstream out(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      double x, y, z;
      std::sscanf(line.c_str(), "v %lf %lf %lf", &x, &y, &z);
      out << "v " << x * file_units_per_metre << " " << -z * file_units_per_metre << " " << y * file_units_per_metre
          << "\n";
    } else {
      out << line << "\n";
    }
  }
  return path.string();
}

TEST(LoadOptions, ZUpFileInMillimetresLoadsAsTheYUpRoomInMetres) {
  const Scene ref = loadScene(kRoom, optionsWith([](LoadOptions& o) { o.floors = "faces"; }));
  const std::string zup = writeZUpRoom(1000.0);
  LoadOptions options;
  options.up_axis = 'z';
  options.unit_scale = 0.001;
  options.floors = "faces";
  const Scene s = loadScene(zup, options);
  ASSERT_EQ(s.polygons.size(), ref.polygons.size());
  ASSERT_EQ(s.vertices.size(), ref.vertices.size());
  for (size_t i = 0; i < s.vertices.size(); ++i) {
    // Millimetres scaled by 0.001 round once: within an ulp of the metre coordinates.
    EXPECT_NEAR(s.vertices[i].x, ref.vertices[i].x, 1e-15 * 8);
    EXPECT_NEAR(s.vertices[i].y, ref.vertices[i].y, 1e-15 * 8);
    EXPECT_NEAR(s.vertices[i].z, ref.vertices[i].z, 1e-15 * 8);
  }
  for (size_t i = 0; i < s.polygons.size(); ++i) {
    const Polygon& p = s.polygons[i];
    EXPECT_NEAR(glm::distance(p.plane.n, ref.polygons[i].plane.n), 0.0, 1e-15);
    for (const auto& v : s.polygonVertices(p)) EXPECT_NEAR(glm::dot(p.plane.n, v), p.plane.d, 1e-12);
  }
  // Horizontal faces stay exactly horizontal through the turn, so the floor is one exact level.
  ASSERT_EQ(s.levels.size(), ref.levels.size());
  EXPECT_EQ(s.levels[0].floor_y, 0.0);
  EXPECT_NEAR(s.levels[0].walkable_area, ref.levels[0].walkable_area, 1e-12);
  EXPECT_NE(s.report.notes.back().find("given on the command line"), std::string::npos);
  // The turned scene partitions like the original: same fragment count.
  EXPECT_EQ(buildBsp(s).fragments.size(), buildBsp(ref).fragments.size());
}

TEST(LoadOptions, TransformSceneKeepsPlanesConsistentWithVertices) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int trial = 0; trial < 20; ++trial) {
    Scene s;
    for (int f = 0; f < 30; ++f) {
      const glm::dvec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
      const glm::dvec3 tri[] = {a, b, c};
      addFace(s, tri, 0, "t");
    }
    const Scene before = s;
    const double scale = trial % 2 ? 0.001 : 2.54;
    transformScene(s, trial % 3 != 0, scale);
    for (size_t i = 0; i < s.polygons.size(); ++i) {
      const Polygon& p = s.polygons[i];
      EXPECT_NEAR(glm::length(p.plane.n), 1.0, 1e-12);
      for (const auto& v : s.polygonVertices(p)) {
        EXPECT_NEAR(glm::dot(p.plane.n, v), p.plane.d, 1e-10 * scale * 100.0);
      }
      // Orientation is kept: the turn is a rotation, so the normal still sees the loop counter-clockwise.
      const auto v = s.polygonVertices(p);
      EXPECT_GT(glm::dot(glm::cross(v[1] - v[0], v[2] - v[0]), p.plane.n), 0.0);
      EXPECT_EQ(p.face_id, before.polygons[i].face_id);
    }
  }
}

TEST(LoadOptions, BadValuesAreOneLineErrorsNamingTheScene) {
  const auto expectError = [](const LoadOptions& o, const std::string& what) {
    try {
      loadScene(kRoom, o);
      ADD_FAILURE() << "no error for " << what;
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(kRoom), std::string::npos) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  };
  expectError(optionsWith([](LoadOptions& o) { o.loader = "magic"; }), "unknown loader");
  expectError(optionsWith([](LoadOptions& o) { o.up_axis = 'x'; }), "up axis");
  expectError(optionsWith([](LoadOptions& o) { o.unit_scale = 0.0; }), "unit scale");
  expectError(optionsWith([](LoadOptions& o) { o.unit_scale = NAN; }), "unit scale");
  expectError(optionsWith([](LoadOptions& o) { o.floors = "stairs"; }), "unknown floor method");
}

TEST(LoadOptions, FloorsFacesTakesEveryUpwardFaceHeight) {
  // A floor and a table top: as faces, two levels; the default (the navmesh) never makes the
  // table top a level (test_walkable checks what it makes).
  const auto path = std::filesystem::temp_directory_path() / "walkvis_table_faces.obj";
  {
    std::ofstream out(path);
    out << "v 0 0 0\nv 6 0 0\nv 6 0 6\nv 0 0 6\n"
           "v 2 0.75 2\nv 4 0.75 2\nv 4 0.75 4\nv 2 0.75 4\n"
           "f 1 4 3 2\nf 5 8 7 6\n";
  }
  const Scene faces = loadScene(path.string(), optionsWith([](LoadOptions& o) { o.floors = "faces"; }));
  ASSERT_EQ(faces.levels.size(), 2u);
  EXPECT_EQ(faces.levels[1].floor_y, 0.75);
}

}  // namespace
}  // namespace walkvis
