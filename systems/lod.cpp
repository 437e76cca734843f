#include "systems/lod.h"

#include <algorithm>
#include <array>
#include <cmath>

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
           float radius, float height, int previous, int fixed_level, int levels) {
  if (!frustum.sees(center, radius)) return -1;
  if (fixed_level >= 0) return fixed_level;
  const float distance = std::max(glm::length(center - view.eye), 1e-3f);
  const float pixels = view.focal_px * height / distance;
  const float thresholds[2] = {policy.level0_px, policy.level1_px};
  // The plain choice; then, against the previous level, thresholds raised by the hysteresis factor to move
  // finer and lowered by it to move coarser, so a walker sitting on a threshold keeps its level.
  auto pick = [&](float scale) { return pixels > thresholds[0] * scale ? 0 : pixels > thresholds[1] * scale ? 1 : 2; };
  int level = pick(1.0f);
  if (previous >= 0 && previous <= 2 && level != previous) {
    const float h = std::max(policy.hysteresis, 1.0f);
    level = level < previous ? std::min(previous, pick(h)) : std::max(previous, pick(1.0f / h));
  }
  return std::clamp(level, 0, std::max(levels - 1, 0));
}

}  // namespace

int lod_decide(const LodView& view, const LodPolicy& policy, const glm::vec3& center, float radius, float height,
               int previous, int fixed_level, int levels) {
  return decide(Frustum(view.view_projection), view, policy, center, radius, height, previous, fixed_level, levels);
}

bool LodJob::validate() const {
  if (view == nullptr || policy == nullptr) return false;
  if (levels < 1 || levels > 3 || fixed_level >= levels || previous_level >= levels) return false;
  if (!(std::isfinite(body_height) && body_height > 0.0f)) return false;
  if (decided.size() != walkers) return false;
  if (walkers == 0) return true;
  return placement != nullptr && world != nullptr && stride >= walkers;
}

bool LodJob::run() const {
  if (!validate()) return false;
  const Frustum frustum(view->view_projection);
  for (std::size_t w = 0; w < walkers; ++w) {
    const float heading = placement[3 * stride + w];
    const float scale = placement[4 * stride + w];
    const glm::vec3 position(placement[0 * stride + w], placement[1 * stride + w], placement[2 * stride + w]);
    const Placement P{position, std::cos(heading), std::sin(heading), scale};
    // The root's posed position (F(0)'s translation, humanoid space) placed in the world; the sphere reaches
    // the head, the feet and outstretched arms.
    const glm::vec3 root(world[9 * stride + w], world[10 * stride + w], world[11 * stride + w]);
    const float height = body_height * P.scale;
    const int level = decide(frustum, *view, *policy, P.point(root), 0.75f * height, height, previous_level,
                             fixed_level, levels);
    decided[w] = level < 0 ? culled_slot : static_cast<std::uint8_t>(level);
  }
  return true;
}

}  // namespace strata
