#pragma once
// The scalar twin of the FK system: a plain recursive evaluation of the H-Anim transform chain
// G_j = G_p * T(c_j) * R_j * T(-c_j) with glm 4x4 matrices, one walker at a time. Slow and obvious; tests compare
// the SoA system against it.
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#include "components/skeleton.h"

namespace strata {

struct ReferencePose {
  std::vector<glm::mat4> skinning;  // G_j = F(j) A(j)^-1
  std::vector<glm::mat4> world;     // F(j) = G_j T(c_j)
};

ReferencePose fk_reference(const Skeleton& skeleton, const std::vector<glm::quat>& local_rotations,
                           const glm::vec3& root_translation);

}  // namespace strata
