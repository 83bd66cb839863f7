// PfdRunStore (pfd_hfd/pfd_run_store.h), against a brute-force map from lists to ids: equal lists
// get one id, different lists different ids, and every stored run or sequence reads back as the
// list it was made from. Random lists over a small alphabet (so that equal ones recur), fixed seeds.
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include "core/rng.h"
#include "pfd_hfd/pfd_run_store.h"

namespace walkvis {
namespace {

std::vector<uint32_t> randomList(Rng& rng, uint32_t max_len, uint32_t alphabet) {
  std::vector<uint32_t> v(rng.below(max_len + 1));
  for (uint32_t& x : v) x = static_cast<uint32_t>(rng.below(alphabet));
  return v;
}

TEST(PfdRunStore, EqualRunsShareOneIdAndReadBack) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    Rng rng{seed};
    PfdTree tree;
    PfdRunStore store(tree);
    std::map<std::vector<uint32_t>, uint32_t> seen;
    for (int k = 0; k < 2000; ++k) {
      const std::vector<uint32_t> ids = randomList(rng, 4, 3);
      const uint32_t id = store.findOrAddRun(ids);
      const auto [it, added] = seen.emplace(ids, id);
      EXPECT_EQ(it->second, id) << "an equal run got another id";
      if (added) {
        EXPECT_EQ(id + 1, tree.runs.size()) << "a new list must make a new run";
      }
      ASSERT_LT(id, tree.runs.size());
      const PfdRun& run = tree.runs[id];
      EXPECT_EQ(std::vector<uint32_t>(tree.fragment_ids.begin() + run.first,
                                      tree.fragment_ids.begin() + run.first + run.count),
                ids);
      EXPECT_EQ(store.refLength(id), ids.size());
      EXPECT_EQ(store.refDepth(id), 0u);
    }
    EXPECT_EQ(tree.runs.size(), seen.size());
  }
}

TEST(PfdRunStore, NewRunIsAlwaysNew) {
  PfdTree tree;
  PfdRunStore store(tree);
  const std::vector<uint32_t> ids = {4, 5, 6};
  const uint32_t a = store.newRun(ids), b = store.newRun(ids);
  EXPECT_NE(a, b);
  // findOrAddRun only finds what it added itself: newRun's runs are not indexed.
  const uint32_t c = store.findOrAddRun(ids);
  EXPECT_NE(c, a);
  EXPECT_NE(c, b);
  EXPECT_EQ(store.findOrAddRun(ids), c);
}

TEST(PfdRunStore, SequencesNestAndDeduplicate) {
  Rng rng{7};
  PfdTree tree;
  tree.objects.push_back({});
  tree.objects.back().fragments = 5;
  PfdRunStore store(tree);
  std::vector<uint32_t> runs;
  for (int k = 0; k < 6; ++k) runs.push_back(store.findOrAddRun(std::vector<uint32_t>{static_cast<uint32_t>(k), 9}));
  const uint32_t object = kPfdObjectBit | 0;
  EXPECT_EQ(store.refLength(object), 5u);
  EXPECT_EQ(store.refLength(kPfdEmptyRef), 0u);
  std::map<std::vector<uint32_t>, uint32_t> seen;
  std::vector<uint32_t> made;  // sequence references, to nest
  for (int k = 0; k < 500; ++k) {
    std::vector<uint32_t> items;
    const uint32_t n = 1 + static_cast<uint32_t>(rng.below(3));
    uint32_t length = 0, depth = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const uint64_t pick = rng.below(8);
      uint32_t ref = pick < 6 ? runs[pick] : pick == 6 ? object : (made.empty() ? runs[0] : made[rng.below(made.size())]);
      if (store.refDepth(ref) + 1 >= kPfdMaxSeqDepth) ref = runs[0];  // the builder inlines at the limit
      items.push_back(ref);
      length += store.refLength(ref);
      depth = std::max(depth, store.refDepth(ref));
    }
    const uint32_t q = store.findOrAddSeq(items, length);
    ASSERT_TRUE(q & kPfdSeqBit);
    const auto [it, added] = seen.emplace(items, q);
    EXPECT_EQ(it->second, q) << "an equal sequence got another id";
    if (added) made.push_back(q);
    const PfdSeq& s = tree.seqs[q & ~kPfdSeqBit];
    EXPECT_EQ(std::vector<uint32_t>(tree.seq_items.begin() + s.first, tree.seq_items.begin() + s.first + s.count),
              items);
    EXPECT_EQ(store.refLength(q), length);
    EXPECT_EQ(store.refDepth(q), depth + 1);
  }
  EXPECT_EQ(tree.seqs.size(), seen.size());
  uint32_t deepest = 0;
  for (uint32_t q : made) deepest = std::max(deepest, store.refDepth(q));
  EXPECT_GE(deepest, 3u) << "the random nesting should reach a few levels";
}

}  // namespace
}  // namespace walkvis
