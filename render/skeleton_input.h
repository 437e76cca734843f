#pragma once
// What the renderer draws skeletons (and places the ground) from: every walker's world-space joint positions.
#include <cstddef>
#include <span>

#include <glm/vec3.hpp>

#include "components/skeleton.h"

namespace strata {

struct SkeletonDrawInput {
  const Skeleton* skeleton = nullptr;
  // World-space joint positions, walker-major: joint j of walker w at [w * joint_count + j].
  std::span<const glm::vec3> joint_positions;
  std::size_t walker_count = 0;
  // Further points the ground must reach under: walkers drawn without joints (impostors), at their feet.
  std::span<const glm::vec3> ground_points = {};
  // Further points the sun's shadow frustum must hold (RenderQuality::High fits it to the box of the joints and
  // these): a process drawing part of a crowd gives the corners of the whole crowd's joints (dist/), so that its
  // shadow map has the same texels as one process drawing everything.
  std::span<const glm::vec3> shadow_fit_points = {};
};

// Throws std::invalid_argument when `input` has walkers but no skeleton, a skeleton whose parents disagree with
// its joint count, or fewer joint positions than walkers x joints. The passes that read the joints rely on it.
void check_skeleton_input(const SkeletonDrawInput& input);

// The joint positions an input really holds: walker_count x joint_count of them (none without a skeleton).
std::span<const glm::vec3> drawn_joint_positions(const SkeletonDrawInput& input);

}  // namespace strata
