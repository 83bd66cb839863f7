// The web export's binaries (docs/web/README.md, "Format") and its folder. The layout is chosen
// for the page: a section is stored raw or deflated, whichever is smaller (the trees of
// docs/web/README.md's scenes shrink 3.8-14 times, and browsers inflate natively:
// DecompressionStream), and the viewer maps its arrays as typed arrays over the inflated bytes, or
// over the file itself for a raw section, which starts on an 8-byte boundary. The trees, most of
// an export's bytes, are one file per view cell: a page fetches the cell it stands in first and
// draws the BSP order until it arrives.
#include "walkthrough/web_export.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <set>

#include <nlohmann/json.hpp>
#include <zlib.h>

#include "core/byte_io.h"
#include "core/hash.h"
#include "walkthrough/camera.h"
#include "walkthrough/camera_path.h"

namespace walkvis {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the web export is little-endian: the page reads it with typed arrays");

constexpr char kMagic[8] = {'W', 'A', 'L', 'K', 'V', 'I', 'S', 'W'};
constexpr uint32_t kVersion = 3;
constexpr size_t kHeaderBytes = 40;
constexpr size_t kTocEntryBytes = 40;
constexpr uint32_t kRaw = 0, kDeflate = 1;  // a section's encoding (deflate: RFC 1950 zlib stream)

struct Section {
  char tag[4];
  ByteWriter out;            // the section's bytes; once packed, as stored (deflated where smaller)
  uint32_t encoding = kRaw;  // how `out` is stored
  uint64_t length = 0;       // the bytes before packing
};

// The zlib stream of `bytes` at level 9, or nothing when it would not be smaller. zlib's output
// depends only on its input, level and version, so an export is reproducible with one zlib.
std::optional<std::vector<uint8_t>> deflated(const std::vector<uint8_t>& bytes) {
  uLongf size = compressBound(bytes.size());
  std::vector<uint8_t> out(size);
  if (compress2(out.data(), &size, bytes.data(), bytes.size(), 9) != Z_OK || size >= bytes.size()) return std::nullopt;
  out.resize(size);
  return out;
}

Section section(const char* tag) {
  Section s;
  std::memcpy(s.tag, tag, 4);
  return s;
}

// WALK: the walker's floors as doubles (counts too: exact below 2^53): levels, then connections.
ByteWriter walkSection(const Scene& scene) {
  ByteWriter out;
  auto ring = [&](const std::vector<glm::dvec2>& r) {
    out.put(static_cast<double>(r.size()));
    for (const glm::dvec2& p : r) {
      out.put(p.x);
      out.put(p.y);
    }
  };
  out.put(static_cast<double>(scene.levels.size()));
  for (const FloorLevel& l : scene.levels) {
    out.put(l.floor_y);
    out.put(static_cast<double>(l.walkable.size()));
    for (const auto& piece : l.walkable) ring(piece);
  }
  out.put(static_cast<double>(scene.connections.size()));
  for (const WalkableConnection& c : scene.connections) {
    out.put(static_cast<double>(c.patches.size()));
    for (const WalkablePatch& p : c.patches) {
      out.putPlane(p.plane);
      ring(p.piece);
    }
  }
  return out;
}

// CELL: u32 header[16], f64 box[4], f64 planes, then the u32 arrays of the tree (pfd.h).
ByteWriter cellSection(const PfdTree& t, uint32_t level) {
  ByteWriter out;
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
  for (uint32_t h : head) out.put(h);
  const PfdBox box = t.cell.value_or(PfdBox{});
  out.put(box.lo.x);
  out.put(box.lo.y);
  out.put(box.hi.x);
  out.put(box.hi.y);
  for (const Plane& p : t.planes) out.putPlane(p);
  for (const PfdNode& n : t.nodes) {
    out.put(n.plane);
    out.put(n.front);
    out.put(n.back);
    out.put(n.first_ref);
    out.put(n.ref_count);
  }
  for (uint32_t r : t.run_refs) out.put(r);
  for (const PfdRun& r : t.runs) {
    out.put(r.first);
    out.put(r.count);
  }
  for (const PfdSeq& s : t.seqs) {
    out.put(s.first);
    out.put(s.count);
    out.put(s.length);
  }
  for (uint32_t i : t.seq_items) out.put(i);
  for (uint32_t f : t.fragment_ids) out.put(f);
  for (const PfdObject& o : t.objects) {
    out.put(o.root);
    out.put(o.nodes);
    out.put(o.fragments);
  }
  for (const PfdObjectNode& o : t.object_nodes) {
    out.put(o.plane);
    out.put(o.front);
    out.put(o.back);
    out.put(o.parent);
    out.put(o.front_run);
    out.put(o.back_run);
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

// A container (docs/web/README.md, "Format"): each section deflated where smaller (`deflate`),
// then the header, the table of sections and the sections, each padded to 8 bytes.
std::vector<uint8_t> containerBytes(std::vector<Section>& sections, bool deflate) {
  for (Section& s : sections) {
    s.length = s.out.bytes.size();
    if (!deflate) continue;
    if (auto d = deflated(s.out.bytes)) {
      s.out.bytes = std::move(*d);
      s.encoding = kDeflate;
    }
  }
  ByteWriter toc;
  uint64_t offset = kHeaderBytes + kTocEntryBytes * sections.size();
  offset = (offset + 7) & ~uint64_t{7};
  const uint64_t first_offset = offset;
  for (const Section& s : sections) {
    toc.bytes.insert(toc.bytes.end(), s.tag, s.tag + 4);
    toc.put(s.encoding);
    toc.put(offset);
    toc.put(static_cast<uint64_t>(s.out.bytes.size()));
    toc.put(s.length);
    toc.put(fnv1a(s.out.bytes.data(), s.out.bytes.size()));
    offset = (offset + s.out.bytes.size() + 7) & ~uint64_t{7};
  }
  ByteWriter file;
  file.bytes.reserve(offset);
  file.bytes.insert(file.bytes.end(), kMagic, kMagic + 8);
  file.put(kVersion);
  file.put(static_cast<uint32_t>(sections.size()));
  file.put(offset);
  file.put(fnv1a(toc.bytes.data(), toc.bytes.size()));
  file.put(uint64_t{0});
  file.bytes.insert(file.bytes.end(), toc.bytes.begin(), toc.bytes.end());
  file.bytes.resize(first_offset, 0);
  for (const Section& s : sections) {
    file.bytes.insert(file.bytes.end(), s.out.bytes.begin(), s.out.bytes.end());
    file.bytes.resize((file.bytes.size() + 7) & ~size_t{7}, 0);
  }
  return std::move(file.bytes);
}

// The checksum of a container's table of sections (header bytes 24-31), as 16 hex digits: META
// names each view cell's file by it, so that a cell file of another export is told apart.
std::string tocChecksumHex(const std::vector<uint8_t>& container) {
  uint64_t sum = 0;
  std::memcpy(&sum, container.data() + 24, sizeof sum);
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(sum));
  return text;
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

// `call` followed by the base64 of `bytes` in quotes and the closing parenthesis: a script that
// hands the bytes to the page.
std::string scriptCall(const std::string& call, std::span<const uint8_t> bytes) {
  std::string script = call + "\"";
  script.reserve(bytes.size() * 4 / 3 + call.size() + 8);
  appendBase64(script, bytes);
  script += "\");\n";
  return script;
}

}  // namespace

WebExportFiles webExportFiles(const World& world, const WebExportOptions& options, WebExportReport* report) {
  if (world.trees.levels.empty() || world.trees.kind != TreeKind::kHfd)
    throw Error(world.source + ": a web export needs a tree file made by `walkvis build --tree hfd`");
  const BspTree& bsp = world.trees.bsp;
  const Walker walker(world.scene, bsp, options.move);
  const CameraPath tour = automaticTour(world.scene, bsp, options.tour_frames);
  WebExportFiles files;

  // Each view cell a container of its own (cells/K.bin), listed in META with its level, box and
  // the checksum of its table.
  nlohmann::json cells = nlohmann::json::array();
  WebSectionBytes cell_bytes{"CELL", 0, 0};
  for (uint32_t l = 0; l < world.trees.levels.size(); ++l) {
    for (const PfdTree& t : world.trees.levels[l].cells) {
      std::vector<Section> one(1, section("CELL"));
      one[0].out = cellSection(t, l);
      files.cells.push_back(containerBytes(one, options.deflate));
      cell_bytes.bytes += one[0].length;
      cell_bytes.stored += one[0].out.bytes.size();
      nlohmann::json c = {{"level", l}, {"checksum", tocChecksumHex(files.cells.back())}};
      c["box"] = t.cell ? nlohmann::json{t.cell->lo.x, t.cell->lo.y, t.cell->hi.x, t.cell->hi.y} : nlohmann::json();
      cells.push_back(std::move(c));
    }
  }

  std::vector<Section> sections;
  {
    Section s = section("META");
    nlohmann::json meta = metaJson(world, tour, walker);
    meta["cells"] = std::move(cells);
    const std::string text = meta.dump();
    s.out.bytes.assign(text.begin(), text.end());
    sections.push_back(std::move(s));
  }
  {
    Section s = section("VERT");
    for (const glm::dvec3& v : bsp.vertices) {
      s.out.put(v.x);
      s.out.put(v.y);
      s.out.put(v.z);
    }
    sections.push_back(std::move(s));
  }
  {
    Section f = section("FRAG"), p = section("FPLN");
    for (const Polygon& poly : bsp.fragments) {
      const uint32_t color = poly.face_id < world.scene.face_colors.size() ? world.scene.face_colors[poly.face_id]
                                                                           : faceColor(poly.face_id);
      f.out.put(poly.first_vertex);
      f.out.put(poly.vertex_count);
      f.out.put(poly.face_id);
      f.out.put(color);
      p.out.putPlane(poly.plane);
    }
    sections.push_back(std::move(f));
    sections.push_back(std::move(p));
  }
  {
    Section n = section("BNOD"), p = section("BPLN");
    for (const BspNode& node : bsp.nodes) {
      n.out.put(node.front);
      n.out.put(node.back);
      n.out.put(node.first_fragment);
      n.out.put(node.fragment_count);
      p.out.putPlane(node.plane);
    }
    sections.push_back(std::move(n));
    sections.push_back(std::move(p));
  }
  {
    Section s = section("WALK");
    s.out = walkSection(world.scene);
    sections.push_back(std::move(s));
  }
  files.binary = containerBytes(sections, options.deflate);
  if (report) {
    report->sections.clear();
    for (const Section& s : sections) report->sections.push_back({std::string(s.tag, 4), s.length, s.out.bytes.size()});
    report->sections.push_back(cell_bytes);
    report->binary_bytes = files.binary.size();
    report->cell_bytes = 0;
    for (const auto& c : files.cells) report->cell_bytes += c.size();
    report->cells = static_cast<uint32_t>(files.cells.size());
    report->tour_keys = static_cast<uint32_t>(tour.keys.size());
  }
  return files;
}

std::string webDataScript(std::span<const uint8_t> bytes) { return scriptCall("walkvisData(", bytes); }

std::string webCellScript(uint32_t k, std::span<const uint8_t> bytes) {
  return scriptCall("walkvisCell(" + std::to_string(k) + ", ", bytes);
}

WebExportReport writeWebExport(const World& world, const std::string& dir, const WebExportOptions& options) {
  WebExportReport report;
  const WebExportFiles files = webExportFiles(world, options, &report);
  namespace fs = std::filesystem;
  const fs::path root(dir), cells = root / "cells";
  std::error_code ec;
  fs::create_directories(cells, ec);
  if (ec || !fs::is_directory(cells)) throw Error(dir + ": cannot create the export folder");
  // Each file is renamed into place whole: the cells first, then the binary that names them by
  // their checksums (a page never pairs a new walkvis.bin with an old cell unnoticed), then the
  // page, so a first export's folder that holds index.html holds the data too.
  std::set<std::string> written;
  for (uint32_t k = 0; k < files.cells.size(); ++k) {
    const std::string bin = std::to_string(k) + ".bin", js = std::to_string(k) + ".js";
    writeFileAtomically((cells / bin).string(), files.cells[k], "the web export");
    const std::string script = webCellScript(k, files.cells[k]);
    writeTextFileAtomically((cells / js).string(), script, "the web export");
    report.script_bytes += script.size();
    written.insert(bin);
    written.insert(js);
  }
  writeFileAtomically((root / "walkvis.bin").string(), files.binary, "the web export");
  const std::string script = webDataScript(files.binary);
  writeTextFileAtomically((root / "walkvis-data.js").string(), script, "the web export");
  report.script_bytes += script.size();
  for (const WebAsset& a : webAssets()) {
    writeFileAtomically((root / a.name).string(), std::span(a.data, a.size), "the web export");
    report.page_bytes += a.size;
  }
  // Cells of an earlier export into the same folder that this one does not have.
  for (const fs::directory_entry& e : fs::directory_iterator(cells, ec)) {
    const std::string name = e.path().filename().string(), stem = e.path().stem().string();
    const bool cell_file = !stem.empty() && stem.find_first_not_of("0123456789") == std::string::npos &&
                           (e.path().extension() == ".bin" || e.path().extension() == ".js");
    if (cell_file && !written.count(name)) fs::remove(e.path(), ec);
  }
  return report;
}

}  // namespace walkvis
