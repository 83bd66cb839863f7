// Priority-order validation against exact ray casting (docs/DESIGN.md, "Order error").
// For sampled eyes and the six 90° faces around each, the painter's image of an order, and z-buffer
// images at several depth precisions, are compared pixel by pixel with the exact reference.
//
// Pixel classes, for an image that shows polygon p where the exact nearest front-facing polygon is q
// (all distances are camera depths t along the pixel-centre ray, recomputed in double):
//   match        p == q, or the double re-check shows p is the unique nearest hit;
//   order error  the ray hits p, and some polygon that the ray hits nearer than p by more than the
//                tie tolerance covers the pixel solidly (RayHit::solid: no edge within
//                kEdgeMarginPixels of the pixel centre), so every rasteriser draws it there;
//   tie          p is within the tie tolerance of the nearest hit, and some other polygon is too;
//   edge         coverage: p is not on the exact ray (rasterisation at edges and silhouettes),
//                nothing exact but p drawn, or the polygons nearer than p pass the pixel centre
//                within kEdgeMarginPixels of their edges; `uncovered` (nothing drawn, something
//                exact) is a part of edge and is also reported on its own;
//   missed       (painter's image only; an order that may leave visible polygons out, e.g. the HFD
//                tree's) every hit within the tie tolerance of the nearest exact hit belongs to a
//                polygon that the order does not list, so no order of the listed polygons could show
//                the right one there: the shown polygon (or nothing) is behind an unlisted nearest
//                polygon. Checked first; the other classes are then decided among the listed
//                polygons' hits only (unlisted hits are ignored), so an order error always means two
//                LISTED polygons drawn in the wrong order. An order that lists every front-facing
//                polygon (BSP, PFD) has no missed pixels unless it is wrong.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "scenes/scene.h"
#include "walkthrough/raycast.h"

namespace walkvis {

// Two hits are a tie when their depths differ by at most this fraction of the nearer depth. Far
// above double rounding of t = (d - n·eye) / (n·dir) at any angle a pixel can see a surface from,
// far below any depth step a 32-bit z-buffer can resolve, so ties are only true coincidences
// (coplanar overlaps, shared edges, split lines).
constexpr double kTieRelativeTolerance = 1e-6;

enum class PixelClass : uint8_t { kMatch, kOrderError, kTie, kEdge, kUncovered, kMissed };

// Classifies one pixel. `shown` is the image's polygon (kNoPolygon for nothing); `hits` are the
// double-checked front-facing hits on the pixel's ray, sorted by t (RayCaster::exactHits with
// also_check = shown, so shown is among them when the ray hits it). `listed`: per polygon index,
// nonzero when the order lists it (indices beyond its size count as unlisted); empty = every
// polygon is listed (then kMissed never happens, e.g. for z-buffer images).
PixelClass classifyPixel(uint32_t shown, std::span<const RayHit> hits,
                         double tie_tolerance = kTieRelativeTolerance, std::span<const uint8_t> listed = {});

struct PixelCounts {
  uint64_t order_error = 0;
  uint64_t tie = 0;
  uint64_t edge = 0;       // includes uncovered
  uint64_t uncovered = 0;  // nothing drawn where the exact image has a polygon
  uint64_t missed = 0;     // the exact nearest polygon is not listed (not part of edge or order_error)
  void add(PixelClass c);
  PixelCounts& operator+=(const PixelCounts& o);
};

// An eye for validation; on_height_plane is false for the extra eyes off the height planes.
struct ValidationEye {
  glm::dvec3 position{0.0};
  int level = -1;  // index into Scene::levels, -1 when not on a level's height plane
  bool on_height_plane = true;
};

// `count` eyes, uniform over the walkable area of all levels (each convex piece weighted by its area)
// at floor_y + eye_height. A fraction `off_plane_fraction` of them (rounded down) keeps its (x, z)
// but takes a uniform random y within the scene's vertical bounds. Without levels, eyes are uniform
// in the scene's bounding box. Deterministic for a seed. With min_clearance > 0, an eye on a height
// plane within that distance of a polygon is drawn again (at most 64 times; the last draw is kept).
std::vector<ValidationEye> sampleEyes(const Scene& scene, int count, uint64_t seed, double off_plane_fraction,
                                      double min_clearance = 0.0);

// order(eye, out): the polygons to draw for that eye in painter's order (back to front), indices into
// the polygon span given to runValidation; back faces may be left in or out (GL culls them).
using OrderProvider = std::function<void(const glm::dvec3& eye, std::vector<uint32_t>& out)>;

struct ValidationOptions {
  int eyes = 200;                    // eyes; each gives kCubeFaces views
  uint64_t seed = 1;
  int size = 256;                    // pixels per side of a cube face
  std::vector<int> zbits{16, 24, 32};  // z-buffer precisions to test; may be empty
  double off_plane_fraction = 0.0;   // see sampleEyes
  double near = -1.0;                // near plane (camera depth); < 0: 0.05 * eye height
  // Eyes at least the near distance from every polygon. For orders that leave polygons out (HFD):
  // an eye nearer a wall than the near plane sees through it in GL and in the reference alike, and
  // what lies behind (rightly not listed) would count as missed. Off for the BSP and PFD orders,
  // which list everything and so draw the see-through view correctly.
  bool eyes_clear_of_near = false;
  int worst_views = 5;               // how many worst views to keep
  std::string diff_dir;              // when set: PNGs of views with order or z-buffer errors
  int max_diff_images = 200;         // at most this many PNGs are written
  std::function<void(int eyes_done, int eyes_total, uint64_t order_errors)> progress;
};

struct ZBufferResult {
  int bits = 0;
  std::string depth_format;
  PixelCounts counts;
  double render_seconds = 0.0;  // drawing and reading back this precision's images, all views
};

struct ViewReport {
  int eye_index = 0;
  glm::dvec3 eye{0.0};
  int face = 0;
  bool on_height_plane = true;
  PixelCounts painter;
  std::vector<uint64_t> zbuffer_errors;  // per ValidationOptions::zbits entry
};

struct ValidationResult {
  uint64_t eyes = 0;
  uint64_t views = 0;
  uint64_t pixels = 0;          // per image kind: views * size * size
  uint64_t exact_pixels = 0;    // pixels where the exact reference shows a polygon
  double listed_mean = 0.0;     // polygons in the order per eye
  PixelCounts painter;
  std::vector<ZBufferResult> zbuffer;
  std::vector<ViewReport> worst_views;  // most painter's order errors, then most z-buffer errors
  uint64_t diff_images = 0;
  // Polygons of the drawn set that break the convex-polygon contract (a reflex turn beyond rounding):
  // the renderer, Embree and the double re-check all use the same fan, but an order for them may be
  // wrong. Reported so that such input is never hidden.
  uint64_t nonconvex_polygons = 0;
  double near = 0.0;
  double tie_tolerance = kTieRelativeTolerance;
  std::string gl_renderer;
  double seconds = 0.0, order_seconds = 0.0, render_seconds = 0.0, raycast_seconds = 0.0, classify_seconds = 0.0;
};

// Runs the validation of `order` on the polygons (vertices, polygons) — the set the order indexes,
// e.g. a BSP's fragments — using `scene` for eyes (levels, bounds, eye height) and face colours
// (polygons' face_id, in the diff PNGs). Throws std::runtime_error when no GL renderer can be made,
// Error for options out of range.
ValidationResult runValidation(const Scene& scene, std::span<const glm::dvec3> vertices,
                               std::span<const Polygon> polygons, const OrderProvider& order,
                               const ValidationOptions& options);

// Writes an 8-bit RGB PNG (rgb: width * height * 3 bytes, top row first) to a temporary file next to
// `path`, then renames it into place. Error naming the path when it cannot be written.
void writePngRgb(const std::string& path, int width, int height, std::span<const uint8_t> rgb);

}  // namespace walkvis
