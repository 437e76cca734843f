#pragma once
// step(): one frame of a crowd, the fixed-order script every command runs (crowd, view, bench, soak, export, the
// reports), each stage timed into the profiler and into the FrameProfile it returns (Box2D's b2Profile).
//
//   stage       system                   reads -> writes                                              when
//   locomotion  systems/locomotion.h     path, cadence, footprints -> placement, pelvis, IK goals     walk
//   animation   systems/animation_sample clock + keyframed clip -> local rotations, root translation  clip
//   mocap       systems/mocap_drive.h    retargeted capture -> rotations, root motion, foot-lock goals mocap
//   ik          systems/ik.h             IK goals -> arm and leg joint rotations                      walk, mocap
//   fk          systems/fk.h             local rotations -> world F(j) and skinning F(j) A(j)^-1      always
//   muscle      systems/muscle.h         skinning matrices -> control points, force factors           muscles on
//   lod         systems/lod.h            the camera of the last render_frame, walker bounds -> the    a body
//                                        table (DetailSlot) each walker is skinned from; moves walkers
//   skin        systems/skin.h           per mesh-level table: layout + matrices (+ muscles) ->       mesh levels
//                                        that table's skinned vertices
//   subdiv      systems/subdiv.h         the cage skinned (+ muscle-displaced) and Loop-refined       S1..S3
//
// Stages run over every walker table in slot order; within a stage, walkers run in parallel (oneTBB) and each
// writes only its own row, so the result is the same for any thread count.
#include <array>
#include <cstddef>
#include <cstdint>

#include "profiling/profiler.h"
#include "scene/crowd.h"

namespace strata {

enum class Stage : std::uint8_t { Locomotion, Animation, Mocap, Ik, Fk, Muscle, Lod, Skin, Subdiv };
inline constexpr std::size_t kStageCount = 9;
// The stage's name in the profiler, the Chrome trace and every JSON that reports per-system times.
const char* stage_name(Stage stage);

// What one step cost and did. Stages that did not run read 0 ms and ran = false.
struct FrameProfile {
  std::array<double, kStageCount> ms{};
  std::array<bool, kStageCount> ran{};
  double total_ms = 0.0;
  // Walkers skinned at mesh levels 0, 1, 2 (S levels count as 0), and culled.
  std::array<std::size_t, 4> walkers_per_level{};
  std::size_t moved = 0;  // walkers that changed tables in the lod stage

  double stage_ms(Stage s) const { return ms[static_cast<std::size_t>(s)]; }
};

// Advances every walker of `crowd` by `dt` seconds. Throws std::invalid_argument before touching anything when
// dt is not finite or negative.
FrameProfile step(Crowd& crowd, float dt, Profiler& profiler);

}  // namespace strata
