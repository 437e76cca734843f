// Google Benchmark: the skinning kernel (SoA, grouped by influence set, vectorised) in each skinning mode (linear
// blend, dual quaternions, centres of rotation) against two baselines written the way common engines do it, on
// the same shipped-body level and pose, in one run. Items are vertices (positions and normals).
//   BM_SkinBaselineAos4x4  per vertex, array-of-structures input, a full glm 4x4 matrix blended per influence.
//   BM_SkinBaselineOzzStyle the shape of ozz-animation's SkinningJob (written here from its description, not its
//                           code): vertices partitioned by influence count, each partition a loop over vertices
//                           that looks up its joints' 4x4 matrices and blends them with 4-wide SIMD across matrix
//                           columns (the last weight is 1 - the others), then transforms position and normal; no
//                           normal renormalisation. Built twice: for the baseline ISA (SSE2, ozz's default build)
//                           and for x86-64-v3 (AVX2 + FMA, ozz built for AVX2).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <immintrin.h>

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
void time_kernel(benchmark::State& state, const SkinLayout& layout, const SoaTable& walkers,
                 SkinningMode mode = SkinningMode::Linear) {
  const std::size_t padded = pad_to_lanes(layout.vertex_count);
  AlignedBuffer<float> out(6 * padded);
  const SkinOutput soa = skin_output_in(out.data(), padded);
  const SkinWalkerJob job = make_skin_walker_job(layout, walkers, 0, soa, mode);
  for (auto _ : state) {
    if (!job.run()) state.SkipWithError("invalid SkinWalkerJob");
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(layout.vertex_count));
}

// Args: level, muscles (0: skinning only; 1: with the default muscle layer's displacement, the walker's force
// factors taken from a walking frame), mode (0 lbs, 1 dqs, 2 cor). Google Benchmark runs the argument
// combinations one after another; for ratios between modes, run with --benchmark_repetitions and compare
// within that run (the cost ratio the issue asks for is also measured interleaved by `strata report skin`).
void BM_SkinKernel(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  Fixture f(static_cast<int>(state.range(0)), state.range(1) != 0);
  const SkinningMode mode = kSkinningModes[static_cast<std::size_t>(state.range(2))];
  set_skinning_mode(*f.scene, mode);
  const SkinLayout& layout = current_layout(*f.scene);
  time_kernel(state, layout, f.scene->table(initial_slot(*f.scene)), mode);
}
BENCHMARK(BM_SkinKernel)
    ->ArgsProduct({{0, 1, 2}, {0, 1}, {0, 1, 2}})
    ->ArgNames({"level", "muscles", "mode"})
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

// The kernel forced onto its AVX2 + FMA body, level 0, no muscles, per mode: on an AVX-512 CPU (where
// BM_SkinKernel runs the AVX-512 body) the like-for-like comparison with the ozz-style AVX2 build.
void BM_SkinKernelAvx2(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  if (!skin_kernel_isa_supported(SkinKernelIsa::Avx2Fma)) {
    state.SkipWithError("no AVX2 + FMA on this CPU");
    return;
  }
  Fixture f(0);
  const SkinningMode mode = kSkinningModes[static_cast<std::size_t>(state.range(0))];
  set_skinning_mode(*f.scene, mode);
  force_skin_kernel_isa(SkinKernelIsa::Avx2Fma);
  time_kernel(state, current_layout(*f.scene), f.scene->table(initial_slot(*f.scene)), mode);
  force_skin_kernel_isa(SkinKernelIsa::Auto);
}
BENCHMARK(BM_SkinKernelAvx2)->ArgName("mode")->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

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

// The ozz-style baseline's input: vertices reordered into partitions by influence count (1..4), AoS float3
// positions and normals, joint indices per influence and influences - 1 weights per vertex.
struct OzzStyleInput {
  struct Partition {
    int influences = 0;
    std::vector<float> positions, normals;  // 3 per vertex
    std::vector<std::uint16_t> joints;      // influences per vertex
    std::vector<float> weights;             // influences - 1 per vertex (the last is 1 - their sum)
    std::vector<float> out_positions, out_normals;
  };
  std::array<Partition, 4> parts;
  std::vector<glm::mat4> matrices;
  std::size_t vertices = 0;
};

OzzStyleInput make_ozz_style_input(const BodyLevel& level, const std::vector<glm::mat4>& matrices) {
  OzzStyleInput in;
  in.matrices = matrices;
  for (int k = 0; k < 4; ++k) in.parts[static_cast<std::size_t>(k)].influences = k + 1;
  for (std::size_t v = 0; v < level.mesh.vertex_count(); ++v) {
    std::array<std::pair<std::uint16_t, float>, 4> inf{};
    int n = 0;
    float total = 0.0f;
    for (int k = 0; k < 4; ++k)
      if (level.binding.weights[v][k] > 0.0f) {
        inf[static_cast<std::size_t>(n++)] = {static_cast<std::uint16_t>(level.binding.joints[v][k]), level.binding.weights[v][k]};
        total += level.binding.weights[v][k];
      }
    if (n == 0) inf[static_cast<std::size_t>(n++)] = {0, total = 1.0f};
    OzzStyleInput::Partition& p = in.parts[static_cast<std::size_t>(n - 1)];
    for (int c = 0; c < 3; ++c) {
      p.positions.push_back(level.mesh.positions[v][c]);
      p.normals.push_back(level.mesh.normals[v][c]);
    }
    for (int k = 0; k < n; ++k) p.joints.push_back(inf[static_cast<std::size_t>(k)].first);
    for (int k = 0; k + 1 < n; ++k) p.weights.push_back(inf[static_cast<std::size_t>(k)].second / total);
    ++in.vertices;
  }
  for (OzzStyleInput::Partition& p : in.parts) {
    p.out_positions.assign(p.positions.size(), 0.0f);
    p.out_normals.assign(p.normals.size(), 0.0f);
  }
  return in;
}

// One partition: per vertex, blend its K matrices column by column in __m128 registers and transform.
template <int K>
[[gnu::always_inline]] inline void ozz_style_partition(OzzStyleInput::Partition& p, const glm::mat4* m) {
  const std::size_t n = p.positions.size() / 3;
  const float* pos = p.positions.data();
  const float* nrm = p.normals.data();
  const std::uint16_t* joints = p.joints.data();
  const float* weights = p.weights.data();
  float* op = p.out_positions.data();
  float* on = p.out_normals.data();
  for (std::size_t v = 0; v < n; ++v) {
    __m128 c0, c1, c2, c3;
    const float* m0 = &m[joints[v * K]][0][0];
    if constexpr (K == 1) {
      c0 = _mm_loadu_ps(m0), c1 = _mm_loadu_ps(m0 + 4), c2 = _mm_loadu_ps(m0 + 8), c3 = _mm_loadu_ps(m0 + 12);
    } else {
      float last = 1.0f;
      __m128 w = _mm_set1_ps(weights[v * (K - 1)]);
      last -= weights[v * (K - 1)];
      c0 = _mm_mul_ps(w, _mm_loadu_ps(m0)), c1 = _mm_mul_ps(w, _mm_loadu_ps(m0 + 4));
      c2 = _mm_mul_ps(w, _mm_loadu_ps(m0 + 8)), c3 = _mm_mul_ps(w, _mm_loadu_ps(m0 + 12));
      for (int k = 1; k < K; ++k) {
        const float* mk = &m[joints[v * K + static_cast<std::size_t>(k)]][0][0];
        float wk;
        if (k + 1 < K) {
          wk = weights[v * (K - 1) + static_cast<std::size_t>(k)];
          last -= wk;
        } else {
          wk = last;
        }
        w = _mm_set1_ps(wk);
        c0 = _mm_add_ps(c0, _mm_mul_ps(w, _mm_loadu_ps(mk)));
        c1 = _mm_add_ps(c1, _mm_mul_ps(w, _mm_loadu_ps(mk + 4)));
        c2 = _mm_add_ps(c2, _mm_mul_ps(w, _mm_loadu_ps(mk + 8)));
        c3 = _mm_add_ps(c3, _mm_mul_ps(w, _mm_loadu_ps(mk + 12)));
      }
    }
    const __m128 x = _mm_set1_ps(pos[3 * v]), y = _mm_set1_ps(pos[3 * v + 1]), z = _mm_set1_ps(pos[3 * v + 2]);
    const __m128 rp = _mm_add_ps(_mm_add_ps(_mm_mul_ps(c0, x), _mm_mul_ps(c1, y)), _mm_add_ps(_mm_mul_ps(c2, z), c3));
    const __m128 a = _mm_set1_ps(nrm[3 * v]), b = _mm_set1_ps(nrm[3 * v + 1]), c = _mm_set1_ps(nrm[3 * v + 2]);
    const __m128 rn = _mm_add_ps(_mm_add_ps(_mm_mul_ps(c0, a), _mm_mul_ps(c1, b)), _mm_mul_ps(c2, c));
    alignas(16) float tp[4], tn[4];
    _mm_store_ps(tp, rp);
    _mm_store_ps(tn, rn);
    op[3 * v] = tp[0], op[3 * v + 1] = tp[1], op[3 * v + 2] = tp[2];
    on[3 * v] = tn[0], on[3 * v + 1] = tn[1], on[3 * v + 2] = tn[2];
  }
}

[[gnu::always_inline]] inline void ozz_style_all(OzzStyleInput& in) {
  const glm::mat4* m = in.matrices.data();
  ozz_style_partition<1>(in.parts[0], m);
  ozz_style_partition<2>(in.parts[1], m);
  ozz_style_partition<3>(in.parts[2], m);
  ozz_style_partition<4>(in.parts[3], m);
}
void ozz_style_sse2(OzzStyleInput& in) { ozz_style_all(in); }
[[gnu::target("arch=x86-64-v3")]] void ozz_style_avx2(OzzStyleInput& in) { ozz_style_all(in); }

// Args: level, ISA (0: SSE2 build, 1: AVX2 + FMA build).
void BM_SkinBaselineOzzStyle(benchmark::State& state) {
  Fixture f(static_cast<int>(state.range(0)));
  const BodyLevel& level = f.rig.body->levels[static_cast<std::size_t>(state.range(0))];
  OzzStyleInput in = make_ozz_style_input(level, f.matrices);
  const bool avx2 = state.range(1) != 0;
  if (avx2 && !skin_kernel_isa_supported(SkinKernelIsa::Avx2Fma)) {
    state.SkipWithError("no AVX2 + FMA on this CPU");
    return;
  }
  for (auto _ : state) {
    if (avx2)
      ozz_style_avx2(in);
    else
      ozz_style_sse2(in);
    for (const OzzStyleInput::Partition& p : in.parts) {
      benchmark::DoNotOptimize(p.out_positions.data());
      benchmark::DoNotOptimize(p.out_normals.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(in.vertices));
}
BENCHMARK(BM_SkinBaselineOzzStyle)->ArgsProduct({{0, 1, 2}, {0, 1}})->ArgNames({"level", "avx2"})->Unit(benchmark::kMicrosecond);

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
