// The normal-mask grid of Zhang & Hoff 1997 [ZhangHoff1997] (normal_mask.cpp), shared by the
// whole-mesh culler (method `mask`) and the priority-list culler (list_cull.cpp).
//
// §2: the normal sphere is cut by the N×N grids of the six faces of its bounding cube into 6·N²
// clusters (N <= 18, so 6·N² <= 2048 = the paper's 256-byte mask). A polygon stores its cluster id,
// two bytes. §3: per frame the clusters whose every normal is back-facing for every direction of a
// cone are set in a table; the test per polygon is then one table read. The table is a byte per
// cluster (2048 bytes, 0 or 1) rather than the paper's bit per cluster: the read is then a plain
// load indexed by the 2-byte id, with no shift or AND, and the loop has no branch.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace walkvis {

// The grid side N for `requested` (1..18: itself, anything else is NormalMaskGrid's error) or, for
// requested == 0, for a mesh of `polygons` polygons: the largest N with 6·N² <= polygons / 5, in
// [4, 16]. The per-frame table tests 6·N² cells, so on small meshes it costs more than the one
// AND per polygon it enables; Zhang & Hoff's table (§4) shows culling saturating with N (39.9% at
// 6·8², 42.6% at 6·16²), so small meshes lose little (the figures on our meshes:
// docs/backface/README.md, "Normal masks").
int maskResolutionFor(size_t polygons, int requested);

class NormalMaskGrid {
 public:
  static constexpr int kMaxResolution = 18;  // 6·18² = 1944 clusters <= 2048
  static constexpr uint16_t kNeverCell = 2047;  // a zero or non-finite normal: never culled
  // 2048 entries and 16 zero bytes after them, so that 16 entries can be loaded from any cluster id
  // (normal_mask.cpp reads 16 polygons' entries with one load and one byte shuffle).
  static constexpr size_t kTablePadding = 16;
  using Table = std::array<uint8_t, 2048 + kTablePadding>;

  // Throws Error unless 1 <= n <= kMaxResolution.
  explicit NormalMaskGrid(int n);

  int resolution() const { return n_; }
  // §2.1: the cluster of the cube face that the ray along `normal` crosses (any length > 0).
  uint16_t cell(const glm::dvec3& normal) const;
  // §3.1: table[c] = 1 for every cluster c all of whose normals n̂ satisfy n̂·axis > sin_theta (with
  // a margin against rounding), i.e. back-facing for every direction of the cone of half-angle θ
  // around `axis` (unit length); all other cells 0, and 0 at the kTablePadding entries after the
  // last cell, at kNeverCell and in the padding; the entries in between are left as they were.
  void backTable(const glm::dvec3& axis, double sin_theta, Table& table) const;
  // The four unit corner directions of cluster `cell`, in single precision, exactly as backTable
  // tests them (cell i, j of a face: corners (i, j), (i, j+1), (i+1, j), (i+1, j+1)); zero vectors
  // for kNeverCell or any id >= 6·N² (never inside a cap: its limit is >= kMaskCapMargin > 0). A
  // cluster is back-facing for a cone exactly when all four satisfy c·axis > float(sin θ +
  // kMaskCapMargin), evaluated in float as (c.x·a.x + c.y·a.y) + c.z·a.z.
  std::array<glm::vec3, 4> cellCorners(uint16_t cell) const;

 private:
  int n_;
  size_t stride_ = 0;  // floats per row of corners: N + 1 rounded up to a multiple of 4
  // Unit corner directions of each face's (N+1)² grid in single precision (the per-frame test
  // is 4 corners per SSE operation), structure of arrays: corner_[face][axis][row * stride_ + column].
  std::array<std::array<std::vector<float>, 3>, 6> corner_;
};

// Margin on the cap test n̂·axis > sin θ, evaluated in single precision: the float corner
// directions, axis and limit (relative error 2⁻²⁴ each) and the three-term sum stay below 5e-7 in
// all; 2e-6 leaves a factor four and only spares clusters within ~2e-6 rad of the rim.
inline constexpr double kMaskCapMargin = 2e-6;

// A cone from `eye` around the sphere (center, radius) holding every direction from the eye to the
// sphere: returns false when the eye is inside the sphere (or the input is not finite); otherwise
// sets axis (unit) and sin_theta. `radius` is the build-time radius, grown by kMaskSphereGrowth of
// the centre's and radius' magnitude; the eye's share of the growth is added here.
bool sphereCone(const glm::dvec3& eye, const glm::dvec3& center, double radius, glm::dvec3& axis, double& sin_theta);

// Relative growth of a group's bounding sphere, of the coordinates' magnitude (its centre's and
// radius' at build time, the eye's per frame): a culled group's sphere then clears the eye's
// tangent cone by this much, far more than the ground truth's own rounding (4·2⁻⁵³ of the same
// magnitudes), so a polygon isFrontFacing() calls front-facing is never inside a culled cone.
inline constexpr double kMaskSphereGrowth = 1e-9;

}  // namespace walkvis
