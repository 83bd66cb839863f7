// Normal masks: Zhang & Hoff, "Fast Backface Culling Using Normal Masks", I3D 1997
// (/work/shared/papers/zhang-hoff1997-normal-masks.md).
//
// §2: the normal sphere is cut by the N×N grids of the six faces of its bounding cube into 6·N²
// clusters; a polygon stores its cluster as (byte offset, bit), two bytes. §3: per frame a cluster
// is back-facing when all four corner normals are back-facing for every projection direction of
// the view cone; the back-facing clusters make the backface mask, and the test per polygon is one
// AND, BackMask[offset] & bit. §3.1: for a cone of directions of half-angle θ around axis a, a
// normal n is back-facing for all of them iff angle(n, a) < 90° − θ, i.e. n̂·a > sin θ. That cap
// is spherically convex and a cluster is the cone over a square of the cube face, so all four
// corners in the cap puts every normal of the cluster in it (a nonnegative combination of the
// corners): testing the corners is exact, not an approximation.
//
// Perspective (§3.1 vs §3.2): the paper's view cone (view direction, field of view) covers the
// directions to polygons inside the view cone only; a front face outside it (behind the eye, say)
// may be culled. That is the option mask_use_view_cone. By default each spatial group of polygons
// gets its own cone, the cone from the eye around the group's bounding sphere (§3.2, "a viewing
// cone to each object group"), which holds every direction from the eye to the group: conservative
// for every polygon. An eye inside a group's sphere culls nothing in that group.
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "backface/backface.h"

namespace walkvis {
namespace {

constexpr int kMaxResolution = 18;  // 6·18² = 1944 clusters <= 2048 = 256 bytes · 8 bits (§2.2)

// Margin on the cap test n̂·a > sin θ: the corner directions, the cone axis and a normal's cell
// carry rounding errors below 1e-15; 1e-9 leaves six orders of magnitude and only spares clusters
// within ~1e-9 rad of the cap's rim.
constexpr double kCapMargin = 1e-9;
// Growth of a group's bounding sphere, relative to the coordinates' magnitude (its centre and
// radius at build time, the eye's per frame): a culled group's sphere then clears the eye's
// tangent cone by this much, far more than the ground truth's own rounding (4·2⁻⁵³ of the same
// magnitudes), so a polygon isFrontFacing() calls front-facing is never inside a culled cone.
constexpr double kSphereGrowth = 1e-9;

// A cell index whose byte lies past every real cell (6·18² bits fill 243 bytes): its mask byte
// stays zero, so a polygon with a zero normal is never culled.
constexpr int kNeverCell = 255 * 8;

struct Group {
  uint32_t begin = 0, end = 0;  // range of units (polygons in group order)
  glm::dvec3 center{0.0};
  double radius = 0.0;  // grown by kSphereGrowth·(|center|∞ + radius) and the plane residuals
};

class NormalMaskCuller final : public BackfaceCuller {
 public:
  NormalMaskCuller(const BackfaceInput& input, const BackfaceOptions& options)
      : n_(options.mask_resolution), use_view_cone_(options.mask_use_view_cone) {
    if (n_ < 1 || n_ > kMaxResolution) {
      throw SceneError("backface mask: mask_resolution must be in [1, 18], got " + std::to_string(n_));
    }
    const size_t count = input.polygons.size();
    polygon_count_ = count;
    // Corner grid: u_[i] = -1 + 2i/N; inv_len_[i][j] = 1 / |(±1, u_i, u_j)|.
    u_.resize(static_cast<size_t>(n_) + 1);
    for (int i = 0; i <= n_; ++i) u_[static_cast<size_t>(i)] = -1.0 + 2.0 * i / n_;
    inv_len_.resize(u_.size() * u_.size());
    for (size_t i = 0; i < u_.size(); ++i) {
      for (size_t j = 0; j < u_.size(); ++j) inv_len_[i * u_.size() + j] = 1.0 / std::sqrt(1.0 + u_[i] * u_[i] + u_[j] * u_[j]);
    }

    // Spatial groups (§3.2): median splits on the longest axis of the centroids' box.
    std::vector<glm::dvec3> centroid(count);
    for (size_t p = 0; p < count; ++p) {
      const Polygon& poly = input.polygons[p];
      glm::dvec3 s(0.0);
      for (uint32_t k = 0; k < poly.vertex_count; ++k) s += input.vertices[poly.first_vertex + k];
      centroid[p] = s / static_cast<double>(poly.vertex_count);
    }
    unit_polygons_.resize(count);
    std::iota(unit_polygons_.begin(), unit_polygons_.end(), 0u);
    const size_t group_size = options.mask_group_size == 0 ? std::max<size_t>(count, 1) : options.mask_group_size;
    split(0, static_cast<uint32_t>(count), group_size, centroid);
    if (groups_.empty()) groups_.push_back({0, 0, glm::dvec3(0.0), 0.0});
    for (Group& g : groups_) bound(g, input);

    unit_begin_.resize(count + 1);
    std::iota(unit_begin_.begin(), unit_begin_.end(), 0u);
    offset_.resize(count);
    bit_.resize(count);
    for (size_t u = 0; u < count; ++u) {
      const int cell = encode(input.polygons[unit_polygons_[u]].plane.n);
      offset_[u] = static_cast<uint8_t>(cell >> 3);
      bit_[u] = static_cast<uint8_t>(1u << (cell & 7));
    }
  }

  BackfaceMethod method() const override { return BackfaceMethod::kMask; }
  size_t stateBytes() const override {
    return offset_.size() + bit_.size() + groups_.size() * (sizeof(glm::dvec3) + sizeof(double)) +
           (u_.size() + inv_len_.size()) * sizeof(double);
  }

  void cull(const BackfaceView& view, std::span<uint8_t> unit_culled) const override {
    std::array<uint8_t, 256> mask{};
    if (use_view_cone_) {
      const double len = glm::length(view.view_dir);
      const bool usable = len > 0.0 && std::isfinite(len) && view.fov > 0.0 && view.fov < M_PI;
      if (usable) buildMask(view.view_dir / len, std::sin(0.5 * view.fov), mask);
      for (const Group& g : groups_) andGroup(g, mask, unit_culled);
      return;
    }
    const double eye_scale = kSphereGrowth * std::max({std::abs(view.eye.x), std::abs(view.eye.y), std::abs(view.eye.z)});
    for (const Group& g : groups_) {
      const glm::dvec3 to = g.center - view.eye;
      const double dist = glm::length(to);
      const double radius = g.radius + eye_scale;
      if (!(dist > radius)) {  // eye inside the sphere (or NaN): every direction is possible
        std::fill(unit_culled.begin() + g.begin, unit_culled.begin() + g.end, uint8_t{0});
        continue;
      }
      buildMask(to / dist, radius / dist, mask);
      andGroup(g, mask, unit_culled);
    }
  }

 private:
  // §2.1: the cell of the cube face that the ray along n crosses; cell index f·N² + i·N + j.
  int encode(const glm::dvec3& n) const {
    const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
    int k = 0;
    if (ay > ax && ay >= az) k = 1;
    else if (az > ax && az > ay) k = 2;
    const int a = k == 0 ? 1 : 0, b = k == 2 ? 1 : 2;
    const double nk = n[k];
    const int face = 2 * k + (nk < 0.0 ? 1 : 0);
    auto index = [&](double c) {
      const int i = static_cast<int>(std::floor((c / std::abs(nk) + 1.0) * 0.5 * n_));
      return std::clamp(i, 0, n_ - 1);
    };
    if (!(std::abs(nk) > 0.0)) return kNeverCell;
    return face * n_ * n_ + index(n[a]) * n_ + index(n[b]);
  }

  // Sets the bit of every cell whose four corners satisfy ĉ·axis > sin_theta + kCapMargin.
  void buildMask(const glm::dvec3& axis, double sin_theta, std::array<uint8_t, 256>& mask) const {
    mask.fill(0);
    const size_t m = u_.size();
    std::array<uint8_t, (kMaxResolution + 1) * (kMaxResolution + 1)> in{};
    const double limit = sin_theta + kCapMargin;
    for (int face = 0; face < 6; ++face) {
      const int k = face / 2;
      const double s = face % 2 == 0 ? 1.0 : -1.0;
      const int a = k == 0 ? 1 : 0, b = k == 2 ? 1 : 2;
      const double base = s * axis[k], aa = axis[a], ab = axis[b];
      // A face's normals lie within 54.8° of its centre; a cap of radius < 90° whose axis is more
      // than 145° away cannot reach it (cheap skip; the corner test decides everything else).
      if (base < -0.82) continue;
      bool any = false;
      for (size_t i = 0; i < m; ++i) {
        const double row = base + aa * u_[i];
        for (size_t j = 0; j < m; ++j) {
          const bool hit = (row + ab * u_[j]) * inv_len_[i * m + j] > limit;
          in[i * m + j] = hit;
          any |= hit;
        }
      }
      if (!any) continue;
      const int first = face * n_ * n_;
      for (int i = 0; i < n_; ++i) {
        for (int j = 0; j < n_; ++j) {
          const size_t c = static_cast<size_t>(i) * m + static_cast<size_t>(j);
          if (in[c] & in[c + 1] & in[c + m] & in[c + m + 1]) {
            const int cell = first + i * n_ + j;
            mask[static_cast<size_t>(cell >> 3)] |= static_cast<uint8_t>(1u << (cell & 7));
          }
        }
      }
    }
  }

  // §3: one AND per polygon.
  void andGroup(const Group& g, const std::array<uint8_t, 256>& mask, std::span<uint8_t> unit_culled) const {
    const uint8_t* off = offset_.data();
    const uint8_t* bit = bit_.data();
    uint8_t* out = unit_culled.data();
    for (uint32_t u = g.begin; u < g.end; ++u) out[u] = (mask[off[u]] & bit[u]) != 0;
  }

  void split(uint32_t begin, uint32_t end, size_t group_size, const std::vector<glm::dvec3>& centroid) {
    if (end - begin <= group_size) {
      if (end > begin) groups_.push_back({begin, end, glm::dvec3(0.0), 0.0});
      return;
    }
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (uint32_t u = begin; u < end; ++u) {
      lo = glm::min(lo, centroid[unit_polygons_[u]]);
      hi = glm::max(hi, centroid[unit_polygons_[u]]);
    }
    const glm::dvec3 ext = hi - lo;
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(unit_polygons_.begin() + begin, unit_polygons_.begin() + mid, unit_polygons_.begin() + end,
                     [&](uint32_t p, uint32_t q) { return centroid[p][axis] < centroid[q][axis]; });
    split(begin, mid, group_size, centroid);
    split(mid, end, group_size, centroid);
  }

  // The group's bounding sphere, grown so that it holds, for every vertex v, the point of the
  // polygon's plane nearest to v (|n·v − d| away): the cone test then speaks of the planes.
  void bound(Group& g, const BackfaceInput& input) const {
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (uint32_t u = g.begin; u < g.end; ++u) {
      const Polygon& poly = input.polygons[unit_polygons_[u]];
      for (uint32_t k = 0; k < poly.vertex_count; ++k) {
        lo = glm::min(lo, input.vertices[poly.first_vertex + k]);
        hi = glm::max(hi, input.vertices[poly.first_vertex + k]);
      }
    }
    if (g.begin == g.end) return;
    g.center = 0.5 * (lo + hi);
    double r = 0.0;
    for (uint32_t u = g.begin; u < g.end; ++u) {
      const Polygon& poly = input.polygons[unit_polygons_[u]];
      for (uint32_t k = 0; k < poly.vertex_count; ++k) {
        const glm::dvec3& v = input.vertices[poly.first_vertex + k];
        const double residual = std::abs(glm::dot(poly.plane.n, v) - poly.plane.d);
        r = std::max(r, glm::length(v - g.center) + residual);
      }
    }
    const double scale = std::max({std::abs(g.center.x), std::abs(g.center.y), std::abs(g.center.z), r});
    g.radius = r + kSphereGrowth * scale;
  }

  int n_;
  bool use_view_cone_;
  std::vector<double> u_, inv_len_;
  std::vector<Group> groups_;
  std::vector<uint8_t> offset_, bit_;  // per unit: the two bytes of §2.2
};

}  // namespace

std::unique_ptr<BackfaceCuller> makeNormalMaskCuller(const BackfaceInput& input, const BackfaceOptions& options) {
  return std::make_unique<NormalMaskCuller>(input, options);
}

}  // namespace walkvis
