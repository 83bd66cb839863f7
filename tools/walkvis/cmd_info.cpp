// walkvis info SCENE [--json] [--plan DIR]: what a scene holds and what loading it changed; with
// --plan a top-down PNG per level (DIR/level-K.png) of its walkable region and connections.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "walkthrough/validate.h"

namespace walkvis {
namespace {

struct InfoArgs {
  SceneArgs scene;
  bool json = false;
  std::string plan_dir;
};

// A plan view: x to the right, z downwards (north, -z, up), as seen from above.
class PlanImage {
 public:
  PlanImage(const Bounds& b, int max_side) : lo_(b.lo) {
    const double w = std::max(b.hi.x - b.lo.x, 1e-9), d = std::max(b.hi.z - b.lo.z, 1e-9);
    scale_ = (max_side - 2 * kMargin) / std::max(w, d);
    width_ = static_cast<int>(std::ceil(w * scale_)) + 2 * kMargin;
    height_ = static_cast<int>(std::ceil(d * scale_)) + 2 * kMargin;
    rgb_.assign(static_cast<size_t>(width_) * height_ * 3, 255);
  }
  glm::dvec2 toPixel(double x, double z) const {
    return {(x - lo_.x) * scale_ + kMargin, (z - lo_.z) * scale_ + kMargin};
  }
  // Blends colour into the pixel (alpha in [0, 1]).
  void put(int x, int y, uint32_t color, double alpha) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
    uint8_t* p = &rgb_[(static_cast<size_t>(y) * width_ + x) * 3];
    for (int k = 0; k < 3; ++k) {
      const double c = static_cast<double>((color >> (16 - 8 * k)) & 0xff);
      p[k] = static_cast<uint8_t>(std::lround(p[k] * (1.0 - alpha) + c * alpha));
    }
  }
  void line(glm::dvec2 a, glm::dvec2 b, uint32_t color, double alpha) {
    a = toPixel(a.x, a.y), b = toPixel(b.x, b.y);
    const int n = static_cast<int>(std::ceil(std::max(std::abs(b.x - a.x), std::abs(b.y - a.y)))) + 1;
    for (int i = 0; i <= n; ++i) {
      const glm::dvec2 p = a + (b - a) * (static_cast<double>(i) / n);
      put(static_cast<int>(std::floor(p.x)), static_cast<int>(std::floor(p.y)), color, alpha);
    }
  }
  // A convex polygon of (x, z) points, filled by pixel centres (any orientation).
  void fill(const std::vector<glm::dvec2>& poly, uint32_t color, double alpha) {
    if (poly.size() < 3) return;
    std::vector<glm::dvec2> p;
    for (const auto& q : poly) p.push_back(toPixel(q.x, q.y));
    double y0 = p[0].y, y1 = p[0].y;
    for (const auto& q : p) y0 = std::min(y0, q.y), y1 = std::max(y1, q.y);
    for (int y = std::max(0, static_cast<int>(std::floor(y0))); y <= std::min(height_ - 1, static_cast<int>(y1)); ++y) {
      const double yc = y + 0.5;
      double xl = 1e300, xr = -1e300;
      for (size_t i = 0; i < p.size(); ++i) {
        const glm::dvec2 a = p[i], b = p[(i + 1) % p.size()];
        if ((a.y <= yc) == (b.y <= yc)) continue;
        const double x = a.x + (yc - a.y) / (b.y - a.y) * (b.x - a.x);
        xl = std::min(xl, x), xr = std::max(xr, x);
      }
      for (int x = std::max(0, static_cast<int>(std::ceil(xl - 0.5))); x <= std::min(width_ - 1, static_cast<int>(std::floor(xr - 0.5))); ++x)
        put(x, y, color, alpha);
    }
  }
  void write(const std::string& path) const { writePngRgb(path, width_, height_, rgb_); }

 private:
  static constexpr int kMargin = 8;
  glm::dvec3 lo_;
  double scale_ = 1.0;
  int width_ = 0, height_ = 0;
  std::vector<uint8_t> rgb_;
};

// One PNG per level: every polygon's outline faint, the section at eye height (walls cut by the
// eye plane) dark, the walkable region green and the connections touching the level orange.
void writePlans(const Scene& scene, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(dir + ": cannot create the plan directory");
  const Bounds b = sceneBounds(scene);
  for (size_t l = 0; l < scene.levels.size(); ++l) {
    const FloorLevel& level = scene.levels[l];
    PlanImage img(b, 1024);
    for (const auto& piece : level.walkable) img.fill(piece, 0x30b040, 0.55);
    for (const auto& conn : scene.connections) {
      if (!std::binary_search(conn.levels.begin(), conn.levels.end(), static_cast<uint32_t>(l))) continue;
      for (const auto& patch : conn.patches) img.fill(patch.piece, 0xf08020, 0.6);
    }
    const double cut = level.floor_y + scene.eye_height;
    for (size_t i = 0; i < scene.polygons.size(); ++i) {
      const auto v = scene.polygonVertices(i);
      std::vector<glm::dvec2> hits;
      for (size_t k = 0; k < v.size(); ++k) {
        const glm::dvec3 a = v[k], c = v[(k + 1) % v.size()];
        img.line({a.x, a.z}, {c.x, c.z}, 0x000000, 0.04);
        if ((a.y < cut) != (c.y < cut)) {
          const double t = (cut - a.y) / (c.y - a.y);
          hits.emplace_back(a.x + t * (c.x - a.x), a.z + t * (c.z - a.z));
        }
      }
      if (hits.size() >= 2) img.line(hits[0], hits[1], 0x202020, 1.0);
    }
    img.write((std::filesystem::path(dir) / ("level-" + std::to_string(l) + ".png")).string());
  }
}

int runInfo(const InfoArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const Scene scene = loadScene(args.scene.scene, args.scene.loadOptions());
  const double load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Bounds b = sceneBounds(scene);
  const LoadReport& r = scene.report;
  const bool closed = isClosed(scene);

  nlohmann::ordered_json j;
  j["scene"] = scene.name;
  j["input_faces"] = r.input_faces;
  j["polygons"] = scene.polygons.size();
  j["triangles"] = triangleCount(scene);
  j["vertices"] = scene.vertices.size();
  j["bounds"] = {{"min", {b.lo.x, b.lo.y, b.lo.z}}, {"max", {b.hi.x, b.hi.y, b.hi.z}}};
  j["eye_height"] = scene.eye_height;
  j["start_eye"] = {scene.start_eye.x, scene.start_eye.y, scene.start_eye.z};
  j["start_yaw"] = scene.start_yaw;
  auto levels = nlohmann::ordered_json::array();
  for (const auto& level : scene.levels) {
    levels.push_back({{"floor_y", level.floor_y},
                      {"eye_y", level.floor_y + scene.eye_height},
                      {"walkable_pieces", level.walkable.size()},
                      {"walkable_area", level.walkable_area}});
  }
  j["levels"] = levels;
  auto connections = nlohmann::ordered_json::array();
  for (const auto& conn : scene.connections) {
    double lo = 1e300, hi = -1e300;
    for (const auto& patch : conn.patches)
      for (const auto& p : patch.piece) {
        const double y = (patch.plane.d - patch.plane.n.x * p.x - patch.plane.n.z * p.y) / patch.plane.n.y;
        lo = std::min(lo, y), hi = std::max(hi, y);
      }
    connections.push_back({{"levels", conn.levels}, {"patches", conn.patches.size()}, {"area", conn.area},
                           {"floor_y_min", lo}, {"floor_y_max", hi}});
  }
  j["connections"] = connections;
  j["kept_faces"] = r.kept_faces;
  j["split_faces"] = r.split_faces;
  j["split_pieces"] = r.split_pieces;
  j["dropped_faces"] = r.dropped_zero_area + r.dropped_degenerate;
  j["dropped_zero_area"] = r.dropped_zero_area;
  j["dropped_degenerate"] = r.dropped_degenerate;
  j["merged_input_faces"] = r.merged_input_faces;
  j["merged_faces"] = r.merged_faces;
  j["tjunctions_removed"] = r.tjunctions_removed;
  j["objects"] = scene.face_object.empty() ? 0 : scene.face_object.back() + 1;
  j["closed"] = closed;
  j["notes"] = r.notes;
  j["load_seconds"] = load_seconds;

  if (!args.plan_dir.empty()) writePlans(scene, args.plan_dir);
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("scene        %s\n", scene.name.c_str());
  std::printf("input faces  %llu\n", static_cast<unsigned long long>(r.input_faces));
  std::printf("polygons     %zu (%llu triangles, %zu vertices)\n", scene.polygons.size(),
              static_cast<unsigned long long>(triangleCount(scene)), scene.vertices.size());
  std::printf("bounds       (%.6g, %.6g, %.6g) .. (%.6g, %.6g, %.6g)\n", b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y,
              b.hi.z);
  std::printf("eye          %.6g above the floor; start (%.6g, %.6g, %.6g), yaw %.3g rad\n", scene.eye_height,
              scene.start_eye.x, scene.start_eye.y, scene.start_eye.z, scene.start_yaw);
  std::printf("levels       %zu\n", scene.levels.size());
  for (const auto& level : scene.levels) {
    std::printf("  floor %-10.6g eye plane y=%-10.6g %5zu walkable pieces, area %.6g\n", level.floor_y,
                level.floor_y + scene.eye_height, level.walkable.size(), level.walkable_area);
  }
  std::printf("connections  %zu\n", scene.connections.size());
  for (const auto& c : connections) {
    std::string lv;
    for (const auto& l : c["levels"]) lv += (lv.empty() ? "" : ",") + std::to_string(l.get<uint32_t>());
    std::printf("  levels %-8s floor y %.4g..%-8.4g %5zu patches, area %.6g\n", lv.empty() ? "-" : lv.c_str(),
                c["floor_y_min"].get<double>(), c["floor_y_max"].get<double>(), c["patches"].get<size_t>(),
                c["area"].get<double>());
  }
  std::printf("loader       %llu kept, %llu split into %llu pieces, %llu dropped (%llu zero-area, %llu degenerate)\n",
              static_cast<unsigned long long>(r.kept_faces), static_cast<unsigned long long>(r.split_faces),
              static_cast<unsigned long long>(r.split_pieces),
              static_cast<unsigned long long>(r.dropped_zero_area + r.dropped_degenerate),
              static_cast<unsigned long long>(r.dropped_zero_area),
              static_cast<unsigned long long>(r.dropped_degenerate));
  if (r.merged_input_faces > 0 || r.tjunctions_removed > 0) {
    std::printf("merged       %llu input faces into %llu faces (adjacent, coplanar, one object and colour); "
                "%llu T-junction vertices put on edges\n",
                static_cast<unsigned long long>(r.merged_input_faces), static_cast<unsigned long long>(r.merged_faces),
                static_cast<unsigned long long>(r.tjunctions_removed));
  }
  for (const auto& note : r.notes) std::printf("  note: %s\n", note.c_str());
  std::printf("closed       %s\n", closed ? "yes" : "no");
  std::printf("loaded in    %.3f s\n", load_seconds);
  return 0;
}

}  // namespace

void addInfoCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<InfoArgs>();
  auto* sub = app.add_subcommand("info", "Counts, bounds, levels, start eye and what the loader changed");
  addSceneArgs(*sub, args->scene, false);
  sub->add_flag("--json", args->json, "Print one JSON object");
  sub->add_option("--plan", args->plan_dir,
                  "Write a top-down PNG per level to DIR/level-K.png: walkable region, connections, walls");
  sub->callback([args, &runner] { runner = [args] { return runInfo(*args); }; });
}

}  // namespace walkvis
