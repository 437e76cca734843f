#pragma once
// Animation system: advances each walker's clock and samples its keyframed clip (X3D interpolators) into the
// walker's local joint rotations and root translation. Runs first in the frame script; FK reads what it writes.
#include <span>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "components/animation_clip.h"
#include "components/rig.h"
#include "components/walker.h"

namespace strata {

// Walker clip selectors besides a clip index (the walker clock's third component).
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
void animation_system(const Rig& rig, const WalkerLanes& lanes, float dt);

}  // namespace strata
