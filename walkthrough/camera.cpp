// Cube-face cameras: a standard OpenGL perspective (fovy 90°, aspect 1), with the pixel-centre
// rays derived from the same frame so that GL rasterisation and ray casting sample the same rays.
#include "walkthrough/camera.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/check.h"

namespace walkvis {

CubeFrame cubeFrame(int face) {
  switch (std::clamp(face, 0, kCubeFaces - 1)) {
    case 0: return {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}};
    case 1: return {{-1, 0, 0}, {0, 0, -1}, {0, 1, 0}};
    case 2: return {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}};
    case 3: return {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}};
    case 4: return {{0, 0, 1}, {-1, 0, 0}, {0, 1, 0}};
    default: return {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}};
  }
}

glm::dvec3 pixelRay(const View& view, int i, int j) {
  const CubeFrame f = cubeFrame(view.face);
  const double s = view.size;
  const double a = 2.0 * (i + 0.5) / s - 1.0;
  const double b = 1.0 - 2.0 * (j + 0.5) / s;
  return f.forward + a * f.right + b * f.up;
}

std::array<float, 16> clipFromEyeRelative(const View& view) {
  WALKVIS_DCHECK(view.size > 0 && view.near > 0.0 && view.far > view.near);
  const CubeFrame f = cubeFrame(view.face);
  const double n = view.near, fa = view.far;
  // Camera space: x = right·p, y = up·p, z = -forward·p (looking down -z).
  // Clip: (x, y, A z + B, -z) with A = (f + n) / (n - f), B = 2 f n / (n - f).
  const double A = (fa + n) / (n - fa);
  const double B = 2.0 * fa * n / (n - fa);
  // Rows of the clip matrix as functions of p.
  const glm::dvec3 row0 = f.right, row1 = f.up, row2 = -A * f.forward, row3 = f.forward;
  std::array<float, 16> m{};
  auto set = [&](int row, const glm::dvec3& r, double w) {
    m[0 * 4 + row] = static_cast<float>(r.x);
    m[1 * 4 + row] = static_cast<float>(r.y);
    m[2 * 4 + row] = static_cast<float>(r.z);
    m[3 * 4 + row] = static_cast<float>(w);
  };
  set(0, row0, 0.0);
  set(1, row1, 0.0);
  set(2, row2, B);
  set(3, row3, 0.0);
  return m;
}

}  // namespace walkvis

namespace walkvis {

// FreeCamera: yaw about +y (0 looks along -z, positive towards -x), pitch up; a standard OpenGL
// perspective with the vertical field of view fov_y and the image's aspect ratio.
CubeFrame cameraFrame(const FreeCamera& camera) {
  const double cp = std::cos(camera.pitch), sp = std::sin(camera.pitch);
  const double cy = std::cos(camera.yaw), sy = std::sin(camera.yaw);
  CubeFrame frame;
  frame.forward = {-sy * cp, sp, -cy * cp};
  frame.right = {cy, 0.0, -sy};  // forward × +y, normalised
  frame.up = {sy * sp, cp, cy * sp};
  return frame;
}

namespace {

// GL gets float positions relative to the eye and a float matrix: their rounding (~6e-8 of the
// distance each) could move a vertex just inside a plane that double arithmetic put it outside of,
// so a ball (or a corner, radius 0) at c from the eye grows by 1e-6 of the farthest distance it
// reaches, ten times more than that.
double grownRadius(const glm::dvec3& c, double radius) {
  return radius + 1e-6 * (radius + std::abs(c.x) + std::abs(c.y) + std::abs(c.z));
}

// A point p - eye = x right + y up + w forward is inside where |x| <= w tx, |y| <= w ty and
// near <= w <= far.
ViewFrustum frustumOf(const glm::dvec3& eye, const CubeFrame& frame, double tx, double ty, double near, double far) {
  ViewFrustum v;
  v.eye = eye;
  v.forward = frame.forward;
  v.near = near;
  v.far = far;
  v.inward[0] = (tx * frame.forward - frame.right) / std::sqrt(1.0 + tx * tx);
  v.inward[1] = (tx * frame.forward + frame.right) / std::sqrt(1.0 + tx * tx);
  v.inward[2] = (ty * frame.forward - frame.up) / std::sqrt(1.0 + ty * ty);
  v.inward[3] = (ty * frame.forward + frame.up) / std::sqrt(1.0 + ty * ty);
  return v;
}

}  // namespace

ViewFrustum viewFrustum(const FreeCamera& camera) {
  WALKVIS_DCHECK(camera.width > 0 && camera.height > 0 && camera.near > 0.0 && camera.near < camera.far);
  const double ty = std::tan(0.5 * camera.fov_y);
  const double tx = ty * static_cast<double>(camera.width) / static_cast<double>(camera.height);
  return frustumOf(camera.eye, cameraFrame(camera), tx, ty, camera.near, camera.far);
}

ViewFrustum viewFrustum(const View& view) {
  WALKVIS_DCHECK(view.size > 0 && view.near > 0.0 && view.far > view.near);
  return frustumOf(view.eye, cubeFrame(view.face), 1.0, 1.0, view.near, view.far);
}

bool ViewFrustum::excludesBall(const glm::dvec3& centre, double radius) const {
  return cutPlanes(centre, radius) == kBallOutside;
}

unsigned ViewFrustum::cutPlanes(const glm::dvec3& centre, double radius) const {
  const glm::dvec3 c = centre - eye;
  const double r = grownRadius(c, radius);
  unsigned cut = 0;
  for (unsigned k = 0; k < 4; ++k) {
    const double d = glm::dot(inward[k], c);
    if (d < -r) return kBallOutside;
    if (d < r) cut |= 1u << k;
  }
  const double w = glm::dot(forward, c);
  if (w < near - r || w > far + r) return kBallOutside;
  if (w < near + r) cut |= 16u;
  if (w > far - r) cut |= 32u;
  return cut;
}

bool ViewFrustum::cornersOutside(unsigned planes, std::span<const glm::dvec3> corners) const {
  for (unsigned k = 0; k < 6; ++k) {
    if (!(planes & (1u << k))) continue;
    bool all = true;
    for (const glm::dvec3& p : corners) {
      const glm::dvec3 q = p - eye;
      const double d = k < 4 ? glm::dot(inward[k], q) : k == 4 ? glm::dot(forward, q) - near : far - glm::dot(forward, q);
      if (!(d < -grownRadius(q, 0.0))) {
        all = false;
        break;
      }
    }
    if (all) return true;
  }
  return false;
}

std::array<float, 16> clipFromEyeRelative(const FreeCamera& camera) {
  WALKVIS_DCHECK(camera.width > 0 && camera.height > 0 && camera.near > 0.0 && camera.near < camera.far);
  const CubeFrame frame = cameraFrame(camera);
  const glm::dvec3 forward = frame.forward, right = frame.right, up = frame.up;
  const double f = 1.0 / std::tan(0.5 * camera.fov_y);
  const double aspect = static_cast<double>(camera.width) / static_cast<double>(camera.height);
  const double n = camera.near, fa = camera.far;
  const double A = (fa + n) / (n - fa);
  const double B = 2.0 * fa * n / (n - fa);
  std::array<float, 16> m{};
  auto set = [&](int row, const glm::dvec3& r, double w) {
    m[0 * 4 + row] = static_cast<float>(r.x);
    m[1 * 4 + row] = static_cast<float>(r.y);
    m[2 * 4 + row] = static_cast<float>(r.z);
    m[3 * 4 + row] = static_cast<float>(w);
  };
  set(0, (f / aspect) * right, 0.0);
  set(1, f * up, 0.0);
  set(2, -A * forward, B);
  set(3, forward, 0.0);
  return m;
}

}  // namespace walkvis
