#include "reference/skin_reference.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <algorithm>
#include <array>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

namespace strata {

std::vector<glm::mat4> walker_skinning_matrices(const WalkerLanes& lanes, std::size_t walker) {
  if (walker >= lanes.count) throw std::invalid_argument("walker_skinning_matrices: walker out of range");
  std::vector<glm::mat4> out(lanes.joints, glm::mat4(1.0f));
  for (std::size_t j = 0; j < lanes.joints; ++j)
    for (int col = 0; col < 4; ++col)
      for (int row = 0; row < 3; ++row)
        out[j][col][row] = lanes.at(lanes.skinning, j * kAffineFloats + col * 3 + row)[walker];
  return out;
}

SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning) {
  const std::size_t n = rest.vertex_count();
  if (binding.vertex_count() != n)
    throw std::invalid_argument("skin_reference: binding has " + std::to_string(binding.vertex_count()) +
                                " vertices, mesh has " + std::to_string(n));
  std::vector<glm::vec3> computed;
  const std::vector<glm::vec3>* rest_normals = &rest.normals;
  if (rest.normals.size() != n) {
    Mesh copy = rest;
    compute_normals(copy);
    computed = std::move(copy.normals);
    rest_normals = &computed;
  }

  SkinnedVertices out;
  out.positions.resize(n);
  out.normals.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    double total = 0.0;
    for (int k = 0; k < kMaxInfluences; ++k) total += binding.weights[v][k] > 0.0f ? binding.weights[v][k] : 0.0f;
    glm::dmat4 blended(0.0);
    if (total > 0.0) {
      for (int k = 0; k < kMaxInfluences; ++k) {
        const float w = binding.weights[v][k];
        if (!(w > 0.0f)) continue;
        const int j = binding.joints[v][k];
        if (j < 0 || static_cast<std::size_t>(j) >= skinning.size())
          throw std::invalid_argument("skin_reference: vertex " + std::to_string(v) + " uses joint " +
                                      std::to_string(j) + " but there are " + std::to_string(skinning.size()) +
                                      " skinning matrices");
        blended += (double(w) / total) * glm::dmat4(skinning[j]);
      }
    } else {
      blended = glm::dmat4(1.0);  // an unbound vertex stays where it is rather than collapsing to the origin
    }
    const glm::dvec4 p = blended * glm::dvec4(glm::dvec3(rest.positions[v]), 1.0);
    out.positions[v] = glm::vec3(p);
    const glm::dvec3 nrm = glm::dmat3(blended) * glm::dvec3((*rest_normals)[v]);
    // Below 1e-6 the direction is float noise of the matrices (opposed rotations cancel), not a normal.
    const double len = glm::length(nrm);
    out.normals[v] = len > 1e-6 && std::isfinite(len) ? glm::vec3(nrm / len) : (*rest_normals)[v];
  }
  return out;
}

std::vector<float> walker_muscle_forces(const WalkerLanes& lanes, std::size_t walker) {
  if (walker >= lanes.count) throw std::invalid_argument("walker_muscle_forces: walker out of range");
  std::vector<float> f(lanes.muscle_points);
  for (std::size_t p = 0; p < f.size(); ++p) f[p] = lanes.at(lanes.muscle_force, p)[walker];
  return f;
}

std::vector<double> muscle_displacement_reference(std::size_t vertex_count, const MuscleReference& m) {
  std::vector<double> d(vertex_count, 0.0);
  if (!m.set || !m.binding) return d;
  const MuscleSet& set = *m.set;
  const MuscleBinding& b = *m.binding;
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (b.vertex[i] >= vertex_count) throw std::invalid_argument("muscle_displacement_reference: vertex out of range");
    const ActionLine& line = set.lines.at(b.line[i]);
    double sum = 0.0;
    for (int s = 0; s < kMusclePointsPerVertex; ++s) {
      const std::uint32_t p = b.point[i][s];
      if (p < line.first_point || p >= line.first_point + line.point_count || p >= m.force.size())
        throw std::invalid_argument("muscle_displacement_reference: control point outside its line");
      const std::vector<ForceVector>& vectors = line.forces[p - line.first_point];
      double field = 0.0;
      for (std::size_t a = 0; a < vectors.size(); ++a)
        field += double(b.share[b.share_first[i][s] + a]) * double(vectors[a].magnitude);
      sum += double(b.weight[i][s]) * field * double(m.force[p]);
    }
    d[b.vertex[i]] = double(b.falloff[i]) * double(m.gains.of(b.line[i])) * sum;
  }
  return d;
}

SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning,
                               const MuscleReference& muscles) {
  SkinnedVertices out = skin_reference(rest, binding, skinning);
  const std::vector<double> d = muscle_displacement_reference(rest.vertex_count(), muscles);
  for (std::size_t v = 0; v < d.size(); ++v)
    out.positions[v] = glm::vec3(glm::dvec3(out.positions[v]) + d[v] * glm::dvec3(out.normals[v]));
  return out;
}

SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, const WalkerLanes& lanes,
                               std::size_t walker) {
  const std::vector<glm::mat4> matrices = walker_skinning_matrices(lanes, walker);
  return skin_reference(rest, binding, matrices);
}

namespace {

// Rotation of an (orthonormal up to float noise) skinning matrix as a unit quaternion; the identity for a matrix
// that has none (zero), so no NaN leaves.
glm::dquat rotation_of(const glm::dmat4& m) {
  glm::dquat q = glm::quat_cast(glm::dmat3(m));
  const double len = glm::length(q);
  if (!(len > 1e-12) || !std::isfinite(len)) return glm::dquat(1.0, 0.0, 0.0, 0.0);
  return q / len;
}

}  // namespace

SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning,
                               SkinningMode mode, std::span<const glm::vec3> centres) {
  SkinnedVertices out = skin_reference(rest, binding, skinning);  // linear, and the checks
  if (mode == SkinningMode::Linear) return out;
  const std::size_t n = rest.vertex_count();
  if (mode == SkinningMode::CentresOfRotation && centres.size() != n)
    throw std::invalid_argument("skin_reference: centres of rotation need one centre per vertex");
  std::vector<glm::vec3> computed;
  const std::vector<glm::vec3>* rest_normals = &rest.normals;
  if (rest.normals.size() != n) {
    Mesh copy = rest;
    compute_normals(copy);
    computed = std::move(copy.normals);
    rest_normals = &computed;
  }
  std::vector<glm::dquat> rot(skinning.size());
  for (std::size_t j = 0; j < skinning.size(); ++j) rot[j] = rotation_of(glm::dmat4(skinning[j]));
  for (std::size_t v = 0; v < n; ++v) {
    std::array<std::pair<int, double>, kMaxInfluences> inf{};
    int count = 0;
    double total = 0.0;
    for (int k = 0; k < kMaxInfluences; ++k)
      if (binding.weights[v][k] > 0.0f) {
        inf[static_cast<std::size_t>(count++)] = {binding.joints[v][k], binding.weights[v][k]};
        total += binding.weights[v][k];
      }
    if (count < 2) continue;  // rigid: the linear result is exact
    std::sort(inf.begin(), inf.begin() + count);
    const glm::dquat q0 = rot[static_cast<std::size_t>(inf[0].first)];
    glm::dquat real(0.0, 0.0, 0.0, 0.0), dual(0.0, 0.0, 0.0, 0.0);
    glm::dmat4 blended(0.0);
    for (int k = 0; k < count; ++k) {
      const auto j = static_cast<std::size_t>(inf[static_cast<std::size_t>(k)].first);
      const double w = inf[static_cast<std::size_t>(k)].second / total;
      const glm::dmat4 m(skinning[j]);
      const double sign = glm::dot(rot[j], q0) < 0.0 ? -1.0 : 1.0;
      const glm::dquat t(0.0, m[3][0], m[3][1], m[3][2]);
      real += (w * sign) * rot[j];
      dual += (w * sign) * (0.5 * (t * rot[j]));
      blended += w * m;
    }
    const double len = glm::length(real);  // >= the first joint's weight: the others are aligned with it
    const glm::dquat r = real / len;
    const glm::dmat3 R = glm::mat3_cast(r);
    const glm::dvec3 p(rest.positions[v]);
    glm::dvec3 posed;
    if (mode == SkinningMode::DualQuaternion) {
      const glm::dquat d = dual / len;
      const glm::dquat tq = 2.0 * (d * glm::conjugate(r));
      posed = R * p + glm::dvec3(tq.x, tq.y, tq.z);
    } else {
      const glm::dvec3 c(centres[v]);
      posed = R * (p - c) + glm::dvec3(blended * glm::dvec4(c, 1.0));
    }
    out.positions[v] = glm::vec3(posed);
    const glm::dvec3 nrm = R * glm::dvec3((*rest_normals)[v]);
    const double nlen = glm::length(nrm);
    out.normals[v] = nlen > 1e-12 && std::isfinite(nlen) ? glm::vec3(nrm / nlen) : (*rest_normals)[v];
  }
  return out;
}

SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning,
                               SkinningMode mode, std::span<const glm::vec3> centres, const MuscleReference& muscles) {
  SkinnedVertices out = skin_reference(rest, binding, skinning, mode, centres);
  const std::vector<double> d = muscle_displacement_reference(rest.vertex_count(), muscles);
  for (std::size_t v = 0; v < d.size(); ++v)
    out.positions[v] = glm::vec3(glm::dvec3(out.positions[v]) + d[v] * glm::dvec3(out.normals[v]));
  return out;
}

}  // namespace strata
