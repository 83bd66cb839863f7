// The runs and sequences of a PFD or HFD tree being built: PfdTree::runs with fragment_ids, and
// PfdTree::seqs with seq_items, each equal list stored once (docs/DESIGN.md, "PFD tree": runs
// shared between nodes and orders stored as sequences of sub-orders). Internal to pfd_hfd (the
// builder, pfd_build_cgal.cpp); no CGAL.
#pragma once

#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "pfd_hfd/pfd.h"

namespace walkvis {

// No entry: an order that emits nothing.
constexpr uint32_t kPfdEmptyRef = UINT32_MAX - 1;

class PfdRunStore {
 public:
  // Appends to `tree`'s runs and sequences, which must outlive the store. The tree's objects must
  // be there before refLength is asked about them.
  explicit PfdRunStore(PfdTree& tree) : tree_(tree) {}

  // A new run of `ids`, even if an equal one exists. PfdBudgetError past 2^30 runs.
  uint32_t newRun(std::span<const uint32_t> ids);
  // The run equal to `ids` if one was added by findOrAddRun, else a new one.
  uint32_t findOrAddRun(std::span<const uint32_t> ids);
  // kPfdSeqBit | the sequence of `items` (run, object and sequence references) expanding to
  // `length` fragment ids: an equal one found by this call's way, else a new one. Its depth is one
  // more than its deepest item's. PfdBudgetError past 2^30 sequences.
  uint32_t findOrAddSeq(std::span<const uint32_t> items, uint32_t length);

  // Fragment ids a reference expands to (0 for kPfdEmptyRef).
  uint32_t refLength(uint32_t ref) const;
  // Nesting depth: 0 for a run or an object, 1 + the deepest item's for a sequence.
  uint32_t refDepth(uint32_t ref) const { return ref & kPfdSeqBit ? seq_depth_[ref & ~kPfdSeqBit] : 0; }

 private:
  PfdTree& tree_;
  std::unordered_multimap<uint64_t, uint32_t> run_index_, seq_index_;
  std::vector<uint8_t> seq_depth_;  // per sequence
};

}  // namespace walkvis
