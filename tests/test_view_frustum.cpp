// The view frustum's ball test (camera.h) against brute force: a ball it excludes holds no point
// that the camera's perspective puts inside its image and depth range, whatever the camera; a ball
// whose centre is inside is never excluded; and on random balls it excludes many.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "core/rng.h"
#include "walkthrough/camera.h"

namespace walkvis {
namespace {

glm::dvec3 randomUnit(Rng& rng) {
  for (;;) {
    const glm::dvec3 v(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const double l = glm::length(v);
    if (l > 1e-3 && l <= 1.0) return v / l;
  }
}

FreeCamera randomCamera(Rng& rng) {
  FreeCamera c;
  c.eye = {rng.uniform(-50, 50), rng.uniform(-5, 5), rng.uniform(-50, 50)};
  c.yaw = rng.uniform(-3.2, 3.2);
  c.pitch = rng.uniform(-1.5, 1.5);
  c.fov_y = rng.uniform(0.3, 2.5);
  c.width = 1 + static_cast<int>(rng.below(1920));
  c.height = 1 + static_cast<int>(rng.below(1080));
  c.near = rng.uniform(0.01, 1.0);
  c.far = c.near + rng.uniform(1.0, 200.0);
  return c;
}

// Inside the image and the depth range, by the camera's perspective in double, from camera_path.h's
// conventions (yaw about +y, 0 looking along -z; pitch up), not from camera.cpp's frame.
bool seen(const FreeCamera& c, const glm::dvec3& p) {
  const double cp = std::cos(c.pitch);
  const glm::dvec3 forward(-std::sin(c.yaw) * cp, std::sin(c.pitch), -std::cos(c.yaw) * cp);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, glm::dvec3(0.0, 1.0, 0.0)));
  const glm::dvec3 up = glm::cross(right, forward);
  const glm::dvec3 q = p - c.eye;
  const double x = glm::dot(right, q), y = glm::dot(up, q), w = glm::dot(forward, q);
  const double ty = std::tan(0.5 * c.fov_y), tx = ty * c.width / c.height;
  return w >= c.near && w <= c.far && std::abs(x) <= w * tx && std::abs(y) <= w * ty;
}

TEST(ViewFrustum, ExcludedBallsHoldNoSeenPoint) {
  Rng rng{7};
  int excluded = 0, kept = 0;
  for (int k = 0; k < 4000; ++k) {
    const FreeCamera c = randomCamera(rng);
    const ViewFrustum frustum = viewFrustum(c);
    const glm::dvec3 centre = c.eye + rng.uniform(0.0, 1.2 * c.far) * randomUnit(rng);
    const double radius = rng.chance(0.1) ? 0.0 : rng.uniform(0.0, 0.3 * c.far);
    if (!frustum.excludesBall(centre, radius)) {
      ++kept;
      continue;
    }
    ++excluded;
    EXPECT_FALSE(seen(c, centre)) << "camera " << k;
    // Points of the ball: its surface, where it comes nearest to a plane, and within.
    for (int s = 0; s < 200; ++s) {
      const double t = s < 100 ? 1.0 : std::cbrt(rng.uniform());
      const glm::dvec3 p = centre + t * radius * randomUnit(rng);
      ASSERT_FALSE(seen(c, p)) << "camera " << k << ": a point of an excluded ball is in view";
    }
    // Towards the eye and along the view axis, where the near plane and the sides come closest.
    const glm::dvec3 to_eye = c.eye - centre;
    if (glm::length(to_eye) > 0.0) {
      EXPECT_FALSE(seen(c, centre + radius * glm::normalize(to_eye)));
    }
  }
  std::printf("%d balls excluded, %d kept\n", excluded, kept);
  EXPECT_GT(excluded, 1000) << "the test excludes many random balls";
  EXPECT_GT(kept, 1000);
}

TEST(ViewFrustum, BallsWhoseCentreIsSeenAreKept) {
  Rng rng{11};
  int checked = 0;
  for (int k = 0; k < 20000; ++k) {
    const FreeCamera c = randomCamera(rng);
    const glm::dvec3 centre = c.eye + rng.uniform(0.0, c.far) * randomUnit(rng);
    if (!seen(c, centre)) continue;
    ++checked;
    EXPECT_FALSE(viewFrustum(c).excludesBall(centre, 0.0)) << "camera " << k;
    EXPECT_FALSE(viewFrustum(c).excludesBall(centre, rng.uniform(0.0, 10.0))) << "camera " << k;
  }
  EXPECT_GT(checked, 500);
}

// A ball just outside one side plane is excluded; moved to touch it, it is kept.
TEST(ViewFrustum, BallBesideASidePlane) {
  FreeCamera c;
  c.width = c.height = 100;
  c.fov_y = 2.0 * std::atan(1.0);  // 90 degrees: the side planes are at 45 degrees
  const CubeFrame f = cameraFrame(c);
  const glm::dvec3 on_plane = c.eye + 10.0 * f.forward + 10.0 * f.right;
  const glm::dvec3 out = glm::normalize(f.right - f.forward);
  EXPECT_TRUE(viewFrustum(c).excludesBall(on_plane + 1.01 * out, 1.0));
  EXPECT_FALSE(viewFrustum(c).excludesBall(on_plane + 0.99 * out, 1.0));
  EXPECT_FALSE(viewFrustum(c).excludesBall(on_plane + 1.0 * out, 1.0)) << "touching is not outside";
}

}  // namespace
}  // namespace walkvis
