// Offscreen renderer, cube cameras and the exact ray caster: readback is not blank, back faces are
// not drawn, painter's order matches the z-buffer for a known correct order and not for a wrong one,
// the GL rasteriser and the ray caster sample the same pixel-centre rays, and a 16-bit z-buffer
// loses to a 32-bit one on near-coplanar distant surfaces.
#include <gtest/gtest.h>

#include <random>

#include <glm/geometric.hpp>

#include "walkthrough/camera.h"
#include "walkthrough/raycast.h"
#include "walkthrough/renderer.h"
#include "walkthrough/validate.h"

namespace walkvis {
namespace {

struct Geometry {
  std::vector<glm::dvec3> vertices;
  std::vector<Polygon> polygons;
  // A convex polygon, counter-clockwise seen from its front.
  void add(std::initializer_list<glm::dvec3> loop) {
    Polygon p;
    p.first_vertex = static_cast<uint32_t>(vertices.size());
    p.vertex_count = static_cast<uint32_t>(loop.size());
    p.face_id = static_cast<uint32_t>(polygons.size());
    vertices.insert(vertices.end(), loop.begin(), loop.end());
    const glm::dvec3 a = vertices[p.first_vertex], b = vertices[p.first_vertex + 1], c = vertices[p.first_vertex + 2];
    p.plane.n = glm::normalize(glm::cross(b - a, c - a));
    p.plane.d = glm::dot(p.plane.n, a);
    polygons.push_back(p);
  }
  // A square facing +z at depth z, centred at (cx, cy), half-size h.
  void addQuadFacingZ(double cx, double cy, double z, double h) {
    add({{cx - h, cy - h, z}, {cx + h, cy - h, z}, {cx + h, cy + h, z}, {cx - h, cy + h, z}});
  }
};

OffscreenRenderer makeRenderer(int size, int bits) {
  std::string why;
  auto r = OffscreenRenderer::create(size, bits, &why);
  if (!r) throw std::runtime_error("no renderer: " + why);
  return std::move(*r);
}

size_t countId(const std::vector<uint32_t>& ids, uint32_t id) { return std::count(ids.begin(), ids.end(), id); }

TEST(Camera, ClipMatrixPutsPixelRaysOnPixelCentres) {
  for (int face = 0; face < kCubeFaces; ++face) {
    const View view{{3.0, -2.0, 7.5}, face, 64, 0.1, 500.0};
    const CubeFrame f = cubeFrame(face);
    EXPECT_EQ(glm::cross(f.up, f.right), f.forward) << "face " << face;
    const std::array<float, 16> m = clipFromEyeRelative(view);
    for (int j : {0, 17, 63}) {
      for (int i : {0, 40, 63}) {
        const glm::dvec3 dir = pixelRay(view, i, j);
        EXPECT_DOUBLE_EQ(glm::dot(dir, f.forward), 1.0);
        const glm::dvec3 p = 7.0 * dir;
        double clip[4];
        for (int r = 0; r < 4; ++r) clip[r] = m[0 * 4 + r] * p.x + m[1 * 4 + r] * p.y + m[2 * 4 + r] * p.z + m[3 * 4 + r];
        const double x_window = (clip[0] / clip[3] * 0.5 + 0.5) * view.size;
        const double y_window = (clip[1] / clip[3] * 0.5 + 0.5) * view.size;  // GL rows from the bottom
        EXPECT_NEAR(x_window, i + 0.5, 1e-4);
        EXPECT_NEAR(y_window, view.size - 1 - j + 0.5, 1e-4);
        EXPECT_NEAR(clip[3], 7.0, 1e-5);  // w is the camera depth t
      }
    }
  }
}

TEST(Renderer, RejectsBadDepthBits) {
  std::string why;
  EXPECT_FALSE(OffscreenRenderer::create(32, 12, &why));
  EXPECT_FALSE(why.empty());
}

TEST(Renderer, ReadbackIsNotBlankAndBackFacesAreNotDrawn) {
  OffscreenRenderer r = makeRenderer(64, 24);
  EXPECT_NE(r.glRenderer().find("4.5"), std::string::npos) << r.glRenderer();
  Geometry g;
  g.addQuadFacingZ(0.0, 0.0, -5.0, 1.0);  // 0: seen from the origin looking down -z
  g.add({{-1, -1, -4}, {-1, 1, -4}, {1, 1, -4}, {1, -1, -4}});  // 1: nearer, but facing away (-z)
  r.upload(g.vertices, g.polygons);
  const View view{{0, 0, 0}, 5, 64, 0.1, 100.0};
  const std::vector<uint32_t> order{0, 1};
  for (int mode = 0; mode < 2; ++mode) {
    if (mode == 0) r.drawPainter(view, order);
    else r.drawZBuffer(view);
    const std::vector<uint32_t> ids = r.readIds();
    ASSERT_EQ(ids.size(), 64u * 64u);
    // The quad spans ndc [-0.2, 0.2]: pixels 25.6..38.4 → columns 26..37 (12 × 12).
    EXPECT_EQ(countId(ids, 0), 144u) << "mode " << mode;
    EXPECT_EQ(countId(ids, 1), 0u) << "back face drawn, mode " << mode;
    EXPECT_EQ(ids[32 * 64 + 32], 0u);
    EXPECT_EQ(ids[0], kNoPolygon);
  }
  // Other faces see nothing; the +z face sees the back of nothing.
  r.drawZBuffer({{0, 0, 0}, 4, 64, 0.1, 100.0});
  EXPECT_EQ(countId(r.readIds(), kNoPolygon), 64u * 64u);
}

// Quads at distinct depths, all facing the eyes (which stay at z > -1): back to front is by z.
Geometry stackedQuads() {
  Geometry g;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int k = 0; k < 12; ++k) g.addQuadFacingZ(u(rng), u(rng), -2.0 - 0.5 * k, 0.8 + 0.1 * (k % 4));
  return g;
}

Scene eyeRegionScene(double half) {
  Scene scene;
  scene.eye_height = 1.7;
  FloorLevel level;
  level.floor_y = -1.7;
  level.walkable.push_back({{-half, -half}, {-half, half}, {half, half}, {half, -half}});
  level.walkable_area = 4 * half * half;
  scene.levels.push_back(level);
  return scene;
}

TEST(Renderer, PainterMatchesZBufferForCorrectOrderOnly) {
  const Geometry g = stackedQuads();
  OffscreenRenderer r = makeRenderer(96, 24);
  r.upload(g.vertices, g.polygons);
  std::vector<uint32_t> back_to_front;
  for (uint32_t k = static_cast<uint32_t>(g.polygons.size()); k-- > 0;) back_to_front.push_back(k);
  std::vector<uint32_t> wrong(back_to_front.rbegin(), back_to_front.rend());
  size_t correct_diff = 0, wrong_diff = 0;
  for (const glm::dvec3 eye : {glm::dvec3(0, 0, 0), glm::dvec3(0.4, -0.3, -0.5), glm::dvec3(-0.6, 0.5, 0.8)}) {
    const View view{eye, 5, 96, 0.05, 100.0};
    r.drawZBuffer(view);
    const auto z = r.readIds();
    r.drawPainter(view, back_to_front);
    const auto good = r.readIds();
    r.drawPainter(view, wrong);
    const auto bad = r.readIds();
    EXPECT_GT(g.polygons.size() - countId(z, kNoPolygon), 0u);
    for (size_t k = 0; k < z.size(); ++k) {
      correct_diff += good[k] != z[k];
      wrong_diff += bad[k] != z[k];
    }
  }
  EXPECT_EQ(correct_diff, 0u);
  EXPECT_GT(wrong_diff, 1000u);

  // The same through runValidation: zero order errors for the right order, many for the wrong one.
  const Scene scene = eyeRegionScene(0.8);
  ValidationOptions options;
  options.eyes = 4;
  options.size = 64;
  options.zbits = {24};
  const ValidationResult ok = runValidation(
      scene, g.vertices, g.polygons, [&](const glm::dvec3&, std::vector<uint32_t>& out) { out = back_to_front; },
      options);
  EXPECT_EQ(ok.views, 24u);
  EXPECT_EQ(ok.pixels, 24u * 64 * 64);
  EXPECT_EQ(ok.painter.order_error, 0u);
  EXPECT_EQ(ok.zbuffer.at(0).counts.order_error, 0u);
  EXPECT_GT(ok.exact_pixels, 0u);
  const ValidationResult bad = runValidation(
      scene, g.vertices, g.polygons, [&](const glm::dvec3&, std::vector<uint32_t>& out) { out = wrong; }, options);
  EXPECT_GT(bad.painter.order_error, 500u);
  EXPECT_GT(bad.worst_views.at(0).painter.order_error, 0u);
  EXPECT_EQ(bad.zbuffer.at(0).counts.order_error, 0u);  // the z-buffer ignores the order
}

// Random non-intersecting triangles: each lies in its own cell of a grid around the eye.
Geometry randomTriangles(uint64_t seed) {
  Geometry g;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.45, 0.45);
  for (int x = -3; x <= 3; ++x)
    for (int y = -3; y <= 3; ++y)
      for (int z = -3; z <= 3; ++z) {
        if (x == 0 && y == 0 && z == 0) continue;  // the eye's cell
        const glm::dvec3 c(x, y, z);
        glm::dvec3 a = c + glm::dvec3(u(rng), u(rng), u(rng)), b = c + glm::dvec3(u(rng), u(rng), u(rng)),
                   d = c + glm::dvec3(u(rng), u(rng), u(rng));
        if (glm::length(glm::cross(b - a, d - a)) < 0.05) continue;
        // Face the origin so that most are drawn.
        if (glm::dot(glm::cross(b - a, d - a), a) > 0.0) std::swap(b, d);
        g.add({a, b, d});
      }
  return g;
}

TEST(RayCast, MatchesZBufferExceptAtEdges) {
  for (uint64_t seed : {1u, 2u}) {
    const Geometry g = randomTriangles(seed);
    OffscreenRenderer r = makeRenderer(128, 32);
    r.upload(g.vertices, g.polygons);
    const RayCaster caster(g.vertices, g.polygons);
    const glm::dvec3 eye(0.02, -0.03, 0.01);
    const std::vector<uint8_t> front = caster.frontFacing(eye);
    size_t covered = 0, differ = 0;
    PixelCounts counts;
    double worst_t = 0.0;
    for (int face = 0; face < kCubeFaces; ++face) {
      const View view{eye, face, 128, 0.05, 20.0};
      r.drawZBuffer(view);
      const auto ids = r.readIds();
      std::vector<RayHit> nearest;
      caster.castNearest(view, front, nearest);
      for (size_t k = 0; k < ids.size(); ++k) {
        covered += nearest[k].polygon != kNoPolygon;
        const int i = static_cast<int>(k % 128), j = static_cast<int>(k / 128);
        if (ids[k] == nearest[k].polygon) {
          if (ids[k] != kNoPolygon && k % 97 == 0) {
            const auto hits = caster.exactHits(view, front, i, j);
            ASSERT_FALSE(hits.empty());
            EXPECT_EQ(hits[0].polygon, ids[k]);
            worst_t = std::max(worst_t, std::abs(hits[0].t - nearest[k].t) / hits[0].t);
          }
          continue;
        }
        ++differ;
        const std::vector<uint32_t> shown{ids[k]};
        const auto hits = caster.exactHits(view, front, i, j, shown);
        const PixelClass cls = classifyPixel(ids[k], hits);
        counts.add(cls);
        if (cls == PixelClass::kOrderError) {
          ADD_FAILURE() << "order error at face " << face << " pixel " << i << "," << j << " shown " << ids[k]
                        << " embree " << nearest[k].polygon << " t " << nearest[k].t << " format " << r.depthFormat();
          for (const RayHit& h : hits) ADD_FAILURE() << "  hit " << h.polygon << " t " << h.t;
        }
      }
    }
    EXPECT_GT(covered, 20000u) << "seed " << seed;
    EXPECT_EQ(counts.order_error, 0u) << "seed " << seed;
    EXPECT_LT(static_cast<double>(differ), 0.01 * covered) << "seed " << seed;
    EXPECT_LT(worst_t, 1e-5);
  }
}

TEST(Classify, Cases) {
  const RayHit a{1, 10.0, true}, b{2, 10.0 + 1e-9, true}, c{3, 12.0, true};
  const std::vector<RayHit> hits{a, c};
  EXPECT_EQ(classifyPixel(1, hits), PixelClass::kMatch);
  EXPECT_EQ(classifyPixel(3, hits), PixelClass::kOrderError);
  EXPECT_EQ(classifyPixel(7, hits), PixelClass::kEdge);
  EXPECT_EQ(classifyPixel(kNoPolygon, hits), PixelClass::kUncovered);
  EXPECT_EQ(classifyPixel(kNoPolygon, {}), PixelClass::kMatch);
  EXPECT_EQ(classifyPixel(1, {}), PixelClass::kEdge);
  const std::vector<RayHit> tied{a, b, c};
  EXPECT_EQ(classifyPixel(1, tied), PixelClass::kTie);
  EXPECT_EQ(classifyPixel(2, tied), PixelClass::kTie);
  EXPECT_EQ(classifyPixel(3, tied), PixelClass::kOrderError);
  // Nearer hits that only graze the pixel centre (within the edge margin) make a coverage case.
  const std::vector<RayHit> grazing{{1, 10.0, false}, {3, 12.0, true}, {4, 13.0, true}};
  EXPECT_EQ(classifyPixel(3, grazing), PixelClass::kEdge);
  EXPECT_EQ(classifyPixel(4, grazing), PixelClass::kOrderError);
}

// freedoom2 MAP18's BSP has a fragment whose split points rounded onto its first vertex, so its fan
// starts with zero-area triangles. Those cover nothing (a rasteriser draws nothing for them); the
// exact test once counted every point of the plane as inside them, which made a false order error.
TEST(RayCast, ZeroAreaFanTrianglesCoverNothing) {
  const Plane floor{{0.0, 1.0, 0.0}, 208.0};
  const std::vector<glm::dvec3> sliver{{592, 208, -1328}, {592, 208, -1328}, {592, 208, -1328},
                                       {587.72752043596734, 208, -1270.3215258855587}, {624, 208, -1248}};
  const glm::dvec3 eye{525.0818304334783, 249.0, -1286.4630586834583};
  // Inside the real triangle, 2e-4 units from its edge: a hit.
  EXPECT_TRUE(exactPolygonHit(sliver, floor, eye, {1.0, -0.41796875, 0.37109375}, 0.1, 1e4).has_value());
  // Outside it (to the side of the edge towards +z and far away): no hit, whatever the fan's
  // zero-area triangles would say.
  EXPECT_FALSE(exactPolygonHit(sliver, floor, eye, {1.0, -0.41796875, 0.40}, 0.1, 1e4).has_value());
  EXPECT_FALSE(exactPolygonHit(sliver, floor, eye, {1.0, -0.2, -0.9}, 0.1, 1e4).has_value());
  const std::vector<glm::dvec3> point{{1, 0, 1}, {1, 0, 1}, {1, 0, 1}};
  EXPECT_FALSE(exactPolygonHit(point, {{0.0, 1.0, 0.0}, 0.0}, {0, 5, 0}, {0.0, -1.0, 0.0}, 0.1, 1e4).has_value());
}

TEST(ZBuffer, SixteenBitsLoseToThirtyTwoOnNearCoplanarDistantSurfaces) {
  // Two large walls 100 units away, 0.02 apart, the nearer one in front: a 16-bit depth buffer
  // with near = 0.085 cannot separate them; 32 bits can.
  Geometry g;
  g.add({{-300, -300, -100.02}, {300, -300, -100.02}, {300, 300, -100.02}, {-300, 300, -100.02}});
  g.add({{-300, -300, -100}, {300, -300, -100}, {300, 300, -100}, {-300, 300, -100}});
  const Scene scene = eyeRegionScene(1.0);
  ValidationOptions options;
  options.eyes = 2;
  options.size = 64;
  options.zbits = {16, 32};
  options.near = 0.085;
  const ValidationResult res = runValidation(
      scene, g.vertices, g.polygons, [](const glm::dvec3&, std::vector<uint32_t>& out) { out = {0, 1}; }, options);
  ASSERT_EQ(res.zbuffer.size(), 2u);
  EXPECT_EQ(res.painter.order_error, 0u);
  EXPECT_GT(res.zbuffer[0].counts.order_error, 1000u);
  EXPECT_LT(res.zbuffer[1].counts.order_error, res.zbuffer[0].counts.order_error / 10);
}

}  // namespace
}  // namespace walkvis
