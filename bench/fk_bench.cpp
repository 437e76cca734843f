// Google Benchmark: the FK system's throughput in joints per second over crowds of the shipped skeleton.
#include <memory>
#include <benchmark/benchmark.h>

#include <random>

#include <glm/gtc/quaternion.hpp>
#include <tbb/global_control.h>

#include "io/hanim_loader.h"
#include "systems/animation_sample.h"
#include "systems/fk.h"
#include "scene/crowd.h"
#include "scene/spawn.h"
#include "scene/body_settings.h"
#include "scene/step.h"

namespace {

std::unique_ptr<strata::Crowd> make_scene(std::size_t walkers) {
  auto crowd = std::make_unique<strata::Crowd>(strata::to_rig(strata::load_default_humanoid()));
  strata::Crowd& scene = *crowd;
  strata::CrowdConfig config;
  config.motion = strata::MotionSource::Clip;
  config.walkers = walkers;
  spawn_crowd(scene, config);
  strata::Profiler profiler(120, false);
  step(scene, 0.5f, profiler);  // a non-rest pose
  return crowd;
}

void BM_FkSingleThread(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  std::unique_ptr<strata::Crowd> crowd = make_scene(static_cast<std::size_t>(state.range(0)));
  strata::Crowd& scene = *crowd;
  strata::WalkerLanes lanes = scene.lanes();
  const strata::FkJob job = strata::make_fk_job(scene.rig().skeleton, scene.table(initial_slot(scene)));
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
  std::unique_ptr<strata::Crowd> crowd = make_scene(static_cast<std::size_t>(state.range(0)));
  strata::Crowd& scene = *crowd;
  strata::WalkerLanes lanes = scene.lanes();
  const strata::AnimationJob job = strata::make_animation_job(scene.rig(), scene.table(initial_slot(scene)), 1.0f / 60.0f);
  for (auto _ : state) {
    if (!job.run()) state.SkipWithError("invalid AnimationJob");
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(lanes.count * lanes.joints));
}
BENCHMARK(BM_AnimationSample)->Arg(1000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
