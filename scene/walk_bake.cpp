#include "scene/walk_bake.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/gtc/quaternion.hpp>

#include "profiling/profiler.h"
#include "scene/body_settings.h"
#include "scene/crowd.h"
#include "scene/spawn.h"
#include "scene/step.h"

namespace strata {
namespace {

glm::quat heading_rotation(float heading) { return glm::angleAxis(heading, glm::vec3(0.0f, 1.0f, 0.0f)); }

}  // namespace

BakedWalk bake_walk(const Rig& rig, const WalkBakeOptions& options) {
  if (!(options.seconds > 0.0f) || !std::isfinite(options.seconds) || !(options.fps > 0.0f) ||
      !std::isfinite(options.fps))
    throw std::invalid_argument("bake_walk: seconds and fps must be positive and finite");
  const double key_count = std::floor(static_cast<double>(options.seconds) * options.fps + 1e-3) + 2.0;
  if (key_count > 100'000.0) throw std::invalid_argument("bake_walk: more than 100,000 keys");

  // Only the joints are sampled: no body, so the skin system (and the muscle system, which needs a body) does not
  // run; the clips of the source rig would only confuse a reader of the scene.
  Rig skeleton_only;
  skeleton_only.name = rig.name;
  skeleton_only.skeleton = rig.skeleton;
  Crowd scene(std::move(skeleton_only));
  if (!scene.motion.walk_error.empty()) throw std::invalid_argument(scene.motion.walk_error);
  const Skeleton& skeleton = scene.rig().skeleton;

  CrowdConfig config;
  config.motion = MotionSource::Walk;
  config.walkers = 1;
  config.seed = options.seed;
  config.height_mean = scene.motion.locomotion->rig_height;  // placement scale = height / rig height = 1 exactly
  config.height_spread = 0.0f;
  spawn_crowd(scene, config);
  set_detail_level(scene, DetailLevel::none());

  const std::size_t joints = skeleton.joint_count();
  const glm::vec3 c_root = skeleton.centers[0];
  BakedWalk out;
  AnimationClip& clip = out.clip;
  clip.name = "walk";
  clip.loop = false;  // a walk along a path does not return to its start
  clip.rotations.resize(joints);
  for (std::size_t j = 0; j < joints; ++j) clip.rotations[j].joint = static_cast<std::int32_t>(j);
  clip.translations.resize(1);
  clip.translations[0].joint = 0;

  Profiler profiler(1, false);
  const float frame_dt = 1.0f / options.fps;
  const auto whole_steps = static_cast<std::size_t>(std::floor(static_cast<double>(options.seconds) * options.fps + 1e-3));
  float time = 0.0f;
  // Key 0 is the start state itself (dt = 0 settles IK and FK without advancing the gait), then whole frames of
  // the crowd's dt, then, when seconds is not a whole number of frames, one short step to land on it exactly.
  for (std::size_t k = 0;; ++k) {
    float dt = 0.0f;
    if (k > 0 && k <= whole_steps) {
      dt = frame_dt;
      time = static_cast<float>(static_cast<double>(k) / options.fps);
    } else if (k > whole_steps) {
      if (options.seconds - time <= 1e-4f * frame_dt) break;
      dt = options.seconds - time;
      time = options.seconds;
    }
    step(scene, dt, profiler);
    WalkerLanes lanes = scene.lanes();
    const Placement placement = placement_of(lanes, 0);
    const float heading = lanes.placement[3 * lanes.stride];
    if (std::abs(placement.scale - 1.0f) > 1e-6f)
      throw std::logic_error("bake_walk: walker scale " + std::to_string(placement.scale) + " is not 1");
    if (k == 0) {
      out.start_position = placement.position;
      out.start_heading = heading;
    }
    const float relative_heading = heading - out.start_heading;
    const glm::quat turn = heading_rotation(relative_heading);
    const glm::vec3 position = glm::inverse(heading_rotation(out.start_heading)) * (placement.position - out.start_position);

    for (std::size_t j = 0; j < joints; ++j) {
      const float* q = lanes.local_rotation + j * 4 * lanes.stride;
      glm::quat r(q[3 * lanes.stride], q[0], q[lanes.stride], q[2 * lanes.stride]);
      const float norm = glm::length(r);
      // FK accepts unnormalised quaternions (and maps zero to identity); a clip's keys must be unit.
      r = norm > 1e-12f ? r / norm : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
      if (j == 0) r = turn * r;
      RotationTrack& track = clip.rotations[j];
      // Keep consecutive keys in one hemisphere so that any slerp, shortest-arc or not, turns the short way.
      if (!track.values.empty() && glm::dot(track.values.back(), r) < 0.0f) r = -r;
      track.times.push_back(time);
      track.values.push_back(r);
    }
    const glm::vec3 t(lanes.root_translation[0], lanes.root_translation[lanes.stride],
                      lanes.root_translation[2 * lanes.stride]);
    clip.translations[0].times.push_back(time);
    clip.translations[0].values.push_back(position + turn * (t + c_root) - c_root);
    if (time >= options.seconds) break;
  }
  clip.duration = clip.translations[0].times.back();
  return out;
}

}  // namespace strata
