// What every scene a loader returns must satisfy, checked after each successful fuzz input:
// a violation traps, so libFuzzer keeps the input as a crash.
#pragma once

#include <cmath>

#include <glm/geometric.hpp>

#include "scenes/scene.h"

namespace walkvis {

inline void checkSceneInvariants(const Scene& scene) {
  uint64_t faces = scene.report.kept_faces + scene.report.split_faces + scene.report.dropped_zero_area +
                   scene.report.dropped_degenerate;
  if (faces != scene.report.input_faces) __builtin_trap();
  if (scene.face_colors.size() != scene.report.input_faces) __builtin_trap();
  for (const Polygon& p : scene.polygons) {
    if (p.vertex_count < 3) __builtin_trap();
    if (uint64_t{p.first_vertex} + p.vertex_count > scene.vertices.size()) __builtin_trap();
    if (p.face_id >= scene.face_colors.size()) __builtin_trap();
    if (!std::isfinite(p.plane.d) || std::abs(glm::length(p.plane.n) - 1.0) > 1e-9) __builtin_trap();
    for (const auto& v : scene.polygonVertices(p)) {
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) __builtin_trap();
    }
  }
}

}  // namespace walkvis
