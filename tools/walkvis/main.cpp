// walkvis: subcommands over the walkvis libraries. Bad input prints one line and exits 2.
#include <cstdio>
#include <exception>

#include "commands.h"

namespace walkvis {

void addLoadOptions(CLI::App& sub, LoadOptions& load) {
  // One heading in --help, so a command's own options stay easy to find.
  static constexpr const char* kLoadGroup = "Scene loading";
  sub.add_option("--eye-height", load.eye_height, "Eye height above the floor (default: 41 for WAD maps, 1.7 otherwise)")
      ->check(CLI::PositiveNumber)->group(kLoadGroup);
  sub.add_option("--loader", load.loader,
                 "assimp: read .obj/.gltf through assimp too (other formats always are); default: by extension")
      ->check(CLI::IsMember({"assimp"}))->group(kLoadGroup);
  sub.add_option_function<std::string>(
         "--up", [&load](const std::string& axis) { load.up_axis = axis[0]; },
         "The file's up axis, y or z (default: as the file states; y when it states none)")
      ->check(CLI::IsMember({"y", "z"}))->group(kLoadGroup);
  sub.add_option("--unit-scale", load.unit_scale, "Metres per file unit (default: as the file states; 1 when it states none)")
      ->check(CLI::PositiveNumber)->group(kLoadGroup);
  sub.add_flag("!--no-merge", load.merge_faces, "Keep every input face (no merging of adjacent coplanar triangles)")
      ->group(kLoadGroup);
  sub.add_option("--floors", load.floors,
                 "Floor levels: navmesh (Recast: what a walker can stand on) | faces (every upward face height); "
                 "default: WAD sector floors, navmesh for mesh files")
      ->check(CLI::IsMember({"navmesh", "faces"}))->group(kLoadGroup);
  WalkableOptions& w = load.walkable;
  sub.add_option("--agent-height", w.agent_height, "Headroom a walker needs (default: 1.2 x eye height)")
      ->check(CLI::PositiveNumber)->group(kLoadGroup);
  sub.add_option("--agent-radius", w.agent_radius, "Walker radius kept from walls (default: 0.15 x eye height)")
      ->check(CLI::NonNegativeNumber)->group(kLoadGroup);
  sub.add_option("--max-climb", w.max_climb, "Highest step a walker climbs (default: 0.2 x eye height)")
      ->check(CLI::NonNegativeNumber)->group(kLoadGroup);
  sub.add_option("--max-slope", w.max_slope_deg, "Steepest walkable slope in degrees (default: 45)")
      ->check(CLI::Range(0.0, 89.0))->group(kLoadGroup);
  sub.add_option("--min-level-area", w.min_level_area,
                 "Smallest floor area that is a level (default: 0.35 x eye height squared, 1 m2 at 1.7 m)")
      ->check(CLI::NonNegativeNumber)->group(kLoadGroup);
}

void addSceneArgs(CLI::App& sub, SceneArgs& args, bool required) {
  auto* opt = sub.add_option("scene", args.scene,
                             "Scene: model.obj, model.gltf/.glb, a file assimp reads (.ifc, .fbx, .dae, .3ds, ...), "
                             "freedoom2.wad:MAP07, gen:office?rooms=40&seed=3");
  if (required) opt->required();
  addLoadOptions(sub, args.load);
}

}  // namespace walkvis

int main(int argc, char** argv) {
  using namespace walkvis;
  CLI::App app{"walkvis: priority-order walkthroughs of buildings (BSP, PFD and HFD trees, backface culling)"};
  app.require_subcommand(1);
  CommandRunner runner;
  addInfoCommand(app, runner);
  addBenchCommand(app, runner);
  addValidateCommand(app, runner);
  addBuildCommand(app, runner);
  addPlanCommand(app, runner);
  addRenderCommand(app, runner);
  addWalkCommand(app, runner);
  addStatsCommand(app, runner);
  addReportCommand(app, runner);
  addExportCommand(app, runner);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int status = app.exit(e);
    return status == 0 ? 0 : kExitBadInput;
  }
  try {
    return runner ? runner() : 0;
  } catch (const Error& e) {
    std::fprintf(stderr, "walkvis: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "walkvis: error: %s\n", e.what());
    return 1;
  }
}
