#include "reference/fk_reference.h"

#include <glm/gtc/matrix_transform.hpp>
#include <stdexcept>

namespace strata {
namespace {

void visit(const Skeleton& skeleton, const std::vector<std::vector<int>>& children,
           const std::vector<glm::quat>& rotations, int joint, const glm::mat4& parent_global, ReferencePose& pose) {
  const glm::vec3 c = skeleton.centers[joint];
  // X3D Transform with only center and rotation: T(c) * R * T(-c), applied after the parent's.
  glm::mat4 local = glm::translate(glm::mat4(1.0f), c) * glm::mat4_cast(glm::normalize(rotations[joint])) *
                    glm::translate(glm::mat4(1.0f), -c);
  glm::mat4 global = parent_global * local;
  pose.skinning[joint] = global;
  pose.world[joint] = global * glm::translate(glm::mat4(1.0f), c);
  for (int child : children[joint]) visit(skeleton, children, rotations, child, global, pose);
}

}  // namespace

ReferencePose fk_reference(const Skeleton& skeleton, const std::vector<glm::quat>& local_rotations,
                           const glm::vec3& root_translation) {
  const std::size_t n = skeleton.joint_count();
  if (local_rotations.size() != n) throw std::invalid_argument("fk_reference: one rotation per joint expected");
  std::vector<std::vector<int>> children(n);
  int root = -1;
  for (std::size_t j = 0; j < n; ++j) {
    if (skeleton.parents[j] < 0)
      root = static_cast<int>(j);
    else
      children[skeleton.parents[j]].push_back(static_cast<int>(j));
  }
  ReferencePose pose;
  pose.skinning.resize(n);
  pose.world.resize(n);
  if (root >= 0) visit(skeleton, children, local_rotations, root, glm::translate(glm::mat4(1.0f), root_translation), pose);
  return pose;
}

}  // namespace strata
