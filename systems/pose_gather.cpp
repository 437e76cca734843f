#include "systems/pose_gather.h"

#include <cmath>

#include <glm/common.hpp>

namespace strata {

void gather_joint_positions(const WalkerLanes& lanes, std::vector<glm::vec3>& out) {
  const std::size_t joints = lanes.joints;
  out.resize(lanes.count * joints);
  const std::size_t stride = lanes.stride;
  for (std::size_t w = 0; w < lanes.count; ++w) {
    const float px = lanes.placement[0 * stride + w];
    const float py = lanes.placement[1 * stride + w];
    const float pz = lanes.placement[2 * stride + w];
    const float heading = lanes.placement[3 * stride + w];
    const float scale = lanes.placement[4 * stride + w];
    const float ch = std::cos(heading), sh = std::sin(heading);
    for (std::size_t j = 0; j < joints; ++j) {
      const float x = scale * lanes.world[(j * kAffineFloats + 9) * stride + w];
      const float y = scale * lanes.world[(j * kAffineFloats + 10) * stride + w];
      const float z = scale * lanes.world[(j * kAffineFloats + 11) * stride + w];
      // Heading rotates about +Y: a walker with heading h faces (sin h, 0, cos h) instead of +Z.
      out[w * joints + j] = glm::vec3(ch * x + sh * z + px, y + py, -sh * x + ch * z + pz);
    }
  }
}

bool joint_bounds(const std::vector<glm::vec3>& positions, glm::vec3& lo, glm::vec3& hi) {
  if (positions.empty()) return false;
  lo = hi = positions.front();
  for (const glm::vec3& p : positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  return true;
}

}  // namespace strata
