// Loads the embedded default skeleton, poses a small crowd and prints what it got; the install test checks it.
#include <cstdio>

#include <strata/io/hanim_loader.h>
#include <strata/scene/spawn.h>
#include <strata/scene/step.h>

int main() {
  strata::Crowd scene(strata::to_rig(strata::load_default_humanoid()));
  strata::CrowdConfig config;
  config.walkers = 4;
  strata::spawn_crowd(scene, config);
  strata::Profiler profiler;
  strata::step(scene, 1.0f / 30.0f, profiler);
  const std::size_t joints = scene.rig().skeleton.joint_count();
  std::printf("consumer: %zu joints, %zu walkers, %zu systems timed\n", joints, scene.walker_count(),
              profiler.stats().size());
  return joints == 25 && scene.walker_count() == 4 ? 0 : 1;
}
