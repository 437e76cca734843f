#include "rig/uv_transfer.h"

#include "components/triangle_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

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

  // Cells of about the source's mean edge length: a few triangles each.
  double edges = 0.0;
  for (std::size_t i = 0; i < source.triangles.size(); ++i)
    edges += glm::length(source.positions[source.triangles[i]] - source.positions[source.triangles[i % 3 == 2 ? i - 2 : i + 1]]);
  const TriangleGrid grid(source.positions, source.triangles,
                          static_cast<float>(std::max(edges / double(source.triangles.size()), 1e-4)));
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
