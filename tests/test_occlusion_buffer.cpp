// The occlusion buffer (occlusion_buffer.h) against brute force: wherever it calls a polygon
// hidden, the ray through every pixel centre inside the polygon's image meets an occluder before
// the polygon, for random walls, cameras looking any way, occluders reaching behind the eye, and
// targets crossing the near plane; it hides a wall's far side and nothing in front of it or seen
// past its edge; and on random scenes it hides many.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

#include <glm/geometric.hpp>

#include "core/rng.h"
#include "walkthrough/camera.h"
#include "walkthrough/occlusion_buffer.h"

namespace walkvis {
namespace {

using Quad = std::vector<glm::dvec3>;

// A rectangle centred at c, spanned by the unit vectors a and b, half-sides ha and hb.
Quad rect(const glm::dvec3& c, const glm::dvec3& a, const glm::dvec3& b, double ha, double hb) {
  return {c - ha * a - hb * b, c + ha * a - hb * b, c + ha * a + hb * b, c - ha * a + hb * b};
}

glm::dvec3 randomUnit(Rng& rng) {
  for (;;) {
    const glm::dvec3 v(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const double l = glm::length(v);
    if (l > 1e-3 && l <= 1.0) return v / l;
  }
}

Quad randomRect(Rng& rng, const glm::dvec3& around, double spread, double size) {
  const glm::dvec3 a = randomUnit(rng);
  const glm::dvec3 b = glm::normalize(glm::cross(a, randomUnit(rng)));
  return rect(around + spread * randomUnit(rng) * rng.uniform(), a, b, rng.uniform(0.05, 1.0) * size,
              rng.uniform(0.05, 1.0) * size);
}

// Ray eye + t·dir against a convex planar polygon: t > 0 of the hit inside it, if any.
std::optional<double> hit(const glm::dvec3& eye, const glm::dvec3& dir, const Quad& q) {
  const glm::dvec3 n = glm::cross(q[1] - q[0], q[2] - q[0]);
  const double den = glm::dot(n, dir);
  if (den == 0.0) return std::nullopt;
  const double t = glm::dot(n, q[0] - eye) / den;
  if (!(t > 0.0)) return std::nullopt;
  const glm::dvec3 p = eye + t * dir;
  for (size_t k = 0; k < q.size(); ++k)
    if (glm::dot(glm::cross(q[(k + 1) % q.size()] - q[k], p - q[k]), n) < 0.0) return std::nullopt;
  return t;
}

// The ray through pixel centre (i + 0.5, j + 0.5), rows from the bottom (GL's window coordinates),
// from camera_path.h's conventions.
glm::dvec3 pixelDir(const FreeCamera& c, int i, int j) {
  const CubeFrame f = cameraFrame(c);
  const double ty = std::tan(0.5 * c.fov_y), tx = ty * c.width / c.height;
  const double u = (2.0 * (i + 0.5) / c.width - 1.0) * tx, v = (2.0 * (j + 0.5) / c.height - 1.0) * ty;
  return f.forward + u * f.right + v * f.up;
}

// Pixels whose ray meets the target (beyond the near plane) without meeting an occluder first.
int pixelsShowing(const FreeCamera& c, const Quad& target, const std::vector<Quad>& occluders) {
  int showing = 0;
  const CubeFrame f = cameraFrame(c);
  for (int j = 0; j < c.height; ++j)
    for (int i = 0; i < c.width; ++i) {
      const glm::dvec3 d = pixelDir(c, i, j);
      const std::optional<double> t = hit(c.eye, d, target);
      if (!t || *t * glm::dot(d, f.forward) < c.near) continue;
      bool covered = false;
      for (const Quad& o : occluders) {
        const std::optional<double> s = hit(c.eye, d, o);
        if (s && *s < *t && *s * glm::dot(d, f.forward) >= c.near) {  // GL clips what is nearer
          covered = true;
          break;
        }
      }
      showing += !covered;
    }
  return showing;
}

TEST(OcclusionBuffer, AWallHidesItsFarSideOnly) {
  FreeCamera c;  // at the origin, looking along -z
  c.width = 64;
  c.height = 48;
  OcclusionBuffer buffer;
  buffer.reset(c, 4);
  const glm::dvec3 x(1, 0, 0), y(0, 1, 0);
  // A slanted wall 5 ahead (z = -5 - 0.15 x), far wider than the view, reaching behind the eye on
  // the left: only its part beyond the near plane serves.
  const Quad wall = {{-40, -30, 1}, {40, -30, -11}, {40, 30, -11}, {-40, 30, 1}};
  ASSERT_TRUE(buffer.addOccluder(wall));
  EXPECT_EQ(buffer.coveredCells(), static_cast<size_t>(buffer.cellsX() * buffer.cellsY()));
  EXPECT_TRUE(buffer.hides(rect({0, 0, -20}, x, y, 3, 3)));
  EXPECT_TRUE(buffer.hides(rect({0, 0, -20}, x, y, 300, 300))) << "beyond the image's edges";
  EXPECT_FALSE(buffer.hides(rect({0, 0, -2}, x, y, 0.5, 0.5))) << "in front of the wall";
  EXPECT_FALSE(buffer.hides(rect({0, 0, -4.6}, x, y, 3, 3))) << "through the wall on its near side";
  // Crossing the near plane, from behind the eye to beyond the wall: its part in front of the wall
  // shows, and it is kept.
  const Quad strip = {{-1, -0.5, 1}, {1, -0.5, 1}, {1, -0.5, -30}, {-1, -0.5, -30}};
  EXPECT_GT(pixelsShowing(c, strip, {wall}), 0);
  EXPECT_FALSE(buffer.hides(strip));

  // A narrower wall: a target seen past its edge is kept, one wholly behind it hidden.
  buffer.reset(c, 4);
  const Quad narrow = rect({0, 0, -5}, x, y, 2, 2);
  ASSERT_TRUE(buffer.addOccluder(narrow));
  EXPECT_TRUE(buffer.hides(rect({0, 0, -10}, x, y, 1.5, 1.5)));
  EXPECT_FALSE(buffer.hides(rect({0, 0, -10}, x, y, 6, 6)));
  EXPECT_FALSE(buffer.hides(rect({3.5, 0, -10}, x, y, 1, 1))) << "across the wall's edge";
  // A wall seen edge-on or lying wholly behind the eye serves as nothing.
  EXPECT_FALSE(buffer.addOccluder(Quad{{0, -1, -2}, {0, -1, -9}, {0, 1, -9}, {0, 1, -2}}));
  EXPECT_FALSE(buffer.addOccluder(rect({0, 0, 5}, x, y, 2, 2)));
}

// Two walls side by side with a gap: a target behind the join is hidden by the two together,
// which neither alone covers; behind the gap it is kept.
TEST(OcclusionBuffer, NeighbouringWallsHideTogether) {
  FreeCamera c;
  c.width = 80;
  c.height = 60;
  const glm::dvec3 x(1, 0, 0), y(0, 1, 0);
  const Quad left = {{-6, -4, -5}, {0, -4, -5}, {0, 4, -5}, {-6, 4, -5}};
  const Quad right = {{0, -4, -5}, {6, -4, -5}, {6, 4, -5}, {0, 4, -5}};
  const Quad behind = rect({0, 0, -10}, x, y, 2, 2);
  OcclusionBuffer one, both;
  one.reset(c, 4);
  both.reset(c, 4);
  ASSERT_TRUE(one.addOccluder(left));
  ASSERT_TRUE(both.addOccluder(left));
  ASSERT_TRUE(both.addOccluder(right));
  EXPECT_FALSE(one.hides(behind));
  EXPECT_TRUE(both.hides(behind));
  OcclusionBuffer gap;
  gap.reset(c, 4);
  ASSERT_TRUE(gap.addOccluder(Quad{{-6, -4, -5}, {-0.5, -4, -5}, {-0.5, 4, -5}, {-6, 4, -5}}));
  ASSERT_TRUE(gap.addOccluder(Quad{{0.5, -4, -5}, {6, -4, -5}, {6, 4, -5}, {0.5, 4, -5}}));
  EXPECT_FALSE(gap.hides(behind));
  EXPECT_GT(pixelsShowing(c, behind, {Quad{{-6, -4, -5}, {-0.5, -4, -5}, {-0.5, 4, -5}, {-6, 4, -5}},
                                       Quad{{0.5, -4, -5}, {6, -4, -5}, {6, 4, -5}, {0.5, 4, -5}}}),
            0);
}

// A near wall's edge and a far wall beyond it meet in the image: a small target between the two,
// across the near wall's edge, shows in front of the far wall and is kept, whatever cells the
// edge crosses.
TEST(OcclusionBuffer, ATargetBetweenTwoWallsIsKept) {
  FreeCamera c;
  c.width = 80;
  c.height = 60;
  const glm::dvec3 x(1, 0, 0), y(0, 1, 0);
  // Seen from the eye, the near wall (3 ahead) ends where the far wall (10 ahead) begins: along
  // x / z = 0.1.
  const Quad near_wall = {{-6, -4, -3}, {0.3, -4, -3}, {0.3, 4, -3}, {-6, 4, -3}};
  const Quad far_wall = {{1.0, -10, -10}, {20, -10, -10}, {20, 10, -10}, {1.0, 10, -10}};
  const Quad between = rect({0.6, 0.0, -6}, x, y, 0.1, 1.0);
  ASSERT_GT(pixelsShowing(c, between, {near_wall, far_wall}), 0);
  for (int cell = 2; cell <= 8; ++cell) {
    OcclusionBuffer buffer;
    buffer.reset(c, cell);
    ASSERT_TRUE(buffer.addOccluder(near_wall));
    ASSERT_TRUE(buffer.addOccluder(far_wall));
    EXPECT_FALSE(buffer.hides(between)) << "cells of " << cell;
    EXPECT_TRUE(buffer.hides(rect({-1.0, 0.0, -12}, x, y, 0.2, 2.0))) << "cells of " << cell << ": behind the near wall";
  }
}

// Random rooms of rectangles around random cameras (pitched, any field of view and image shape,
// cells of 1 to 9 pixels): no polygon the buffer hides shows at a pixel centre when the rays are
// cast. Many are hidden, so the property is not vacuous.
TEST(OcclusionBuffer, WhatItHidesShowsAtNoPixel) {
  Rng rng{11};
  int hidden = 0, tested = 0;
  for (int scene = 0; scene < 150; ++scene) {
    FreeCamera c;
    c.eye = {rng.uniform(-5, 5), rng.uniform(-2, 2), rng.uniform(-5, 5)};
    c.yaw = rng.uniform(-3.2, 3.2);
    c.pitch = rng.uniform(-1.4, 1.4);
    c.fov_y = rng.uniform(0.5, 2.0);
    c.width = 24 + static_cast<int>(rng.below(60));
    c.height = 18 + static_cast<int>(rng.below(50));
    c.near = rng.uniform(0.01, 0.5);
    const CubeFrame f = cameraFrame(c);
    OcclusionBuffer buffer;
    buffer.reset(c, 1 + static_cast<int>(rng.below(9)));
    std::vector<Quad> occluders;
    const int count = 1 + static_cast<int>(rng.below(8));
    for (int k = 0; k < count; ++k) {
      // Near the eye and ahead of it, large: some reach behind the eye.
      const Quad o = randomRect(rng, c.eye + rng.uniform(1.0, 6.0) * f.forward, 3.0, 6.0);
      if (buffer.addOccluder(o)) occluders.push_back(o);
    }
    for (int t = 0; t < 30; ++t) {
      const Quad target = randomRect(rng, c.eye + rng.uniform(0.0, 20.0) * f.forward, 8.0,
                                     rng.chance(0.2) ? 12.0 : 2.0);
      ++tested;
      if (!buffer.hides(target)) continue;
      ++hidden;
      ASSERT_EQ(pixelsShowing(c, target, occluders), 0)
          << "scene " << scene << " target " << t << ": hidden, yet its rays reach it";
    }
  }
  std::printf("%d of %d targets hidden\n", hidden, tested);
  EXPECT_GT(hidden, tested / 10);
}

}  // namespace
}  // namespace walkvis
