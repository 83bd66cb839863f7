// hullsSeparated (pfd_hfd/hull_distance.h): a certificate only where the hulls are apart, over
// random point sets with known distances (fixed seeds).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include <glm/geometric.hpp>

#include "pfd_hfd/hull_distance.h"

namespace walkvis {
namespace {

std::vector<glm::dvec3> ball(std::mt19937_64& rng, const glm::dvec3& c, double r, int n) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> pts;
  for (int k = 0; k < n; ++k) {
    glm::dvec3 d{g(rng), g(rng), g(rng)};
    pts.push_back(c + glm::normalize(d) * (r * std::cbrt(u(rng))));
  }
  return pts;
}

// Points in two balls whose gap exceeds twice the margin are separated; sets sharing a point, or
// one holding the other's centre region, are not; a segment through a box is not.
TEST(HullDistance, SeparatedExactlyWhenApart) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int apart = 0, meeting = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const glm::dvec3 ca{u(rng), u(rng), u(rng)};
    const glm::dvec3 dir = glm::normalize(glm::dvec3{u(rng), u(rng), u(rng)} + glm::dvec3(1e-9));
    const double ra = 0.1 + std::abs(u(rng)), rb = 0.1 + std::abs(u(rng));
    const double gap = std::abs(u(rng));
    const double margin = 0.01;
    const int na = 1 + static_cast<int>(rng() % 20), nb = 1 + static_cast<int>(rng() % 20);
    const std::vector<glm::dvec3> a = ball(rng, ca, ra, na);
    std::vector<glm::dvec3> b = ball(rng, ca + dir * (ra + rb + gap), rb, nb);
    if (gap > 2.0 * margin + 1e-9) {
      EXPECT_TRUE(hullsSeparated(a, b, margin)) << "trial " << trial;
      EXPECT_TRUE(hullsSeparated(b, a, margin)) << "trial " << trial;
      ++apart;
    }
    b.push_back(a[rng() % a.size()]);  // now they meet
    EXPECT_FALSE(hullsSeparated(a, b, margin)) << "trial " << trial;
    EXPECT_FALSE(hullsSeparated(a, b, 0.0)) << "trial " << trial;
    ++meeting;
  }
  EXPECT_GT(apart, 1000);
  EXPECT_EQ(meeting, 2000);

  // A segment piercing a cube through two faces (no vertex of either inside the other's hull).
  std::vector<glm::dvec3> cube;
  for (int k = 0; k < 8; ++k) cube.push_back({k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0, k & 4 ? 1.0 : -1.0});
  const std::vector<glm::dvec3> through{{-3, 0.2, 0.1}, {3, -0.1, 0.3}};
  const std::vector<glm::dvec3> beside{{-3, 1.5, 0.1}, {3, 1.2, 0.3}};
  EXPECT_FALSE(hullsSeparated(cube, through, 1e-9));
  EXPECT_TRUE(hullsSeparated(cube, beside, 0.05));
  EXPECT_FALSE(hullsSeparated(cube, beside, 0.2));  // the gap is about 0.2996: within twice this margin
}

}  // namespace
}  // namespace walkvis
