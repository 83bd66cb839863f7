// OBJ and glTF loaders: committed models, in-memory variants, the error messages for malformed
// input (file and line), and seeded mutations of valid files that must load or throw Error.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/byte_io.h"
#include "scenes/loaders.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

const std::string kModels = std::string(WALKVIS_SOURCE_DIR) + "/tests/data/models/";

glm::dvec3 centroid(std::span<const glm::dvec3> v) {
  glm::dvec3 c(0.0);
  for (const auto& p : v) c += p;
  return c / static_cast<double>(v.size());
}

// Every polygon's plane normal points away from `centre` (a convex closed body seen from outside).
void expectOutward(const Scene& scene, glm::dvec3 centre) {
  for (size_t i = 0; i < scene.polygons.size(); ++i) {
    const auto v = scene.polygonVertices(i);
    EXPECT_GT(glm::dot(scene.polygons[i].plane.n, centroid(v) - centre), 0.0) << "polygon " << i;
    // The stored plane must agree with the vertex order (counter-clockwise from the front).
    const Plane newell = newellPlane(v);
    EXPECT_NEAR(glm::dot(newell.n, scene.polygons[i].plane.n), 1.0, 1e-12) << "polygon " << i;
  }
}

std::string expectSceneError(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no Error";
  return "";
}

// ---------------------------------------------------------------- OBJ

TEST(Obj, CubeFileWithMaterialsAndIndexForms) {
  const Scene s = loadObj(kModels + "cube.obj");
  EXPECT_EQ(s.report.input_faces, 6u);
  EXPECT_EQ(s.report.kept_faces, 6u);
  ASSERT_EQ(s.polygons.size(), 6u);
  EXPECT_TRUE(isClosed(s));
  const Bounds b = sceneBounds(s);
  EXPECT_EQ(b.lo, glm::dvec3(0.0));
  EXPECT_EQ(b.hi, glm::dvec3(1.0));
  expectOutward(s, glm::dvec3(0.5));
  ASSERT_EQ(s.face_colors.size(), 6u);
  EXPECT_EQ(s.face_colors[0], 0x00ff00u);  // usemtl green
  EXPECT_EQ(s.face_colors[2], 0x00ff00u);
  EXPECT_EQ(s.face_colors[3], faceColor(3));  // material not in the library
  EXPECT_EQ(s.face_colors[4], 0x0000ffu);     // usemtl blue, relative indices
  EXPECT_EQ(s.face_colors[5], 0x0000ffu);
  ASSERT_EQ(s.report.notes.size(), 1u);
  EXPECT_NE(s.report.notes[0].find("material"), std::string::npos);
}

TEST(Obj, RoomWithNonConvexFloorIsSplit) {
  const Scene s = loadObj(kModels + "room.obj");
  EXPECT_EQ(s.report.input_faces, 8u);
  EXPECT_EQ(s.report.kept_faces, 6u);
  EXPECT_EQ(s.report.split_faces, 2u);
  EXPECT_GE(s.report.split_pieces, 4u);
  EXPECT_TRUE(isClosed(s));
  double floor_area = 0.0;
  for (size_t i = 0; i < s.polygons.size(); ++i) {
    if (s.polygons[i].face_id != 0) continue;
    EXPECT_NEAR(s.polygons[i].plane.n.y, 1.0, 1e-15);
    const auto v = s.polygonVertices(i);
    for (size_t k = 1; k + 1 < v.size(); ++k) floor_area += 0.5 * glm::length(glm::cross(v[k] - v[0], v[k + 1] - v[0]));
  }
  EXPECT_NEAR(floor_area, 12.0, 1e-12);  // 4x4 minus a 2x2 corner
}

TEST(Obj, LineEndingsCommentsAndIgnoredRecords) {
  const std::string text =
      "# comment\r\nv 0 0 0\r\nv 1 0 0 # trailing\rv 1 1 0\n\nv +0 1 0 1.0\n"
      "vt 0.5 0.5\nvn 0 0 1\ng a b\ns off\no thing\nl 1 2\n\tf\t1/1 2/1 3/1 4/1  \n";
  const Scene s = loadObjFromMemory(text, "mem.obj");
  ASSERT_EQ(s.polygons.size(), 1u);
  EXPECT_EQ(s.polygons[0].vertex_count, 4u);
  EXPECT_NEAR(s.polygons[0].plane.n.z, 1.0, 1e-15);
}

TEST(Obj, ForwardPositiveIndicesAreAllowed) {
  const Scene s = loadObjFromMemory("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", "fwd.obj");
  EXPECT_EQ(s.polygons.size(), 1u);
}

TEST(Obj, DoublePrecisionCoordinatesSurvive) {
  // 1e6 with features of 1e-3 (docs/DESIGN.md, "Hard cases"): float would round 1e6 + 1e-3 to 1e6.
  const Scene s = loadObjFromMemory("v 1000000 0 0\nv 1000000.001 0 0\nv 1000000 0.001 0\nf 1 2 3\n", "big.obj");
  ASSERT_EQ(s.polygons.size(), 1u);
  EXPECT_EQ(s.vertices[s.polygons[0].first_vertex + 1].x, 1000000.001);
}

TEST(Obj, DegenerateFacesAreDroppedAndCounted) {
  const Scene s = loadObjFromMemory("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\nf 1 2 4\n", "d.obj");
  EXPECT_EQ(s.report.input_faces, 3u);
  EXPECT_EQ(s.polygons.size(), 1u);
  EXPECT_EQ(s.report.dropped_degenerate + s.report.dropped_zero_area, 2u);
}

// Random convex polygons written with 17 significant digits come back bit for bit, in order,
// with the plane their vertex order gives.
TEST(Obj, RandomConvexPolygonsRoundTrip) {
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-100.0, 100.0);
    std::uniform_int_distribution<int> sides(3, 9);
    std::string text;
    std::vector<std::vector<glm::dvec3>> polys;
    size_t base = 0;
    for (int k = 0; k < 10; ++k) {
      const int n = sides(rng);
      const glm::dvec3 c(u(rng), u(rng), u(rng));
      glm::dvec3 a = glm::normalize(glm::dvec3(u(rng), u(rng), u(rng)));
      glm::dvec3 b = glm::normalize(glm::cross(a, glm::dvec3(u(rng), u(rng), u(rng))));
      a = glm::cross(b, glm::normalize(glm::cross(a, b)));
      const double r = 1.0 + std::abs(u(rng));
      std::vector<glm::dvec3> poly;
      for (int i = 0; i < n; ++i) {
        const double t = 2.0 * M_PI * i / n;
        poly.push_back(c + r * (std::cos(t) * a + std::sin(t) * b));
        char buf[128];
        std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", poly.back().x, poly.back().y, poly.back().z);
        text += buf;
      }
      text += "f";
      for (int i = 0; i < n; ++i) {
        // Two appends: GCC 12 at -O3 warns (-Wrestrict, falsely) on " " + std::to_string(...).
        text += ' ';
        text += std::to_string(k % 2 == 0 ? static_cast<long>(base + i + 1) : i - n);
      }
      text += "\n";
      base += n;
      polys.push_back(poly);
    }
    const Scene s = loadObjFromMemory(text, "seed" + std::to_string(seed) + ".obj");
    ASSERT_EQ(s.polygons.size(), polys.size()) << "seed " << seed;
    for (size_t k = 0; k < polys.size(); ++k) {
      const auto v = s.polygonVertices(k);
      ASSERT_EQ(v.size(), polys[k].size());
      for (size_t i = 0; i < v.size(); ++i) EXPECT_EQ(v[i], polys[k][i]) << "seed " << seed << " poly " << k;
      EXPECT_NEAR(glm::dot(s.polygons[k].plane.n, newellPlane(polys[k]).n), 1.0, 1e-12);
    }
  }
}

struct BadObj {
  const char* text;
  const char* message;  // the whole error must contain this
};

TEST(Obj, MalformedInputNamesFileAndLine) {
  const BadObj cases[] = {
      {"", "bad.obj: no faces"},
      {"# only a comment\nv 0 0 0\n", "bad.obj: no faces"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "bad.obj:4: face index 9 out of range (3 vertices)"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "bad.obj:4: face index -4 out of range (3 vertices so far)"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "bad.obj:4: face index 0"},
      {"v 0 0 0\nv 1 abc 0\n", "bad.obj:2: bad number 'abc'"},
      {"v 0 0 0\nv 1 nan 0\n", "bad.obj:2: non-finite number 'nan'"},
      {"v 0 0 0\r\nv 1 0 -inf\r\n", "bad.obj:2: non-finite number '-inf'"},
      {"v 1e999 0 0\n", "bad.obj:1: number '1e999' is out of range"},
      {"v 0 0\n", "bad.obj:1: vertex needs 3 coordinates, got 2"},
      {"v 0 0 0\nv 1 0 0\nf 1 2\n", "bad.obj:3: face with 2 vertices"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "bad.obj:4: bad face index 'x'"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/\n", "bad.obj:4: bad face corner '3/'"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/1/1/1\n", "bad.obj:4: bad face corner"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n", "bad.obj:4: bad face index"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/-1\n", "bad.obj:4: texture coordinate index -1 out of range"},
      {"vn 0 0 1.5.5\n", "bad.obj:1: bad number '1.5.5'"},
      {"v 0 0 0\nf 1 1 -9223372036854775808\n", "bad.obj:2: face index -9223372036854775808 out of range"},
      {"v 0 0 0\nf 1 1 1/-9223372036854775808\n", "bad.obj:2: texture coordinate index -9223372036854775808"},
      {"v 1 2 3\nv 1 2 3\nv 1 2 3.\x01\n", "bad.obj:3: bad number '3.?'"},
  };
  for (const auto& c : cases) {
    const std::string msg = expectSceneError([&] { loadObjFromMemory(c.text, "bad.obj"); });
    EXPECT_NE(msg.find(c.message), std::string::npos) << "input:\n" << c.text << "\nmessage: " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(Obj, MissingFileIsNamed) {
  const std::string msg = expectSceneError([] { loadObj("/nonexistent/dir/model.obj"); });
  EXPECT_NE(msg.find("/nonexistent/dir/model.obj"), std::string::npos) << msg;
}

// Seeded random edits of a valid file: each result loads or throws Error, nothing else.
TEST(Obj, MutatedFilesLoadOrThrowSceneError) {
  const std::string base = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nf 1 2 3 4\nf -5 -4 -1\nusemtl a\nf 1/1/1 2//2 5\n";
  const std::string alphabet = "v f0123456789-+./ \n#eE";
  int loaded = 0, rejected = 0;
  for (uint32_t seed = 0; seed < 2000; ++seed) {
    std::mt19937 rng(seed);
    std::string text = base;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const size_t at = rng() % (text.size() + 1);
      switch (rng() % 3) {
        case 0: text.insert(at, 1, alphabet[rng() % alphabet.size()]); break;
        case 1: if (at < text.size()) text.erase(at, 1); break;
        default: if (at < text.size()) text[at] = alphabet[rng() % alphabet.size()]; break;
      }
    }
    try {
      loadObjFromMemory(text, "m.obj");
      ++loaded;
    } catch (const Error& e) {
      ++rejected;
      EXPECT_EQ(std::string(e.what()).rfind("m.obj", 0), 0u) << e.what();
    }
  }
  EXPECT_GT(loaded, 100);
  EXPECT_GT(rejected, 100);
}

// ---------------------------------------------------------------- glTF

std::string base64(const std::vector<uint8_t>& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = uint32_t{bytes[i]} << 16;
    if (i + 1 < bytes.size()) v |= uint32_t{bytes[i + 1]} << 8;
    if (i + 2 < bytes.size()) v |= bytes[i + 2];
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? k[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? k[v & 63] : '=';
  }
  return out;
}

template <typename T>
void append(std::vector<uint8_t>& out, const std::vector<T>& values) {
  const auto* p = reinterpret_cast<const uint8_t*>(values.data());
  out.insert(out.end(), p, p + values.size() * sizeof(T));
}

// A unit cube (12 triangles, CCW from outside) as one glTF document with an embedded buffer;
// tests edit the JSON before loading it.
nlohmann::json cubeGltf() {
  const std::vector<float> pos = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
  const int quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}};
  std::vector<uint16_t> idx;
  for (const auto& q : quads) {
    for (int i : {q[0], q[1], q[2], q[0], q[2], q[3]}) idx.push_back(static_cast<uint16_t>(i));
  }
  std::vector<uint8_t> blob;
  append(blob, pos);
  append(blob, idx);
  nlohmann::json j;
  j["asset"] = {{"version", "2.0"}};
  j["scenes"] = {{{"nodes", {0}}}};
  j["nodes"] = {{{"mesh", 0}}};
  j["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}};
  j["buffers"] = {{{"byteLength", blob.size()}, {"uri", "data:application/octet-stream;base64," + base64(blob)}}};
  j["bufferViews"] = {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}},
                      {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 72}}};
  j["accessors"] = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"}},
                    {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}}};
  return j;
}

Scene loadJson(const nlohmann::json& j, const std::string& context = "t.gltf", bool merge = true) {
  const std::string text = j.dump();
  return loadGltfFromMemory({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, context, false, merge);
}

TEST(Gltf, CommittedCubeGltfAndGlbAgree) {
  const Scene a = loadGltf(kModels + "cube.gltf");
  const Scene b = loadGltf(kModels + "cube.glb");
  for (const Scene* s : {&a, &b}) {
    EXPECT_EQ(s->report.input_faces, 12u);
    // Face merging (mesh_merge.h): the 12 triangles of the one primitive become 6 square faces.
    EXPECT_EQ(s->polygons.size(), 6u);
    EXPECT_EQ(s->report.merged_input_faces, 12u);
    EXPECT_EQ(s->report.merged_faces, 6u);
    EXPECT_TRUE(isClosed(*s));
    const Bounds bounds = sceneBounds(*s);
    EXPECT_EQ(bounds.lo, glm::dvec3(10.0, 0.0, 0.0));  // node translation (10,0,0) of a child scaled 2x
    EXPECT_EQ(bounds.hi, glm::dvec3(12.0, 2.0, 2.0));
    expectOutward(*s, glm::dvec3(11.0, 1.0, 1.0));
    for (uint32_t c : s->face_colors) EXPECT_EQ(c, 0xff0000u);  // material base colour
  }
  EXPECT_EQ(a.vertices, b.vertices);
  const Scene unmerged = loadGltf(kModels + "cube.gltf", false);
  EXPECT_EQ(unmerged.polygons.size(), 12u);
  EXPECT_TRUE(isClosed(unmerged));
}

TEST(Gltf, MatrixAndMirrorTransformsKeepFrontsOutward) {
  nlohmann::json j = cubeGltf();
  // Column-major: a mirror in x then a shift by (5, 6, 7).
  j["nodes"][0]["matrix"] = {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 6, 7, 1};
  const Scene s = loadJson(j);
  const Bounds b = sceneBounds(s);
  EXPECT_EQ(b.lo, glm::dvec3(4.0, 6.0, 7.0));
  EXPECT_EQ(b.hi, glm::dvec3(5.0, 7.0, 8.0));
  expectOutward(s, glm::dvec3(4.5, 6.5, 7.5));
  EXPECT_TRUE(isClosed(s));
}

TEST(Gltf, RotationQuaternion) {
  nlohmann::json j = cubeGltf();
  j["nodes"][0]["rotation"] = {0.0, std::sqrt(0.5), 0.0, std::sqrt(0.5)};  // 90 degrees about +y
  const Scene s = loadJson(j);
  const Bounds b = sceneBounds(s);
  EXPECT_NEAR(b.lo.x, 0.0, 1e-12);
  EXPECT_NEAR(b.hi.x, 1.0, 1e-12);
  EXPECT_NEAR(b.lo.z, -1.0, 1e-12);  // x → -z
  EXPECT_NEAR(b.hi.z, 0.0, 1e-12);
  expectOutward(s, glm::dvec3(0.5, 0.5, -0.5));
}

TEST(Gltf, NonIndexedStripAndFan) {
  // One quad as a 4-vertex strip and as a 4-vertex fan: two triangles each, both facing +z.
  const std::vector<float> strip = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  const std::vector<float> fan = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  for (int mode : {5, 6}) {
    nlohmann::json j = cubeGltf();
    std::vector<uint8_t> blob;
    append(blob, mode == 5 ? strip : fan);
    j["buffers"][0] = {{"byteLength", blob.size()}, {"uri", "data:application/octet-stream;base64," + base64(blob)}};
    j["bufferViews"] = {{{"buffer", 0}, {"byteLength", 48}}};
    j["accessors"] = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}}};
    j["meshes"][0]["primitives"][0] = {{"attributes", {{"POSITION", 0}}}, {"mode", mode}};
    const Scene s = loadJson(j, "t.gltf", /*merge=*/false);
    ASSERT_EQ(s.polygons.size(), 2u) << "mode " << mode;
    for (const auto& p : s.polygons) EXPECT_NEAR(p.plane.n.z, 1.0, 1e-15) << "mode " << mode;
  }
}

struct BadGltf {
  const char* name;
  std::function<void(nlohmann::json&)> edit;
  const char* message;
};

TEST(Gltf, MalformedDocumentsAreSceneErrors) {
  const BadGltf cases[] = {
      {"accessor past view", [](auto& j) { j["accessors"][0]["count"] = 9; }, "accessor 0 (offset 0, 9 elements"},
      {"accessor offset", [](auto& j) { j["accessors"][1]["byteOffset"] = 4; }, "out of range of bufferView 1"},
      {"huge count", [](auto& j) { j["accessors"][1]["count"] = 4000000000u; }, "out of range of bufferView"},
      {"view past buffer", [](auto& j) { j["bufferViews"][1]["byteLength"] = 80; }, "out of range of its buffer"},
      {"missing view", [](auto& j) { j["accessors"][0]["bufferView"] = 7; }, "bufferView 7 out of range"},
      {"missing buffer", [](auto& j) { j["bufferViews"][0]["buffer"] = 3; }, "buffer 3 out of range"},
      {"index range", [](auto& j) { j["accessors"][0]["count"] = 6; }, "index 6 out of range (6 vertices)"},
      {"positions not float", [](auto& j) { j["accessors"][0]["componentType"] = 5123; }, "is not float VEC3"},
      {"indices float", [](auto& j) { j["accessors"][1]["componentType"] = 5126; j["accessors"][1]["count"] = 18; },
       "componentType 5126"},
      {"odd triangle count", [](auto& j) { j["accessors"][1]["count"] = 35; }, "not a whole number of triangles"},
      {"no position", [](auto& j) { j["meshes"][0]["primitives"][0]["attributes"] = {{"NORMAL", 0}}; },
       "no POSITION"},
      {"bad mesh", [](auto& j) { j["nodes"][0]["mesh"] = 4; }, "mesh 4 out of range"},
      {"bad child", [](auto& j) { j["nodes"][0]["children"] = {5}; }, "node 5 out of range"},
      {"cycle", [](auto& j) { j["nodes"][0]["children"] = {0}; }, "node 0 is reached twice"},
      {"bad scene", [](auto& j) { j["scene"] = 3; }, "scene"},
      {"bad material", [](auto& j) { j["meshes"][0]["primitives"][0]["material"] = 2; }, "material 2 out of range"},
      {"short matrix", [](auto& j) { j["nodes"][0]["matrix"] = {1, 0, 0}; }, "matrix has 3 numbers"},
      {"zero quaternion", [](auto& j) { j["nodes"][0]["rotation"] = {0, 0, 0, 0}; }, "not a unit quaternion"},
      {"bad mode", [](auto& j) { j["meshes"][0]["primitives"][0]["mode"] = 9; }, "bad mode 9"},
      {"no version", [](auto& j) { j.erase("asset"); }, "malformed glTF"},
      {"short base64", [](auto& j) { j["buffers"][0]["byteLength"] = 400; }, "malformed glTF"},
      {"external file", [](auto& j) { j["buffers"][0]["uri"] = "cube.bin"; }, "malformed glTF"},
      {"sparse", [](auto& j) { j["accessors"][0]["sparse"] = {{"count", 1}, {"indices", {{"bufferView", 1}, {"componentType", 5123}}}, {"values", {{"bufferView", 0}}}}; },
       "sparse"},
      {"no triangles", [](auto& j) { j["meshes"][0]["primitives"][0]["mode"] = 1; }, "no faces"},
      {"overflowing transform", [](auto& j) { j["nodes"][0]["scale"] = {1e308, 1e308, 1e308}; j["nodes"][0]["translation"] = {1e308, 0, 0}; },
       "non-finite"},
  };
  for (const auto& c : cases) {
    nlohmann::json j = cubeGltf();
    c.edit(j);
    const std::string msg = expectSceneError([&] { loadJson(j, "bad.gltf"); });
    EXPECT_EQ(msg.rfind("bad.gltf: ", 0), 0u) << c.name << ": " << msg;
    EXPECT_NE(msg.find(c.message), std::string::npos) << c.name << ": " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << c.name << ": " << msg;
  }
}

TEST(Gltf, MalformedJsonAndGlbHeaders) {
  const std::string json = "{\"asset\": {\"version\": \"2.0\"";
  EXPECT_NE(expectSceneError([&] {
              loadGltfFromMemory({reinterpret_cast<const uint8_t*>(json.data()), json.size()}, "j.gltf", false);
            }).find("j.gltf: malformed glTF"),
            std::string::npos);
  const std::vector<uint8_t> glb = readFileBytes(kModels + "cube.glb");
  auto tryGlb = [](std::vector<uint8_t> bytes) {
    return expectSceneError([&] { loadGltfFromMemory(bytes, "x.glb", true); });
  };
  EXPECT_NE(tryGlb({glb.begin(), glb.begin() + 7}).find("x.glb: truncated GLB header"), std::string::npos);
  EXPECT_NE(tryGlb({glb.begin(), glb.begin() + 100}).find("x.glb: truncated GLB (header says 908"), std::string::npos);
  std::vector<uint8_t> magic = glb;
  magic[0] = 'G';
  EXPECT_NE(tryGlb(magic).find("x.glb: not a GLB file (bad magic)"), std::string::npos);
  std::vector<uint8_t> version = glb;
  version[4] = 1;
  EXPECT_NE(tryGlb(version).find("GLB version 1"), std::string::npos);
  std::vector<uint8_t> chunk = glb;
  chunk[12] = 0xff;  // JSON chunk longer than the file
  EXPECT_NE(tryGlb(chunk).find("x.glb: malformed glTF"), std::string::npos);
}

TEST(Gltf, DeepJsonNestingIsRefusedNotAStackOverflow) {
  // tinygltf converts `extras` recursively; 30000 levels overflowed the stack before the check.
  const std::string deep = "{\"asset\":{\"version\":\"2.0\"},\"extras\":" + std::string(30000, '[') +
                           std::string(30000, ']') + "}";
  const std::string msg = expectSceneError([&] {
    loadGltfFromMemory({reinterpret_cast<const uint8_t*>(deep.data()), deep.size()}, "deep.gltf", false);
  });
  EXPECT_NE(msg.find("deep.gltf: malformed glTF: JSON nested deeper than"), std::string::npos) << msg;
  // Brackets inside strings do not count.
  nlohmann::json j = cubeGltf();
  j["extras"] = {{"text", std::string(1000, '[') + "\"{"}};
  EXPECT_EQ(loadJson(j, "t.gltf", /*merge=*/false).polygons.size(), 12u);
}

TEST(Gltf, InstancingBeyondTheTriangleCapIsRefusedBeforeBuilding) {
  // 42 nodes x 10 primitives x 10000 triangles (one shared index accessor) = 4.2M > 2^22.
  nlohmann::json j = cubeGltf();
  std::vector<uint8_t> blob(96 + 30000, 0);
  j["buffers"][0] = {{"byteLength", blob.size()}, {"uri", "data:application/octet-stream;base64," + base64(blob)}};
  j["bufferViews"][1] = {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 30000}};
  j["accessors"][1] = {{"bufferView", 1}, {"componentType", 5121}, {"count", 30000}, {"type", "SCALAR"}};
  nlohmann::json prims = nlohmann::json::array();
  for (int i = 0; i < 10; ++i) prims.push_back({{"attributes", {{"POSITION", 0}}}, {"indices", 1}});
  j["meshes"][0]["primitives"] = prims;
  j["nodes"] = nlohmann::json::array();
  j["scenes"][0]["nodes"] = nlohmann::json::array();
  for (int i = 0; i < 42; ++i) {
    j["nodes"].push_back({{"mesh", 0}});
    j["scenes"][0]["nodes"].push_back(i);
  }
  const std::string msg = expectSceneError([&] { loadJson(j, "many.gltf"); });
  EXPECT_NE(msg.find("many.gltf: more than 4194304 triangles"), std::string::npos) << msg;
  // One node fewer than the cap needs loads (all triangles degenerate: indices are all 0).
  j["nodes"] = {{{"mesh", 0}}};
  j["scenes"][0]["nodes"] = {0};
  const Scene s = loadJson(j, "one.gltf");
  EXPECT_EQ(s.report.input_faces, 100000u);
  EXPECT_EQ(s.report.dropped_degenerate, 100000u);
}

// Seeded random byte edits of the committed .glb and .gltf: load or Error, nothing else.
TEST(Gltf, MutatedFilesLoadOrThrowSceneError) {
  for (const char* name : {"cube.glb", "cube.gltf"}) {
    const std::vector<uint8_t> base = readFileBytes(kModels + name);
    const bool binary = std::string(name).ends_with(".glb");
    int loaded = 0, rejected = 0;
    for (uint32_t seed = 0; seed < 1500; ++seed) {
      std::mt19937 rng(seed);
      std::vector<uint8_t> bytes = base;
      const int edits = 1 + static_cast<int>(rng() % 3);
      for (int e = 0; e < edits; ++e) {
        const size_t at = rng() % bytes.size();
        switch (rng() % 4) {
          case 0: bytes[at] = static_cast<uint8_t>(rng()); break;
          case 1: bytes[at] ^= static_cast<uint8_t>(1u << (rng() % 8)); break;
          case 2: bytes.erase(bytes.begin() + static_cast<long>(at)); break;
          default: bytes[at] = static_cast<uint8_t>("0123456789"[rng() % 10]); break;
        }
      }
      try {
        loadGltfFromMemory(bytes, name, binary);
        ++loaded;
      } catch (const Error& e) {
        ++rejected;
        EXPECT_EQ(std::string(e.what()).rfind(name, 0), 0u) << e.what();
      }
    }
    EXPECT_GT(loaded, 50) << name;
    EXPECT_GT(rejected, 50) << name;
  }
}

}  // namespace
}  // namespace walkvis
