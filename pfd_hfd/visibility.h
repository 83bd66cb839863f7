// Point-sampled area-to-area visibility for the HFD tree (James & Day, "The hidden face
// determination tree", 1998 [JamesDay1998HFD]; docs/DESIGN.md, "HFD tree"): is a BSP fragment
// visible from some point of a
// region of the height plane? Rays run from sample points of the region (at the plane's height) to
// sample points of the fragment (inset from its edges); one unblocked ray keeps the fragment, none
// rejects it. The blockers are every fragment of the BSP: those drawn earlier lie behind the
// fragment for every eye of the region, so one Embree scene of the whole model answers for all.
//
// Usage (Embree style): build once, then query from any number of threads (queries are const and
// allocate nothing after a warm-up of their thread-local scratch; counters are the caller's).
// Deterministic: the samples depend only on the options' seed, the fragment and the region, never
// on thread order.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "bsp/bsp.h"

namespace walkvis {

struct VisibilityOptions {
  // Defaults from the speed-against-error sweeps of `walkvis bench hfd` (docs/hfd/README.md, "HFD
  // sampling sweeps"): refinement buys far more accuracy per ray than uniform samples. Where one
  // room's walls are tested from a region of many, samples in front of the fragment (near_samples)
  // cut the false-hidden rate at the same rays (docs/hfd/README.md, "Samples in front of the
  // fragment").
  uint32_t region_samples = 16;  // points on the region per test (stratified by area, plus its boundary)
  uint32_t polygon_samples = 8;  // points on the fragment per test, inset from its edges
  uint32_t refine_rays = 256;    // extra rays spent where visibility changes (0: uniform sampling only)
  uint64_t seed = 1;
  // Rays at most spent per test trying to prove the fragment hidden outright (every sub-cone of
  // region-to-fragment segments crossing one blocker's outline; exact, so it never loses a visible
  // fragment), after the first packet of uniform rays; 0: off. Not stored in tree files.
  uint32_t proof_rays = 64;
  // A quarter of the region samples stand in front of the fragment (the region's nearest points
  // to points out along its normal) instead of inside by area. Not stored in tree files.
  bool near_samples = true;
  // The proof may join blockers across shared edges into one occluding patch (occluder fusion:
  // a corridor's walls hide what lies past its bend together). Not stored in tree files.
  bool fuse_occluders = true;
  // Conservative: a fragment is rejected only when the proof shows it hidden from the whole
  // region (but for the band of eyes within 4e-6 of the extent of its edges); a test the
  // proof cannot settle, within conservative_proof_rays, keeps the fragment (no witness then).
  // Not stored in tree files.
  bool conservative = false;
  uint32_t conservative_proof_rays = 256;
  // Sampled verdicts are taken only from regions of at most this area; a test from a larger one
  // is conservative (sampling a large region thinly is where misses come from). Not stored in
  // tree files.
  double sampled_max_area = std::numeric_limits<double>::infinity();
};

struct VisibilityCounters {
  uint64_t tests = 0;    // fragment-versus-region queries
  uint64_t rays = 0;     // occlusion rays cast
  uint64_t visible = 0;  // queries answered "visible"
  uint64_t hidden_rays = 0;  // rays of the queries answered "hidden" (counted by visibleBatch)
  uint64_t proved_hidden = 0;  // queries answered "hidden" by the proof (a blocker or a patch per sub-cone)
  uint64_t proof_rays = 0;     // rays cast by that proof (answered or not)
  uint64_t refine_rays = 0;    // rays cast by the refinement past blockers' edges
  uint64_t refined_visible = 0;  // queries answered "visible" by the refinement (uniform rays missed them)
  uint64_t patch_covers = 0;   // proof sub-cones covered by a patch of joined outlines, not by one
  uint64_t kept_unproven = 0;  // conservative: queries answered "visible" because nothing was proved
  void add(const VisibilityCounters& o) {
    tests += o.tests;
    rays += o.rays;
    visible += o.visible;
    hidden_rays += o.hidden_rays;
    proved_hidden += o.proved_hidden;
    proof_rays += o.proof_rays;
    refine_rays += o.refine_rays;
    refined_visible += o.refined_visible;
    patch_covers += o.patch_covers;
    kept_unproven += o.kept_unproven;
  }
};

class VisibilityScene {
 public:
  // All fragments of `bsp` as blockers (one Embree device and scene, committed). Throws Error
  // when Embree cannot be initialised.
  static VisibilityScene build(const BspTree& bsp, const VisibilityOptions& options = {});
  VisibilityScene(VisibilityScene&&) noexcept;
  VisibilityScene& operator=(VisibilityScene&&) noexcept;
  ~VisibilityScene();

  // True when some sampled ray from `region` (convex (x, z) pieces at y = height, any
  // orientation; zero-area pieces ignored; must not be empty) to fragment `fragment` of the BSP
  // is unblocked. False means hidden from every sample (the one approximation of the HFD tree).
  // When visible and `witness` is given, *witness is the (x, z) of that ray's eye: a point of the
  // region from which the fragment is seen, so every sub-region holding it sees it too; NaN when
  // the conservative mode keeps a fragment no ray was seen to reach.
  bool visibleFromRegion(uint32_t fragment, std::span<const std::vector<glm::dvec2>> region, double height,
                         VisibilityCounters& counters, glm::dvec2* witness = nullptr) const;

  // The same test for the surface of an axis-aligned box lo..hi, face by face: false when every
  // face is hidden from every sample (or, conservative, proved hidden). Whatever the box holds is
  // then hidden too, since a ray to any point inside meets the box's surface first with the same
  // stretch behind it. True when the region's bounds meet the box's footprint at a height inside
  // it (an eye may stand within the box). Used to drop a detail object whole.
  bool boxVisibleFromRegion(const glm::dvec3& lo, const glm::dvec3& hi, std::span<const std::vector<glm::dvec2>> region,
                            double height, VisibilityCounters& counters) const;

  const VisibilityOptions& options() const;

  // One line on the Embree build in use: version and which ray packet widths it runs natively
  // (the queries cast packets of 16; a width that is not native is emulated, slower).
  std::string deviceInfo() const;

  // True when the segment from `from` to `to` meets the front side of some fragment (the same
  // blockers and intersection filter as the queries; no end gap). For throughput benchmarks.
  bool occluded(const glm::dvec3& from, const glm::dvec3& to) const;

 private:
  struct Impl;
  explicit VisibilityScene(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace walkvis
