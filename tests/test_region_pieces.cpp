// nearestInPieces with its grid (pfd_hfd/region_pieces.h) against a scan of every piece, over random
// convex pieces, query points inside and outside their bounds, with and without a half-plane
// (fixed seeds). The grid may only change which of two equally near pieces answers, never the
// distance.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include "pfd_hfd/region_pieces.h"

namespace walkvis {
namespace {

// A random convex polygon (a regular polygon of 3-8 corners, stretched and turned) around c.
Convex2 randomPiece(std::mt19937_64& rng, const glm::dvec2& c, double size) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = 3 + static_cast<int>(rng() % 6);
  const double turn = 6.283185307179586 * u(rng), sx = size * (0.2 + u(rng)), sy = size * (0.2 + u(rng));
  Convex2 p;
  for (int k = 0; k < n; ++k) {
    const double a = 6.283185307179586 * k / n;
    const glm::dvec2 q{sx * std::cos(a), sy * std::sin(a)};
    p.v.push_back(c + glm::dvec2(q.x * std::cos(turn) - q.y * std::sin(turn), q.x * std::sin(turn) + q.y * std::cos(turn)));
  }
  for (const auto& v : p.v) p.centroid += v;
  p.centroid /= static_cast<double>(n);
  for (const auto& v : p.v) p.radius = std::max(p.radius, glm::length(v - p.centroid));
  return p;
}

// The nearest squared distance by a scan of every piece (nullopt when the half-plane keeps none).
std::optional<double> scanNearest(const std::vector<Convex2>& pieces, const glm::dvec2& want, const glm::dvec2* g,
                                  double c0) {
  std::optional<double> best;
  std::vector<glm::dvec2> clip;
  for (const Convex2& p : pieces) {
    if (g && !clipHalfPlane(p.v, *g, c0, clip)) continue;
    double d2;
    closestInConvex(g ? clip : p.v, want, d2);
    if (!best || d2 < *best) best = d2;
  }
  return best;
}

TEST(RegionPieces, GridNearestEqualsScan) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int gridded = 0, empty = 0, queries = 0;
  for (const int count : {5, 40, 300, 2000}) {
    for (int layout = 0; layout < 4; ++layout) {
      // A long strip or a square, of pieces small against it (a level's rooms) or not.
      const double w = 100.0, h = layout % 2 ? 100.0 : 7.0, size = layout < 2 ? 2.0 : 15.0;
      std::vector<Convex2> pieces;
      for (int k = 0; k < count; ++k) pieces.push_back(randomPiece(rng, {w * u(rng), h * u(rng)}, size));
      PieceGrid grid;
      grid.build(pieces);
      gridded += grid.nx > 0;
      EXPECT_EQ(grid.nx > 0, pieces.size() >= PieceGrid::kMinPieces);
      std::vector<glm::dvec2> clip;
      for (int q = 0; q < 300; ++q) {
        // Queries inside the bounds and up to half their size beyond.
        const glm::dvec2 want{w * (2.0 * u(rng) - 0.5), h * (2.0 * u(rng) - 0.5)};
        const bool half = q % 3 != 0;
        const double ang = 6.283185307179586 * u(rng);
        const glm::dvec2 g{std::cos(ang), std::sin(ang)};
        const double c0 = -glm::dot(g, glm::dvec2(w * u(rng), h * u(rng)));
        const std::optional<glm::dvec2> got = nearestInPieces(pieces, want, 0.0, half ? &g : nullptr, c0, clip, grid);
        const std::optional<double> want_d2 = scanNearest(pieces, want, half ? &g : nullptr, c0);
        ASSERT_EQ(got.has_value(), want_d2.has_value()) << count << " pieces, query " << q;
        ++queries;
        if (!got) {
          ++empty;
          continue;
        }
        const double d2 = glm::dot(*got - want, *got - want);
        EXPECT_NEAR(d2, *want_d2, 1e-9 * (1.0 + *want_d2)) << count << " pieces, layout " << layout << ", query " << q;
        if (half) {
          EXPECT_GE(glm::dot(g, *got) + c0, -1e-9 * (1.0 + std::abs(c0)));
        }
      }
    }
  }
  EXPECT_EQ(gridded, 12);  // 40, 300 and 2000 pieces, four layouts each
  EXPECT_GT(empty, 0);     // half-planes that keep nothing were asked too
  EXPECT_LT(empty, queries / 2);
}

// A grid built over other pieces first, then over these: nothing of the first stays.
TEST(RegionPieces, GridRebuildForgetsThePreviousPieces) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Convex2> a, b;
  for (int k = 0; k < 200; ++k) a.push_back(randomPiece(rng, {50.0 * u(rng), 50.0 * u(rng)}, 1.0));
  for (int k = 0; k < 60; ++k) b.push_back(randomPiece(rng, {500.0 + 20.0 * u(rng), 20.0 * u(rng)}, 1.0));
  PieceGrid grid;
  grid.build(a);
  std::vector<glm::dvec2> clip;
  ASSERT_TRUE(nearestInPieces(a, {25.0, 25.0}, 0.0, nullptr, 0.0, clip, grid));
  grid.build(b);
  for (int q = 0; q < 100; ++q) {
    const glm::dvec2 want{600.0 * u(rng), 50.0 * u(rng)};
    const std::optional<glm::dvec2> got = nearestInPieces(b, want, 0.0, nullptr, 0.0, clip, grid);
    ASSERT_TRUE(got);
    EXPECT_NEAR(glm::dot(*got - want, *got - want), *scanNearest(b, want, nullptr, 0.0), 1e-9);
  }
}

}  // namespace
}  // namespace walkvis
