#include "systems/skin.h"

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "systems/skin_kernel.h"

namespace strata {

void skin_system(const SkinLayout& layout, const WalkerLanes& lanes, SkinnedCrowd& out,
                 const std::vector<std::uint32_t>* walkers) {
  const bool subset = walkers != nullptr;
  const std::size_t n = layout.vertex_count;
  const std::size_t stride = pad_to_lanes(n);
  const std::size_t count = subset ? walkers->size() : lanes.count;
  // Grown, never shrunk: a crowd whose visible count changes every frame must not reallocate every frame.
  if (out.px.size() < stride * count)
    for (AlignedBuffer<float>* b : {&out.px, &out.py, &out.pz, &out.nx, &out.ny, &out.nz}) b->reset(stride * count);
  out.vertex_count = n;
  out.stride = stride;
  out.walkers = count;
  if (subset)
    out.walker_ids = *walkers;
  else
    out.walker_ids.clear();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k < r.end(); ++k) {
                        const std::size_t o = k * stride;
                        const std::size_t w = subset ? (*walkers)[k] : k;
                        if (w >= lanes.count) throw std::out_of_range("skin_system: walker out of range");
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
