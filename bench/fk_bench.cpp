// Google Benchmark: the FK system's throughput in joints per second over crowds of the shipped skeleton.
#include <benchmark/benchmark.h>

#include <random>

#include <glm/gtc/quaternion.hpp>
#include <tbb/global_control.h>

#include "io/hanim_loader.h"
#include "systems/animation_sample.h"
#include "systems/fk.h"
#include "scene/crowd_scene.h"

namespace {

strata::CrowdScene make_scene(std::size_t walkers) {
  strata::CrowdScene scene(strata::to_rig(strata::load_default_humanoid()));
  strata::CrowdConfig config;
  config.motion = strata::MotionSource::Clip;
  config.walkers = walkers;
  scene.spawn_crowd(config);
  strata::Profiler profiler(120, false);
  scene.simulate(0.5f, profiler);  // a non-rest pose
  return scene;
}

void BM_FkSingleThread(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  strata::CrowdScene scene = make_scene(static_cast<std::size_t>(state.range(0)));
  strata::WalkerLanes lanes = scene.lanes();
  const strata::FkJob job = strata::make_fk_job(scene.rig().skeleton, scene.walkers());
  for (auto _ : state) {
    if (!job.run()) state.SkipWithError("invalid FkJob");
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(lanes.count * lanes.joints));
  state.counters["walkers"] = static_cast<double>(lanes.count);
}
BENCHMARK(BM_FkSingleThread)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);

void BM_AnimationSample(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  strata::CrowdScene scene = make_scene(static_cast<std::size_t>(state.range(0)));
  strata::WalkerLanes lanes = scene.lanes();
  const strata::AnimationJob job = strata::make_animation_job(scene.rig(), scene.walkers(), 1.0f / 60.0f);
  for (auto _ : state) {
    if (!job.run()) state.SkipWithError("invalid AnimationJob");
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(lanes.count * lanes.joints));
}
BENCHMARK(BM_AnimationSample)->Arg(1000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
