#pragma once
// AnimationClip: keyframed joint motion, e.g. the H-Anim interpolators of an X3D file (one clip per TimeSensor).
// Immutable shared data like the Skeleton it animates; systems/animation_sample.h samples it per walker.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

namespace strata {

// Rotation keys of one joint: times in seconds (strictly increasing, within [0, duration]), unit quaternions.
// Sampled with slerp along the shorter arc (an X3D OrientationInterpolator's behaviour).
struct RotationTrack {
  std::int32_t joint = -1;
  std::vector<float> times;
  std::vector<glm::quat> values;
};

// Translation keys of one joint (in practice HumanoidRoot), metres, sampled linearly.
struct TranslationTrack {
  std::int32_t joint = -1;
  std::vector<float> times;
  std::vector<glm::vec3> values;
};

struct AnimationClip {
  std::string name;          // the TimeSensor's DEF (or a generated name)
  float duration = 0.0f;     // seconds (X3D cycleInterval)
  bool loop = true;
  std::vector<RotationTrack> rotations;
  std::vector<TranslationTrack> translations;

  std::size_t channel_count() const { return rotations.size() + translations.size(); }
};

}  // namespace strata
