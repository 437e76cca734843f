#pragma once
// Animation system: advances each walker's clock and samples its keyframed clip (X3D interpolators) into the
// walker's local joint rotations and root translation. Runs first in the frame script; FK reads what it writes.
//
//   reads:  rig (skeleton joint count, clips), clip (I32), rate (clock component 1), dt
//   writes: time (clock component 0, advanced and wrapped), local_rotation (joints*4), root_translation (3)
#include <cstdint>
#include <span>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "components/animation_clip.h"
#include "components/rig.h"
#include "ecs/column_view.h"
#include "systems/job.h"

namespace strata {

// Walker clip selectors besides a clip index (the walker's clip field).
inline constexpr int kRestPose = -1;  // hold the rest pose
inline constexpr int kAllClips = -2;  // play every clip of the rig at once, each on its own cycle: what an X3D
                                      // browser shows, since all of a scene's TimeSensors run together

// Samples `clip` at `time` seconds (wrapped into [0, duration) for looping clips, clamped otherwise).
// Joints without a track get identity; the root translation is zero without a HumanoidRoot translation track.
// Rotation keys are slerped along the shorter arc, translations interpolated linearly.
void sample_clip(const AnimationClip& clip, float time, std::span<glm::quat> rotations, glm::vec3& root_translation);
// As sample_clip, but writes only the joints `clip` has tracks for, leaving the others as they are; layering
// several clips this way lets a later clip override an earlier one where both drive a joint.
void apply_clip(const AnimationClip& clip, float time, std::span<glm::quat> rotations, glm::vec3& root_translation);

// For every walker: time += dt * rate, then sample its clip (a clip index, kAllClips, or kRestPose; an index the
// rig lacks gives the rest pose). Walkers are independent, so this runs in parallel chunks.
struct AnimationJob {
  const Rig* rig = nullptr;               // skeleton (joint count) and clips
  float dt = 0.0f;                        // seconds to advance
  ColumnView<const std::int32_t> clip;    // 1: clip selector per walker
  ColumnView<const float> rate;           // 1: playback rate (1 = real time)
  ColumnView<float> time;                 // 1: animation time (s), read and advanced
  ColumnView<float> local_rotation;       // joints*4: quaternion x, y, z, w per joint
  ColumnView<float> root_translation;     // 3: HumanoidRoot translation (m)

  // Rig set with joints; every view with the same rows and its width; dt finite; outputs not overlapping each
  // other or an input.
  bool validate() const;
  bool run() const;
};

// The job over every walker of `walkers` (a walker table, components/walker.h).
AnimationJob make_animation_job(const Rig& rig, SoaTable& walkers, float dt);

}  // namespace strata
