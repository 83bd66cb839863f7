// What every scene a loader returns must satisfy, checked after each successful fuzz input:
// a violation traps, so libFuzzer keeps the input as a crash.
#pragma once

#include <cmath>

#include <glm/geometric.hpp>

#include "scenes/scene.h"

namespace walkvis {

inline void checkSceneInvariants(const Scene& scene) {
  const LoadReport& r = scene.report;
  // Merged input faces became fewer faces: each merged face counts once in kept or split.
  if (r.merged_faces > r.merged_input_faces) __builtin_trap();
  const uint64_t merged_away = r.merged_input_faces - r.merged_faces;
  if (r.kept_faces + r.split_faces + r.dropped_zero_area + r.dropped_degenerate + merged_away != r.input_faces)
    __builtin_trap();
  if (scene.face_colors.size() != r.input_faces - merged_away) __builtin_trap();
  if (!r.input_to_face.empty()) {
    if (r.input_to_face.size() != r.input_faces) __builtin_trap();
    for (uint32_t f : r.input_to_face)
      if (f >= scene.face_colors.size()) __builtin_trap();
  }
  if (!scene.face_object.empty() && scene.face_object.size() != scene.face_colors.size()) __builtin_trap();
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
