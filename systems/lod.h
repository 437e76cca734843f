#pragma once
// Level-of-detail system (the frame's lod stage, after muscle, before skin): for every walker decides whether the
// camera sees it at all (frustum culling against its bounding sphere) and, under the automatic policy, which
// body level to skin and draw from its projected height in pixels, with hysteresis so a walker near a threshold
// does not flicker between levels. The decision is the table the walker is skinned from (scene/step.cpp moves
// it there); culled walkers are neither skinned nor drawn.
//
// Per walker, independent of the others and of thread scheduling, so deterministic.
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <span>

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

// The level-of-detail job over one walker table (ozz-style: inputs and outputs are public members, validate()
// then run()). The table a walker sits in is its previous decision (scene/crowd.h: DetailSlot), so one job runs
// per table with that table's `previous_level`.
//
// Reads: placement (5 components: x, y, z, heading, scale) and world matrices (joint 0's translation, components
// 9..11: the root's posed position) of `walkers` rows, `stride` apart. Writes: decided[w], the slot index the
// walker is skinned from this frame: its mesh level 0..levels-1, or `culled_slot` when the camera does not see it.
struct LodJob {
  const LodView* view = nullptr;
  const LodPolicy* policy = nullptr;
  float body_height = 1.75f;  // the rig's rest height (m); a walker's is that times its scale
  int previous_level = -1;    // the mesh level the table holds, or -1 (culled or never decided: no hysteresis)
  int fixed_level = -1;       // >= 0: every visible walker gets this level (culling only); -1: the automatic policy
  int levels = 1;             // mesh levels the body has (1..3)
  std::uint8_t culled_slot = 4;  // the value written for a culled walker (the caller's culled table, scene/crowd.h)
  std::size_t walkers = 0;
  std::size_t stride = 0;
  const float* placement = nullptr;
  const float* world = nullptr;
  std::span<std::uint8_t> decided;

  // Every pointer set for a non-empty table, stride >= walkers, decided.size() == walkers, levels in 1..3,
  // fixed_level < levels, body_height finite and positive. No side effects.
  bool validate() const;
  // validate(), then decide every walker; false (writing nothing) when invalid.
  bool run() const;
};

// `previous` of a walker that has no level to keep (culled, or never decided): its decision is the plain one.
inline constexpr int kLodNoPrevious = -1;

// The decision for one walker given its bounding sphere (world), and its previous level (kLodUnset at first).
int lod_decide(const LodView& view, const LodPolicy& policy, const glm::vec3& center, float radius, float height,
               int previous, int fixed_level, int levels);

}  // namespace strata
