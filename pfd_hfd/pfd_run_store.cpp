#include "pfd_hfd/pfd_run_store.h"

#include <algorithm>

#include "core/check.h"
#include "core/hash.h"

namespace walkvis {
namespace {

// FNV-1a over the ids as words, with a shift that mixes high bits down (ids are small numbers).
uint64_t hashIds(std::span<const uint32_t> ids) {
  uint64_t h = kFnvOffset ^ ids.size();
  for (uint32_t id : ids) {
    h = fnv1aWord(h, id);
    h ^= h >> 29;
  }
  return h;
}

}  // namespace

uint32_t PfdRunStore::newRun(std::span<const uint32_t> ids) {
  const uint32_t id = static_cast<uint32_t>(tree_.runs.size());
  if (id >= kPfdObjectBit) throw PfdBudgetError("pfd: more than 2^30 runs");
  tree_.runs.push_back({static_cast<uint32_t>(tree_.fragment_ids.size()), static_cast<uint32_t>(ids.size())});
  tree_.fragment_ids.insert(tree_.fragment_ids.end(), ids.begin(), ids.end());
  return id;
}

uint32_t PfdRunStore::findOrAddRun(std::span<const uint32_t> ids) {
  const uint64_t h = hashIds(ids);
  auto [lo, hi] = run_index_.equal_range(h);
  for (auto it = lo; it != hi; ++it) {
    const PfdRun& run = tree_.runs[it->second];
    if (run.count == ids.size() && std::equal(ids.begin(), ids.end(), tree_.fragment_ids.begin() + run.first))
      return it->second;
  }
  const uint32_t run_id = newRun(ids);
  run_index_.emplace(h, run_id);
  return run_id;
}

uint32_t PfdRunStore::findOrAddSeq(std::span<const uint32_t> items, uint32_t length) {
  const uint64_t h = hashIds(items) ^ 0x5bd1e995ull;  // apart from the runs' hashes of the same words
  auto [lo, hi] = seq_index_.equal_range(h);
  for (auto it = lo; it != hi; ++it) {
    const PfdSeq& q = tree_.seqs[it->second];
    if (q.count == items.size() && std::equal(items.begin(), items.end(), tree_.seq_items.begin() + q.first))
      return it->second | kPfdSeqBit;
  }
  const uint32_t id = static_cast<uint32_t>(tree_.seqs.size());
  if (id >= kPfdObjectBit) throw PfdBudgetError("pfd: more than 2^30 sequences");
  uint32_t depth = 0;
  for (uint32_t item : items) depth = std::max(depth, refDepth(item));
  WALKVIS_DCHECK(depth < kPfdMaxSeqDepth);  // the builder inlines a sequence at the limit
  tree_.seqs.push_back({static_cast<uint32_t>(tree_.seq_items.size()), static_cast<uint32_t>(items.size()), length});
  tree_.seq_items.insert(tree_.seq_items.end(), items.begin(), items.end());
  seq_depth_.push_back(static_cast<uint8_t>(depth + 1));
  seq_index_.emplace(h, id);
  return id | kPfdSeqBit;
}

uint32_t PfdRunStore::refLength(uint32_t ref) const {
  if (ref == kPfdEmptyRef) return 0;
  if (ref & kPfdSeqBit) {
    WALKVIS_DCHECK((ref & ~kPfdSeqBit) < tree_.seqs.size());
    return tree_.seqs[ref & ~kPfdSeqBit].length;
  }
  if (ref & kPfdObjectBit) {
    WALKVIS_DCHECK((ref & ~kPfdObjectBit) < tree_.objects.size());  // objects are added before they are asked about
    return tree_.objects[ref & ~kPfdObjectBit].fragments;
  }
  WALKVIS_DCHECK(ref < tree_.runs.size());
  return tree_.runs[ref].count;
}

}  // namespace walkvis
