#pragma once
// Where in a frame a process's own walkers can show: the screen rectangle of a world box and, under the sun, of
// the shadow it casts on the ground. A crowd spread over processes composites only these rectangles
// (dist/composite.h), since outside them every process's frame is the same shared scene.
//
// Why a projected box rather than reading the changed pixels back: a shadow changes colour, not depth, so the
// pixels a process changed cannot be told from its own frame without drawing the scene a second time without its
// walkers; eight corners and their eight shadow points cost nothing.
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace strata {

// Pixels [x0, x1) x [y0, y1) of a frame, rows top to bottom (read_rgba's order). Empty when x0 >= x1 or y0 >= y1.
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  bool operator==(const PixelRect&) const = default;
};

// The pixels of a width x height frame drawn with `view_projection` that the box [lo, hi] can cover, grown by
// `pad_px` on every side for rasterisation's rounding; with `to_sun` (towards the sun, y > 0) the box's shadow on
// the ground plane y = 0 too (the box swept along the sun's rays down to the ground, so a shadow falling on
// anything standing on the ground between them is inside). Only what lies in front of the near plane counts (a
// box reaching behind the camera is clipped there; nothing is drawn behind it). The whole frame when a value is
// not finite or the sun is within about 3 degrees of the horizon (shadows reach too far to bound usefully); empty
// when lo > hi or the box lies wholly behind the near plane. `view_projection` maps to GL's clip space (z in
// [-w, w]).
PixelRect screen_footprint(const glm::vec3& lo, const glm::vec3& hi, const glm::vec3* to_sun,
                           const glm::mat4& view_projection, int width, int height, int pad_px = 2);

}  // namespace strata
