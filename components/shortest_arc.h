#pragma once
// The rotation that takes one direction onto another by the shortest arc (no twist about either), in float or
// double: what retargeting aims a capture's bones with (motion/retarget.cpp) and what fits the MakeHuman body's
// limbs onto a skeleton (rig/makehuman_body.cpp).
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

namespace strata {

template <typename T>
glm::qua<T> shortest_arc(glm::vec<3, T> from, glm::vec<3, T> to) {
  from = glm::normalize(from);
  to = glm::normalize(to);
  const T d = glm::dot(from, to);
  if (d < T(-0.999999)) {
    // Opposite: any axis perpendicular to `from` will do; pick the one least aligned with it.
    glm::vec<3, T> axis = glm::cross(glm::vec<3, T>(1, 0, 0), from);
    if (glm::dot(axis, axis) < T(1e-6)) axis = glm::cross(glm::vec<3, T>(0, 1, 0), from);
    return glm::angleAxis(T(3.14159265358979), glm::normalize(axis));
  }
  const glm::vec<3, T> c = glm::cross(from, to);
  return glm::normalize(glm::qua<T>(T(1) + d, c.x, c.y, c.z));
}

}  // namespace strata
