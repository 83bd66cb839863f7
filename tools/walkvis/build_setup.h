// What `walkvis build` and `walkvis plan` share: the build's options on the command line and the
// inputs every build computes before its trees (the scene, the BSP, the visibility scene).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "pfd_hfd/pfd.h"
#include "pfd_hfd/visibility.h"

namespace walkvis {

// Bytes as parseSize reads them back: "1G", "64M", "512k" for whole binary multiples, else digits.
std::string formatSize(uint64_t bytes);

// Defaults come from the options structs, so each knob is declared once.
struct BuildArgs {
  SceneArgs scene;
  std::string output;
  std::string tree = "pfd";
  std::string max_memory = formatSize(PfdLevelOptions{}.max_memory);
  std::string cell_memory = formatSize(PfdLevelOptions{}.cell_memory);
  std::string heuristic = "balanced";
  double object_extent = PfdLevelOptions{}.object_extent;
  std::string samples;  // hfd: R,P,REFINE
  std::vector<uint32_t> levels;  // only these level indices; empty: all
  uint64_t visibility_seed = VisibilityOptions{}.seed;
  bool keep_back_faces = false;
  bool no_fuse_occluders = false;
  std::string visibility_mode = "sampled";
  double sampled_region_max = 0.0;
  bool no_dedup = false;
  bool no_object_boxes = false;
  uint32_t share_min = PfdOptions{}.share_min;
  uint32_t stat_eyes = PfdOptions{}.stat_eyes;
  uint32_t search_lines = PfdOptions{}.search_lines;
  uint64_t search_work = PfdOptions{}.search_work;
  uint32_t root_search_lines = PfdOptions{}.root_search_lines;
  uint64_t root_search_work = PfdOptions{}.root_search_work;
  uint32_t threads = 0;  // per process; 0: all cores, shared by the ranks on one machine under MPI
  bool fresh = false;
  bool json = false;
};

// The options that decide the trees (everything but the output, --threads, --fresh and --json).
void addBuildOptions(CLI::App& sub, BuildArgs& args);

// A build's inputs. Not movable: options.tree.visibility points at `visibility`.
struct BuildSetup {
  bool hfd = false;
  Scene scene;
  TreeFile file;  // eye height, kind, visibility options and the BSP; no levels yet
  std::optional<VisibilityScene> visibility;
  PfdLevelOptions options;
  std::vector<uint32_t> only;  // --levels, ascending, distinct
  double load_seconds = 0.0, visibility_seconds = 0.0;  // the BSP's time is in file.bsp.stats
};

// Checks the options, loads the scene, builds the BSP and (HFD) the visibility scene, saying each
// step to `progress`. Error on bad input.
std::unique_ptr<BuildSetup> prepareBuild(const BuildArgs& args, const std::function<void(const std::string&)>& progress);

}  // namespace walkvis
