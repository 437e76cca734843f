// Google Benchmark: the skinning kernel (SoA, grouped by influence set, vectorised) against a baseline written
// the way common engines do it — per vertex, array-of-structures input, a full 4x4 matrix blended per influence
// — on the same shipped-body level and pose, in one run. Items are vertices (positions and normals).
#include <benchmark/benchmark.h>

#include <algorithm>

#include <glm/mat4x4.hpp>
#include <tbb/global_control.h>

#include "components/skin_layout.h"
#include "io/hanim_loader.h"
#include "rig/body_rig.h"
#include "rig/muscle_binding.h"
#include "scene/crowd.h"
#include "systems/skin_kernel.h"
#include "reference/skin_reference.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"

namespace {

using namespace strata;

struct Fixture {
  Rig rig;
  std::unique_ptr<Crowd> scene;
  std::vector<glm::mat4> matrices;  // the walker's skinning matrices, for the baseline
  explicit Fixture(int level, bool muscles = false) {
    rig = to_rig(load_default_humanoid());
    rig.body = default_bound_body();
    if (muscles) rig.muscles = default_muscle_rig();
    scene = std::make_unique<Crowd>(rig);
    CrowdConfig config;
    config.walkers = 1;
    config.motion = MotionSource::Walk;
    spawn_crowd(*scene, config);
    set_detail_level(*scene, DetailLevel::mesh(level));
    Profiler profiler(8, false);
    for (int f = 0; f < 10; ++f) step(*scene, 1.0f / 30.0f, profiler);
    matrices = walker_skinning_matrices(scene->lanes(), 0);
  }
};

// Times SkinWalkerJob on walker 0; items are vertices.
void time_kernel(benchmark::State& state, const SkinLayout& layout, const SoaTable& walkers) {
  const std::size_t padded = pad_to_lanes(layout.vertex_count);
  AlignedBuffer<float> out(6 * padded);
  const SkinOutput soa = skin_output_in(out.data(), padded);
  const SkinWalkerJob job = make_skin_walker_job(layout, walkers, 0, soa);
  for (auto _ : state) {
    if (!job.run()) state.SkipWithError("invalid SkinWalkerJob");
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(layout.vertex_count));
}

// Args: level, muscles (0: linear blend skinning only; 1: with the default muscle layer's displacement, the
// walker's force factors taken from a walking frame).
void BM_SkinKernel(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  Fixture f(static_cast<int>(state.range(0)), state.range(1) != 0);
  const SkinLayout& layout = current_layout(*f.scene);
  time_kernel(state, layout, f.scene->table(initial_slot(*f.scene)));
}
BENCHMARK(BM_SkinKernel)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->ArgNames({"level", "muscles"})
    ->Unit(benchmark::kMicrosecond);

// The same kernel forced onto its portable (SSE2) body, level 0, for the SIMD width's share of the speed.
void BM_SkinKernelPortable(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  Fixture f(0, state.range(0) != 0);
  force_skin_kernel_isa(SkinKernelIsa::Portable);
  time_kernel(state, current_layout(*f.scene), f.scene->table(initial_slot(*f.scene)));
  force_skin_kernel_isa(SkinKernelIsa::Auto);
}
BENCHMARK(BM_SkinKernelPortable)->ArgName("muscles")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The baseline: AoS vertices with up to four (joint, weight) pairs each, blending 4x4 matrices per vertex.
struct AosVertex {
  glm::vec3 position, normal;
  std::array<std::int16_t, 4> joints;
  std::array<float, 4> weights;
};

void BM_SkinBaselineAos4x4(benchmark::State& state) {
  Fixture f(static_cast<int>(state.range(0)));
  const BodyLevel& level = f.rig.body->levels[static_cast<std::size_t>(state.range(0))];
  std::vector<AosVertex> in(level.mesh.vertex_count());
  for (std::size_t v = 0; v < in.size(); ++v)
    in[v] = {level.mesh.positions[v], level.mesh.normals[v], level.binding.joints[v], level.binding.weights[v]};
  std::vector<glm::vec3> pos(in.size()), nrm(in.size());
  for (auto _ : state) {
    for (std::size_t v = 0; v < in.size(); ++v) {
      glm::mat4 m(0.0f);
      for (int k = 0; k < 4; ++k)
        if (in[v].weights[k] > 0.0f) m += in[v].weights[k] * f.matrices[static_cast<std::size_t>(in[v].joints[k])];
      pos[v] = glm::vec3(m * glm::vec4(in[v].position, 1.0f));
      nrm[v] = glm::normalize(glm::vec3(m * glm::vec4(in[v].normal, 0.0f)));
    }
    benchmark::DoNotOptimize(pos.data());
    benchmark::DoNotOptimize(nrm.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(in.size()));
}
BENCHMARK(BM_SkinBaselineAos4x4)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

// The same kernel on a level whose every vertex has exactly `influences` joints (the level's own weights replaced
// by an even split over its first joint and its parents), to separate 1-, 2- and 4-influence throughput from the
// level's natural mix.
void BM_SkinKernelUniformInfluences(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  Fixture f(0);
  BodyLevel level = f.rig.body->levels[0];
  const int k = static_cast<int>(state.range(0));
  const Skeleton& s = f.rig.skeleton;
  for (std::size_t v = 0; v < level.mesh.vertex_count(); ++v) {
    std::int16_t j = level.binding.joints[v][0];
    level.binding.joints[v] = {0, 0, 0, 0};
    level.binding.weights[v] = {0.0f, 0.0f, 0.0f, 0.0f};
    for (int i = 0; i < k; ++i) {
      level.binding.joints[v][i] = j;
      level.binding.weights[v][i] = 1.0f / static_cast<float>(k);
      j = static_cast<std::int16_t>(std::max(s.parents[static_cast<std::size_t>(j)], 0));
    }
  }
  const SkinLayout layout = make_skin_layout(level);
  time_kernel(state, layout, f.scene->table(initial_slot(*f.scene)));
}
BENCHMARK(BM_SkinKernelUniformInfluences)->Arg(1)->Arg(2)->Arg(4)->Unit(benchmark::kMicrosecond);

// Memory-bandwidth ceiling for context: a streaming copy of 256 MB, counted as bytes read + written.
void BM_MemoryCopyBandwidth(benchmark::State& state) {
  const std::size_t n = std::size_t{64} << 20;  // floats: 256 MB
  std::vector<float> a(n, 1.0f), b(n, 0.0f);
  for (auto _ : state) {
    std::copy(a.begin(), a.end(), b.begin());
    benchmark::DoNotOptimize(b.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<long>(2 * n * sizeof(float)));
}
BENCHMARK(BM_MemoryCopyBandwidth)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
