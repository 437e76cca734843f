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

// Walkers taller than level0_px on screen get level 0, taller than level1_px level 1, taller than impostor_px
// level 2, and shorter ones are impostors (when the crowd may have impostors, scene/crowd.h). A walker moves to a
// finer tier only once it is `hysteresis` times past the threshold, and to a coarser one only once it is that
// factor below it. The defaults keep level 0 for walkers taller than about a third of a 1080-pixel frame; below
// ~160 px level 1's 8,923 vertices are already finer than the pixels; below 100 px an impostor cell (128 px
// high, render/impostor_atlas.h) still has more texels than the walker has pixels.
//
// mesh_budget caps the walkers drawn as meshes in a frame: when more qualify, the nearest keep their mesh and the
// rest become impostors, so a frame's cost is bounded whatever the crowd (a walker already a mesh ranks as if
// `hysteresis` times nearer, so walkers near the cut do not trade places every frame). 0 = no cap. The default
// is what the 2-core llvmpipe machine draws at ~30 fps next to a thousand impostors (README, `report lod`).
struct LodPolicy {
  float level0_px = 360.0f;
  float level1_px = 160.0f;
  float impostor_px = 100.0f;
  float hysteresis = 1.15f;
  std::uint32_t mesh_budget = 24;
};

// The decision "impostor" in lod_decide and the previous level of a walker that was one.
inline constexpr int kLodImpostor = 3;

// The level-of-detail job over one walker table (ozz-style: inputs and outputs are public members, validate()
// then run()). The table a walker sits in is its previous decision (scene/crowd.h: DetailSlot), so one job runs
// per table with that table's `previous_level`.
//
// Reads: placement (5 components: x, y, z, heading, scale) and root translation (3: the HumanoidRoot's offset in
// humanoid space, which with the rig's rest root centre places the body) of `walkers` rows, `stride` apart; both
// exist in every walker table, including the narrow impostor table, and are written by every motion system before
// the frame's lod stage reads them. Writes: decided[w], the slot index the walker is skinned from this frame: its
// mesh level 0..levels-1, `impostor_slot`, or `culled_slot` when the camera does not see it; and distance[w], its
// bounding sphere's centre's distance from the eye (m), which the mesh budget ranks.
struct LodJob {
  const LodView* view = nullptr;
  const LodPolicy* policy = nullptr;
  float body_height = 1.75f;  // the rig's rest height (m); a walker's is that times its scale
  glm::vec3 root_center{0.0f, 1.0f, 0.0f};  // the rig's rest HumanoidRoot centre, humanoid space
  int previous_level = -1;    // the mesh level the table holds, kLodImpostor, or -1 (culled or never decided)
  int fixed_level = -1;       // >= 0: every visible walker gets this level (a mesh level or kLodImpostor); -1: the
                              // automatic policy
  int levels = 1;             // mesh levels the body has (1..3)
  bool impostors = false;     // may the automatic policy choose impostors (scene/crowd.h: walking crowds)
  std::uint8_t culled_slot = 4;    // the value written for a culled walker (the caller's culled table)
  std::uint8_t impostor_slot = 6;  // the value written for an impostor (the caller's impostor table)
  std::size_t walkers = 0;
  std::size_t stride = 0;
  const float* placement = nullptr;
  const float* root_translation = nullptr;
  std::span<std::uint8_t> decided;
  std::span<float> distance;

  // Every pointer set for a non-empty table, stride >= walkers, decided.size() == distance.size() == walkers,
  // levels in 1..3, fixed_level < levels or kLodImpostor, body_height finite and positive. No side effects.
  bool validate() const;
  // validate(), then decide every walker; false (writing nothing) when invalid.
  bool run() const;
};

// `previous` of a walker that has no level to keep (culled, or never decided): its decision is the plain one.
inline constexpr int kLodNoPrevious = -1;

// The decision for one walker given its bounding sphere (world), and its previous level (kLodNoPrevious at
// first): a mesh level, kLodImpostor, or -1 when the camera does not see it.
int lod_decide(const LodView& view, const LodPolicy& policy, const glm::vec3& center, float radius, float height,
               int previous, int fixed_level, int levels, bool impostors = false);

}  // namespace strata
