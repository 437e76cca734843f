#include "systems/skin.h"

#include <cmath>

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
                        const std::size_t s = lanes.stride;
                        const glm::vec3 origin{lanes.placement[0 * s + w], lanes.placement[1 * s + w],
                                               lanes.placement[2 * s + w]};
                        const float heading = lanes.placement[3 * s + w], scale = lanes.placement[4 * s + w];
                        const float c = std::cos(heading), sn = std::sin(heading);
                        // Placement: T(origin) Ry(heading) S(scale), as systems/pose_gather.cpp.
                        for (std::size_t v = 0; v < n; ++v) {
                          const glm::vec3 p = scale * posed.positions[v], q = posed.normals[v];
                          out.positions[w * n + v] = origin + glm::vec3(c * p.x + sn * p.z, p.y, -sn * p.x + c * p.z);
                          out.normals[w * n + v] = glm::vec3(c * q.x + sn * q.z, q.y, -sn * q.x + c * q.z);
                        }
                      }
                    },
                    tbb::simple_partitioner());
}

}  // namespace strata
