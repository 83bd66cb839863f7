// Priority-order validation: painter's and z-buffer ID images (OSMesa) against exact ray casting
// (Embree [Embree2014] + double re-check), docs/DESIGN.md, "Validation and statistics". The
// painter's algorithm and the z-buffer are Newell, Newell & Sancha (1972) [NewellNewellSancha1972]
// and Catmull (1974) [Catmull1974]; the classification of mismatching pixels into order errors,
// ties and coverage differences is ours (docs/DESIGN.md, "Order error").
#include "walkthrough/validate.h"

#include <png.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "core/sample.h"
#include "walkthrough/renderer.h"

namespace walkvis {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }


uint32_t faceColorOf(const Scene& scene, const Polygon& p) {
  return p.face_id < scene.face_colors.size() ? scene.face_colors[p.face_id] : faceColor(p.face_id);
}

void writeDiffImage(const std::string& path, int size, const Scene& scene, std::span<const Polygon> polygons,
                    std::span<const uint32_t> ids, std::span<const PixelClass> classes) {
  std::vector<uint8_t> rgb(static_cast<size_t>(size) * size * 3);
  for (size_t k = 0; k < ids.size(); ++k) {
    uint32_t c = 0x000000;
    switch (classes[k]) {
      case PixelClass::kOrderError: c = 0xFF0000; break;
      case PixelClass::kTie: c = 0x00FFFF; break;
      case PixelClass::kEdge: c = 0xFFFF00; break;
      case PixelClass::kUncovered: c = 0xFF00FF; break;
      case PixelClass::kMissed: c = 0xFF8000; break;
      case PixelClass::kMatch:
        if (ids[k] < polygons.size()) {
          // Dimmed face colour, so the highlighted classes stand out.
          const uint32_t f = faceColorOf(scene, polygons[ids[k]]);
          c = (((f >> 16) & 0xFF) * 2 / 5) << 16 | (((f >> 8) & 0xFF) * 2 / 5) << 8 | ((f & 0xFF) * 2 / 5);
        }
        break;
    }
    rgb[3 * k] = static_cast<uint8_t>(c >> 16);
    rgb[3 * k + 1] = static_cast<uint8_t>(c >> 8);
    rgb[3 * k + 2] = static_cast<uint8_t>(c);
  }
  writePngRgb(path, size, size, rgb);
}

bool isConvex(std::span<const glm::dvec3> verts, const Plane& plane) {
  const size_t n = verts.size();
  for (size_t k = 0; k < n; ++k) {
    const glm::dvec3 e1 = verts[(k + 1) % n] - verts[k], e2 = verts[(k + 2) % n] - verts[(k + 1) % n];
    // Relative to the edge lengths: collinear vertices give a turn of rounding size, either sign.
    if (glm::dot(plane.n, glm::cross(e1, e2)) < -1e-9 * glm::length(e1) * glm::length(e2)) return false;
  }
  return true;
}

}  // namespace

PixelClass classifyPixel(uint32_t shown, std::span<const RayHit> hits, double tie_tolerance,
                         std::span<const uint8_t> listed) {
  if (hits.empty()) return shown == kNoPolygon ? PixelClass::kMatch : PixelClass::kEdge;
  const auto is_listed = [&](const RayHit& h) {
    return listed.empty() || (h.polygon < listed.size() && listed[h.polygon] != 0);
  };
  // Missed: nothing in the nearest tie group is listed.
  auto first = hits.begin();
  if (!listed.empty()) {
    const double window0 = tie_tolerance * hits[0].t;
    while (first != hits.end() && !is_listed(*first)) {
      if (first->t - hits[0].t > window0) return PixelClass::kMissed;
      ++first;
    }
    if (first == hits.end()) return PixelClass::kMissed;
  }
  // From here on only listed hits count.
  if (shown == kNoPolygon) return PixelClass::kUncovered;
  const auto it = std::find_if(first, hits.end(), [&](const RayHit& h) { return h.polygon == shown; });
  if (it == hits.end()) return PixelClass::kEdge;
  const double t_min = first->t;
  const double window = tie_tolerance * t_min;
  if (it->t - t_min > window) {
    for (auto h = first; h != it && it->t - h->t > window; ++h)
      if (h->solid && is_listed(*h)) return PixelClass::kOrderError;
    return PixelClass::kEdge;
  }
  bool unique_nearest = it == first;
  if (unique_nearest)
    for (auto h = first + 1; h != hits.end() && h->t - t_min <= window; ++h)
      if (is_listed(*h)) unique_nearest = false;
  return unique_nearest ? PixelClass::kMatch : PixelClass::kTie;
}

void PixelCounts::add(PixelClass c) {
  switch (c) {
    case PixelClass::kMatch: break;
    case PixelClass::kOrderError: ++order_error; break;
    case PixelClass::kTie: ++tie; break;
    case PixelClass::kEdge: ++edge; break;
    case PixelClass::kUncovered:
      ++edge;
      ++uncovered;
      break;
    case PixelClass::kMissed: ++missed; break;
  }
}

PixelCounts& PixelCounts::operator+=(const PixelCounts& o) {
  order_error += o.order_error;
  tie += o.tie;
  edge += o.edge;
  uncovered += o.uncovered;
  missed += o.missed;
  return *this;
}

namespace {

// True when `p` lies within `clearance` of polygon `poly` (its plane within the clearance and p's
// foot inside it, or an edge within the clearance). Doubles are enough: it only chooses eyes.
bool nearPolygon(const Scene& scene, const Polygon& poly, const glm::dvec3& p, double clearance) {
  const double side = glm::dot(poly.plane.n, p) - poly.plane.d;
  if (!(std::abs(side) <= clearance)) return false;
  const glm::dvec3 foot = p - side * poly.plane.n;
  bool all_left = true, all_right = true;
  for (uint32_t k = 0; k < poly.vertex_count; ++k) {
    const glm::dvec3 a = scene.vertices[poly.first_vertex + k];
    const glm::dvec3 b = scene.vertices[poly.first_vertex + (k + 1) % poly.vertex_count];
    const glm::dvec3 ab = b - a;
    const double len2 = glm::dot(ab, ab);
    const double t = len2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
    if (glm::length(p - (a + t * ab)) <= clearance) return true;
    const double turn = glm::dot(glm::cross(ab, foot - a), poly.plane.n);
    all_left &= turn >= 0.0;
    all_right &= turn <= 0.0;
  }
  return all_left || all_right;  // inside a convex polygon (the BSP's fragments are convex)
}

}  // namespace

std::vector<ValidationEye> sampleEyes(const Scene& scene, int count, uint64_t seed, double off_plane_fraction,
                                      double min_clearance) {
  std::vector<ValidationEye> eyes;
  if (count <= 0) return eyes;
  // core/rng.h's generator, not std::*_distribution: the eyes, and so every figure, are the same
  // with every standard library.
  uint64_t rng = seed;
  const Bounds b = sceneBounds(scene);
  struct Piece {
    int level;
    const std::vector<glm::dvec2>* ring;
  };
  std::vector<Piece> pieces;
  std::vector<double> weights;
  for (size_t l = 0; l < scene.levels.size(); ++l) {
    for (const auto& ring : scene.levels[l].walkable) {
      const double a = ring.size() >= 3 ? std::abs(signedArea(ring)) : 0.0;
      if (a > 0.0 && std::isfinite(a)) {
        pieces.push_back({static_cast<int>(l), &ring});
        weights.push_back((weights.empty() ? 0.0 : weights.back()) + a);  // cumulative
      }
    }
  }
  constexpr int kClearanceAttempts = 64;
  std::vector<std::pair<glm::dvec3, glm::dvec3>> boxes;  // polygon bounds, for min_clearance
  if (min_clearance > 0.0)
    for (const Polygon& poly : scene.polygons) {
      glm::dvec3 lo(HUGE_VAL), hi(-HUGE_VAL);
      for (uint32_t k = 0; k < poly.vertex_count; ++k) {
        lo = glm::min(lo, scene.vertices[poly.first_vertex + k]);
        hi = glm::max(hi, scene.vertices[poly.first_vertex + k]);
      }
      boxes.push_back({lo, hi});
    }
  auto tooClose = [&](const glm::dvec3& p) {
    for (size_t i = 0; i < boxes.size(); ++i) {
      const glm::dvec3 q = glm::clamp(p, boxes[i].first, boxes[i].second);
      if (glm::length(q - p) <= min_clearance && nearPolygon(scene, scene.polygons[i], p, min_clearance)) return true;
    }
    return false;
  };
  const int off_count = static_cast<int>(std::floor(count * std::clamp(off_plane_fraction, 0.0, 1.0)));
  for (int k = 0; k < count; ++k) {
    ValidationEye eye;
    if (pieces.empty()) {
      const double x = uniform01(rng), y = uniform01(rng), z = uniform01(rng);
      eye.position = b.lo + glm::dvec3(x, y, z) * (b.hi - b.lo);
      eye.on_height_plane = false;
    } else {
      for (int attempt = 0; attempt < kClearanceAttempts; ++attempt) {
        const Piece& piece = pieces[pickByWeight(weights, rng)];
        const glm::dvec2 xz = uniformPointInConvex<glm::dvec2>(*piece.ring, rng);
        eye.level = piece.level;
        eye.position = {xz.x, scene.levels[piece.level].floor_y + scene.eye_height, xz.y};
        if (!tooClose(eye.position)) break;
      }
    }
    if (k >= count - off_count) {
      eye.position.y = b.lo.y + uniform01(rng) * (b.hi.y - b.lo.y);
      eye.on_height_plane = false;
      eye.level = -1;
    }
    eyes.push_back(eye);
  }
  return eyes;
}

// libpng reports errors by longjmp: nothing here is modified between setjmp and the jump.
static bool writePngStream(FILE* f, png_structp png, png_infop info, int width, int height, const uint8_t* rgb) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  png_init_io(png, f);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int r = 0; r < height; ++r)
    png_write_row(png, const_cast<png_bytep>(rgb + static_cast<size_t>(r) * width * 3));
  png_write_end(png, nullptr);
  return true;
}

void writePngRgb(const std::string& path, int width, int height, std::span<const uint8_t> rgb) {
  if (width <= 0 || height <= 0 || rgb.size() != static_cast<size_t>(width) * height * 3)
    throw Error(path + ": bad image size for PNG");
  const std::string tmp = path + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw Error(path + ": cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  bool ok = png && info && writePngStream(f, png, info, width, height, rgb.data());
  png_destroy_write_struct(png ? &png : nullptr, info ? &info : nullptr);
  ok = std::fclose(f) == 0 && ok;
  std::error_code ec;
  if (ok) std::filesystem::rename(tmp, path, ec);
  if (!ok || ec) {
    std::filesystem::remove(tmp, ec);
    throw Error(path + ": cannot write PNG");
  }
}

ValidationResult runValidation(const Scene& scene, std::span<const glm::dvec3> vertices,
                               std::span<const Polygon> polygons, const OrderProvider& order,
                               const ValidationOptions& options) {
  const auto t_start = Clock::now();
  if (options.size < 8 || options.size > 4096) throw Error("validate: --size must be in [8, 4096]");
  if (options.eyes < 1 || options.eyes > 1000000) throw Error("validate: --views must be in [1, 1000000]");
  for (int bits : options.zbits)
    if (bits != 16 && bits != 24 && bits != 32) throw Error("validate: --zbits takes 16, 24 and 32");
  ValidationResult result;
  const int size = options.size;
  const size_t pixels = static_cast<size_t>(size) * size;

  glm::dvec3 lo(0.0), hi(0.0);
  if (!vertices.empty()) {
    lo = hi = vertices[0];
    for (const auto& v : vertices) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
  }
  const double diagonal = glm::length(hi - lo);
  // A near plane at 5% of the eye height keeps walls the eye stands next to in view and leaves
  // z-buffer precision at its usual game-like ratio; geometry nearer than it is clipped in both the
  // GL images and the ray caster (the same camera depth), so it never causes a mismatch.
  double near = options.near > 0.0 ? options.near : 0.05 * scene.eye_height;
  if (!(near > 0.0) || !std::isfinite(near)) near = std::max(diagonal * 1e-4, 1e-6);
  result.near = near;

  // Renderers: one per z-buffer precision; the first also draws the painter's images.
  std::vector<OffscreenRenderer> zbuffers;
  for (int bits : options.zbits) {
    std::string why;
    auto r = OffscreenRenderer::create(size, bits, &why);
    if (!r) throw std::runtime_error("validate: no offscreen GL renderer: " + why);
    zbuffers.push_back(std::move(*r));
  }
  std::optional<OffscreenRenderer> painter_only;
  if (zbuffers.empty()) {
    std::string why;
    painter_only = OffscreenRenderer::create(size, 24, &why);
    if (!painter_only) throw std::runtime_error("validate: no offscreen GL renderer: " + why);
  }
  OffscreenRenderer& painter = zbuffers.empty() ? *painter_only : zbuffers[0];
  result.gl_renderer = painter.glRenderer();
  for (auto& r : zbuffers) r.upload(vertices, polygons);
  if (painter_only) painter_only->upload(vertices, polygons);
  for (size_t k = 0; k < zbuffers.size(); ++k)
    result.zbuffer.push_back({options.zbits[k], zbuffers[k].depthFormat(), {}, 0.0});

  for (const Polygon& p : polygons) {
    if (p.first_vertex <= vertices.size() && p.vertex_count <= vertices.size() - p.first_vertex &&
        !isConvex(vertices.subspan(p.first_vertex, p.vertex_count), p.plane))
      ++result.nonconvex_polygons;
  }

  auto t0 = Clock::now();
  const RayCaster caster(vertices, polygons);
  result.raycast_seconds += since(t0);

  const std::vector<ValidationEye> eyes =
      sampleEyes(scene, options.eyes, options.seed, options.off_plane_fraction, options.eyes_clear_of_near ? near : 0.0);
  std::vector<ViewReport> reports;
  std::vector<uint32_t> order_ids, painter_ids;
  std::vector<uint8_t> listed;
  uint64_t listed_total = 0;
  std::vector<std::vector<uint32_t>> z_ids(zbuffers.size());
  std::vector<RayHit> nearest;
  std::vector<uint32_t> mismatch;
  std::vector<std::vector<RayHit>> mismatch_hits;
  std::vector<PixelClass> painter_classes;
  std::vector<std::vector<PixelClass>> z_classes(zbuffers.size());
  if (!options.diff_dir.empty()) std::filesystem::create_directories(options.diff_dir);

  for (size_t e = 0; e < eyes.size(); ++e) {
    const glm::dvec3 eye = eyes[e].position;
    t0 = Clock::now();
    order(eye, order_ids);
    result.order_seconds += since(t0);
    listed.assign(polygons.size(), 0);
    for (uint32_t id : order_ids)
      if (id < listed.size()) listed[id] = 1;
    listed_total += order_ids.size();
    t0 = Clock::now();
    const std::vector<uint8_t> front = caster.frontFacing(eye);
    result.raycast_seconds += since(t0);
    double far = near * 2.0;
    for (int c = 0; c < 8; ++c) {
      const glm::dvec3 corner((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
      far = std::max(far, glm::length(corner - eye) * 1.01 + near);
    }
    for (int face = 0; face < kCubeFaces; ++face) {
      const View view{eye, face, size, near, far};
      t0 = Clock::now();
      painter.drawPainter(view, order_ids);
      painter.readIds(painter_ids);
      for (size_t z = 0; z < zbuffers.size(); ++z) {
        const auto tz = Clock::now();
        zbuffers[z].drawZBuffer(view);
        zbuffers[z].readIds(z_ids[z]);
        result.zbuffer[z].render_seconds += since(tz);
      }
      result.render_seconds += since(t0);
      t0 = Clock::now();
      caster.castNearest(view, front, nearest);
      result.raycast_seconds += since(t0);

      t0 = Clock::now();
      mismatch.clear();
      for (size_t k = 0; k < pixels; ++k) {
        bool differs = painter_ids[k] != nearest[k].polygon;
        for (const auto& ids : z_ids) differs = differs || ids[k] != nearest[k].polygon;
        if (differs) mismatch.push_back(static_cast<uint32_t>(k));
        if (nearest[k].polygon != kNoPolygon) ++result.exact_pixels;
      }
      mismatch_hits.assign(mismatch.size(), {});
      tbb::parallel_for(size_t{0}, mismatch.size(), [&](size_t m) {
        const uint32_t k = mismatch[m];
        std::vector<uint32_t> shown{painter_ids[k]};
        for (const auto& ids : z_ids) shown.push_back(ids[k]);
        mismatch_hits[m] = caster.exactHits(view, front, static_cast<int>(k % size), static_cast<int>(k / size), shown);
      });
      ViewReport report;
      report.eye_index = static_cast<int>(e);
      report.eye = eye;
      report.face = face;
      report.on_height_plane = eyes[e].on_height_plane;
      report.zbuffer_errors.assign(zbuffers.size(), 0);
      painter_classes.assign(pixels, PixelClass::kMatch);
      for (auto& zc : z_classes) zc.assign(pixels, PixelClass::kMatch);
      for (size_t m = 0; m < mismatch.size(); ++m) {
        const uint32_t k = mismatch[m];
        painter_classes[k] = classifyPixel(painter_ids[k], mismatch_hits[m], kTieRelativeTolerance, listed);
        report.painter.add(painter_classes[k]);
        for (size_t z = 0; z < zbuffers.size(); ++z) {
          z_classes[z][k] = classifyPixel(z_ids[z][k], mismatch_hits[m]);
          result.zbuffer[z].counts.add(z_classes[z][k]);
          if (z_classes[z][k] == PixelClass::kOrderError) ++report.zbuffer_errors[z];
        }
      }
      result.painter += report.painter;
      result.classify_seconds += since(t0);

      if (!options.diff_dir.empty()) {
        const std::string stem = options.diff_dir + "/eye" + std::to_string(e) + "_face" + std::to_string(face);
        if ((report.painter.order_error > 0 || report.painter.missed > 0) && result.diff_images < static_cast<uint64_t>(options.max_diff_images)) {
          writeDiffImage(stem + "_painter.png", size, scene, polygons, painter_ids, painter_classes);
          ++result.diff_images;
        }
        for (size_t z = 0; z < zbuffers.size(); ++z) {
          if (report.zbuffer_errors[z] > 0 && result.diff_images < static_cast<uint64_t>(options.max_diff_images)) {
            writeDiffImage(stem + "_z" + std::to_string(options.zbits[z]) + ".png", size, scene, polygons, z_ids[z],
                           z_classes[z]);
            ++result.diff_images;
          }
        }
      }
      reports.push_back(std::move(report));
      ++result.views;
    }
    ++result.eyes;
    if (options.progress) options.progress(static_cast<int>(e + 1), static_cast<int>(eyes.size()), result.painter.order_error);
  }
  result.pixels = result.views * pixels;
  result.listed_mean = result.eyes ? static_cast<double>(listed_total) / static_cast<double>(result.eyes) : 0.0;
  auto zsum = [](const ViewReport& r) {
    uint64_t s = 0;
    for (uint64_t v : r.zbuffer_errors) s += v;
    return s;
  };
  const size_t keep = std::min(reports.size(), static_cast<size_t>(std::max(options.worst_views, 0)));
  std::partial_sort(reports.begin(), reports.begin() + static_cast<std::ptrdiff_t>(keep), reports.end(),
                    [&](const ViewReport& a, const ViewReport& b) {
                      if (a.painter.order_error != b.painter.order_error)
                        return a.painter.order_error > b.painter.order_error;
                      if (zsum(a) != zsum(b)) return zsum(a) > zsum(b);
                      return a.painter.edge > b.painter.edge;
                    });
  reports.resize(keep);
  result.worst_views = std::move(reports);
  result.seconds = since(t_start);
  return result;
}

}  // namespace walkvis
