// Walkable floors the way a navmesh finds them (Recast: Mononen, Recast Navigation): the surfaces a
// walker of a given height and radius can stand on, with a maximum step and slope. A level is a
// connected walkable area at one floor height with headroom for the eye; its region is the scene's
// exact upward horizontal faces clipped to what Recast's voxels allow. Walkable surfaces that join
// levels (stairs, ramps) become Scene::connections.
#pragma once

#include "scenes/scene.h"

namespace walkvis {

// Replaces scene.levels and scene.connections from the scene's polygons. Options with a negative
// value take the defaults stated in scene.h (from scene.eye_height).
//  * Voxels: cell size agent radius / 3 (coarser if the grid would pass 4M columns or 4000 cells a
//    side), cell height max climb / 8 (a gap reads up to 3 cell heights lower than it is);
//    Recast's filters for low obstacles, ledges and headroom, and erosion by the radius. Recast
//    links two cells when the gap they share is the agent's height: a stair whose tread steps
//    out from under a slab needs the headroom at the slab's edge, not only over each tread.
//  * An area is a Recast-linked set of walkable cells whose floor is one candidate height (the
//    exact upward horizontal faces; heights within 1e-6 of the scene's size are one) and which
//    those faces cover.
//  * A level is an area of at least min_level_area in a seeded region (cells linked through any
//    walkable cells, stairs and ramps included). Seeds: the largest area of the scene, and every
//    area of at least the minimum that is walled rather than a ledge (beyond most of its edges an
//    obstacle or too low a headroom rises; a drop to a floor more than a climb below is a ledge).
//    So a table top or a roof is no level even when large, while a room shut by a closed door
//    (common in IFC models) is one. One FloorLevel per height, with all its areas' pieces.
//  * Walkable cells of seeded regions on no level (treads, ramps, small landings) form connections.
// Notes the parameters, cell size, grid and what was filtered in scene.report.notes. Throws
// Error (naming scene.name) when the options are out of range.
void deriveWalkableLevels(Scene& scene, const WalkableOptions& options);

}  // namespace walkvis
