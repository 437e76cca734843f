#include "systems/animation_sample.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "components/walker.h"

namespace strata {
namespace {

// Index k of the key interval [times[k], times[k+1]] holding t, and the blend factor within it.
std::pair<std::size_t, float> locate(const std::vector<float>& times, float t) {
  if (times.size() < 2 || t <= times.front()) return {0, 0.0f};
  if (t >= times.back()) return {times.size() - 1, 0.0f};
  auto upper = std::upper_bound(times.begin(), times.end(), t);
  std::size_t k = static_cast<std::size_t>(upper - times.begin()) - 1;
  float span = times[k + 1] - times[k];
  // Equal keys (a step in an X3D interpolator) have zero span: jump to the later value.
  float u = span > 0.0f ? (t - times[k]) / span : 1.0f;
  return {k, u};
}

glm::quat slerp_shortest(glm::quat a, glm::quat b, float u) {
  if (glm::dot(a, b) < 0.0f) b = -b;
  return glm::normalize(glm::slerp(a, b, u));
}

}  // namespace

void sample_clip(const AnimationClip& clip, float time, std::span<glm::quat> rotations, glm::vec3& root_translation) {
  std::fill(rotations.begin(), rotations.end(), glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  root_translation = glm::vec3(0.0f);
  apply_clip(clip, time, rotations, root_translation);
}

void apply_clip(const AnimationClip& clip, float time, std::span<glm::quat> rotations, glm::vec3& root_translation) {
  float t = time;
  if (!std::isfinite(t)) t = 0.0f;
  if (clip.duration > 0.0f) {
    if (clip.loop) {
      t = std::fmod(t, clip.duration);
      if (t < 0.0f) t += clip.duration;
    } else {
      t = std::clamp(t, 0.0f, clip.duration);
    }
  }
  for (const RotationTrack& track : clip.rotations) {
    if (track.joint < 0 || static_cast<std::size_t>(track.joint) >= rotations.size() || track.values.empty()) continue;
    auto [k, u] = locate(track.times, t);
    rotations[track.joint] = (k + 1 < track.values.size() && u > 0.0f)
                                 ? slerp_shortest(track.values[k], track.values[k + 1], u)
                                 : track.values[std::min(k, track.values.size() - 1)];
  }
  for (const TranslationTrack& track : clip.translations) {
    // Only the root's translation moves a humanoid in H-Anim; other joints' translation fields stay zero.
    if (track.joint != 0 || track.values.empty()) continue;
    auto [k, u] = locate(track.times, t);
    root_translation = (k + 1 < track.values.size()) ? glm::mix(track.values[k], track.values[k + 1], u)
                                                     : track.values[std::min(k, track.values.size() - 1)];
  }
}

bool AnimationJob::validate() const {
  if (!rig || !std::isfinite(dt)) return false;
  const auto joints = static_cast<std::uint32_t>(rig->skeleton.joint_count());
  const std::size_t n = clip.count;
  if (joints == 0 || joints > kMaxJointsPerRig || !clip.fits(n, 1) || !rate.fits(n, 1) || !time.fits(n, 1) || !local_rotation.fits(n, joints * 4) ||
      !root_translation.fits(n, 3))
    return false;
  return !time.overlaps(local_rotation) && !time.overlaps(root_translation) &&
         !local_rotation.overlaps(root_translation) && !time.overlaps(rate) && !time.overlaps(clip) &&
         !local_rotation.overlaps(rate) && !local_rotation.overlaps(clip) && !root_translation.overlaps(rate) &&
         !root_translation.overlaps(clip);
}

bool AnimationJob::run() const {
  if (!validate()) return false;
  const std::size_t count = clip.count;
  if (count == 0) return true;
  const Rig& rig = *this->rig;
  const float dt = this->dt;
  const std::size_t joints = rig.skeleton.joint_count();
  auto sample_range = [&](std::size_t first, std::size_t last) {
    // On the stack (8 KiB at the joint cap), not a vector per chunk: run() allocates nothing.
    glm::quat stack[kMaxJointsPerRig];
    const std::span<glm::quat> rotations(stack, joints);
    float* time = this->time.base;
    const float* rate = this->rate.base;
    const std::int32_t* clip_index = this->clip.base;
    for (std::size_t i = first; i < last; ++i) {
      time[i] += dt * rate[i];
      glm::vec3 root(0.0f);
      std::fill(rotations.begin(), rotations.end(), glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
      const int c = clip_index[i];
      if (c >= 0 && static_cast<std::size_t>(c) < rig.clips.size()) {
        const AnimationClip& clip = rig.clips[c];
        // Keep the clock inside one cycle so float time never loses precision in long runs.
        if (clip.loop && clip.duration > 0.0f && time[i] >= clip.duration) time[i] = std::fmod(time[i], clip.duration);
        apply_clip(clip, time[i], rotations, root);
      } else if (c == kAllClips) {
        // Clips of different lengths share one clock, so it cannot be wrapped to a common cycle; it is left to
        // grow (float seconds keep millisecond resolution for about 2 hours of playback).
        for (const AnimationClip& clip : rig.clips) apply_clip(clip, time[i], rotations, root);
      }
      for (std::size_t j = 0; j < joints; ++j) {
        const auto q = static_cast<std::uint32_t>(j * 4);
        local_rotation.at(q + 0, i) = rotations[j].x;
        local_rotation.at(q + 1, i) = rotations[j].y;
        local_rotation.at(q + 2, i) = rotations[j].z;
        local_rotation.at(q + 3, i) = rotations[j].w;
      }
      root_translation.at(0, i) = root.x;
      root_translation.at(1, i) = root.y;
      root_translation.at(2, i) = root.z;
    }
  };
  constexpr std::size_t kChunk = 256;
  if (count <= kChunk) {
    sample_range(0, count);
    return true;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kChunk),
                    [&](const tbb::blocked_range<std::size_t>& r) { sample_range(r.begin(), r.end()); },
                    tbb::simple_partitioner());
  return true;
}

AnimationJob make_animation_job(const Rig& rig, SoaTable& walkers, float dt) {
  const ColumnView<float> clock = f32_view(walkers, kWalkerClock);
  return {&rig, dt, i32_view(std::as_const(walkers), kWalkerClip), clock.columns(1, 1), clock.columns(0, 1),
          f32_view(walkers, kWalkerLocalRotation), f32_view(walkers, kWalkerRootTranslation)};
}

}  // namespace strata
