// Google Benchmark: the navigation mesh (nav/navmesh.h). Build time of the shipped plaza and bottleneck meshes
// without the cache (Recast + Detour; the plaza's 600 x 600 cells are 9 tiles built in parallel), and one
// find_path between random walkable points, in microseconds.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "io/scenario_file.h"
#include "nav/navmesh.h"

namespace {

void build(benchmark::State& state, const char* name) {
  const strata::Scenario scenario = strata::shipped_scenario(name);
  std::size_t polygons = 0;
  for (auto _ : state) {
    const auto mesh = strata::NavMesh::build(scenario, strata::NavBuildSettings{}, /*use_cache=*/false);
    polygons = mesh->info().polygons;
    benchmark::DoNotOptimize(mesh.get());
  }
  state.counters["polygons"] = static_cast<double>(polygons);
}

void BM_BuildPlaza(benchmark::State& state) { build(state, "plaza"); }
void BM_BuildBottleneck(benchmark::State& state) { build(state, "bottleneck"); }
BENCHMARK(BM_BuildPlaza)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildBottleneck)->Unit(benchmark::kMillisecond);

// Random pairs of walkable points (snapped first, so every query is a real path), cycled. In the plaza most pairs
// are in sight of each other (one ray cast, no A*); in the bottleneck every pair is from inside the room to
// outside it, through the door (A*, string pulling and the shortcut pass).
void find_path(benchmark::State& state, const char* name, glm::vec2 from_lo, glm::vec2 from_hi, glm::vec2 to_lo,
               glm::vec2 to_hi) {
  const auto mesh = strata::NavMesh::build(strata::shipped_scenario(name), strata::NavBuildSettings{}, false);
  strata::NavQuery query(*mesh);
  std::mt19937 rng(7);
  auto pick = [&rng](glm::vec2 lo, glm::vec2 hi) {
    return glm::vec2(std::uniform_real_distribution<float>(lo.x, hi.x)(rng),
                     std::uniform_real_distribution<float>(lo.y, hi.y)(rng));
  };
  std::vector<glm::vec2> from, to;
  while (from.size() < 1024)
    if (const auto p = query.nearest_walkable(pick(from_lo, from_hi), 1.0f)) from.push_back(*p);
  while (to.size() < 1024)
    if (const auto p = query.nearest_walkable(pick(to_lo, to_hi), 1.0f)) to.push_back(*p);
  std::size_t i = 0, corners = 0, complete = 0;
  for (auto _ : state) {
    const strata::NavPath path = query.find_path(from[i & 1023], to[(i * 7 + 1) & 1023], 16);
    corners += path.corners.size();
    complete += path.complete;
    ++i;
    benchmark::DoNotOptimize(path.corners.data());
  }
  state.counters["corners/path"] = static_cast<double>(corners) / static_cast<double>(i);
  state.counters["complete"] = static_cast<double>(complete) / static_cast<double>(i);
}

void BM_FindPathPlaza(benchmark::State& state) {
  find_path(state, "plaza", glm::vec2(-29.0f), glm::vec2(29.0f), glm::vec2(-29.0f), glm::vec2(29.0f));
}
void BM_FindPathBottleneck(benchmark::State& state) {
  find_path(state, "bottleneck", {-9.5f, -5.5f}, {-0.5f, 5.5f}, {2.0f, -7.0f}, {13.0f, 7.0f});
}
BENCHMARK(BM_FindPathPlaza)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FindPathBottleneck)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
