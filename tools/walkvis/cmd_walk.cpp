// walkvis walk SCENE|FILE: the interactive walkthrough window (walk_window.h).
#include <memory>

#include "commands.h"
#include "walk_window.h"

namespace walkvis {

void addWalkCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<WalkArgs>();
  CLI::App* sub = app.add_subcommand(
      "walk",
      "Walk a building in a window: WASD + mouse, 1-4 order mode, B backface method, F wireframe, R rejected, "
      "P/F12 screenshot, H overlay, Esc release mouse / quit");
  sub->add_option("source", args->source, "A scene (model.obj, freedoom2.wad:MAP01, gen:office) or a tree file")
      ->required();
  sub->add_option("--scene", args->scene, "For a tree file: the scene it was built from (its colours)");
  addLoadOptions(*sub, args->load);
  sub->add_option("--mode", args->mode, "zbuffer | bsp | pfd | hfd (default: the tree file's kind, else bsp)");
  sub->add_option("--cull", args->cull, "Backface method: none | polygon | mask | cluster | hierarchy | region");
  sub->add_option("--objects", args->objects,
                  "Mesh objects: auto (the animated blob in gen:office) | none | blob (in the start room)");
  sub->add_option("--size", args->size, "Window size WxH");
  sub->add_option("--path", args->path, "Follow this camera path (CSV), one frame per key");
  sub->add_flag("--quit-at-end", args->quit_at_end, "With --path: close the window after the last key");
  sub->add_option("--record", args->record, "Write the walk as a camera path (CSV) when the window closes");
  sub->add_option("--screenshot-dir", args->screenshot_dir,
                  "Folder for screenshots (P/F12); with --path one per key, frame_NNNNN.png, overlay hidden");
  sub->add_flag("--ids", args->ids, "Draw ids (fragment index + 1 as RGB) instead of shaded faces");
  sub->add_flag("--screenshot-overlay", args->screenshot_overlay,
                "Path screenshots include the overlay (default: the scene only, as `walkvis render`)");
  sub->add_flag("--wireframe", args->wireframe, "Start in wireframe (F toggles)");
  sub->add_flag("--show-rejected", args->show_rejected,
                "Start showing what the order and culling rejected, drawn last in a marker colour (R toggles)");
  sub->add_flag("--no-overlay", args->no_overlay, "Start with the overlay hidden (H toggles it)");
  sub->callback([args, &runner] { runner = [args] { return runWalk(*args); }; });
}

}  // namespace walkvis
