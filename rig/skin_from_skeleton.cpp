#include "rig/skin_from_skeleton.h"

#include <algorithm>
#include <map>

namespace strata {

std::optional<BodyLevel> skin_from_skeleton(const Skeleton& s) {
  if (s.skin_points.empty() || s.skin_triangles.empty() || s.skin_offsets.size() != s.joint_count() + 1)
    return std::nullopt;
  const std::size_t n = s.skin_points.size();
  std::vector<std::vector<std::pair<float, std::int16_t>>> influences(n);
  for (std::size_t j = 0; j < s.joint_count(); ++j)
    for (std::uint32_t k = s.skin_offsets[j]; k < s.skin_offsets[j + 1]; ++k) {
      const SkinInfluence& inf = s.skin_influences[k];
      if (inf.vertex < n && inf.weight > 0.0f) influences[inf.vertex].push_back({inf.weight, static_cast<std::int16_t>(j)});
    }
  BodyLevel level;
  level.mesh.name = s.name + "_skin";
  level.mesh.positions = s.skin_points;
  level.mesh.triangles = s.skin_triangles;
  level.binding.joints.assign(n, {0, 0, 0, 0});
  level.binding.weights.assign(n, {0.0f, 0.0f, 0.0f, 0.0f});
  std::map<std::int16_t, std::uint16_t> part_of_joint;
  level.mesh.part.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    auto& list = influences[v];
    if (list.empty()) list.push_back({1.0f, 0});  // unlisted: follow the root (see the header)
    // Largest first; ties by joint index so the result never depends on input order.
    std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    const std::size_t keep = std::min<std::size_t>(list.size(), kMaxInfluences);
    float sum = 0.0f;
    for (std::size_t i = 0; i < keep; ++i) sum += list[i].first;
    for (std::size_t i = 0; i < keep; ++i) {
      level.binding.joints[v][i] = list[i].second;
      level.binding.weights[v][i] = list[i].first / sum;
    }
    const std::int16_t strongest = list.front().second;
    auto [it, added] = part_of_joint.emplace(strongest, static_cast<std::uint16_t>(level.mesh.part_names.size()));
    if (added) level.mesh.part_names.push_back("skin_" + s.joint_names[static_cast<std::size_t>(strongest)]);
    level.mesh.part[v] = it->second;
  }
  compute_normals(level.mesh);
  return level;
}

}  // namespace strata
