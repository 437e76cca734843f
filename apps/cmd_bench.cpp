// strata bench: the full simulation (locomotion, IK, FK, skinning; no rendering) of N walkers for F frames, with
// per-system timings, total frame time and walkers per second.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <iostream>

#include "apps/commands.h"
#include "apps/json_output.h"
#include "apps/crowd_setup.h"

namespace strata::cli {
namespace {

struct BenchOptions {
  SceneOptions scene;
  std::size_t frames = 120;
  float fps = 60.0f;
  std::string json;
};

int run_bench(const BenchOptions& o) {
  const int threads = thread_count(o.scene);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  try {
    std::unique_ptr<CrowdScene> scene = build_scene(o.scene);
    // Warm-up frames settle caches and the thread pool; they are not measured.
    Profiler warmup(8, false);
    for (int f = 0; f < 3; ++f) scene->simulate(1.0f / o.fps, warmup);
    Profiler profiler(o.frames, false);
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t f = 0; f < o.frames; ++f) {
      profiler.begin_frame();
      {
        STRATA_PROFILE_SCOPE(profiler, "frame");
        scene->simulate(1.0f / o.fps, profiler);
      }
      profiler.end_frame();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double frame_ms = 1000.0 * seconds / static_cast<double>(o.frames);
    // Vertices per walker of the (finest) level drawn; under --level auto with no camera every walker is at 0.
    const auto draws = scene->body_draws();
    const std::size_t vertices = draws.empty() ? 0 : draws.front().skinned->vertex_count;
    nlohmann::json j;
    j["walkers"] = scene->walker_count();
    j["frames"] = o.frames;
    j["threads"] = threads;
    j["level"] = scene->body_level();
    j["level_name"] = body_level_name(scene->body_level());
    j["vertices_per_walker"] = vertices;
    j["frame_ms"] = frame_ms;
    j["walkers_per_second"] = static_cast<double>(scene->walker_count()) * 1000.0 / frame_ms;
    nlohmann::json systems = nlohmann::json::array();
    for (const SystemStats& s : profiler.stats())
      systems.push_back({{"name", s.name}, {"mean_ms", s.mean_ms}, {"p95_ms", s.p95_ms}, {"min_ms", s.min_ms},
                         {"max_ms", s.max_ms}});
    j["systems"] = systems;
    if (!o.json.empty()) write_json_file(o.json, j);
    std::printf("strata bench: %zu walkers x %zu frames, level %s (%zu vertices each), %d threads: %.2f ms/frame, "
                "%.0f walker-frames/s\n",
                scene->walker_count(), o.frames, body_level_name(scene->body_level()).c_str(), vertices, threads, frame_ms,
                static_cast<double>(scene->walker_count()) * 1000.0 / frame_ms);
    profiler.print_table(std::cout);
  } catch (const std::exception& e) {
    std::cerr << "strata bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

void add_bench_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<BenchOptions>();
  auto* cmd = app.add_subcommand("bench", "Time the full simulation (locomotion, IK, FK, skinning) without rendering");
  add_scene_options(*cmd, o->scene);
  cmd->add_option("--frames,-f", o->frames, "Frames to measure")->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000}));
  cmd->add_option("--fps", o->fps, "Simulation steps per second")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--json", o->json, "Write the results here");
  cmd->callback([o, &exit_code] { exit_code = run_bench(*o); });
}

}  // namespace strata::cli
