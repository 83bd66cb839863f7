// One Embree 3 scene of triangles (Wald et al. 2014 [Embree2014], docs/REFERENCES.md), the only
// place walkvis makes one: the HFD visibility scene (pfd_hfd/visibility.cpp) and the exact
// reference ray caster (walkthrough/raycast.cpp) both query it. Embree's pattern: build, commit,
// then query from any number of threads; the object owns the device and the scene (RAII).
//
// The scene is robust (watertight triangle tests: a ray through an edge two triangles share is not
// let through) and built at high quality, since it is built once and queried millions of times.
// Vertices are stored in single precision relative to `origin`, which keeps their precision
// where the geometry is (far from the coordinate origin, a model's numbers lose it).
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

#include <embree3/rtcore.h>
#include <glm/vec3.hpp>

namespace walkvis {

struct EmbreeTriangles {
  std::span<const glm::dvec3> vertices;
  glm::dvec3 origin{0.0};
  std::span<const uint32_t> indices;  // three per triangle, into `vertices`
  RTCFilterFunctionN intersect_filter = nullptr;
  RTCFilterFunctionN occluded_filter = nullptr;
  void* user_data = nullptr;  // the geometry's user data, for the filters
};

class EmbreeScene {
 public:
  EmbreeScene() = default;
  // Builds and commits the scene (an empty one when there are no indices). Throws Error
  // "<context>: Embree ..." when Embree fails; indices must be below vertices.size().
  EmbreeScene(const EmbreeTriangles& triangles, std::string_view context);
  EmbreeScene(EmbreeScene&& other) noexcept;
  EmbreeScene& operator=(EmbreeScene&& other) noexcept;
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;
  ~EmbreeScene();

  RTCDevice device() const { return device_; }
  RTCScene scene() const { return scene_; }

 private:
  void release();
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

}  // namespace walkvis
