// Internal to bsp/: the exact part of the build, kept in bsp_build_cgal.cpp so that only that
// translation unit pays for CGAL's headers.
#pragma once

#include <cstdint>
#include <string>

#include "bsp/bsp.h"

namespace walkvis::detail {

// Fills tree.vertices, fragments, fragment_polygon, fragment_orientation, nodes (with depth and
// parent) and root for a scene whose polygons buildBsp has validated. Returns the number of vertex
// classifications the double filter left to exact arithmetic. `groups` is detailGroups(scene,
// options.detail_extent).
uint64_t buildBspExact(const Scene& scene, const BspOptions& options, const DetailGroups& groups, BspTree& tree);

// The first rule of BspTree's layout (bsp.h) that `tree` breaks, in words ("node 7: bad child"),
// or empty when it keeps them all: parallel fragment arrays; each fragment of at least 3 vertices
// inside `vertices`, its orientation +1 where its plane has its node's coefficients, -1 where they
// are exactly negated, 0 otherwise; root 0 (none for no nodes); every other node after its parent,
// which links to it, one level deeper; children after their parent; disjoint fragment ranges that cover
// every fragment, empty only at separators; statistics counting the arrays. loadBsp
// rejects a file whose tree breaks one; buildBsp's trees keep them (checked by WALKVIS_DCHECK).
std::string bspStructureProblem(const BspTree& tree);

}  // namespace walkvis::detail
