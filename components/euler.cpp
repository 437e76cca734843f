#include "components/euler.h"

#include <algorithm>
#include <cmath>

namespace strata {

// Written out, R = Rx(x) Rz(z) Ry(y) has (row, column) entries
//   R01 = -sin z            R00 = cos z cos y    R02 = cos z sin y
// so z comes from one entry and y from atan2 of two entries scaled by cos z (>= 0 on the branch |z| <= pi/2).
// x is then read from what is left, Rx(x) = R (Rz(z) Ry(y))^T, rather than from atan2(R21, R11): those entries
// carry a factor cos z too, and near the lock the two separately noisy angles x and y would no longer rebuild R.
// From the residual, x absorbs y's error and the rebuilt rotation stays exact; at the lock itself (y = 0) the
// same formula yields x - y or x + y, the only defined combination. glm is column-major: (row r, col c) = m[c][r].
// The work is done in double: near the lock the float products would lose the digits atan2 needs.
glm::dvec3 limit_angles(const glm::dmat3& m) {
  const double cz = std::sqrt(m[0][0] * m[0][0] + m[2][0] * m[2][0]);
  const double sz = -m[1][0];
  // atan2(sin, cos) rather than asin(-R01): asin loses half its digits next to +-1, exactly where the lock is.
  const double z = std::atan2(sz, cz);
  const double y = cz < 1e-6 ? 0.0 : std::atan2(m[2][0], m[0][0]);
  const double h = std::sqrt(sz * sz + cz * cz);
  const double s = sz / h, c = cz / h, sy = cz < 1e-6 ? 0.0 : m[2][0] / cz, cy = cz < 1e-6 ? 1.0 : m[0][0] / cz;
  // Rows 1 and 2 of R dotted with row 1 of Rz Ry = [sin z cos y, cos z, sin z sin y]: cos x and sin x.
  const double cos_x = m[0][1] * s * cy + m[1][1] * c + m[2][1] * s * sy;
  const double sin_x = m[0][2] * s * cy + m[1][2] * c + m[2][2] * s * sy;
  return {std::atan2(sin_x, cos_x), y, z};
}

glm::vec3 limit_angles(const glm::mat3& rotation) { return glm::vec3(limit_angles(glm::dmat3(rotation))); }

glm::mat3 rotation_from_limit_angles(const glm::vec3& angles) {
  const double sx = std::sin(angles.x), cx = std::cos(angles.x);
  const double sy = std::sin(angles.y), cy = std::cos(angles.y);
  const double sz = std::sin(angles.z), cz = std::cos(angles.z);
  // Rows of Rx * (Rz * Ry); Rz * Ry rows are [cz cy, -sz, cz sy], [sz cy, cz, sz sy], [-sy, 0, cy].
  const double m[3][3] = {
      {cz * cy, -sz, cz * sy},
      {cx * sz * cy + sx * sy, cx * cz, cx * sz * sy - sx * cy},
      {sx * sz * cy - cx * sy, sx * cz, sx * sz * sy + cx * cy},
  };
  glm::mat3 out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out[c][r] = static_cast<float>(m[r][c]);
  return out;
}

float limit_violation(const JointLimits& limits, const glm::vec3& angles) {
  if (!limits.present) return 0.0f;
  float total = 0.0f;
  for (int a = 0; a < 3; ++a)
    total += std::max(0.0f, limits.lower[a] - angles[a]) + std::max(0.0f, angles[a] - limits.upper[a]);
  return total;
}

glm::vec3 clamp_to_limits(const JointLimits& limits, const glm::vec3& angles) {
  if (!limits.present) return angles;
  glm::vec3 out;
  for (int a = 0; a < 3; ++a) out[a] = std::clamp(angles[a], limits.lower[a], limits.upper[a]);
  return out;
}

}  // namespace strata
