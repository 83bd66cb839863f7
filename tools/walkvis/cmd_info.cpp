// walkvis info SCENE [--json]: what a scene holds and what loading it changed.
#include <chrono>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "commands.h"

namespace walkvis {
namespace {

struct InfoArgs {
  SceneArgs scene;
  bool json = false;
};

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
  j["kept_faces"] = r.kept_faces;
  j["split_faces"] = r.split_faces;
  j["split_pieces"] = r.split_pieces;
  j["dropped_faces"] = r.dropped_zero_area + r.dropped_degenerate;
  j["dropped_zero_area"] = r.dropped_zero_area;
  j["dropped_degenerate"] = r.dropped_degenerate;
  j["closed"] = closed;
  j["notes"] = r.notes;
  j["load_seconds"] = load_seconds;

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
  std::printf("loader       %llu kept, %llu split into %llu pieces, %llu dropped (%llu zero-area, %llu degenerate)\n",
              static_cast<unsigned long long>(r.kept_faces), static_cast<unsigned long long>(r.split_faces),
              static_cast<unsigned long long>(r.split_pieces),
              static_cast<unsigned long long>(r.dropped_zero_area + r.dropped_degenerate),
              static_cast<unsigned long long>(r.dropped_zero_area),
              static_cast<unsigned long long>(r.dropped_degenerate));
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
  sub->callback([args, &runner] { runner = [args] { return runInfo(*args); }; });
}

}  // namespace walkvis
