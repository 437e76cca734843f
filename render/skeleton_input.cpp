#include "render/skeleton_input.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace strata {

void check_skeleton_input(const SkeletonDrawInput& input) {
  if (input.walker_count == 0) return;
  if (!input.skeleton) throw std::invalid_argument("crowd renderer: walkers given without a skeleton");
  if (input.skeleton->parents.size() != input.skeleton->joint_count())
    throw std::invalid_argument("crowd renderer: skeleton parents/joint count mismatch");
  const std::size_t needed = input.walker_count * input.skeleton->joint_count();
  if (input.joint_positions.size() < needed)
    throw std::invalid_argument("crowd renderer: " + std::to_string(input.joint_positions.size()) +
                                " joint positions for " + std::to_string(needed) + " walker joints");
}

std::span<const glm::vec3> drawn_joint_positions(const SkeletonDrawInput& input) {
  const std::size_t n = input.walker_count * (input.skeleton ? input.skeleton->joint_count() : 0);
  return input.joint_positions.first(std::min(n, input.joint_positions.size()));
}

}  // namespace strata
