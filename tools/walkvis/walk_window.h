// `walkvis walk`: the interactive walkthrough window (GLFW, OpenGL 4.5 core, Dear ImGui overlay).
// Kept in the tool so that no library others link depends on GLFW or ImGui.
#pragma once

#include <cstdint>
#include <string>

#include "scenes/scene.h"

namespace walkvis {

struct WalkArgs {
  std::string source;              // scene spec or tree file
  std::string scene;               // for a tree file: the scene it was built from
  LoadOptions load;                // how a scene (or the --scene of a tree file) is loaded
  std::string mode;                // zbuffer | bsp | pfd | hfd; empty: the source's best
  std::string cull = "none";
  std::string objects = "auto";    // mesh objects: auto | none | blob (mesh_object.h)
  std::string size = "960x600";
  std::string path;                // camera path to follow, one frame per key
  bool quit_at_end = false;        // with path: close after its last key
  std::string record;              // write the walk as a camera path here on exit
  std::string screenshot_dir;      // screenshots (F12 / P; with path: one per key, frame_NNNNN.png)
  bool ids = false;                // ids style (DrawStyle::kIds), for comparisons
  bool no_overlay = false;
  bool wireframe = false;          // start with wireframe on (F toggles)
  bool show_rejected = false;      // start showing what was rejected (R toggles)
  bool screenshot_overlay = false;  // path screenshots include the overlay (for people, not comparisons)
};

// Opens the window and runs until it is closed (Esc twice, the close button, or the end of the
// path with quit_at_end). Returns the exit status; throws Error for bad input and
// std::runtime_error when no window or GL 4.5 context can be had.
int runWalk(const WalkArgs& args);

}  // namespace walkvis
