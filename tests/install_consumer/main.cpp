// Loads the embedded default skeleton, poses a small crowd and prints what it got; the install test checks it.
// It also builds the shipped bottleneck's navigation mesh and finds a path out of the room: the nav headers must
// compile without Recast/Detour's (which libstrata links privately).
#include <cstdio>

#include <strata/io/hanim_loader.h>
#include <strata/io/scenario_file.h>
#include <strata/nav/navmesh.h>
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
  const auto mesh = strata::NavMesh::build(strata::shipped_scenario("bottleneck"), {}, /*use_cache=*/false);
  strata::NavQuery query(*mesh);
  const bool out = query.find_path({-5.0f, 0.0f}, {10.0f, 0.0f}).complete;
  std::printf("consumer: bottleneck %s\n", out ? "passable" : "blocked");
  return joints == 25 && scene.walker_count() == 4 && out ? 0 : 1;
}
