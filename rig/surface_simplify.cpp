#include "rig/surface_simplify.h"

#include <algorithm>
#include <array>
#include <functional>
#include <iterator>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include <glm/geometric.hpp>
#include <meshoptimizer.h>

namespace strata {

bool is_closed_manifold(const std::vector<std::uint32_t>& tris, std::size_t vertex_count) {
  // Every directed edge once and its reverse once; every vertex's fan a single cycle.
  std::unordered_map<std::uint64_t, std::uint32_t> next_in_fan;  // (v, a) -> b for triangle (v, a, b)
  next_in_fan.reserve(tris.size() * 2);
  std::vector<std::uint32_t> valence(vertex_count, 0), first(vertex_count, 0);
  auto key = [](std::uint32_t a, std::uint32_t b) { return (static_cast<std::uint64_t>(a) << 32) | b; };
  for (std::size_t t = 0; t < tris.size(); t += 3)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = tris[t + c], a = tris[t + (c + 1) % 3], b = tris[t + (c + 2) % 3];
      if (v == a || a == b || v == b) return false;
      if (!next_in_fan.emplace(key(v, a), b).second) return false;  // directed edge used twice
      if (valence[v]++ == 0) first[v] = a;
    }
  for (const auto& entry : next_in_fan) {
    const std::uint32_t v = static_cast<std::uint32_t>(entry.first >> 32), a = static_cast<std::uint32_t>(entry.first);
    if (!next_in_fan.count(key(a, v))) return false;  // open edge
  }
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    if (valence[v] == 0) continue;
    // Around a disc the fan returns to its first neighbour after exactly valence[v] triangles.
    std::uint32_t a = first[v], steps = 0;
    do {
      a = next_in_fan.at(key(v, a));
      ++steps;
    } while (a != first[v] && steps <= valence[v]);
    if (steps != valence[v]) return false;
  }
  return true;
}

namespace {


// Compacts to the referenced vertices and reorders for the post-transform cache and for fetch locality.
SimplifiedSurface compact(const std::vector<glm::vec3>& positions, std::vector<std::uint32_t> tris) {
  SimplifiedSurface s;
  meshopt_optimizeVertexCache(tris.data(), tris.data(), tris.size(), positions.size());
  // The remap form of meshopt_optimizeVertexFetch (the same first-use order), so each kept vertex's input index
  // is known.
  std::vector<std::uint32_t> remap(positions.size());
  const std::size_t n = meshopt_optimizeVertexFetchRemap(remap.data(), tris.data(), tris.size(), positions.size());
  s.positions.resize(n);
  s.source_vertex.resize(n);
  for (std::uint32_t v = 0; v < positions.size(); ++v)
    if (remap[v] != ~0u) s.positions[remap[v]] = positions[v], s.source_vertex[remap[v]] = v;
  for (std::uint32_t& i : tris) i = remap[i];
  s.triangles = std::move(tris);
  return s;
}



// Quadric-error half-edge collapse that refuses any collapse breaking the link condition, so a closed 2-manifold
// stays one. meshopt_simplify (0.18) was the first choice, but it does not test the link condition and left ~100
// fins and a few pinched edges on every run here; meshoptimizer still orders the result for the GPU (compact()).
// It also refuses collapses that leave a sliver (below min_quality, kSkinnedMinQuality for the levels).
class Collapser {
 public:
  Collapser(std::vector<glm::vec3> positions, std::vector<std::uint32_t> tris, double min_quality)
      : min_quality_(min_quality), pos_(std::move(positions)), tris_(std::move(tris)), vert_tris_(pos_.size()),
        quadric_(pos_.size()), version_(pos_.size(), 0), alive_(pos_.size(), 0) {
    tri_alive_.assign(tris_.size() / 3, 1);
    for (std::uint32_t t = 0; t < tris_.size() / 3; ++t) {
      const glm::dvec3 a = pos_[tris_[3 * t]], b = pos_[tris_[3 * t + 1]], c = pos_[tris_[3 * t + 2]];
      glm::dvec3 n = glm::cross(b - a, c - a);
      const double area2 = glm::length(n);
      if (area2 > 0.0) n /= area2;
      const double d = -glm::dot(n, a);
      const double w = 0.5 * area2;  // area weighting: big flat triangles dominate, slivers do not
      const double q[10] = {n.x * n.x, n.x * n.y, n.x * n.z, n.x * d, n.y * n.y, n.y * n.z, n.y * d,
                            n.z * n.z, n.z * d,   d * d};
      for (int c3 = 0; c3 < 3; ++c3) {
        const std::uint32_t v = tris_[3 * t + c3];
        vert_tris_[v].push_back(t);
        alive_[v] = 1;
        for (int k = 0; k < 10; ++k) quadric_[v][k] += w * q[k];
      }
    }
    for (std::uint8_t a : alive_) live_ += a;
    for (std::uint32_t t = 0; t < tris_.size() / 3; ++t)
      for (int c3 = 0; c3 < 3; ++c3) push(tris_[3 * t + c3], tris_[3 * t + (c3 + 1) % 3]);
  }

  void run(std::size_t target_vertices) {
    // Strict fold limit first for well-shaped triangles; if every remaining collapse folds that much, re-queue
    // all edges and accept steeper ones (coarse levels need them on fingers and toes).
    for (double limit : {0.3, 0.0, -0.5}) {
      min_cos_ = limit;
      if (heap_.empty())
        for (std::uint32_t t = 0; t < tris_.size() / 3; ++t)
          if (tri_alive_[t])
            for (int c3 = 0; c3 < 3; ++c3) push(tris_[3 * t + c3], tris_[3 * t + (c3 + 1) % 3]);
      drain(target_vertices);
      if (live_ <= target_vertices) return;
    }
  }

 private:
  void drain(std::size_t target_vertices) {
    while (live_ > target_vertices && !heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), std::greater<>());
      const Candidate c = heap_.back();
      heap_.pop_back();
      if (!alive_[c.from] || !alive_[c.to] || version_[c.from] != c.version_from || version_[c.to] != c.version_to)
        continue;
      if (!collapse(c.from, c.to)) continue;
    }
  }


 public:
  SimplifiedSurface result() const {
    std::vector<std::uint32_t> out;
    for (std::size_t t = 0; t < tri_alive_.size(); ++t)
      if (tri_alive_[t]) out.insert(out.end(), {tris_[3 * t], tris_[3 * t + 1], tris_[3 * t + 2]});
    return compact(pos_, std::move(out));
  }

 private:
  struct Candidate {
    double cost;
    std::uint32_t from, to, version_from, version_to;
    bool operator>(const Candidate& o) const {
      if (cost != o.cost) return cost > o.cost;
      return from != o.from ? from > o.from : to > o.to;  // total order: deterministic ties
    }
  };

  // 1 for an equilateral triangle, 0 for a degenerate one: twice the area over the longest edge squared,
  // normalised. Height over longest edge is what a sliver lacks.
  static double shape_quality(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const double longest = std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
    return longest > 0.0 ? glm::length(glm::cross(b - a, c - a)) / (longest * 0.8660254037844386) : 0.0;
  }
  double error(const std::array<double, 10>& q, const glm::dvec3& p) const {
    return q[0] * p.x * p.x + 2 * q[1] * p.x * p.y + 2 * q[2] * p.x * p.z + 2 * q[3] * p.x + q[4] * p.y * p.y +
           2 * q[5] * p.y * p.z + 2 * q[6] * p.y + q[7] * p.z * p.z + 2 * q[8] * p.z + q[9];
  }
  void push(std::uint32_t a, std::uint32_t b) {
    std::array<double, 10> q{};
    for (int k = 0; k < 10; ++k) q[k] = quadric_[a][k] + quadric_[b][k];
    const double to_b = error(q, pos_[b]), to_a = error(q, pos_[a]);
    // Ties go to a fixed direction so the result does not depend on the edge's orientation.
    const bool a_into_b = to_b < to_a || (to_b == to_a && a < b);
    const std::uint32_t from = a_into_b ? a : b, to = a_into_b ? b : a;
    heap_.push_back({std::max(0.0, std::min(to_a, to_b)), from, to, version_[from], version_[to]});
    std::push_heap(heap_.begin(), heap_.end(), std::greater<>());
  }
  void neighbours(std::uint32_t v, std::vector<std::uint32_t>& out) const {
    out.clear();
    for (std::uint32_t t : vert_tris_[v])
      for (int c = 0; c < 3; ++c)
        if (tris_[3 * t + c] != v) out.push_back(tris_[3 * t + c]);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  bool collapse(std::uint32_t u, std::uint32_t v) {
    neighbours(u, nu_);
    neighbours(v, nv_);
    common_.clear();
    std::set_intersection(nu_.begin(), nu_.end(), nv_.begin(), nv_.end(), std::back_inserter(common_));
    if (common_.size() != 2) return false;  // link condition (the edge's two apexes only)
    const glm::dvec3 pv = pos_[v];
    for (std::uint32_t t : vert_tris_[u]) {
      std::uint32_t idx[3] = {tris_[3 * t], tris_[3 * t + 1], tris_[3 * t + 2]};
      if (idx[0] == v || idx[1] == v || idx[2] == v) continue;
      const glm::dvec3 a = pos_[idx[0]], b = pos_[idx[1]], c = pos_[idx[2]];
      const glm::dvec3 n0 = glm::cross(b - a, c - a);
      for (auto& i : idx)
        if (i == u) i = v;
      const glm::dvec3 a1 = idx[0] == v ? pv : a, b1 = idx[1] == v ? pv : b, c1 = idx[2] == v ? pv : c;
      const glm::dvec3 n1 = glm::cross(b1 - a1, c1 - a1);
      const double l1 = glm::length(n1), l0 = glm::length(n0);
      if (l1 < 1e-9 || glm::dot(n0, n1) < min_cos_ * l0 * l1) return false;  // fold or sliver
      const double q1 = shape_quality(a1, b1, c1);
      if (q1 < min_quality_ && q1 < shape_quality(a, b, c)) return false;  // a new or worse sliver
    }
    for (std::uint32_t t : vert_tris_[u]) {
      const bool has_v = tris_[3 * t] == v || tris_[3 * t + 1] == v || tris_[3 * t + 2] == v;
      if (has_v) {
        tri_alive_[t] = 0;
        for (int c = 0; c < 3; ++c) {
          auto& list = vert_tris_[tris_[3 * t + c]];
          if (tris_[3 * t + c] != u) list.erase(std::find(list.begin(), list.end(), t));
        }
      } else {
        for (int c = 0; c < 3; ++c)
          if (tris_[3 * t + c] == u) tris_[3 * t + c] = v;
        vert_tris_[v].push_back(t);
      }
    }
    vert_tris_[u].clear();
    alive_[u] = 0;
    --live_;
    for (int k = 0; k < 10; ++k) quadric_[v][k] += quadric_[u][k];
    // Only v's quadric changed: its edges get fresh candidates, stale ones die by the version stamp.
    ++version_[v];
    neighbours(v, nv_);
    for (std::uint32_t w : nv_) push(v, w);
    return true;
  }

  double min_quality_;
  std::vector<glm::vec3> pos_;
  std::vector<std::uint32_t> tris_;
  std::vector<std::vector<std::uint32_t>> vert_tris_;
  std::vector<std::array<double, 10>> quadric_;
  std::vector<std::uint32_t> version_;
  std::vector<std::uint8_t> alive_, tri_alive_;
  std::size_t live_ = 0;
  double min_cos_ = 0.3;
  std::vector<Candidate> heap_;
  std::vector<std::uint32_t> nu_, nv_, common_;
};

}  // namespace

SimplifiedSurface simplify_surface(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& triangles,
                                   std::uint32_t target_vertices, double min_quality) {
  Collapser c(positions, triangles, min_quality);
  c.run(target_vertices);
  SimplifiedSurface s = c.result();
  if (!is_closed_manifold(s.triangles, s.positions.size()))
    throw std::logic_error("simplify_surface: simplification broke the closed manifold");
  return s;
}

Mesh body_level_mesh(SimplifiedSurface surface, std::string name,
                     const std::function<std::uint16_t(std::size_t, const glm::vec3&)>& part_of) {
  Mesh mesh;
  mesh.name = std::move(name);
  mesh.positions = std::move(surface.positions);
  mesh.triangles = std::move(surface.triangles);
  mesh.part_names = paper_part_names();
  mesh.part.resize(mesh.positions.size());
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) mesh.part[v] = part_of(v, mesh.positions[v]);
  compute_normals(mesh);
  return mesh;
}

}  // namespace strata
