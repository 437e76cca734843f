#include "motion/track.h"

#include <cmath>
#include <stdexcept>

namespace strata {

std::vector<CardinalSpline> make_stadium_lanes(const glm::vec3& center, float straight_length, float inner_radius,
                                               int lanes, float lane_spacing) {
  if (lanes < 1 || !(straight_length >= 0.0f) || !(inner_radius > 0.0f) || !(lane_spacing >= 0.0f))
    throw std::invalid_argument("make_stadium_lanes: need lanes >= 1, straight >= 0, radius > 0, spacing >= 0");
  constexpr int kPoints = 24;
  constexpr float kPi = 3.14159265358979f;
  std::vector<CardinalSpline> out;
  out.reserve(static_cast<std::size_t>(lanes));
  for (int lane = 0; lane < lanes; ++lane) {
    const float r = inner_radius + static_cast<float>(lane) * lane_spacing;
    const float half = 0.5f * straight_length;
    const float arc = kPi * r;
    const float total = 2.0f * straight_length + 2.0f * arc;
    std::vector<glm::vec3> points;
    points.reserve(kPoints);
    for (int k = 0; k < kPoints; ++k) {
      // Walk the outline by arc length: along +X on the +Z straight, then round the +X end.
      float s = total * static_cast<float>(k) / kPoints;
      glm::vec3 p;
      if (s < straight_length) {
        p = {-half + s, 0.0f, r};
      } else if ((s -= straight_length) < arc) {
        const float a = s / r;  // around the +X end, from z = +r to z = -r
        p = {half + r * std::sin(a), 0.0f, r * std::cos(a)};
      } else if ((s -= arc) < straight_length) {
        p = {half - s, 0.0f, -r};
      } else {
        s -= straight_length;
        const float a = s / r;
        p = {-half - r * std::sin(a), 0.0f, -r * std::cos(a)};
      }
      points.push_back(center + p);
    }
    out.emplace_back(std::move(points), 0.0f, true);
  }
  return out;
}

}  // namespace strata
