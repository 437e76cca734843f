// Google Benchmark: the navigation mesh (nav/navmesh.h). Build time of the shipped plaza and bottleneck meshes
// without the cache (Recast + Detour, single-threaded), and one find_path between random walkable points of the
// plaza, in microseconds.
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

// Random pairs of walkable points of the plaza (snapped first, so every query is a real path), cycled.
void BM_FindPathPlaza(benchmark::State& state) {
  const auto mesh = strata::NavMesh::build(strata::shipped_scenario("plaza"), strata::NavBuildSettings{}, false);
  strata::NavQuery query(*mesh);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pick(-29.0f, 29.0f);
  std::vector<glm::vec2> points;
  while (points.size() < 1024)
    if (const auto p = query.nearest_walkable({pick(rng), pick(rng)}, 1.0f)) points.push_back(*p);
  std::size_t i = 0, corners = 0;
  for (auto _ : state) {
    const strata::NavPath path = query.find_path(points[i & 1023], points[(i * 7 + 1) & 1023], 16);
    corners += path.corners.size();
    ++i;
    benchmark::DoNotOptimize(path.corners.data());
  }
  state.counters["corners/path"] = static_cast<double>(corners) / static_cast<double>(i);
}
BENCHMARK(BM_FindPathPlaza)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
