// An offscreen OpenGL 4.5 core context on OSMesa (Mesa's software GL, llvmpipe) with its own RGBA8
// colour buffer and a depth buffer, for SceneDrawer (scene_drawer.h): offscreen frames, `bench
// frames` and tests draw with exactly the code the window uses.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "walkthrough/scene_drawer.h"

namespace walkvis {

class OsMesaContext {
 public:
  // width × height pixels (each in [1, 16384]), depth_bits 16, 24 or 32. nullopt (and *why) when
  // OSMesa cannot give a GL 4.5 core context. The new context is current on this thread.
  static std::optional<OsMesaContext> create(int width, int height, int depth_bits = 24,
                                             std::string* why = nullptr);
  OsMesaContext(OsMesaContext&&) noexcept;
  OsMesaContext& operator=(OsMesaContext&&) noexcept;
  ~OsMesaContext();

  // Makes this context current on the calling thread (OSMesa binds per thread); throws
  // std::runtime_error when OSMesa refuses.
  void makeCurrent();
  int width() const;
  int height() const;
  // OSMesaGetProcAddress, as SceneDrawer::create wants it.
  static GlLoader loader();

 private:
  struct Impl;
  explicit OsMesaContext(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace walkvis
