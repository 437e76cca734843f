#include "rig/harmonic_weights.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace strata {

std::vector<std::vector<JointWeight>> harmonic_weights(const Mesh& mesh, const SkinBinding& binding,
                                                       std::span<const std::uint8_t> free,
                                                       const HarmonicWeightOptions& options) {
  const std::size_t n = mesh.vertex_count();
  if (binding.vertex_count() != n || free.size() != n)
    throw std::invalid_argument("harmonic_weights: mesh, binding and free mask differ in vertex count");
  std::vector<std::vector<JointWeight>> out(n);
  const CotangentEdges neighbours = cotangent_edges(mesh, free);

  // Free vertices that reach a fixed one through free vertices: the others have no boundary value to take.
  std::vector<std::uint8_t> solvable(n, 0);
  std::vector<std::uint32_t> stack;
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!free[v] || solvable[v]) continue;
    bool touches_fixed = false;
    for (const auto& [u, w] : neighbours[v]) touches_fixed = touches_fixed || (w > 0.0 && !free[u]);
    if (!touches_fixed) continue;
    solvable[v] = 1;
    stack.push_back(v);
    while (!stack.empty()) {
      const std::uint32_t a = stack.back();
      stack.pop_back();
      for (const auto& [u, w] : neighbours[a])
        if (w > 0.0 && free[u] && !solvable[u]) solvable[u] = 1, stack.push_back(u);
    }
  }

  // The joints on the boundary: the only ones a harmonic field can carry into the region.
  std::vector<int> joints;
  for (std::uint32_t v = 0; v < n; ++v)
    if (solvable[v])
      for (const auto& [u, w] : neighbours[v])
        if (!free[u])
          for (int k = 0; k < kMaxInfluences; ++k)
            if (binding.weights[u][k] > 0.0f) joints.push_back(binding.joints[u][k]);
  std::sort(joints.begin(), joints.end());
  joints.erase(std::unique(joints.begin(), joints.end()), joints.end());
  if (joints.empty()) return out;
  const std::size_t jn = joints.size();
  auto slot_of = [&](int joint) {
    return static_cast<std::size_t>(std::lower_bound(joints.begin(), joints.end(), joint) - joints.begin());
  };
  auto dense = [&](std::uint32_t v, double* row) {
    std::fill(row, row + jn, 0.0);
    for (int k = 0; k < kMaxInfluences; ++k) {
      const std::size_t s = slot_of(binding.joints[v][k]);
      if (binding.weights[v][k] > 0.0f && s < jn && joints[s] == binding.joints[v][k]) row[s] += binding.weights[v][k];
    }
  };

  // Per free vertex: the fixed neighbours' share (right-hand side), the total edge weight, the current weights.
  std::vector<std::uint32_t> order;
  for (std::uint32_t v = 0; v < n; ++v)
    if (solvable[v]) order.push_back(v);
  std::vector<double> fixed_share(order.size() * jn, 0.0), total(order.size(), 0.0), x(n * jn, 0.0);
  std::vector<double> row(jn);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const std::uint32_t v = order[i];
    dense(v, &x[v * jn]);
    for (const auto& [u, w] : neighbours[v]) {
      total[i] += w;
      if (free[u]) continue;
      dense(u, row.data());
      for (std::size_t s = 0; s < jn; ++s) fixed_share[i * jn + s] += w * row[s];
    }
  }
  for (int sweep = 0; sweep < options.max_sweeps; ++sweep) {
    double largest_step = 0.0;
    for (std::size_t i = 0; i < order.size(); ++i) {
      const std::uint32_t v = order[i];
      if (!(total[i] > 0.0)) continue;
      for (std::size_t s = 0; s < jn; ++s) row[s] = fixed_share[i * jn + s];
      for (const auto& [u, w] : neighbours[v])
        if (free[u] && w > 0.0)
          for (std::size_t s = 0; s < jn; ++s) row[s] += w * x[u * jn + s];
      for (std::size_t s = 0; s < jn; ++s) {
        const double step = options.relaxation * (row[s] / total[i] - x[v * jn + s]);
        x[v * jn + s] += step;
        largest_step = std::max(largest_step, std::abs(step));
      }
    }
    if (largest_step <= options.tolerance) break;
  }

  // Soft threshold: every weight is lowered by min_weight and clamped at 0 before renormalising, so a joint fades
  // out continuously where its weight falls to min_weight. A plain cut made a jump of min_weight there, and on
  // the small triangles of the armpit a 1-2 % jump was enough to flip one in the walk.
  const double soft = options.min_weight;
  for (std::uint32_t v : order) {
    double sum = 0.0, largest = -1.0;
    std::size_t best = 0;
    for (std::size_t s = 0; s < jn; ++s) {
      const double w = std::clamp(x[v * jn + s], 0.0, 1.0);
      sum += std::max(w - soft, 0.0);
      if (w > largest) largest = w, best = s;
    }
    if (!(sum > 0.0)) {  // every weight within min_weight of 0 (more than 1 / min_weight joints): the largest
      out[v].push_back({joints[best], 1.0});
      continue;
    }
    for (std::size_t s = 0; s < jn; ++s) {
      const double w = std::max(std::clamp(x[v * jn + s], 0.0, 1.0) - soft, 0.0) / sum;
      if (w > 0.0) out[v].push_back({joints[s], w});
    }
  }
  return out;
}

}  // namespace strata
