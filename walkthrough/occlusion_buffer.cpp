// The occlusion buffer of occlusion_buffer.h: a coarse depth image in the spirit of the
// hierarchical z-buffer and the occlusion maps [GreeneKassMiller1993, ZhangManochaHudsonHoff1997],
// made conservative by covering cells wholly rather than by sampling pixels.
#include "walkthrough/occlusion_buffer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "core/check.h"

namespace walkvis {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// How far GL's image of a target may reach beyond its exact projected box, in pixels: its float
// vertices (eye-relative, through a float matrix) sit within ~1e-4 pixel of the exact ones at
// these image sizes, and llvmpipe snaps them to 1/256 pixel. Twelve times the snap.
constexpr double kTargetSlackPixels = 0.05;

// ceil(v) or floor(v) clamped to [lo, hi] before it becomes an int: an image point of a corner
// just beyond the near plane can lie far outside the image, and an empty span is ±infinity.
int ceilIn(double v, int lo, int hi) { return static_cast<int>(std::clamp(std::ceil(v), double(lo), double(hi))); }
int floorIn(double v, int lo, int hi) { return static_cast<int>(std::clamp(std::floor(v), double(lo), double(hi))); }

}  // namespace

void OcclusionBuffer::reset(const FreeCamera& camera, int cell_pixels) {
  WALKVIS_DCHECK(camera.width > 0 && camera.height > 0 && cell_pixels > 0);
  frame_ = cameraFrame(camera);
  eye_ = camera.eye;
  ty_ = std::tan(0.5 * camera.fov_y);
  tx_ = ty_ * static_cast<double>(camera.width) / static_cast<double>(camera.height);
  near_ = camera.near;
  far_ = camera.far;
  width_ = camera.width;
  height_ = camera.height;
  cell_ = std::max(cell_pixels, 1);
  cells_x_ = (width_ + cell_ - 1) / cell_;
  cells_y_ = (height_ + cell_ - 1) / cell_;
  depth_.assign(static_cast<size_t>(cells_x_) * static_cast<size_t>(cells_y_), 0.0);
}

size_t OcclusionBuffer::coveredCells() const {
  return static_cast<size_t>(std::count_if(depth_.begin(), depth_.end(), [](double d) { return d > 0.0; }));
}

// The polygon's part at camera depth w >= w_min (Sutherland–Hodgman against one plane
// [SutherlandHodgman1974]; the part of a convex polygon, convex), projected to pixels from the
// image's lower-left corner as GL's window coordinates: x = (u + 1) / 2 · width with
// u = right / (w · tx), the frustum of clipFromEyeRelative(FreeCamera). False when nothing of it
// lies there, or some corner lies beyond the far plane.
bool OcclusionBuffer::project(std::span<const glm::dvec3> corners, double w_min, std::vector<Projected>& out) const {
  out.clear();
  clip_.clear();
  const size_t n = corners.size();
  for (size_t k = 0; k < n; ++k) {
    const glm::dvec3 p = corners[k] - eye_, q = corners[(k + 1) % n] - eye_;
    const double wp = glm::dot(p, frame_.forward), wq = glm::dot(q, frame_.forward);
    if (!(wp <= far_)) return false;
    if (wp >= w_min) clip_.push_back(p);
    if ((wp >= w_min) != (wq >= w_min)) {
      glm::dvec3 x = p + (q - p) * ((w_min - wp) / (wq - wp));
      x += frame_.forward * (w_min - glm::dot(x, frame_.forward));  // exactly on the plane, up to rounding
      clip_.push_back(x);
    }
  }
  if (clip_.size() < 3) return false;
  for (const glm::dvec3& c : clip_) {
    Projected q;
    q.w = std::max(glm::dot(c, frame_.forward), w_min);
    q.x = 0.5 * (glm::dot(c, frame_.right) / (q.w * tx_) + 1.0) * width_;
    q.y = 0.5 * (glm::dot(c, frame_.up) / (q.w * ty_) + 1.0) * height_;
    out.push_back(q);
  }
  return true;
}

bool OcclusionBuffer::addOccluder(std::span<const glm::dvec3> corners) {
  // Only the occluder's part beyond twice the near distance serves: GL clips at the near plane in
  // float, and a whole near distance of margin keeps what is used clear of that clip. The part
  // used is drawn wherever the whole occluder is.
  if (corners.size() < 3 || !project(corners, 2.0 * near_, scratch_)) return false;
  // The occluder's plane, eye-relative: n · (p − eye) = c. Along the ray through image point
  // (x, y), p − eye = w · dir(x, y) with dir's forward component 1, so 1/w = n · dir / c is affine
  // in (x, y): 1/w = a + b x + e y. Its least value over a cell (the farthest depth) is at a corner.
  double a = 0.0, b = 0.0, e = 0.0;
  if (!inverseDepthPlane(corners, a, b, e)) return false;  // the eye in its plane
  double y0 = kInf, y1 = -kInf;
  for (const Projected& q : scratch_) {
    y0 = std::min(y0, q.y);
    y1 = std::max(y1, q.y);
  }
  if (!(y1 - y0 > 1e-9)) return false;  // edge-on: covers no cell
  const int gy0 = ceilIn(y0 / cell_, 0, cells_y_);
  const int gy1 = floorIn(y1 / cell_, 0, cells_y_);
  size_t marked = 0;
  double lo_l = 0.0, lo_r = 0.0;
  spanAt(static_cast<double>(gy0 * cell_), y0, y1, lo_l, lo_r);
  for (int gy = gy0; gy < gy1; ++gy) {
    double hi_l = 0.0, hi_r = 0.0;
    spanAt(static_cast<double>((gy + 1) * cell_), y0, y1, hi_l, hi_r);
    // A cell is covered when its four corners are: both rows' spans hold its sides. On a span's
    // end counts as inside: a pixel centre of the cell is half a pixel from its sides.
    const double xl = std::max(lo_l, hi_l), xr = std::min(lo_r, hi_r);
    const int cx0 = ceilIn(xl / cell_, 0, cells_x_);
    const int cx1 = floorIn(xr / cell_, 0, cells_x_);
    if (cx0 < cx1) marked += static_cast<size_t>(cx1 - cx0);
    const double cy_lo = static_cast<double>(gy * cell_), cy_hi = static_cast<double>((gy + 1) * cell_);
    const double ey = e * (e < 0.0 ? cy_hi : cy_lo);
    double* row = depth_.data() + static_cast<size_t>(gy) * static_cast<size_t>(cells_x_);
    for (int cx = cx0; cx < cx1; ++cx) {
      const double x_lo = static_cast<double>(cx * cell_), x_hi = static_cast<double>((cx + 1) * cell_);
      const double inv = a + b * (b < 0.0 ? x_hi : x_lo) + ey;
      if (inv > row[cx]) row[cx] = inv;
    }
    lo_l = hi_l;
    lo_r = hi_r;
  }
  return marked > 0;
}

bool OcclusionBuffer::inverseDepthPlane(std::span<const glm::dvec3> corners, double& a, double& b, double& e) const {
  const glm::dvec3 normal = glm::cross(corners[1] - corners[0], corners[2] - corners[0]);
  const double c = glm::dot(normal, corners[0] - eye_);
  if (c == 0.0) return false;
  const double nf = glm::dot(normal, frame_.forward), nr = glm::dot(normal, frame_.right),
               nu = glm::dot(normal, frame_.up);
  b = 2.0 * tx_ * nr / (width_ * c);
  e = 2.0 * ty_ * nu / (height_ * c);
  a = (nf - tx_ * nr - ty_ * nu) / c;
  return true;
}

void OcclusionBuffer::spanAt(double y, double y0, double y1, double& xl, double& xr) const {
  xl = kInf;
  xr = -kInf;
  if (y < y0 || y > y1) return;
  const size_t n = scratch_.size();
  for (size_t k = 0; k < n; ++k) {
    const Projected& p = scratch_[k];
    const Projected& q = scratch_[(k + 1) % n];
    if ((y < p.y && y < q.y) || (y > p.y && y > q.y)) continue;
    if (p.y == q.y) {
      xl = std::min(xl, std::min(p.x, q.x));
      xr = std::max(xr, std::max(p.x, q.x));
    } else {
      const double x = p.x + (q.x - p.x) * ((y - p.y) / (q.y - p.y));
      xl = std::min(xl, x);
      xr = std::max(xr, x);
    }
  }
}

uint32_t OcclusionBuffer::hiddenCells(std::span<const glm::dvec3> corners) const {
  if (corners.size() < 3) return 0;
  // First the cells under a few points of the polygon, its corners' mean and the points three
  // quarters of the way from it to each corner: with nothing there nearer than such a point, the
  // polygon is not hidden (most that are seen end here; the corners of a partly hidden wall see
  // past its occluder). Where such a cell is not one the full test would look at, answering no is
  // merely cautious.
  auto shownAt = [&](const glm::dvec3& p) {
    const glm::dvec3 c = p - eye_;
    const double w = glm::dot(c, frame_.forward);
    if (!(w >= 0.5 * near_ && w <= far_)) return false;
    const double x = 0.5 * (glm::dot(c, frame_.right) / (w * tx_) + 1.0) * width_;
    const double y = 0.5 * (glm::dot(c, frame_.up) / (w * ty_) + 1.0) * height_;
    if (!(x >= 0.0 && y >= 0.0 && x < width_ && y < height_)) return false;
    const size_t cx = std::min(static_cast<size_t>(x) / static_cast<size_t>(cell_), static_cast<size_t>(cells_x_ - 1));
    const size_t cy = std::min(static_cast<size_t>(y) / static_cast<size_t>(cell_), static_cast<size_t>(cells_y_ - 1));
    return !(depth_[cy * static_cast<size_t>(cells_x_) + cx] > 1.0 / w);
  };
  glm::dvec3 m(0.0);
  for (const glm::dvec3& p : corners) m += p;
  m /= static_cast<double>(corners.size());
  if (shownAt(m)) return 0;
  for (const glm::dvec3& p : corners)
    if (shownAt(m + 0.75 * (p - m))) return 0;
  // What GL can draw of the polygon lies beyond its near plane; half the near distance leaves a
  // margin for the float clip. Nothing there: kept all the same (the frustum test's business).
  if (!project(corners, 0.5 * near_, scratch_)) return 0;
  double y0 = kInf, y1 = -kInf, nearest = kInf;
  for (const Projected& q : scratch_) {
    y0 = std::min(y0, q.y);
    y1 = std::max(y1, q.y);
    nearest = std::min(nearest, q.w);
  }
  // Over a cell the polygon is no nearer than its nearest corner, nor than its plane at the
  // cell's nearest corner (1/w affine over the cell, as for the occluders; the polygon's points
  // in the cell lie on the plane). The eye in its plane: the corner bound alone.
  double a = 0.0, b = 0.0, e = 0.0;
  const bool plane = inverseDepthPlane(corners, a, b, e);
  const double inv_nearest = 1.0 / nearest;
  // The cells holding a pixel centre (i + 0.5, j + 0.5) within kTargetSlackPixels of the projected
  // polygon: row by row, the polygon's extent over the row's strip (its spans at the strip's edges
  // and its corners inside the strip; convex), grown by the slack.
  const double s = kTargetSlackPixels;
  const int j0 = ceilIn(y0 - s - 0.5, 0, height_);
  const int j1 = floorIn(y1 + s - 0.5, -1, height_ - 1);
  // No pixel centre near it: GL draws none of it, but that is not being hidden (it is outside the
  // image, or too small to reach a pixel), so the answer is no.
  if (j1 < j0) return 0;
  uint32_t cells = 0;  // tested: a pixel centre near the polygon lies in each
  for (int cy = j0 / cell_; cy <= j1 / cell_; ++cy) {
    // Pixel centres of this cell row that lie in the polygon's rows: their y, grown by the slack.
    const double ya = std::max(y0, std::max(cy * cell_, j0) + 0.5 - s);
    const double yb = std::min(y1, std::min((cy + 1) * cell_ - 1, j1) + 0.5 + s);
    // Every cell row from j0 to j1 holds a centre row within the slack of [y0, y1], so ya <= yb.
    double xl = kInf, xr = -kInf, l = 0.0, r = 0.0;
    spanAt(ya, y0, y1, l, r);
    xl = std::min(xl, l);
    xr = std::max(xr, r);
    spanAt(yb, y0, y1, l, r);
    xl = std::min(xl, l);
    xr = std::max(xr, r);
    for (const Projected& q : scratch_)
      if (q.y >= ya && q.y <= yb) {
        xl = std::min(xl, q.x);
        xr = std::max(xr, q.x);
      }
    if (!(xl <= xr)) continue;  // cannot happen for ya <= yb; kept out all the same
    const int i0 = ceilIn(xl - s - 0.5, 0, width_);
    const int i1 = floorIn(xr + s - 0.5, -1, width_ - 1);
    if (i1 < i0) continue;
    const double* row = depth_.data() + static_cast<size_t>(cy) * static_cast<size_t>(cells_x_);
    const double cy_lo = static_cast<double>(cy * cell_), cy_hi = static_cast<double>((cy + 1) * cell_);
    const double ey = e * (e > 0.0 ? cy_hi : cy_lo);
    for (int cx = i0 / cell_; cx <= i1 / cell_; ++cx) {
      double bound = inv_nearest;
      if (plane) {
        const double x_lo = static_cast<double>(cx * cell_), x_hi = static_cast<double>((cx + 1) * cell_);
        bound = std::min(bound, a + b * (b > 0.0 ? x_hi : x_lo) + ey);
      }
      if (!(row[cx] > bound)) return 0;
      ++cells;
    }
  }
  return cells;
}

}  // namespace walkvis
