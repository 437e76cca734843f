#include "systems/skin.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "systems/skin_reference.h"

namespace strata {

void skin_system(const BodyLevel& level, const WalkerLanes& lanes, SkinnedCrowd& out) {
  const std::size_t n = level.mesh.vertex_count();
  out.vertex_count = n;
  out.positions.resize(lanes.count * n);
  out.normals.resize(lanes.count * n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lanes.count, 4),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t w = r.begin(); w < r.end(); ++w) {
                        const SkinnedVertices posed = skin_reference(level.mesh, level.binding, lanes, w);
                        const Placement placement = placement_of(lanes, w);
                        for (std::size_t v = 0; v < n; ++v) {
                          out.positions[w * n + v] = placement.point(posed.positions[v]);
                          out.normals[w * n + v] = placement.direction(posed.normals[v]);
                        }
                      }
                    },
                    tbb::simple_partitioner());
}

}  // namespace strata
