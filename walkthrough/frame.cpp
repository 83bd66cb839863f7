// Walkthrough frames (frame.h): the order sources are the BSP back-to-front traversal (Fuchs, Kedem,
// Naylor 1980 [FuchsKedemNaylor1980]) and the PFD/HFD trees (James & Day 1998 [JamesDay1998,
// JamesDay1998HFD]; docs/DESIGN.md, "PFD tree" and "HFD tree"); backface culling inside priority
// lists is backface/list_cull.h (docs/DESIGN.md, "Facing at emission").
#include "walkthrough/frame.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstring>
#include <fstream>
#include <numeric>

#include <glm/geometric.hpp>

#include "core/check.h"

namespace walkvis {
namespace {

bool isRunTimeMethod(ListCullMethod m) {
  return m == ListCullMethod::kPolygon || m == ListCullMethod::kMask || m == ListCullMethod::kCluster ||
         m == ListCullMethod::kHierarchy;
}

// A tree file holds the BSP and the trees, not the scene: the fragments stand in for the polygons,
// the trees' regions for the walkable levels, and the stable faceColor() for the colours.
Scene sceneFromTrees(const TreeFile& trees, const std::string& source) {
  Scene scene;
  scene.name = source;
  scene.vertices = trees.bsp.vertices;
  scene.polygons = trees.bsp.fragments;
  uint32_t faces = 0;
  for (const Polygon& p : scene.polygons) faces = std::max(faces, p.face_id + 1);
  scene.face_colors.resize(faces);
  for (uint32_t f = 0; f < faces; ++f) scene.face_colors[f] = faceColor(f);
  scene.eye_height = trees.eye_height;
  for (const PfdLevel& level : trees.levels) {
    FloorLevel fl;
    fl.floor_y = level.floor_y;
    for (const PfdTree& cell : level.cells)
      for (const auto& piece : cell.region) fl.walkable.push_back(piece);
    scene.levels.push_back(std::move(fl));
  }
  // No loader's start: placeStartEye takes the centre of a region piece, well inside where the
  // trees answer (a made-up start such as the origin may lie on a region's edge, in the plane of a
  // wall, where nothing is defined).
  scene.start_eye = glm::dvec3(std::numeric_limits<double>::quiet_NaN());
  placeStartEye(scene);
  return scene;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The circular cone around the camera's frustum (list_cull.h's view cone): the full apex angle
// through the image's corners.
BackfaceView backfaceView(const FreeCamera& camera, const glm::dvec3& eye) {
  BackfaceView view;
  view.eye = eye;
  view.view_dir = cameraFrame(camera).forward;
  const double aspect = static_cast<double>(camera.width) / std::max(camera.height, 1);
  const double t = std::tan(0.5 * camera.fov_y);
  view.fov = std::min(2.0 * std::atan(t * std::sqrt(1.0 + aspect * aspect)), 3.14);
  return view;
}

}  // namespace

std::string_view orderModeName(OrderMode mode) {
  switch (mode) {
    case OrderMode::kZBuffer: return "zbuffer";
    case OrderMode::kBsp: return "bsp";
    case OrderMode::kPfd: return "pfd";
    case OrderMode::kHfd: return "hfd";
  }
  return "?";
}

OrderMode parseOrderMode(std::string_view name) {
  for (OrderMode m : {OrderMode::kZBuffer, OrderMode::kBsp, OrderMode::kPfd, OrderMode::kHfd})
    if (orderModeName(m) == name) return m;
  throw Error("order mode '" + std::string(name) + "': expected zbuffer, bsp, pfd or hfd");
}

std::optional<uint32_t> World::levelAt(const glm::dvec3& eye) const {
  for (size_t i = 0; i < trees.levels.size(); ++i) {
    const double h = trees.levels[i].height;
    // Paths store eyes in decimal text: a height read back may be off by a few ulps of its scale.
    if (std::abs(eye.y - h) <= 1e-9 * std::max(1.0, std::abs(h))) return static_cast<uint32_t>(i);
  }
  return std::nullopt;
}

World openWorld(const std::string& source, const WorldOptions& options,
                const std::function<void(const std::string&)>& progress) {
  auto say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  World world;
  world.source = source;
  world.cull = options.cull;
  world.frustum_culling = options.frustum_culling;
  world.occlusion_culling = options.occlusion_culling;
  world.occlusion = options.occlusion;
  if (isTreeFile(source)) {
    say("loading tree file " + source);
    world.trees = loadTreeFile(source);
    if (!options.scene.empty()) {
      world.scene = loadScene(options.scene, options.load);
      checkBspMatchesScene(world.trees.bsp, world.scene, source);
      world.scene.eye_height = world.trees.eye_height;
    } else {
      world.scene = sceneFromTrees(world.trees, source);
    }
  } else {
    say("loading " + source);
    world.scene = loadScene(source, options.load);
    say("building the BSP of " + std::to_string(world.scene.polygons.size()) + " polygons");
    world.trees.bsp = buildBsp(world.scene);
    world.trees.eye_height = world.scene.eye_height;
    if (options.build_pfd) {
      PfdLevelOptions level_options;
      level_options.tree.stat_eyes = 0;
      // Run-time methods need the back faces in the lists; otherwise the exact region method.
      level_options.tree.drop_back_faces = !isRunTimeMethod(options.cull);
      uint64_t used = 0;
      world.trees.levels =
          buildPfdLevels(world.trees.bsp, world.scene.levels, world.scene.eye_height, level_options, used, progress);
    }
  }
  const BspTree& bsp = world.trees.bsp;
  const uint32_t n = static_cast<uint32_t>(bsp.fragments.size());
  world.fragment_balls.reserve(n);
  for (const Polygon& f : bsp.fragments) world.fragment_balls.push_back(polygonBall(bsp.vertices, f));
  world.objects = makeObjects(options.objects, options.scene.empty() ? source : options.scene, world.scene, n);
  if (options.cull != ListCullMethod::kNone) {
    say(std::string("building list cullers (") + std::string(listCullMethodName(options.cull)) + ")");
    const BackfaceInput input{bsp.vertices, bsp.fragments};
    world.all_fragments.resize(n);
    std::iota(world.all_fragments.begin(), world.all_fragments.end(), 0u);
    const IndexRange all{0, n};
    world.all_culler = std::make_unique<ListCuller>(
        ListCuller::build(input, world.all_fragments, std::span<const IndexRange>(&all, 1), options.cull,
                          options.backface));
    if (isRunTimeMethod(options.cull)) {
      std::vector<IndexRange> ranges;
      for (const PfdLevel& level : world.trees.levels) {
        auto& per_cell = world.run_cullers.emplace_back();
        for (const PfdTree& tree : level.cells) {
          ranges.clear();
          for (const PfdRun& r : tree.runs) ranges.push_back({r.first, r.count});
          per_cell.push_back(ListCuller::build(input, tree.fragment_ids, ranges, options.cull, options.backface));
        }
      }
    }
  }
  return world;
}

FrameStats FrameBuilder::build(const World& world, const FreeCamera& camera, OrderMode mode,
                               std::vector<uint32_t>& draw, double time) {
  const auto t0 = std::chrono::steady_clock::now();
  const BspTree& bsp = world.trees.bsp;
  const uint32_t n = static_cast<uint32_t>(bsp.fragments.size());
  FrameStats stats;
  stats.scene_polygons = n;
  draw.clear();
  const ListCullMethod method = world.all_culler ? world.cull : ListCullMethod::kNone;

  if (mode == OrderMode::kZBuffer) {
    stats.used = OrderMode::kZBuffer;
    stats.listed = n;
    if (method != ListCullMethod::kNone) {
      stats.culled = world.all_culler->cullRange(0, backfaceView(camera, camera.eye), draw);
    } else {
      draw.resize(n);
      std::iota(draw.begin(), draw.end(), 0u);
    }
  } else {
    bool done = false;
    if (mode == OrderMode::kPfd || mode == OrderMode::kHfd) {
      if (const std::optional<uint32_t> level = world.levelAt(camera.eye)) {
        const PfdLevel& pl = world.trees.levels[*level];
        // The tree answers for eyes ON its height plane: snap the few ulps a path file may add.
        const glm::dvec3 eye(camera.eye.x, pl.height, camera.eye.z);
        if (const PfdTree* tree = findPfdCell(pl, eye); tree && !tree->nodes.empty()) {
          // Run indices, not runs: the list cullers are per run.
          const PfdQueryResult q = pfdQueryRunIds(*tree, eye, run_indices_);
          stats.tests = q.tests + q.object_tests;
          const ListCuller* culler = nullptr;
          if (*level < world.run_cullers.size()) {
            const size_t cell = static_cast<size_t>(tree - pl.cells.data());
            if (cell < world.run_cullers[*level].size()) culler = &world.run_cullers[*level][cell];
          }
          const BackfaceView view = backfaceView(camera, eye);
          for (uint32_t r : run_indices_) stats.listed += tree->runs[r].count;
          if (culler) {
            stats.culled += culler->cullRanges(run_indices_, view, draw);  // all runs in one call
          } else {
            for (uint32_t r : run_indices_) {
              const PfdRun& run = tree->runs[r];
              draw.insert(draw.end(), tree->fragment_ids.begin() + run.first,
                          tree->fragment_ids.begin() + run.first + run.count);
            }
          }
          stats.level = static_cast<int>(*level);
          stats.used = mode;
          done = true;
        }
      }
    }
    if (!done) {
      // The BSP path: any eye (off the height plane, stairs, no tree).
      stats.used = OrderMode::kBsp;
      stats.tests = static_cast<uint32_t>(bsp.nodes.size());
      stats.listed = n;
      if (method == ListCullMethod::kNone) {
        backToFront(bsp, camera.eye, draw, false);
      } else if (method == ListCullMethod::kPolygon || method == ListCullMethod::kRegion) {
        // The per-polygon plane test, fused into the traversal (the same test, exact).
        backToFront(bsp, camera.eye, draw, true);
      } else {
        backToFront(bsp, camera.eye, scratch_, false);
        run_indices_.clear();
        world.all_culler->cullRange(0, backfaceView(camera, camera.eye), run_indices_);
        keep_.assign(n, 0);
        for (uint32_t f : run_indices_) keep_[f] = 1;
        for (uint32_t f : scratch_)
          if (keep_[f]) draw.push_back(f);
      }
      stats.culled = n - static_cast<uint32_t>(draw.size());
    }
  }
  if (world.frustum_culling) {
    WALKVIS_DCHECK(world.fragment_balls.size() == n);  // World's rule: a ball per fragment
    // In place: the order of what stays is the order that was made.
    const ViewFrustum frustum = viewFrustum(camera);
    // A fragment's corners are read only when the frustum's planes cut its ball.
    const auto kept = std::remove_if(draw.begin(), draw.end(), [&](uint32_t f) {
      const unsigned cut = frustum.cutPlanes(world.fragment_balls[f].centre, world.fragment_balls[f].radius);
      if (cut == 0 || cut == ViewFrustum::kBallOutside) return cut != 0;
      const Polygon& p = bsp.fragments[f];
      return frustum.cornersOutside(cut, std::span<const glm::dvec3>(bsp.vertices).subspan(p.first_vertex, p.vertex_count));
    });
    stats.outside = static_cast<uint32_t>(draw.end() - kept);
    draw.erase(kept, draw.end());
  }
  if (world.occlusion_culling && mode != OrderMode::kZBuffer) {
    OcclusionPace& pace = pace_[static_cast<size_t>(mode)];
    if (pace.rest > 0) {
      --pace.rest;
      stats.occlusion_rested = true;
    } else {
      cullOccluded(world, camera, draw, stats);
      const uint32_t most = world.occlusion.max_rest_frames;
      if (stats.occluded_pixels < world.occlusion.min_occluded_pixels) {
        pace.rest = std::min(pace.next_rest, most);
        pace.next_rest = std::min(2 * pace.next_rest, std::max(most, 1u));
      } else {
        pace.next_rest = 1;
      }
    }
  }
  stats.drawn = static_cast<uint32_t>(draw.size());
  // FrameStats' rule: what was listed is drawn, culled, outside or occluded.
  WALKVIS_DCHECK(stats.listed == stats.drawn + stats.culled + stats.outside + stats.occluded);
  stats.order_ms = msSince(t0);
  const auto t1 = std::chrono::steady_clock::now();
  objects_.resize(world.objects.size());
  for (size_t k = 0; k < world.objects.size(); ++k) {
    tessellateObject(world.objects[k], time, camera.eye, world.object_culling, objects_[k]);
    stats.object_triangles += objects_[k].drawn();
    stats.object_triangles_computed += objects_[k].computed;
  }
  stats.object_ms = msSince(t1);
  return stats;
}

void FrameBuilder::cullOccluded(const World& world, const FreeCamera& camera, std::vector<uint32_t>& draw,
                                FrameStats& stats) {
  const BspTree& bsp = world.trees.bsp;
  WALKVIS_DCHECK(world.fragment_balls.size() == bsp.fragments.size());  // World's rule: a ball per fragment
  auto corners = [&](uint32_t f) {
    const Polygon& p = bsp.fragments[f];
    return std::span<const glm::dvec3>(bsp.vertices).subspan(p.first_vertex, p.vertex_count);
  };
  // How large a fragment looks: (ball radius / distance to its centre)².
  auto apparent = [&](uint32_t f) {
    const Ball& b = world.fragment_balls[f];
    const glm::dvec3 d = b.centre - camera.eye;
    return b.radius * b.radius / std::max(glm::dot(d, d), 1e-300);
  };
  // The occluders: the largest fragments as seen from the eye (ball radius over distance), from
  // the list itself, so that each is drawn, and facing the eye, so that a drawer culling back
  // faces draws them too. (A fragment that covers a whole cell is far from edge-on, so GL's float
  // winding agrees with its plane's side.)
  candidates_.clear();
  for (uint32_t f : draw) {
    const Polygon& p = bsp.fragments[f];
    if (glm::dot(p.plane.n, camera.eye) - p.plane.d > 0.0) candidates_.push_back({apparent(f), f});
  }
  const size_t k = std::min<size_t>(world.occlusion.max_occluders, candidates_.size());
  std::partial_sort(candidates_.begin(), candidates_.begin() + static_cast<std::ptrdiff_t>(k), candidates_.end(),
                    [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
  occlusion_.reset(camera, world.occlusion.cell_pixels);
  stats.occluders = 0;
  for (size_t i = 0; i < k; ++i) stats.occluders += occlusion_.addOccluder(corners(candidates_[i].second));
  stats.occluded = 0;
  if (stats.occluders == 0) return;  // no cell covered: nothing can be hidden
  // Occluders are tested too: the one that gives a cell its depth is never hidden there (its
  // nearest point is at least as near as its farthest over the cell), so what it hides stays hidden.
  // Only fragments that look large are tested: a small one costs GL less to draw than the test.
  const double pixels_per_unit = 0.5 * camera.height / std::tan(0.5 * camera.fov_y);
  const double min_ratio = world.occlusion.min_target_pixels / pixels_per_unit;
  uint64_t cells = 0;
  const auto kept = std::remove_if(draw.begin(), draw.end(), [&](uint32_t f) {
    if (apparent(f) < min_ratio * min_ratio) return false;
    const uint32_t c = occlusion_.hiddenCells(corners(f));
    cells += c;
    return c > 0;
  });
  stats.occluded = static_cast<uint32_t>(draw.end() - kept);
  const uint64_t cell_area = static_cast<uint64_t>(world.occlusion.cell_pixels) * static_cast<uint64_t>(world.occlusion.cell_pixels);
  stats.occluded_pixels = static_cast<uint32_t>(std::min<uint64_t>(cells * cell_area, UINT32_MAX));
  draw.erase(kept, draw.end());
}

}  // namespace walkvis
