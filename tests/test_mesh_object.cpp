// Mesh objects in walkthrough frames (mesh_object.h): the animated blob is placed in gen:office's
// start room and seen from the start; its pixels in painter's frames (BSP, PFD, HFD order; the
// painter's pass writing depth with GL_ALWAYS, the object then drawn with GL_LESS) equal its pixels
// in the z-buffer frame of the same view, ids for ids, including views where walls hide part of
// it; without the painter's depth writes the same check fails (so it can); Möller–Séquin culling
// while subdividing gives the same ids images as full subdivision and computes fewer triangles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "walkthrough/frame.h"
#include "walkthrough/mesh_object.h"
#include "walkthrough/osmesa_context.h"
#include "walkthrough/scene_drawer.h"
#include "frame_test_util.h"

namespace walkvis {
namespace {

bool isObject(const World& world, uint32_t id) {
  return id != kNoFragment && id >= world.trees.bsp.fragments.size();
}

FreeCamera lookingAt(const glm::dvec3& eye, const glm::dvec3& target) {
  FreeCamera c;
  c.eye = eye;
  // camera_path.h: yaw 0 looks along -z, positive turns towards -x.
  c.yaw = std::atan2(-(target.x - eye.x), -(target.z - eye.z));
  c.pitch = std::atan2(target.y - eye.y, std::hypot(target.x - eye.x, target.z - eye.z));
  c.width = kW;
  c.height = kH;
  return c;
}

// Eyes on level 0's height plane within 12 m of the blob (sampled in the tree cells), each looking
// at the blob: from the corridor, the lobby and the rooms whose doors open onto it.
std::vector<FreeCamera> camerasOnBlob(const World& world, int count, uint64_t seed) {
  std::vector<FreeCamera> cameras;
  const PfdLevel& level = world.trees.levels.at(0);
  const glm::dvec3 target = world.objects.at(0).center;
  uint64_t state = seed;
  for (int k = 0; k < 20000 && cameras.size() < static_cast<size_t>(count); ++k) {
    const PfdTree& tree = level.cells[static_cast<size_t>(k) % level.cells.size()];
    const glm::dvec2 p = samplePfdRegion(tree, state);
    if (std::hypot(p.x - target.x, p.y - target.z) > 12.0) continue;
    cameras.push_back(lookingAt({p.x, level.height, p.y}, target));
  }
  return cameras;
}

// Draws one frame (scene in `mode`, then the objects of the builder's last build) as ids.
void drawIds(const World& world, FrameBuilder& builder, SceneDrawer& drawer, const FreeCamera& camera,
             OrderMode mode, double time, bool painter_depth, std::vector<uint32_t>& ids) {
  std::vector<uint32_t> draw;
  builder.build(world, camera, mode, draw, time);
  DrawSettings s;
  s.style = DrawStyle::kIds;
  s.depth_test = s.cull_back_faces = mode == OrderMode::kZBuffer;
  s.write_depth = painter_depth && mode != OrderMode::kZBuffer;
  drawer.draw(camera, draw, s);
  for (const ObjectTriangles& o : builder.objects()) drawer.drawTriangles(camera, o.corners, o.ids, o.color, s);
  drawer.readIds(kW, kH, ids);
}

size_t objectPixels(const World& world, const std::vector<uint32_t>& ids) {
  size_t n = 0;
  for (uint32_t id : ids) n += isObject(world, id);
  return n;
}

TEST(MeshObject, BlobIsPlacedInTheOfficeStartRoomAndSeenFromTheStart) {
  const World& world = office();
  ASSERT_EQ(world.objects.size(), 1u);
  const MeshObject& blob = world.objects[0];
  EXPECT_EQ(blob.first_id, world.trees.bsp.fragments.size()) << "object ids follow the fragment ids";
  EXPECT_EQ(blob.finalTriangles(), 80u * 64u);
  // Standing on the floor under the start eye, below the eye, within a few eye heights of it.
  const double e = world.scene.eye_height;
  EXPECT_GT(blob.center.y - 1.45 * blob.scale, world.scene.levels[0].floor_y);
  EXPECT_LT(blob.center.y, world.scene.start_eye.y);
  EXPECT_LT(glm::length(blob.center - world.scene.start_eye), 3.0 * e);
  EXPECT_GT(blob.scale, 0.1 * e);

  Offscreen o = makeOffscreen();
  o.drawer.upload(world.trees.bsp, world.scene);
  FrameBuilder builder;
  FreeCamera start;
  start.eye = world.scene.start_eye;
  start.yaw = world.scene.start_yaw;
  start.width = kW;
  start.height = kH;
  std::vector<uint32_t> ids;
  drawIds(world, builder, o.drawer, start, OrderMode::kPfd, 0.0, true, ids);
  EXPECT_GT(objectPixels(world, ids), size_t(kW * kH / 100)) << "the blob is in view from the start";
  const FrameStats s = builder.build(world, start, OrderMode::kPfd, ids, 0.0);
  EXPECT_GT(s.object_triangles, 0u);
  EXPECT_LT(s.object_triangles, blob.finalTriangles()) << "only front-facing triangles are drawn";
  EXPECT_GT(s.object_triangles_computed, s.object_triangles);
}

TEST(MeshObject, PainterFramesShowTheObjectAsTheZBufferDoes) {
  const World& world = office();
  ASSERT_EQ(world.objects.size(), 1u);
  Offscreen o = makeOffscreen();
  o.drawer.upload(world.trees.bsp, world.scene);
  FrameBuilder builder;
  std::vector<uint32_t> truth, ids, alone;
  uint64_t object_pixels = 0, differing = 0, differing_without_depth = 0;
  int partly_hidden = 0, views_with_object = 0;
  const std::vector<FreeCamera> cameras = camerasOnBlob(world, 160, 5);
  for (size_t k = 0; k < cameras.size(); ++k) {
    const FreeCamera& camera = cameras[k];
    const double time = 0.37 * static_cast<double>(k);
    drawIds(world, builder, o.drawer, camera, OrderMode::kZBuffer, time, true, truth);
    const size_t visible = objectPixels(world, truth);
    if (visible == 0) continue;
    ++views_with_object;
    // The object alone (nothing drawn before it): how many pixels it covers unhidden.
    o.drawer.draw(camera, {}, DrawSettings{.style = DrawStyle::kIds, .depth_test = true});
    for (const ObjectTriangles& ot : builder.objects())
      o.drawer.drawTriangles(camera, ot.corners, ot.ids, ot.color, DrawSettings{.style = DrawStyle::kIds});
    o.drawer.readIds(kW, kH, alone);
    const size_t whole = objectPixels(world, alone);
    // Partly hidden by the scene: at least 10% of it and not all of it.
    if (visible < whole - whole / 10) ++partly_hidden;
    for (OrderMode mode : {OrderMode::kBsp, OrderMode::kPfd, OrderMode::kHfd}) {
      drawIds(world, builder, o.drawer, camera, mode, time, true, ids);
      for (size_t p = 0; p < ids.size(); ++p) {
        if (!isObject(world, ids[p]) && !isObject(world, truth[p])) continue;
        ++object_pixels;
        differing += ids[p] != truth[p];
      }
      // Without the painter's depth the object is drawn over everything: the check must see that.
      drawIds(world, builder, o.drawer, camera, mode, time, false, ids);
      for (size_t p = 0; p < ids.size(); ++p)
        differing_without_depth += (isObject(world, ids[p]) || isObject(world, truth[p])) && ids[p] != truth[p];
    }
  }
  std::printf("%d views show the blob, %d of them partly hidden; %llu object pixels compared\n", views_with_object,
              partly_hidden, static_cast<unsigned long long>(object_pixels));
  EXPECT_GE(views_with_object, 10);
  EXPECT_GE(partly_hidden, 3) << "some views must have walls in front of part of the blob";
  EXPECT_GT(object_pixels, 1000u);
  EXPECT_EQ(differing, 0u) << differing << " of " << object_pixels << " object pixels differ";
  EXPECT_GT(differing_without_depth, 100u);
}

TEST(MeshObject, CullingWhileSubdividingDrawsTheSameIds) {
  const World& world = office();
  ASSERT_EQ(world.objects.size(), 1u);
  const MeshObject& blob = world.objects[0];
  Offscreen o = makeOffscreen();
  o.drawer.upload(world.trees.bsp, world.scene);
  FrameBuilder builder;
  std::vector<uint32_t> draw, culled_ids, full_ids;
  ObjectTriangles culled, full;
  uint64_t computed_culled = 0, computed_full = 0, differing = 0, object_pixels = 0;
  std::vector<FreeCamera> cameras = camerasOnBlob(world, 16, 9);
  // Also close up, from all around the blob at 2-4 radii (eyes need not be walkable).
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> angle(-3.14159, 3.14159), dist(2.0, 4.0);
  for (int k = 0; k < 8; ++k) {
    // Along the corridor (x), where no wall stands between.
    const double a = (k % 2 ? 1.5708 : -1.5708) + 0.2 * angle(rng) / 3.14159, d = dist(rng) * 1.45 * blob.scale;
    cameras.push_back(lookingAt(blob.center + glm::dvec3(d * std::sin(a), 0.3 * d, d * std::cos(a)), blob.center));
  }
  for (size_t k = 0; k < cameras.size(); ++k) {
    const FreeCamera& camera = cameras[k];
    const double time = 0.61 * static_cast<double>(k);
    builder.build(world, camera, OrderMode::kZBuffer, draw, time);
    tessellateObject(blob, time, camera.eye, true, culled);
    tessellateObject(blob, time, camera.eye, false, full);
    EXPECT_EQ(culled.ids, full.ids) << "camera " << k;
    EXPECT_EQ(culled.corners, full.corners) << "camera " << k;
    computed_culled += culled.computed;
    computed_full += full.computed;
    DrawSettings z{.style = DrawStyle::kIds, .depth_test = true, .cull_back_faces = true};
    o.drawer.draw(camera, draw, z);
    o.drawer.drawTriangles(camera, culled.corners, culled.ids, culled.color, z);
    o.drawer.readIds(kW, kH, culled_ids);
    o.drawer.draw(camera, draw, z);
    o.drawer.drawTriangles(camera, full.corners, full.ids, full.color, z);
    o.drawer.readIds(kW, kH, full_ids);
    object_pixels += objectPixels(world, full_ids);
    for (size_t p = 0; p < full_ids.size(); ++p) differing += culled_ids[p] != full_ids[p];
  }
  EXPECT_GT(object_pixels, 3000u);
  EXPECT_EQ(differing, 0u);
  // Roughly half the surface faces away from any eye: culling skips most of its subdivision.
  EXPECT_LT(static_cast<double>(computed_culled), 0.75 * static_cast<double>(computed_full))
      << computed_culled << " vs " << computed_full;
}

TEST(MeshObject, ObjectSets) {
  EXPECT_EQ(parseObjectSet("none"), ObjectSet::kNone);
  EXPECT_EQ(parseObjectSet("blob"), ObjectSet::kBlob);
  EXPECT_EQ(parseObjectSet("auto"), ObjectSet::kAuto);
  EXPECT_THROW(parseObjectSet("teapot"), Error);
  const Scene& scene = office().scene;
  EXPECT_TRUE(makeObjects(ObjectSet::kNone, "gen:office", scene, 7).empty());
  EXPECT_TRUE(makeObjects(ObjectSet::kAuto, "freedoom2.wad:MAP01", scene, 7).empty());
  const std::vector<MeshObject> blob = makeObjects(ObjectSet::kBlob, "x.obj", scene, 7);
  ASSERT_EQ(blob.size(), 1u);
  EXPECT_EQ(blob[0].first_id, 7u);
  Scene no_levels;
  EXPECT_THROW(makeObjects(ObjectSet::kBlob, "empty", no_levels, 0), Error);
  EXPECT_TRUE(makeObjects(ObjectSet::kAuto, "gen:office", no_levels, 0).empty());
}

}  // namespace
}  // namespace walkvis
