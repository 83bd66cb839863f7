// Building the PFD tree by partial evaluation of the BSP back-to-front traversal over regions of
// the height plane (James & Day, "The priority face determination tree for hidden surface
// removal", Computer Graphics Forum 17(1), 1998 [JamesDay1998]; definition and construction:
// docs/DESIGN.md, "PFD tree"). Regions are exact (pfd_region_cgal.h): test-lines through corners
// happen (1–16% of decisions, docs/DESIGN.md, "Sizes and errors"), and a corner that lies on a
// line must count as touching it, not crossing it. This file is the traversal: which line a node
// tests is pfd_line_choice_cgal.h's, and the lists' runs and sequences are pfd_run_store.h's.
#include <algorithm>
#include <bit>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>
#include <span>
#include <unordered_map>

#include "bsp/exact_sign.h"
#include "core/check.h"
#include "core/hash.h"
#include "pfd_hfd/pfd.h"
#include "pfd_hfd/pfd_internal.h"
#include "pfd_hfd/pfd_line_choice_cgal.h"
#include "pfd_hfd/pfd_region_cgal.h"
#include "pfd_hfd/pfd_run_store.h"

namespace walkvis {
using namespace pfd_exact;
namespace {

// tests_optimal needs the tree's exact mean tests and the search's prediction to agree this closely
// (relative): both sum the same leaves' areas in doubles by different clips (~1e-15 each), while a
// leaf tested once more or less than the model says differs by its area fraction (a sliver trimmed
// off, 1e-9 of the extent, or far more).
constexpr double kOptimalAgreement = 1e-9;

// A pending step of the back-to-front traversal.
struct Item {
  int32_t node = -1;
  int8_t emit_side = 0;  // 0: visit the subtree at `node`; ±1 or 2 (eye on the plane): emit its fragments
};
constexpr int8_t kEmitOn = 2;

// A memoised emission of a fully resolved BSP subtree: its order depends only on the sides of the
// lines inside it that cross the tree's whole region (every other side is the same everywhere).
struct MemoEntry {
  int32_t node = -1;
  uint32_t key_first = 0;  // key_pool_[key_first, key_first + key_words): 2 bits per varying line
  uint32_t key_words = 0;
  uint32_t run = UINT32_MAX;  // the output run (PFD with dedup), or
  uint32_t first = 0;         // memo_pool_[first, first + count) otherwise
  uint32_t count = 0;
};

// A subtree whose order resolvedRef is assembling from its children's.
struct RefFrame {
  int32_t node = -1;
  int32_t far_child = -1, near_child = -1;
  int s = 0;
  uint8_t stage = 0;  // 0: start; 1: far child's entry wanted; 2: near child's; 3: combine
  uint32_t far_ref = kPfdEmptyRef, near_ref = kPfdEmptyRef;
};

class Builder {
 public:
  Builder(const BspTree& bsp, double height, const PfdOptions& options, const Region& root,
          const std::vector<uint8_t>& objects, const std::vector<std::pair<glm::dvec3, glm::dvec3>>& object_boxes,
          PfdTree& out)
      : bsp_(bsp),
        options_(options),
        out_(out),
        height_(height),
        lines_(bsp, height, options.drop_back_faces, root, objects),
        sliver_tol_(kSliverTolerance * regionExtent(root)),
        choice_(options, lines_, sliver_tol_),
        object_(objects),
        object_box_(object_boxes) {
    const size_t nn = bsp.nodes.size();
    if (bsp.fragments.size() >= kObjectMark) throw PfdBudgetError("pfd: more than 2^31 fragments");
    object_of_.assign(nn, UINT32_MAX);
    unresolved_stamp_.assign(nn, 0);
    test_plane_.assign(lines_.size(), UINT32_MAX);
    hidden_.assign(bsp.fragments.size(), 0);
    witness_.assign(bsp.fragments.size(), std::nullopt);
    // Per BSP subtree, in preorder: its varying lines and its fragments (contiguous ranges).
    vary_range_.assign(nn, {0, 0});
    frag_range_.assign(nn, {0, 0});
    if (bsp.root >= 0) {
      std::vector<std::pair<int32_t, bool>> dfs{{bsp.root, false}};
      while (!dfs.empty()) {
        auto [id, done] = dfs.back();
        dfs.pop_back();
        if (done) {
          vary_range_[id].second = static_cast<uint32_t>(vary_list_.size());
          frag_range_[id].second = static_cast<uint32_t>(frag_pre_.size());
          continue;
        }
        const BspNode& node = bsp.nodes[id];
        vary_range_[id].first = static_cast<uint32_t>(vary_list_.size());
        frag_range_[id].first = static_cast<uint32_t>(frag_pre_.size());
        if (lines_.varying(id)) vary_list_.push_back(static_cast<uint32_t>(id));
        for (uint32_t f = node.first_fragment; f < node.first_fragment + node.fragment_count; ++f) {
          frag_pre_.push_back(f);
          const uint32_t fl = lines_.fragmentLine(f);
          if (fl != UINT32_MAX && lines_.varying(fl)) vary_list_.push_back(fl);
        }
        dfs.push_back({id, true});
        if (node.back >= 0) dfs.push_back({node.back, false});
        if (node.front >= 0) dfs.push_back({node.front, false});
      }
    }
  }

  void run(Region region) {
    std::vector<Item> stack;
    if (bsp_.root >= 0) stack.push_back({bsp_.root, 0});
    build(std::move(region), std::move(stack), 1);
  }

  Counters& counters() { return lines_.counters; }
  const RootSearch& rootSearch() const { return choice_.rootSearch(); }
  VisibilityCounters vis_counters;
  uint64_t hidden_rejected = 0;
  uint64_t visibility_witnessed = 0;
  uint64_t objects_box_rejected = 0;
  std::vector<double> leaf_areas;
  double leaf_bound_tests = 0.0;  // Σ over leaves of area × tested lines bounding the leaf
  double leaf_depth_area = 0.0;   // Σ over leaves of area × tests on the leaf's path
  uint64_t depth_max = 0;
  uint64_t list_fragments = 0;

 private:
  double done_area_ = 0.0;  // leaves built, for options_.progress (against out_.stats.region_area)

  bool hfd() const { return options_.visibility != nullptr; }

  void undo(size_t mark, size_t hidden_mark, size_t witness_mark) {
    lines_.undo(mark);
    while (hidden_log_.size() > hidden_mark) {
      hidden_[hidden_log_.back()] = 0;
      hidden_log_.pop_back();
    }
    while (witness_log_.size() > witness_mark) {
      witness_[witness_log_.back().fragment] = witness_log_.back().point;
      witness_log_.pop_back();
    }
  }

  // HFD: whether the eye that saw f from an ancestor region lies in r (a closed convex piece of
  // it, by double orientation tests): then f is visible from r with no new rays.
  bool witnessedIn(uint32_t f, const Region& r) {
    if (!witness_[f]) return false;
    for (const std::vector<glm::dvec2>& ring : rings(r))
      if (insideConvexRing(ring, *witness_[f])) return true;
    return false;
  }

  void setWitness(uint32_t f, const glm::dvec2& p) {
    witness_log_.push_back({f, witness_[f]});
    witness_[f] = p;
  }

  void runTests(std::span<const uint32_t> batch, const Region& r) {
    results_.assign(batch.size(), 0);
    witness_scratch_.assign(batch.size(), glm::dvec2(0.0));
    visibleBatch(*options_.visibility, batch, rings(r), height_, results_, witness_scratch_, vis_counters);
    for (size_t i = 0; i < batch.size(); ++i)
      if (results_[i] && std::isfinite(witness_scratch_[i].x)) setWitness(batch[i], witness_scratch_[i]);
  }

  // The crossing line (if any) among the orientation-0 fragments of a node; UINT32_MAX if none.
  uint32_t crossingFragmentLine(const BspNode& node, const Region& r) {
    for (uint32_t f = node.first_fragment; f < node.first_fragment + node.fragment_count; ++f) {
      const uint32_t fl = lines_.fragmentLine(f);
      if (fl != UINT32_MAX && lines_.side(fl, r) == kCross) return fl;
    }
    return UINT32_MAX;
  }

  // A node's fragments whose plane side (and degenerate fragments' sides) are known, as
  // backToFront(..., drop_back_faces) emits them: front-facing ones only, or all of them.
  void emitFragments(const BspNode& node, int s, const Region& r, std::vector<uint32_t>& out) {
    for (uint32_t f = node.first_fragment; f < node.first_fragment + node.fragment_count; ++f) {
      if (!options_.drop_back_faces) {
        out.push_back(f);
        continue;
      }
      const int8_t o = bsp_.fragment_orientation[f];
      const int fs = o != 0 ? s * o : lines_.side(lines_.fragmentLine(f), r);
      if (fs > 0) out.push_back(f);
    }
  }

  static void children(const BspNode& node, int s, int32_t& far_child, int32_t& near_child) {
    // As backToFront: the eye on the plane takes the same order as in front.
    far_child = s >= 0 ? node.back : node.front;
    near_child = s >= 0 ? node.front : node.back;
  }

  // Whether no line inside the subtree crosses r (every varying line of it is decided).
  bool resolved(int32_t id, const Region& r) {
    if (unresolved_stamp_[id] == lines_.regionStamp()) return false;
    const auto [b, e] = vary_range_[id];
    for (uint32_t k = b; k < e; ++k)
      if (lines_.side(vary_list_[k], r) == kCross) {
        unresolved_stamp_[id] = lines_.regionStamp();
        return false;
      }
    return true;
  }

  // The back-to-front emission of a resolved subtree (every side known), without recursion: a
  // degenerate BSP may be as deep as it has nodes.
  void emitSubtree(int32_t root, const Region& r, std::vector<uint32_t>& out) {
    walk_.clear();
    walk_.push_back({root, 0});
    while (!walk_.empty()) {
      const Item item = walk_.back();
      walk_.pop_back();
      const BspNode& node = bsp_.nodes[item.node];
      if (item.emit_side != 0) {
        emitFragments(node, item.emit_side == kEmitOn ? 0 : item.emit_side, r, out);
        continue;
      }
      if (object_[item.node] == 1) {
        out.push_back(kObjectMark | static_cast<uint32_t>(item.node));  // a detail object, whole
        continue;
      }
      const int s = lines_.side(static_cast<uint32_t>(item.node), r);
      int32_t far_child, near_child;
      children(node, s, far_child, near_child);
      if (near_child >= 0) walk_.push_back({near_child, 0});
      walk_.push_back({item.node, static_cast<int8_t>(s == 0 ? kEmitOn : s)});
      if (far_child >= 0) walk_.push_back({far_child, 0});
    }
  }

  // The key of a resolved subtree's order: the sides of the lines inside it that cross the
  // tree's whole region (2 bits each) in key_, and its hash.
  uint64_t memoKey(int32_t id) {
    const auto [b, e] = vary_range_[id];
    key_.assign((e - b + 31) / 32, 0);
    for (uint32_t k = b; k < e; ++k) {
      const uint64_t v = static_cast<uint64_t>(lines_.decidedSide(vary_list_[k]) + 1) & 3;
      key_[(k - b) / 32] |= v << (2 * ((k - b) % 32));
    }
    uint64_t h = kFnvOffset ^ static_cast<uint64_t>(id);
    for (uint64_t w : key_) {
      h = fnv1aWord(h, w);
      h ^= h >> 31;
    }
    return h;
  }

  // The memo entry for key_ (just made by memoKey(id) with hash h), or null.
  const MemoEntry* memoFind(int32_t id, uint64_t h) const {
    auto [lo, hi] = memo_.equal_range(h);
    for (auto it = lo; it != hi; ++it) {
      const MemoEntry& m = memo_entries_[it->second];
      if (m.node == id && m.key_words == key_.size() &&
          std::equal(key_.begin(), key_.end(), key_pool_.begin() + m.key_first))
        return &m;
    }
    return nullptr;
  }

  MemoEntry& memoAdd(int32_t id, uint64_t h) {
    MemoEntry m;
    m.node = id;
    m.key_first = static_cast<uint32_t>(key_pool_.size());
    m.key_words = static_cast<uint32_t>(key_.size());
    key_pool_.insert(key_pool_.end(), key_.begin(), key_.end());
    memo_.emplace(h, static_cast<uint32_t>(memo_entries_.size()));
    memo_entries_.push_back(m);
    return memo_entries_.back();
  }

  // HFD or no dedup: the emission of a resolved subtree as ids, memoised by the sides of its
  // varying lines.
  void resolvedEmission(int32_t id, const Region& r, std::span<const uint32_t>& content) {
    const uint64_t h = memoKey(id);
    if (const MemoEntry* m = memoFind(id, h)) {
      content = std::span<const uint32_t>(memo_pool_.data() + m->first, m->count);
      return;
    }
    scratch_.clear();
    emitSubtree(id, r, scratch_);
    MemoEntry& m = memoAdd(id, h);
    m.first = static_cast<uint32_t>(memo_pool_.size());
    m.count = static_cast<uint32_t>(scratch_.size());
    memo_pool_.insert(memo_pool_.end(), scratch_.begin(), scratch_.end());
    content = std::span<const uint32_t>(memo_pool_.data() + m.first, m.count);
  }

  bool toRefs() const { return options_.dedup && !hfd(); }

  // The fragment ids an id list expands to: an object mark stands for all its fragments.
  uint64_t idsLength(std::span<const uint32_t> ids) const {
    uint64_t n = 0;
    for (uint32_t x : ids) {
      if (x & kObjectMark) {
        const auto& range = frag_range_[x & ~kObjectMark];
        n += range.second - range.first;
      } else {
        ++n;
      }
    }
    return n;
  }

  // Appends the ids `ref` expands to (sequences nest at most kPfdMaxSeqDepth deep).
  void expandRef(uint32_t ref, std::vector<uint32_t>& out) const {
    if (ref == kEmptyRun) return;
    if (!(ref & kPfdSeqBit) && (ref & kPfdObjectBit)) {
      out.push_back(kObjectMark | static_cast<uint32_t>(object_root_[ref & ~kPfdObjectBit]));
      return;
    }
    if (!(ref & kPfdSeqBit)) {
      const PfdRun& run = out_.runs[ref];
      out.insert(out.end(), out_.fragment_ids.begin() + run.first, out_.fragment_ids.begin() + run.first + run.count);
      return;
    }
    const PfdSeq& q = out_.seqs[ref & ~kPfdSeqBit];
    for (uint32_t k = q.first; k < q.first + q.count; ++k) expandRef(out_.seq_items[k], out);
  }

  // PFD with dedup: the list entry for the order of the resolved subtree `root` in r (kEmptyRun
  // when it emits nothing). Each (subtree, sides of its varying lines) is memoised; an order of at
  // least share_min ids becomes a sequence [far child's order, the node's fragments, near child's
  // order], sharing the children's entries, and a shorter one a flat run. Iterative: a degenerate
  // BSP may be as deep as it has nodes.
  uint32_t resolvedRef(int32_t root, const Region& r) {
    {
      const uint64_t h = memoKey(root);
      if (const MemoEntry* m = memoFind(root, h)) return m->run;
    }
    std::vector<RefFrame>& stack = ref_frames_;
    stack.clear();
    stack.push_back(RefFrame{root});
    uint32_t result = kEmptyRun;
    // Returns true when the child's entry was known (memo), false when a frame was pushed for it.
    auto want = [&](int32_t child, uint32_t& slot) {
      if (child < 0 || smallSubtree(child)) {
        slot = kEmptyRun;  // combine() emits a small child's order itself
        return true;
      }
      const uint64_t h = memoKey(child);
      if (const MemoEntry* m = memoFind(child, h)) {
        slot = m->run;
        return true;
      }
      stack.push_back(RefFrame{child});
      return false;
    };
    while (!stack.empty()) {
      const size_t top = stack.size() - 1;
      RefFrame& f = stack[top];
      if (f.stage == 0) {
        const BspNode& node = bsp_.nodes[f.node];
        if (vary_range_[f.node].first == vary_range_[f.node].second || smallSubtree(f.node)) {
          // No line inside crosses the tree's region (its one order), or too few fragments for a
          // sequence: flat.
          scratch_.clear();
          emitSubtree(f.node, r, scratch_);
          result = scratch_.empty() ? kEmptyRun : findOrAddRef(scratch_);
        } else {
          f.s = lines_.side(static_cast<uint32_t>(f.node), r);
          children(node, f.s, f.far_child, f.near_child);
          f.stage = 1;
          if (!want(f.far_child, f.far_ref)) continue;
          stack[top].stage = 2;
          if (!want(stack[top].near_child, stack[top].near_ref)) continue;
          stack[top].stage = 3;
          continue;
        }
      } else if (f.stage == 3) {
        result = combine(f.node, f.s, f.far_ref, f.near_ref, r);
      } else {
        continue;  // unreachable: a frame waiting for a child is never on top
      }
      // stack[top] is done with `result`: memoise it and hand it to the parent.
      const int32_t done = stack[top].node;
      const uint64_t h = memoKey(done);
      memoAdd(done, h).run = result;
      stack.pop_back();
      if (stack.empty()) break;
      RefFrame& parent = stack.back();
      if (parent.stage == 1) {
        parent.far_ref = result;
        parent.stage = 2;
        if (!want(parent.near_child, stack.back().near_ref)) continue;
        stack.back().stage = 3;
      } else {
        parent.near_ref = result;
        parent.stage = 3;
      }
    }
    return result;
  }

  // The entry for [far, the fragments of `node` on side s, near].
  // A subtree with fewer fragments than share_min: its orders are always stored flat, inside its
  // ancestors' runs, never as runs of their own.
  bool smallSubtree(int32_t id) const { return frag_range_[id].second - frag_range_[id].first < options_.share_min; }

  uint32_t combine(int32_t node_id, int s, uint32_t far_ref, uint32_t near_ref, const Region& r) {
    int32_t far_child, near_child;
    children(bsp_.nodes[node_id], s, far_child, near_child);
    own_.clear();
    emitFragments(bsp_.nodes[node_id], s, r, own_);
    small_far_.clear();
    small_near_.clear();
    if (far_child >= 0 && smallSubtree(far_child)) emitSubtree(far_child, r, small_far_);
    if (near_child >= 0 && smallSubtree(near_child)) emitSubtree(near_child, r, small_near_);
    const uint64_t length = uint64_t{store_.refLength(far_ref)} + idsLength(small_far_) + idsLength(own_) +
                            idsLength(small_near_) + store_.refLength(near_ref);
    if (length == 0) return kEmptyRun;
    if (length < std::max<uint32_t>(options_.share_min, 1)) {
      flat_.clear();
      expandRef(far_ref, flat_);
      flat_.insert(flat_.end(), small_far_.begin(), small_far_.end());
      flat_.insert(flat_.end(), own_.begin(), own_.end());
      flat_.insert(flat_.end(), small_near_.begin(), small_near_.end());
      expandRef(near_ref, flat_);
      return findOrAddRef(flat_);
    }
    items_.clear();
    acc_.clear();
    // Short runs are copied together into one run; longer runs and sequences are referenced.
    // A sequence already at the depth limit is inlined (its items referenced instead).
    auto flush = [&] {
      if (acc_.empty()) return;
      appendRefs(acc_, items_);
      acc_.clear();
    };
    auto part = [&](uint32_t ref) {
      if (ref == kEmptyRun) return;
      if (!(ref & (kPfdSeqBit | kPfdObjectBit)) && out_.runs[ref].count < options_.share_min) {
        expandRef(ref, acc_);
        return;
      }
      flush();
      items_.push_back(ref);
    };
    auto add = [&](uint32_t ref) {
      if (ref != kEmptyRun && store_.refDepth(ref) >= kPfdMaxSeqDepth) {
        const PfdSeq q = out_.seqs[ref & ~kPfdSeqBit];
        for (uint32_t k = q.first; k < q.first + q.count; ++k) part(out_.seq_items[k]);
      } else {
        part(ref);
      }
    };
    add(far_ref);
    acc_.insert(acc_.end(), small_far_.begin(), small_far_.end());
    acc_.insert(acc_.end(), own_.begin(), own_.end());
    acc_.insert(acc_.end(), small_near_.begin(), small_near_.end());
    add(near_ref);
    flush();
    if (items_.size() == 1) return items_[0];
    return store_.findOrAddSeq(items_, static_cast<uint32_t>(length));
  }

  const std::vector<std::vector<glm::dvec2>>& rings(const Region& r) {
    if (rings_stamp_ != lines_.regionStamp()) {
      rings_stamp_ = lines_.regionStamp();
      rings_.clear();
      for (const Piece& p : r) {
        std::vector<glm::dvec2> ring;
        ring.reserve(p.corners.size());
        for (const Corner& k : p.corners) ring.emplace_back(k.ax, k.az);
        rings_.push_back(std::move(ring));
      }
    }
    return rings_;
  }

  void markHidden(uint32_t f) {
    if (hidden_[f]) return;
    hidden_[f] = 1;
    hidden_log_.push_back(f);
  }

  // HFD: the fragments of `ids` visible from r, in order; the hidden ones are remembered for the
  // rest of this root-to-node path and never tested again below.
  void filterVisible(std::span<const uint32_t> ids, const Region& r, std::vector<uint32_t>& out) {
    // Witnessed fragments into seen_, the others tested, then both merged back in list order.
    seen_.clear();
    to_test_.clear();
    for (uint32_t f : ids) {
      if (hidden_[f]) continue;
      if (witnessedIn(f, r)) {
        ++visibility_witnessed;
        seen_.push_back(f);
      } else {
        to_test_.push_back(f);
      }
    }
    runTests(to_test_, r);
    size_t a = 0, b = 0;
    for (uint32_t f : ids) {
      if (a < seen_.size() && seen_[a] == f) {
        out.push_back(f);
        ++a;
      } else if (b < to_test_.size() && to_test_[b] == f) {
        if (results_[b]) {
          out.push_back(f);
        } else {
          markHidden(f);
          ++hidden_rejected;
        }
        ++b;
      }
    }
  }

  // HFD: whether every fragment of `ids` is hidden from r (or back-facing for all of it when back
  // faces are dropped), testing in fixed batches in order and stopping at the first batch with a
  // visible one, so that the answer and what is remembered do not depend on threads.
  // `object_root` >= 0: `ids` are that detail object's fragments, and when enough of them are still
  // to test, the object's box is tried first (PfdOptions::object_boxes): a box costs up to six face
  // tests (a face turned away from every eye casts no ray) where the fragments of a hidden object
  // cost one each, and a visible box is wasted work when its fragments are hidden from r after
  // all. A hidden box marks them all hidden.
  bool allHidden(std::span<const uint32_t> ids, const Region& r, int32_t object_root = -1) {
    to_test_.clear();
    size_t open = 0;  // not hidden from an ancestor
    for (uint32_t f : ids) {
      if (hidden_[f]) continue;
      if (witnessedIn(f, r)) {
        ++visibility_witnessed;
        return false;  // seen from a point of r: not all hidden, whatever the others are
      }
      ++open;
      if (options_.drop_back_faces) {
        const int8_t o = bsp_.fragment_orientation[f];
        const uint32_t node_line = static_cast<uint32_t>(&nodeOf(f) - bsp_.nodes.data());
        const int s = o != 0 ? lines_.side(node_line, r) : lines_.side(lines_.fragmentLine(f), r);
        if (s != kCross && (o != 0 ? s * o : s) <= 0) continue;  // back-facing everywhere in r
      }
      to_test_.push_back(f);
    }
    if (object_root >= 0 && options_.object_boxes && open >= kBoxMinFragments) {
      const auto& [lo, hi] = object_box_[object_root];
      if (!options_.visibility->boxVisibleFromRegion(lo, hi, rings(r), height_, vis_counters)) {
        ++objects_box_rejected;
        for (uint32_t f : ids) markHidden(f);
        return true;
      }
    }
    constexpr size_t kBatch = 32;
    for (size_t start = 0; start < to_test_.size(); start += kBatch) {
      const size_t n = std::min(kBatch, to_test_.size() - start);
      runTests(std::span<const uint32_t>(to_test_.data() + start, n), r);
      bool any = false;
      for (size_t i = 0; i < n; ++i) {
        if (results_[i]) any = true;
        else markHidden(to_test_[start + i]);
      }
      if (any) return false;
    }
    return true;
  }

  const BspNode& nodeOf(uint32_t fragment) {
    if (frag_node_.empty()) {
      frag_node_.assign(bsp_.fragments.size(), 0);
      for (uint32_t n = 0; n < bsp_.nodes.size(); ++n)
        for (uint32_t f = bsp_.nodes[n].first_fragment; f < bsp_.nodes[n].first_fragment + bsp_.nodes[n].fragment_count;
             ++f)
          frag_node_[f] = n;
    }
    return bsp_.nodes[frag_node_[fragment]];
  }

  static constexpr uint32_t kEmptyRun = kPfdEmptyRef;

  // Appends list entries for `ids` (fragments and object marks; HFD: the visible ones),
  // deduplicated when asked.
  void addRun(std::span<const uint32_t> ids, const Region& r) {
    splitMarks(
        ids, [&](int32_t root) { addObject(root, r); }, [&](std::span<const uint32_t> f) { addFragments(f, r); });
  }

  // Calls object(BSP root) for each object mark of `ids` and fragments(stretch) for each maximal
  // stretch of fragment ids between them, in order.
  template <typename Object, typename Fragments>
  static void splitMarks(std::span<const uint32_t> ids, Object&& object, Fragments&& fragments) {
    for (size_t b = 0; b < ids.size();) {
      if (ids[b] & kObjectMark) {
        object(static_cast<int32_t>(ids[b] & ~kObjectMark));
        ++b;
        continue;
      }
      size_t e = b;
      while (e < ids.size() && !(ids[e] & kObjectMark)) ++e;
      fragments(ids.subspan(b, e - b));
      b = e;
    }
  }

  // A list entry for the detail object rooted at BSP node `root` (HFD: unless all its fragments
  // are hidden from r).
  void addObject(int32_t root, const Region& r) {
    const auto [fb, fe] = frag_range_[root];
    const std::span<const uint32_t> ids(frag_pre_.data() + fb, fe - fb);
    if (hfd() && allHidden(ids, r, root)) return;
    const uint32_t ref = objectRef(root);
    list_fragments += store_.refLength(ref);
    out_.run_refs.push_back(ref);
  }

  // The object entry for the subtree at `root`, made on first use: its nodes in preorder with the
  // BSP node's plane and its fragments by facing as two runs.
  uint32_t objectRef(int32_t root) {
    if (object_of_[root] != UINT32_MAX) return object_of_[root] | kPfdObjectBit;
    const uint32_t index = static_cast<uint32_t>(out_.objects.size());
    if (index >= kPfdObjectBit) throw PfdBudgetError("pfd: more than 2^30 objects");
    PfdObject object;
    object.root = static_cast<uint32_t>(out_.object_nodes.size());
    struct Pending {
      int32_t bsp_node, parent;
      bool front;
    };
    std::vector<Pending> dfs{{root, -1, false}};
    std::vector<uint32_t> facing;
    while (!dfs.empty()) {
      const Pending p = dfs.back();
      dfs.pop_back();
      const BspNode& node = bsp_.nodes[p.bsp_node];
      const int32_t me = static_cast<int32_t>(out_.object_nodes.size());
      PfdObjectNode on;
      on.plane = testPlaneIndex(static_cast<uint32_t>(p.bsp_node));
      on.parent = p.parent;
      for (const int8_t o : {int8_t{1}, int8_t{-1}}) {
        facing.clear();
        for (uint32_t f = node.first_fragment; f < node.first_fragment + node.fragment_count; ++f)
          if (bsp_.fragment_orientation[f] == o) facing.push_back(f);
        (o > 0 ? on.front_run : on.back_run) = facing.empty() ? kPfdNoRun : store_.findOrAddRun(facing);
      }
      object.fragments += node.fragment_count;
      out_.object_nodes.push_back(on);
      if (p.parent >= 0) (p.front ? out_.object_nodes[p.parent].front : out_.object_nodes[p.parent].back) = me;
      if (node.back >= 0) dfs.push_back({node.back, me, false});
      if (node.front >= 0) dfs.push_back({node.front, me, true});
    }
    object.nodes = static_cast<uint32_t>(out_.object_nodes.size()) - object.root;
    out_.objects.push_back(object);
    object_root_.push_back(root);
    object_of_[root] = index;
    return index | kPfdObjectBit;
  }

  // The references `ids` (fragments and object marks) make, appended to `items`: a run per stretch
  // of fragments, an object entry per mark.
  void appendRefs(const std::vector<uint32_t>& ids, std::vector<uint32_t>& items) {
    splitMarks(
        ids, [&](int32_t root) { items.push_back(objectRef(root)); },
        [&](std::span<const uint32_t> f) {
          plain_.assign(f.begin(), f.end());
          items.push_back(store_.findOrAddRun(plain_));
        });
  }

  // One reference for `ids` (fragments and object marks): a run, an object, or a sequence of them.
  uint32_t findOrAddRef(const std::vector<uint32_t>& ids) {
    ref_items_.clear();
    appendRefs(ids, ref_items_);
    if (ref_items_.size() == 1) return ref_items_[0];
    uint64_t length = 0;
    for (uint32_t x : ref_items_) length += store_.refLength(x);
    return store_.findOrAddSeq(ref_items_, static_cast<uint32_t>(length));
  }

  void addFragments(std::span<const uint32_t> ids, const Region& r) {
    if (ids.empty()) return;
    std::vector<uint32_t>& v = run_scratch_;
    v.clear();
    if (hfd()) {
      filterVisible(ids, r, v);
    } else {
      v.assign(ids.begin(), ids.end());
    }
    if (v.empty()) return;
    list_fragments += v.size();
    out_.run_refs.push_back(options_.dedup ? store_.findOrAddRun(v) : store_.newRun(v));
  }

  void addRunRef(uint32_t ref) {
    if (ref == kEmptyRun) return;
    list_fragments += store_.refLength(ref);
    out_.run_refs.push_back(ref);
  }

 public:
  uint64_t bytesNow() const {
    // Arrays at their sizes, the hash indexes at about 48 bytes an entry (node + bucket), the
    // memo's keys and contents; the undo logs and scratch are small beside them.
    return out_.nodes.size() * sizeof(PfdNode) + out_.run_refs.size() * sizeof(uint32_t) +
           out_.runs.size() * (sizeof(PfdRun) + (options_.dedup ? 48 : 0)) +
           out_.fragment_ids.size() * sizeof(uint32_t) + out_.planes.size() * sizeof(Plane) +
           memo_entries_.size() * (sizeof(MemoEntry) + 48) + key_pool_.size() * sizeof(uint64_t) +
           memo_pool_.size() * sizeof(uint32_t) + out_.seqs.size() * (sizeof(PfdSeq) + 1 + 48) +
           out_.seq_items.size() * sizeof(uint32_t) + out_.objects.size() * sizeof(PfdObject) +
           out_.object_nodes.size() * sizeof(PfdObjectNode);
  }

 private:
  void checkBudget() const {
    if (options_.max_memory == 0) return;
    const uint64_t bytes = bytesNow();
    if (bytes > options_.max_memory)
      throw PfdBudgetError("pfd: tree needs more than its memory budget of " + std::to_string(options_.max_memory) +
                               " bytes (" + std::to_string(out_.nodes.size()) + " nodes, " +
                               std::to_string(out_.fragment_ids.size() + out_.run_refs.size()) +
                               " list entries so far); raise --max-memory or use smaller view cells",
                           bytes, out_.stats.region_area > 0.0 ? std::min(1.0, done_area_ / out_.stats.region_area) : 0.0);
  }

  // Undecided lines ahead in the traversal (the first crossing line first), for the heuristic.
  // HFD: only from the subtree that stopped the traversal (the others may turn out hidden).
  LineCandidates candidates(uint32_t first, const std::vector<Item>& stack, const Region& r) {
    LineCandidates out;
    std::vector<uint32_t>& result = out.lines;
    result.push_back(first);
    if (options_.heuristic == PfdHeuristic::kTraversal || options_.candidates <= 1) return out;
    std::vector<int32_t> queue;
    size_t examined = 0;
    const size_t max_examined = 8 * static_cast<size_t>(options_.candidates);
    const size_t lowest = hfd() && !stack.empty() ? stack.size() - 1 : 0;
    const bool deep = options_.deep_candidates && !hfd();
    out.complete = deep;
    for (size_t k = stack.size(); k-- > lowest && result.size() < options_.candidates && examined < max_examined;) {
      if (stack[k].emit_side != 0) {
        // A node's own fragments' lines (orientation 0) are not gathered here.
        const BspNode& own = bsp_.nodes[stack[k].node];
        for (uint32_t f = own.first_fragment; f < own.first_fragment + own.fragment_count; ++f) {
          const uint32_t fl = lines_.fragmentLine(f);
          if (fl != UINT32_MAX && fl != first && lines_.side(fl, r) == kCross) out.complete = false;
        }
        continue;
      }
      queue.assign(1, stack[k].node);
      for (size_t q = 0; q < queue.size() && result.size() < options_.candidates && examined < max_examined; ++q) {
        const int32_t id = queue[q];
        if (id < 0) continue;
        ++examined;
        if (vary_range_[id].first == vary_range_[id].second) continue;  // no line in it crosses
        const int s = lines_.side(static_cast<uint32_t>(id), r);
        if (s == kCross) {
          if (static_cast<uint32_t>(id) != first) result.push_back(static_cast<uint32_t>(id));
          // Lines beyond it are reached by the traversal only after it is decided, but each is
          // tested somewhere below anyway (PfdOptions::deep_candidates).
          if (!deep) continue;
        }
        queue.push_back(bsp_.nodes[id].front);
        queue.push_back(bsp_.nodes[id].back);
      }
    }
    if (result.size() >= options_.candidates || examined >= max_examined) out.complete = false;
    return out;
  }

  // The line node `node` tests (`first`: the crossing line that stopped the traversal): a plan's,
  // or chosen among the root's candidates or, where those do not cover every line still to be
  // tested, the traversal's own.
  uint32_t chooseLine(uint32_t first, const std::vector<Item>& stack, const Region& r, int32_t node) {
    if (const std::optional<uint32_t> planned = choice_.plannedLine(r, path_lines_, path_sides_)) return *planned;
    LineCandidates found = node == 0 ? choice_.rootCandidates(first, r) : LineCandidates{};
    if (!found.complete) found = candidates(first, stack, r);
    return choice_.choose(first, found, r, rings(r), node, path_lines_.size());
  }

  // A line that crosses r only in a sliver (see trimSlivers: narrower than sliver_tol_, the
  // rounding of plane coefficients) trims r to its other side, exactly, instead of being tested:
  // the lists emitted so far hold for any part of r, and the line then only touches r. Where two
  // walls' lines nearly coincide, the slivers appear only once one of them bounds the region, so
  // this is done at every node, not only on W. Returns whether r changed.
  bool trimSliver(Region& r, uint32_t id) {
    if (!options_.trim_slivers) return false;
    const Line& l = lines_.line(id);
    const int sliver = sliverSide(r, l, sliver_tol_, true);  // called for crossing lines only
    if (sliver == 0) return false;
    Region front, back;
    clipRegion(r, l, lines_.counters, &front, &back);
    Region& keep = sliver > 0 ? back : front;
    if (keep.empty()) return false;
    r = std::move(keep);
    lines_.enterRegion();  // cached crossings and rings were of the untrimmed region
    return true;
  }

  // Drops the pieces of r narrower than sliver_tol_ (twice the area over the box's diagonal), while
  // a wider one remains. A line that crosses one piece and grazes another leaves a needle of the
  // second on its far side (two walls' lines 6e-14 apart: freedoom2 MAP04 level 1, a needle of
  // area 3e-11 and length 18), which every line along it then crosses: the eyes there leave W, as
  // at trimSlivers, instead of costing tests for leaves of no width. The search's model never
  // sees such a needle (it cuts piece by piece, with the same sliver rule), so its plan lasts.
  void dropNeedles(Region& r) const {
    if (!options_.trim_slivers || r.size() < 2) return;
    auto thin = [&](const Piece& p) {
      return 2.0 * pieceArea(p) < sliver_tol_ * std::hypot(p.hix - p.lox, p.hiz - p.loz);
    };
    if (std::all_of(r.begin(), r.end(), thin)) return;
    r.erase(std::remove_if(r.begin(), r.end(), thin), r.end());
  }

  std::vector<uint32_t> path_lines_;  // canonical ids of the lines tested on the way to this node
  std::vector<int8_t> path_sides_;    // and the side taken after each (+1 front, -1 back)
  static constexpr uint32_t kMaxTrimsPerNode = 64;  // a guard: each trim removes a line's crossing

  uint32_t testPlaneIndex(uint32_t line) {
    if (test_plane_[line] == UINT32_MAX) {
      test_plane_[line] = static_cast<uint32_t>(out_.planes.size());
      out_.planes.push_back(lines_.plane(line));
    }
    return test_plane_[line];
  }

  // Builds the node for region r with the traversal continuing from `stack`; returns its index.
  int32_t build(Region r, std::vector<Item> stack, uint64_t depth) {
    const int32_t index = static_cast<int32_t>(out_.nodes.size());
    out_.nodes.push_back({});
    dropNeedles(r);
    lines_.enterRegion();
    depth_max = std::max(depth_max, depth);
    const uint32_t first_ref = static_cast<uint32_t>(out_.run_refs.size());
    uint32_t crossing = UINT32_MAX;
    uint32_t trims = 0;
    while (!stack.empty()) {
      const Item item = stack.back();
      const BspNode& node = bsp_.nodes[item.node];
      if (item.emit_side == 0 && object_[item.node] == 1) {
        stack.pop_back();
        addObject(item.node, r);
        continue;
      }
      if (item.emit_side == 0) {
        const int s = lines_.side(static_cast<uint32_t>(item.node), r);
        if (s == kCross) {
          // HFD: a subtree hidden from the whole region needs no test-line.
          const auto [fb, fe] = frag_range_[item.node];
          if (hfd() && allHidden(std::span<const uint32_t>(frag_pre_.data() + fb, fe - fb), r)) {
            stack.pop_back();
            continue;
          }
          if (trims < kMaxTrimsPerNode && trimSliver(r, static_cast<uint32_t>(item.node))) {
            ++trims;
            continue;  // the same item again, in the trimmed region
          }
          crossing = static_cast<uint32_t>(item.node);
          break;
        }
        if (resolved(item.node, r)) {
          stack.pop_back();
          if (toRefs()) {
            addRunRef(resolvedRef(item.node, r));
          } else {
            std::span<const uint32_t> content;
            resolvedEmission(item.node, r, content);
            addRun(content, r);
          }
          continue;
        }
        stack.pop_back();
        int32_t far_child, near_child;
        children(node, s, far_child, near_child);
        if (near_child >= 0) stack.push_back({near_child, 0});
        stack.push_back({item.node, static_cast<int8_t>(s == 0 ? kEmitOn : s)});
        if (far_child >= 0) stack.push_back({far_child, 0});
      } else {
        const uint32_t fl = crossingFragmentLine(node, r);
        if (fl != UINT32_MAX) {
          const std::span<const uint32_t> own = nodeFragments(node);
          if (hfd() && allHidden(own, r)) {
            stack.pop_back();
            continue;
          }
          if (trims < kMaxTrimsPerNode && trimSliver(r, fl)) {
            ++trims;
            continue;
          }
          crossing = fl;
          break;
        }
        stack.pop_back();
        scratch_.clear();
        emitFragments(node, item.emit_side == kEmitOn ? 0 : item.emit_side, r, scratch_);
        addRun(scratch_, r);
      }
    }
    out_.nodes[index].first_ref = first_ref;
    out_.nodes[index].ref_count = static_cast<uint32_t>(out_.run_refs.size()) - first_ref;
    checkBudget();
    if (crossing == UINT32_MAX) {
      double area = 0.0;
      for (const Piece& p : r) area += pieceArea(p);
      leaf_areas.push_back(area);
      done_area_ += area;
      if (options_.progress && out_.stats.region_area > 0.0)
        options_.progress(std::min(1.0, done_area_ / out_.stats.region_area));
      // Every tested line that bounds the leaf was tested on its path: a lower bound of its depth
      // that no order of the tests can beat (PfdStats::tests_cell_bound).
      uint32_t bounding = 0;
      for (size_t k = 0; k < path_lines_.size(); ++k) {
        const uint32_t canon = path_lines_[k];
        if (std::find(path_lines_.begin(), path_lines_.begin() + static_cast<std::ptrdiff_t>(k), canon) !=
            path_lines_.begin() + static_cast<std::ptrdiff_t>(k))
          continue;  // counted already
        bool on_edge = false;
        for (const Piece& p : r)
          on_edge |= std::find(p.edge_line.begin(), p.edge_line.end(), canon) != p.edge_line.end();
        bounding += on_edge;
      }
      leaf_bound_tests += area * bounding;
      leaf_depth_area += area * static_cast<double>(path_lines_.size());
      return index;
    }
    const uint32_t line = chooseLine(crossing, stack, r, index);
    Region front, back;
    clipRegion(r, lines_.line(line), lines_.counters, &front, &back);
    r.clear();
    r.shrink_to_fit();
    const size_t mark = lines_.mark(), hidden_mark = hidden_log_.size(), witness_mark = witness_log_.size();
    lines_.decide(line, 1);
    path_lines_.push_back(lines_.canon(line));
    path_sides_.push_back(1);
    const int32_t f = build(std::move(front), stack, depth + 1);
    undo(mark, hidden_mark, witness_mark);
    lines_.decide(line, -1);
    path_sides_.back() = -1;
    const int32_t b = build(std::move(back), std::move(stack), depth + 1);
    undo(mark, hidden_mark, witness_mark);
    path_lines_.pop_back();
    path_sides_.pop_back();
    choice_.leaveNode(index);
    out_.nodes[index].plane = testPlaneIndex(line);
    out_.nodes[index].front = f;
    out_.nodes[index].back = b;
    return index;
  }

  std::span<const uint32_t> nodeFragments(const BspNode& node) {
    node_frags_.clear();
    for (uint32_t f = node.first_fragment; f < node.first_fragment + node.fragment_count; ++f) node_frags_.push_back(f);
    return node_frags_;
  }

  const BspTree& bsp_;
  const PfdOptions& options_;
  PfdTree& out_;
  double height_ = 0.0;
  PfdLines lines_;
  double sliver_tol_ = 0.0;  // kSliverTolerance × the root region's extent
  PfdLineChoice choice_;
  std::vector<uint32_t> unresolved_stamp_;  // == lines_.regionStamp(): subtree not resolved in the current region
  std::vector<uint32_t> test_plane_;
  std::vector<uint32_t> vary_list_, frag_pre_;
  std::vector<std::pair<uint32_t, uint32_t>> vary_range_, frag_range_;
  std::vector<uint8_t> hidden_;      // HFD: hidden from an ancestor region on the current path
  std::vector<uint32_t> hidden_log_;
  // HFD: per fragment, the eye that last saw it on the current path (docs/DESIGN.md, "HFD tree":
  // a witness in a sub-region keeps the fragment with no new rays), with an undo log.
  struct WitnessEntry {
    uint32_t fragment;
    std::optional<glm::dvec2> point;  // what it was before
  };
  std::vector<std::optional<glm::dvec2>> witness_;
  std::vector<WitnessEntry> witness_log_;
  std::vector<glm::dvec2> witness_scratch_;
  std::vector<uint32_t> seen_;
  std::vector<uint32_t> frag_node_;
  std::vector<uint32_t> scratch_, run_scratch_, to_test_, node_frags_;
  std::vector<uint8_t> results_;
  std::vector<Item> walk_;
  std::vector<uint64_t> key_, key_pool_;
  std::vector<uint32_t> memo_pool_;
  std::vector<MemoEntry> memo_entries_;
  std::unordered_multimap<uint64_t, uint32_t> memo_;
  PfdRunStore store_{out_};  // the tree's runs and sequences, each equal one once
  std::vector<uint32_t> own_, flat_, acc_, items_, small_far_, small_near_;
  std::vector<RefFrame> ref_frames_;
  // Detail objects (PfdOptions::object_extent): per BSP node 1 at an object's root, 2 inside;
  // per node the object made for it; per object its BSP root. In id lists an object is the mark
  // kObjectMark | its BSP root (fragment ids stay below it).
  static constexpr uint32_t kObjectMark = 0x80000000u;
  const std::vector<uint8_t>& object_;
  const std::vector<std::pair<glm::dvec3, glm::dvec3>>& object_box_;  // per BSP node, its subtree's box
  static constexpr size_t kBoxMinFragments = 6;
  std::vector<uint32_t> object_of_;
  std::vector<int32_t> object_root_;
  std::vector<uint32_t> plain_, ref_items_;
  std::vector<std::vector<glm::dvec2>> rings_;
  uint32_t rings_stamp_ = 0;
};

}  // namespace

const char* treeKindName(TreeKind kind) {
  switch (kind) {
    case TreeKind::kPfd:
      return "pfd";
    case TreeKind::kHfd:
      return "hfd";
  }
  return "unknown";
}

PfdLineCount countPfdLines(const BspTree& bsp, std::span<const std::vector<glm::dvec2>> walkable, double height,
                           const std::optional<PfdBox>& cell, std::span<const uint8_t> objects,
                           const std::vector<uint32_t>* candidates, std::vector<uint32_t>* crossing) {
  if (!std::isfinite(height)) throw Error("pfd: height plane is not finite");
  Counters counters;
  const Region region = makeRegion(walkable, cell, counters);
  PfdLineCount count;
  for (const Piece& p : region) count.area += pieceArea(p);
  if (region.empty()) return count;
  if (!objects.empty() && objects.size() != bsp.nodes.size())
    throw Error("pfd: object node flags do not match the BSP");
  auto tryNode = [&](uint32_t i) {
    WALKVIS_DCHECK(i < bsp.nodes.size());
    if ((objects.empty() || objects[i] == 0) && classifyRegion(planeLine(bsp.nodes[i].plane, height), region, counters) == kCross) {
      ++count.crossing;
      if (crossing) crossing->push_back(i);
    }
  };
  if (candidates) {
    for (uint32_t i : *candidates) tryNode(i);
  } else {
    for (size_t i = 0; i < bsp.nodes.size(); ++i) tryNode(static_cast<uint32_t>(i));
  }
  return count;
}

PfdTree buildPfd(const BspTree& bsp, std::span<const std::vector<glm::dvec2>> walkable, double height,
                 const std::optional<PfdBox>& cell, const PfdOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (!std::isfinite(height)) throw Error("pfd: height plane is not finite");
  PfdTree tree;
  tree.height = height;
  tree.cell = cell;

  Counters counters;
  Region region = makeRegion(walkable, cell, counters);
  std::vector<std::pair<glm::dvec3, glm::dvec3>> object_boxes;
  const std::vector<uint8_t> objects =
      pfdObjectNodes(bsp, options.drop_back_faces ? options.object_extent : 0.0, &object_boxes);
  if (options.trim_slivers) trimSlivers(region, bsp, height, objects, counters);
  for (const Piece& p : region) {
    std::vector<glm::dvec2> ring;
    for (const Corner& k : p.corners) ring.emplace_back(k.ax, k.az);
    tree.region.push_back(std::move(ring));
    tree.stats.region_area += pieceArea(p);
  }

  Builder builder(bsp, height, options, region, objects, object_boxes, tree);
  if (!region.empty()) builder.run(std::move(region));
  else tree.nodes.push_back({});

  PfdStats& s = tree.stats;
  s.fragments = bsp.fragments.size();
  s.nodes = tree.nodes.size();
  s.leaves = std::max<uint64_t>(1, builder.leaf_areas.size());
  s.depth_max = builder.depth_max > 0 ? builder.depth_max - 1 : 0;
  s.list_entries = tree.run_refs.size();
  s.list_fragments = builder.list_fragments;
  s.pool_entries = tree.fragment_ids.size();
  s.runs = tree.runs.size();
  s.seqs = tree.seqs.size();
  s.seq_items = tree.seq_items.size();
  {
    std::vector<uint32_t> tested;
    for (const PfdNode& n : tree.nodes)
      if (n.front >= 0) tested.push_back(n.plane);
    std::sort(tested.begin(), tested.end());
    s.test_planes = static_cast<uint64_t>(std::unique(tested.begin(), tested.end()) - tested.begin());
  }
  s.objects = tree.objects.size();
  s.object_nodes = tree.object_nodes.size();
  for (const PfdObject& o : tree.objects) s.object_fragments += o.fragments;
  s.exact_fallbacks = counters.exact_fallbacks + builder.counters().exact_fallbacks;
  s.touching = builder.counters().touching;
  s.decisions = builder.counters().decisions;
  s.visibility_tests = builder.vis_counters.tests;
  s.visibility_rays = builder.vis_counters.rays;
  s.hidden_rejected = builder.hidden_rejected;
  s.visibility_witnessed = builder.visibility_witnessed;
  s.objects_box_rejected = builder.objects_box_rejected;
  s.visibility_hidden_rays = builder.vis_counters.hidden_rays;
  s.visibility_proved_hidden = builder.vis_counters.proved_hidden;
  s.visibility_proof_rays = builder.vis_counters.proof_rays;
  s.visibility_refine_rays = builder.vis_counters.refine_rays;
  s.visibility_refined_visible = builder.vis_counters.refined_visible;
  s.visibility_patch_covers = builder.vis_counters.patch_covers;
  s.visibility_kept_unproven = builder.vis_counters.kept_unproven;
  double entropy = 0.0;
  if (s.region_area > 0.0) {
    for (double a : builder.leaf_areas) {
      const double frac = a / s.region_area;
      if (frac > 0.0) entropy -= frac * std::log2(frac);
    }
  }
  s.tests_entropy_bound = entropy;
  s.tests_huffman_bound = huffmanMeanDepth(builder.leaf_areas);
  s.tests_cell_bound = s.region_area > 0.0 ? builder.leaf_bound_tests / s.region_area : 0.0;
  s.tests_area_mean = s.region_area > 0.0 ? builder.leaf_depth_area / s.region_area : 0.0;
  const RootSearch& root_search = builder.rootSearch();
  s.root_search_lines = root_search.lines;
  s.root_search_work_done = root_search.work_done;
  if (root_search.planned && root_search.area > 0.0) {
    s.tests_search_mean = root_search.cost / root_search.area;
    // The plan reached every leaf, and the exact tree costs what the double model said: then no
    // tree over these lines does better (the search's minimum), up to the model's rounding.
    s.tests_optimal = !root_search.plan_left &&
                      std::abs(s.tests_area_mean - s.tests_search_mean) <= kOptimalAgreement * std::max(1.0, s.tests_area_mean);
  }
  // A tree that meets a lower bound of every tree (no test at all, or Huffman's, or the cells') is
  // optimal whatever chose its tests.
  const double bound = std::max(s.tests_huffman_bound, s.tests_cell_bound);
  if (tree.nodes.size() == 1 || s.tests_area_mean <= bound * (1.0 + kOptimalAgreement)) s.tests_optimal = true;
  tree.nodes.shrink_to_fit();
  tree.run_refs.shrink_to_fit();
  tree.runs.shrink_to_fit();
  tree.fragment_ids.shrink_to_fit();
  tree.seqs.shrink_to_fit();
  tree.seq_items.shrink_to_fit();
  tree.object_nodes.shrink_to_fit();
  s.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  measurePfd(tree, options.stat_eyes, options.seed);
  return tree;
}

}  // namespace walkvis
