// The choice of test order in the PFD tree (James & Day, "The priority face determination tree
// for hidden surface removal", Computer Graphics Forum 17(1), 1998 [JamesDay1998], leave it to a
// heuristic): an
// optimal binary decision tree over the cells of a line arrangement, found by depth-first branch
// and bound with a memo over sets of classes. Lower bounds: Shannon's and Kraft's inequality (a
// prefix code's mean length; Cover & Thomas, "Elements of Information Theory", ch. 5
// [CoverThomas2006]), with the
// cell bound of pfd_build_cgal.cpp (a line that bounds a leaf is tested on every path to it) as a
// constraint on each leaf's depth, joined by a Lagrange multiplier (lowerBoundOf).
#include "pfd_hfd/pfd_search.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "core/rng.h"

namespace walkvis {

namespace {

// How far r reaches to l's front (hi >= 0) and back (lo <= 0), in l's units.
std::pair<double, double> reachD(const DRegion& r, const SearchLine& l) {
  double hi = 0.0, lo = 0.0;
  for (const glm::dvec2& p : r.pts) {
    const double v = lineValue(l, p);
    hi = std::max(hi, v);
    lo = std::min(lo, v);
  }
  return {hi, lo};
}

}  // namespace

bool crossesD(const DRegion& r, const SearchLine& l) {
  const auto [hi, lo] = reachD(r, l);
  if (!(hi > 0.0 && lo < 0.0)) return false;
  return (hi < l.reach) == (-lo < l.reach);
}

int sideD(const DRegion& r, const SearchLine& l) {
  const auto [hi, lo] = reachD(r, l);
  return hi >= -lo ? 1 : -1;
}

double areaD(const DRegion& r) {
  double total = 0.0;
  for (size_t k = 0; k < r.pieces(); ++k) {
    const uint32_t b = r.start[k], n = r.start[k + 1] - b;
    double a = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
      const glm::dvec2& u = r.pts[b + i];
      const glm::dvec2& v = r.pts[b + (i + 1) % n];
      a += u.x * v.y - v.x * u.y;
    }
    total += 0.5 * std::abs(a);
  }
  return total;
}

void clipD(const DRegion& r, const SearchLine& l, DRegion& front, DRegion& back) {
  front.clear();
  back.clear();
  auto close = [](DRegion& d) {
    if (d.pts.size() - d.start.back() >= 3) d.start.push_back(static_cast<uint32_t>(d.pts.size()));
    else d.pts.resize(d.start.back());
  };
  for (size_t k = 0; k < r.pieces(); ++k) {
    const uint32_t b = r.start[k], n = r.start[k + 1] - b;
    for (uint32_t i = 0; i < n; ++i) {
      const glm::dvec2& u = r.pts[b + i];
      const glm::dvec2& v = r.pts[b + (i + 1) % n];
      const double fu = lineValue(l, u), fv = lineValue(l, v);
      if (fu >= 0) front.pts.push_back(u);
      if (fu <= 0) back.pts.push_back(u);
      if ((fu > 0 && fv < 0) || (fu < 0 && fv > 0)) {
        const glm::dvec2 x = u + (fu / (fu - fv)) * (v - u);
        front.pts.push_back(x);
        back.pts.push_back(x);
      }
    }
    close(front);
    close(back);
  }
}

namespace {

template <typename F>
void forEachBit(const uint64_t* set, size_t words, F&& f) {
  for (size_t w = 0; w < words; ++w)
    for (uint64_t bits = set[w]; bits != 0; bits &= bits - 1)
      f(static_cast<uint32_t>(w * 64 + static_cast<size_t>(std::countr_zero(bits))));
}

[[gnu::always_inline]] inline int popcount(LineBits b) {
  return std::popcount(static_cast<uint64_t>(b)) + std::popcount(static_cast<uint64_t>(b >> 64));
}

uint32_t lowestBit(LineBits b) {
  const uint64_t lo = static_cast<uint64_t>(b);
  return lo != 0 ? static_cast<uint32_t>(std::countr_zero(lo))
                 : 64 + static_cast<uint32_t>(std::countr_zero(static_cast<uint64_t>(b >> 64)));
}

LineBits lineBit(uint32_t j) { return LineBits{1} << j; }

constexpr double kInvLn2 = 1.4426950408889634;  // 1 / ln 2

// 2^−b for every count of lines b a class can be bounded by.
constexpr auto kPow2Neg = [] {
  std::array<double, kSearchMaxLines + 1> t{};
  double v = 1.0;
  for (double& x : t) {
    x = v;
    v *= 0.5;
  }
  return t;
}();

struct LineBitsHash {
  size_t operator()(LineBits b) const {
    return std::hash<uint64_t>()(static_cast<uint64_t>(b) * 0x9e3779b97f4a7c15ull ^ static_cast<uint64_t>(b >> 64));
  }
};

uint64_t hashSet(const uint64_t* set, size_t words) {
  uint64_t h = 0x9e3779b97f4a7c15ull;
  for (size_t w = 0; w < words; ++w) {
    uint64_t s = set[w] + h + 0x9e3779b97f4a7c15ull * w;  // splitmix64 adds the constant once more
    h ^= splitmix64(s);
  }
  return h;
}

}  // namespace

bool CellSearch::init(const DRegion& r, std::span<const SearchLine> lines, size_t max_classes) {
  class_.clear();
  front_.clear();
  entries_.clear();
  keys_.clear();
  slots_.clear();
  lines_ = static_cast<uint32_t>(lines.size());
  words_ = 0;
  total_area_ = 0.0;
  work_ = 0;
#if defined(__x86_64__)
  has_popcnt_ = __builtin_cpu_supports("popcnt");
#endif
  if (lines.size() > kSearchMaxLines) return false;

  // Each convex piece cut by every line: cells (piece, front sides). Cells of one piece whose sides
  // differ in line j alone share an edge on j (the piece cut by the other lines is convex, and j
  // crosses it), so j bounds both.
  struct Cell {
    uint32_t piece;
    LineBits sign;
    double area;
  };
  std::vector<Cell> cells;
  const size_t max_cells = 4 * max_classes + 64;
  std::vector<std::pair<DRegion, DRegion>> depth(lines.size() + 1);
  DRegion piece;
  bool too_many = false;
  auto cut = [&](auto&& self, const DRegion& part, uint32_t k, uint32_t pos, LineBits sign) -> void {
    if (too_many) return;
    if (pos == lines.size()) {
      const double a = areaD(part);
      if (a > 0.0) cells.push_back({k, sign, a});
      too_many = cells.size() > max_cells;
      return;
    }
    const SearchLine& l = lines[pos];
    const LineBits bit = lineBit(pos);
    if (!crossesD(part, l)) {
      self(self, part, k, pos + 1, sideD(part, l) > 0 ? sign | bit : sign);
      return;
    }
    auto& [front, back] = depth[pos];
    clipD(part, l, front, back);
    self(self, front, k, pos + 1, sign | bit);
    self(self, back, k, pos + 1, sign);
  };
  for (size_t k = 0; k < r.pieces() && !too_many; ++k) {
    piece.clear();
    piece.pts.assign(r.pts.begin() + r.start[k], r.pts.begin() + r.start[k + 1]);
    piece.start.push_back(static_cast<uint32_t>(piece.pts.size()));
    cut(cut, piece, static_cast<uint32_t>(k), 0, 0);
  }
  if (too_many) return false;

  std::unordered_map<LineBits, uint32_t, LineBitsHash> class_of;
  std::vector<uint32_t> cell_class(cells.size());
  for (size_t i = 0; i < cells.size(); ++i) {
    auto [it, fresh] = class_of.try_emplace(cells[i].sign, static_cast<uint32_t>(class_.size()));
    if (fresh) class_.push_back({cells[i].sign, 0, 0.0, 0.0});
    cell_class[i] = it->second;
    class_[it->second].area += cells[i].area;
    total_area_ += cells[i].area;
  }
  if (class_.size() > max_classes || total_area_ <= 0.0) {
    class_.clear();
    return false;
  }
  // Pieces are cut one after the other, so one piece's cells are contiguous.
  std::unordered_set<LineBits, LineBitsHash> in_piece;
  for (size_t first = 0, i = 0; first < cells.size(); first = i) {
    in_piece.clear();
    for (i = first; i < cells.size() && cells[i].piece == cells[first].piece; ++i) in_piece.insert(cells[i].sign);
    for (size_t c = first; c < i; ++c)
      for (uint32_t j = 0; j < lines_; ++j)
        if (in_piece.count(cells[c].sign ^ lineBit(j))) class_[cell_class[c]].bounding |= lineBit(j);
  }
  for (ClassInfo& c : class_) c.log_area = std::log2(c.area);
  words_ = (class_.size() + 63) / 64;
  front_.assign(static_cast<size_t>(lines_) * words_, 0);
  for (uint32_t j = 0; j < lines_; ++j)
    for (size_t c = 0; c < class_.size(); ++c)
      if ((class_[c].sign >> j & 1) != 0) front_[j * words_ + c / 64] |= uint64_t{1} << (c % 64);
  return true;
}

// A region of two or more classes costs at least its area (one test for every eye), and at least
// Σ a·b (`cell`: every class c, of area a, lies at a depth d >= b, the lines bounding it that cross
// the region). Depths also obey Kraft's inequality Σ 2^−d <= 1, and the least Σ a·d under both is
// at least, for any μ >= 0, Σ min over d >= b of (a·d + μ·2^−d) − μ (Lagrange). At μ = A/ln 2 (A
// the region's area) a class's term is a·d* + a/ln 2 where d* = log2(A/a) >= b, which sums to the
// entropy bound A·H where no b binds, and a·b + μ·2^−b where b does: `kraft` holds Σ of those.
double CellSearch::lowerBoundOf(const Summary& s, double cell, double kraft) {
  if (s.count <= 1) return 0.0;
  return std::max({kraft - s.area * kInvLn2, cell, s.area});
}

// The body of orderLines, inlined into a function built for the popcnt instruction and into one
// built without (the build targets baseline x86-64, where a popcount is a library call: 13% of a
// search's time).
[[gnu::always_inline]] inline void CellSearch::orderLinesBody(const CellSearch& cs, const uint64_t* set,
                                                              LineBits crossing, double area, Scratch& sc) {
  const std::vector<ClassInfo>& class_ = cs.class_;
  const size_t words_ = cs.words_;
  sc.lines.clear();
  for (LineBits m = crossing; m != 0; m &= m - 1) sc.lines.push_back(lowestBit(m));
  const size_t n = sc.lines.size();
  sc.sums.assign(2 * n, Summary{});
  sc.cell.assign(2 * n, 0.0);
  sc.kraft.assign(2 * n, 0.0);
  // Plain loops, not forEachBit: its lambdas would not be inlined into the popcnt build.
  for (size_t w = 0; w < words_; ++w) {
    for (uint64_t bits = set[w]; bits != 0; bits &= bits - 1) {
      const ClassInfo& info = class_[w * 64 + static_cast<size_t>(std::countr_zero(bits))];
      for (size_t i = 0; i < n; ++i) sc.sums[2 * i + static_cast<size_t>(info.sign >> sc.lines[i] & 1)].add(info);
    }
  }
  sc.log_side.resize(2 * n);
  for (size_t k = 0; k < 2 * n; ++k) sc.log_side[k] = std::log2(sc.sums[k].area);
  for (size_t w = 0; w < words_; ++w) {
    for (uint64_t bits = set[w]; bits != 0; bits &= bits - 1) {
      const ClassInfo& info = class_[w * 64 + static_cast<size_t>(std::countr_zero(bits))];
      for (size_t i = 0; i < n; ++i) {
        const size_t k = 2 * i + static_cast<size_t>(info.sign >> sc.lines[i] & 1);
        const int b = popcount(info.bounding & (sc.sums[k].any & ~sc.sums[k].all));
        const double ab = info.area * b;
        sc.cell[k] += ab;
        const double d = sc.log_side[k] - info.log_area;  // log2(A/a)
        sc.kraft[k] += b > d ? ab + sc.sums[k].area * kInvLn2 * kPow2Neg[b] : info.area * (d + kInvLn2);
      }
    }
  }
  sc.order.clear();
  for (size_t i = 0; i < n; ++i) {
    const double back = lowerBoundOf(sc.sums[2 * i], sc.cell[2 * i], sc.kraft[2 * i]);
    const double front = lowerBoundOf(sc.sums[2 * i + 1], sc.cell[2 * i + 1], sc.kraft[2 * i + 1]);
    sc.order.push_back({area + back + front, front, back, sc.lines[i]});
  }
  std::sort(sc.order.begin(), sc.order.end());
}

#if defined(__x86_64__)
[[gnu::target("popcnt")]] void CellSearch::orderLinesPopcnt(const CellSearch& cs, const uint64_t* set,
                                                            LineBits crossing, double area, Scratch& sc) {
  orderLinesBody(cs, set, crossing, area, sc);
}
#endif

void CellSearch::orderLines(const uint64_t* set, LineBits crossing, double area, Scratch& sc) const {
#if defined(__x86_64__)
  if (has_popcnt_) return orderLinesPopcnt(*this, set, crossing, area, sc);
#endif
  orderLinesBody(*this, set, crossing, area, sc);
}

std::vector<uint64_t> CellSearch::allClasses() const {
  std::vector<uint64_t> set(words_, ~uint64_t{0});
  if (class_.size() % 64 != 0) set.back() = (uint64_t{1} << (class_.size() % 64)) - 1;
  return set;
}

std::optional<double> CellSearch::solve(uint64_t max_work, size_t memo_bytes) {
  entries_.clear();
  keys_.clear();
  slots_.assign(1024, UINT32_MAX);
  work_ = 0;
  over_ = false;
  if (class_.empty()) return std::nullopt;
  max_work_ = max_work;
  max_entries_ = memo_bytes / (words_ * sizeof(uint64_t) + sizeof(Entry) + 2 * sizeof(uint32_t));
  scratch_.resize(lines_ + 2);
  for (Scratch& s : scratch_) {
    s.front.assign(words_, 0);
    s.back.assign(words_, 0);
  }
  const std::vector<uint64_t> all = allClasses();
  const double cost = search(all.data(), INFINITY, 0, 0.0);
  if (over_ || !std::isfinite(cost)) return std::nullopt;
  return cost;
}

std::optional<size_t> CellSearch::find(const uint64_t* set) const {
  if (slots_.empty()) return std::nullopt;
  const size_t mask = slots_.size() - 1;
  for (size_t s = hashSet(set, words_) & mask;; s = (s + 1) & mask) {
    const uint32_t e = slots_[s];
    if (e == UINT32_MAX) return std::nullopt;
    if (std::equal(set, set + words_, keys_.begin() + static_cast<std::ptrdiff_t>(e * words_))) return e;
  }
}

size_t CellSearch::insert(const uint64_t* set) {
  const size_t e = entries_.size();
  entries_.push_back({});
  keys_.insert(keys_.end(), set, set + words_);
  if (2 * entries_.size() > slots_.size()) {  // rehash at half load
    slots_.assign(2 * slots_.size(), UINT32_MAX);
    const size_t mask = slots_.size() - 1;
    for (size_t i = 0; i < entries_.size(); ++i) {
      size_t s = hashSet(keys_.data() + i * words_, words_) & mask;
      while (slots_[s] != UINT32_MAX) s = (s + 1) & mask;
      slots_[s] = static_cast<uint32_t>(i);
    }
    return e;
  }
  const size_t mask = slots_.size() - 1;
  size_t s = hashSet(set, words_) & mask;
  while (slots_[s] != UINT32_MAX) s = (s + 1) & mask;
  slots_[s] = static_cast<uint32_t>(e);
  return e;
}

// Returns the least cost of `set` where it is at most `bound`; otherwise a lower bound of it above
// `bound` (and INFINITY once the budget is spent: over_). `lower`: a lower bound the caller knows.
double CellSearch::search(const uint64_t* set, double bound, uint32_t depth, double lower) {
  if (lower > bound) return lower;
  Summary all;
  forEachBit(set, words_, [&](uint32_t c) { all.add(class_[c]); });
  if (all.count <= 1) return 0.0;
  std::optional<size_t> found = find(set);
  double known = lower;  // a lower bound proven earlier
  if (found) {
    const Entry& e = entries_[*found];
    if (e.exact || e.value > bound) return e.value;
    known = e.value;
  }
  const LineBits crossing = all.any & ~all.all;
  work_ += static_cast<uint64_t>(all.count) * static_cast<uint64_t>(popcount(crossing));
  if (work_ > max_work_ || (!found && entries_.size() >= max_entries_)) {
    over_ = true;
    return INFINITY;
  }
  const size_t index = found ? *found : insert(set);
  const double area = all.area;
  Scratch& sc = scratch_[depth];
  orderLines(set, crossing, area, sc);
  // What earlier searches proved of the sides (exact costs, or lower bounds above their bounds
  // then) is at least as good a bound as orderLines' and usually better: fewer lines are tried.
  for (Option& option : sc.order) {
    const uint64_t* f = front_.data() + option.line * words_;
    for (size_t w = 0; w < words_; ++w) {
      sc.front[w] = set[w] & f[w];
      sc.back[w] = set[w] & ~f[w];
    }
    if (const std::optional<size_t> e = find(sc.front.data()))
      option.front_lower = std::max(option.front_lower, entries_[*e].value);
    if (const std::optional<size_t> e = find(sc.back.data()))
      option.back_lower = std::max(option.back_lower, entries_[*e].value);
    option.lower = area + option.front_lower + option.back_lower;
  }
  std::sort(sc.order.begin(), sc.order.end());
  double best = INFINITY, floor = INFINITY;  // floor: the least lower bound of a line pruned
  int best_line = -1;
  for (const Option& option : sc.order) {
    const double cap = std::min(best, bound);
    if (option.lower > cap) {  // sorted: so is every line after it
      floor = std::min(floor, option.lower);
      break;
    }
    const uint32_t j = option.line;
    const uint64_t* f = front_.data() + j * words_;
    for (size_t w = 0; w < words_; ++w) {
      sc.front[w] = set[w] & f[w];
      sc.back[w] = set[w] & ~f[w];
    }
    // The deeper searches use deeper scratch only: sc.back stays intact while the front is searched.
    const double front_bound = cap - area - option.back_lower;
    const double vf = search(sc.front.data(), front_bound, depth + 1, option.front_lower);
    if (over_) return INFINITY;
    if (vf > front_bound) {
      floor = std::min(floor, area + vf + option.back_lower);
      continue;
    }
    const double back_bound = cap - area - vf;
    const double vb = search(sc.back.data(), back_bound, depth + 1, option.back_lower);
    if (over_) return INFINITY;
    const double total = area + vf + vb;
    if (vb > back_bound) {
      floor = std::min(floor, total);
      continue;
    }
    if (total < best) {
      best = total;
      best_line = static_cast<int>(j);
    }
  }
  Entry& e = entries_[index];
  if (best_line >= 0) {
    e = {best, static_cast<int8_t>(best_line), true};
    return best;
  }
  e.value = std::max({known, floor, e.value});
  return e.value;
}

std::optional<uint32_t> CellSearch::bestLine(std::span<const std::pair<uint32_t, int8_t>> path) const {
  if (class_.empty()) return std::nullopt;
  std::vector<uint64_t> set = allClasses();
  for (const auto& [pos, side] : path) {
    if (pos >= lines_) return std::nullopt;
    const uint64_t* f = front_.data() + pos * words_;
    for (size_t w = 0; w < words_; ++w) set[w] &= side > 0 ? f[w] : ~f[w];
  }
  const std::optional<size_t> e = find(set.data());
  if (!e || !entries_[*e].exact || entries_[*e].best < 0) return std::nullopt;
  return static_cast<uint32_t>(entries_[*e].best);
}

}  // namespace walkvis
