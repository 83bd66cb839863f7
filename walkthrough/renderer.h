// Offscreen OpenGL 4.5 ID-buffer renderer (OSMesa, software): every polygon drawn in one flat
// unsigned id, no lighting, no anti-aliasing; back faces are never drawn (docs/DESIGN.md, "ID
// images"). GL functions are loaded per context (glad --mx), so this can live beside a
// windowed GL context in the same process.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "scenes/scene.h"
#include "walkthrough/camera.h"

namespace walkvis {

constexpr uint32_t kNoPolygon = 0xFFFFFFFFu;

class OffscreenRenderer {
 public:
  // A size × size renderer with a depth buffer of depth_bits (16, 24 or 32; 32 uses a 32-bit
  // unsigned-normalised buffer when the driver can render to one, else 32-bit float; depthFormat()
  // says which). Returns nullopt when OSMesa cannot give a GL 4.5 core context or the framebuffer is
  // incomplete; error() of a failed create is written to *why when given.
  static std::optional<OffscreenRenderer> create(int size, int depth_bits, std::string* why = nullptr);

  OffscreenRenderer(OffscreenRenderer&&) noexcept;
  OffscreenRenderer& operator=(OffscreenRenderer&&) noexcept;
  ~OffscreenRenderer();

  // Uploads the geometry once: polygons[k] uses vertices[first_vertex, first_vertex + vertex_count),
  // convex, counter-clockwise seen from the front, drawn as a triangle fan with id k. Replaces any
  // earlier geometry. Vertices are kept in double and sent to GL relative to each view's eye, so
  // large coordinates keep their precision near the eye.
  void upload(std::span<const glm::dvec3> vertices, std::span<const Polygon> polygons);

  // Painter's mode: the polygons of `order` (indices into the uploaded polygons, any that are out of
  // range are skipped) drawn in the given order, first drawn = farthest, depth test off.
  void drawPainter(const View& view, std::span<const uint32_t> order);
  // Z-buffer mode: the polygons of `order` (all of them when order is empty), depth test on (LESS).
  void drawZBuffer(const View& view, std::span<const uint32_t> order = {});

  // The last image: size * size polygon indices (kNoPolygon where nothing was drawn), row 0 at the
  // top (camera.h convention).
  std::vector<uint32_t> readIds();
  void readIds(std::vector<uint32_t>& out);

  int size() const;
  int depthBits() const;
  const char* depthFormat() const;  // "DEPTH_COMPONENT16", ..., or "DEPTH_COMPONENT32F"
  std::string glRenderer() const;   // GL_RENDERER and GL_VERSION strings

 private:
  struct Impl;
  explicit OffscreenRenderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace walkvis
