#include "components/triangle_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace strata {

glm::dvec3 closest_barycentric(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {1.0, 0.0, 0.0};
  const glm::dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return {0.0, 1.0, 0.0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {1.0 - v, v, 0.0};
  }
  const glm::dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return {0.0, 0.0, 1.0};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {1.0 - w, 0.0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0.0, 1.0 - w, w};
  }
  const double sum = va + vb + vc;
  if (!(std::abs(sum) > 0.0)) return {1.0, 0.0, 0.0};
  const double v = vb / sum, w = vc / sum;
  return {1.0 - v - w, v, w};
}

TriangleGrid::TriangleGrid(std::span<const glm::vec3> positions, std::span<const std::uint32_t> triangles, float cell)
    : p_(positions.begin(), positions.end()), tri_(triangles.begin(), triangles.end()), cell_(cell) {
  if (p_.empty()) throw std::invalid_argument("triangle grid: no positions");
  if (!(cell > 0.0f)) throw std::invalid_argument("triangle grid: the cell size must be positive");
  for (const std::uint32_t i : tri_)
    if (i >= p_.size()) throw std::invalid_argument("triangle grid: index " + std::to_string(i) + " out of range");
  lo_ = hi_ = p_.front();
  for (const glm::dvec3& v : p_) lo_ = glm::min(lo_, v), hi_ = glm::max(hi_, v);
  for (int a = 0; a < 3; ++a) dims_[a] = std::max(1, static_cast<int>(std::ceil((hi_[a] - lo_[a]) / cell_)) + 1);
  std::vector<std::vector<std::uint32_t>> cells(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2]);
  for (std::uint32_t t = 0; t < tri_.size() / 3; ++t) {
    const glm::dvec3 a = p_[tri_[3 * t]], b = p_[tri_[3 * t + 1]], c = p_[tri_[3 * t + 2]];
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

TriangleGrid::Hit TriangleGrid::nearest(const glm::dvec3& q) const {
  Hit best;
  if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) return best;
  const glm::ivec3 c = cell_of(q);
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
            const glm::dvec3 a = p_[tri_[3 * t]], b = p_[tri_[3 * t + 1]], d = p_[tri_[3 * t + 2]];
            const glm::dvec3 w = closest_barycentric(q, a, b, d);
            const double dist = glm::length(q - (w.x * a + w.y * b + w.z * d));
            if (dist < best.distance || (dist == best.distance && t < best.triangle)) best = {t, w, dist};
          }
        }
    // Every triangle within r cells of q has been seen: a triangle first met in a later shell lies more than r
    // cells from q's cell on some axis, and q, if clamped into the grid on an axis, lies further out still.
    if (best.distance <= static_cast<double>(r) * cell_) break;
  }
  return best;
}

glm::ivec3 TriangleGrid::cell_of(const glm::dvec3& v) const {
  glm::ivec3 i;
  for (int a = 0; a < 3; ++a)
    i[a] = static_cast<int>(std::clamp(std::floor((v[a] - lo_[a]) / cell_), 0.0, static_cast<double>(dims_[a] - 1)));
  return i;
}

std::size_t TriangleGrid::index(int x, int y, int z) const {
  return (static_cast<std::size_t>(z) * dims_[1] + static_cast<std::size_t>(y)) * dims_[0] + static_cast<std::size_t>(x);
}

}  // namespace strata
