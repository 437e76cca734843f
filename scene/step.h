#pragma once
// step(): one frame of a crowd, the fixed-order script every command runs (crowd, view, bench, soak, export, the
// reports), each stage timed into the profiler and into the FrameProfile it returns (Box2D's b2Profile).
//
//   stage       system                   reads -> writes                                              when
//   lod         systems/lod.h            the camera of the last render_frame, placements -> the table  a body
//                                        (DetailSlot) each walker is simulated and skinned from, the
//                                        mesh budget; moves walkers; restarts the walk of walkers
//                                        leaving a light table (impostors, culled walkers of a walk)
//   navigation  systems/navigation.h     goals, navigation mesh -> preferred velocities, a few paths   scenario
//   avoidance   systems/avoidance.h,     every agent's preferred velocity -> collision-free velocity;  scenario
//               systems/agent_move.h     turned, limited and integrated into agent positions
//   locomotion  systems/locomotion.h     path (or agent), cadence, footprints -> placement, pelvis,   walk
//                                        IK goals
//                                        (light tables: the gait clock and placement only)
//   animation   systems/animation_sample clock + keyframed clip -> local rotations, root translation  clip
//   mocap       systems/mocap_drive.h    retargeted capture -> rotations, root motion, foot-lock goals mocap
//   ik          systems/ik.h             IK goals -> arm and leg joint rotations                      walk, mocap
//   fk          systems/fk.h             local rotations -> world F(j) and skinning F(j) A(j)^-1      always
//   muscle      systems/muscle.h         skinning matrices -> control points, force factors           muscles on
//   skin        systems/skin.h           per mesh-level table: layout + matrices (+ muscles) ->       mesh levels
//                                        that table's skinned vertices
//   subdiv      systems/subdiv.h         the cage skinned (+ muscle-displaced) and Loop-refined       S1..S3
//
// ik, fk, muscle (and animation, mocap) skip the light tables (slot_is_light, scene/crowd.h): simulation level
// of detail. Impostors are not skinned; the renderer draws them from the rig's atlas (render/impostor_atlas.h).
// Stages run over every walker table in slot order; within a stage, walkers run in parallel (oneTBB) and each
// writes only its own row, so the result is the same for any thread count.
#include <array>
#include <cstddef>
#include <cstdint>

#include "profiling/profiler.h"
#include "scene/crowd.h"

namespace strata {

enum class Stage : std::uint8_t { Locomotion, Animation, Mocap, Ik, Fk, Muscle, Lod, Skin, Subdiv, Navigation, Avoidance };
inline constexpr std::size_t kStageCount = 11;
// The stage's name in the profiler, the Chrome trace and every JSON that reports per-system times.
const char* stage_name(Stage stage);

// What one step cost and did. Stages that did not run read 0 ms and ran = false.
struct FrameProfile {
  std::array<double, kStageCount> ms{};
  std::array<bool, kStageCount> ran{};
  double total_ms = 0.0;
  // Walkers skinned at mesh levels 0, 1, 2 (S levels count as 0), and culled.
  std::array<std::size_t, 4> walkers_per_level{};
  std::size_t impostors = 0;  // walkers drawn as impostors
  std::array<std::size_t, kDetailSlots> walkers_per_slot{};  // every table's walkers after the lod stage
  std::size_t moved = 0;  // walkers that changed tables in the lod stage

  double stage_ms(Stage s) const { return ms[static_cast<std::size_t>(s)]; }
};

// Advances every walker of `crowd` by `dt` seconds. Throws std::invalid_argument before touching anything when
// dt is not finite or negative.
FrameProfile step(Crowd& crowd, float dt, Profiler& profiler);

}  // namespace strata
