// Internal to bsp/: the exact part of the build, kept in bsp_build_cgal.cpp so that only that
// translation unit pays for CGAL's headers.
#pragma once

#include <cstdint>

#include "bsp/bsp.h"

namespace walkvis::detail {

// Fills tree.vertices, fragments, fragment_polygon, fragment_orientation, nodes (with depth and
// parent) and root for a scene whose polygons buildBsp has validated. Returns the number of vertex
// classifications the double filter left to exact arithmetic. `groups` is detailGroups(scene,
// options.detail_extent).
uint64_t buildBspExact(const Scene& scene, const BspOptions& options, const DetailGroups& groups, BspTree& tree);

}  // namespace walkvis::detail
