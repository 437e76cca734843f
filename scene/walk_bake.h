#pragma once
// Baking the walk generator into a keyframed clip: one walker of a rig is driven by the real frame script
// (Crowd with MotionSource::Walk: locomotion -> IK -> FK, systems/frame_script.h) and every joint's local
// rotation plus the root's motion is sampled at a fixed rate. The result is an ordinary AnimationClip in H-Anim
// terms, so anything that plays clips (the animation system, the glTF writer io/gltf_export.h) can replay it.
//
// The walker's placement (its position on the ground and its heading, components/walker.h Placement) is folded
// into the root: with P the placement made relative to the walker's start (so the clip starts at the origin,
// facing +Z, as glTF assets are expected to), the clip's root rotation is Ry(heading) * R_root and its root
// translation is t' = P(t + c_root) - c_root, so that T(t' + c_root) R' T(-c_root) = P T(t + c_root) R T(-c_root):
// the clip posed by FK at placement identity gives exactly the walker's world pose, moved to start at the origin.
// A clip cannot carry a scale, so the walker is given the rig's own stature (placement scale exactly 1).
// The muscle layer is not part of a clip (it is a deformation, not a joint motion) and is not run.
#include <cstdint>

#include <glm/vec3.hpp>

#include "components/animation_clip.h"
#include "components/rig.h"

namespace strata {

struct WalkBakeOptions {
  float seconds = 2.0f;     // clip length; the last key is at exactly this time
  float fps = 30.0f;        // keys per second (the frame script's dt = 1 / fps)
  std::uint64_t seed = 1;   // CrowdConfig::seed: the walker's gait phase, lane speed and start on the track
};

struct BakedWalk {
  AnimationClip clip;              // rotation tracks for every joint, one HumanoidRoot translation track
  glm::vec3 start_position{0.0f};  // the walker's placement at t = 0 in the scene, which the clip is relative to
  float start_heading = 0.0f;      // radians about +Y
};

// Throws std::invalid_argument when the rig cannot walk (Crowd::walk_unavailable), or seconds or fps are not
// positive and finite, or more than 100,000 keys would be needed.
BakedWalk bake_walk(const Rig& rig, const WalkBakeOptions& options = {});

}  // namespace strata
