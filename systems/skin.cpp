#include "systems/skin.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "systems/skin_kernel.h"

namespace strata {

void skin_system(const SkinLayout& layout, const WalkerLanes& lanes, SkinnedCrowd& out) {
  const std::size_t n = layout.vertex_count;
  out.vertex_count = n;
  out.positions.resize(lanes.count * n);
  out.normals.resize(lanes.count * n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lanes.count, 4),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t w = r.begin(); w < r.end(); ++w)
                        skin_walker(layout, lanes, w, std::span(out.positions).subspan(w * n, n),
                                    std::span(out.normals).subspan(w * n, n));
                    },
                    tbb::simple_partitioner());
}

}  // namespace strata
