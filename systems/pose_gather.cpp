#include "systems/pose_gather.h"

#include <cmath>
#include <limits>

#include <glm/common.hpp>

namespace strata {

void gather_joint_positions(const WalkerLanes& lanes, std::vector<glm::vec3>& out) {
  const std::size_t joints = lanes.joints;
  out.resize(lanes.count * joints);
  const std::size_t stride = lanes.stride;
  for (std::size_t w = 0; w < lanes.count; ++w) {
    const Placement placement = placement_of(lanes, w);
    for (std::size_t j = 0; j < joints; ++j)
      out[w * joints + j] = placement.point({lanes.world[(j * kAffineFloats + 9) * stride + w],
                                             lanes.world[(j * kAffineFloats + 10) * stride + w],
                                             lanes.world[(j * kAffineFloats + 11) * stride + w]});
  }
}

bool joint_bounds(std::span<const glm::vec3> positions, glm::vec3& lo, glm::vec3& hi) {
  lo = glm::vec3(std::numeric_limits<float>::max());
  hi = glm::vec3(std::numeric_limits<float>::lowest());
  for (const glm::vec3& p : positions)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) lo = glm::min(lo, p), hi = glm::max(hi, p);
  return lo.x <= hi.x;
}

}  // namespace strata
