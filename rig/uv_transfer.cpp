#include "rig/uv_transfer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace strata {
namespace {

void check(const UvSource& s) {
  if (s.triangles.empty() || s.triangles.size() % 3 != 0)
    throw std::invalid_argument("uv transfer: the source has no triangles");
  if (s.corner_uvs.size() != s.triangles.size())
    throw std::invalid_argument("uv transfer: the source has " + std::to_string(s.corner_uvs.size()) +
                                " corner uvs for " + std::to_string(s.triangles.size()) + " corners");
  for (const std::uint32_t i : s.triangles)
    if (i >= s.positions.size())
      throw std::invalid_argument("uv transfer: source index " + std::to_string(i) + " out of range");
}

// The point of triangle (a, b, c) closest to p, as barycentric weights (u, v, w) of a, b, c: the Voronoi regions
// of the vertices, then of the edges, then the face (Ericson, Real-Time Collision Detection, 5.1.5).
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
  if (!(sum > 0.0)) return {1.0, 0.0, 0.0};  // a degenerate triangle: its first corner
  const double v = vb / sum, w = vc / sum;
  return {1.0 - v - w, v, w};
}

// Source triangles bucketed by the grid cells their boxes overlap; nearest-triangle queries grow a cube of cells
// until the best distance found lies inside it (every triangle nearer than the cube's half-width overlaps it).
class TriangleGrid {
 public:
  explicit TriangleGrid(const UvSource& s) : s_(s) {
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : s.positions) lo = glm::min(lo, glm::dvec3(p)), hi = glm::max(hi, glm::dvec3(p));
    lo_ = lo;
    extent_ = glm::length(hi - lo);
    // About two triangles across a cell: the mean edge length.
    double edges = 0.0;
    const std::size_t t = s.triangles.size() / 3;
    for (std::size_t i = 0; i < s.triangles.size(); ++i)
      edges += glm::length(glm::dvec3(s.positions[s.triangles[i]]) -
                           glm::dvec3(s.positions[s.triangles[i % 3 == 2 ? i - 2 : i + 1]]));
    cell_ = std::max(edges / double(s.triangles.size()), 1e-6 * std::max(extent_, 1e-9));
    for (std::uint32_t k = 0; k < t; ++k) {
      glm::dvec3 a(std::numeric_limits<double>::max()), b(-std::numeric_limits<double>::max());
      for (int c = 0; c < 3; ++c) {
        const glm::dvec3 p(s.positions[s.triangles[3 * k + c]]);
        a = glm::min(a, p), b = glm::max(b, p);
      }
      const glm::ivec3 ca = cell_of(a), cb = cell_of(b);
      for (int x = ca.x; x <= cb.x; ++x)
        for (int y = ca.y; y <= cb.y; ++y)
          for (int z = ca.z; z <= cb.z; ++z) cells_[key(x, y, z)].push_back(k);
    }
    seen_.assign(t, 0);
  }

  struct Hit {
    std::uint32_t triangle = 0;
    glm::dvec3 barycentric{1.0, 0.0, 0.0};
    double distance = std::numeric_limits<double>::max();
  };

  Hit nearest(const glm::dvec3& p) {
    Hit best;
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return best;  // triangle 0's first corner
    ++stamp_;
    for (int reach = 1;; reach *= 2) {
      // A point far from the surface would grow the cube past every occupied cell: scan the triangles instead.
      const double side = 2.0 * reach + 1.0;
      if (side * side * side > double(cells_.size())) {
        for (std::uint32_t k = 0; k < seen_.size(); ++k) consider(p, k, best);
        return best;
      }
      const glm::ivec3 c = cell_of(p);
      for (int x = c.x - reach; x <= c.x + reach; ++x)
        for (int y = c.y - reach; y <= c.y + reach; ++y)
          for (int z = c.z - reach; z <= c.z + reach; ++z) {
            const auto it = cells_.find(key(x, y, z));
            if (it == cells_.end()) continue;
            for (const std::uint32_t k : it->second) {
              if (seen_[k] == stamp_) continue;
              seen_[k] = stamp_;
              consider(p, k, best);
            }
          }
      // Cells reached cover every point within (reach) cells of p's own cell.
      if (best.distance <= reach * cell_) return best;
      ++stamp_;  // the next, larger cube revisits the inner cells: cheap, and the ties rule keeps the result
    }
  }

 private:
  void consider(const glm::dvec3& p, std::uint32_t k, Hit& best) const {
    const glm::dvec3 a(s_.positions[s_.triangles[3 * k]]), b(s_.positions[s_.triangles[3 * k + 1]]),
        d(s_.positions[s_.triangles[3 * k + 2]]);
    const glm::dvec3 w = closest_barycentric(p, a, b, d);
    const double dist = glm::length(p - (w.x * a + w.y * b + w.z * d));
    // Ties to the lower triangle index, so the answer does not depend on the cells' visiting order.
    if (dist < best.distance || (dist == best.distance && k < best.triangle)) best = {k, w, dist};
  }
  glm::ivec3 cell_of(const glm::dvec3& p) const {
    const glm::dvec3 q = glm::floor((p - lo_) / cell_);
    return glm::ivec3(glm::clamp(q, glm::dvec3(-1e6), glm::dvec3(1e6)));
  }
  static std::uint64_t key(int x, int y, int z) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(x) & 0x1FFFFF) << 42) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(y) & 0x1FFFFF) << 21) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(z) & 0x1FFFFF));
  }

  const UvSource& s_;
  glm::dvec3 lo_{0.0};
  double extent_ = 0.0, cell_ = 1.0;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
  std::vector<std::uint32_t> seen_;
  std::uint32_t stamp_ = 0;
};

}  // namespace

std::vector<glm::vec2> transfer_corner_uvs(const UvSource& source, const Mesh& target) {
  check(source);
  const std::size_t t = source.triangles.size() / 3;
  // Across each corner's opposite edge (the edge from corner c+1 to c+2), the triangle beyond it when the two share
  // their UVs there, else none: a walk never crosses a UV seam.
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> across(source.triangles.size(), kNone);
  {
    std::unordered_map<std::uint64_t, std::uint32_t> half;  // directed edge (a -> b) -> its corner's edge slot
    for (std::uint32_t c = 0; c < source.triangles.size(); ++c) {
      const std::uint32_t base = c - c % 3;
      const std::uint32_t a = source.triangles[base + (c + 1) % 3], b = source.triangles[base + (c + 2) % 3];
      half[(static_cast<std::uint64_t>(a) << 32) | b] = c;
    }
    for (std::uint32_t c = 0; c < source.triangles.size(); ++c) {
      const std::uint32_t base = c - c % 3;
      const std::uint32_t ca = base + (c + 1) % 3, cb = base + (c + 2) % 3;
      const auto it = half.find((static_cast<std::uint64_t>(source.triangles[cb]) << 32) | source.triangles[ca]);
      if (it == half.end()) continue;
      const std::uint32_t o = it->second, obase = o - o % 3;
      const std::uint32_t oa = obase + (o + 1) % 3, ob = obase + (o + 2) % 3;  // oa is b's corner there, ob is a's
      if (source.corner_uvs[ca] == source.corner_uvs[ob] && source.corner_uvs[cb] == source.corner_uvs[oa])
        across[c] = obase / 3;
    }
  }
  auto corner = [&](std::uint32_t tri, int k) { return glm::dvec3(source.positions[source.triangles[3 * tri + k]]); };
  // From `start`, step across the edge p lies most beyond (in the triangle's plane) until p lies inside, a seam or
  // the mesh's edge stops the walk, or it would revisit; the answer is the nearest of the triangles walked.
  std::vector<std::uint32_t> visited_at(t, kNone);
  std::uint32_t walk_id = 0;
  auto walk = [&](std::uint32_t start, const glm::dvec3& p) {
    ++walk_id;
    std::uint32_t tri = start, best_tri = start;
    glm::dvec3 best_w{1.0, 0.0, 0.0};
    double best_d = std::numeric_limits<double>::max();
    for (int step = 0; step < 256 && tri != kNone && visited_at[tri] != walk_id; ++step) {
      visited_at[tri] = walk_id;
      const glm::dvec3 a = corner(tri, 0), b = corner(tri, 1), c = corner(tri, 2);
      const glm::dvec3 w = closest_barycentric(p, a, b, c);
      const double d = glm::length(p - (w.x * a + w.y * b + w.z * c));
      if (d < best_d) best_d = d, best_tri = tri, best_w = w;
      // Unclamped barycentrics of p's projection onto the plane: the most negative names the edge to cross.
      const glm::dvec3 n = glm::cross(b - a, c - a);
      const double n2 = glm::dot(n, n);
      if (!(n2 > 0.0)) break;
      const double u = glm::dot(glm::cross(c - b, p - b), n) / n2, v = glm::dot(glm::cross(a - c, p - c), n) / n2;
      const double bary[3] = {u, v, 1.0 - u - v};
      int out = 0;
      for (int k = 1; k < 3; ++k)
        if (bary[k] < bary[out]) out = k;
      if (bary[out] >= -1e-9) break;  // inside
      tri = across[3 * tri + static_cast<std::uint32_t>(out)];
    }
    return std::pair{best_tri, best_w};
  };

  TriangleGrid grid(source);
  std::vector<glm::vec2> out(target.triangles.size());
  // Per target vertex, the UVs its corners took so far. Walks from different triangles to one vertex that lies a
  // little off the source (the levels are cut from the Loop-smoothed surface) can end in neighbouring source
  // triangles and project it onto slightly different planes: UVs ~1e-5 apart, a hairline seam for a texture
  // sampler's derivatives. A corner within kSameSide of a UV its vertex already has takes that one; a real seam's
  // two sides are far further apart.
  constexpr float kSameSide = 1e-3f;  // texture units: ~2 mm of MakeHuman's skin
  std::vector<std::vector<glm::vec2>> taken(target.vertex_count());
  for (std::size_t k = 0; k + 2 < target.triangles.size(); k += 3) {
    glm::dvec3 centroid(0.0);
    for (int c = 0; c < 3; ++c) centroid += glm::dvec3(target.positions.at(target.triangles[k + c])) / 3.0;
    const std::uint32_t start = grid.nearest(centroid).triangle;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = target.triangles[k + c];
      const auto [tri, w] = walk(start, glm::dvec3(target.positions[v]));
      const glm::vec2 uv(w.x * glm::dvec2(source.corner_uvs[3 * tri]) + w.y * glm::dvec2(source.corner_uvs[3 * tri + 1]) +
                         w.z * glm::dvec2(source.corner_uvs[3 * tri + 2]));
      const auto same = std::find_if(taken[v].begin(), taken[v].end(),
                                     [&](const glm::vec2& u) { return glm::length(u - uv) < kSameSide; });
      if (same != taken[v].end()) {
        out[k + c] = *same;
      } else {
        out[k + c] = uv;
        taken[v].push_back(uv);
      }
    }
  }
  return out;
}

}  // namespace strata
