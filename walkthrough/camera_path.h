// Walking cameras: a person's view (eye, yaw, pitch) over time, recorded paths, and the automatic
// tour through a scene's walkable region used when no path is given.
//
// Conventions: y is up. yaw in radians about +y, 0 looks along −z, positive turns towards −x
// (counter-clockwise seen from above); pitch in radians, positive looks up, |pitch| < pi/2.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "bsp/bsp.h"
#include "scenes/scene.h"

namespace walkvis {

struct CameraKey {
  double time = 0.0;  // seconds from the path's start, non-decreasing along a path
  glm::dvec3 eye{0.0};
  double yaw = 0.0;
  double pitch = 0.0;
};

struct CameraPath {
  std::vector<CameraKey> keys;
};

// Unit view direction of a yaw and pitch.
glm::dvec3 viewDirection(double yaw, double pitch);

// CSV with the header line "time,x,y,z,yaw,pitch" and one key per line. Error naming the file
// and line for a missing file, a bad header, a non-number, a non-finite value, a time going back,
// |pitch| >= pi/2, or no keys at all.
CameraPath loadCameraPath(const std::string& path);
// Written to a temporary file beside `path` and renamed; Error naming the path on failure.
void saveCameraPath(const CameraPath& path, const std::string& file);

// `frames` keys, one per 1/fps s, walking at eye height through the walkable region of the scene
// (levels, eye_height): from the start eye, along straight legs between random walkable points
// that the BSP says are mutually visible at eye height (no leg passes through a wall), turning the
// view towards the direction of travel. Deterministic for a seed. Empty for a scene without
// walkable region or when frames == 0.
CameraPath automaticTour(const Scene& scene, const BspTree& bsp, uint32_t frames, double fps = 30.0,
                         uint64_t seed = 1);

}  // namespace walkvis
