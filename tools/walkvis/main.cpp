// walkvis: subcommands over the walkvis libraries. Bad input prints one line and exits 2.
#include <cstdio>
#include <exception>

#include "commands.h"

namespace walkvis {

void addSceneArgs(CLI::App& sub, SceneArgs& args, bool required) {
  auto* opt = sub.add_option("scene", args.scene,
                             "Scene: model.obj, model.gltf/.glb, freedoom2.wad:MAP07, gen:office?rooms=40&seed=3");
  if (required) opt->required();
  sub.add_option("--eye-height", args.eye_height,
                 "Eye height above the floor (default: 41 for WAD maps, 1.7 otherwise)")
      ->check(CLI::PositiveNumber);
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
  addRenderCommand(app, runner);
  addWalkCommand(app, runner);
  addStatsCommand(app, runner);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int status = app.exit(e);
    return status == 0 ? 0 : kExitBadInput;
  }
  try {
    return runner ? runner() : 0;
  } catch (const SceneError& e) {
    std::fprintf(stderr, "walkvis: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "walkvis: error: %s\n", e.what());
    return 1;
  }
}
