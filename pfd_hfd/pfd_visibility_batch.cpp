// A batch of HFD visibility queries (James & Day, "The hidden face determination tree", 1998
// [JamesDay1998HFD]:
// the area-to-area test at list promotion) run in parallel with TBB.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pfd_hfd/pfd_internal.h"

#include "core/check.h"

namespace walkvis {

void visibleBatch(const VisibilityScene& vis, std::span<const uint32_t> fragments,
                  std::span<const std::vector<glm::dvec2>> region, double height, std::span<uint8_t> visible,
                  std::span<glm::dvec2> witnesses, VisibilityCounters& counters) {
  WALKVIS_DCHECK(visible.size() == fragments.size());
  WALKVIS_DCHECK(witnesses.empty() || witnesses.size() == fragments.size());
  const size_t n = fragments.size();
  if (n == 0) return;
  const auto witness = [&](size_t i) { return witnesses.empty() ? nullptr : &witnesses[i]; };
  if (n == 1) {
    const uint64_t rays = counters.rays;
    visible[0] = vis.visibleFromRegion(fragments[0], region, height, counters, witness(0)) ? 1 : 0;
    if (!visible[0]) counters.hidden_rays += counters.rays - rays;
    return;
  }
  std::vector<VisibilityCounters> each(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i != range.end(); ++i) {
      visible[i] = vis.visibleFromRegion(fragments[i], region, height, each[i], witness(i)) ? 1 : 0;
      if (!visible[i]) each[i].hidden_rays = each[i].rays;
    }
  });
  for (const VisibilityCounters& c : each) counters.add(c);
}

}  // namespace walkvis
