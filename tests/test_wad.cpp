// Doom WAD maps: every Freedoom map loads with levels and a start eye above a walkable region;
// walls face into the playable space; a hand-made WAD loads exactly as drawn; malformed WADs give
// one-line SceneErrors and never crash.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <unistd.h>

#include "core/byte_io.h"
#include "scenes/loaders.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

const std::string kFreedoom1 = "/usr/share/games/doom/freedoom1.wad";
const std::string kFreedoom2 = "/usr/share/games/doom/freedoom2.wad";

// ---- Building WADs in memory ----

void putU16(std::vector<uint8_t>& b, int v) {
  b.push_back(static_cast<uint8_t>(v & 0xFF));
  b.push_back(static_cast<uint8_t>((v >> 8) & 0xFF));
}
void putI32(std::vector<uint8_t>& b, int64_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<uint8_t>((v >> (8 * i)) & 0xFF));
}
void putName(std::vector<uint8_t>& b, const std::string& s) {
  for (size_t i = 0; i < 8; ++i) b.push_back(i < s.size() ? static_cast<uint8_t>(s[i]) : 0);
}

struct LumpSpec {
  std::string name;
  std::vector<uint8_t> data;
};

std::vector<uint8_t> buildWad(const std::vector<LumpSpec>& lumps) {
  std::vector<uint8_t> out{'P', 'W', 'A', 'D'};
  putI32(out, static_cast<int64_t>(lumps.size()));
  size_t dir = 12;
  for (const auto& l : lumps) dir += l.data.size();
  putI32(out, static_cast<int64_t>(dir));
  for (const auto& l : lumps) out.insert(out.end(), l.data.begin(), l.data.end());
  size_t pos = 12;
  for (const auto& l : lumps) {
    putI32(out, static_cast<int64_t>(pos));
    putI32(out, static_cast<int64_t>(l.data.size()));
    putName(out, l.name);
    pos += l.data.size();
  }
  return out;
}

struct TestMap {
  struct Vertex { int x, y; };
  struct Linedef { int v1, v2, front, back; };
  struct Sidedef { int sector; };
  struct Sector { int floor, ceiling; std::string ceiling_flat = "CEIL1_1"; };
  struct Thing { int x, y, angle, type; };
  std::vector<Vertex> vertices;
  std::vector<Linedef> linedefs;
  std::vector<Sidedef> sidedefs;
  std::vector<Sector> sectors;
  std::vector<Thing> things;

  std::vector<LumpSpec> lumps(const std::string& marker) const {
    std::vector<LumpSpec> out(9);
    out[0].name = marker;
    out[1].name = "THINGS";
    for (const auto& t : things) {
      putU16(out[1].data, t.x);
      putU16(out[1].data, t.y);
      putU16(out[1].data, t.angle);
      putU16(out[1].data, t.type);
      putU16(out[1].data, 7);
    }
    out[2].name = "LINEDEFS";
    for (const auto& l : linedefs) {
      putU16(out[2].data, l.v1);
      putU16(out[2].data, l.v2);
      putU16(out[2].data, l.back < 0 ? 1 : 4);  // flags: impassable / two-sided
      putU16(out[2].data, 0);
      putU16(out[2].data, 0);
      putU16(out[2].data, l.front < 0 ? 0xFFFF : l.front);
      putU16(out[2].data, l.back < 0 ? 0xFFFF : l.back);
    }
    out[3].name = "SIDEDEFS";
    for (const auto& s : sidedefs) {
      putU16(out[3].data, 0);
      putU16(out[3].data, 0);
      putName(out[3].data, "-");
      putName(out[3].data, "-");
      putName(out[3].data, "STARTAN3");
      putU16(out[3].data, s.sector);
    }
    out[4].name = "VERTEXES";
    for (const auto& v : vertices) {
      putU16(out[4].data, v.x);
      putU16(out[4].data, v.y);
    }
    out[5].name = "SEGS";
    out[6].name = "SSECTORS";
    out[7].name = "NODES";
    out[8].name = "SECTORS";
    for (const auto& s : sectors) {
      putU16(out[8].data, s.floor);
      putU16(out[8].data, s.ceiling);
      putName(out[8].data, "FLOOR4_8");
      putName(out[8].data, s.ceiling_flat);
      putU16(out[8].data, 160);
      putU16(out[8].data, 0);
      putU16(out[8].data, 0);
    }
    return out;
  }
};

// A 256 x 256 room (floor 0, ceiling 128) with a 64 x 64 platform (floor 32) inside, and the
// player 1 start at (200, 200) looking north (angle 90).
TestMap roomWithPlatform() {
  TestMap m;
  // Outer square clockwise (front side = right = inside); platform counter-clockwise (front = room).
  m.vertices = {{0, 0}, {0, 256}, {256, 256}, {256, 0}, {64, 64}, {128, 64}, {128, 128}, {64, 128}};
  m.sectors = {{0, 128}, {32, 128}};
  m.sidedefs = {{0}, {0}, {0}, {0}, {0}, {1}, {0}, {1}, {0}, {1}, {0}, {1}};
  m.linedefs = {{0, 1, 0, -1}, {1, 2, 1, -1}, {2, 3, 2, -1}, {3, 0, 3, -1},
                {4, 5, 4, 5},  {5, 6, 6, 7},  {6, 7, 8, 9},  {7, 4, 10, 11}};
  m.things = {{200, 200, 90, 1}, {100, 100, 0, 3004}};
  return m;
}

std::vector<uint8_t> roomWad() {
  auto lumps = roomWithPlatform().lumps("MAP01");
  return buildWad(lumps);
}

std::string loadError(const std::vector<uint8_t>& bytes, const std::string& map = "MAP01") {
  try {
    loadWadMapFromMemory(bytes, map, "test.wad");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

bool insideConvexXz(const std::vector<glm::dvec2>& piece, glm::dvec2 q) {
  // Walkable pieces are counter-clockwise from +y: clockwise in (x, z), every cross product <= 0.
  for (size_t i = 0; i < piece.size(); ++i) {
    glm::dvec2 a = piece[i], b = piece[(i + 1) % piece.size()];
    if ((b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x) > 0.0) return false;
  }
  return true;
}

bool startAboveWalkable(const Scene& scene) {
  const glm::dvec2 q(scene.start_eye.x, scene.start_eye.z);
  for (const auto& level : scene.levels) {
    if (std::abs(level.floor_y + scene.eye_height - scene.start_eye.y) > 1e-9) continue;
    for (const auto& piece : level.walkable) {
      if (insideConvexXz(piece, q)) return true;
    }
  }
  return false;
}

glm::dvec3 centroid(std::span<const glm::dvec3> v) {
  glm::dvec3 c(0.0);
  for (const auto& p : v) c += p;
  return c / static_cast<double>(v.size());
}

// ---- An independent reading of a map's sectors, for the facing property ----

struct RawSector {
  double floor, ceiling;
  std::vector<std::pair<glm::dvec2, glm::dvec2>> edges;  // Doom (x, y)
};

int16_t i16(const std::vector<uint8_t>& b, size_t at) { return static_cast<int16_t>(b[at] | b[at + 1] << 8); }
int32_t i32(const std::vector<uint8_t>& b, size_t at) {
  return static_cast<int32_t>(b[at] | b[at + 1] << 8 | b[at + 2] << 16 | uint32_t(b[at + 3]) << 24);
}

std::vector<RawSector> rawSectors(const std::vector<uint8_t>& wad, const std::string& map) {
  const int32_t n = i32(wad, 4), dir = i32(wad, 8);
  auto name = [&](int32_t i) { return std::string(reinterpret_cast<const char*>(&wad[dir + 16 * i + 8]), strnlen(reinterpret_cast<const char*>(&wad[dir + 16 * i + 8]), 8)); };
  int32_t marker = -1;
  for (int32_t i = 0; i < n; ++i) {
    if (name(i) == map) marker = i;
  }
  EXPECT_GE(marker, 0);
  auto lump = [&](const std::string& want) {
    for (int32_t i = marker + 1; i < marker + 11 && i < n; ++i) {
      if (name(i) == want) {
        int32_t pos = i32(wad, dir + 16 * i), size = i32(wad, dir + 16 * i + 4);
        return std::vector<uint8_t>(wad.begin() + pos, wad.begin() + pos + size);
      }
    }
    ADD_FAILURE() << "no lump " << want;
    return std::vector<uint8_t>{};
  };
  const auto linedefs = lump("LINEDEFS"), sidedefs = lump("SIDEDEFS"), vertexes = lump("VERTEXES"),
             sectors = lump("SECTORS");
  std::vector<RawSector> out(sectors.size() / 26);
  for (size_t s = 0; s < out.size(); ++s) {
    out[s].floor = i16(sectors, 26 * s);
    out[s].ceiling = i16(sectors, 26 * s + 2);
  }
  for (size_t l = 0; l < linedefs.size() / 14; ++l) {
    const auto v1 = static_cast<uint16_t>(i16(linedefs, 14 * l)), v2 = static_cast<uint16_t>(i16(linedefs, 14 * l + 2));
    const glm::dvec2 a(i16(vertexes, 4 * v1), i16(vertexes, 4 * v1 + 2));
    const glm::dvec2 b(i16(vertexes, 4 * v2), i16(vertexes, 4 * v2 + 2));
    int sec[2] = {-1, -1};
    for (int side = 0; side < 2; ++side) {
      const auto sd = static_cast<uint16_t>(i16(linedefs, 14 * l + 10 + 2 * side));
      if (sd != 0xFFFF) sec[side] = static_cast<uint16_t>(i16(sidedefs, 30 * sd + 28));
    }
    if (sec[0] == sec[1]) continue;
    for (int s : sec) {
      if (s >= 0) out[s].edges.emplace_back(a, b);
    }
  }
  return out;
}

bool insideSector(const RawSector& s, glm::dvec2 p) {
  bool in = false;
  for (const auto& [a, b] : s.edges) {
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

// Every vertical polygon, stepped a little from its centroid along its normal, lands inside a
// sector between that sector's floor and ceiling. Returns the number of walls checked.
size_t expectWallsFaceIntoSectors(const Scene& scene, const std::vector<RawSector>& sectors, const std::string& what) {
  size_t walls = 0, bad = 0;
  for (size_t i = 0; i < scene.polygons.size(); ++i) {
    const auto& poly = scene.polygons[i];
    if (std::abs(poly.plane.n.y) > 1e-9) continue;
    ++walls;
    // The polygon's own winding, not the stored plane: what a renderer culls by.
    const Plane own = newellPlane(scene.polygonVertices(i));
    // 1/32 unit: freedoom2 MAP01 has a sector only 0.3 units wide (sector 72, under linedef 766).
    const glm::dvec3 p = centroid(scene.polygonVertices(i)) + (1.0 / 32.0) * own.n;
    const glm::dvec2 doom(p.x, -p.z);
    bool ok = false;
    for (const auto& s : sectors) {
      if (s.floor <= p.y && p.y <= s.ceiling && insideSector(s, doom)) {
        ok = true;
        break;
      }
    }
    if (!ok && ++bad <= 5) ADD_FAILURE() << what << ": wall polygon " << i << " faces out of the map at (" << p.x
                                         << ", " << p.y << ", " << p.z << ")";
  }
  EXPECT_EQ(bad, 0u) << what << ": of " << walls << " walls";
  return walls;
}

// ---- The hand-made map ----

TEST(Wad, HandMadeMapLoadsAsDrawn) {
  const auto bytes = roomWad();
  const Scene scene = loadWadMapFromMemory(bytes, "map01", "room.wad");
  // 4 outer walls, 4 platform step walls, 2 floors, 2 ceilings.
  EXPECT_EQ(scene.report.input_faces, 12u);
  EXPECT_EQ(scene.face_colors.size(), 12u);
  ASSERT_EQ(scene.levels.size(), 2u);
  EXPECT_EQ(scene.levels[0].floor_y, 0.0);
  EXPECT_EQ(scene.levels[1].floor_y, 32.0);
  EXPECT_DOUBLE_EQ(scene.levels[0].walkable_area, 256.0 * 256.0 - 64.0 * 64.0);
  EXPECT_DOUBLE_EQ(scene.levels[1].walkable_area, 64.0 * 64.0);
  EXPECT_EQ(scene.eye_height, 41.0);
  EXPECT_EQ(scene.start_eye, glm::dvec3(200.0, 41.0, -200.0));
  EXPECT_NEAR(scene.start_yaw, 0.0, 1e-12);  // Doom angle 90 (north, +y) is walkvis -z
  EXPECT_TRUE(startAboveWalkable(scene));

  double wall_area = 0.0, floor_area = 0.0, ceiling_area = 0.0;
  for (size_t i = 0; i < scene.polygons.size(); ++i) {
    const auto v = scene.polygonVertices(i);
    const Plane own = newellPlane(v);
    // Area from Newell's vector: twice the area times the unit normal.
    glm::dvec3 nsum(0.0);
    for (size_t k = 0; k < v.size(); ++k) {
      const auto& a = v[k];
      const auto& b = v[(k + 1) % v.size()];
      nsum += glm::dvec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    }
    const double area = 0.5 * std::sqrt(nsum.x * nsum.x + nsum.y * nsum.y + nsum.z * nsum.z);
    EXPECT_NEAR(glm::length(own.n - scene.polygons[i].plane.n), 0.0, 1e-12) << "stored plane matches winding";
    const glm::dvec3 c = centroid(v);
    if (own.n.y > 0.5) {
      floor_area += area;
    } else if (own.n.y < -0.5) {
      EXPECT_EQ(c.y, 128.0);
      ceiling_area += area;
    } else {
      wall_area += area;
      // Outer walls face the room's middle; platform steps face away from the platform's middle.
      const glm::dvec3 room_mid(128, 0, -128), platform_mid(96, 0, -96);
      const bool step = c.y < 32.0 && std::abs(c.x - 96) <= 32 && std::abs(c.z + 96) <= 32;
      const glm::dvec3 to_mid = (step ? platform_mid : room_mid) - glm::dvec3(c.x, 0, c.z);
      EXPECT_EQ(glm::dot(own.n, to_mid) > 0, !step) << "wall " << i;
    }
  }
  EXPECT_DOUBLE_EQ(wall_area, 4 * 256.0 * 128.0 + 4 * 64.0 * 32.0);
  EXPECT_DOUBLE_EQ(floor_area, 256.0 * 256.0);
  EXPECT_DOUBLE_EQ(ceiling_area, 256.0 * 256.0);

  std::vector<RawSector> raw = rawSectors(bytes, "MAP01");
  EXPECT_EQ(expectWallsFaceIntoSectors(scene, raw, "room.wad"), 8u);
}

TEST(Wad, ClosedDoorAndSkyUpperWalls) {
  // Two rooms joined by a shut door sector; the rooms have sky ceilings at different heights.
  TestMap m;
  m.vertices = {{0, 0}, {0, 64}, {64, 64}, {64, 0}, {72, 64}, {72, 0}, {136, 64}, {136, 0}};
  m.sectors = {{0, 128, "F_SKY1"}, {0, 0}, {0, 160, "F_SKY1"}};
  // Room A: (0..64); door: (64..72); room B: (72..136).
  m.sidedefs = {{0}, {0}, {0}, {1}, {1}, {1}, {0}, {1}, {2}, {2}, {2}, {2}};
  m.linedefs = {{0, 1, 0, -1}, {1, 2, 1, -1}, {3, 0, 2, -1},   // room A
                {2, 4, 3, -1}, {5, 3, 4, -1},                  // door jambs
                {3, 2, 5, 6},  {4, 5, 7, 8},                   // door faces: front side in the door
                {4, 6, 9, -1}, {6, 7, 10, -1}, {7, 5, 11, -1}};  // room B
  m.things = {{32, 32, 0, 1}};
  const auto bytes = buildWad(m.lumps("E1M1"));
  const Scene scene = loadWadMapFromMemory(bytes, "E1M1", "door.wad");
  ASSERT_EQ(scene.levels.size(), 1u);
  EXPECT_DOUBLE_EQ(scene.levels[0].walkable_area, 2 * 64.0 * 64.0);  // the door sector is not walkable
  EXPECT_EQ(scene.start_eye, glm::dvec3(32.0, 41.0, -32.0));
  EXPECT_NEAR(scene.start_yaw, -M_PI / 2, 1e-12);  // Doom angle 0 (east) is walkvis +x: yaw -90 degrees
  // Walls: 3 + 3 room walls, door faces from floor to each room's ceiling; no door jambs (zero
  // height), no door floor or ceiling; 2 floors and 2 ceilings.
  EXPECT_EQ(scene.report.input_faces, 6u + 2u + 4u);
  expectWallsFaceIntoSectors(scene, rawSectors(bytes, "E1M1"), "door.wad");

  // Open the door (ceiling 112): two jambs, a floor and a ceiling more; the upper walls above
  // the doorway stay.
  m.sectors[1] = {0, 112};
  const Scene open = loadWadMapFromMemory(buildWad(m.lumps("E1M1")), "E1M1", "door.wad");
  EXPECT_EQ(open.levels.size(), 1u);
  EXPECT_DOUBLE_EQ(open.levels[0].walkable_area, 2 * 64.0 * 64.0 + 8 * 64.0);
  EXPECT_EQ(open.report.input_faces, scene.report.input_faces + 4);
  // A sky door sector: its upper walls towards both sky rooms are not drawn by Doom: skipped.
  m.sectors[1] = {0, 112, "F_SKY1"};
  const Scene sky = loadWadMapFromMemory(buildWad(m.lumps("E1M1")), "E1M1", "door.wad");
  EXPECT_EQ(sky.report.input_faces, open.report.input_faces - 2);
}

// ---- Malformed input ----

void expectError(const std::vector<uint8_t>& bytes, const std::string& fragment, const std::string& map = "MAP01") {
  const std::string msg = loadError(bytes, map);
  EXPECT_NE(msg.find("test.wad"), std::string::npos) << msg;
  EXPECT_NE(msg.find(fragment), std::string::npos) << "expected '" << fragment << "' in: " << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

TEST(Wad, MalformedInputGivesSceneErrors) {
  const auto good = roomWad();
  ASSERT_EQ(loadError(good), "(no error)");

  expectError({'P', 'W', 'A'}, "truncated WAD header");
  auto bad_magic = good;
  bad_magic[0] = 'X';
  expectError(bad_magic, "not a WAD file (bad magic)");
  auto huge_dir = good;
  huge_dir[4] = 0xFF;  // lump count 255 + ...: the directory runs past the end
  expectError(huge_dir, "truncated WAD directory");
  expectError(std::vector<uint8_t>(good.begin(), good.end() - 1), "truncated WAD directory");
  expectError(good, "has no map MAP99; it has MAP01", "MAP99");

  auto lumps = roomWithPlatform().lumps("MAP01");
  auto with = [&](auto edit) {
    auto copy = lumps;
    edit(copy);
    return buildWad(copy);
  };
  expectError(with([](auto& l) { l[2].data.push_back(0); }), "malformed LINEDEFS lump (113 bytes is not a multiple of 14)");
  expectError(with([](auto& l) { l[2].data[2] = 99; }), "linedef 0 names vertex 99 (out of range; the map has 8)");
  expectError(with([](auto& l) { l[2].data[10] = 50; }), "linedef 0 names sidedef 50 (out of range");
  expectError(with([](auto& l) { l[3].data[28] = 7; }), "sidedef 0 names sector 7 (out of range; the map has 2)");
  expectError(with([](auto& l) { l[2].data.clear(); }), "empty map");
  expectError(with([](auto& l) { l.erase(l.begin() + 8); }), "map has no SECTORS lump");

  // A lump whose offset points past the end of the file.
  auto out_of_range = good;
  const size_t dir = static_cast<size_t>(i32(good, 8));
  out_of_range[dir + 16 * 2 + 1] = 0x7F;  // LINEDEFS file position
  expectError(out_of_range, "LINEDEFS lump out of range");

  try {
    readFileBytes("/nonexistent/dir/none.wad");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/none.wad"), std::string::npos);
  }
  EXPECT_THROW(loadWadMap("/nonexistent/none.wad", "MAP01"), Error);
  EXPECT_THROW(loadWadMap("/tmp", "MAP01"), Error);
  EXPECT_THROW(wadMapNames("/nonexistent/none.wad"), Error);
}

TEST(Wad, LoadsFromFile) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string path = (dir / ("walkvis_test_wad_" + std::to_string(::getpid()) + ".wad")).string();
  const auto bytes = roomWad();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_TRUE(f);
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
  EXPECT_EQ(wadMapNames(path), std::vector<std::string>{"MAP01"});
  EXPECT_EQ(readFileBytes(path), bytes);
  const Scene scene = loadWadMap(path, "MAP01");
  EXPECT_EQ(scene.polygons.size(), loadWadMapFromMemory(bytes, "MAP01", path).polygons.size());
  EXPECT_EQ(scene.name, path + ":MAP01");
  f = std::fopen(path.c_str(), "wb");  // now empty
  std::fclose(f);
  try {
    loadWadMap(path, "MAP01");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": truncated WAD header (0 bytes, need 12)");
  }
  std::filesystem::remove(path);
}

// One sector bounded by the star polygon {n/k}: n (k - 1) crossings among its own lines.
TestMap starSector(int n, int k) {
  TestMap m;
  m.sectors = {{0, 128}};
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / n;
    m.vertices.push_back({int(std::lround(1000 * std::cos(t))), int(std::lround(1000 * std::sin(t)))});
    m.sidedefs.push_back({0});
    m.linedefs.push_back({i, (i + k) % n, i, -1});
  }
  m.things = {{0, 0, 0, 1}};
  return m;
}

TEST(Wad, SelfCrossingSectors) {
  // A pentagram sector loads: its even-odd region is the five points, not the middle.
  const Scene star = loadWadMapFromMemory(buildWad(starSector(5, 2).lumps("MAP01")), "MAP01", "star.wad");
  ASSERT_EQ(star.levels.size(), 1u);
  bool noted = false;
  for (const auto& note : star.report.notes) noted |= note.find("5 crossings") != std::string::npos;
  EXPECT_TRUE(noted);
  // A corrupt map whose lines cross 12,480 times is refused instead of triangulated.
  const std::string msg = loadError(buildWad(starSector(160, 79).lumps("MAP01")));
  EXPECT_NE(msg.find("test.wad:MAP01: sector lines cross each other 10000 times or more"), std::string::npos)
      << msg;
}

TEST(Wad, TruncatedAndCorruptedBytesNeverCrash) {
  const auto good = roomWad();
  for (size_t n = 0; n < good.size(); n += 3) {
    std::vector<uint8_t> cut(good.begin(), good.begin() + n);
    EXPECT_NE(loadError(cut), "(no error)") << n;
  }
  // Random byte changes over fixed seeds: a scene or a Error, nothing else.
  size_t loaded = 0;
  for (uint32_t seed = 1; seed <= 300; ++seed) {
    std::mt19937 rng(seed);
    auto bytes = good;
    for (int k = 0; k < 1 + int(seed % 4); ++k) bytes[rng() % bytes.size()] = static_cast<uint8_t>(rng());
    try {
      loadWadMapFromMemory(bytes, "MAP01", "test.wad");
      ++loaded;
    } catch (const Error&) {
    }
  }
  EXPECT_GT(loaded, 0u);
}

// ---- Freedoom ----

void loadAllMaps(const std::string& wad, size_t expected_maps) {
  if (!std::filesystem::exists(wad)) GTEST_SKIP() << wad << " is not installed";
  const auto names = wadMapNames(wad);
  EXPECT_EQ(names.size(), expected_maps);
  const auto bytes = readFileBytes(wad);
  for (const auto& name : names) {
    SCOPED_TRACE(wad + ":" + name);
    const Scene scene = loadWadMapFromMemory(bytes, name, wad);
    EXPECT_GT(scene.polygons.size(), 0u);
    EXPECT_GE(scene.levels.size(), 1u);
    for (size_t i = 1; i < scene.levels.size(); ++i) EXPECT_LT(scene.levels[i - 1].floor_y, scene.levels[i].floor_y);
    EXPECT_TRUE(startAboveWalkable(scene)) << "start eye (" << scene.start_eye.x << ", " << scene.start_eye.y
                                           << ", " << scene.start_eye.z << ")";
  }
}

TEST(Wad, AllFreedoom2MapsLoad) { loadAllMaps(kFreedoom2, 32); }
TEST(Wad, AllFreedoom1MapsLoad) { loadAllMaps(kFreedoom1, 36); }

TEST(Wad, FreedoomWallsFaceIntoThePlayableSpace) {
  for (const auto& [wad, map] : std::vector<std::pair<std::string, std::string>>{
           {kFreedoom2, "MAP01"}, {kFreedoom2, "MAP07"}, {kFreedoom2, "MAP13"}, {kFreedoom1, "E1M1"}, {kFreedoom1, "E3M4"}}) {
    if (!std::filesystem::exists(wad)) GTEST_SKIP() << wad << " is not installed";
    const auto bytes = readFileBytes(wad);
    const Scene scene = loadWadMapFromMemory(bytes, map, wad);
    EXPECT_GT(expectWallsFaceIntoSectors(scene, rawSectors(bytes, map), wad + ":" + map), 100u);
  }
}

// Random points of the map: inside an open sector (read independently, even-odd) exactly when
// inside a walkable piece of that sector's floor level.
TEST(Wad, FreedoomFloorsCoverTheirSectors) {
  for (const auto& [wad, map] : std::vector<std::pair<std::string, std::string>>{
           {kFreedoom2, "MAP01"}, {kFreedoom2, "MAP10"}, {kFreedoom1, "E1M1"}, {kFreedoom1, "E2M5"}}) {
    if (!std::filesystem::exists(wad)) GTEST_SKIP() << wad << " is not installed";
    SCOPED_TRACE(wad + ":" + map);
    const auto bytes = readFileBytes(wad);
    const Scene scene = loadWadMapFromMemory(bytes, map, wad);
    const auto sectors = rawSectors(bytes, map);
    const Bounds b = sceneBounds(scene);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> ux(b.lo.x, b.hi.x), uz(b.lo.z, b.hi.z);
    size_t inside = 0, mismatches = 0;
    for (int k = 0; k < 3000; ++k) {
      const glm::dvec2 q(ux(rng), uz(rng));
      std::vector<double> want, got;
      for (const auto& s : sectors) {
        if (s.ceiling > s.floor && insideSector(s, {q.x, -q.y})) want.push_back(s.floor);
      }
      for (const auto& level : scene.levels) {
        for (const auto& piece : level.walkable) {
          if (insideConvexXz(piece, q)) got.push_back(level.floor_y);
        }
      }
      std::sort(want.begin(), want.end());
      std::sort(got.begin(), got.end());
      // A point on a shared piece edge lies in both pieces; random doubles almost never do.
      got.erase(std::unique(got.begin(), got.end()), got.end());
      want.erase(std::unique(want.begin(), want.end()), want.end());
      inside += !want.empty();
      if (want != got && ++mismatches <= 5) {
        ADD_FAILURE() << "at (" << q.x << ", " << q.y << "): " << want.size() << " sectors, " << got.size()
                      << " levels";
      }
    }
    EXPECT_EQ(mismatches, 0u);
    EXPECT_GT(inside, 300u);
  }
}

TEST(Wad, MissingMapNamesTheMapsThereAre) {
  if (!std::filesystem::exists(kFreedoom2)) GTEST_SKIP() << kFreedoom2 << " is not installed";
  try {
    loadWadMap(kFreedoom2, "MAP99");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), kFreedoom2 + ": has no map MAP99; it has MAP01..MAP32 (32 maps)");
  }
}

}  // namespace
}  // namespace walkvis
