// convexPartition: the pieces are convex, counter-clockwise, disjoint and cover exactly the
// even-odd interior of the rings.
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "scenes/scene.h"

namespace walkvis {
namespace {

using Ring = std::vector<glm::dvec2>;
using Rings = std::vector<Ring>;

double signedArea(const Ring& r) {
  // Relative to the first vertex: far from the origin the plain shoelace cancels small areas away.
  double a = 0.0;
  for (size_t i = 1; i + 1 < r.size(); ++i) {
    const glm::dvec2 p = r[i] - r[0], q = r[i + 1] - r[0];
    a += p.x * q.y - q.x * p.y;
  }
  return 0.5 * a;
}

double totalArea(const Rings& pieces) {
  double a = 0.0;
  for (const auto& p : pieces) a += signedArea(p);
  return a;
}

// Even-odd point in rings (crossing number).
bool insideRings(const Rings& rings, glm::dvec2 p) {
  bool in = false;
  for (const auto& r : rings) {
    for (size_t i = 0, j = r.size() - 1; i < r.size(); j = i++) {
      const auto& a = r[i];
      const auto& b = r[j];
      if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
    }
  }
  return in;
}

// Strictly inside a convex CCW piece, `margin` away from every edge line.
bool insideConvex(const Ring& piece, glm::dvec2 p, double margin) {
  for (size_t i = 0; i < piece.size(); ++i) {
    glm::dvec2 a = piece[i], b = piece[(i + 1) % piece.size()];
    glm::dvec2 e = b - a;
    double cross = e.x * (p.y - a.y) - e.y * (p.x - a.x);
    if (cross <= margin * std::hypot(e.x, e.y)) return false;
  }
  return true;
}

// Distance from p to the nearest ring edge.
double distanceToRings(const Rings& rings, glm::dvec2 p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& r : rings) {
    for (size_t i = 0; i < r.size(); ++i) {
      glm::dvec2 a = r[i], b = r[(i + 1) % r.size()];
      glm::dvec2 ab = b - a;
      double len2 = ab.x * ab.x + ab.y * ab.y;
      double t = len2 > 0 ? std::clamp(((p.x - a.x) * ab.x + (p.y - a.y) * ab.y) / len2, 0.0, 1.0) : 0.0;
      glm::dvec2 c = a + t * ab;
      best = std::min(best, std::hypot(p.x - c.x, p.y - c.y));
    }
  }
  return best;
}

// Every piece: >= 3 vertices, no repeated vertex, strictly convex and counter-clockwise.
void expectConvexCcw(const Rings& pieces) {
  for (const auto& piece : pieces) {
    ASSERT_GE(piece.size(), 3u);
    double scale = 0.0;
    for (const auto& p : piece) scale = std::max({scale, std::abs(p.x), std::abs(p.y)});
    EXPECT_GT(signedArea(piece), 0.0);
    for (size_t i = 0; i < piece.size(); ++i) {
      glm::dvec2 a = piece[i], b = piece[(i + 1) % piece.size()], c = piece[(i + 2) % piece.size()];
      double cross = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
      // Cross products of double coordinates of size `scale` are accurate to ~1e-16 scale^2.
      EXPECT_GT(cross, -1e-12 * scale * scale) << "reflex vertex " << i + 1;
    }
  }
}

// Points well away from ring edges are inside exactly as many pieces as the even-odd rule says.
void expectCoverage(const Rings& rings, const Rings& pieces, uint32_t seed, glm::dvec2 lo, glm::dvec2 hi,
                    int samples) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(lo.x, hi.x), uy(lo.y, hi.y);
  double margin = 1e-6 * std::max(hi.x - lo.x, hi.y - lo.y);
  int checked = 0;
  for (int s = 0; s < samples; ++s) {
    glm::dvec2 p(ux(rng), uy(rng));
    if (distanceToRings(rings, p) < 4 * margin) continue;
    int count = 0;
    bool on_boundary = false;
    for (const auto& piece : pieces) {
      if (insideConvex(piece, p, margin)) ++count;
      else if (insideConvex(piece, p, -margin)) on_boundary = true;  // near an inner diagonal
    }
    if (on_boundary && count == 0) continue;
    ++checked;
    ASSERT_EQ(count, insideRings(rings, p) ? 1 : 0) << "at (" << p.x << ", " << p.y << ")";
  }
  EXPECT_GT(checked, samples / 2);
}

Ring square(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }
Ring reversed(Ring r) {
  std::reverse(r.begin(), r.end());
  return r;
}

TEST(Partition, ConvexPolygonIsOnePiece) {
  Ring r;
  for (int i = 0; i < 20; ++i) r.push_back({std::cos(i * 2 * M_PI / 20), std::sin(i * 2 * M_PI / 20)});
  auto pieces = convexPartition({reversed(r)});
  ASSERT_EQ(pieces.size(), 1u);
  EXPECT_EQ(pieces[0].size(), 20u);
  EXPECT_NEAR(totalArea(pieces), std::abs(signedArea(r)), 1e-12);
  expectConvexCcw(pieces);
}

TEST(Partition, CollinearVerticesAreDropped) {
  Ring r;
  for (int i = 0; i < 10; ++i) r.push_back({double(i), 0});
  for (int i = 0; i < 10; ++i) r.push_back({10, double(i)});
  for (int i = 10; i > 0; --i) r.push_back({double(i), 10});
  for (int i = 10; i > 0; --i) r.push_back({0, double(i)});
  auto pieces = convexPartition({r});
  ASSERT_EQ(pieces.size(), 1u);
  EXPECT_EQ(pieces[0].size(), 4u);
  EXPECT_DOUBLE_EQ(totalArea(pieces), 100.0);
}

TEST(Partition, SquareWithHole) {
  for (bool flip_outer : {false, true}) {
    for (bool flip_hole : {false, true}) {
      Ring outer = square(0, 0, 10, 10), hole = square(4, 4, 6, 6);
      if (flip_outer) outer = reversed(outer);
      if (flip_hole) hole = reversed(hole);
      Rings rings{hole, outer};
      auto pieces = convexPartition(rings);
      expectConvexCcw(pieces);
      EXPECT_DOUBLE_EQ(totalArea(pieces), 96.0);
      EXPECT_LE(pieces.size(), 8u);  // a hole in a square needs 4; Hertel–Mehlhorn is within 4x
      for (const auto& p : pieces) EXPECT_FALSE(insideConvex(p, {5, 5}, 0.0));
      expectCoverage(rings, pieces, 1, {-1, -1}, {11, 11}, 500);
    }
  }
}

TEST(Partition, TwoIslandsAndIslandInHole) {
  Rings rings{square(0, 0, 10, 10), square(2, 2, 8, 8), square(4, 4, 6, 6), reversed(square(20, 0, 23, 1))};
  auto pieces = convexPartition(rings);
  expectConvexCcw(pieces);
  EXPECT_DOUBLE_EQ(totalArea(pieces), 100.0 - 36.0 + 4.0 + 3.0);
  expectCoverage(rings, pieces, 2, {-1, -1}, {24, 11}, 1000);
}

TEST(Partition, TouchingRings) {
  // Two squares meeting at one vertex.
  auto corner = convexPartition({square(0, 0, 1, 1), square(1, 1, 2, 2)});
  expectConvexCcw(corner);
  EXPECT_DOUBLE_EQ(totalArea(corner), 2.0);
  // Two squares sharing an edge (covered twice): their union, one rectangle.
  auto edge = convexPartition({square(0, 0, 1, 1), reversed(square(1, 0, 2, 1))});
  expectConvexCcw(edge);
  EXPECT_DOUBLE_EQ(totalArea(edge), 2.0);
  EXPECT_EQ(edge.size(), 1u);
  // A hole touching the outer boundary at a vertex, and a ring touching itself (figure eight).
  Rings notch{square(0, 0, 4, 4), {{0, 0}, {2, 1}, {1, 2}}};
  auto n = convexPartition(notch);
  expectConvexCcw(n);
  EXPECT_DOUBLE_EQ(totalArea(n), 16.0 - 1.5);
  expectCoverage(notch, n, 3, {-1, -1}, {5, 5}, 500);
  Rings eight{{{0, 0}, {1, 1}, {2, 0}, {2, 2}, {1, 1}, {0, 2}}};
  auto e = convexPartition(eight);
  expectConvexCcw(e);
  EXPECT_DOUBLE_EQ(totalArea(e), 2.0);
  // The same ring twice cancels out.
  EXPECT_TRUE(convexPartition({square(0, 0, 1, 1), square(0, 0, 1, 1)}).empty());
}

TEST(Partition, DegenerateInputNeverCrashes) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(convexPartition({}).empty());
  EXPECT_TRUE(convexPartition({{}}).empty());
  EXPECT_TRUE(convexPartition({{{1, 1}}}).empty());
  EXPECT_TRUE(convexPartition({{{0, 0}, {1, 1}, {2, 2}, {3, 3}}}).empty());
  EXPECT_TRUE(convexPartition({{{0, 0}, {1, 0}, {0, 0}, {1, 0}}}).empty());
  auto with_nan = convexPartition({{{0, 0}, {nan, 5}, {1, 0}, {1, inf}, {1, 1}, {0, 1}}});
  expectConvexCcw(with_nan);
  EXPECT_DOUBLE_EQ(totalArea(with_nan), 1.0);
  // A sliver of area 1e-9 of the scene and coordinates near 1e6 with features of 1e-3.
  auto sliver = convexPartition({{{0, 0}, {1e3, 0}, {1e3, 1e-3}}});
  expectConvexCcw(sliver);
  EXPECT_NEAR(totalArea(sliver), 0.5, 1e-9);
  auto far = convexPartition({square(1e6, 1e6, 1e6 + 1e-3, 1e6 + 2e-3)});
  expectConvexCcw(far);
  EXPECT_NEAR(totalArea(far), 2e-6, 1e-12);
}

// A star-shaped ring around c with radii in [r0, r1].
Ring star(std::mt19937& rng, glm::dvec2 c, double r0, double r1, int n) {
  std::uniform_real_distribution<double> ur(r0, r1);
  Ring r;
  for (int i = 0; i < n; ++i) {
    double t = i * 2 * M_PI / n;
    double rad = ur(rng);
    r.push_back(c + rad * glm::dvec2(std::cos(t), std::sin(t)));
  }
  return r;
}

TEST(Partition, RandomStarsWithHolesMatchShoelace) {
  for (uint32_t seed = 1; seed <= 40; ++seed) {
    std::mt19937 rng(seed);
    Rings rings;
    double expected = 0.0;
    int islands = 1 + seed % 3;
    for (int k = 0; k < islands; ++k) {
      glm::dvec2 c(30.0 * k, 5.0 * (seed % 2));
      Ring outer = star(rng, c, 6, 12, 5 + int(rng() % 40));
      Ring hole = star(rng, c, 1, 5, 3 + int(rng() % 20));
      expected += std::abs(signedArea(outer)) - std::abs(signedArea(hole));
      if (rng() % 2) outer = reversed(outer);
      if (rng() % 2) hole = reversed(hole);
      rings.push_back(outer);
      rings.push_back(hole);
    }
    auto pieces = convexPartition(rings);
    SCOPED_TRACE(seed);
    expectConvexCcw(pieces);
    EXPECT_NEAR(totalArea(pieces), expected, 1e-9 * expected);
    expectCoverage(rings, pieces, seed, {-13, -13}, {30.0 * islands, 18}, 300);
  }
}

TEST(Partition, RandomSelfIntersectingRingsFollowEvenOdd) {
  for (uint32_t seed = 1; seed <= 30; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 10);
    Rings rings;
    int nrings = 1 + seed % 3;
    for (int k = 0; k < nrings; ++k) {
      Ring r;
      int n = 3 + int(rng() % 12);
      // Half the seeds on an integer grid, so many edges overlap and pass through vertices.
      for (int i = 0; i < n; ++i) {
        double x = u(rng), y = u(rng);
        if (seed % 2) x = std::floor(x), y = std::floor(y);
        r.push_back({x, y});
      }
      rings.push_back(r);
    }
    auto pieces = convexPartition(rings);
    SCOPED_TRACE(seed);
    expectConvexCcw(pieces);
    expectCoverage(rings, pieces, seed, {-0.5, -0.5}, {10.5, 10.5}, 600);
  }
}

}  // namespace
}  // namespace walkvis
