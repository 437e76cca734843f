#pragma once
// Pose gather: turns the joint-major FK output into what a consumer outside the SoA world wants, walker-major
// world-space joint positions (each walker's placement applied). The render system's CPU side.
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "components/skeleton.h"
#include "components/walker.h"

namespace strata {

// out[w * joints + j] = placement(w) * origin of F(j) of walker w (position, heading and scale). Resizes `out`.
void gather_joint_positions(const WalkerLanes& lanes, std::vector<glm::vec3>& out);

// Axis-aligned bounds of the finite positions; false when there are none.
bool joint_bounds(std::span<const glm::vec3> positions, glm::vec3& lo, glm::vec3& hi);

}  // namespace strata
