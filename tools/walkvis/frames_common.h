// Shared by `walkvis render` and `walkvis bench frames`: image sizes, the camera tour (a path file
// or the automatic tour) and one timed frame.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "scenes/scene.h"
#include "walkthrough/camera_path.h"
#include "walkthrough/frame.h"
#include "walkthrough/scene_drawer.h"

namespace walkvis {

struct ImageSize {
  int width = 640, height = 480;
};

// "640x480" → {640, 480}; Error naming the option otherwise (each side in [8, 8192]).
inline ImageSize parseImageSize(const std::string& text, const std::string& option) {
  ImageSize s;
  char x = 0;
  char rest = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &s.width, &x, &s.height, &rest) != 3 || (x != 'x' && x != 'X') ||
      s.width < 8 || s.height < 8 || s.width > 8192 || s.height > 8192)
    throw Error(option + ": '" + text + "' is not an image size WxH with sides in [8, 8192]");
  return s;
}

// The path's keys (loadCameraPath, Error naming the file) when a file is given, else the
// automatic tour of `frames` keys; then at most `frames` keys are kept (0 = all of a path file).
inline CameraPath framesPath(const World& world, const std::string& path_file, uint32_t frames) {
  CameraPath path;
  if (!path_file.empty()) {
    path = loadCameraPath(path_file);
    if (frames > 0 && path.keys.size() > frames) path.keys.resize(frames);
  } else {
    path = automaticTour(world.scene, world.trees.bsp, frames);
    if (path.keys.empty() && frames > 0)
      throw Error(world.source + ": no walkable region for an automatic tour (give --path)");
  }
  return path;
}

inline FreeCamera cameraAt(const CameraKey& key, ImageSize size) {
  FreeCamera c;
  c.eye = key.eye;
  c.yaw = key.yaw;
  c.pitch = key.pitch;
  c.width = size.width;
  c.height = size.height;
  return c;
}

// How a mode is drawn: painter's modes without depth buffer or GL culling; the z-buffer baseline
// with both. With mesh objects (world.objects not empty) the painter's modes also write depth
// (DrawSettings::write_depth: depth test GL_ALWAYS), and the objects are then drawn with GL_LESS.
//
// Why that is exact for painter's order: the painter's pass draws, over every pixel, the polygons
// covering it from back to front, so the last one drawn there is the one the pixel shows, the
// nearest surface. With GL_ALWAYS every polygon drawn writes its depth, so the depth left in the
// pixel is that last polygon's depth: the depth of the nearest surface, rasterised from the same
// float positions and interpolated the same way as the z-buffer pass would store it. An object
// fragment then passes GL_LESS exactly where it passes in the z-buffer frame. Where it is not
// exact: (1) pixels where two surfaces meet or touch within float rounding of their interpolated
// depths (coplanar surfaces, depth ties at 24 bits): the z-buffer keeps the smaller depth, the
// painter's the last drawn, so the scene images and the depth left can differ there, and an object
// surface within that rounding of them can go either way; (2) coverage: a pixel the painter's list
// leaves uncovered where the z-buffer frame shows a polygon (a polygon the order or the backface
// method wrongly dropped: an error the ids comparison counts anyway) keeps the cleared, far depth,
// so the object shows there in front of what should hide it; (3) the show-rejected view, whose
// marker polygons are drawn last over everything and write their depth too.
inline DrawSettings settingsFor(OrderMode mode, DrawStyle style, bool objects = false) {
  DrawSettings s;
  s.style = style;
  s.depth_test = mode == OrderMode::kZBuffer;
  s.cull_back_faces = mode == OrderMode::kZBuffer;
  s.write_depth = objects && mode != OrderMode::kZBuffer;
  return s;
}

// The mesh objects of the builder's last frame, over the scene just drawn.
inline void drawObjects(const FrameBuilder& builder, SceneDrawer& drawer, const FreeCamera& camera,
                        const DrawSettings& settings) {
  for (const ObjectTriangles& o : builder.objects()) drawer.drawTriangles(camera, o.corners, o.ids, o.color, settings);
}

// One frame at animation time `time`: order + objects + draw + glFinish; stats.draw_ms filled.
inline FrameStats timedFrame(const World& world, FrameBuilder& builder, SceneDrawer& drawer, const FreeCamera& camera,
                             OrderMode mode, DrawStyle style, std::vector<uint32_t>& draw, double time = 0.0) {
  FrameStats stats = builder.build(world, camera, mode, draw, time);
  const auto t0 = std::chrono::steady_clock::now();
  const DrawSettings settings = settingsFor(mode, style, !world.objects.empty());
  drawer.draw(camera, draw, settings);
  drawObjects(builder, drawer, camera, settings);
  drawer.finish();
  stats.draw_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

}  // namespace walkvis
