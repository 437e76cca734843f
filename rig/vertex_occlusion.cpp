#include "rig/vertex_occlusion.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "components/fnv_hasher.h"
#include "rig/body_cache.h"
#include "rig/subdiv_topology.h"

namespace strata {
namespace {

// A binary bounding-volume hierarchy over triangles, split at the median centroid along the widest axis: simple,
// and for a body's few tens of thousands of triangles built in milliseconds.
class TriangleBvh {
 public:
  TriangleBvh(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& triangles)
      : positions_(positions) {
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
      const std::uint32_t a = triangles[t], b = triangles[t + 1], c = triangles[t + 2];
      if (a >= positions.size() || b >= positions.size() || c >= positions.size()) continue;
      const glm::vec3 n = glm::cross(positions[b] - positions[a], positions[c] - positions[a]);
      if (!(glm::dot(n, n) > 1e-20f)) continue;  // degenerate (or non-finite): hits nothing
      tris_.push_back({a, b, c});
    }
    if (tris_.empty()) return;
    centroids_.resize(tris_.size());
    for (std::size_t t = 0; t < tris_.size(); ++t)
      centroids_[t] = (positions[tris_[t][0]] + positions[tris_[t][1]] + positions[tris_[t][2]]) / 3.0f;
    order_.resize(tris_.size());
    std::iota(order_.begin(), order_.end(), 0u);
    nodes_.reserve(4 * tris_.size() / kLeaf + 1);
    nodes_.push_back({});
    build(0, 0, static_cast<std::uint32_t>(tris_.size()));
  }

  // Distance to the nearest hit within (0, t_max], or t_max when none.
  float nearest(const glm::vec3& origin, const glm::vec3& dir, float t_max) const {
    if (nodes_.empty()) return t_max;
    const glm::vec3 inv(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
    std::array<std::uint32_t, 64> stack;
    std::size_t top = 0;
    stack[top++] = 0;
    float best = t_max;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if (!hits_box(node, origin, inv, best)) continue;
      if (node.count > 0) {
        for (std::uint32_t k = node.first; k < node.first + node.count; ++k) best = std::min(best, hit(order_[k], origin, dir, best));
      } else if (top + 2 <= stack.size()) {
        stack[top++] = node.first;
        stack[top++] = node.first + 1;
      }
    }
    return best;
  }

 private:
  static constexpr std::uint32_t kLeaf = 4;
  struct Node {
    glm::vec3 lo, hi;
    std::uint32_t first = 0;  // leaf: first index into order_; inner: index of the left child (right = +1)
    std::uint32_t count = 0;  // triangles in a leaf; 0 for an inner node
  };

  // Fills node `slot` with triangles order_[begin, end) and builds its children, made as a pair so the right one
  // is always left + 1.
  void build(std::uint32_t slot, std::uint32_t begin, std::uint32_t end) {
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
    glm::vec3 clo = lo, chi = hi;
    for (std::uint32_t k = begin; k < end; ++k) {
      for (std::uint32_t corner : tris_[order_[k]]) lo = glm::min(lo, positions_[corner]), hi = glm::max(hi, positions_[corner]);
      clo = glm::min(clo, centroids_[order_[k]]), chi = glm::max(chi, centroids_[order_[k]]);
    }
    nodes_[slot].lo = lo, nodes_[slot].hi = hi;
    if (end - begin <= kLeaf) {
      nodes_[slot].first = begin, nodes_[slot].count = end - begin;
      return;
    }
    const glm::vec3 extent = chi - clo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const std::uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](std::uint32_t a, std::uint32_t b) { return centroids_[a][axis] < centroids_[b][axis]; });
    const auto left = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back({}), nodes_.push_back({});
    nodes_[slot].first = left;
    build(left, begin, mid);
    build(left + 1, mid, end);
  }

  static bool hits_box(const Node& n, const glm::vec3& o, const glm::vec3& inv, float t_max) {
    float t0 = 0.0f, t1 = t_max;
    for (int a = 0; a < 3; ++a) {
      float near = (n.lo[a] - o[a]) * inv[a], far = (n.hi[a] - o[a]) * inv[a];
      if (near > far) std::swap(near, far);
      t0 = std::max(t0, near);
      t1 = std::min(t1, far);
      if (t0 > t1) return false;
    }
    return true;
  }
  // Moller-Trumbore; t_max when the ray misses.
  float hit(std::uint32_t t, const glm::vec3& o, const glm::vec3& d, float t_max) const {
    const glm::vec3 &a = positions_[tris_[t][0]], &b = positions_[tris_[t][1]], &c = positions_[tris_[t][2]];
    const glm::vec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
    const float det = glm::dot(e1, p);
    if (std::abs(det) < 1e-12f) return t_max;
    const float inv_det = 1.0f / det;
    const glm::vec3 s = o - a;
    const float u = glm::dot(s, p) * inv_det;
    if (u < 0.0f || u > 1.0f) return t_max;
    const glm::vec3 q = glm::cross(s, e1);
    const float v = glm::dot(d, q) * inv_det;
    if (v < 0.0f || u + v > 1.0f) return t_max;
    const float dist = glm::dot(e2, q) * inv_det;
    return dist > 0.0f && dist < t_max ? dist : t_max;
  }

  const std::vector<glm::vec3>& positions_;
  std::vector<std::array<std::uint32_t, 3>> tris_;
  std::vector<glm::vec3> centroids_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace

VertexOcclusion bake_vertex_occlusion(const Mesh& mesh, const OcclusionOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  VertexOcclusion out;
  const std::size_t n = mesh.vertex_count();
  out.open.assign(n, 1.0f);
  Mesh with_normals;
  const std::vector<glm::vec3>* normals = &mesh.normals;
  if (mesh.normals.size() != n) {
    with_normals.positions = mesh.positions;
    // Only whole triangles with indices in range (compute_normals trusts its input).
    for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3)
      if (mesh.triangles[t] < n && mesh.triangles[t + 1] < n && mesh.triangles[t + 2] < n)
        with_normals.triangles.insert(with_normals.triangles.end(), mesh.triangles.begin() + static_cast<std::ptrdiff_t>(t),
                                      mesh.triangles.begin() + static_cast<std::ptrdiff_t>(t + 3));
    compute_normals(with_normals);
    normals = &with_normals.normals;
  }
  const TriangleBvh bvh(mesh.positions, mesh.triangles);
  const int rays = std::max(options.rays, 1);
  const float range = std::max(options.range, 1e-4f);
  // Cosine-weighted directions in the normal's frame: points spread evenly over the unit disk (a golden-angle
  // spiral) lifted onto the hemisphere (Malley's method).
  std::vector<glm::vec3> pattern(static_cast<std::size_t>(rays));
  for (int k = 0; k < rays; ++k) {
    const float r = std::sqrt((static_cast<float>(k) + 0.5f) / static_cast<float>(rays));
    const float phi = 2.39996323f * static_cast<float>(k);
    pattern[static_cast<std::size_t>(k)] = {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - r * r))};
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& range_v) {
    for (std::size_t v = range_v.begin(); v != range_v.end(); ++v) {
      const glm::vec3 normal = (*normals)[v];
      if (!(glm::dot(normal, normal) > 0.25f) || !std::isfinite(mesh.positions[v].x + mesh.positions[v].y + mesh.positions[v].z))
        continue;
      const glm::vec3 z = glm::normalize(normal);
      const glm::vec3 helper = std::abs(z.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
      const glm::vec3 x0 = glm::normalize(glm::cross(helper, z)), y0 = glm::cross(z, x0);
      // The pattern turned about the normal by an angle hashed from the vertex number.
      const float turn = 6.2831853f * static_cast<float>((static_cast<std::uint32_t>(v) * 2654435761u) >> 8) / 16777216.0f;
      const glm::vec3 x = std::cos(turn) * x0 + std::sin(turn) * y0, y = glm::cross(z, x);
      const glm::vec3 origin = mesh.positions[v] + z * 2e-4f;
      float occluded = 0.0f;
      for (const glm::vec3& p : pattern) {
        const glm::vec3 dir = p.x * x + p.y * y + p.z * z;
        const float t = bvh.nearest(origin, dir, range);
        occluded += 1.0f - t / range;  // a hit at the vertex occludes fully, one at the range's end not at all
      }
      out.open[v] = std::clamp(1.0f - occluded / static_cast<float>(rays), 0.0f, 1.0f);
    }
  });
  // Two passes of neighbour averaging over the triangles' edges: a few dozen rays leave a vertex-to-vertex
  // grain, and a crease's occlusion on an irregular mesh zigzags; the smoothed field keeps its shape.
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<float> sum(out.open), count(n, 1.0f);
    for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = mesh.triangles[t + static_cast<std::size_t>(k)];
        const std::uint32_t b = mesh.triangles[t + static_cast<std::size_t>((k + 1) % 3)];
        if (a >= n || b >= n) continue;
        sum[a] += out.open[b], count[a] += 1.0f;
        sum[b] += out.open[a], count[b] += 1.0f;
      }
    for (std::size_t v = 0; v < n; ++v) out.open[v] = sum[v] / count[v];
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

namespace {

constexpr char kOcclusionMagic[8] = {'S', 'T', 'R', 'A', 'O', 'C', '0', '1'};
constexpr std::uint32_t kOcclusionVersion = 1;  // bump when the bake changes its result

std::uint64_t occlusion_cache_key(const Mesh& mesh, const OcclusionOptions& options) {
  FnvHasher h;
  h.value(kOcclusionVersion);
  h.vector(mesh.positions);
  h.vector(mesh.normals);
  h.vector(mesh.triangles);
  h.value(options.rays);
  h.value(options.range);
  return h.h;
}

}  // namespace

VertexOcclusion cached_vertex_occlusion(const Mesh& mesh, const OcclusionOptions& options) {
  const std::uint64_t key = occlusion_cache_key(mesh, options);
  const std::optional<std::filesystem::path> dir = body_cache_directory();
  char name[48];
  std::snprintf(name, sizeof name, "occlusion-%016llx.bin", static_cast<unsigned long long>(key));
  if (dir)
    if (std::optional<std::vector<float>> open = load_float_cache(*dir / name, kOcclusionMagic, key, 1, 1u << 26);
        open && open->size() == mesh.vertex_count()) {
      VertexOcclusion out;
      out.open = std::move(*open);
      out.from_cache = true;
      return out;
    }
  VertexOcclusion out = bake_vertex_occlusion(mesh, options);
  if (dir) save_float_cache(*dir / name, kOcclusionMagic, key, 1, out.open);
  return out;
}

std::shared_ptr<const VertexOcclusion> body_vertex_occlusion(const Body& body, int level) {
  const BodyLevel* l = body_level_or_cage(body, level);
  if (!l) return nullptr;
  return body.occlusion.get(per_level_slot(level), [&] { return std::make_shared<const VertexOcclusion>(cached_vertex_occlusion(l->mesh)); });
}

std::vector<float> refined_occlusion(const std::vector<float>& cage_open, const SubdivSurface& surface) {
  std::vector<float> level(surface.cage_layout.vertex_count, 1.0f);
  for (std::size_t v = 0; v < level.size() && v < surface.cage_layout.original.size(); ++v)
    if (surface.cage_layout.original[v] < cage_open.size()) level[v] = cage_open[surface.cage_layout.original[v]];
  for (const SubdivStencils& step : surface.steps) {
    std::vector<float> next(step.rows(), 1.0f);
    for (std::size_t r = 0; r < step.rows(); ++r) {
      float sum = 0.0f, weight = 0.0f;
      for (std::uint32_t t = step.offsets[r]; t < step.offsets[r + 1]; ++t)
        if (step.indices[t] < level.size()) sum += step.weights[t] * level[step.indices[t]], weight += step.weights[t];
      if (weight > 1e-6f) next[r] = std::clamp(sum / weight, 0.0f, 1.0f);
    }
    level = std::move(next);
  }
  // The last step's rows are the refined vertices in SubdivSurface numbering already.
  level.resize(surface.vertex_count, 1.0f);
  return level;
}

}  // namespace strata
