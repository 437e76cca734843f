#include "render/footprint.h"

#include <algorithm>
#include <cmath>

#include <glm/vec4.hpp>

namespace strata {

PixelRect screen_footprint(const glm::vec3& lo, const glm::vec3& hi, const glm::vec3* to_sun,
                           const glm::mat4& view_projection, int width, int height, int pad_px) {
  const PixelRect whole{0, 0, std::max(width, 0), std::max(height, 0)};
  for (float v : {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z})
    if (std::isnan(v)) return whole;
  if (lo.x > hi.x || lo.y > hi.y || lo.z > hi.z) return {};  // nothing of this process's in the frame
  if (!std::isfinite(lo.x + lo.y + lo.z + hi.x + hi.y + hi.z)) return whole;
  if (to_sun && !(to_sun->y > 0.05f)) return whole;  // also for a NaN sun
  // The box's corners and, under the sun, where each corner's ray meets the ground: their hull holds everything
  // the walkers and their shadows can cover.
  glm::vec4 clip[16];
  int points = 0;
  for (int k = 0; k < 8; ++k) {
    const glm::vec3 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
    clip[points++] = view_projection * glm::vec4(corner, 1.0f);
    if (to_sun && corner.y > 0.0f)
      clip[points++] = view_projection * glm::vec4(corner - *to_sun * (corner.y / to_sun->y), 1.0f);
  }
  // Only the part in front of the near plane (clip z >= -w) is drawn. The hull clipped there has as vertices the
  // points in front and the crossings of its edges with the plane; the crossings of every pair of points are a
  // superset of those, all inside the clipped hull, so their rectangle still bounds it. A box reaching behind the
  // camera (a camera inside the crowd) keeps a rectangle this way instead of the whole frame.
  float x_min = INFINITY, x_max = -INFINITY, y_min = INFINITY, y_max = -INFINITY;
  bool folded = false;
  const auto add = [&](const glm::vec4& c) {
    if (!(c.w > 1e-6f)) {
      folded = true;  // not a perspective or orthographic projection's point in front of the eye
      return;
    }
    const float x = c.x / c.w, y = c.y / c.w;
    x_min = std::min(x_min, x), x_max = std::max(x_max, x);
    y_min = std::min(y_min, y), y_max = std::max(y_max, y);
  };
  const auto in_front = [](const glm::vec4& c) { return c.z + c.w; };
  for (int a = 0; a < points; ++a) {
    const float fa = in_front(clip[a]);
    if (fa >= 0.0f) add(clip[a]);
    for (int b = a + 1; b < points; ++b) {
      const float fb = in_front(clip[b]);
      if ((fa >= 0.0f) == (fb >= 0.0f)) continue;
      add(clip[a] + (fa / (fa - fb)) * (clip[b] - clip[a]));
    }
  }
  if (folded) return whole;
  if (x_min > x_max) return {};  // all of it behind the near plane: nothing drawn
  if (!std::isfinite(x_min + x_max + y_min + y_max)) return whole;
  // NDC x in [-1, 1] left to right; y in [-1, 1] bottom to top, rows counted from the top. Clamped in floats
  // first: a box far off screen projects to values no int holds.
  const auto column = [&](float ndc) { return std::clamp((ndc + 1.0f) * 0.5f * static_cast<float>(width), -1.0f, static_cast<float>(width) + 1.0f); };
  const auto row = [&](float ndc) { return std::clamp((1.0f - ndc) * 0.5f * static_cast<float>(height), -1.0f, static_cast<float>(height) + 1.0f); };
  PixelRect r{static_cast<int>(std::floor(column(x_min))) - pad_px, static_cast<int>(std::floor(row(y_max))) - pad_px,
              static_cast<int>(std::ceil(column(x_max))) + pad_px, static_cast<int>(std::ceil(row(y_min))) + pad_px};
  r.x0 = std::max(r.x0, 0), r.y0 = std::max(r.y0, 0);
  r.x1 = std::min(r.x1, whole.x1), r.y1 = std::min(r.y1, whole.y1);
  return r.empty() ? PixelRect{} : r;
}

}  // namespace strata
