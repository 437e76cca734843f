// Google Benchmark: arc-length evaluation of Cardinal paths (motion/cardinal_spline.h), in ns per query.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "motion/cardinal_spline.h"

namespace {

constexpr std::size_t kQueries = 1024;  // a power of two, cycled with a mask

// A 20-knot closed walk loop: a wobbling 8 m circle with some height change, as a cyclic walker path would be.
strata::CardinalSpline make_loop(float tension) {
  std::vector<glm::vec3> points;
  for (int i = 0; i < 20; ++i) {
    const float a = 6.2831853f * static_cast<float>(i) / 20.0f;
    const float r = 4.0f + 0.4f * std::sin(3.0f * a);
    points.emplace_back(r * std::cos(a), 0.2f * std::sin(2.0f * a), r * std::sin(a));
  }
  return strata::CardinalSpline(points, tension, true);
}

// Random arc lengths, so the branch predictor and the table search see what a crowd of walkers would give.
std::vector<float> random_lengths(float total) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> pick(0.0f, total);
  std::vector<float> out(kQueries);
  for (float& s : out) s = pick(rng);
  return out;
}

void BM_PointAtLength(benchmark::State& state) {
  const strata::CardinalSpline loop = make_loop(static_cast<float>(state.range(0)) / 10.0f);
  const std::vector<float> lengths = random_lengths(loop.length());
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(loop.point_at_length(lengths[i++ & (kQueries - 1)]));
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["tension"] = static_cast<double>(state.range(0)) / 10.0;
}
BENCHMARK(BM_PointAtLength)->Arg(0)->Arg(9);  // tension 0 and 0.9

void BM_TangentAtLength(benchmark::State& state) {
  const strata::CardinalSpline loop = make_loop(0.0f);
  const std::vector<float> lengths = random_lengths(loop.length());
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(loop.tangent_at_length(lengths[i++ & (kQueries - 1)]));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TangentAtLength);

void BM_CardinalSplineBuild(benchmark::State& state) {
  std::vector<glm::vec3> points;
  for (int i = 0; i < 20; ++i) points.emplace_back(static_cast<float>(i), std::sin(static_cast<float>(i)), 0.0f);
  for (auto _ : state) {
    strata::CardinalSpline spline(points, 0.0f, true);
    benchmark::DoNotOptimize(spline.length());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_CardinalSplineBuild);

// One swing foot per frame: 9 knots (ankle and foot pitch, evenly spaced in time) evaluated once, what a walker in
// swing costs besides placing the knots. The knots move a little per iteration so nothing is hoisted out of the loop.
std::array<glm::vec4, 9> swing_knots(float shift) {
  std::array<glm::vec4, 9> k;
  for (std::size_t i = 0; i < k.size(); ++i) {
    const float u = static_cast<float>(i) / 8.0f;
    k[i] = glm::vec4(shift + 1.4f * u, 0.05f + 0.1f * u * (1.0f - u), 0.02f * u, 0.8f - u);
  }
  return k;
}

void BM_SwingKnotsEvaluate(benchmark::State& state) {
  std::size_t i = 0;
  for (auto _ : state) {
    const float phase = static_cast<float>(i & 63) / 64.0f;
    const std::array<glm::vec4, 9> knots = swing_knots(0.001f * static_cast<float>(i & 7));
    benchmark::DoNotOptimize(strata::cardinal_through(knots, phase));
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SwingKnotsEvaluate);

void BM_DistanceCurve(benchmark::State& state) {
  const strata::DistanceCurve curve({0.0f, 0.3f, 0.7f, 1.0f}, {0.0f, 0.1f, 1.3f, 1.4f});
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(curve.distance(static_cast<float>(i++ & 1023) / 1024.0f));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DistanceCurve);

}  // namespace

BENCHMARK_MAIN();
