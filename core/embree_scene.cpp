#include "core/embree_scene.h"

#include <string>
#include <utility>

#include "core/check.h"
#include "core/error.h"

namespace walkvis {

EmbreeScene::EmbreeScene(const EmbreeTriangles& t, std::string_view context) {
  WALKVIS_DCHECK(t.indices.size() % 3 == 0);
  const std::string where(context);
  device_ = rtcNewDevice(nullptr);
  if (!device_) throw Error(where + ": Embree rtcNewDevice failed");
  scene_ = rtcNewScene(device_);
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
  if (!t.indices.empty()) {
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                           3 * sizeof(float), t.vertices.size()));
    auto* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(uint32_t), t.indices.size() / 3));
    if (!vb || !ib) {
      const RTCError error = rtcGetDeviceError(device_);
      rtcReleaseGeometry(geom);
      release();
      throw Error(where + ": Embree buffer allocation failed (error " + std::to_string(error) + ")");
    }
    for (size_t k = 0; k < t.vertices.size(); ++k) {
      const glm::vec3 p(t.vertices[k] - t.origin);
      vb[3 * k] = p.x, vb[3 * k + 1] = p.y, vb[3 * k + 2] = p.z;
    }
    for (size_t k = 0; k < t.indices.size(); ++k) {
      WALKVIS_DCHECK(t.indices[k] < t.vertices.size());
      ib[k] = t.indices[k];
    }
    if (t.user_data) rtcSetGeometryUserData(geom, t.user_data);
    if (t.intersect_filter) rtcSetGeometryIntersectFilterFunction(geom, t.intersect_filter);
    if (t.occluded_filter) rtcSetGeometryOccludedFilterFunction(geom, t.occluded_filter);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(scene_);
  if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) {
    release();
    throw Error(where + ": Embree scene build failed");
  }
}

EmbreeScene::EmbreeScene(EmbreeScene&& other) noexcept
    : device_(std::exchange(other.device_, nullptr)), scene_(std::exchange(other.scene_, nullptr)) {}

EmbreeScene& EmbreeScene::operator=(EmbreeScene&& other) noexcept {
  if (this != &other) {
    release();
    device_ = std::exchange(other.device_, nullptr);
    scene_ = std::exchange(other.scene_, nullptr);
  }
  return *this;
}

EmbreeScene::~EmbreeScene() { release(); }

void EmbreeScene::release() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
  scene_ = nullptr;
  device_ = nullptr;
}

}  // namespace walkvis
