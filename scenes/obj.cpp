// Wavefront OBJ scenes. Format: the OBJ/MTL appendix of the Wavefront Advanced Visualizer manual
// (as summarised at https://paulbourke.net/dataformats/obj/ and .../mtl/).
//
// Geometry (`v`, `f`, `usemtl`, `mtllib`) is read by a strict line parser here rather than by
// tinyobjloader: tinyobjloader is lenient (it reads "abc" as 0, clamps or wraps bad indices and
// reports no line numbers) and keeps positions in float, which cannot hold the 1e6-with-1e-3
// hard case. Every malformed record therefore gets a one-line Error naming file and line.
// Material libraries are read with tinyobjloader's MTL parser; only the diffuse colour is used.
// Records a walkthrough does not need (vt, vn, s, l, p, curves) are skipped. Each `o` or `g`
// record starts a new object for face merging (mesh_merge.h); without any, the file is one object.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>

#include "core/byte_io.h"
#include "scenes/loaders.h"
#include "scenes/mesh_merge.h"
#include "scenes/scene.h"

namespace walkvis {
namespace {

struct ObjFace {
  size_t line = 0;
  std::vector<int64_t> indices;  // 0-based, already resolved and range-checked
  int material = -1;             // index into the material list, -1 for none
  uint32_t object = 0;           // counts the `o`/`g` records before it
};

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

// Splits a line into whitespace-separated tokens; stops at a '#' comment.
std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isSpace(line[i])) ++i;
    if (i >= line.size() || line[i] == '#') break;
    size_t j = i;
    while (j < line.size() && !isSpace(line[j])) ++j;
    out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

// Keeps a token quotable in a one-line message: binary garbage and very long tokens are cut.
std::string quoted(std::string_view token) {
  std::string s;
  for (char c : token.substr(0, 40)) s += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
  if (token.size() > 40) s += "...";
  return "'" + s + "'";
}

class ObjParser {
 public:
  ObjParser(std::string_view text, const std::string& context) : text_(text), context_(context) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw Error(context_ + ":" + std::to_string(line_) + ": " + what);
  }

  double number(std::string_view token) const {
    std::string_view t = token;
    // from_chars does not take a leading '+', which some exporters write.
    if (t.size() > 1 && t[0] == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
    if (ec == std::errc::result_out_of_range) fail("number " + quoted(token) + " is out of range");
    if (ec != std::errc() || ptr != t.data() + t.size()) fail("bad number " + quoted(token));
    if (!std::isfinite(value)) fail("non-finite number " + quoted(token));
    return value;
  }

  // An index field of a face corner ("7", "-2"); 0 is not an OBJ index.
  int64_t index(std::string_view field, std::string_view token) const {
    int64_t value = 0;
    const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
    if (ec != std::errc() || ptr != field.data() + field.size() || field.empty()) {
      fail("bad face index " + quoted(token));
    }
    if (value == 0) fail("face index 0 in " + quoted(token) + " (OBJ indices start at 1)");
    return value;
  }

  void parse() {
    size_t pos = 0;
    while (pos < text_.size()) {
      // Lines end in \n, \r\n or a lone \r, as tinyobjloader and most exporters accept.
      size_t end = text_.find_first_of("\r\n", pos);
      if (end == std::string_view::npos) end = text_.size();
      ++line_;
      parseLine(text_.substr(pos, end - pos));
      pos = end + 1;
      if (end + 1 < text_.size() && text_[end] == '\r' && text_[end + 1] == '\n') ++pos;
    }
    // Positive indices may point forward (tinyobjloader and most readers allow it): checked here.
    for (const auto& [line, index] : forward_) {
      if (index > static_cast<int64_t>(vertices_.size())) {
        throw Error(context_ + ":" + std::to_string(line) + ": face index " + std::to_string(index) +
                         " out of range (" + std::to_string(vertices_.size()) + " vertices)");
      }
    }
  }

  void parseLine(std::string_view line) {
    const auto tok = tokens(line);
    if (tok.empty()) return;
    const std::string_view cmd = tok[0];
    if (cmd == "v") {
      // x y z, then optionally w (a curve weight, ignored for polygons as tinyobjloader does) or
      // an r g b vertex colour.
      const size_t n = tok.size() - 1;
      if (n < 3) fail("vertex needs 3 coordinates, got " + std::to_string(n));
      if (n > 7) fail("vertex has " + std::to_string(n) + " numbers (expected 3 to 7)");
      double xyz[3] = {0.0, 0.0, 0.0};
      for (size_t i = 1; i < tok.size(); ++i) {
        const double value = number(tok[i]);
        if (i <= 3) xyz[i - 1] = value;
      }
      vertices_.emplace_back(xyz[0], xyz[1], xyz[2]);
    } else if (cmd == "vt" || cmd == "vn" || cmd == "vp") {
      // Not used, but a malformed number is still a malformed file.
      for (size_t i = 1; i < tok.size(); ++i) number(tok[i]);
      if (cmd == "vt") ++texcoords_;
      if (cmd == "vn") ++normals_;
    } else if (cmd == "f" || cmd == "fo") {
      ObjFace face;
      face.line = line_;
      face.material = material_;
      face.object = object_;
      const size_t n = tok.size() - 1;
      if (n < 3) fail("face with " + std::to_string(n) + " vertices (needs at least 3)");
      for (size_t i = 1; i < tok.size(); ++i) face.indices.push_back(corner(tok[i]));
      faces_.push_back(std::move(face));
    } else if (cmd == "usemtl") {
      const std::string name = tok.size() > 1 ? std::string(tok[1]) : std::string();
      auto it = material_ids_.find(name);
      if (it == material_ids_.end()) {
        it = material_ids_.emplace(name, static_cast<int>(material_names_.size())).first;
        material_names_.push_back(name);
      }
      material_ = it->second;
    } else if (cmd == "o" || cmd == "g") {
      ++object_;
    } else if (cmd == "mtllib") {
      for (size_t i = 1; i < tok.size(); ++i) mtllibs_.emplace_back(tok[i]);
    }
  }

  // One face corner "v", "v/vt", "v//vn" or "v/vt/vn" → resolved 0-based vertex index.
  int64_t corner(std::string_view token) {
    const size_t slash = token.find('/');
    const std::string_view vfield = token.substr(0, slash);
    const int64_t v = index(vfield, token);
    if (slash != std::string_view::npos) {
      const std::string_view rest = token.substr(slash + 1);
      const size_t slash2 = rest.find('/');
      const std::string_view vt = rest.substr(0, slash2);
      if (!vt.empty()) checkAttribute(index(vt, token), texcoords_, "texture coordinate", token);
      if (slash2 != std::string_view::npos) {
        const std::string_view vn = rest.substr(slash2 + 1);
        if (vn.find('/') != std::string_view::npos) fail("bad face corner " + quoted(token));
        if (!vn.empty()) checkAttribute(index(vn, token), normals_, "normal", token);
      } else if (vt.empty()) {
        fail("bad face corner " + quoted(token));
      }
    }
    const auto count = static_cast<int64_t>(vertices_.size());
    if (v < 0) {
      // Relative: -1 is the last vertex defined so far.
      if (v < -count) {
        fail("face index " + std::to_string(v) + " out of range (" + std::to_string(count) + " vertices so far)");
      }
      return count + v;
    }
    forward_.emplace_back(line_, v);
    return v - 1;
  }

  // Texture and normal indices are not used; only relative ones can be checked here and only
  // relative ones could reach before the start.
  void checkAttribute(int64_t index, size_t count, const char* what, std::string_view token) const {
    if (index < 0 && index < -static_cast<int64_t>(count)) {
      fail(std::string(what) + " index " + std::to_string(index) + " out of range in " + quoted(token));
    }
  }

  std::string_view text_;
  const std::string& context_;
  size_t line_ = 0;
  size_t texcoords_ = 0;
  size_t normals_ = 0;
  int material_ = -1;
  uint32_t object_ = 0;

 public:
  std::vector<glm::dvec3> vertices_;
  std::vector<ObjFace> faces_;
  std::vector<std::pair<size_t, int64_t>> forward_;  // (line, 1-based index) to check at the end
  std::vector<std::string> material_names_;          // in order of first use
  std::map<std::string, int> material_ids_;
  std::vector<std::string> mtllibs_;
};

uint32_t toRgb(const tinyobj::real_t* rgb) {
  uint32_t out = 0;
  for (int i = 0; i < 3; ++i) {
    const double c = std::isfinite(rgb[i]) ? std::clamp(static_cast<double>(rgb[i]), 0.0, 1.0) : 0.0;
    out = (out << 8) | static_cast<uint32_t>(std::lround(c * 255.0));
  }
  return out;
}

// Diffuse colours by material name from the material libraries, read relative to `dir`.
// A missing or unreadable library is a note, not an error: the geometry is still good.
std::map<std::string, uint32_t> readMaterials(const std::vector<std::string>& libs, const std::filesystem::path& dir,
                                              LoadReport& report) {
  std::map<std::string, uint32_t> colors;
  for (const auto& lib : libs) {
    const std::string path = (dir / lib).string();
    std::vector<uint8_t> bytes;
    try {
      bytes = readFileBytes(path);
    } catch (const Error& e) {
      report.notes.push_back(std::string("material library skipped: ") + e.what());
      continue;
    }
    std::istringstream in(std::string(bytes.begin(), bytes.end()));
    std::map<std::string, int> ids;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    tinyobj::LoadMtl(&ids, &materials, &in, &warn, &err);
    for (const auto& m : materials) colors[m.name] = toRgb(m.diffuse);
  }
  return colors;
}

Scene buildObj(std::string_view text, const std::string& context, const std::filesystem::path* mtl_dir,
               bool merge) {
  ObjParser parser(text, context);
  parser.parse();
  if (parser.faces_.empty()) {
    throw Error(context + ": no faces (" + std::to_string(parser.vertices_.size()) + " vertices, no 'f' records)");
  }
  Scene scene;
  std::vector<std::optional<uint32_t>> material_colors(parser.material_names_.size());
  if (mtl_dir != nullptr && !parser.mtllibs_.empty()) {
    const auto colors = readMaterials(parser.mtllibs_, *mtl_dir, scene.report);
    size_t unknown = 0;
    for (size_t i = 0; i < parser.material_names_.size(); ++i) {
      auto it = colors.find(parser.material_names_[i]);
      if (it != colors.end()) {
        material_colors[i] = it->second;
      } else {
        ++unknown;
      }
    }
    if (unknown > 0) {
      scene.report.notes.push_back(std::to_string(unknown) + " material(s) not found in the material libraries");
    }
  }
  // One object per run of faces between `o`/`g` records, in file order, so input face i of the
  // file is entry i of report.input_to_face.
  std::vector<uint32_t> indices, sizes, colors;
  for (size_t start = 0; start < parser.faces_.size();) {
    size_t end = start;
    indices.clear();
    sizes.clear();
    colors.clear();
    while (end < parser.faces_.size() && parser.faces_[end].object == parser.faces_[start].object) {
      const ObjFace& face = parser.faces_[end];
      for (int64_t i : face.indices) indices.push_back(static_cast<uint32_t>(i));
      sizes.push_back(static_cast<uint32_t>(face.indices.size()));
      uint32_t color = kFaceColorById;
      if (face.material >= 0 && material_colors[static_cast<size_t>(face.material)]) {
        color = *material_colors[static_cast<size_t>(face.material)];
      }
      colors.push_back(color);
      ++end;
    }
    const MeshObjectInput object{parser.vertices_, indices, sizes, colors};
    addMeshObject(scene, object, merge, context + ":" + std::to_string(parser.faces_[start].line));
    start = end;
  }
  return scene;
}

}  // namespace

Scene loadObjFromMemory(std::string_view text, const std::string& context, bool merge) {
  return buildObj(text, context, nullptr, merge);
}

Scene loadObj(const std::string& path, bool merge) {
  const std::vector<uint8_t> bytes = readFileBytes(path);
  const std::string text(bytes.begin(), bytes.end());
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  return buildObj(text, path, &dir, merge);
}

}  // namespace walkvis
