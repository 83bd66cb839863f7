// The web export's binary (docs/web/README.md, "Format") and its folder. The layout is chosen
// for the page: every section starts on an 8-byte boundary, so the viewer maps the arrays as
// typed arrays over the one buffer without copying; a view cell is a section of its own, so its
// tree can be fetched alone.
#include "walkthrough/web_export.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "core/byte_io.h"
#include "core/hash.h"
#include "walkthrough/camera.h"
#include "walkthrough/camera_path.h"

namespace walkvis {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the web export is little-endian: the page reads it with typed arrays");

constexpr char kMagic[8] = {'W', 'A', 'L', 'K', 'V', 'I', 'S', 'W'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 40;
constexpr size_t kTocEntryBytes = 32;

struct Section {
  char tag[4];
  std::vector<uint8_t> bytes;
};

Section section(const char* tag) {
  Section s;
  std::memcpy(s.tag, tag, 4);
  return s;
}

template <typename T>
void put(std::vector<uint8_t>& out, T value) {
  const size_t at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &value, sizeof(T));
}

void putPlane(std::vector<uint8_t>& out, const Plane& p) {
  put(out, p.n.x);
  put(out, p.n.y);
  put(out, p.n.z);
  put(out, p.d);
}

// WALK: the walker's floors as doubles (counts too: exact below 2^53): levels, then connections.
std::vector<uint8_t> walkSection(const Scene& scene) {
  std::vector<uint8_t> out;
  auto ring = [&](const std::vector<glm::dvec2>& r) {
    put(out, static_cast<double>(r.size()));
    for (const glm::dvec2& p : r) {
      put(out, p.x);
      put(out, p.y);
    }
  };
  put(out, static_cast<double>(scene.levels.size()));
  for (const FloorLevel& l : scene.levels) {
    put(out, l.floor_y);
    put(out, static_cast<double>(l.walkable.size()));
    for (const auto& piece : l.walkable) ring(piece);
  }
  put(out, static_cast<double>(scene.connections.size()));
  for (const WalkableConnection& c : scene.connections) {
    put(out, static_cast<double>(c.patches.size()));
    for (const WalkablePatch& p : c.patches) {
      putPlane(out, p.plane);
      ring(p.piece);
    }
  }
  return out;
}

// CELL: u32 header[16], f64 box[4], f64 planes, then the u32 arrays of the tree (pfd.h).
std::vector<uint8_t> cellSection(const PfdTree& t, uint32_t level) {
  std::vector<uint8_t> out;
  const uint32_t head[16] = {level,
                             t.cell ? 1u : 0u,
                             static_cast<uint32_t>(t.planes.size()),
                             static_cast<uint32_t>(t.nodes.size()),
                             static_cast<uint32_t>(t.run_refs.size()),
                             static_cast<uint32_t>(t.runs.size()),
                             static_cast<uint32_t>(t.seqs.size()),
                             static_cast<uint32_t>(t.seq_items.size()),
                             static_cast<uint32_t>(t.fragment_ids.size()),
                             static_cast<uint32_t>(t.objects.size()),
                             static_cast<uint32_t>(t.object_nodes.size()),
                             0, 0, 0, 0, 0};
  for (uint32_t h : head) put(out, h);
  const PfdBox box = t.cell.value_or(PfdBox{});
  put(out, box.lo.x);
  put(out, box.lo.y);
  put(out, box.hi.x);
  put(out, box.hi.y);
  for (const Plane& p : t.planes) putPlane(out, p);
  for (const PfdNode& n : t.nodes) {
    put(out, n.plane);
    put(out, n.front);
    put(out, n.back);
    put(out, n.first_ref);
    put(out, n.ref_count);
  }
  for (uint32_t r : t.run_refs) put(out, r);
  for (const PfdRun& r : t.runs) {
    put(out, r.first);
    put(out, r.count);
  }
  for (const PfdSeq& s : t.seqs) {
    put(out, s.first);
    put(out, s.count);
    put(out, s.length);
  }
  for (uint32_t i : t.seq_items) put(out, i);
  for (uint32_t f : t.fragment_ids) put(out, f);
  for (const PfdObject& o : t.objects) {
    put(out, o.root);
    put(out, o.nodes);
    put(out, o.fragments);
  }
  for (const PfdObjectNode& o : t.object_nodes) {
    put(out, o.plane);
    put(out, o.front);
    put(out, o.back);
    put(out, o.parent);
    put(out, o.front_run);
    put(out, o.back_run);
  }
  return out;
}

nlohmann::json metaJson(const World& world, const CameraPath& tour, const Walker& walker) {
  const BspTree& bsp = world.trees.bsp;
  const FreeCamera camera;  // the projection every view uses (the size comes from the page)
  nlohmann::json m;
  m["format"] = "walkvis-web";
  m["version"] = kVersion;
  m["source"] = world.source;
  m["scene"] = world.scene.name;
  m["fragments"] = bsp.fragments.size();
  m["vertices"] = bsp.vertices.size();
  m["bsp_nodes"] = bsp.nodes.size();
  m["bsp_root"] = bsp.root;
  m["input_polygons"] = bsp.stats.input_polygons;
  m["eye_height"] = world.trees.eye_height;
  m["camera"] = {{"fov_y", camera.fov_y}, {"near", camera.near}, {"far", camera.far}};
  m["walk"] = {{"radius", walker.radius()}, {"step", walker.stepHeight()}, {"tol", walker.tolerance()},
               {"speed", 2.0 * world.trees.eye_height}, {"run_factor", 3.0}, {"mouse_radians_per_pixel", 0.0025},
               {"max_pitch", 1.5}};
  m["start"] = {{"eye", {world.scene.start_eye.x, world.scene.start_eye.y, world.scene.start_eye.z}},
                {"yaw", world.scene.start_yaw}};
  nlohmann::json levels = nlohmann::json::array();
  for (const PfdLevel& l : world.trees.levels)
    levels.push_back({{"floor_y", l.floor_y}, {"height", l.height}, {"cells", l.cells.size()}});
  m["levels"] = levels;
  nlohmann::json keys = nlohmann::json::array();
  for (const CameraKey& k : tour.keys) keys.push_back({k.time, k.eye.x, k.eye.y, k.eye.z, k.yaw, k.pitch});
  m["tour"] = keys;  // [time, x, y, z, yaw, pitch] per key
  return m;
}

void appendBase64(std::string& out, std::span<const uint8_t> bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const uint32_t v = uint32_t(bytes[i]) << 16 | uint32_t(bytes[i + 1]) << 8 | bytes[i + 2];
    out += kDigits[v >> 18];
    out += kDigits[(v >> 12) & 63];
    out += kDigits[(v >> 6) & 63];
    out += kDigits[v & 63];
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint32_t(bytes[i]) << 16;
    out += kDigits[v >> 18];
    out += kDigits[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = uint32_t(bytes[i]) << 16 | uint32_t(bytes[i + 1]) << 8;
    out += kDigits[v >> 18];
    out += kDigits[(v >> 12) & 63];
    out += kDigits[(v >> 6) & 63];
    out += '=';
  }
}

}  // namespace

std::vector<uint8_t> webExportBytes(const World& world, const WebExportOptions& options, WebExportReport* report) {
  if (world.trees.levels.empty() || world.trees.kind != TreeKind::kHfd)
    throw Error(world.source + ": a web export needs a tree file made by `walkvis build --tree hfd`");
  const BspTree& bsp = world.trees.bsp;
  const Walker walker(world.scene, bsp, options.move);
  const CameraPath tour = automaticTour(world.scene, bsp, options.tour_frames);

  std::vector<Section> sections;
  {
    Section s = section("META");
    const std::string text = metaJson(world, tour, walker).dump();
    s.bytes.assign(text.begin(), text.end());
    sections.push_back(std::move(s));
  }
  {
    Section s = section("VERT");
    for (const glm::dvec3& v : bsp.vertices) {
      put(s.bytes, v.x);
      put(s.bytes, v.y);
      put(s.bytes, v.z);
    }
    sections.push_back(std::move(s));
  }
  {
    Section f = section("FRAG"), p = section("FPLN");
    for (const Polygon& poly : bsp.fragments) {
      const uint32_t color = poly.face_id < world.scene.face_colors.size() ? world.scene.face_colors[poly.face_id]
                                                                           : faceColor(poly.face_id);
      put(f.bytes, poly.first_vertex);
      put(f.bytes, poly.vertex_count);
      put(f.bytes, poly.face_id);
      put(f.bytes, color);
      putPlane(p.bytes, poly.plane);
    }
    sections.push_back(std::move(f));
    sections.push_back(std::move(p));
  }
  {
    Section n = section("BNOD"), p = section("BPLN");
    for (const BspNode& node : bsp.nodes) {
      put(n.bytes, node.front);
      put(n.bytes, node.back);
      put(n.bytes, node.first_fragment);
      put(n.bytes, node.fragment_count);
      putPlane(p.bytes, node.plane);
    }
    sections.push_back(std::move(n));
    sections.push_back(std::move(p));
  }
  {
    Section s = section("WALK");
    s.bytes = walkSection(world.scene);
    sections.push_back(std::move(s));
  }
  uint32_t cells = 0;
  for (uint32_t l = 0; l < world.trees.levels.size(); ++l) {
    for (const PfdTree& t : world.trees.levels[l].cells) {
      Section s = section("CELL");
      s.bytes = cellSection(t, l);
      sections.push_back(std::move(s));
      ++cells;
    }
  }

  // Header, table of sections, then the sections, each padded to 8 bytes.
  std::vector<uint8_t> toc;
  uint64_t offset = kHeaderBytes + kTocEntryBytes * sections.size();
  offset = (offset + 7) & ~uint64_t{7};
  const uint64_t first_offset = offset;
  for (const Section& s : sections) {
    toc.insert(toc.end(), s.tag, s.tag + 4);
    put(toc, uint32_t{0});
    put(toc, offset);
    put(toc, static_cast<uint64_t>(s.bytes.size()));
    put(toc, fnv1a(s.bytes.data(), s.bytes.size()));
    offset = (offset + s.bytes.size() + 7) & ~uint64_t{7};
  }
  std::vector<uint8_t> out;
  out.reserve(offset);
  out.insert(out.end(), kMagic, kMagic + 8);
  put(out, kVersion);
  put(out, static_cast<uint32_t>(sections.size()));
  put(out, offset);
  put(out, fnv1a(toc.data(), toc.size()));
  put(out, uint64_t{0});
  out.insert(out.end(), toc.begin(), toc.end());
  out.resize(first_offset, 0);
  for (const Section& s : sections) {
    out.insert(out.end(), s.bytes.begin(), s.bytes.end());
    out.resize((out.size() + 7) & ~size_t{7}, 0);
  }
  if (report) {
    report->sections.clear();
    for (const Section& s : sections) {
      const std::string tag(s.tag, 4);
      if (!report->sections.empty() && report->sections.back().first == tag) report->sections.back().second += s.bytes.size();
      else report->sections.emplace_back(tag, s.bytes.size());
    }
    report->binary_bytes = out.size();
    report->cells = cells;
    report->tour_keys = static_cast<uint32_t>(tour.keys.size());
  }
  return out;
}

std::string webDataScript(std::span<const uint8_t> bytes) {
  std::string script = "walkvisData(\"";
  script.reserve(bytes.size() * 4 / 3 + 64);
  appendBase64(script, bytes);
  script += "\");\n";
  return script;
}

WebExportReport writeWebExport(const World& world, const std::string& dir, const WebExportOptions& options) {
  WebExportReport report;
  const std::vector<uint8_t> bytes = webExportBytes(world, options, &report);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) throw Error(dir + ": cannot create the export folder");
  const std::filesystem::path root(dir);
  // The binary is written before the page that names it, so a folder whose index.html is
  // there holds a whole export of some run (each file is itself renamed into place whole).
  writeFileAtomically((root / "walkvis.bin").string(), bytes, "the web export");
  const std::string script = webDataScript(bytes);
  writeTextFileAtomically((root / "walkvis-data.js").string(), script, "the web export");
  report.script_bytes = script.size();
  for (const WebAsset& a : webAssets()) {
    writeFileAtomically((root / a.name).string(), std::span(a.data, a.size), "the web export");
    report.page_bytes += a.size;
  }
  return report;
}

}  // namespace walkvis
