// The PFD builder's optimal test order (pfd_hfd/pfd_search.h): the branch and bound over sets of
// classes finds the same least cost as a brute force over every order of the tests, by geometry
// alone; the tree its memo gives costs what it says; its lower bounds hold.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

#include "pfd_hfd/pfd_search.h"

namespace walkvis {
namespace {

DRegion polygon(std::initializer_list<glm::dvec2> pts) {
  DRegion r;
  r.pts.assign(pts);
  r.start.push_back(static_cast<uint32_t>(r.pts.size()));
  return r;
}

void addPiece(DRegion& r, std::initializer_list<glm::dvec2> pts) {
  r.pts.insert(r.pts.end(), pts);
  r.start.push_back(static_cast<uint32_t>(r.pts.size()));
}

// With the builder's sliver reach (1e-9 of the extent, here ~10): a clipped corner rounds to a
// hair beside the line, which must not count as a crossing again.
SearchLine lineThrough(glm::dvec2 p, glm::dvec2 q) {
  const glm::dvec2 d = q - p;
  return {d.y, -d.x, -(d.y * p.x - d.x * p.y), 1e-8 * std::hypot(d.x, d.y)};
}

// Σ over leaves of area × tests of the best tree, trying every untested line first at every
// region (no memo, no bound): the definition the search must meet.
double bruteForce(const DRegion& r, std::span<const SearchLine> lines, uint32_t tested = 0) {
  double best = INFINITY;
  for (uint32_t i = 0; i < lines.size(); ++i) {
    if ((tested >> i & 1) || !crossesD(r, lines[i])) continue;
    DRegion front, back;
    clipD(r, lines[i], front, back);
    best = std::min(best, bruteForce(front, lines, tested | 1u << i) + bruteForce(back, lines, tested | 1u << i));
  }
  return std::isinf(best) ? 0.0 : areaD(r) + best;
}

// The cost of testing the lines in their given order, each where it crosses: what the search must
// beat where the order matters.
double inOrder(const DRegion& r, std::span<const SearchLine> lines, uint32_t from = 0) {
  for (uint32_t i = from; i < lines.size(); ++i) {
    if (!crossesD(r, lines[i])) continue;
    DRegion front, back;
    clipD(r, lines[i], front, back);
    return areaD(r) + inOrder(front, lines, i + 1) + inOrder(back, lines, i + 1);
  }
  return 0.0;
}

// The cost of the tree the memo describes, walked by geometry from the whole region.
double planCost(const CellSearch& search, const DRegion& r, std::span<const SearchLine> lines,
                std::vector<std::pair<uint32_t, int8_t>>& path, int& unplanned) {
  const std::optional<uint32_t> line = search.bestLine(path);
  if (!line) {
    for (const SearchLine& l : lines) unplanned += crossesD(r, l);  // a leaf: nothing may cross
    return 0.0;
  }
  if (!crossesD(r, lines[*line])) {
    ++unplanned;
    return 0.0;
  }
  DRegion front, back;
  clipD(r, lines[*line], front, back);
  path.push_back({*line, 1});
  double cost = planCost(search, front, lines, path, unplanned);
  path.back().second = -1;
  cost += planCost(search, back, lines, path, unplanned);
  path.pop_back();
  return areaD(r) + cost;
}

TEST(PfdSearch, RandomArrangementsMatchBruteForce) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> coord(0.0, 10.0);
  int order_matters = 0;
  for (int trial = 0; trial < 60; ++trial) {
    DRegion r = polygon({{0, 0}, {10, 0}, {10, 10}, {0, 10}});
    if (trial % 3 == 0) addPiece(r, {{12, 2}, {16, 2}, {14, 7}});  // lines may separate the pieces
    const int n = 2 + trial % 5;
    std::vector<SearchLine> lines;
    for (int i = 0; i < n; ++i) {
      glm::dvec2 p{coord(rng), coord(rng)}, q{coord(rng), coord(rng)};
      if (i % 3 == 2) q = {p.x, p.y + 1.0};  // axis-aligned lines, as walls often are
      lines.push_back(lineThrough(p, q));
    }
    CellSearch search;
    ASSERT_TRUE(search.init(r, lines, 4096));
    const std::optional<double> cost = search.solve(1'000'000, 64u << 20);
    ASSERT_TRUE(cost.has_value());
    const double brute = bruteForce(r, lines);
    EXPECT_NEAR(*cost, brute, 1e-9 * brute) << "trial " << trial;
    EXPECT_NEAR(search.area(), areaD(r), 1e-9 * areaD(r));
    // The tree the memo holds, walked by geometry, is the one whose cost the search returned.
    std::vector<std::pair<uint32_t, int8_t>> path;
    int unplanned = 0;
    EXPECT_NEAR(planCost(search, r, lines, path, unplanned), *cost, 1e-9 * *cost) << "trial " << trial;
    EXPECT_EQ(unplanned, 0) << "trial " << trial;
    order_matters += *cost < inOrder(r, lines) * (1.0 - 1e-9);
  }
  // Arrangements where every order costs the same would check nothing.
  std::printf("%d of 60 arrangements: the best order beats the given one\n", order_matters);
  EXPECT_GE(order_matters, 20);
}

// Two parallel lines cutting a square into thirds: either order costs 1 + 2/3 tests per eye (one
// test for all, a second for the two thirds on the far side of the first).
TEST(PfdSearch, ThirdsCostWhatEveryOrderCosts) {
  const DRegion r = polygon({{0, 0}, {3, 0}, {3, 3}, {0, 3}});
  const std::vector<SearchLine> lines = {lineThrough({1, 0}, {1, 1}), lineThrough({2, 0}, {2, 1})};
  CellSearch search;
  ASSERT_TRUE(search.init(r, lines, 16));
  EXPECT_EQ(search.classes(), 3u);
  const std::optional<double> cost = search.solve(1000, 1u << 20);
  ASSERT_TRUE(cost.has_value());
  EXPECT_NEAR(*cost / search.area(), 1.0 + 2.0 / 3.0, 1e-12);
}

// Seventy parallel lines (more than one 64-bit word of lines) cut a rectangle into 71 equal strips:
// the best tree is a balanced one, whose cost is Huffman's for 71 equal weights: 71·6 + 2·(71 − 64)
// tests over the strips.
TEST(PfdSearch, EqualStripsCostHuffman) {
  const DRegion r = polygon({{0, 0}, {71, 0}, {71, 1}, {0, 1}});
  std::vector<SearchLine> lines;
  for (int i = 70; i >= 1; --i) lines.push_back(lineThrough({i, 0}, {i, 1}));
  CellSearch search;
  ASSERT_TRUE(search.init(r, lines, 4096));
  EXPECT_EQ(search.classes(), 71u);
  const std::optional<double> cost = search.solve(1'000'000, 64u << 20);
  ASSERT_TRUE(cost.has_value());
  EXPECT_NEAR(*cost, 71.0 * 6 + 2.0 * (71 - 64), 1e-9);
}

// A line reaching less than its sliver reach into one side is no test: the search must not split
// there (the builder trims the sliver instead).
TEST(PfdSearch, SliverIsNotACrossing) {
  const DRegion r = polygon({{0, 0}, {4, 0}, {4, 4}, {0, 4}});
  const SearchLine l = lineThrough({1e-12, 0}, {1e-12, 1});
  EXPECT_FALSE(crossesD(r, l));
  CellSearch search;
  const std::vector<SearchLine> lines = {l, lineThrough({2, 0}, {2, 1})};
  ASSERT_TRUE(search.init(r, lines, 16));
  EXPECT_EQ(search.classes(), 2u);
  const std::optional<double> cost = search.solve(1000, 1u << 20);
  ASSERT_TRUE(cost.has_value());
  EXPECT_NEAR(*cost, 16.0, 1e-12);
}

// Out of budget or memory: no answer, never a wrong one.
TEST(PfdSearch, BudgetGivesNoAnswer) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> coord(0.0, 10.0);
  const DRegion r = polygon({{0, 0}, {10, 0}, {10, 10}, {0, 10}});
  std::vector<SearchLine> lines;
  for (int i = 0; i < 14; ++i) lines.push_back(lineThrough({coord(rng), coord(rng)}, {coord(rng), coord(rng)}));
  CellSearch search;
  ASSERT_TRUE(search.init(r, lines, 4096));
  EXPECT_FALSE(search.solve(10, 64u << 20).has_value());
  EXPECT_FALSE(search.solve(1'000'000'000, 4096).has_value());
  EXPECT_FALSE(search.bestLine({}).has_value());
  EXPECT_FALSE(search.init(r, lines, 8));  // more classes than allowed
}

}  // namespace
}  // namespace walkvis
