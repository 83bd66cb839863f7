// The baseline: the plane test per polygon (the traditional backface test, e.g. Johannsen &
// Carter 1998 [JohannsenCarter1998] §2: a polygon faces away from e iff n·(e − p) <= 0). Stored as
// n and d of each plane, structure of arrays, in double: the test is isFrontFacing() itself,
// evaluated in the same order of operations, so it culls exactly the polygons that are not
// front-facing.
#include <numeric>

#include "backface/backface.h"

#include "core/check.h"

namespace walkvis {
namespace {

class PolygonCuller final : public BackfaceCuller {
 public:
  explicit PolygonCuller(const BackfaceInput& input) {
    const size_t n = input.polygons.size();
    polygon_count_ = n;
    nx_.resize(n);
    ny_.resize(n);
    nz_.resize(n);
    d_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const Plane& p = input.polygons[i].plane;
      nx_[i] = p.n.x;
      ny_[i] = p.n.y;
      nz_[i] = p.n.z;
      d_[i] = p.d;
    }
    unit_begin_.resize(n + 1);
    std::iota(unit_begin_.begin(), unit_begin_.end(), 0u);
    unit_polygons_.resize(n);
    std::iota(unit_polygons_.begin(), unit_polygons_.end(), 0u);
  }

  BackfaceMethod method() const override { return BackfaceMethod::kPolygon; }
  size_t stateBytes() const override { return polygon_count_ * 4 * sizeof(double); }

  void cull(const BackfaceView& view, std::span<uint8_t> unit_culled) const override {
    WALKVIS_DCHECK(unit_culled.size() == unitCount());
    const double ex = view.eye.x, ey = view.eye.y, ez = view.eye.z;
    const size_t n = polygon_count_;
    const double* nx = nx_.data();
    const double* ny = ny_.data();
    const double* nz = nz_.data();
    const double* d = d_.data();
    uint8_t* out = unit_culled.data();
    // Same expression as glm::dot (x + y) + z, so the result equals isFrontFacing() bit for bit.
    for (size_t i = 0; i < n; ++i) out[i] = !((nx[i] * ex + ny[i] * ey) + nz[i] * ez > d[i]);
  }

 private:
  std::vector<double> nx_, ny_, nz_, d_;
};

}  // namespace

std::unique_ptr<BackfaceCuller> makePolygonCuller(const BackfaceInput& input) {
  return std::make_unique<PolygonCuller>(input);
}

}  // namespace walkvis
