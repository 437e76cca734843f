#pragma once
// Walking tracks for crowds: closed loops on the ground built as Cardinal splines.
#include <vector>

#include <glm/vec3.hpp>

#include "motion/cardinal_spline.h"

namespace strata {

// A stadium (two straights joined by half circles) around `center` on the ground, long axis along X, as `lanes`
// concentric closed Cardinal splines: lane k runs at radius `inner_radius + k * lane_spacing`. A walker
// moving forward along a lane travels +X on its +Z straight. Each loop interpolates 24 points of the exact outline, so its length
// is within 0.1 % of the stadium's.
std::vector<CardinalSpline> make_stadium_lanes(const glm::vec3& center, float straight_length, float inner_radius,
                                               int lanes, float lane_spacing);

}  // namespace strata
