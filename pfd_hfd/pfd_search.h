// Internal to pfd_hfd: the double-precision model in which the PFD builder chooses which line to
// test next (pfd_build_cgal.cpp). It only picks among lines that cross a region exactly; every
// classification the tree relies on stays exact, so the model's rounding can cost tests, never
// correctness.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>

namespace walkvis {

// One bit per line of a search (at most kSearchMaxLines).
__extension__ typedef unsigned __int128 LineBits;
constexpr uint32_t kSearchMaxLines = 128;

// The line a·x + b·z + c = 0 of the height plane; positive values are its front.
struct SearchLine {
  double a = 0.0, b = 0.0, c = 0.0;
  double reach = 0.0;  // a sliver narrower than this (in a·x + b·z + c units) is not a crossing
};

// Convex pieces stored flat (piece k: pts[start[k], start[k + 1]), counter-clockwise or not), so
// that clearing one keeps its memory: a search clips thousands of times and allocates nothing once
// warm.
struct DRegion {
  std::vector<glm::dvec2> pts;
  std::vector<uint32_t> start{0};
  size_t pieces() const { return start.size() - 1; }
  void clear() {
    pts.clear();
    start.assign(1, 0);
  }
};

inline double lineValue(const SearchLine& l, const glm::dvec2& p) { return l.a * p.x + l.b * p.y + l.c; }

// Whether l leaves a vertex of r strictly on each side, and reaches at least l.reach into both (a
// line that reaches less far into one side is not tested: the builder trims that sliver off).
bool crossesD(const DRegion& r, const SearchLine& l);

// The side r lies on where l does not cross it (crossesD false): +1 front, -1 back; where a sliver
// is all l cuts, the side of the rest.
int sideD(const DRegion& r, const SearchLine& l);

double areaD(const DRegion& r);

// Splits r's convex pieces by l (Sutherland–Hodgman on each side); a part of no corner strictly on
// its side, or of fewer than 3 corners, is dropped.
void clipD(const DRegion& r, const SearchLine& l, DRegion& front, DRegion& back);

// The optimal order of tests over an arrangement of lines: the tree testing these lines whose
// leaves (the classes: points on the same side of every line) are reached in the least
// area-weighted mean tests. The state of a search is the set of classes a region holds, not the
// tests that led there, so every order of the same tests is one state: the dense memo over test
// codes (3^lines) this replaced stopped at 12 lines, this one stops at its budget.
// Depth-first branch and bound over the memo: at each region the lines are tried cheapest lower
// bound first, and only while that bound is under the best found. A region's lower bound
// (lowerBoundOf) joins Shannon's (its classes' entropy × its area), the cell bound (a class's
// depth is at least the number of lines still crossing the region that bound it: every path to it
// tests each) and Kraft's inequality; where a side was searched before, what that search proved.
class CellSearch {
 public:
  // Cuts r by the lines (at most kSearchMaxLines) into classes. False, and nothing to solve, where there are
  // more than max_classes or r has no area.
  bool init(const DRegion& r, std::span<const SearchLine> lines, size_t max_classes);

  // Σ over leaves of area × tests of an optimal tree (divide by area() for the mean), or nullopt
  // when it needs more than max_work (work(): Σ over the regions it expands of their classes × the
  // lines crossing them, what the expansions cost; 6-9 ns each here) or memo_bytes of memo.
  std::optional<double> solve(uint64_t max_work, size_t memo_bytes);

  // Position of an optimal first test in the region the tests `path` (line position, side ±1)
  // lead to from the whole region: nullopt where that region is a leaf (one class) or the solved
  // search did not reach it.
  std::optional<uint32_t> bestLine(std::span<const std::pair<uint32_t, int8_t>> path) const;

  double area() const { return total_area_; }
  size_t classes() const { return class_.size(); }
  uint64_t work() const { return work_; }

 private:
  struct Entry {
    double value = 0.0;  // exact cost, or a lower bound of it
    int8_t best = -1;    // position of the best first line (exact entries)
    bool exact = false;
  };
  struct ClassInfo {
    LineBits sign = 0;              // the lines it lies in front of
    LineBits bounding = 0;          // the lines one of its edges lies on
    double area = 0.0, log_area = 0.0;  // area, log2 area
  };
  // What a lower bound needs of a set of classes, gathered in one pass.
  struct Summary {
    double area = 0.0;
    uint32_t count = 0;
    LineBits any = 0, all = ~LineBits{0};  // OR and AND of the classes' signs
    void add(const ClassInfo& c) {
      area += c.area;
      ++count;
      any |= c.sign;
      all &= c.sign;
    }
  };
  struct Option {
    double lower;       // of the cost of testing the line first
    double front_lower, back_lower;  // of its sides' costs
    uint32_t line;
    bool operator<(const Option& o) const { return lower < o.lower || (lower == o.lower && line < o.line); }
  };
  struct Scratch {
    std::vector<uint64_t> front, back;
    std::vector<uint32_t> lines;  // the lines crossing the region
    std::vector<Summary> sums;    // per crossing line i: [2i] its back, [2i + 1] its front
    std::vector<double> cell, kraft;  // the same: the sums of the two bounds (lowerBoundOf)
    std::vector<double> log_side;     // the same: log2 of the side's area
    std::vector<Option> order;
  };

  // Either bound alone holds for any tree below a region of two or more classes, and so does one
  // test for every eye; a single class is a leaf (0).
  static double lowerBoundOf(const Summary& s, double cell, double kraft);
  double search(const uint64_t* set, double bound, uint32_t depth, double lower);
  // sc.order: per line crossing `set` (the bits of `crossing`), a lower bound of the cost of testing
  // it first, cheapest first. One pass over the classes for every line, one more for the cell bound.
  void orderLines(const uint64_t* set, LineBits crossing, double area, Scratch& sc) const;
  static void orderLinesBody(const CellSearch& cs, const uint64_t* set, LineBits crossing, double area,
                             Scratch& sc);
  static void orderLinesPopcnt(const CellSearch& cs, const uint64_t* set, LineBits crossing, double area,
                               Scratch& sc);
  std::vector<uint64_t> allClasses() const;  // the set of every class
  std::optional<size_t> find(const uint64_t* set) const;
  size_t insert(const uint64_t* set);

  uint32_t lines_ = 0;
  size_t words_ = 0;
  double total_area_ = 0.0;
  std::vector<ClassInfo> class_;
  std::vector<uint64_t> front_;              // per line: the classes on its front (words_ each)
  std::vector<uint64_t> keys_;               // per entry: its class set (words_ each)
  std::vector<Entry> entries_;
  std::vector<uint32_t> slots_;              // open addressing over entries_; UINT32_MAX: empty
  std::vector<Scratch> scratch_;             // per depth
  uint64_t work_ = 0, max_work_ = 0;
  size_t max_entries_ = 0;
  bool over_ = false;
  bool has_popcnt_ = false;
};

}  // namespace walkvis
