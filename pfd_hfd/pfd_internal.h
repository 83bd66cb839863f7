// Internal to pfd_hfd: the parallel visibility batch the PFD builder calls for HFD trees. It lives
// outside the CGAL translation unit so that TBB is only linked where the library declares it.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

#include "pfd_hfd/visibility.h"

namespace walkvis {

// visible[i] = vis.visibleFromRegion(fragments[i], region, height) for every i, tested in
// parallel; counters gets the sum of the queries' counters. The result does not depend on thread
// order (each query is deterministic and the sums are taken in index order). visible.size() must
// equal fragments.size(); so must witnesses.size() unless it is empty (then no witnesses are kept),
// and witnesses[i] is the eye that saw fragment i where visible[i] is 1.
void visibleBatch(const VisibilityScene& vis, std::span<const uint32_t> fragments,
                  std::span<const std::vector<glm::dvec2>> region, double height, std::span<uint8_t> visible,
                  std::span<glm::dvec2> witnesses, VisibilityCounters& counters);

}  // namespace walkvis
