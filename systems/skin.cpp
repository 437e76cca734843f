#include "systems/skin.h"

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "systems/skin_kernel.h"

namespace strata {

void skin_system(const SkinLayout& layout, const WalkerLanes& lanes, SkinnedCrowd& out) {
  const std::size_t n = layout.vertex_count;
  const std::size_t stride = pad_to_lanes(n);
  if (out.stride * out.walkers != stride * lanes.count || out.px.size() < stride * lanes.count)
    for (AlignedBuffer<float>* b : {&out.px, &out.py, &out.pz, &out.nx, &out.ny, &out.nz}) b->reset(stride * lanes.count);
  out.vertex_count = n;
  out.stride = stride;
  out.walkers = lanes.count;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lanes.count, 4),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t w = r.begin(); w < r.end(); ++w) {
                        const std::size_t o = w * stride;
                        skin_walker(layout, lanes, w,
                                    SkinOutput{out.px.data() + o, out.py.data() + o, out.pz.data() + o,
                                               out.nx.data() + o, out.ny.data() + o, out.nz.data() + o});
                      }
                    },
                    tbb::simple_partitioner());
}

bool SkinnedCrowd::bounds(glm::vec3& lo, glm::vec3& hi) const {
  if (walkers == 0 || vertex_count == 0) return false;
  lo = hi = position(0, 0);
  for (std::size_t w = 0; w < walkers; ++w)
    for (std::size_t v = 0; v < vertex_count; ++v) {
      const glm::vec3 p = position(w, v);
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  return true;
}

}  // namespace strata
