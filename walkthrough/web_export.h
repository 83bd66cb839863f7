// A building and its HFD trees as a static web page (`walkvis export FILE --web DIR`): index.html,
// the viewer scripts (walkthrough/web/, embedded in the binary), one binary of the building and
// one per view cell's tree, in the format docs/web/README.md describes (versioned, little-endian,
// each section checksummed with FNV-1a 64 and deflated where that is smaller).
//
// The page walks the building by the C++ rules, ported (walkthrough/web/viewer.js): the order of
// a frame is FrameBuilder::build's for mode hfd with no backface culling, the walking is Walker's,
// the camera is clipFromEyeRelative(FreeCamera)'s. The automatic tour is computed here and stored,
// so `index.html?frame=K` shows the view `walkvis render` draws for key K of the same tour.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "walkthrough/frame.h"
#include "walkthrough/movement.h"

namespace walkvis {

struct WebExportOptions {
  uint32_t tour_frames = 120;  // keys of the automatic tour stored for ?frame=K (automaticTour, 30 fps)
  MoveOptions move;            // the walker's radius and step, as the window uses
  bool deflate = true;         // store a section deflated where that is smaller (false: every section raw)
};

struct WebSectionBytes {
  std::string tag;
  uint64_t bytes = 0;   // the section's bytes (CELL: all view cells together)
  uint64_t stored = 0;  // as stored in walkvis.bin (deflated where smaller)
};

struct WebExportReport {
  std::vector<WebSectionBytes> sections;  // walkvis.bin's in file order, then CELL (all cell files)
  uint64_t binary_bytes = 0;  // walkvis.bin
  uint64_t cell_bytes = 0;    // cells/K.bin, all together
  uint64_t script_bytes = 0;  // walkvis-data.js and cells/K.js: the same bytes in base64, for file://
  uint64_t page_bytes = 0;    // index.html and the viewer scripts
  uint32_t cells = 0;
  uint32_t tour_keys = 0;
};

// The binaries: walkvis.bin (the building, its walking floors, the tour, and META's list of view
// cells) and each view cell's tree as a container of its own (cells/K.bin, K in META's order), so
// that a page fetches only the cells it stands in. `world` must hold HFD trees (Error otherwise).
// Deterministic.
struct WebExportFiles {
  std::vector<uint8_t> binary;
  std::vector<std::vector<uint8_t>> cells;
};
WebExportFiles webExportFiles(const World& world, const WebExportOptions& options = {},
                              WebExportReport* report = nullptr);

// The scripts a page opened from file:// loads instead (browsers refuse fetch() there, not
// <script src>): walkvis-data.js is one call walkvisData("<base64 of walkvis.bin>"), cells/K.js
// one call walkvisCell(K, "<base64 of cells/K.bin>").
std::string webDataScript(std::span<const uint8_t> bytes);
std::string webCellScript(uint32_t k, std::span<const uint8_t> bytes);

// Writes the folder: index.html, viewer.js, page.js, walkvis.bin, walkvis-data.js and cells/K.bin,
// cells/K.js, each through a temporary file and a rename; cell files of an earlier export there
// that this one lacks are removed. Error naming the folder or file that cannot be written.
WebExportReport writeWebExport(const World& world, const std::string& dir, const WebExportOptions& options = {});

// The embedded page files (web_assets.cpp, generated from walkthrough/web/ at build time).
struct WebAsset {
  const char* name;
  const unsigned char* data;
  size_t size;
};
std::vector<WebAsset> webAssets();

}  // namespace walkvis
