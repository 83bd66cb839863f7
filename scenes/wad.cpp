// Doom-format WAD maps as walkvis scenes.
//
// Source: the Unofficial Doom Specs v1.666 (Matthew S. Fell, 1994 [DoomSpecs]), sections 1 (WAD
// directory) and 4 (THINGS, LINEDEFS, SIDEDEFS, VERTEXES, SECTORS); the Doom source release (id
// Software 1997, r_segs.c [DoomSource1997]) for which parts of a two-sided line are drawn: the
// lower wall between the two floors, the upper wall between the two ceilings, clipped to the open
// span of the sector that sees it, and no upper wall where both ceilings are sky (F_SKY1).
//
// Axes: Doom (x, y) in the map plane and heights z become walkvis (x, height, -y), so the scene is
// right-handed with y up. Every wall, sector floor and sector ceiling is one input face.
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "scenes/loaders.h"

namespace walkvis {
namespace {

constexpr double kDefaultEyeHeight = 41.0;  // Doom's VIEWHEIGHT
constexpr uint16_t kNoSide = 0xFFFF;
constexpr size_t kThingSize = 10, kLinedefSize = 14, kSidedefSize = 30, kVertexSize = 4, kSectorSize = 26;

struct Lump {
  int64_t pos = 0;
  int64_t size = 0;
  std::string name;
};

int32_t readI32(std::span<const uint8_t> b, size_t at) {
  return static_cast<int32_t>(uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 |
                              uint32_t(b[at + 3]) << 24);
}
uint16_t readU16(std::span<const uint8_t> b, size_t at) { return static_cast<uint16_t>(b[at] | b[at + 1] << 8); }
int16_t readI16(std::span<const uint8_t> b, size_t at) { return static_cast<int16_t>(readU16(b, at)); }

// An 8-byte name field: up to the first NUL, upper case (Doom compares names case-blind).
std::string readName(std::span<const uint8_t> b, size_t at) {
  std::string s;
  for (size_t i = 0; i < 8 && b[at + i] != 0; ++i) {
    s.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(b[at + i]))));
  }
  return s;
}

std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::vector<Lump> readDirectory(std::span<const uint8_t> bytes, const std::string& context) {
  if (bytes.size() < 12) {
    throw Error(context + ": truncated WAD header (" + std::to_string(bytes.size()) + " bytes, need 12)");
  }
  const std::string magic(reinterpret_cast<const char*>(bytes.data()), 4);
  if (magic != "IWAD" && magic != "PWAD") throw Error(context + ": not a WAD file (bad magic)");
  const int64_t count = readI32(bytes, 4);
  const int64_t offset = readI32(bytes, 8);
  if (count < 0 || offset < 0 || offset + count * 16 > static_cast<int64_t>(bytes.size())) {
    throw Error(context + ": truncated WAD directory (" + std::to_string(count) + " entries at offset " +
                     std::to_string(offset) + ", file has " + std::to_string(bytes.size()) + " bytes)");
  }
  std::vector<Lump> lumps(static_cast<size_t>(count));
  for (size_t i = 0; i < lumps.size(); ++i) {
    const size_t at = static_cast<size_t>(offset) + 16 * i;
    lumps[i].pos = readI32(bytes, at);
    lumps[i].size = readI32(bytes, at + 4);
    lumps[i].name = readName(bytes, at + 8);
  }
  return lumps;
}

// A map is a marker lump followed by THINGS (Doom, Hexen) or TEXTMAP (UDMF).
std::vector<std::string> mapNames(const std::vector<Lump>& lumps) {
  std::vector<std::string> names;
  for (size_t i = 0; i + 1 < lumps.size(); ++i) {
    if (lumps[i + 1].name == "THINGS" || lumps[i + 1].name == "TEXTMAP") names.push_back(lumps[i].name);
  }
  return names;
}

std::string describeMaps(const std::vector<std::string>& names) {
  if (names.empty()) return "it has no maps";
  if (names.size() <= 4) {
    std::string s = "it has ";
    for (size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + names[i];
    return s;
  }
  return "it has " + names.front() + ".." + names.back() + " (" + std::to_string(names.size()) + " maps)";
}

struct MapLumps {
  std::array<std::optional<Lump>, 5> lump;  // THINGS, LINEDEFS, SIDEDEFS, VERTEXES, SECTORS
  bool hexen = false;
};
constexpr std::array<const char*, 5> kMapLumpNames{"THINGS", "LINEDEFS", "SIDEDEFS", "VERTEXES", "SECTORS"};

std::span<const uint8_t> lumpBytes(std::span<const uint8_t> bytes, const Lump& l, size_t record,
                                   const std::string& where) {
  if (l.pos < 0 || l.size < 0 || l.pos + l.size > static_cast<int64_t>(bytes.size())) {
    throw Error(where + ": " + l.name + " lump out of range (" + std::to_string(l.size) + " bytes at offset " +
                     std::to_string(l.pos) + ", file has " + std::to_string(bytes.size()) + " bytes)");
  }
  if (l.size % static_cast<int64_t>(record) != 0) {
    throw Error(where + ": malformed " + l.name + " lump (" + std::to_string(l.size) +
                     " bytes is not a multiple of " + std::to_string(record) + ")");
  }
  return bytes.subspan(static_cast<size_t>(l.pos), static_cast<size_t>(l.size));
}

struct Sector {
  double floor = 0.0, ceiling = 0.0;
  bool sky = false;  // ceiling flat F_SKY1
  bool open() const { return ceiling > floor; }
};

struct Line {
  uint16_t v1 = 0, v2 = 0;
  int32_t front = -1, back = -1;  // sector indices; -1 for no side
};

using Vec2 = glm::dvec2;

// Rings of one sector's boundary: the edges are chained end to end. Where every vertex has an
// even degree this is an Euler decomposition into closed rings; a walk that gets stuck (an unclosed
// sector, a map error) is closed with a straight edge and counted.
std::vector<std::vector<Vec2>> chainRings(const std::vector<std::pair<Vec2, Vec2>>& edges, uint64_t& open_chains) {
  auto key = [](const Vec2& p) {
    // Doom vertices are 16-bit integers: the pair packs exactly.
    return uint32_t(uint16_t(int16_t(p.x))) << 16 | uint32_t(uint16_t(int16_t(p.y)));
  };
  std::unordered_map<uint32_t, std::vector<uint32_t>> at;
  for (uint32_t i = 0; i < edges.size(); ++i) {
    at[key(edges[i].first)].push_back(i);
    at[key(edges[i].second)].push_back(i);
  }
  std::vector<bool> used(edges.size(), false);
  std::unordered_map<uint32_t, size_t> next_slot;
  auto takeEdge = [&](uint32_t k) -> std::optional<uint32_t> {
    auto& list = at[k];
    size_t& slot = next_slot[k];
    while (slot < list.size() && used[list[slot]]) ++slot;
    if (slot == list.size()) return std::nullopt;
    used[list[slot]] = true;
    return list[slot];
  };
  // Odd-degree vertices first, so open chains are walked end to end.
  std::vector<Vec2> starts;
  for (const auto& e : edges) {
    for (const Vec2& p : {e.first, e.second}) {
      if (at[key(p)].size() % 2 == 1) starts.push_back(p);
    }
  }
  for (const auto& e : edges) starts.push_back(e.first);
  std::vector<std::vector<Vec2>> rings;
  for (const Vec2& s : starts) {
    const uint32_t ks = key(s);
    while (auto first = takeEdge(ks)) {
      std::vector<Vec2> ring{s};
      Vec2 cur = s;
      std::optional<uint32_t> e = first;
      bool closed = false;
      while (e) {
        cur = key(edges[*e].first) == key(cur) ? edges[*e].second : edges[*e].first;
        if (key(cur) == ks) {
          closed = true;
          break;
        }
        ring.push_back(cur);
        e = takeEdge(key(cur));
      }
      if (!closed) ++open_chains;
      if (ring.size() >= 3) rings.push_back(std::move(ring));
    }
  }
  return rings;
}

// Even-odd crossing test of p against segments (a, b).
bool insideEdges(const std::vector<std::pair<Vec2, Vec2>>& edges, Vec2 p) {
  bool in = false;
  for (const auto& [a, b] : edges) {
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

// Proper crossings (interiors meet in one point) among a sector's boundary edges, counted up to
// `limit`. Each one becomes a new vertex of the sector's triangulation, so a corrupt map whose lines
// all cross would otherwise cost quadratic time and memory there. Doom coordinates are 16-bit
// integers, so these orientation tests are exact in doubles (products below 2^35).
uint64_t countCrossings(const std::vector<std::pair<Vec2, Vec2>>& edges, uint64_t limit) {
  struct Box {
    double x0, x1, y0, y1;
    uint32_t edge;
  };
  std::vector<Box> boxes;
  boxes.reserve(edges.size());
  for (uint32_t i = 0; i < edges.size(); ++i) {
    const auto& [a, b] = edges[i];
    boxes.push_back({std::min(a.x, b.x), std::max(a.x, b.x), std::min(a.y, b.y), std::max(a.y, b.y), i});
  }
  std::sort(boxes.begin(), boxes.end(), [](const Box& p, const Box& q) { return p.x0 < q.x0; });
  auto orient = [](Vec2 a, Vec2 b, Vec2 c) {
    const double o = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    return (o > 0) - (o < 0);
  };
  uint64_t crossings = 0;
  std::vector<Box> active;
  for (const Box& box : boxes) {
    std::erase_if(active, [&](const Box& o) { return o.x1 < box.x0; });
    const auto& [a, b] = edges[box.edge];
    for (const Box& o : active) {
      if (o.y1 < box.y0 || box.y1 < o.y0) continue;
      const auto& [c, d] = edges[o.edge];
      if (orient(a, b, c) * orient(a, b, d) < 0 && orient(c, d, a) * orient(c, d, b) < 0 && ++crossings >= limit) {
        return crossings;
      }
    }
    active.push_back(box);
  }
  return crossings;
}

glm::dvec3 to3d(Vec2 p, double height) { return {p.x, height, -p.y}; }

// A wall on the line a -> b between heights lo and hi, facing the right side of a -> b (Doom's
// front side), i.e. counter-clockwise seen from there.
void addWall(Scene& scene, Vec2 a, Vec2 b, double lo, double hi, const std::string& context) {
  const std::array<glm::dvec3, 4> quad{to3d(a, lo), to3d(b, lo), to3d(b, hi), to3d(a, hi)};
  addFace(scene, quad, faceColor(static_cast<uint32_t>(scene.face_colors.size())), context);
}

// A read-only mapping of a whole file: a map needs only the WAD's directory and its own few
// lumps, so mapping touches a few hundred KB of a 28 MB IWAD instead of copying all of it.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error(path + ": cannot open (" + std::strerror(errno) + ")");
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd);
      throw Error(path + ": not a regular file");
    }
    size_ = static_cast<size_t>(st.st_size);
    if (size_ > 0) {
      data_ = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      if (data_ == MAP_FAILED) {
        const int err = errno;
        ::close(fd);
        throw Error(path + ": cannot map (" + std::strerror(err) + ")");
      }
    }
    ::close(fd);
  }
  ~MappedFile() {
    if (size_ > 0) ::munmap(data_, size_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::span<const uint8_t> bytes() const { return {static_cast<const uint8_t*>(data_), size_}; }

 private:
  void* data_ = nullptr;
  size_t size_ = 0;
};

}  // namespace

std::vector<std::string> wadMapNames(const std::string& path) {
  const MappedFile file(path);
  return mapNames(readDirectory(file.bytes(), path));
}

Scene loadWadMap(const std::string& path, const std::string& map) {
  const MappedFile file(path);
  return loadWadMapFromMemory(file.bytes(), map, path);
}

Scene loadWadMapFromMemory(std::span<const uint8_t> bytes, const std::string& map_name, const std::string& context) {
  const auto lumps = readDirectory(bytes, context);
  const std::string map = upper(map_name);
  size_t marker = lumps.size();
  for (size_t i = 0; i + 1 < lumps.size(); ++i) {
    if (lumps[i].name == map && (lumps[i + 1].name == "THINGS" || lumps[i + 1].name == "TEXTMAP")) marker = i;
  }
  if (marker == lumps.size()) {
    throw Error(context + ": has no map " + map + "; " + describeMaps(mapNames(lumps)));
  }
  const std::string where = context + ":" + map;
  if (lumps[marker + 1].name == "TEXTMAP") throw Error(where + ": UDMF (TEXTMAP) maps are not supported");

  // The map's lumps follow its marker, up to the next lump that is not a map lump.
  static constexpr std::array<const char*, 12> kAllMapLumps{"THINGS", "LINEDEFS", "SIDEDEFS", "VERTEXES",
                                                            "SEGS",   "SSECTORS", "NODES",    "SECTORS",
                                                            "REJECT", "BLOCKMAP", "BEHAVIOR", "SCRIPTS"};
  MapLumps ml;
  for (size_t i = marker + 1; i < lumps.size(); ++i) {
    const auto& name = lumps[i].name;
    if (std::find(kAllMapLumps.begin(), kAllMapLumps.end(), name) == kAllMapLumps.end()) break;
    if (name == "BEHAVIOR") ml.hexen = true;
    for (size_t k = 0; k < kMapLumpNames.size(); ++k) {
      if (name == kMapLumpNames[k] && !ml.lump[k]) ml.lump[k] = lumps[i];
    }
  }
  if (ml.hexen) throw Error(where + ": Hexen-format maps are not supported");
  for (size_t k = 0; k < kMapLumpNames.size(); ++k) {
    if (!ml.lump[k]) throw Error(where + ": map has no " + std::string(kMapLumpNames[k]) + " lump");
  }
  const auto things = lumpBytes(bytes, *ml.lump[0], kThingSize, where);
  const auto linedefs = lumpBytes(bytes, *ml.lump[1], kLinedefSize, where);
  const auto sidedefs = lumpBytes(bytes, *ml.lump[2], kSidedefSize, where);
  const auto vertexes = lumpBytes(bytes, *ml.lump[3], kVertexSize, where);
  const auto sectors_raw = lumpBytes(bytes, *ml.lump[4], kSectorSize, where);
  if (linedefs.empty() || vertexes.empty() || sectors_raw.empty() || sidedefs.empty()) {
    throw Error(where + ": empty map (" + std::to_string(linedefs.size() / kLinedefSize) + " linedefs, " +
                     std::to_string(vertexes.size() / kVertexSize) + " vertices, " +
                     std::to_string(sidedefs.size() / kSidedefSize) + " sidedefs, " +
                     std::to_string(sectors_raw.size() / kSectorSize) + " sectors)");
  }

  std::vector<Vec2> verts(vertexes.size() / kVertexSize);
  for (size_t i = 0; i < verts.size(); ++i) {
    verts[i] = Vec2(readI16(vertexes, 4 * i), readI16(vertexes, 4 * i + 2));
  }
  std::vector<Sector> sectors(sectors_raw.size() / kSectorSize);
  for (size_t i = 0; i < sectors.size(); ++i) {
    const size_t at = kSectorSize * i;
    sectors[i].floor = readI16(sectors_raw, at);
    sectors[i].ceiling = readI16(sectors_raw, at + 2);
    sectors[i].sky = readName(sectors_raw, at + 12) == "F_SKY1";
  }
  const size_t nsides = sidedefs.size() / kSidedefSize;
  auto sideSector = [&](uint16_t side, size_t line) -> int32_t {
    if (side == kNoSide) return -1;
    if (side >= nsides) {
      throw Error(where + ": linedef " + std::to_string(line) + " names sidedef " + std::to_string(side) +
                       " (out of range; the map has " + std::to_string(nsides) + ")");
    }
    const uint16_t sec = readU16(sidedefs, kSidedefSize * side + 28);
    if (sec >= sectors.size()) {
      throw Error(where + ": sidedef " + std::to_string(side) + " names sector " + std::to_string(sec) +
                       " (out of range; the map has " + std::to_string(sectors.size()) + ")");
    }
    return sec;
  };

  Scene scene;
  scene.name = where;
  scene.eye_height = kDefaultEyeHeight;
  uint64_t no_sides = 0, sky_uppers = 0, zero_length = 0, open_chains = 0, closed_sectors = 0, self_lines = 0;

  std::vector<Line> lines(linedefs.size() / kLinedefSize);
  std::vector<std::vector<std::pair<Vec2, Vec2>>> boundary(sectors.size());
  for (size_t i = 0; i < lines.size(); ++i) {
    const size_t at = kLinedefSize * i;
    Line& l = lines[i];
    l.v1 = readU16(linedefs, at);
    l.v2 = readU16(linedefs, at + 2);
    if (l.v1 >= verts.size() || l.v2 >= verts.size()) {
      throw Error(where + ": linedef " + std::to_string(i) + " names vertex " +
                       std::to_string(std::max(l.v1, l.v2)) + " (out of range; the map has " +
                       std::to_string(verts.size()) + ")");
    }
    l.front = sideSector(readU16(linedefs, at + 10), i);
    l.back = sideSector(readU16(linedefs, at + 12), i);
    if (l.front < 0) {
      // Vanilla Doom needs a front side; a back-only line is read as its mirror image.
      std::swap(l.front, l.back);
      std::swap(l.v1, l.v2);
    }
    if (l.front < 0) {
      ++no_sides;
      continue;
    }
    const Vec2 a = verts[l.v1], b = verts[l.v2];
    if (a == b) {
      ++zero_length;
      continue;
    }
    if (l.front == l.back) {
      ++self_lines;  // inside one sector: no wall, and not part of its boundary
      continue;
    }
    boundary[l.front].emplace_back(a, b);
    if (l.back >= 0) boundary[l.back].emplace_back(a, b);
  }

  // Walls, facing into the sector that sees them.
  for (size_t i = 0; i < lines.size(); ++i) {
    const Line& l = lines[i];
    if (l.front < 0 || l.front == l.back) continue;
    const Vec2 a = verts[l.v1], b = verts[l.v2];
    if (a == b) continue;
    const std::string ctx = where + " linedef " + std::to_string(i);
    const Sector& f = sectors[l.front];
    if (l.back < 0) {
      if (f.open()) addWall(scene, a, b, f.floor, f.ceiling, ctx);
      continue;
    }
    const Sector& k = sectors[l.back];
    // Lower wall: seen from the lower floor, up to the higher floor or the viewer's ceiling.
    if (f.floor < k.floor) {
      const double hi = std::min(k.floor, f.ceiling);
      if (hi > f.floor) addWall(scene, a, b, f.floor, hi, ctx);
    } else if (k.floor < f.floor) {
      const double hi = std::min(f.floor, k.ceiling);
      if (hi > k.floor) addWall(scene, b, a, k.floor, hi, ctx);
    }
    // Upper wall: seen from the higher ceiling, down to the lower ceiling or the viewer's floor.
    if (f.ceiling != k.ceiling && f.sky && k.sky) {
      ++sky_uppers;
    } else if (f.ceiling > k.ceiling) {
      const double lo = std::max(k.ceiling, f.floor);
      if (f.ceiling > lo) addWall(scene, a, b, lo, f.ceiling, ctx);
    } else if (k.ceiling > f.ceiling) {
      const double lo = std::max(f.ceiling, k.floor);
      if (k.ceiling > lo) addWall(scene, b, a, lo, k.ceiling, ctx);
    }
  }

  // Real maps have a handful of crossing sector lines at most; thousands mean a corrupt map.
  constexpr uint64_t kMaxCrossings = 10000;
  uint64_t crossings = 0;
  for (size_t s = 0; s < sectors.size(); ++s) {
    if (!sectors[s].open()) continue;
    crossings += countCrossings(boundary[s], kMaxCrossings - crossings);
    if (crossings >= kMaxCrossings) {
      throw Error(where + ": sector lines cross each other " + std::to_string(kMaxCrossings) +
                       " times or more (corrupt map)");
    }
  }

  // Floors (facing up) and ceilings (facing down) of open sectors; floors make the levels.
  std::map<double, FloorLevel> levels;
  for (size_t s = 0; s < sectors.size(); ++s) {
    if (boundary[s].empty()) continue;
    if (!sectors[s].open()) {
      ++closed_sectors;
      continue;
    }
    const auto rings = chainRings(boundary[s], open_chains);
    if (rings.empty()) continue;
    const std::string ctx = where + " sector " + std::to_string(s);
    const double fy = sectors[s].floor, cy = sectors[s].ceiling;
    const size_t first_floor = scene.polygons.size();
    // (u, v) = Doom (x, y): u_axis x v_axis = +y.
    addPlanarRegion(scene, rings, {0.0, fy, 0.0}, {1.0, 0.0, 0.0}, {0.0, 0.0, -1.0},
                    faceColor(static_cast<uint32_t>(scene.face_colors.size())), ctx + " floor");
    FloorLevel& level = levels[fy];
    level.floor_y = fy;
    for (size_t p = first_floor; p < scene.polygons.size(); ++p) {
      std::vector<Vec2> piece;
      for (const auto& v : scene.polygonVertices(p)) piece.emplace_back(v.x, v.z);
      double area2 = 0.0;
      for (size_t k = 0; k < piece.size(); ++k) {
        const auto& u = piece[k];
        const auto& w = piece[(k + 1) % piece.size()];
        area2 += u.x * w.y - w.x * u.y;
      }
      level.walkable_area += -0.5 * area2;  // counter-clockwise from +y is clockwise in (x, z)
      level.walkable.push_back(std::move(piece));
    }
    // (u, v) = Doom (x, -y): u_axis x v_axis = -y.
    auto mirrored = rings;
    for (auto& r : mirrored) {
      for (auto& p : r) p.y = -p.y;
    }
    addPlanarRegion(scene, mirrored, {0.0, cy, 0.0}, {1.0, 0.0, 0.0}, {0.0, 0.0, 1.0},
                    faceColor(static_cast<uint32_t>(scene.face_colors.size())), ctx + " ceiling");
  }
  for (auto& [y, level] : levels) {
    if (!level.walkable.empty()) scene.levels.push_back(std::move(level));
  }
  if (scene.polygons.empty()) throw Error(where + ": empty map (no walls, floors or ceilings)");

  // Player 1 start: the sector around it gives the floor.
  std::optional<size_t> start;
  for (size_t i = 0; i < things.size() / kThingSize; ++i) {
    if (readI16(things, kThingSize * i + 6) == 1) start = i;
  }
  if (start) {
    const size_t at = kThingSize * *start;
    const Vec2 p(readI16(things, at), readI16(things, at + 2));
    const double angle = readI16(things, at + 4);
    std::optional<double> floor;
    for (size_t s = 0; s < sectors.size(); ++s) {
      if (sectors[s].open() && insideEdges(boundary[s], p) && (!floor || sectors[s].floor > *floor)) {
        floor = sectors[s].floor;
      }
    }
    if (!floor) scene.report.notes.push_back("player 1 start is outside every open sector; its floor taken as 0");
    scene.start_eye = to3d(p, floor.value_or(0.0) + scene.eye_height);
    // Doom angles: degrees counter-clockwise from east (+x); 90 is north (+y, walkvis -z). walkvis
    // yaw 0 looks along -z and grows towards -x, so yaw = angle - 90 degrees, in (-pi, pi].
    double yaw = (angle - 90.0) * M_PI / 180.0;
    yaw = std::remainder(yaw, 2.0 * M_PI);
    scene.start_yaw = yaw;
  } else {
    scene.report.notes.push_back("no player 1 start (THINGS type 1); the start eye is placed by walkvis");
  }

  auto& notes = scene.report.notes;
  notes.push_back("Doom map " + map + ": walls, sector floors and ceilings in their start state (doors closed, "
                  "lifts and crushers where they start); default eye height 41 (Doom's view height)");
  notes.push_back("left out: middle textures of two-sided lines (grates, fences, windows), things other than the "
                  "player 1 start, line and sector specials, lighting and textures");
  notes.push_back("sky: sky ceilings are flat ceilings at their sector's height; " + std::to_string(sky_uppers) +
                  " upper walls between two sky ceilings skipped, as Doom does not draw them");
  if (closed_sectors) {
    notes.push_back(std::to_string(closed_sectors) +
                    " closed sectors (ceiling <= floor, e.g. shut doors): walls around them only, no floor, "
                    "ceiling or walkable region");
  }
  if (crossings) notes.push_back(std::to_string(crossings) + " crossings between lines of one sector's boundary");
  if (open_chains) {
    notes.push_back(std::to_string(open_chains) + " unclosed sector boundaries closed with a straight edge");
  }
  if (no_sides) notes.push_back(std::to_string(no_sides) + " linedefs without sidedefs skipped");
  if (zero_length) notes.push_back(std::to_string(zero_length) + " zero-length linedefs skipped");
  if (self_lines) {
    notes.push_back(std::to_string(self_lines) + " linedefs with the same sector on both sides (no wall)");
  }
  return scene;
}

}  // namespace walkvis
