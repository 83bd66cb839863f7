// Hidden-polygon rejection statistics (docs/DESIGN.md, "Hidden-polygon statistics"; the HFD tree
// of James & Day, "The hidden face determination tree", 1998 [JamesDay1998HFD]): listed fragments
// against an exact 360° item buffer (walkthrough/raycast.h) at random eyes of every level.
#include "walkthrough/hfd_stats.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "walkthrough/camera.h"
#include "walkthrough/raycast.h"

namespace walkvis {
namespace {

size_t missedBin(uint32_t missed) {
  if (missed < 4) return missed;
  if (missed < 8) return 4;
  if (missed < 16) return 5;
  return 6;
}

size_t pixelErrorBin(double ratio) {
  if (!(ratio > 0.0)) return 0;
  double bound = 1e-6;
  for (size_t b = 1; b < 6; ++b, bound *= 10.0)
    if (ratio <= bound) return b;
  return 6;
}

// Weighted means over eyes (walkthrough/hfd_stats.h: the weights are equal within a level).
HfdSummary summarise(std::span<const HfdEyeStats> eyes, uint64_t fragments) {
  HfdSummary s;
  s.fragments = fragments;
  double w_sum = 0, listed = 0, visible = 0, missed = 0, rejection = 0, tests = 0, missing = 0;
  double over = 0, over_w = 0, error_px = 0, px = 0;
  for (const HfdEyeStats& e : eyes) {
    const double w = e.weight;
    ++s.eyes;
    w_sum += w;
    listed += w * e.listed;
    visible += w * e.visible;
    missed += w * e.missed;
    tests += w * e.tests;
    error_px += w * static_cast<double>(e.error_pixels);
    px += w * static_cast<double>(e.pixels);
    s.listed_max = std::max(s.listed_max, e.listed);
    s.visible_max = std::max(s.visible_max, e.visible);
    s.missed_max = std::max(s.missed_max, e.missed);
    s.error_pixels += e.error_pixels;
    s.pixels += e.pixels;
    const double ratio = e.pixels ? static_cast<double>(e.error_pixels) / static_cast<double>(e.pixels) : 0.0;
    s.pixel_error_ratio_max = std::max(s.pixel_error_ratio_max, ratio);
    ++s.missed_histogram[missedBin(e.missed)];
    ++s.pixel_error_histogram[pixelErrorBin(ratio)];
    if (fragments) rejection += w * (1.0 - static_cast<double>(e.listed) / static_cast<double>(fragments));
    if (e.visible) {
      over += w * static_cast<double>(e.listed) / e.visible;
      over_w += w;
    }
    if (e.missed) missing += w;
  }
  if (!(w_sum > 0.0)) return s;
  s.listed_mean = listed / w_sum;
  s.visible_mean = visible / w_sum;
  s.missed_mean = missed / w_sum;
  s.rejection_ratio = rejection / w_sum;
  s.overestimation = over_w > 0.0 ? over / over_w : 0.0;
  s.tests_mean = tests / w_sum;
  s.eyes_with_miss = missing / w_sum;
  s.pixel_error_ratio = px > 0.0 ? error_px / px : 0.0;
  return s;
}

// Eyes per level (hfd_stats.h, HfdStatsOptions::per_level), from the levels' areas.
std::vector<uint32_t> eyesPerLevel(std::span<const double> area, const HfdStatsOptions& options) {
  double total = 0.0;
  uint32_t with_area = 0;
  for (const double a : area) {
    total += a;
    with_area += a > 0.0;
  }
  std::vector<uint32_t> n(area.size(), 0);
  const double all = static_cast<double>(options.views) * with_area;
  const uint32_t least = std::min(options.views, kMinLevelEyes);
  for (size_t l = 0; l < n.size(); ++l)
    if (area[l] > 0.0)
      n[l] = options.per_level ? options.views
                               : std::max(least, static_cast<uint32_t>(std::llround(all * area[l] / total)));
  return n;
}

}  // namespace

HfdStats computeHfdStats(const TreeFile& file, const HfdStatsOptions& options,
                         const std::function<void(const std::string&)>& progress) {
  if (options.views == 0 || options.res <= 0 || options.res > 8192)
    throw Error("stats: --views must be > 0 and --res in [1, 8192]");
  const auto t0 = std::chrono::steady_clock::now();
  const BspTree& bsp = file.bsp;
  const uint64_t n = bsp.fragments.size();
  HfdStats out;
  if (n == 0) return out;
  // Camera depth range: everything of the model from anywhere inside it. The rays are exact
  // visibility from the eye point, so near clips nothing the eye could see: region eyes stand as
  // close to a wall as they like, and a near plane beyond the wall sees through it (1e-6 of the
  // extent did, at eyes 0.0028 and 0.0036 units from a wall of freedoom2 MAP01, counting 133 and
  // 55 fragments behind it as missed). 1e-9 of the extent is below the single-precision rounding
  // of the coordinates (6e-8 of it), where the float scene cannot tell a side anyway.
  glm::dvec3 lo = bsp.vertices[0], hi = bsp.vertices[0];
  for (const auto& v : bsp.vertices) {
    lo = glm::min(lo, v);
    hi = glm::max(hi, v);
  }
  const double extent = std::max(glm::length(hi - lo), 1e-9);
  const RayCaster caster(bsp.vertices, bsp.fragments);
  std::vector<RayHit> hits;
  std::vector<uint32_t> order;
  std::vector<uint32_t> listed_stamp(n, 0), visible_stamp(n, 0);
  uint32_t stamp = 0;
  uint64_t rng = options.seed ^ 0x5DEECE66Dull;
  std::vector<double> area;
  double area_total = 0.0;
  for (const PfdLevel& level : file.levels) {
    area.push_back(pfdLevelArea(level));
    area_total += area.back();
  }
  const std::vector<uint32_t> wanted = eyesPerLevel(area, options);
  std::vector<size_t> first_eye(file.levels.size() + 1, 0);
  for (size_t li = 0; li < file.levels.size(); ++li) {
    const PfdLevel& level = file.levels[li];
    first_eye[li] = out.eyes.size();
    for (uint32_t k = 0; k < wanted[li]; ++k) {
      const std::optional<glm::dvec3> sampled = samplePfdLevel(level, rng);
      if (!sampled) break;  // no region area on this level
      const glm::dvec3 eye = *sampled;
      // The tree the walkthrough would use there (cells are half-open boxes covering the region).
      const PfdTree* tree = findPfdCell(level, eye);
      if (!tree) continue;  // exactly on the outer upper side of the cells: no tree holds it
      HfdEyeStats e;
      e.level = level.level;
      e.eye = eye;
      e.tests = pfdQuery(*tree, eye, order).tests;
      if (++stamp == 0) {  // wrapped: clear the stamps
        std::fill(listed_stamp.begin(), listed_stamp.end(), 0);
        std::fill(visible_stamp.begin(), visible_stamp.end(), 0);
        stamp = 1;
      }
      for (uint32_t f : order)
        if (f < n && listed_stamp[f] != stamp) {
          listed_stamp[f] = stamp;
          ++e.listed;
        }
      const std::vector<uint8_t> front = caster.frontFacing(eye);
      for (int face = 0; face < kCubeFaces; ++face) {
        View view;
        view.eye = eye;
        view.face = face;
        view.size = options.res;
        view.near = 1e-9 * extent;
        view.far = 4.0 * extent;
        caster.castNearest(view, front, hits);
        e.pixels += hits.size();
        for (const RayHit& h : hits) {
          if (h.polygon == kNoPolygon || h.polygon >= n) continue;
          if (visible_stamp[h.polygon] != stamp) {
            visible_stamp[h.polygon] = stamp;
            ++e.visible;
            if (listed_stamp[h.polygon] != stamp) ++e.missed;
          }
          if (listed_stamp[h.polygon] != stamp) ++e.error_pixels;
        }
      }
      out.eyes.push_back(e);
      if (progress && ((k + 1) % 50 == 0 || k + 1 == wanted[li])) {
        char line[160];
        std::snprintf(line, sizeof line, "stats: level %u: %u/%u eyes", level.level, k + 1, wanted[li]);
        progress(line);
      }
    }
  }
  first_eye.back() = out.eyes.size();
  // Weights from the eyes each level got (an eye on no cell's box is dropped), so that the overall
  // figures are area-weighted whatever the split.
  const double eyes_total = static_cast<double>(out.eyes.size());
  for (size_t li = 0; li < file.levels.size(); ++li) {
    const size_t count = first_eye[li + 1] - first_eye[li];
    const double weight = count ? (area[li] / area_total) / (count / eyes_total) : 0.0;
    for (size_t k = first_eye[li]; k < first_eye[li + 1]; ++k) out.eyes[k].weight = weight;
    HfdLevelSummary ls;
    ls.level = file.levels[li].level;
    ls.height = file.levels[li].height;
    // One weight for the whole level cancels: its figures are plain means.
    ls.summary = summarise(std::span<const HfdEyeStats>(out.eyes).subspan(first_eye[li], count), n);
    out.levels.push_back(ls);
  }
  out.overall = summarise(out.eyes, n);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace walkvis
