// PFD tree queries (James & Day, "The priority face determination tree for hidden surface
// removal", Computer Graphics Forum 17(1), 1998 [JamesDay1998]; docs/DESIGN.md, "PFD tree"): a
// root-to-leaf walk
// that appends each node's runs; the frame-coherent form keeps the prefix of the order that the
// eye's move did not change (Kumar et al. 1996 [Kumar1996] track the view point the same way).
#include <algorithm>
#include <chrono>
#include <cmath>

#include <glm/common.hpp>

#include "core/rng.h"
#include "pfd_hfd/pfd.h"

namespace walkvis {
namespace {

// Calls emit(run index) for each run of detail object `object` in backToFront's order for `eye`
// (skipping back faces), walking its nodes by their parent links: no stack, whatever its depth.
// As backToFront, an eye on a node's plane takes the order of an eye in front and draws none of
// the node's fragments. Returns the plane tests (one per node).
template <typename Emit>
inline uint32_t forEachObjectRun(const PfdTree& tree, uint32_t object, const glm::dvec3& eye, Emit&& emit) {
  const PfdObject& o = tree.objects[object];
  const PfdObjectNode* nodes = tree.object_nodes.data();
  int32_t cur = static_cast<int32_t>(o.root), prev = -1;
  while (cur >= 0) {
    const PfdObjectNode& n = nodes[cur];
    const int s = planeSide(tree.planes[n.plane], eye);
    const int32_t far_child = s >= 0 ? n.back : n.front, near_child = s >= 0 ? n.front : n.back;
    const int32_t from = prev;
    prev = cur;
    if (from == n.parent && far_child >= 0) {  // arrived: the far side first
      cur = far_child;
      continue;
    }
    if (from == n.parent || from == far_child) {  // the far side done: the node, then the near side
      const uint32_t run = s > 0 ? n.front_run : s < 0 ? n.back_run : kPfdNoRun;
      if (run != kPfdNoRun) emit(run);
      if (near_child >= 0) {
        cur = near_child;
        continue;
      }
    }
    cur = n.parent;  // both sides done
  }
  return o.nodes;
}

// Calls emit(run index) for each flat run that `ref` (a run, a sequence or an object) expands to
// for `eye`, in order; adds the object plane tests to `object_tests`. A sequence nests at most
// kPfdMaxSeqDepth deep (the builder and the loader ensure it).
template <typename Emit>
inline void forEachRun(const PfdTree& tree, uint32_t ref, const glm::dvec3& eye, uint32_t& object_tests,
                       Emit&& emit) {
  if (!(ref & kPfdSeqBit)) {
    if (ref & kPfdObjectBit) object_tests += forEachObjectRun(tree, ref & ~kPfdObjectBit, eye, emit);
    else emit(ref);
    return;
  }
  struct Frame {
    uint32_t next, end;
  };
  Frame stack[kPfdMaxSeqDepth];
  int top = 0;
  const PfdSeq& root = tree.seqs[ref & ~kPfdSeqBit];
  stack[0] = {root.first, root.first + root.count};
  while (top >= 0) {
    Frame& f = stack[top];
    if (f.next == f.end) {
      --top;
      continue;
    }
    const uint32_t item = tree.seq_items[f.next++];
    if (!(item & kPfdSeqBit)) {
      if (item & kPfdObjectBit) object_tests += forEachObjectRun(tree, item & ~kPfdObjectBit, eye, emit);
      else emit(item);
      continue;
    }
    const PfdSeq& c = tree.seqs[item & ~kPfdSeqBit];
    stack[++top] = {c.first, c.first + c.count};
  }
}

// Appends the node's list for `eye`; returns the object plane tests.
inline uint32_t appendList(const PfdTree& tree, const PfdNode& node, const glm::dvec3& eye,
                           std::vector<uint32_t>& order) {
  const uint32_t end = node.first_ref + node.ref_count;
  uint32_t object_tests = 0;
  for (uint32_t r = node.first_ref; r < end; ++r) {
    forEachRun(tree, tree.run_refs[r], eye, object_tests, [&](uint32_t run_index) {
      const PfdRun& run = tree.runs[run_index];
      const uint32_t* ids = tree.fragment_ids.data() + run.first;
      order.insert(order.end(), ids, ids + run.count);
    });
  }
  return object_tests;
}

double triangleArea(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  return 0.5 * std::abs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

}  // namespace

namespace {

// The root-to-leaf walk every query makes: visit(node) for each node on the eye's path, root first.
template <typename Visit>
PfdQueryResult walkPath(const PfdTree& tree, const glm::dvec3& eye, Visit&& visit) {
  PfdQueryResult result;
  if (tree.nodes.empty()) return result;
  uint32_t i = 0;
  for (;;) {
    const PfdNode& node = tree.nodes[i];
    visit(node);
    if (node.front < 0) break;
    const int s = planeSide(tree.planes[node.plane], eye);
    ++result.tests;
    result.on_line |= s == 0;
    i = static_cast<uint32_t>(s > 0 ? node.front : node.back);
  }
  return result;
}

// The walk of the run queries: emit(run index) for each node's list in order.
template <typename Emit>
PfdQueryResult walkRuns(const PfdTree& tree, const glm::dvec3& eye, Emit&& emit) {
  uint32_t object_tests = 0;
  PfdQueryResult result = walkPath(tree, eye, [&](const PfdNode& node) {
    for (uint32_t r = node.first_ref; r < node.first_ref + node.ref_count; ++r)
      forEachRun(tree, tree.run_refs[r], eye, object_tests, emit);
  });
  result.object_tests = object_tests;
  return result;
}

}  // namespace

PfdQueryResult pfdQuery(const PfdTree& tree, const glm::dvec3& eye, std::vector<uint32_t>& order) {
  order.clear();
  uint32_t object_tests = 0;
  PfdQueryResult result =
      walkPath(tree, eye, [&](const PfdNode& node) { object_tests += appendList(tree, node, eye, order); });
  result.object_tests = object_tests;
  return result;
}

PfdQueryResult pfdQueryRuns(const PfdTree& tree, const glm::dvec3& eye, std::vector<PfdRun>& runs) {
  runs.clear();
  return walkRuns(tree, eye, [&](uint32_t run) { runs.push_back(tree.runs[run]); });
}

PfdQueryResult pfdQueryRunIds(const PfdTree& tree, const glm::dvec3& eye, std::vector<uint32_t>& run_ids) {
  run_ids.clear();
  return walkRuns(tree, eye, [&](uint32_t run) { run_ids.push_back(run); });
}

PfdQueryResult pfdQueryRefs(const PfdTree& tree, const glm::dvec3& eye, std::vector<PfdRefRange>& lists) {
  lists.clear();
  return walkPath(tree, eye, [&](const PfdNode& node) {
    if (node.ref_count > 0) lists.push_back({node.first_ref, node.ref_count});
  });
}

uint32_t pfdExpandRefs(const PfdTree& tree, std::span<const PfdRefRange> lists, const glm::dvec3& eye,
                       std::vector<uint32_t>& run_ids) {
  uint32_t object_tests = 0;
  for (const PfdRefRange& l : lists) {
    for (uint32_t r = l.first; r < l.first + l.count; ++r) {
      forEachRun(tree, tree.run_refs[r], eye, object_tests, [&](uint32_t run) { run_ids.push_back(run); });
    }
  }
  return object_tests;
}

PfdQueryResult pfdQueryCoherent(const PfdTree& tree, const glm::dvec3& eye, PfdCursor& cursor,
                                std::vector<uint32_t>& order) {
  PfdQueryResult result;
  const bool valid = cursor.tree == &tree && !cursor.path.empty() &&
                     cursor.path.size() == cursor.order_size.size() && order.size() >= cursor.order_size.back() &&
                     cursor.fixed <= cursor.path.size();
  cursor.tree = &tree;
  if (tree.nodes.empty()) {
    order.clear();
    cursor.path.clear();
    cursor.order_size.clear();
    cursor.fixed = 0;
    return result;
  }
  uint32_t cur = 0;
  if (valid) {
    // Re-test the stored path; stop at the first node the eye no longer reaches, or at the first
    // list holding an object (its order may have changed with the eye).
    size_t k = 1;
    for (; k < cursor.path.size(); ++k) {
      const PfdNode& node = tree.nodes[cursor.path[k - 1]];
      const int s = planeSide(tree.planes[node.plane], eye);
      ++result.tests;
      result.on_line |= s == 0;
      cur = static_cast<uint32_t>(s > 0 ? node.front : node.back);
      if (cur != cursor.path[k]) break;
    }
    if (k == cursor.path.size() && cursor.fixed == k) return result;  // the same leaf, no object: the order stands
    if (k > cursor.fixed) {
      // The lists from `fixed` on are walked again, from the node the eye still reaches there.
      k = cursor.fixed;
      cur = cursor.path[k];
      // The tests below `fixed` were made again above; the walk below repeats them, so uncount.
      result.tests = static_cast<uint32_t>(k);
    }
    order.resize(cursor.order_size[k]);  // keep the lists of path[0, k)
    cursor.path.resize(k);
    cursor.order_size.resize(k);
    cursor.fixed = std::min(cursor.fixed, static_cast<uint32_t>(k));
  } else {
    order.clear();
    cursor.path.clear();
    cursor.order_size.clear();
    cursor.fixed = 0;
  }
  if (cursor.path.empty()) cur = 0;
  bool fixed = true;  // cursor.fixed == cursor.path.size() here
  for (;;) {
    cursor.path.push_back(cur);
    cursor.order_size.push_back(static_cast<uint32_t>(order.size()));
    const PfdNode& node = tree.nodes[cur];
    const uint32_t object_tests = appendList(tree, node, eye, order);
    result.object_tests += object_tests;
    // A list with an object expands to at least one plane test.
    if (fixed && object_tests == 0) cursor.fixed = static_cast<uint32_t>(cursor.path.size());
    else fixed = false;
    if (node.front < 0) break;
    const int s = planeSide(tree.planes[node.plane], eye);
    ++result.tests;
    result.on_line |= s == 0;
    cur = static_cast<uint32_t>(s > 0 ? node.front : node.back);
  }
  return result;
}

std::vector<uint8_t> pfdObjectNodes(const BspTree& bsp, double extent,
                                    std::vector<std::pair<glm::dvec3, glm::dvec3>>* boxes) {
  const size_t n = bsp.nodes.size();
  std::vector<uint8_t> out(n, 0);
  if (boxes) boxes->clear();
  if (!(extent > 0.0) || n == 0) return out;
  // Bottom up (children have larger indices): each subtree's box and whether all its fragments
  // lie in their node's plane (orientation ±1: facing follows the node's side).
  std::vector<glm::dvec3> lo(n, glm::dvec3(HUGE_VAL)), hi(n, glm::dvec3(-HUGE_VAL));
  std::vector<uint8_t> plain(n, 1);
  for (size_t i = n; i-- > 0;) {
    const BspNode& node = bsp.nodes[i];
    for (uint32_t f = node.first_fragment; f < node.first_fragment + node.fragment_count; ++f) {
      plain[i] &= bsp.fragment_orientation[f] != 0;
      for (const glm::dvec3& v : bsp.fragmentVertices(f)) {
        lo[i] = glm::min(lo[i], v);
        hi[i] = glm::max(hi[i], v);
      }
    }
    for (const int32_t c : {node.front, node.back}) {
      if (c < 0) continue;
      lo[i] = glm::min(lo[i], lo[c]);
      hi[i] = glm::max(hi[i], hi[c]);
      plain[i] &= plain[c];
    }
  }
  // Top down: the maximal such subtrees.
  for (size_t i = 0; i < n; ++i) {
    const int32_t p = bsp.nodes[i].parent;
    if (p >= 0 && out[p] != 0) {
      out[i] = 2;
      continue;
    }
    const glm::dvec3 e = hi[i] - lo[i];
    if (plain[i] && lo[i].x <= hi[i].x && std::max({e.x, e.y, e.z}) <= extent) out[i] = 1;
  }
  if (boxes) {
    boxes->resize(n);
    for (size_t i = 0; i < n; ++i) (*boxes)[i] = {lo[i], hi[i]};
  }
  return out;
}

glm::dvec2 samplePfdRegion(const PfdTree& tree, uint64_t& rng_state) {
  double total = 0.0;
  for (const auto& ring : tree.region)
    for (size_t i = 1; i + 1 < ring.size(); ++i) total += triangleArea(ring[0], ring[i], ring[i + 1]);
  if (!(total > 0.0)) return {0.0, 0.0};
  double pick = uniform01(rng_state) * total;
  for (const auto& ring : tree.region) {
    for (size_t i = 1; i + 1 < ring.size(); ++i) {
      const double a = triangleArea(ring[0], ring[i], ring[i + 1]);
      if (pick <= a || (&ring == &tree.region.back() && i + 2 == ring.size())) {
        double u = uniform01(rng_state), v = uniform01(rng_state);
        if (u + v > 1.0) {
          u = 1.0 - u;
          v = 1.0 - v;
        }
        return ring[0] + u * (ring[i] - ring[0]) + v * (ring[i + 1] - ring[0]);
      }
      pick -= a;
    }
  }
  return tree.region.front().front();
}

PfdQueryTiming timePfdQueries(const BspTree& bsp, const PfdTree& tree, uint32_t eyes) {
  PfdQueryTiming t;
  if (tree.region.empty() || eyes == 0) return t;
  t.eyes = eyes;
  std::vector<glm::dvec3> points;
  uint64_t state = 12345;
  for (uint32_t i = 0; i < eyes; ++i) {
    const glm::dvec2 p = samplePfdRegion(tree, state);
    points.emplace_back(p.x, tree.height, p.y);
  }
  std::vector<uint32_t> order;
  order.reserve(bsp.fragments.size());
  std::vector<PfdRun> runs;
  std::vector<PfdRefRange> lists;
  // Mean ns per eye of query(eye), and the mean of what it returns (the size of its output).
  auto timeEach = [&](auto&& query, double& ns, double& mean) {
    uint64_t total = 0;
    const auto start = std::chrono::steady_clock::now();
    for (const glm::dvec3& e : points) total += query(e);
    ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count() / eyes;
    mean = static_cast<double>(total) / eyes;
  };
  double ids_mean = 0.0;
  uint64_t object_tests = 0;  // counted in the timed pass: one add per query beside the walk
  timeEach([&](const glm::dvec3& e) {
    object_tests += pfdQuery(tree, e, order).object_tests;
    return order.size();
  }, t.pfd_ns, ids_mean);
  t.object_tests_mean = static_cast<double>(object_tests) / eyes;
  timeEach([&](const glm::dvec3& e) { backToFront(bsp, e, order, true); return order.size(); }, t.bsp_ns, ids_mean);
  timeEach([&](const glm::dvec3& e) { pfdQueryRuns(tree, e, runs); return runs.size(); }, t.runs_ns, t.runs_mean);
  timeEach([&](const glm::dvec3& e) { pfdQueryRefs(tree, e, lists); return lists.size(); }, t.refs_ns, t.refs_mean);
  return t;
}

void measurePfd(PfdTree& tree, uint32_t eyes, uint64_t seed) {
  PfdStats& s = tree.stats;
  s.bytes = tree.nodes.size() * sizeof(PfdNode) + tree.run_refs.size() * sizeof(uint32_t) +
            tree.runs.size() * sizeof(PfdRun) + tree.fragment_ids.size() * sizeof(uint32_t) +
            tree.seqs.size() * sizeof(PfdSeq) + tree.seq_items.size() * sizeof(uint32_t) +
            tree.planes.size() * sizeof(Plane) + tree.objects.size() * sizeof(PfdObject) +
            tree.object_nodes.size() * sizeof(PfdObjectNode);
  for (const auto& ring : tree.region) s.bytes += ring.size() * sizeof(glm::dvec2);
  s.tests_mean = 0.0;
  s.tests_max = 0;
  if (eyes == 0 || tree.nodes.empty() || tree.region.empty()) return;
  uint64_t state = seed;
  uint64_t sum = 0;
  for (uint32_t e = 0; e < eyes; ++e) {
    const glm::dvec2 p = samplePfdRegion(tree, state);
    const glm::dvec3 eye{p.x, tree.height, p.y};
    uint64_t tests = 0;
    for (uint32_t i = 0; tree.nodes[i].front >= 0; ++tests) {
      const PfdNode& node = tree.nodes[i];
      i = static_cast<uint32_t>(planeSide(tree.planes[node.plane], eye) > 0 ? node.front : node.back);
    }
    sum += tests;
    s.tests_max = std::max(s.tests_max, tests);
  }
  s.tests_mean = static_cast<double>(sum) / eyes;
}

double huffmanMeanDepth(std::span<const double> weights) {
  std::vector<double> w;
  double total = 0.0;
  for (double x : weights) {
    if (x > 0.0) {
      w.push_back(x);
      total += x;
    }
  }
  if (w.size() < 2) return 0.0;
  for (double& x : w) x /= total;
  std::sort(w.begin(), w.end());
  // Two queues (van Leeuwen 1976 [vanLeeuwen1976]): merged weights come out in non-decreasing
  // order, so the two least are always at the fronts. Each merge adds its weight once per level it
  // sinks.
  std::vector<double> merged;
  merged.reserve(w.size());
  size_t a = 0, b = 0;
  auto take = [&]() {
    if (b >= merged.size() || (a < w.size() && w[a] <= merged[b])) return w[a++];
    return merged[b++];
  };
  double depth = 0.0;
  for (size_t k = 1; k < w.size(); ++k) {
    const double x = take() + take();
    merged.push_back(x);
    depth += x;
  }
  return depth;
}

const PfdTree* findPfdCell(const PfdLevel& level, const glm::dvec3& eye) {
  for (const PfdTree& t : level.cells) {
    if (!t.cell) return &t;
    if (eye.x >= t.cell->lo.x && eye.x < t.cell->hi.x && eye.z >= t.cell->lo.y && eye.z < t.cell->hi.y) return &t;
  }
  return nullptr;
}

double pfdLevelArea(const PfdLevel& level) {
  double total = 0.0;
  for (const PfdTree& t : level.cells) total += std::max(t.stats.region_area, 0.0);
  return total;
}

std::optional<glm::dvec3> samplePfdLevel(const PfdLevel& level, uint64_t& rng_state) {
  const double total = pfdLevelArea(level);
  if (!(total > 0.0)) return std::nullopt;
  double pick = uniform01(rng_state) * total;
  size_t c = 0, last = 0;
  for (; c < level.cells.size(); ++c) {
    const double a = level.cells[c].stats.region_area;
    if (!(a > 0.0)) continue;
    last = c;
    if (pick < a) break;
    pick -= a;
  }
  if (c == level.cells.size()) c = last;  // rounding left a sliver of `pick`
  const glm::dvec2 p = samplePfdRegion(level.cells[c], rng_state);
  return glm::dvec3{p.x, level.height, p.y};
}

bool strictlyInsidePfdRegion(const PfdTree& tree, const glm::dvec3& eye) {
  for (const auto& ring : tree.region) {
    size_t pos = 0, neg = 0;
    for (size_t i = 0; i < ring.size(); ++i) {
      const glm::dvec2 a = ring[i], b = ring[(i + 1) % ring.size()];
      const double c = (b.x - a.x) * (eye.z - a.y) - (b.y - a.y) * (eye.x - a.x);
      pos += c > 0;
      neg += c < 0;
    }
    if (pos == ring.size() || neg == ring.size()) return true;
  }
  return false;
}

}  // namespace walkvis
