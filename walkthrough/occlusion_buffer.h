// Occlusion culling at run time, for one eye: a coarse depth buffer of a few large polygons of the
// frame's own list (the occluders), and a test that leaves out a polygon only when every pixel it
// can reach lies behind one of them. It is the from-point counterpart of the HFD tree's from-region
// rejection (docs/DESIGN.md, "Occlusion culling of a frame"): a region's list holds what some eye
// of the region sees, and the buffer takes out what this eye does not. Occluder fusion comes free,
// as in every image-space method [GreeneKassMiller1993, ZhangManochaHudsonHoff1997]: neighbouring
// occluders fill neighbouring cells.
//
// The contract, in pixels of the camera's image (GL's window coordinates, pixel centres at
// half-integers):
//   - A cell is a block of `cell_pixels` × `cell_pixels` whole pixels. An occluder marks a cell only
//     when its exact projection covers the whole cell, and stores there its farthest camera depth
//     over the cell. Every pixel centre of the cell then lies at least half a pixel inside the
//     occluder's projection, far more than GL's rounding of its float vertices moves an edge, so
//     GL draws the occluder over every pixel of the cell.
//   - hides(polygon) is true only when each cell holding a pixel centre within kTargetSlackPixels
//     of the polygon's projection stores a depth below the polygon's nearest depth over that cell
//     (bounded by its nearest corner and by its plane at the cell's corners): along every pixel's
//     ray the occluder comes first.
//   - An occluder serves by its part beyond twice the near distance, a target is tested by its
//     part beyond half of it (what GL can draw of it). One with a corner beyond the far plane is
//     never used and never hidden.
// For a painter's order (nearer drawn later, where one hides the other) a hidden polygon is painted
// over wherever it would have shown, so leaving it out keeps the image, as long as the occluders
// are drawn: the caller takes them from its own list. The z-buffer mode does not need the order.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "walkthrough/camera.h"

namespace walkvis {

struct OcclusionOptions {
  // Pixels per cell side. Finer cells cover more near an occluder's edge and cost more per
  // occluder (the figures are in docs/frames/).
  int cell_pixels = 8;
  // Occluders per frame: the fragments of the list with the largest apparent size (ball radius over
  // distance).
  uint32_t max_occluders = 16;
  // Fragments are tested only when their ball looks at least this many pixels in radius.
  double min_target_pixels = 8.0;
  // Pacing (FrameBuilder): after a frame whose test left out fragments reaching fewer than
  // `min_occluded_pixels` (FrameStats::occluded_pixels), that mode rests from occlusion culling for
  // 1 frame, after the next such test for 2, then 4, up to `max_rest_frames`; a test that leaves
  // out more sets the rest back to 1. A test costs tens of microseconds; llvmpipe fills a pixel in
  // about 8 ns, so one that saves fewer than about 2,000 pixels costs more than GL then saves
  // (docs/frames/). max_rest_frames 0: test every frame.
  uint32_t min_occluded_pixels = 2048;
  uint32_t max_rest_frames = 8;
};

class OcclusionBuffer {
 public:
  // Empty buffer for this camera (its image size and frustum); keeps its memory between frames.
  void reset(const FreeCamera& camera, int cell_pixels);
  // Marks the cells the convex planar polygon covers wholly; false when it covers none (nothing of
  // it beyond twice the near distance, a corner beyond the far plane, seen edge-on, or too small).
  bool addOccluder(std::span<const glm::dvec3> corners);
  // See the contract above; false for a polygon wholly nearer than half the near distance or with
  // a corner beyond the far plane.
  bool hides(std::span<const glm::dvec3> corners) const { return hiddenCells(corners) > 0; }
  // hides(), and what it saves: 0 when not hidden, else the cells the polygon's pixels fall in (at
  // least 1; times cell_pixels² it bounds the pixels GL would have filled).
  uint32_t hiddenCells(std::span<const glm::dvec3> corners) const;

  int cellsX() const { return cells_x_; }
  int cellsY() const { return cells_y_; }
  // Cells holding an occluder (for tests and statistics).
  size_t coveredCells() const;

 private:
  struct Projected {
    double x = 0.0, y = 0.0, w = 0.0;  // pixels from the image's lower-left corner; camera depth
  };
  bool project(std::span<const glm::dvec3> corners, double w_min, std::vector<Projected>& out) const;
  // 1/w = a + b x + e y over the image for the corners' plane; false when the eye lies in it.
  bool inverseDepthPlane(std::span<const glm::dvec3> corners, double& a, double& b, double& e) const;
  // The projected polygon in scratch_ (convex, rows y0..y1) cut by the row at height y: [xl, xr],
  // empty (xl > xr) outside its rows.
  void spanAt(double y, double y0, double y1, double& xl, double& xr) const;

  CubeFrame frame_;
  glm::dvec3 eye_{0.0};
  double tx_ = 1.0, ty_ = 1.0, near_ = 0.0, far_ = 0.0;
  int width_ = 0, height_ = 0, cell_ = 1, cells_x_ = 0, cells_y_ = 0;
  // Per cell, 1 / (the farthest depth over the cell of its nearest occluder), 0 where none.
  std::vector<double> depth_;
  mutable std::vector<Projected> scratch_;
  mutable std::vector<glm::dvec3> clip_;  // eye-relative corners of the clipped polygon
};

}  // namespace walkvis
