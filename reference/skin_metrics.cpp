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

std::vector<glm::quat> flexion_rotations(const Skeleton& skeleton, int joint, float angle_rad) {
  if (joint < 0 || static_cast<std::size_t>(joint) >= skeleton.joint_count())
    throw std::invalid_argument("flexion: joint out of range");
  const JointLimits& lim = skeleton.limits[joint];
  const float sign = lim.present && -lim.lower.x > lim.upper.x ? -1.0f : 1.0f;
  std::vector<glm::quat> rotations(skeleton.joint_count(), glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  rotations[joint] = glm::angleAxis(sign * angle_rad, glm::vec3(1.0f, 0.0f, 0.0f));
  return rotations;
}

double flexion_volume_change_pct(const Mesh& rest, const SkinBinding& binding, const Skeleton& skeleton, int joint,
                                 float angle_rad, float radius, SkinningMode mode, std::span<const glm::vec3> centres) {
  const ReferencePose pose = fk_reference(skeleton, flexion_rotations(skeleton, joint, angle_rad), glm::vec3(0.0f));
  const SkinnedVertices posed = skin_reference(rest, binding, pose.skinning, mode, centres);
  return joint_volume_change_pct(rest, posed.positions, skeleton.centers[joint], glm::vec3(pose.world[joint][3]),
                                 radius);
}

namespace {

double segment_distance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(p - (a + t * ab));
}

double weight_of(const SkinBinding& binding, std::size_t v, int joint) {
  double w = 0.0, total = 0.0;
  for (int k = 0; k < kMaxInfluences; ++k) {
    if (!(binding.weights[v][k] > 0.0f)) continue;
    total += binding.weights[v][k];
    if (binding.joints[v][k] == joint) w += binding.weights[v][k];
  }
  return total > 0.0 ? w / total : 0.0;
}

bool bound_only_to(const SkinBinding& binding, std::size_t v, int a, int b) {
  for (int k = 0; k < kMaxInfluences; ++k)
    if (binding.weights[v][k] > 0.0f && binding.joints[v][k] != a && binding.joints[v][k] != b) return false;
  return true;
}

}  // namespace

double flexion_bulge_m(const Mesh& rest, const SkinBinding& binding, const Skeleton& skeleton, int joint, int child,
                       float angle_rad, float radius, SkinningMode mode, std::span<const glm::vec3> centres) {
  if (child < 0 || static_cast<std::size_t>(child) >= skeleton.joint_count())
    throw std::invalid_argument("flexion_bulge_m: child joint out of range");
  const int parent = skeleton.parents[static_cast<std::size_t>(joint)];
  if (parent < 0) throw std::invalid_argument("flexion_bulge_m: the joint has no parent bone");
  const ReferencePose pose = fk_reference(skeleton, flexion_rotations(skeleton, joint, angle_rad), glm::vec3(0.0f));
  const SkinnedVertices posed = skin_reference(rest, binding, pose.skinning, mode, centres);
  const glm::dvec3 rp(skeleton.centers[static_cast<std::size_t>(parent)]), rj(skeleton.centers[static_cast<std::size_t>(joint)]),
      rc(skeleton.centers[static_cast<std::size_t>(child)]);
  const glm::dvec3 pp(pose.world[static_cast<std::size_t>(parent)][3]), pj(pose.world[static_cast<std::size_t>(joint)][3]),
      pc(pose.world[static_cast<std::size_t>(child)][3]);
  double bulge = 0.0;
  for (std::size_t v = 0; v < rest.vertex_count(); ++v) {
    const glm::dvec3 r(rest.positions[v]);
    if (glm::length(r - rj) > radius) continue;
    const double before = std::min(segment_distance(r, rp, rj), segment_distance(r, rj, rc));
    const glm::dvec3 q(posed.positions[v]);
    const double after = std::min(segment_distance(q, pp, pj), segment_distance(q, pj, pc));
    bulge = std::max(bulge, after - before);
  }
  return bulge;
}

TwistSection twist_section(const Mesh& rest, const SkinBinding& binding, const Skeleton& skeleton, int joint,
                           int child, float angle_rad, SkinningMode mode, std::span<const glm::vec3> centres) {
  if (joint < 0 || child < 0 || static_cast<std::size_t>(std::max(joint, child)) >= skeleton.joint_count())
    throw std::invalid_argument("twist_section: joint out of range");
  const int parent = skeleton.parents[static_cast<std::size_t>(joint)];
  const glm::dvec3 o(skeleton.centers[static_cast<std::size_t>(joint)]);
  const glm::dvec3 axis = glm::normalize(glm::dvec3(skeleton.centers[static_cast<std::size_t>(child)]) - o);
  // The blend zone's middle along the axis.
  double num = 0.0, den = 0.0;
  for (std::size_t v = 0; v < rest.vertex_count(); ++v) {
    if (!bound_only_to(binding, v, joint, parent)) continue;
    const double w = weight_of(binding, v, joint);
    const double m = std::min(w, 1.0 - w);
    if (m <= 0.0) continue;
    num += m * glm::dot(glm::dvec3(rest.positions[v]) - o, axis);
    den += m;
  }
  TwistSection out;
  if (!(den > 0.0)) return out;  // nothing blended: nothing to twist
  out.axial_m = num / den;
  const glm::dvec3 centre = o + out.axial_m * axis;
  std::vector<std::size_t> tris;
  for (std::size_t t = 0; t + 2 < rest.triangles.size(); t += 3) {
    bool limb = true;
    for (int k = 0; k < 3; ++k) limb = limb && bound_only_to(binding, rest.triangles[t + k], joint, parent);
    if (limb) tris.push_back(t);
  }
  // Rest rotations are identity, so the axis in the joint's local frame is the world axis; the joint stays put.
  std::vector<glm::quat> rotations(skeleton.joint_count(), glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  rotations[static_cast<std::size_t>(joint)] = glm::angleAxis(angle_rad, glm::vec3(axis));
  const ReferencePose pose = fk_reference(skeleton, rotations, glm::vec3(0.0f));
  const SkinnedVertices posed = skin_reference(rest, binding, pose.skinning, mode, centres);
  out.rest_area_m2 = plane_section(rest.positions, rest.triangles, tris, centre, axis).area;
  out.posed_area_m2 = plane_section(posed.positions, rest.triangles, tris, centre, axis).area;
  out.area_ratio = out.rest_area_m2 > 0.0 ? out.posed_area_m2 / out.rest_area_m2 : 1.0;
  return out;
}

}  // namespace strata
