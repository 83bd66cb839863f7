// Walking physics for the window and the automatic tour: the eye stays at eye height above the
// floor under it, steps up at most a step height onto another floor level or onto a connection
// (Scene::connections: stair treads, ramps), switching the level (hence the tree the frame uses;
// -1 on a connection, where the frame uses the BSP order), drops down any height, never crosses a
// wall and keeps a radius away from walls it approaches, sliding along them. The floor under a
// point is the highest of the levels' floors and the connection patches' planes there.
//
// Walls are the fragments of the BSP whose plane is not horizontal (|n.y| < kWallMaxNormalY):
// floors and ceilings are the floor levels' business. A move is a horizontal segment at the eye's
// height, then (at the new x, z) a vertical segment to the new eye height; both are tested against
// the walls through the BSP (the segment and a ball at its end descend only the subtrees they
// reach). Guarantees (double precision, walls enlarged by a tolerance of 1e-9 of the scene's scale
// so that the seam between two fragments of one wall is never a gap):
//  * no accepted move's segment crosses a wall fragment or ends on one;
//  * a move never ends within `radius` of a wall unless it increases the distance to that wall
//    (only sliding or falling can leave the eye within radius: the eye can always move away).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "bsp/bsp.h"
#include "scenes/scene.h"

namespace walkvis {

constexpr double kWallMaxNormalY = 0.9;  // |n.y| below this: a wall (slopes up to ~64° count as walls)

struct MoveOptions {
  double radius_factor = 0.15;  // radius = factor × eye height (WAD: 6.15 units; 1.7 m eye: 0.255 m)
  double step_factor = 0.6;     // step height = factor × eye height (WAD: 24.6 ≥ Doom's 24-unit steps)
};

struct WalkState {
  glm::dvec3 eye{0.0};
  int level = -1;  // index into Scene::levels whose floor is under the eye; -1 off the walkable region
};

// One walker per thread: its queries share a scratch stack, so that a move allocates nothing.
class Walker {
 public:
  // Keeps references to scene and bsp (which must outlive it); bsp is the scene's BSP.
  Walker(const Scene& scene, const BspTree& bsp, const MoveOptions& options = {});

  double radius() const { return radius_; }
  double stepHeight() const { return step_; }
  double tolerance() const { return tol_; }  // 1e-9 of the scene's scale (the walls' enlargement)

  // The eye put onto the floor under its (x, z): the highest level floor or connection patch there
  // that is at most eye.y − eye height + step height, at exactly that floor + eye height (level -1
  // on a patch). Unchanged with level -1 when there is none.
  WalkState place(const glm::dvec3& eye) const;

  // Moves by delta_xz (x, z) with collision and sliding: the full move when it is allowed, else
  // the move slid along the blocking wall, else along x or z alone, else no move. Standing on a
  // floor (a level, or a connection patch with level -1) the new (x, z) must have a floor at most
  // a step height above the current one (the highest such is taken). Off the walkable region
  // (level -1, no floor under the eye) the eye moves at its height and lands on a floor reachable
  // by a step down or up.
  WalkState move(const WalkState& from, const glm::dvec2& delta_xz) const;

  // One step without sliding: nullopt when blocked (by a wall or by having no floor to go to).
  std::optional<WalkState> tryMove(const WalkState& from, const glm::dvec2& delta_xz) const;

  // True when the segment a→b crosses no wall and (radius > 0) b is not within radius of a wall
  // that it is nearer than a. *blocker gets the unit normal of a blocking wall when not clear.
  bool segmentClear(const glm::dvec3& a, const glm::dvec3& b, double radius,
                    glm::dvec3* blocker = nullptr) const;

  // The highest level containing (x, z) (boundary inclusive) with floor_y <= max_floor_y.
  std::optional<uint32_t> levelUnder(double x, double z, double max_floor_y) const;
  // The highest floor at (x, z) at most max_floor_y: a level's (level index) or a connection
  // patch's plane height there (level -1); a level wins a tie.
  struct Floor {
    double y;
    int level;
  };
  std::optional<Floor> floorUnder(double x, double z, double max_floor_y) const;
  // A uniformly random point of the walkable region (all levels, by area) and its level; nullopt
  // for a scene without walkable area.
  std::optional<std::pair<glm::dvec2, uint32_t>> randomWalkablePoint(uint64_t& rng) const;  // rng: core/rng.h state

 private:
  struct Piece {
    uint32_t level;  // for a patch: the connection's index
    uint32_t index;  // into levels[level].walkable, or into connections[level].patches
    double lo_x, lo_z, hi_x, hi_z;
    bool patch = false;
  };
  bool insidePiece(const Piece& p, double x, double z) const;
  // The grid cell whose pieces may hold (x, z) (points just outside the grid clamp to its edge);
  // nullopt far outside it or for no pieces.
  std::optional<size_t> gridCell(double x, double z) const;
  bool wallBlocks(uint32_t fragment, const glm::dvec3& a, const glm::dvec3& b, double radius) const;
  bool blocks(int32_t node, const glm::dvec3& a, const glm::dvec3& b, double radius, glm::dvec3* blocker) const;

  const Scene& scene_;
  const BspTree& bsp_;
  double radius_ = 0.0, step_ = 0.0;
  double tol_ = 0.0;  // 1e-9 of the scene's scale
  const std::vector<glm::dvec2>& ring(const Piece& p) const;
  double pieceFloor(const Piece& p, double x, double z) const;

  std::vector<Piece> pieces_;  // the levels' pieces first (level_pieces_ of them), then patches
  size_t level_pieces_ = 0;
  std::vector<double> piece_area_cumulative_;
  // Uniform grid over the pieces' bounds: cell → piece indices.
  double grid_x0_ = 0.0, grid_z0_ = 0.0, cell_ = 1.0;
  int grid_nx_ = 0, grid_nz_ = 0;
  std::vector<uint32_t> cell_start_, cell_pieces_;
  mutable std::vector<int32_t> stack_;  // blocks()' BSP walk (capacity 2 · nodes + 2)
};

}  // namespace walkvis
