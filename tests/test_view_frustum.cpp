// The view frustum's ball and polygon tests (camera.h) against brute force: a ball it excludes holds
// no point that the camera's perspective puts inside its image and depth range, whatever the
// camera, nor does a polygon it excludes; a ball whose centre is inside is never excluded; and on
// random balls and polygons it excludes many.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <glm/geometric.hpp>

#include "core/geometry.h"
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

// Random triangles around random cameras, with their balls: whatever the ball test or the corners
// leave out (cutPlanes, then cornersOutside) has no point in view, and the corners leave out many
// that the ball test keeps.
TEST(ViewFrustum, ExcludedPolygonsHoldNoSeenPoint) {
  Rng rng{13};
  int by_ball = 0, by_corners = 0, kept = 0;
  for (int k = 0; k < 6000; ++k) {
    const FreeCamera c = randomCamera(rng);
    const ViewFrustum frustum = viewFrustum(c);
    const glm::dvec3 around = c.eye + rng.uniform(0.0, 1.2 * c.far) * randomUnit(rng);
    const double size = rng.uniform(0.0, 0.5 * c.far);
    std::vector<glm::dvec3> corners;
    for (int v = 0; v < 3; ++v) corners.push_back(around + size * rng.uniform() * randomUnit(rng));
    Polygon polygon;
    polygon.vertex_count = 3;
    const Ball ball = polygonBall(corners, polygon);
    const unsigned cut = frustum.cutPlanes(ball.centre, ball.radius);
    ASSERT_EQ(cut == ViewFrustum::kBallOutside, frustum.excludesBall(ball.centre, ball.radius)) << "camera " << k;
    if (cut == ViewFrustum::kBallOutside) {
      ++by_ball;
    } else if (cut != 0 && frustum.cornersOutside(cut, corners)) {
      ++by_corners;
    } else {
      ++kept;
      continue;
    }
    for (int s = 0; s < 300; ++s) {
      // Barycentric points, a third of them on the edges.
      double a = rng.uniform(), b = rng.uniform();
      if (a + b > 1.0) a = 1.0 - a, b = 1.0 - b;
      if (s % 3 == 0) b = 1.0 - a;
      const glm::dvec3 p = corners[0] + a * (corners[1] - corners[0]) + b * (corners[2] - corners[0]);
      ASSERT_FALSE(seen(c, p)) << "camera " << k << ": a point of an excluded triangle is in view";
    }
  }
  std::printf("%d triangles excluded by their ball, %d by their corners, %d kept\n", by_ball, by_corners, kept);
  EXPECT_GT(by_corners, 300) << "the corners exclude many that the ball keeps";
  EXPECT_GT(kept, 1000);
}

// A long wall beside the view, its ball reaching into it: excluded by its corners; turned to
// reach into the view, kept.
TEST(ViewFrustum, LongWallBesideTheView) {
  FreeCamera c;
  c.width = c.height = 100;
  c.fov_y = 2.0 * std::atan(1.0);  // 90 degrees: the side planes are at 45 degrees
  const CubeFrame f = cameraFrame(c);
  auto wall = [&](const glm::dvec3& a, const glm::dvec3& b) {
    return std::vector<glm::dvec3>{a - f.up, b - f.up, b + f.up, a + f.up};
  };
  // Along the right side plane, just outside it, from 1 to 40 ahead.
  const glm::dvec3 out = 0.2 * glm::normalize(f.right - f.forward);
  const auto beside = wall(c.eye + 1.0 * (f.forward + f.right) + out, c.eye + 40.0 * (f.forward + f.right) + out);
  Polygon quad;
  quad.vertex_count = 4;
  const Ball ball = polygonBall(beside, quad);
  const unsigned cut = viewFrustum(c).cutPlanes(ball.centre, ball.radius);
  ASSERT_NE(cut, ViewFrustum::kBallOutside) << "its ball reaches into the view";
  EXPECT_TRUE(viewFrustum(c).cornersOutside(cut, beside));
  const auto across = wall(c.eye + 1.0 * (f.forward + f.right) + out, c.eye + 40.0 * f.forward);
  const Ball ball2 = polygonBall(across, quad);
  EXPECT_FALSE(viewFrustum(c).cornersOutside(viewFrustum(c).cutPlanes(ball2.centre, ball2.radius), across));
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
