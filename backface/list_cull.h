// Backface culling inside priority lists (docs/DESIGN.md, "Facing at emission"): a PFD/HFD
// query yields a handful of runs (ranges of one index array); each run gets its own culling
// structure, built once per tree (clusters formed per run), tested per frame for the runs a query
// yields. Also the whole-scene case (the BSP path and the z-buffer baseline): one run of all.
//
// Methods: none | polygon | mask | cluster | hierarchy | region. `mask` is Zhang & Hoff's mask
// from the view cone (view direction and field of view): conservative for what a frustum inside
// that cone can draw, not for front faces behind the eye. `region` is the exact build-time
// method: a tree built with drop_back_faces lists only front faces for every eye of the height
// plane, so nothing is left to do at run time; on a path without such lists (BSP, z-buffer) it
// falls back to the per-polygon plane test.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "backface/backface.h"

namespace walkvis {

enum class ListCullMethod : uint8_t { kNone, kPolygon, kMask, kCluster, kHierarchy, kRegion };
std::string_view listCullMethodName(ListCullMethod method);
ListCullMethod parseListCullMethod(std::string_view name);  // Error naming the choices otherwise

// Spare entries cullRange / cullRanges may write past the survivors (vector stores) before
// shrinking `out`: reserve them to keep the per-frame call free of allocation.
inline constexpr size_t kListCullOutSlack = 16;

struct IndexRange {
  uint32_t first = 0;  // into the index array given to build()
  uint32_t count = 0;
};

class ListCuller {
 public:
  // One culling structure per range of `indices` (polygon indices into input.polygons). Ranges may
  // overlap or repeat; empty ranges are allowed. Throws Error for a bad option or index.
  // mask (options.mask_cone kAuto or kView): Zhang & Hoff's mask from the view cone, one per call,
  // over the normal clusters of all positions (one byte per position where they use at most 256
  // clusters). mask with kGroups: each range is cut into chunks of options.mask_group_size
  // positions (0: one chunk), each with its own cone around its bounding sphere, except that a
  // chunk shorter than options.mask_list_min_chunk gets the plane test (a table costs more to build
  // than the plane test on a short chunk: docs/backface/README.md, "Lists (list_cull)"); cluster,
  // hierarchy: clusters are formed per range; cluster's culling probability is over
  // options.cluster_eye_lo/hi, by default the box of all input.vertices (the eyes of a walkthrough
  // are inside the scene).
  static ListCuller build(const BackfaceInput& input, std::span<const uint32_t> indices,
                          std::span<const IndexRange> ranges, ListCullMethod method,
                          const BackfaceOptions& options = {});
  ListCuller(ListCuller&&) noexcept;
  ListCuller& operator=(ListCuller&&) noexcept;
  ~ListCuller();

  // Appends the polygons of range `range` that survive culling for `view`, in the range's order,
  // to `out`; returns how many were culled. Never culls a polygon front-facing at view.eye, except
  // that mask with the view cone (kAuto, kView) may cull a front face that has no point inside the
  // cone (view_dir, fov): one that a frustum inside the cone clips away entirely. No
  // allocation once `out` has the capacity (capacity for out.size() + the range's count +
  // kListCullOutSlack). Not thread-safe for kCluster and kHierarchy (a scratch buffer of unit
  // flags; tracking state): one ListCuller per thread there. kRegion runs the plane test of
  // kPolygon (a caller that knows its lists hold only front faces, drop_back_faces, need not call
  // cullRange at all). Throws Error for a range index out of range (out unchanged then).
  // Same as cullRanges of the one range.
  uint32_t cullRange(uint32_t range, const BackfaceView& view, std::vector<uint32_t>& out) const;

  // cullRange of every range of `ranges`, in that order (ids may repeat; empty ranges add
  // nothing): appends the concatenation of their survivors to `out` and returns the number culled,
  // exactly as the calls one by one would. Made for all the runs of one query: the method is
  // picked once per call and the runs go through one loop (polygon, region and mask's plane-test
  // ranges: each distinct plane tested once per call, AVX-512 or AVX2 where the CPU has it, the same double
  // operations as isFrontFacing(), so the same result bit for bit). No allocation once `out` has
  // capacity for out.size() + the ranges' counts + kListCullOutSlack (`out` is resized once to
  // that size and shrunk to what survives). Throws Error, with `out` unchanged, if an id is
  // out of range.
  uint32_t cullRanges(std::span<const uint32_t> ranges, const BackfaceView& view, std::vector<uint32_t>& out) const;

  // mask: the positions (over all ranges) culled by a Zhang & Hoff table (all of them with the view
  // cone); with kGroups the others get the plane test (chunks under mask_list_min_chunk
  // positions). 0 for the other methods.
  uint64_t maskTablePositions() const;
  ListCullMethod method() const;
  size_t rangeCount() const;
  uint64_t bytes() const;  // per-frame test state of all ranges

 private:
  struct Impl;
  explicit ListCuller(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace walkvis
