#include "reference/skin_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include <glm/ext/vector_int3_sized.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include "reference/fk_reference.h"
#include "reference/skin_reference.h"

namespace strata {
namespace {

glm::dmat3 blended_linear(const SkinBinding& binding, std::span<const glm::mat4> skinning, std::size_t v) {
  glm::dmat3 m(0.0);
  double total = 0.0;
  for (int k = 0; k < kMaxInfluences; ++k) {
    const float w = binding.weights[v][k];
    const int j = binding.joints[v][k];
    if (!(w > 0.0f) || j < 0 || static_cast<std::size_t>(j) >= skinning.size()) continue;
    m += double(w) * glm::dmat3(glm::mat3(skinning[j]));
    total += w;
  }
  return total > 0.0 ? m / total : glm::dmat3(1.0);
}

bool finite(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

double distance(const glm::vec3& a, const glm::vec3& b) { return glm::length(glm::dvec3(a) - glm::dvec3(b)); }

double cone_volume(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& o) {
  return glm::dot(a - o, glm::cross(b - o, c - o)) / 6.0;
}

std::vector<std::size_t> triangles_near(const Mesh& mesh, std::span<const glm::vec3> positions,
                                        const glm::vec3& centre, float radius) {
  std::vector<std::size_t> out;
  const glm::dvec3 c(centre);
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const glm::dvec3 g = (glm::dvec3(positions[mesh.triangles[t]]) + glm::dvec3(positions[mesh.triangles[t + 1]]) +
                          glm::dvec3(positions[mesh.triangles[t + 2]])) / 3.0;
    if (glm::length(g - c) <= radius) out.push_back(t);
  }
  return out;
}

double volume_of(const Mesh& mesh, std::span<const glm::vec3> positions, const std::vector<std::size_t>& tris,
                 const glm::vec3& centre) {
  double sum = 0.0;
  for (std::size_t t : tris)
    sum += cone_volume(glm::dvec3(positions[mesh.triangles[t]]), glm::dvec3(positions[mesh.triangles[t + 1]]),
                       glm::dvec3(positions[mesh.triangles[t + 2]]), glm::dvec3(centre));
  return sum;
}

}  // namespace

SkinMetrics measure_skin(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning,
                         std::span<const glm::vec3> posed, const SkinMetricsOptions& options) {
  const std::size_t n = rest.vertex_count();
  if (posed.size() != n || binding.vertex_count() != n)
    throw std::invalid_argument("measure_skin: rest mesh, binding and posed positions differ in vertex count");
  SkinMetrics m;
  for (const glm::vec3& p : posed) m.nan_count += !finite(p);

  for (std::size_t t = 0; t + 2 < rest.triangles.size(); t += 3) {
    const std::uint32_t a = rest.triangles[t], b = rest.triangles[t + 1], c = rest.triangles[t + 2];
    const glm::dvec3 rest_n = glm::cross(glm::dvec3(rest.positions[b]) - glm::dvec3(rest.positions[a]),
                                         glm::dvec3(rest.positions[c]) - glm::dvec3(rest.positions[a]));
    const double rest_area2 = glm::length(rest_n);
    if (!(rest_area2 > 1e-20)) continue;  // degenerate at rest: it has no orientation to lose
    ++m.triangles;
    if (!finite(posed[a]) || !finite(posed[b]) || !finite(posed[c])) {
      ++m.inverted_triangles;
      continue;
    }
    const glm::dvec3 posed_n = glm::cross(glm::dvec3(posed[b]) - glm::dvec3(posed[a]),
                                          glm::dvec3(posed[c]) - glm::dvec3(posed[a]));
    const glm::dmat3 carry =
        (blended_linear(binding, skinning, a) + blended_linear(binding, skinning, b) +
         blended_linear(binding, skinning, c)) / 3.0;
    const bool flipped = glm::dot(posed_n, carry * rest_n) <= 0.0;
    const bool collapsed = glm::length(posed_n) < options.collapse_fraction * rest_area2;
    m.inverted_triangles += flipped || collapsed;
  }

  // Rest-coincident vertices: a hash grid with cells of the tolerance, each vertex compared with the 27 cells
  // around it. Sorting along one axis and sweeping was the simpler choice, but a mesh with a flat face
  // perpendicular to that axis (every vertex at one x) makes the sweep quadratic.
  const double cell = std::max(options.coincident_m, 1e-9);
  auto cell_of = [&](const glm::vec3& p) {
    return glm::i64vec3(static_cast<std::int64_t>(std::floor(p.x / cell)),
                        static_cast<std::int64_t>(std::floor(p.y / cell)),
                        static_cast<std::int64_t>(std::floor(p.z / cell)));
  };
  auto key_of = [](const glm::i64vec3& c) {
    return static_cast<std::uint64_t>(c.x) * 0x9E3779B97F4A7C15ull ^
           static_cast<std::uint64_t>(c.y) * 0xC2B2AE3D27D4EB4Full ^
           static_cast<std::uint64_t>(c.z) * 0x165667B19E3779F9ull;
  };
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> grid;
  for (std::uint32_t v = 0; v < n; ++v)
    if (finite(rest.positions[v])) grid[key_of(cell_of(rest.positions[v]))].push_back(v);
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!finite(rest.positions[v])) continue;
    const glm::i64vec3 c = cell_of(rest.positions[v]);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(key_of(c + glm::i64vec3(dx, dy, dz)));
          if (it == grid.end()) continue;
          for (std::uint32_t u : it->second) {
            // Each pair once; a hash collision only adds candidates, which the distance test rejects.
            if (u <= v || distance(rest.positions[u], rest.positions[v]) > options.coincident_m) continue;
            const double gap = finite(posed[u]) && finite(posed[v]) ? distance(posed[u], posed[v])
                                                                    : std::numeric_limits<double>::infinity();
            m.seam_gap_max_m = std::max(m.seam_gap_max_m, gap);
          }
        }
  }
  return m;
}

double joint_volume(const Mesh& mesh, std::span<const glm::vec3> positions, const glm::vec3& centre, float radius) {
  if (positions.size() != mesh.vertex_count())
    throw std::invalid_argument("joint_volume: one position per mesh vertex expected");
  return volume_of(mesh, positions, triangles_near(mesh, positions, centre, radius), centre);
}

double joint_volume_change_pct(const Mesh& rest, std::span<const glm::vec3> posed, const glm::vec3& rest_centre,
                               const glm::vec3& posed_centre, float radius) {
  if (posed.size() != rest.vertex_count())
    throw std::invalid_argument("joint_volume_change_pct: one posed position per rest vertex expected");
  const std::vector<std::size_t> tris = triangles_near(rest, rest.positions, rest_centre, radius);
  const double before = volume_of(rest, rest.positions, tris, rest_centre);
  const double after = volume_of(rest, posed, tris, posed_centre);
  if (before == 0.0) return 0.0;
  return 100.0 * (after - before) / std::abs(before);
}

double flexion_volume_change_pct(const Mesh& rest, const SkinBinding& binding, const Skeleton& skeleton, int joint,
                                 float angle_rad, float radius) {
  if (joint < 0 || static_cast<std::size_t>(joint) >= skeleton.joint_count())
    throw std::invalid_argument("flexion_volume_change_pct: joint out of range");
  const JointLimits& lim = skeleton.limits[joint];
  const float sign = lim.present && -lim.lower.x > lim.upper.x ? -1.0f : 1.0f;
  std::vector<glm::quat> rotations(skeleton.joint_count(), glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  rotations[joint] = glm::angleAxis(sign * angle_rad, glm::vec3(1.0f, 0.0f, 0.0f));
  const ReferencePose pose = fk_reference(skeleton, rotations, glm::vec3(0.0f));
  const SkinnedVertices posed = skin_reference(rest, binding, pose.skinning);
  return joint_volume_change_pct(rest, posed.positions, skeleton.centers[joint], glm::vec3(pose.world[joint][3]),
                                 radius);
}

}  // namespace strata
