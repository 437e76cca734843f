// Loads the embedded default skeleton, poses a small crowd and prints what it got; the install test checks it.
#include <cstdio>

#include <strata/io/hanim_loader.h>
#include <strata/systems/frame_script.h>

int main() {
  strata::HumanoidAsset asset = strata::load_default_humanoid();
  strata::Rig rig;
  rig.skeleton = asset.skeleton;
  rig.clips = asset.clips;
  strata::CrowdScene scene(rig);
  strata::CrowdConfig config;
  config.walkers = 4;
  scene.spawn_grid(config);
  strata::Profiler profiler;
  scene.simulate(1.0f / 30.0f, profiler);
  std::printf("consumer: %zu joints, %zu walkers, %zu systems timed\n", rig.skeleton.joint_count(),
              scene.walker_count(), profiler.stats().size());
  return rig.skeleton.joint_count() == 25 && scene.walker_count() == 4 ? 0 : 1;
}
