#include "systems/muscle.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace strata {
namespace {

struct Affine {
  float m[12];  // 3x4 column-major, as in the walker's skinning columns
  glm::vec3 point(const glm::vec3& p) const {
    return {m[0] * p.x + m[3] * p.y + m[6] * p.z + m[9], m[1] * p.x + m[4] * p.y + m[7] * p.z + m[10],
            m[2] * p.x + m[5] * p.y + m[8] * p.z + m[11]};
  }
  glm::vec3 direction(const glm::vec3& d) const {
    return {m[0] * d.x + m[3] * d.y + m[6] * d.z, m[1] * d.x + m[4] * d.y + m[7] * d.z,
            m[2] * d.x + m[5] * d.y + m[8] * d.z};
  }
};

Affine skinning_of(const WalkerLanes& lanes, std::size_t walker, std::int32_t joint) {
  Affine a;
  for (int c = 0; c < 12; ++c) a.m[c] = lanes.at(lanes.skinning, std::size_t(joint) * kAffineFloats + c)[walker];
  return a;
}

// Any unit vector perpendicular to unit z.
glm::vec3 perpendicular(const glm::vec3& z) {
  const glm::vec3 other = std::fabs(z.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(z, other));
}

}  // namespace

void muscle_walker(const MuscleSet& set, const WalkerLanes& lanes, std::size_t w) {
  float lengths[64];
  for (const ActionLine& line : set.lines) {
    const Affine so = skinning_of(lanes, w, line.origin_joint);
    const Affine si = skinning_of(lanes, w, line.insertion_joint);
    const glm::vec3 origin = so.point(line.origin_rest);
    const glm::vec3 insertion = si.point(line.insertion_rest);
    action_line_point_lengths(origin, insertion, line.point_count, lengths);
    // Frame: z along the line; when the ends meet, the rest direction carried by the origin joint instead.
    const glm::vec3 axis = insertion - origin;
    const float axis_length = glm::length(axis);
    const glm::vec3 rest_z = glm::normalize(line.insertion_rest - line.origin_rest);
    glm::vec3 z = axis_length > 1e-6f ? axis / axis_length : so.direction(rest_z);
    if (!(glm::length(z) > 1e-6f)) z = rest_z;  // a collapsed matrix: keep the rest frame rather than NaN
    z = glm::normalize(z);
    glm::vec3 y = so.direction(line.outward_rest);
    y -= glm::dot(y, z) * z;
    y = glm::length(y) > 1e-6f ? glm::normalize(y) : perpendicular(z);
    for (std::uint32_t k = 0; k < line.point_count; ++k) {
      const std::uint32_t p = line.first_point + k;
      const glm::vec3 position = action_line_point(origin, insertion, k, line.point_count);
      for (int c = 0; c < 3; ++c) lanes.at(lanes.muscle_point, p * 3 + c)[w] = position[c];
      for (int c = 0; c < 3; ++c) lanes.at(lanes.muscle_frame, p * 6 + c)[w] = y[c];
      for (int c = 0; c < 3; ++c) lanes.at(lanes.muscle_frame, p * 6 + 3 + c)[w] = z[c];
      const float rest = set.rest_length[p];
      const float l = lengths[k];
      // The clamp keeps a collapsed segment finite; `!(l >= floor)` also catches a NaN length.
      const float floor = set.min_length_ratio * rest;
      const float used = !(l >= floor) ? floor : l;
      lanes.at(lanes.muscle_length, p)[w] = l;
      lanes.at(lanes.muscle_force, p)[w] = rest / used - 1.0f;
    }
  }
}

void muscle_system(const MuscleSet& set, const WalkerLanes& lanes) {
  if (set.point_count == 0 || lanes.count == 0) return;
  if (lanes.muscle_points != set.point_count)
    throw std::invalid_argument("muscle_system: walker table has " + std::to_string(lanes.muscle_points) +
                                " control point columns, the set has " + std::to_string(set.point_count));
  for (const ActionLine& line : set.lines)
    if (line.point_count > 64 || std::size_t(line.origin_joint) >= lanes.joints ||
        std::size_t(line.insertion_joint) >= lanes.joints)
      throw std::invalid_argument("muscle_system: line '" + line.name + "' does not fit this rig");
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lanes.count, 64),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t w = r.begin(); w < r.end(); ++w) muscle_walker(set, lanes, w);
                    });
}

}  // namespace strata
