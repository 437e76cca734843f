#include "rig/muscle_binding.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>


namespace strata {
namespace {

// Added to every angle before inverting it, so a force vector pointing straight at the vertex (angle 0) gets a
// large but finite share (1 / 0.01 against ~1 / 1.57 for a perpendicular one).
constexpr float kAngleEpsilon = 0.01f;

float distance_to_segment(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b) {
  const glm::vec3 ab = b - a;
  const float t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0f, 1.0f);
  return glm::length(p - (a + t * ab));
}

}  // namespace

MuscleBinding bind_muscles(const Mesh& mesh, const MuscleSet& set) {
  MuscleBinding out;
  // Which mesh parts each line may bind.
  std::vector<std::vector<bool>> allowed(set.lines.size(), std::vector<bool>(mesh.part_names.size(), false));
  for (std::size_t m = 0; m < set.lines.size(); ++m)
    for (std::size_t p = 0; p < mesh.part_names.size(); ++p)
      allowed[m][p] = std::find(set.lines[m].parts.begin(), set.lines[m].parts.end(), mesh.part_names[p]) !=
                      set.lines[m].parts.end();
  const bool has_parts = mesh.part.size() == mesh.vertex_count();
  for (std::uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    if (!has_parts) break;
    const glm::vec3 p = mesh.positions[v];
    int best = -1;
    float best_r = 0.0f;
    for (std::size_t m = 0; m < set.lines.size(); ++m) {
      if (!allowed[m][mesh.part[v]]) continue;
      const ActionLine& line = set.lines[m];
      const float r = distance_to_segment(p, line.origin_rest, line.insertion_rest);
      if (r < line.radius && (best < 0 || r < best_r)) best = static_cast<int>(m), best_r = r;
    }
    if (best < 0) continue;
    const ActionLine& line = set.lines[static_cast<std::size_t>(best)];
    // The line's control points by distance (ties by index, so the result does not depend on the sort).
    std::vector<std::pair<float, std::uint32_t>> near;
    for (std::uint32_t k = 0; k < line.point_count; ++k)
      near.push_back({glm::length(p - action_line_point(line.origin_rest, line.insertion_rest, k, line.point_count)), k});
    std::sort(near.begin(), near.end());
    const std::size_t used = std::min<std::size_t>(kMusclePointsPerVertex, near.size());
    std::array<std::uint32_t, kMusclePointsPerVertex> points{};
    std::array<float, kMusclePointsPerVertex> weights{};
    std::array<std::uint32_t, kMusclePointsPerVertex> first{};
    double sum = 0.0;
    for (std::size_t i = 0; i < used; ++i) sum += 1.0 / std::max(near[i].first, 1e-6f);
    // Rest local frame, the same for every point of the straight rest line.
    const glm::vec3 z = glm::normalize(line.insertion_rest - line.origin_rest);
    const glm::vec3 y = line.outward_rest;
    const glm::vec3 x = glm::cross(y, z);
    for (std::size_t i = 0; i < kMusclePointsPerVertex; ++i) {
      const std::uint32_t k = i < used ? near[i].second : near[0].second;
      points[i] = line.first_point + k;
      weights[i] = i < used ? static_cast<float>(1.0 / std::max(near[i].first, 1e-6f) / sum) : 0.0f;
      first[i] = static_cast<std::uint32_t>(out.share.size());
      const glm::vec3 cp = action_line_point(line.origin_rest, line.insertion_rest, k, line.point_count);
      const glm::vec3 to_vertex = p - cp;
      const float reach = glm::length(to_vertex);
      const std::vector<ForceVector>& vectors = line.forces[k];
      std::vector<float> inverse_angle(vectors.size(), 1.0f);  // a vertex on the point itself: equal shares
      float total = 0.0f;
      for (std::size_t a = 0; a < vectors.size(); ++a) {
        if (reach > 1e-7f) {
          const glm::vec3 d = vectors[a].direction;
          const glm::vec3 rest_dir = x * d.x + y * d.y + z * d.z;
          const float c = std::clamp(glm::dot(rest_dir, to_vertex / reach), -1.0f, 1.0f);
          inverse_angle[a] = 1.0f / (std::acos(c) + kAngleEpsilon);
        }
        total += inverse_angle[a];
      }
      for (float s : inverse_angle) out.share.push_back(s / total);
    }
    const float q = best_r / line.radius;
    out.vertex.push_back(v);
    out.line.push_back(static_cast<std::uint16_t>(best));
    out.point.push_back(points);
    out.weight.push_back(weights);
    out.falloff.push_back((1.0f - q * q) * (1.0f - q * q));
    out.share_first.push_back(first);
  }
  return out;
}

std::vector<std::array<float, kMusclePointsPerVertex>> muscle_coefficients(const MuscleSet& set,
                                                                           const MuscleBinding& binding,
                                                                           const MuscleGains& gains) {
  // Control point -> (line, point within the line), to find each point's force vectors.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> owner(set.point_count);
  for (std::uint32_t m = 0; m < set.lines.size(); ++m)
    for (std::uint32_t k = 0; k < set.lines[m].point_count; ++k) owner[set.lines[m].first_point + k] = {m, k};
  std::vector<std::array<float, kMusclePointsPerVertex>> c(binding.size());
  for (std::size_t b = 0; b < binding.size(); ++b) {
    const float gain = gains.of(binding.line[b]) * binding.falloff[b];
    for (int i = 0; i < kMusclePointsPerVertex; ++i) {
      const auto [m, k] = owner[binding.point[b][i]];
      const std::vector<ForceVector>& vectors = set.lines[m].forces[k];
      float sum = 0.0f;
      for (std::size_t a = 0; a < vectors.size(); ++a) sum += binding.share[binding.share_first[b][i] + a] * vectors[a].magnitude;
      c[b][i] = gain * binding.weight[b][i] * sum;
    }
  }
  return c;
}

std::shared_ptr<const MuscleRig> bind_muscle_rig(MuscleSet set, const Body& body) {
  auto rig = std::make_shared<MuscleRig>();
  for (const BodyLevel& level : body.levels) rig->levels.push_back(bind_muscles(level.mesh, set));
  if (body.cage) rig->cage = bind_muscles(body.cage->mesh, set);
  rig->set = std::move(set);
  return rig;
}

}  // namespace strata
