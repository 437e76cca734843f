#pragma once
// The seam between a crowd and the renderer, and the render half of every command's frame:
//
//   step(crowd, dt, profiler)                 scene/step.h: simulate, choose levels, skin
//   render_frame(crowd, renderer, camera...)  here: draw what step() left, hand the camera to the next step()
//
// Every command that draws calls exactly these two per frame (crowd, view, soak --render, bench --render and the
// muscle report's figure); bench and soak without rendering hand a camera over with set_crowd_camera(), so
// culling and levels of detail run in every command's frame.
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include <glm/vec3.hpp>

#include "render/camera.h"
#include "render/crowd_renderer.h"
#include "rig/surface_material.h"
#include "scene/crowd.h"

namespace strata {

// What the body pass draws from the crowd's last step(): one input per table skinned (several under
// DetailLevel::automatic), in slot order; empty when the crowd has no body to draw.
std::vector<BodyDrawInput> body_draw_inputs(const Crowd& crowd);
struct RenderScratch;
// The same with what RenderQuality::High colours bodies by: walker keys and surface classes, kept in `scratch`.
std::vector<BodyDrawInput> body_draw_inputs(const Crowd& crowd, RenderScratch& scratch);
// The crowd's impostors as the body pass draws them (no walkers until the crowd has an atlas:
// render/impostor_bake.h ensure_impostor_atlas, which render_frame calls).
// `standing_phase`: where a scenario's agents stand (kGaitIdle), their impostors show the walk's phase with the feet
// passing each other (0.3: the right foot beside the left) in a copy kept there, instead of the phase they
// stopped at (a stride apart). Null: the phase column as it is.
// `walker_keys`: filled with each impostor's appearance key (its entity slot) and handed to the batch; null: none.
ImpostorBatch impostor_batch(const Crowd& crowd, std::vector<float>* standing_phase = nullptr,
                             std::vector<std::uint32_t>* walker_keys = nullptr);
// Bounds of every skinned vertex drawn and of every impostor (its feet up to its stature); false when none.
bool body_bounds(const Crowd& crowd, glm::vec3& lo, glm::vec3& hi);
// Every posed walker's world-space joint positions, walker-major, table by table (the skeleton pass's input and
// what a camera frames when there are no bodies); impostors have no pose and culled walkers are not drawn: none,
// unless `include_culled` (the viewer framing the whole crowd; a walking crowd's culled walkers hold the pose they
// had when last seen). Resizes `out` (grown, never shrunk in capacity); returns the walkers gathered.
std::size_t gather_crowd_joints(const Crowd& crowd, std::vector<glm::vec3>& out, bool include_culled = false);
// The level-of-detail view (culling, projected sizes) of a camera rendering `viewport_height` pixels high.
LodView lod_view(const OrbitCamera& camera, float aspect, int viewport_height);
// Hands `camera` to the crowd's level-of-detail stage: from the next step() on, walkers it does not see are
// culled and DetailLevel::automatic picks by size.
void set_crowd_camera(Crowd& crowd, const OrbitCamera& camera, float aspect, int viewport_height);

// Frames `camera` on the crowd as its last step() left it: the skinned bodies' bounds, else the joints' (a rig
// without a body), tightly (OrbitCamera::frame_box_tight). False, camera untouched, when there is nothing to frame.
struct RenderScratch;
bool frame_crowd(const Crowd& crowd, OrbitCamera& camera, float aspect, RenderScratch& scratch);
// The box frame_crowd frames: false when there is nothing to frame.
bool crowd_frame_bounds(const Crowd& crowd, RenderScratch& scratch, glm::vec3& lo, glm::vec3& hi);

// Per-frame scratch a command keeps between frames, so render_frame allocates nothing in steady state.
struct RenderScratch {
  // RenderQuality::High's inputs per body slot: each walker's appearance key (its entity slot), and the surface
  // class and ambient occlusion of each vertex, recomputed only when the slot's mesh or vertex order changes.
  std::array<std::vector<std::uint32_t>, kDetailSlots> walker_keys;
  std::array<SurfaceClasses, kDetailSlots> materials;
  std::array<std::vector<float>, kDetailSlots> occlusion;  // ambient occlusion per vertex (rig/vertex_occlusion.h)
  std::array<std::uint64_t, kDetailSlots> materials_of{};  // a key of what `materials` was computed for
  std::vector<glm::vec3> joints;
  std::vector<glm::vec3> impostor_feet;
  std::vector<glm::vec3> shared_ground;  // the corners RenderFrameOptions::share_bounds returned: ground
  std::vector<glm::vec3> shared_joints;  // and joints
  std::vector<float> impostor_phase;
  std::vector<std::uint32_t> impostor_keys;
  std::vector<BodyBatch> batches;
};

struct RenderFrameOptions {
  bool skeleton_overlay = false;  // bones and joints over the bodies (always drawn when the level is none)
  // Called with the body inputs before they are drawn (the binding editor tints weights this way).
  std::function<void(std::vector<BodyDrawInput>&)> recolour;
  // A crowd spread over processes (dist/): called with the corners of a box of this process's (lo > hi when it
  // has nothing) and returning every process's; twice a frame: the joints' box, which the sun's shadow frustum is
  // fitted to, then the box of the joints and impostors' feet, which the ground is fitted to. So each process
  // draws the same ground and shadow map as one process drawing the whole crowd.
  std::function<void(glm::vec3& lo, glm::vec3& hi)> share_bounds;
};

// Draws the crowd's last step from `camera` into `renderer`'s target (aspect = width / height of the target,
// viewport_height its pixel height), then set_crowd_camera(). Returns the body triangles drawn.
std::size_t render_frame(Crowd& crowd, CrowdRenderer& renderer, const OrbitCamera& camera, float aspect,
                         int viewport_height, RenderScratch& scratch, const RenderFrameOptions& options = {});

}  // namespace strata
