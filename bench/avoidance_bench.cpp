// Google Benchmark: one ORCA avoidance step (systems/avoidance.h) over a dense random crowd, about one agent per
// 2 m^2, with six box obstacles (4 x 3 m) and preferred velocities towards random goals. Reports ms per step (the time
// unit) and agents per second. The *Serial variant pins oneTBB to one thread; the others use every core;
// *OnePass turns AvoidanceParameters::second_pass off; *RightOfWay sets AvoidanceParameters::right_of_way to the
// crowds' 0.49, *Crowds that, the crowds' right_of_way_back_fade 0.2, passing_angle 0.3 and back_off_limit 0.5 (the
// plain ones measure the paper's halves).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include <tbb/global_control.h>

#include "systems/avoidance.h"

namespace {

struct Columns {
  std::vector<float> px, pz, vx, vz, pref_vx, pref_vz, radius, max_speed, new_vx, new_vz;
};

bool inside_any(const std::vector<std::vector<glm::vec2>>& boxes, float x, float z) {
  for (const auto& b : boxes)
    if (x > b[0].x && x < b[2].x && z > b[0].y && z < b[2].y) return true;
  return false;
}

// A jittered grid at ~2 m^2 per agent (spacing sqrt(2) m, +-0.35 m jitter, so no two agents overlap, as in a
// running simulation; uniform random positions would start half the agents overlapping someone, a state ORCA only
// passes through), agents already walking roughly towards their goals.
Columns make_crowd(std::size_t n, const std::vector<std::vector<glm::vec2>>& boxes, float side) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<float> pos(-side / 2, side / 2), jitter(-0.35f, 0.35f), rad(0.25f, 0.35f),
      dir(0.0f, 6.2831853f);
  const float spacing = 1.41421356f;
  const auto per_row = static_cast<std::size_t>(std::ceil(side / spacing));
  Columns c;
  for (std::size_t slot = 0; c.px.size() < n; ++slot) {
    const float x = -side / 2 + spacing * (static_cast<float>(slot % per_row) + 0.5f) + jitter(rng);
    const float z = -side / 2 + spacing * (static_cast<float>(slot / per_row) + 0.5f) + jitter(rng);
    if (inside_any(boxes, x, z)) continue;
    const float gx = pos(rng), gz = pos(rng);
    const float dx = gx - x, dz = gz - z, d = std::sqrt(dx * dx + dz * dz) + 1e-6f;
    const float a = dir(rng);
    c.px.push_back(x);
    c.pz.push_back(z);
    c.pref_vx.push_back(1.4f * dx / d);
    c.pref_vz.push_back(1.4f * dz / d);
    c.vx.push_back(0.7f * dx / d + 0.3f * std::cos(a));
    c.vz.push_back(0.7f * dz / d + 0.3f * std::sin(a));
    c.radius.push_back(rad(rng));
    c.max_speed.push_back(1.8f);
  }
  c.new_vx.resize(n);
  c.new_vz.resize(n);
  return c;
}

void run_bench(benchmark::State& state, bool serial, bool second_pass = true, float right_of_way = 0.0f,
               float passing_angle = 0.0f, float back_fade = 0.0f, float back_off = -1.0f) {
  std::unique_ptr<tbb::global_control> one;
  if (serial) one = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, 1);
  const auto n = static_cast<std::size_t>(state.range(0));
  const float side = std::sqrt(2.0f * static_cast<float>(n));  // ~2 m^2 per agent
  std::vector<std::vector<glm::vec2>> boxes;
  for (int k = 0; k < 6; ++k) {
    const float cx = side * (-0.35f + 0.14f * static_cast<float>(k)), cz = side * (k % 2 == 0 ? -0.2f : 0.2f);
    boxes.push_back({{cx - 2.0f, cz - 1.5f}, {cx + 2.0f, cz - 1.5f}, {cx + 2.0f, cz + 1.5f}, {cx - 2.0f, cz + 1.5f}});
  }
  const strata::ObstacleSet obstacles(boxes, 2.0f);
  Columns c = make_crowd(n, boxes, side);
  strata::AvoidanceScratch scratch;
  strata::AvoidanceJob job;
  job.px = c.px;
  job.pz = c.pz;
  job.vx = c.vx;
  job.vz = c.vz;
  job.pref_vx = c.pref_vx;
  job.pref_vz = c.pref_vz;
  job.radius = c.radius;
  job.max_speed = c.max_speed;
  job.new_vx = c.new_vx;
  job.new_vz = c.new_vz;
  job.obstacles = &obstacles;
  job.scratch = &scratch;
  job.params.second_pass = second_pass;
  job.params.right_of_way = right_of_way;
  job.params.passing_angle = passing_angle;
  job.params.right_of_way_back_fade = back_fade;
  job.params.back_off_limit = back_off;
  for (auto _ : state) {
    if (!job.run()) state.SkipWithError("invalid AvoidanceJob");
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(n));
}

void BM_Avoidance(benchmark::State& state) { run_bench(state, false); }
void BM_AvoidanceSerial(benchmark::State& state) { run_bench(state, true); }
void BM_AvoidanceOnePass(benchmark::State& state) { run_bench(state, false, false); }
void BM_AvoidanceRightOfWay(benchmark::State& state) { run_bench(state, false, true, 0.49f); }
void BM_AvoidanceCrowds(benchmark::State& state) { run_bench(state, false, true, 0.49f, 0.3f, 0.2f, 0.5f); }
BENCHMARK(BM_Avoidance)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_AvoidanceOnePass)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_AvoidanceRightOfWay)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_AvoidanceCrowds)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_AvoidanceSerial)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
