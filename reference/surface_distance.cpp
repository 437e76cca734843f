#include "reference/surface_distance.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace strata {
namespace {

// Distance queries against a triangle soup: a uniform grid of cells, each listing the triangles whose bounding
// box touches it; a query searches growing shells of cells until no unsearched cell can hold anything closer.
class TriangleGrid {
 public:
  TriangleGrid(std::vector<glm::vec3> positions, std::span<const std::uint32_t> triangles, float cell)
      : p_(std::move(positions)), tri_(triangles.begin(), triangles.end()), cell_(cell) {
    lo_ = hi_ = p_.front();
    for (const glm::vec3& v : p_) lo_ = glm::min(lo_, v), hi_ = glm::max(hi_, v);
    for (int a = 0; a < 3; ++a) dims_[a] = std::max(1, static_cast<int>(std::ceil((hi_[a] - lo_[a]) / cell_)) + 1);
    std::vector<std::vector<std::uint32_t>> cells(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2]);
    for (std::uint32_t t = 0; t < tri_.size() / 3; ++t) {
      glm::vec3 a = p_[tri_[3 * t]], b = p_[tri_[3 * t + 1]], c = p_[tri_[3 * t + 2]];
      const glm::ivec3 i0 = cell_of(glm::min(a, glm::min(b, c))), i1 = cell_of(glm::max(a, glm::max(b, c)));
      for (int z = i0.z; z <= i1.z; ++z)
        for (int y = i0.y; y <= i1.y; ++y)
          for (int x = i0.x; x <= i1.x; ++x) cells[index(x, y, z)].push_back(t);
    }
    start_.push_back(0);
    for (const auto& c : cells) {
      items_.insert(items_.end(), c.begin(), c.end());
      start_.push_back(static_cast<std::uint32_t>(items_.size()));
    }
  }

  float distance(const glm::vec3& q) const {
    const glm::ivec3 c = cell_of(q);
    float best = 1e30f;
    const int max_ring = std::max(dims_[0], std::max(dims_[1], dims_[2]));
    for (int r = 0; r <= max_ring; ++r) {
      for (int z = c.z - r; z <= c.z + r; ++z)
        for (int y = c.y - r; y <= c.y + r; ++y)
          for (int x = c.x - r; x <= c.x + r; ++x) {
            if (std::max({std::abs(x - c.x), std::abs(y - c.y), std::abs(z - c.z)}) != r) continue;  // shell only
            if (x < 0 || y < 0 || z < 0 || x >= dims_[0] || y >= dims_[1] || z >= dims_[2]) continue;
            const std::size_t i = index(x, y, z);
            for (std::uint32_t k = start_[i]; k < start_[i + 1]; ++k) {
              const std::uint32_t t = items_[k];
              best = std::min(best, point_triangle_distance(q, p_[tri_[3 * t]], p_[tri_[3 * t + 1]], p_[tri_[3 * t + 2]]));
            }
          }
      // Every triangle within r * cell of q (clamped into the grid) has been seen.
      if (best <= static_cast<float>(r) * cell_) break;
    }
    return best;
  }

 private:
  glm::ivec3 cell_of(const glm::vec3& v) const {
    glm::ivec3 i;
    for (int a = 0; a < 3; ++a) i[a] = std::clamp(static_cast<int>(std::floor((v[a] - lo_[a]) / cell_)), 0, dims_[a] - 1);
    return i;
  }
  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * dims_[1] + static_cast<std::size_t>(y)) * dims_[0] + static_cast<std::size_t>(x);
  }
  // Closest point of triangle abc to q by its Voronoi regions (vertex, edge, face), then the distance.
  static float point_triangle_distance(const glm::vec3& q, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const glm::vec3 ab = b - a, ac = c - a, aq = q - a;
    const float d1 = glm::dot(ab, aq), d2 = glm::dot(ac, aq);
    if (d1 <= 0.0f && d2 <= 0.0f) return glm::length(aq);
    const glm::vec3 bq = q - b;
    const float d3 = glm::dot(ab, bq), d4 = glm::dot(ac, bq);
    if (d3 >= 0.0f && d4 <= d3) return glm::length(bq);
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return glm::length(q - (a + ab * (d1 / (d1 - d3))));
    const glm::vec3 cq = q - c;
    const float d5 = glm::dot(ab, cq), d6 = glm::dot(ac, cq);
    if (d6 >= 0.0f && d5 <= d6) return glm::length(cq);
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return glm::length(q - (a + ac * (d2 / (d2 - d6))));
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0.0f && d4 - d3 >= 0.0f && d5 - d6 >= 0.0f)
      return glm::length(q - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    const float denom = va + vb + vc;
    if (!(std::abs(denom) > 0.0f)) return glm::length(aq);  // degenerate triangle: its first corner
    return glm::length(q - (a + ab * (vb / denom) + ac * (vc / denom)));
  }

  std::vector<glm::vec3> p_;
  std::vector<std::uint32_t> tri_;
  float cell_;
  glm::vec3 lo_{0.0f}, hi_{0.0f};
  int dims_[3] = {1, 1, 1};
  std::vector<std::uint32_t> start_, items_;
};

}  // namespace

// For every vertex of the directly skinned mesh, the distance to the nearest point of the refined surface's
// triangles; max and mean.
Deviation surface_deviation(const std::vector<float>& mesh_soa, std::size_t mesh_vertices, std::size_t mesh_stride,
                    const std::vector<float>& refined_soa, std::size_t refined_vertices, std::size_t refined_stride,
                    std::span<const std::uint32_t> refined_triangles) {
  std::vector<glm::vec3> refined(refined_vertices);
  for (std::size_t i = 0; i < refined_vertices; ++i)
    refined[i] = {refined_soa[i], refined_soa[refined_stride + i], refined_soa[2 * refined_stride + i]};
  const TriangleGrid grid(std::move(refined), refined_triangles, 0.02f);
  Deviation d;
  for (std::size_t i = 0; i < mesh_vertices; ++i) {
    const glm::vec3 q{mesh_soa[i], mesh_soa[mesh_stride + i], mesh_soa[2 * mesh_stride + i]};
    const double dist = grid.distance(q);
    d.max_m = std::max(d.max_m, dist);
    d.mean_m += dist;
  }
  d.mean_m /= static_cast<double>(std::max<std::size_t>(mesh_vertices, 1));
  return d;
}

}  // namespace strata
