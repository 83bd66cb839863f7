// walkvis stats FILE [--views N] [--per-level] [--res PIXELS] [--seed S] [--json] [--csv FILE]: hidden-polygon
// rejection statistics of a tree file (walkthrough/hfd_stats.h; docs/DESIGN.md, "Hidden-polygon
// statistics"): per level and overall, listed / visible / missed fragments, pixel_error_ratio,
// rejection ratio and overestimation with means, maxima and histograms. Progress goes to stderr.
#include <cstdio>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "core/byte_io.h"
#include "pfd_hfd/pfd.h"
#include "walkthrough/hfd_stats.h"

namespace walkvis {
namespace {

struct StatsArgs {
  std::string file;
  HfdStatsOptions options;
  bool json = false;
  std::string csv;
};

nlohmann::ordered_json summaryJson(const HfdSummary& s) {
  nlohmann::ordered_json j;
  j["eyes"] = s.eyes;
  j["fragments"] = s.fragments;
  j["listed_mean"] = s.listed_mean;
  j["listed_max"] = s.listed_max;
  j["visible_mean"] = s.visible_mean;
  j["visible_max"] = s.visible_max;
  j["missed_mean"] = s.missed_mean;
  j["missed_max"] = s.missed_max;
  j["eyes_with_miss"] = s.eyes_with_miss;
  j["error_pixels"] = s.error_pixels;
  j["pixels"] = s.pixels;
  j["pixel_error_ratio"] = s.pixel_error_ratio;
  j["pixel_error_ratio_max"] = s.pixel_error_ratio_max;
  j["rejection_ratio"] = s.rejection_ratio;
  j["overestimation"] = s.overestimation;
  j["tests_mean"] = s.tests_mean;
  nlohmann::ordered_json mh, ph;
  for (size_t b = 0; b < s.missed_histogram.size(); ++b) mh[kMissedBins[b]] = s.missed_histogram[b];
  for (size_t b = 0; b < s.pixel_error_histogram.size(); ++b) ph[kPixelErrorBins[b]] = s.pixel_error_histogram[b];
  j["missed_histogram"] = mh;
  j["pixel_error_histogram"] = ph;
  return j;
}

void printSummary(const char* name, const HfdSummary& s) {
  std::printf("%-10s eyes %5llu  N %7llu  listed %9.1f (max %6u)  visible %7.1f (max %5u)  missed %6.3f (max %3u, "
              "%5.1f%% of eyes)\n",
              name, static_cast<unsigned long long>(s.eyes), static_cast<unsigned long long>(s.fragments),
              s.listed_mean, s.listed_max, s.visible_mean, s.visible_max, s.missed_mean, s.missed_max,
              100.0 * s.eyes_with_miss);
  std::printf("%-10s pixel_error_ratio %.3g (worst eye %.3g)  rejection %.4f  overestimation %.2f  tests %.1f\n", "",
              s.pixel_error_ratio, s.pixel_error_ratio_max, s.rejection_ratio, s.overestimation, s.tests_mean);
  std::printf("%-10s missed/eye:", "");
  for (size_t b = 0; b < s.missed_histogram.size(); ++b)
    std::printf(" %s:%llu", kMissedBins[b], static_cast<unsigned long long>(s.missed_histogram[b]));
  std::printf("   pixel error/eye:");
  for (size_t b = 0; b < s.pixel_error_histogram.size(); ++b)
    std::printf(" %s:%llu", kPixelErrorBins[b], static_cast<unsigned long long>(s.pixel_error_histogram[b]));
  std::printf("\n");
}

int runStats(const StatsArgs& args) {
  const TreeFile file = loadTreeFile(args.file);
  const HfdStats stats = computeHfdStats(file, args.options, [](const std::string& line) {
    std::fprintf(stderr, "%s\n", line.c_str());
  });
  if (!args.csv.empty()) {
    std::ostringstream csv;
    csv << "level,x,y,z,listed,visible,missed,error_pixels,pixels,tests,weight\n";
    csv.precision(17);
    for (const HfdEyeStats& e : stats.eyes)
      csv << e.level << ',' << e.eye.x << ',' << e.eye.y << ',' << e.eye.z << ',' << e.listed << ',' << e.visible
          << ',' << e.missed << ',' << e.error_pixels << ',' << e.pixels << ',' << e.tests << ',' << e.weight << '\n';
    writeTextFileAtomically(args.csv, csv.str(), "the eye table");
  }
  if (args.json) {
    nlohmann::ordered_json j;
    j["file"] = args.file;
    j["tree"] = treeKindName(file.kind);
    j["region_samples"] = file.visibility.region_samples;
    j["polygon_samples"] = file.visibility.polygon_samples;
    j["refine_rays"] = file.visibility.refine_rays;
    j["views"] = args.options.views;
    j["eyes_split"] = args.options.per_level ? "per_level" : "by_area";
    j["res"] = args.options.res;
    j["seed"] = args.options.seed;
    j["seconds"] = stats.seconds;
    j["overall"] = summaryJson(stats.overall);
    // The headline keys at the top level too, for scripts.
    j["pixel_error_ratio"] = stats.overall.pixel_error_ratio;
    j["rejection_ratio"] = stats.overall.rejection_ratio;
    j["overestimation"] = stats.overall.overestimation;
    j["missed_mean"] = stats.overall.missed_mean;
    auto levels = nlohmann::ordered_json::array();
    for (const HfdLevelSummary& l : stats.levels) {
      nlohmann::ordered_json lj = summaryJson(l.summary);
      lj["level"] = l.level;
      lj["height"] = l.height;
      levels.push_back(lj);
    }
    j["levels"] = levels;
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("%s: %s tree, %d px cube faces, %llu eyes (%s), overall figures weighted by area, %.1f s\n",
              args.file.c_str(), treeKindName(file.kind), args.options.res,
              static_cast<unsigned long long>(stats.overall.eyes),
              args.options.per_level ? "the same number per level" : "split among levels by area", stats.seconds);
  for (const HfdLevelSummary& l : stats.levels) {
    char name[32];
    std::snprintf(name, sizeof name, "level %u", l.level);
    printSummary(name, l.summary);
  }
  printSummary("overall", stats.overall);
  return 0;
}

}  // namespace

void addStatsCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<StatsArgs>();
  CLI::App* sub = app.add_subcommand("stats", "Hidden-polygon rejection statistics of a tree file against exact "
                                              "360-degree item buffers");
  sub->add_option("file", args->file, "Tree file (walkvis build --tree pfd|hfd)")->required();
  sub->add_option("--views", args->options.views,
                  "Random eyes per level on average (split among levels by area, at least " +
                      std::to_string(kMinLevelEyes) + " each)")
      ->check(CLI::Range(1u, 1000000u));
  sub->add_flag("--per-level", args->options.per_level,
                "The same number of eyes (--views) on every level instead of a split by area (the overall figures "
                "stay area-weighted)");
  sub->add_option("--res", args->options.res, "Pixels per side of each of the six cube faces")
      ->check(CLI::Range(1, 8192));
  sub->add_option("--seed", args->options.seed, "Seed of the eyes");
  sub->add_flag("--json", args->json, "One JSON object on stdout");
  sub->add_option("--csv", args->csv, "Write one row per eye to this file");
  sub->callback([args, &runner] { runner = [args] { return runStats(*args); }; });
}

}  // namespace walkvis
