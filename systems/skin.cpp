#include "systems/skin.h"

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "components/walker.h"


namespace strata {

void SkinnedCrowd::prepare(std::size_t n, std::size_t count, const std::vector<std::uint32_t>* ids) {
  const std::size_t padded = pad_to_lanes(n);
  if (px.size() < padded * count)
    for (AlignedBuffer<float>* b : {&px, &py, &pz, &nx, &ny, &nz}) b->reset(padded * count);
  vertex_count = n;
  stride = padded;
  walkers = count;
  if (ids)
    walker_ids = *ids;
  else
    walker_ids.clear();
}

bool SkinJob::validate() const {
  if (!layout || !out || !skin_columns_valid(skinning, placement, muscle_force)) return false;
  if (!skin_layout_fits(*layout, skinning.components / kAffineFloats, muscle_force.components)) return false;
  if (!skin_mode_fits(*layout, mode)) return false;
  const std::size_t blocks = walkers ? walkers->size() : skinning.count;
  if (walkers) {
    for (const std::uint32_t w : *walkers)
      if (w >= skinning.count) return false;
    if (out->walker_ids != *walkers) return false;
  } else if (!out->walker_ids.empty()) {
    return false;
  }
  const std::size_t floats = out->stride * blocks;
  return out->vertex_count == layout->vertex_count && out->stride == pad_to_lanes(layout->vertex_count) &&
         out->walkers == blocks && out->px.size() >= floats && out->py.size() >= floats &&
         out->pz.size() >= floats && out->nx.size() >= floats && out->ny.size() >= floats && out->nz.size() >= floats;
}

bool SkinJob::run() const {
  if (!validate()) return false;
  const std::size_t count = out->walkers;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k < r.end(); ++k) {
                        const std::size_t w = walkers ? (*walkers)[k] : k;
                        detail::skin_walker(*layout, skinning, placement, muscle_force, w, out->block(k), mode);
                      }
                    },
                    tbb::simple_partitioner());
  return true;
}

SkinJob make_skin_job(const SkinLayout& layout, const SoaTable& walkers, SkinnedCrowd& out,
                      const std::vector<std::uint32_t>* subset, SkinningMode mode) {
  out.prepare(layout.vertex_count, subset ? subset->size() : walkers.size(), subset);
  const SkinColumns c = skin_columns(walkers);
  return {&layout, c.skinning, c.placement, c.muscle_force, subset, &out, mode};
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
