// Hidden-polygon rejection statistics of an HFD (or PFD) tree file (docs/DESIGN.md, "Hidden-polygon
// statistics"): at random eyes of every level, the fragments the tree lists are compared with
// those an exact 360° item buffer shows (six 90° cube faces, one Embree ray per pixel centre,
// walkthrough/raycast.h, front faces only).
//
// Per eye: listed = fragments of pfdQuery; visible = distinct fragments in the exact image;
// missed = visible − listed; error pixels = pixels showing a missed fragment. Per level and
// overall: means and maxima, pixel_error_ratio = error pixels / all pixels, rejection ratio
// = 1 − listed / N, overestimation = listed / visible (eyes that see nothing are left out of it),
// and histograms of missed fragments and of the per-eye pixel error.
//
// The overall figures are those of an eye placed uniformly by area over the whole building: each
// eye weighs its level's share of the area over the level's share of the eyes. Eyes are split
// among the levels by area too (so a landing does not get as many as a hall), with a few on every
// level for its own figures; within a level the weights are equal, so a level's figures are plain
// means. Sums, maxima and histograms count eyes and pixels unweighted.
// (In walkthrough/ rather than pfd_hfd/: it uses the exact ray caster of walkthrough/raycast.h,
// and walkvis_walkthrough already depends on walkvis_pfd_hfd.)
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "pfd_hfd/pfd.h"

namespace walkvis {

struct HfdStatsOptions {
  uint32_t views = 100;  // random eyes per level on average (> 0): about views × levels in all
  int res = 128;         // pixels per side of each cube face (> 0)
  uint64_t seed = 1;
  // false: a level with a share a of the region area gets max(round(a · views · levels),
  // min(views, kMinLevelEyes)) eyes; true: every level gets views eyes. The overall figures are
  // area-weighted either way.
  bool per_level = false;
};

// The fewest eyes a level gets when eyes are split by area: enough for a level's own figures to
// show a level that misses everywhere, few enough that a building of many small landings spends
// its eyes where people walk.
inline constexpr uint32_t kMinLevelEyes = 10;

struct HfdEyeStats {
  uint32_t level = 0;
  glm::dvec3 eye{0.0};
  uint32_t listed = 0;
  uint32_t visible = 0;
  uint32_t missed = 0;
  uint64_t error_pixels = 0;
  uint64_t pixels = 0;       // 6 · res², including pixels that show nothing
  uint32_t tests = 0;        // PFD tests made by the query
  double weight = 1.0;       // in the overall figures: the level's area share over its eye share
};

// Histogram bins: missed fragments per eye 0, 1, 2, 3, 4–7, 8–15, 16+; per-eye pixel error
// ratio 0, (0, 1e-6], (1e-6, 1e-5], (1e-5, 1e-4], (1e-4, 1e-3], (1e-3, 1e-2], > 1e-2.
inline constexpr const char* kMissedBins[] = {"0", "1", "2", "3", "4-7", "8-15", "16+"};
inline constexpr const char* kPixelErrorBins[] = {"0", "<=1e-6", "<=1e-5", "<=1e-4", "<=1e-3", "<=1e-2", ">1e-2"};

struct HfdSummary {
  uint64_t eyes = 0;
  uint64_t fragments = 0;  // N
  double listed_mean = 0.0, visible_mean = 0.0, missed_mean = 0.0;
  uint32_t listed_max = 0, visible_max = 0, missed_max = 0;
  uint64_t error_pixels = 0, pixels = 0;
  double pixel_error_ratio = 0.0;      // Σ weight · error pixels / Σ weight · pixels
  double pixel_error_ratio_max = 0.0;  // the worst eye
  double eyes_with_miss = 0.0;         // fraction of eyes that miss at least one visible fragment
  double rejection_ratio = 0.0;        // mean over eyes of 1 − listed / N
  double overestimation = 0.0;         // mean over eyes (visible > 0) of listed / visible
  double tests_mean = 0.0;
  std::vector<uint64_t> missed_histogram = std::vector<uint64_t>(7, 0);
  std::vector<uint64_t> pixel_error_histogram = std::vector<uint64_t>(7, 0);
};

struct HfdLevelSummary {
  uint32_t level = 0;
  double height = 0.0;
  HfdSummary summary;
};

struct HfdStats {
  std::vector<HfdLevelSummary> levels;  // levels with a non-empty tree, in file order
  HfdSummary overall;
  std::vector<HfdEyeStats> eyes;        // every eye, level by level
  double seconds = 0.0;
};

// Eyes are drawn per level uniformly by area over its cells' regions, as many per level as
// options.per_level says (deterministic in options.seed). `progress` (may be empty) gets a line now and then. Throws Error when
// options are out of range.
HfdStats computeHfdStats(const TreeFile& file, const HfdStatsOptions& options,
                         const std::function<void(const std::string&)>& progress = {});

}  // namespace walkvis
