#include "systems/animation_sample.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

void animation_system(const Rig& rig, const WalkerLanes& lanes, float dt) {
  if (lanes.count == 0) return;
  const std::size_t joints = rig.skeleton.joint_count();
  const std::size_t stride = lanes.stride;
  auto run = [&](std::size_t first, std::size_t last) {
    std::vector<glm::quat> rotations(joints);
    float* time = lanes.clock;
    const float* rate = lanes.clock + stride;
    const float* clip_index = lanes.clock + 2 * stride;
    for (std::size_t i = first; i < last; ++i) {
      time[i] += dt * rate[i];
      glm::vec3 root(0.0f);
      std::fill(rotations.begin(), rotations.end(), glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
      const int c = static_cast<int>(clip_index[i]);
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
        lanes.local_rotation[(j * 4 + 0) * stride + i] = rotations[j].x;
        lanes.local_rotation[(j * 4 + 1) * stride + i] = rotations[j].y;
        lanes.local_rotation[(j * 4 + 2) * stride + i] = rotations[j].z;
        lanes.local_rotation[(j * 4 + 3) * stride + i] = rotations[j].w;
      }
      lanes.root_translation[0 * stride + i] = root.x;
      lanes.root_translation[1 * stride + i] = root.y;
      lanes.root_translation[2 * stride + i] = root.z;
    }
  };
  constexpr std::size_t kChunk = 256;
  if (lanes.count <= kChunk) {
    run(0, lanes.count);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lanes.count, kChunk),
                    [&](const tbb::blocked_range<std::size_t>& r) { run(r.begin(), r.end()); },
                    tbb::simple_partitioner());
}

}  // namespace strata
