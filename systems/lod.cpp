#include "systems/lod.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

namespace strata {
namespace {

// The six frustum planes, normalised, straight from the rows of the view-projection matrix (Gribb & Hartmann):
// for clip = M p, inside means -w <= x, y, z <= w. Built once per view, not per walker.
struct Frustum {
  std::array<glm::vec4, 6> planes{};
  int count = 0;  // planes with a usable normal

  explicit Frustum(const glm::mat4& m) {
    const glm::vec4 row0(m[0][0], m[1][0], m[2][0], m[3][0]);
    const glm::vec4 row1(m[0][1], m[1][1], m[2][1], m[3][1]);
    const glm::vec4 row2(m[0][2], m[1][2], m[2][2], m[3][2]);
    const glm::vec4 row3(m[0][3], m[1][3], m[2][3], m[3][3]);
    for (const glm::vec4& plane : {row3 + row0, row3 - row0, row3 + row1, row3 - row1, row3 + row2, row3 - row2}) {
      const float length = glm::length(glm::vec3(plane));
      if (length > 0.0f) planes[static_cast<std::size_t>(count++)] = plane / length;
    }
  }
  // Is the sphere at least partly inside?
  bool sees(const glm::vec3& c, float r) const {
    const glm::vec4 p(c, 1.0f);
    for (int i = 0; i < count; ++i)
      if (glm::dot(planes[static_cast<std::size_t>(i)], p) < -r) return false;
    return true;
  }
};

int decide(const Frustum& frustum, const LodView& view, const LodPolicy& policy, const glm::vec3& center,
           float radius, float height, int previous, int fixed_level, int levels, bool impostors) {
  if (!frustum.sees(center, radius)) return -1;
  if (fixed_level >= 0) return fixed_level;
  const float distance = std::max(glm::length(center - view.eye), 1e-3f);
  const float pixels = view.focal_px * height / distance;
  const float thresholds[3] = {policy.level0_px, policy.level1_px, policy.impostor_px};
  // Tiers from finest to coarsest: 0, 1, 2, impostor (kLodImpostor). The plain choice; then, against the previous
  // tier, thresholds raised by the hysteresis factor to move finer and lowered by it to move coarser, so a walker
  // sitting on a threshold keeps its tier.
  auto pick = [&](float scale) {
    if (pixels > thresholds[0] * scale) return 0;
    if (pixels > thresholds[1] * scale) return 1;
    return impostors && !(pixels > thresholds[2] * scale) ? kLodImpostor : 2;
  };
  int level = pick(1.0f);
  if (previous >= 0 && previous <= kLodImpostor && level != previous) {
    const float h = std::max(policy.hysteresis, 1.0f);
    level = level < previous ? std::min(previous, pick(h)) : std::max(previous, pick(1.0f / h));
  }
  if (level == kLodImpostor) return level;
  return std::clamp(level, 0, std::max(levels - 1, 0));
}

}  // namespace

int lod_decide(const LodView& view, const LodPolicy& policy, const glm::vec3& center, float radius, float height,
               int previous, int fixed_level, int levels, bool impostors) {
  return decide(Frustum(view.view_projection), view, policy, center, radius, height, previous, fixed_level, levels,
                impostors);
}

bool LodJob::validate() const {
  if (view == nullptr || policy == nullptr) return false;
  if (levels < 1 || levels > 3) return false;
  if (fixed_level >= levels && fixed_level != kLodImpostor) return false;
  if (previous_level >= levels && previous_level != kLodImpostor) return false;
  if (!(std::isfinite(body_height) && body_height > 0.0f)) return false;
  if (decided.size() != walkers || distance.size() != walkers) return false;
  if (walkers == 0) return true;
  return placement != nullptr && root_translation != nullptr && stride >= walkers;
}

bool LodJob::run() const {
  if (!validate()) return false;
  const Frustum frustum(view->view_projection);
  // Walkers are independent: chunks in parallel (100,000 walkers took 4 ms on one core).
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, walkers, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
  for (std::size_t w = r.begin(); w < r.end(); ++w) {
    const float heading = placement[3 * stride + w];
    const float scale = placement[4 * stride + w];
    const glm::vec3 position(placement[0 * stride + w], placement[1 * stride + w], placement[2 * stride + w]);
    const Placement P{position, std::cos(heading), std::sin(heading), scale};
    // The root's position (rest centre plus the motion's root offset, humanoid space) placed in the world; the
    // sphere reaches the head, the feet and outstretched arms. The root's posed frame (FK's F(0)) would be exact
    // but an impostor has none, and the root's rotation moves its centre by nothing.
    const glm::vec3 root = root_center + glm::vec3(root_translation[0 * stride + w], root_translation[1 * stride + w],
                                                   root_translation[2 * stride + w]);
    const glm::vec3 center = P.point(root);
    const float height = body_height * P.scale;
    const int level = decide(frustum, *view, *policy, center, 0.75f * height, height, previous_level, fixed_level,
                             levels, impostors);
    decided[w] = level < 0 ? culled_slot : level == kLodImpostor ? impostor_slot : static_cast<std::uint8_t>(level);
    distance[w] = glm::length(center - view->eye);
  }
  });
  return true;
}

}  // namespace strata
