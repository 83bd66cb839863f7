// Cube-face cameras shared by the OpenGL renderer and the exact ray caster. Both MUST derive their
// rays from the same numbers, so a pixel means the same ray everywhere: pixelRay() is the ray
// through a pixel centre, and clipFromEyeRelative() is the GL matrix built to match it exactly.
//
// Image convention: size × size pixels, column i from the left, row j from the TOP, pixel index
// j * size + i. A ray is eye + t * dir with dir's component along the face's forward axis equal
// to 1, so t is the camera depth (the distance along the view axis), the same quantity the GL
// near and far planes clip.
#pragma once

#include <array>
#include <span>

#include <glm/vec3.hpp>

namespace walkvis {

constexpr int kCubeFaces = 6;

// An orthonormal, right-handed view frame: forward = up × right. Face 0..5 look along
// +x, -x, +y, -y, +z, -z. All components are 0 or ±1, so the frames are exact in float too.
struct CubeFrame {
  glm::dvec3 forward, right, up;
};
CubeFrame cubeFrame(int face);  // face in [0, 6); anything else is clamped into range

// One 90° square view: a cube face seen from `eye`, clipped to camera depth [near, far].
struct View {
  glm::dvec3 eye{0.0};
  int face = 0;
  int size = 256;     // pixels per side, > 0
  double near = 0.1;  // > 0
  double far = 1e4;   // > near
};

// Direction of the ray through the centre of pixel (i, j) (not normalised; forward component 1).
glm::dvec3 pixelRay(const View& view, int i, int j);

// Column-major 4×4 clip matrix for vertex positions given RELATIVE TO THE EYE (p - eye): the
// face's rotation followed by a 90°, aspect-1 OpenGL perspective with the view's near and far.
// A point eye + t * pixelRay(view, i, j) lands on the centre of pixel (i, j) with the GL
// convention of rows counted from the bottom (the renderer flips rows on readback).
std::array<float, 16> clipFromEyeRelative(const View& view);

}  // namespace walkvis

namespace walkvis {

// A person's perspective view (the window and the camera paths), rather than a cube face.
struct FreeCamera {
  glm::dvec3 eye{0.0};
  double yaw = 0.0;    // camera_path.h conventions
  double pitch = 0.0;
  double fov_y = 1.2217304763960306;  // 70 degrees, full vertical angle
  int width = 640, height = 480;      // pixels, > 0
  double near = 0.05, far = 1e4;      // camera depth, 0 < near < far
};

// The camera's orthonormal frame: forward is where it looks, right stays level (pitch does not
// tilt it), up = right × forward.
CubeFrame cameraFrame(const FreeCamera& camera);

// A view volume as six planes, for culling on the CPU before GL sees a polygon: a person's camera
// or a cube face (whose sides lie at 45 degrees).
struct ViewFrustum {
  glm::dvec3 eye{0.0};
  glm::dvec3 inward[4];  // unit normals of the side planes through the eye, pointing inside
  glm::dvec3 forward{0.0};
  double near = 0.0, far = 0.0;
  // True only when the whole ball lies outside one of the planes, so nothing in it can reach a
  // pixel: a polygon inside such a ball can be left out without changing the image.
  bool excludesBall(const glm::dvec3& centre, double radius) const;
  // The planes that cut the ball, as a mask for cornersOutside (bits 0-3 inward[k], 4 near, 5 far;
  // 0: wholly inside them all), or kBallOutside where excludesBall is true.
  static constexpr unsigned kBallOutside = ~0u;
  unsigned cutPlanes(const glm::dvec3& centre, double radius) const;
  // True only when every corner lies outside one of the planes in the mask (with excludesBall's
  // margin for a ball of radius 0), so the polygon they span does too. For the polygons whose
  // ball the planes cut: a long wall beside the view has a ball that reaches into it.
  bool cornersOutside(unsigned planes, std::span<const glm::dvec3> corners) const;
};
ViewFrustum viewFrustum(const FreeCamera& camera);
ViewFrustum viewFrustum(const View& view);

// Column-major clip matrix for positions relative to the eye (p - eye), as clipFromEyeRelative(View).
std::array<float, 16> clipFromEyeRelative(const FreeCamera& camera);

}  // namespace walkvis
