// Drawing walkthrough frames with OpenGL 4.5 core on whatever context is current (a GLFW window or
// an OSMesa buffer): GL functions are loaded per drawer through the given loader (glad --mx), so
// the window and offscreen paths share every line of drawing code and their images can be compared.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "bsp/bsp.h"
#include "scenes/scene.h"
#include "walkthrough/camera.h"

namespace walkvis {

using GlLoader = void* (*)(const char* name);  // glfwGetProcAddress, OSMesaGetProcAddress

enum class DrawStyle : uint8_t {
  kShaded,  // face colour times a fixed head-light term: what a person looks at
  kIds,     // fragment index as a flat colour (RGBA8, index + 1; 0 = nothing): for comparisons
};

struct DrawSettings {
  DrawStyle style = DrawStyle::kShaded;
  bool depth_test = false;       // true only for the z-buffer mode
  // Painter's modes with mesh objects: depth test on with GL_ALWAYS and depth writes, so the depth
  // buffer ends up holding the depth of the polygon each pixel shows (the last drawn there), for
  // drawTriangles to test against. Ignored when depth_test is set.
  bool write_depth = false;
  bool cull_back_faces = false;  // GL's own back-face culling (the z-buffer baseline)
  bool wireframe = false;
  uint32_t highlight_from = UINT32_MAX;  // draw[k] for k >= this in a marker colour (showing what was rejected)
};

class SceneDrawer {
 public:
  // Needs a current GL 4.5 core context; nullopt (and *why) when functions are missing.
  static std::optional<SceneDrawer> create(GlLoader loader, std::string* why = nullptr);
  SceneDrawer(SceneDrawer&&) noexcept;
  SceneDrawer& operator=(SceneDrawer&&) noexcept;
  ~SceneDrawer();

  // The BSP fragments (convex, CCW from the front), coloured by scene.face_colors[face_id].
  void upload(const BspTree& bsp, const Scene& scene);
  // Clears and draws fragments `draw` in order into the bound framebuffer, viewport
  // camera.width × camera.height.
  void draw(const FreeCamera& camera, std::span<const uint32_t> draw, const DrawSettings& settings);
  // Draws free triangles (a mesh object's frame: `corners` 3 per triangle in world coordinates,
  // `ids` one per triangle, any order) over what draw() left, without clearing, with depth test
  // GL_LESS against the depth there and depth writes, no GL face culling (the caller passes only
  // triangles facing the eye), flat-shaded in `color` (0xRRGGBB) or as ids. Needs draw() first in
  // this frame with depth_test or write_depth set for the depth test to mean anything.
  void drawTriangles(const FreeCamera& camera, std::span<const glm::dvec3> corners, std::span<const uint32_t> ids,
                     uint32_t color, const DrawSettings& settings);
  // The bound framebuffer, row 0 at the top: RGB8 (width*height*3) or, after a kIds draw, fragment
  // indices (kNoFragment where nothing was drawn).
  void readRgb(int width, int height, std::vector<uint8_t>& rgb);
  void readIds(int width, int height, std::vector<uint32_t>& ids);
  void finish();  // glFinish, so frame times measure the drawing

 private:
  struct Impl;
  explicit SceneDrawer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

constexpr uint32_t kNoFragment = 0xFFFFFFFFu;

}  // namespace walkvis
