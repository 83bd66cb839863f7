// walkvis validate SCENE [--order bsp] [--views N] [--seed S] [--size PIXELS] [--zbits 16,24,32]
//                        [--json] [--diff-dir DIR]
// Painter's images of a priority order and z-buffer images against exact ray casting, over eyes
// sampled in the walkable regions, six 90° faces each (DESIGN.md "Validation and statistics").
#include <chrono>
#include <cstdio>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bsp/bsp.h"
#include "commands.h"
#include "walkthrough/validate.h"

namespace walkvis {
namespace {

struct ValidateArgs {
  SceneArgs scene;
  std::string order = "bsp";
  int views = 200;
  uint64_t seed = 1;
  int size = 256;
  std::string zbits = "16,24,32";
  double off_plane = 0.25;
  double near = -1.0;
  bool json = false;
  bool quiet = false;
  std::string diff_dir;
};

std::vector<int> parseBits(const std::string& text) {
  std::vector<int> bits;
  if (text.empty() || text == "none") return bits;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item == "16" || item == "24" || item == "32") bits.push_back(std::stoi(item));
    else throw SceneError("validate: --zbits: '" + item + "' is not 16, 24 or 32");
  }
  return bits;
}

nlohmann::ordered_json countsJson(const PixelCounts& c) {
  return {{"order_error_pixels", c.order_error},
          {"tie_pixels", c.tie},
          {"edge_pixels", c.edge},
          {"uncovered_pixels", c.uncovered}};
}

int runValidate(const ValidateArgs& args) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const Scene scene = loadScene(args.scene.scene, args.scene.loadOptions());
  const double load_seconds = std::chrono::duration<double>(Clock::now() - t0).count();

  ValidationOptions options;
  options.eyes = args.views;
  options.seed = args.seed;
  options.size = args.size;
  options.zbits = parseBits(args.zbits);
  options.near = args.near;
  options.diff_dir = args.diff_dir;
  // Off the height planes only the BSP order is defined (PFD/HFD orders hold on the planes).
  options.off_plane_fraction = args.order == "bsp" ? args.off_plane : 0.0;
  const auto progress_start = Clock::now();
  if (!args.quiet) {
    options.progress = [&](int done, int total, uint64_t errors) {
      const double s = std::chrono::duration<double>(Clock::now() - progress_start).count();
      std::fprintf(stderr, "\rvalidate %s: eye %d/%d, %llu order error pixels, %.1f s", scene.name.c_str(), done,
                   total, static_cast<unsigned long long>(errors), s);
      if (done == total) std::fprintf(stderr, "\n");
      std::fflush(stderr);
    };
  }

  const auto t1 = Clock::now();
  const BspTree tree = buildBsp(scene);
  const double bsp_seconds = std::chrono::duration<double>(Clock::now() - t1).count();
  const OrderProvider order = [&](const glm::dvec3& eye, std::vector<uint32_t>& out) {
    backToFront(tree, eye, out, true);
  };
  const ValidationResult r = runValidation(scene, tree.vertices, tree.fragments, order, options);

  nlohmann::ordered_json j;
  j["scene"] = scene.name;
  j["order"] = args.order;
  j["polygons"] = scene.polygons.size();
  j["fragments"] = tree.fragments.size();
  j["nonconvex_fragments"] = r.nonconvex_polygons;
  j["eyes"] = r.eyes;
  j["views"] = r.views;
  j["size"] = args.size;
  j["pixels"] = r.pixels;
  j["exact_pixels"] = r.exact_pixels;
  j["order_error_pixels"] = r.painter.order_error;
  j["tie_pixels"] = r.painter.tie;
  j["edge_pixels"] = r.painter.edge;
  j["uncovered_pixels"] = r.painter.uncovered;
  j["tie_tolerance_relative"] = r.tie_tolerance;
  j["edge_margin_pixels"] = kEdgeMarginPixels;
  j["near"] = r.near;
  j["off_plane_eyes"] = static_cast<int>(args.views * options.off_plane_fraction);
  auto zerr = nlohmann::ordered_json::object();
  auto zdetail = nlohmann::ordered_json::object();
  for (const ZBufferResult& z : r.zbuffer) {
    zerr[std::to_string(z.bits)] = z.counts.order_error;
    auto d = countsJson(z.counts);
    d["depth_format"] = z.depth_format;
    zdetail[std::to_string(z.bits)] = d;
  }
  j["zbuffer_error_pixels"] = zerr;
  j["zbuffer"] = zdetail;
  auto worst = nlohmann::ordered_json::array();
  for (const ViewReport& v : r.worst_views) {
    nlohmann::ordered_json w{{"eye_index", v.eye_index},
                               {"eye", {v.eye.x, v.eye.y, v.eye.z}},
                               {"face", v.face},
                               {"on_height_plane", v.on_height_plane}};
    const nlohmann::ordered_json counts = countsJson(v.painter);
    for (auto it = counts.begin(); it != counts.end(); ++it) w[it.key()] = it.value();
    auto zv = nlohmann::ordered_json::object();
    for (size_t z = 0; z < v.zbuffer_errors.size(); ++z) zv[std::to_string(r.zbuffer[z].bits)] = v.zbuffer_errors[z];
    w["zbuffer_error_pixels"] = zv;
    worst.push_back(w);
  }
  j["worst_views"] = worst;
  j["diff_images"] = r.diff_images;
  j["gl_renderer"] = r.gl_renderer;
  j["seconds"] = {{"load", load_seconds},
                  {"bsp", bsp_seconds},
                  {"validate", r.seconds},
                  {"order", r.order_seconds},
                  {"render", r.render_seconds},
                  {"raycast", r.raycast_seconds},
                  {"classify", r.classify_seconds}};

  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    auto pct = [&](uint64_t n) { return r.pixels ? 100.0 * static_cast<double>(n) / static_cast<double>(r.pixels) : 0.0; };
    std::printf("scene               %s (%zu polygons, %zu BSP fragments)\n", scene.name.c_str(), scene.polygons.size(),
                tree.fragments.size());
    if (r.nonconvex_polygons > 0)
      std::printf("warning             %llu of the drawn polygons are not convex\n",
                  static_cast<unsigned long long>(r.nonconvex_polygons));
    std::printf("views               %llu (%llu eyes x 6 faces, %d x %d, %d off the height planes)\n",
                static_cast<unsigned long long>(r.views), static_cast<unsigned long long>(r.eyes), args.size, args.size,
                static_cast<int>(args.views * options.off_plane_fraction));
    std::printf("pixels              %llu per image kind\n", static_cast<unsigned long long>(r.pixels));
    std::printf("order_error_pixels  %llu (painter's, %s order)\n", static_cast<unsigned long long>(r.painter.order_error),
                args.order.c_str());
    std::printf("tie_pixels          %llu (%.4f%%; tolerance %.0e of the depth)\n",
                static_cast<unsigned long long>(r.painter.tie), pct(r.painter.tie), r.tie_tolerance);
    std::printf("edge_pixels         %llu (%.4f%%; %llu uncovered; edge margin %.4f px)\n",
                static_cast<unsigned long long>(r.painter.edge), pct(r.painter.edge),
                static_cast<unsigned long long>(r.painter.uncovered), kEdgeMarginPixels);
    for (const ZBufferResult& z : r.zbuffer)
      std::printf("zbuffer %2d bits     %llu error pixels, %llu tie, %llu edge (%s)\n", z.bits,
                  static_cast<unsigned long long>(z.counts.order_error), static_cast<unsigned long long>(z.counts.tie),
                  static_cast<unsigned long long>(z.counts.edge), z.depth_format.c_str());
    for (const ViewReport& v : r.worst_views)
      std::printf("worst view          eye %d (%.3f, %.3f, %.3f) face %d: %llu order errors, %llu edge\n", v.eye_index,
                  v.eye.x, v.eye.y, v.eye.z, v.face, static_cast<unsigned long long>(v.painter.order_error),
                  static_cast<unsigned long long>(v.painter.edge));
    if (!args.diff_dir.empty())
      std::printf("diff images         %llu in %s\n", static_cast<unsigned long long>(r.diff_images), args.diff_dir.c_str());
    std::printf("time                %.1f s (bsp %.1f, render %.1f, raycast %.1f, classify %.1f)\n", r.seconds, bsp_seconds,
                r.render_seconds, r.raycast_seconds, r.classify_seconds);
  }
  return r.painter.order_error == 0 ? 0 : 1;
}

}  // namespace

void addValidateCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<ValidateArgs>();
  auto* sub = app.add_subcommand("validate", "Painter's order and z-buffer images against exact ray casting");
  addSceneArgs(*sub, args->scene);
  sub->add_option("--order", args->order, "Priority order to validate")->check(CLI::IsMember({"bsp"}));
  sub->add_option("--views", args->views, "Eyes to sample (6 cube faces each)")->check(CLI::Range(1, 1000000));
  sub->add_option("--seed", args->seed, "Seed of the eye sampling");
  sub->add_option("--size", args->size, "Pixels per side of a cube face")->check(CLI::Range(8, 4096));
  sub->add_option("--zbits", args->zbits, "Z-buffer depth precisions to test: any of 16,24,32, or none");
  sub->add_option("--off-plane", args->off_plane,
                  "Fraction of eyes off the height planes (random y within the bounds; BSP order only)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--near", args->near, "Near plane distance (default: 0.05 x eye height)");
  sub->add_flag("--json", args->json, "Print one JSON object");
  sub->add_flag("--quiet", args->quiet, "No progress on stderr");
  sub->add_option("--diff-dir", args->diff_dir,
                  "Write PNGs of views with order or z-buffer errors (red: order error, cyan: tie, yellow: edge, "
                  "magenta: uncovered), at most 200");
  sub->callback([&runner, args] { runner = [args] { return runValidate(*args); }; });
}

}  // namespace walkvis
