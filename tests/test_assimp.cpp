// The assimp loader (scenes/assimp.cpp): real IFC in y-up metres, instancing and transforms, what
// each format states about units and axes and the command-line overrides of it, bad files, and
// the same house exported by `assimp export` to other formats loading to the same geometry.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "scenes/loaders.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

namespace fs = std::filesystem;

const fs::path kHaus = "/usr/share/assimp/models/IFC/AC14-FZK-Haus.ifc";  // Debian's assimp-testmodels
const fs::path kModels = fs::path(WALKVIS_SOURCE_DIR) / "tests" / "data" / "models";

struct TempDir {
  fs::path path;
  TempDir() {
    char tmpl[] = "/tmp/walkvis_assimp_XXXXXX";
    const char* made = mkdtemp(tmpl);
    EXPECT_NE(made, nullptr);
    path = made ? made : "/tmp";
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

void writeText(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool hasNote(const Scene& scene, const std::string& part) {
  return std::any_of(scene.report.notes.begin(), scene.report.notes.end(),
                     [&](const std::string& n) { return n.find(part) != std::string::npos; });
}

std::string notes(const Scene& scene) {
  std::string s;
  for (const auto& n : scene.report.notes) s += n + "\n";
  return s;
}

void expectBounds(const Scene& scene, glm::dvec3 lo, glm::dvec3 hi, double tol) {
  const Bounds b = sceneBounds(scene);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(b.lo[k], lo[k], tol) << "lo[" << k << "]\n" << notes(scene);
    EXPECT_NEAR(b.hi[k], hi[k], tol) << "hi[" << k << "]\n" << notes(scene);
  }
}

LoadOptions noMerge() {
  LoadOptions o;
  o.merge_faces = false;
  return o;
}

TEST(Assimp, ReadsTheUsualExtensions) {
  for (const char* ext : {"ifc", ".IFC", "fbx", "dae", "3ds", "ply", "stl", "off", ".obj", "gltf"}) {
    EXPECT_TRUE(assimpReadsExtension(ext)) << ext;
  }
  for (const char* ext : {"", ".", "xyz", "wad", "ifc.", "notaformat"}) EXPECT_FALSE(assimpReadsExtension(ext)) << ext;
}

TEST(Assimp, FzkHausIsAHouseInYUpMetres) {
  if (!fs::exists(kHaus)) GTEST_SKIP() << kHaus << " absent (Debian package assimp-testmodels)";
  const auto start = std::chrono::steady_clock::now();
  const Scene scene = loadAssimp(kHaus, LoadOptions{});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const Bounds b = sceneBounds(scene);
  const glm::dvec3 size = b.hi - b.lo;
  std::cout << "FZK-Haus: " << scene.report.input_faces << " input faces, " << scene.polygons.size()
            << " polygons, bounds (" << b.lo.x << ", " << b.lo.y << ", " << b.lo.z << ") .. (" << b.hi.x << ", "
            << b.hi.y << ", " << b.hi.z << "), " << seconds << " s\n"
            << notes(scene);
  // A two-storey house on its plot: 10-25 m across, 4-12 m tall (not millimetres, not z-up).
  EXPECT_GT(size.x, 10.0);
  EXPECT_LT(size.x, 25.0);
  EXPECT_GT(size.z, 10.0);
  EXPECT_LT(size.z, 25.0);
  EXPECT_GT(size.y, 4.0);
  EXPECT_LT(size.y, 12.0);
  EXPECT_GT(scene.polygons.size(), 1000u);
  EXPECT_GT(scene.report.input_faces, 10000u);
  const std::set<uint32_t> colors(scene.face_colors.begin(), scene.face_colors.end());
  EXPECT_GE(colors.size(), 3u);
  EXPECT_TRUE(hasNote(scene, "IFC")) << notes(scene);
  // assimp's z-up turn is a float matrix holding cos(90°) = -4.4e-8; snapped, floors are exactly
  // horizontal (Newell's normal of a loop at one height has x = z = 0 exactly).
  size_t horizontal = 0;
  for (const auto& p : scene.polygons) horizontal += p.plane.n.x == 0.0 && p.plane.n.z == 0.0;
  EXPECT_GT(horizontal, 100u);
}

// The house's levels are its two storeys for any walker from 2.04 m (the default) down to 1.6 m.
// The double bed's top (0.5 m, 2.0 m under the slab) is no level when a walker fits over it: its
// open sides are drops to the floor. The navmesh once read them as walls (the floor's column
// beside the bed held only the bed's rasterized side face) and made the bed a level at <= 1.9 m.
// The spiral stair joins nothing: the attic slab covers its treads up to 0.88 m (1.62 m of
// headroom), and its treads are about 0.75 m long between the post and the handrail.
TEST(Assimp, FzkHausLevelsAreItsStoreysForWalkersFrom1p6To2p04) {
  if (!fs::exists(kHaus)) GTEST_SKIP() << kHaus << " absent (Debian package assimp-testmodels)";
  double attic_area = 0.0;
  for (const double h : {2.04, 1.9, 1.8, 1.6}) {
    LoadOptions options;
    options.walkable.agent_height = h;
    const Scene scene = loadScene(kHaus.string(), options);
    ASSERT_EQ(scene.levels.size(), 2u) << "agent height " << h;
    EXPECT_NEAR(scene.levels[0].floor_y, 0.0, 1e-6) << h;
    EXPECT_NEAR(scene.levels[1].floor_y, 2.7, 1e-6) << h;
    EXPECT_GT(scene.levels[0].walkable_area, 150.0) << h;
    // Under the pitched roof a lower walker stands on more of the attic.
    EXPECT_GT(scene.levels[1].walkable_area, attic_area) << h;
    attic_area = scene.levels[1].walkable_area;
    for (const auto& c : scene.connections) EXPECT_NE(c.levels.size(), 2u) << h;
  }
}

// One red triangle (0,0,0) (1,0,0) (0,1,0), facing +z, referenced by three nodes: translated by
// +10 x; mirrored in x and moved by -10 x; turned 90° about z under a parent moved +5 y.
std::string instancedCollada(const std::string& unit_meter, const std::string& up) {
  const std::string bind =
      "<bind_material><technique_common><instance_material symbol=\"mat\" target=\"#red\"/></technique_common>"
      "</bind_material>";
  return R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="u" meter=")" + unit_meter + R"("/><up_axis>)" + up + R"(</up_axis></asset>
  <library_effects><effect id="red-fx"><profile_COMMON><technique sid="common"><lambert><diffuse><color>1 0 0 1</color></diffuse></lambert></technique></profile_COMMON></effect></library_effects>
  <library_materials><material id="red" name="red"><instance_effect url="#red-fx"/></material></library_materials>
  <library_geometries>
    <geometry id="tri" name="tri"><mesh>
      <source id="tri-pos"><float_array id="tri-pos-array" count="9">0 0 0 1 0 0 0 1 0</float_array>
        <technique_common><accessor source="#tri-pos-array" count="3" stride="3"><param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
      <vertices id="tri-vtx"><input semantic="POSITION" source="#tri-pos"/></vertices>
      <triangles material="mat" count="1"><input semantic="VERTEX" source="#tri-vtx" offset="0"/><p>0 1 2</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene">
      <node id="a"><matrix>1 0 0 10 0 1 0 0 0 0 1 0 0 0 0 1</matrix><instance_geometry url="#tri">)" +
         bind + R"(</instance_geometry></node>
      <node id="b"><matrix>-1 0 0 -10 0 1 0 0 0 0 1 0 0 0 0 1</matrix><instance_geometry url="#tri">)" +
         bind + R"(</instance_geometry></node>
      <node id="c"><matrix>1 0 0 0 0 1 0 5 0 0 1 0 0 0 0 1</matrix>
        <node id="d"><matrix>0 -1 0 0 1 0 0 0 0 0 1 0 0 0 0 1</matrix><instance_geometry url="#tri">)" +
         bind + R"(</instance_geometry></node>
      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
}

std::multiset<std::vector<double>> triangleSet(const Scene& scene) {
  std::multiset<std::vector<double>> out;
  for (size_t i = 0; i < scene.polygons.size(); ++i) {
    std::vector<std::vector<double>> corners;
    for (const auto& v : scene.polygonVertices(i)) corners.push_back({v.x, v.y, v.z});
    std::sort(corners.begin(), corners.end());
    std::vector<double> flat;
    for (const auto& c : corners) flat.insert(flat.end(), c.begin(), c.end());
    out.insert(flat);
  }
  return out;
}

TEST(Assimp, EachNodeInstanceOfAMeshIsAddedAtItsTransform) {
  TempDir dir;
  const fs::path file = dir.path / "instanced.dae";
  writeText(file, instancedCollada("1", "Y_UP"));
  const Scene scene = loadAssimp(file, noMerge());
  ASSERT_EQ(scene.polygons.size(), 3u) << notes(scene);
  EXPECT_TRUE(hasNote(scene, "3 mesh instances of 1 meshes")) << notes(scene);
  const std::multiset<std::vector<double>> expected = {
      {10, 0, 0, 10, 1, 0, 11, 0, 0},   // translated
      {-11, 0, 0, -10, 0, 0, -10, 1, 0},  // mirrored: (-x - 10)
      {-1, 5, 0, 0, 5, 0, 0, 6, 0},     // turned 90° about z, then +5 y
  };
  const auto got = triangleSet(scene);
  ASSERT_EQ(got.size(), expected.size());
  auto g = got.begin();
  for (auto e = expected.begin(); e != expected.end(); ++e, ++g) {
    for (size_t k = 0; k < 9; ++k) EXPECT_NEAR((*g)[k], (*e)[k], 1e-12);
  }
  for (const auto& p : scene.polygons) {
    // Still facing +z: the mirrored instance's triangle was turned back counter-clockwise.
    EXPECT_NEAR(p.plane.n.z, 1.0, 1e-12);
    EXPECT_EQ(scene.face_colors[p.face_id], 0xff0000u);
  }
}

TEST(Assimp, ColladaUnitAndUpAxisAreAppliedOnceAndCanBeOverridden) {
  TempDir dir;
  const fs::path file = dir.path / "cm_zup.dae";
  writeText(file, instancedCollada("0.01", "Z_UP"));
  // As the file states: centimetres, z-up. File (x, y, z) -> (x, z, -y) / 100. assimp holds the
  // 0.01 as a float in the root matrix: relative error up to 6e-8, so 1e-7 m on 0.11 m.
  const double float_tol = 1e-7;
  const Scene stated = loadAssimp(file, noMerge());
  expectBounds(stated, {-0.11, 0.0, -0.06}, {0.11, 0.0, 0.0}, float_tol);
  EXPECT_TRUE(hasNote(stated, "Z_UP")) << notes(stated);
  // Overridden: the file is y-up in metres after all.
  LoadOptions o = noMerge();
  o.up_axis = 'y';
  o.unit_scale = 1.0;
  const Scene given = loadAssimp(file, o);
  expectBounds(given, {-11, 0, 0}, {11, 6, 0}, 20 * float_tol);
  EXPECT_TRUE(hasNote(given, "given on the command line")) << notes(given);
  // Only the up axis given: the unit still from the file.
  o.unit_scale = -1.0;
  o.up_axis = 'z';
  expectBounds(loadAssimp(file, o), {-0.11, 0.0, -0.06}, {0.11, 0.0, 0.0}, float_tol);
}

TEST(Assimp, IfcMillimetresAndZUpAreConvertedAndCanBeOverridden) {
  const fs::path file = kModels / "assimp" / "tiny.ifc";  // a 4 m x 0.2 m x 3 m wall, in mm, z-up
  const Scene stated = loadAssimp(file, noMerge());
  expectBounds(stated, {0, 0, -0.2}, {4, 3, 0}, 1e-6);
  EXPECT_TRUE(hasNote(stated, "millimetre")) << notes(stated);
  // Exactly vertical and horizontal faces once assimp's float rotation is snapped.
  for (const auto& p : stated.polygons) {
    const int zeros = (p.plane.n.x == 0.0) + (p.plane.n.y == 0.0) + (p.plane.n.z == 0.0);
    EXPECT_EQ(zeros, 2) << p.plane.n.x << " " << p.plane.n.y << " " << p.plane.n.z;
  }
  LoadOptions o = noMerge();
  o.up_axis = 'y';  // take the file's own coordinates as y-up: assimp's turn undone
  expectBounds(loadAssimp(file, o), {0, 0, 0}, {4, 0.2, 3}, 1e-6);
  o.up_axis = 'z';
  o.unit_scale = 1.0;  // one metre per file unit: 1000 times larger
  const Scene metres = loadAssimp(file, o);
  expectBounds(metres, {0, 0, -200}, {4000, 3000, 0}, 1e-3);
  EXPECT_TRUE(hasNote(metres, "given on the command line")) << notes(metres);
}

TEST(Assimp, IfcWithoutUnitsOverAKilometreIsMillimetres) {
  TempDir dir;
  std::string text = readText(kModels / "assimp" / "tiny.ifc");
  const std::string unit = "IFCSIUNIT(*,.LENGTHUNIT.,.MILLI.,.METRE.)";
  ASSERT_NE(text.find(unit), std::string::npos);
  text.replace(text.find(unit), unit.size(), "IFCSIUNIT(*,.AREAUNIT.,$,.SQUARE_METRE.)");
  writeText(dir.path / "nounit.ifc", text);
  const Scene scene = loadAssimp(dir.path / "nounit.ifc", noMerge());
  expectBounds(scene, {0, 0, -0.2}, {4, 3, 0}, 1e-6);
  EXPECT_TRUE(hasNote(scene, "assumed millimetres")) << notes(scene);
}

TEST(Assimp, FbxUnitScaleFactorAndAxesAreApplied) {
  const std::string fbx = readText(kModels / "assimp" / "cube.fbx");  // assimp's export: UnitScaleFactor 1 (cm)
  const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(fbx.data()), fbx.size());
  const Scene cm = loadAssimpFromMemory(bytes, "fbx", "cube.fbx", noMerge());
  expectBounds(cm, {0, 0, 0}, {0.01, 0.01, 0.01}, 1e-9);
  EXPECT_TRUE(hasNote(cm, "UnitScaleFactor 1")) << notes(cm);
  // The same cube stated as metres and z-up (3ds Max's axes: up +z, front -y).
  std::string edited = fbx;
  const auto set = [&](const std::string& key, const std::string& value) {
    const std::string prefix = "P: \"" + key + "\", ";
    const size_t at = edited.find(prefix);
    ASSERT_NE(at, std::string::npos) << key;
    const size_t end = edited.find('\n', at);
    const size_t last = edited.rfind(", ", end);
    edited.replace(last + 2, end - last - 2, value);
  };
  set("UnitScaleFactor", "100");
  set("UpAxis", "2");
  set("FrontAxis", "1");
  set("FrontAxisSign", "-1");
  const std::span<const uint8_t> edited_bytes(reinterpret_cast<const uint8_t*>(edited.data()), edited.size());
  const Scene zup = loadAssimpFromMemory(edited_bytes, "fbx", "zup.fbx", noMerge());
  expectBounds(zup, {0, 0, -1}, {1, 1, 0}, 1e-9);
  // Overrides win over the metadata.
  LoadOptions o = noMerge();
  o.up_axis = 'y';
  o.unit_scale = 2.0;
  expectBounds(loadAssimpFromMemory(edited_bytes, "fbx", "zup.fbx", o), {0, 0, 0}, {2, 2, 2}, 1e-9);
}

TEST(Assimp, FormatsThatStateNothingAreYUpMetresUnlessTold) {
  // cube.obj names cube.mtl beside it: loading from the path resolves it (colours from it).
  const Scene obj = loadAssimp(kModels / "cube.obj", noMerge());
  expectBounds(obj, {0, 0, 0}, {1, 1, 1}, 1e-12);
  EXPECT_TRUE(hasNote(obj, "assumed y-up")) << notes(obj);
  LoadOptions o = noMerge();
  o.up_axis = 'z';
  o.unit_scale = 2.0;
  const Scene turned = loadAssimp(kModels / "cube.obj", o);
  expectBounds(turned, {0, 0, -2}, {2, 2, 0}, 1e-12);
  EXPECT_EQ(turned.polygons.size(), obj.polygons.size());
  for (const char* name : {"cube.ply", "cube_binary.ply", "cube.stl", "cube_binary.stl", "cube.off", "cube.dae"}) {
    const Scene s = loadAssimp(kModels / "assimp" / name, noMerge());
    EXPECT_EQ(s.report.input_faces, 12u) << name;
    expectBounds(s, {0, 0, 0}, {1, 1, 1}, 1e-6);
  }
}

TEST(Assimp, BadFilesAreSceneErrorsNamingTheFile) {
  TempDir dir;
  const auto expectError = [](const std::string& path, const std::string& part) {
    try {
      loadAssimp(path, LoadOptions{});
      ADD_FAILURE() << path << " loaded";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path, 0), 0u) << what;
      EXPECT_NE(what.find(part), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  };
  expectError((dir.path / "missing.ifc").string(), "cannot open");
  writeText(dir.path / "empty.fbx", "");
  expectError((dir.path / "empty.fbx").string(), "empty file");
  const std::string ifc = readText(kModels / "assimp" / "tiny.ifc");
  writeText(dir.path / "truncated.ifc", ifc.substr(0, ifc.size() / 2));
  expectError((dir.path / "truncated.ifc").string(), "truncated");  // assimp 5.2 would crash on it
  writeText(dir.path / "garbage.dae", std::string(300, '\x93'));
  expectError((dir.path / "garbage.dae").string(), "assimp: ");
  writeText(dir.path / "lines.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n");
  expectError((dir.path / "lines.off").string(), "no triangles");
  // A Collada node that instances itself: assimp 5.2 would recurse until the stack overflows.
  std::string cycle = instancedCollada("1", "Y_UP");
  cycle.replace(cycle.find("<node id=\"d\">"), 13, "<node id=\"d\"><instance_node url=\"#c\"/>");
  writeText(dir.path / "cycle.dae", cycle);
  expectError((dir.path / "cycle.dae").string(), "cycle");
  // From memory the context names the input, and no other file is read (the OBJ's mtllib).
  const std::string obj = "mtllib " + (kModels / "cube.mtl").string() + "\nusemtl green\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(obj.data()), obj.size());
  const Scene mem = loadAssimpFromMemory(bytes, "obj", "memory.obj", noMerge());
  EXPECT_EQ(mem.polygons.size(), 1u);
  EXPECT_NE(mem.face_colors.at(0), 0x00ff00u);  // green from cube.mtl would mean it was read
  try {
    const std::string junk = "\x01\x02 not a model";
    loadAssimpFromMemory(std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(junk.data()), junk.size()), "ply",
                         "memory.ply", LoadOptions{});
    ADD_FAILURE() << "junk loaded";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("memory.ply: ", 0), 0u) << e.what();
  }
}

TEST(Assimp, ExportsOfTheHouseLoadToTheSameGeometryAndLevels) {
  if (!fs::exists(kHaus)) GTEST_SKIP() << kHaus << " absent (Debian package assimp-testmodels)";
  if (std::system("command -v assimp >/dev/null 2>&1") != 0) GTEST_SKIP() << "assimp CLI absent (assimp-utils)";
  const Scene ifc = loadAssimp(kHaus, noMerge());
  const Bounds want = sceneBounds(ifc);
  const Scene ifc_levels = loadScene(kHaus.string());
  ASSERT_GE(ifc_levels.levels.size(), 2u);
  TempDir dir;
  struct Export {
    const char* format;  // assimp export -f
    const char* ext;
    char up;             // what to tell the loader; 0: nothing
    double unit_scale;
  };
  // assimp 5.2's own FBX writer stores z-up data under y-up axis metadata with UnitScaleFactor 1
  // (centimetres), so that file needs --up z --unit-scale 1; its 3DS writer misplaces nodes (assimp
  // itself reads its bounds back wrong) and is left out.
  const Export exports[] = {{"obj", "obj", 0, -1.0},  {"collada", "dae", 0, -1.0}, {"ply", "ply", 0, -1.0},
                            {"stl", "stl", 0, -1.0},  {"glb2", "glb", 0, -1.0},    {"x", "x", 0, -1.0},
                            {"fbxa", "fbx", 'z', 1.0}};
  for (const Export& e : exports) {
    SCOPED_TRACE(e.format);
    const fs::path out = dir.path / (std::string("haus.") + e.ext);
    const std::string cmd =
        "assimp export '" + kHaus.string() + "' '" + out.string() + "' -f" + e.format + " >/dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    LoadOptions options = noMerge();
    options.loader = "assimp";
    options.up_axis = e.up;
    options.unit_scale = e.unit_scale;
    const Scene s = loadAssimp(out, options);
    // The same triangles, but a writer may drop or keep a few degenerate ones: within 1%.
    EXPECT_NEAR(static_cast<double>(s.polygons.size()), static_cast<double>(ifc.polygons.size()),
                0.01 * static_cast<double>(ifc.polygons.size()));
    const Bounds got = sceneBounds(s);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(got.lo[k], want.lo[k], 1e-3);
      EXPECT_NEAR(got.hi[k], want.hi[k], 1e-3);
    }
    // The same storeys: floor heights to float rounding, areas within 0.5% (a writer's float
    // rounding can move a floor face's edge across a navmesh cell).
    options.merge_faces = true;
    const Scene with_levels = loadScene(out.string(), options);
    ASSERT_EQ(with_levels.levels.size(), ifc_levels.levels.size());
    for (size_t l = 0; l < ifc_levels.levels.size(); ++l) {
      EXPECT_NEAR(with_levels.levels[l].floor_y, ifc_levels.levels[l].floor_y, 1e-5);
      EXPECT_NEAR(with_levels.levels[l].walkable_area, ifc_levels.levels[l].walkable_area,
                  5e-3 * ifc_levels.levels[l].walkable_area);
    }
  }
}

}  // namespace
}  // namespace walkvis
