#pragma once
// Level-of-detail system (frame script step, after muscle, before skin): for every walker decides whether the
// camera sees it at all (frustum culling against its bounding sphere) and, under the automatic policy, which
// body level to skin and draw from its projected height in pixels, with hysteresis so a walker near a threshold
// does not flicker between levels. Writes the decision into the walker's lod column (components/walker.h):
// -1 culled, else the level. Culled walkers are neither skinned nor drawn.
//
// Per walker, independent of the others and of thread scheduling, so deterministic.
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "components/walker.h"

namespace strata {

// What the camera sees: its view-projection matrix (world -> clip), its position, and its focal length in
// pixels (viewport height / (2 tan(fov_y / 2))), which turns a size at a distance into pixels.
struct LodView {
  glm::mat4 view_projection{1.0f};
  glm::vec3 eye{0.0f};
  float focal_px = 1000.0f;
};

// Walkers taller than level0_px on screen get level 0, taller than level1_px level 1, else level 2. A walker
// moves to a finer level only once it is `hysteresis` times past the threshold, and to a coarser one only once
// it is that factor below it. The defaults keep level 0 for walkers taller than about a third of a 1080-pixel
// frame; below ~160 px level 1's 8,923 vertices are already finer than the pixels.
struct LodPolicy {
  float level0_px = 360.0f;
  float level1_px = 160.0f;
  float hysteresis = 1.15f;
};

inline constexpr float kLodCulled = -1.0f;
inline constexpr float kLodUnset = -2.0f;  // a walker's first decision: no hysteresis yet

// `fixed_level` >= 0: every visible walker gets that level (culling only); -1: the automatic policy over levels
// 0..levels-1. `body_height` is the rig's rest height (m); a walker's is that times its scale.
void lod_system(const LodView& view, const LodPolicy& policy, const WalkerLanes& lanes, float body_height,
                int fixed_level, int levels);

// The decision for one walker given its bounding sphere (world), and its previous level (kLodUnset at first).
int lod_decide(const LodView& view, const LodPolicy& policy, const glm::vec3& center, float radius, float height,
               int previous, int fixed_level, int levels);

}  // namespace strata
