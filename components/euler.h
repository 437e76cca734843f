#pragma once
// The Euler convention of joint limits (see JointLimits in components/skeleton.h): R = Rx(x) * Rz(z) * Ry(y),
// column vectors, angles in radians, the solution with |z| <= pi/2.
#include <glm/gtc/quaternion.hpp>
#include <glm/ext/matrix_double3x3.hpp>
#include <glm/ext/vector_double3.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "components/skeleton.h"

namespace strata {

// Angles (x, y, z) of R = Rx(x) Rz(z) Ry(y). At the gimbal lock (|z| = pi/2) y is set to 0 and x takes the rest.
glm::vec3 limit_angles(const glm::mat3& rotation);
// The same in double precision, for solvers that compare against limits at bisection resolution.
glm::dvec3 limit_angles(const glm::dmat3& rotation);
// Inverse of limit_angles: Rx(x) Rz(z) Ry(y).
glm::mat3 rotation_from_limit_angles(const glm::vec3& angles);
// Sum over axes of how far each angle lies outside [lower, upper] (radians); 0 when inside or no limits.
float limit_violation(const JointLimits& limits, const glm::vec3& angles);
// The angles clamped into the limits, axis by axis.
glm::vec3 clamp_to_limits(const JointLimits& limits, const glm::vec3& angles);

}  // namespace strata
