#include "reference/surface_distance.h"

#include "components/triangle_grid.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace strata {

// For every vertex of the directly skinned mesh, the distance to the nearest point of the refined surface's
// triangles; max and mean.
Deviation surface_deviation(const std::vector<float>& mesh_soa, std::size_t mesh_vertices, std::size_t mesh_stride,
                    const std::vector<float>& refined_soa, std::size_t refined_vertices, std::size_t refined_stride,
                    std::span<const std::uint32_t> refined_triangles) {
  std::vector<glm::vec3> refined(refined_vertices);
  for (std::size_t i = 0; i < refined_vertices; ++i)
    refined[i] = {refined_soa[i], refined_soa[refined_stride + i], refined_soa[2 * refined_stride + i]};
  const TriangleGrid grid(refined, refined_triangles, 0.02f);
  Deviation d;
  for (std::size_t i = 0; i < mesh_vertices; ++i) {
    const glm::vec3 q{mesh_soa[i], mesh_soa[mesh_stride + i], mesh_soa[2 * mesh_stride + i]};
    const double dist = grid.nearest(glm::dvec3(q)).distance;
    d.max_m = std::max(d.max_m, dist);
    d.mean_m += dist;
  }
  d.mean_m /= static_cast<double>(std::max<std::size_t>(mesh_vertices, 1));
  return d;
}

}  // namespace strata
