// strata soak: runs a crowd for a given wall time and samples resident memory from /proc/self/statm, asserting it
// stays flat after a warm-up. A leak of a few bytes per frame is invisible in a 60-frame run and fatal in a
// day-long installation; this is the check for it (docs/reliability.md).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <thread>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/scene_options.h"
#include "render/scene_draw.h"
#include "apps/json_output.h"
#include "profiling/profiler.h"
#include "render/camera.h"
#include "render/gl_context.h"
#include "render/crowd_renderer.h"
#include "systems/pose_gather.h"
#include "scene/step.h"

namespace strata::cli {
namespace {

struct SoakOptions {
  SceneOptions scene;
  double seconds = 120.0;
  double warmup = -1.0;      // < 0: a quarter of the run, at least 10 s and at most 300 s
  float fps = 60.0f;
  bool unpaced = false;      // run frames back to back instead of at --fps real time
  bool render = false;       // also render (headless EGL) and read back every frame
  int width = 320, height = 240;
  double tolerance_pct = 1.0;
  double sample_every = 1.0;
  std::string json;
  bool progress = true;
};

int run_soak(const SoakOptions& o) {
  if (!check_outputs("soak", {{"--json", o.json}})) return kExitFailure;
  if (const std::string why = check_crowd_memory(o.scene); !why.empty()) {
    print_error("soak", why);
    return kExitFailure;
  }
  using clock = std::chrono::steady_clock;
  const double warmup = o.warmup >= 0.0 ? o.warmup : std::clamp(o.seconds / 4.0, 10.0, 300.0);
  if (!(o.seconds > warmup)) {
    std::cerr << "strata soak: --seconds must exceed the warm-up (" << warmup << " s)\n";
    return 2;
  }
  if (resident_kib() < 0) {
    std::cerr << "strata soak: cannot read /proc/self/statm\n";
    return 1;
  }
  const int threads = thread_count(o.scene);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  try {
    check_scene_inputs(o.scene);
    std::unique_ptr<Crowd> scene = build_scene(o.scene);
    std::unique_ptr<GlContext> context;
    std::unique_ptr<CrowdRenderer> renderer;
    OrbitCamera camera;
    RenderScratch scratch;
    std::vector<std::uint8_t> pixels;
    if (o.render) {
      context = create_headless_gl_context();
      std::string why;
      renderer = make_checked_renderer(*context, o.width, o.height, why);
      if (!renderer) {
        print_error("soak", why);
        return kExitFailure;
      }
    }
    // A rolling window and no trace: the profiler itself must not grow with the run.
    Profiler profiler(120, false);
    const float dt = 1.0f / o.fps;
    const float aspect = static_cast<float>(o.width) / static_cast<float>(o.height);
    struct Sample {
      double t;
      long kib;
    };
    std::vector<Sample> samples;
    samples.reserve(static_cast<std::size_t>(o.seconds / o.sample_every) + 16);
    const auto start = clock::now();
    auto next_frame = start;
    double next_sample = 0.0;
    std::size_t frames = 0;
    ProgressLine progress("s", o.progress);
    // A walking crowd under --level auto starts as impostors: framed from their feet before the first step.
    if (scene->table(DetailSlot::Impostor).size() > 0 && frame_crowd(*scene, camera, aspect, scratch))
      set_crowd_camera(*scene, camera, aspect, o.height);
    for (;;) {
      const double t = std::chrono::duration<double>(clock::now() - start).count();
      if (t >= next_sample) {
        samples.push_back({t, resident_kib()});
        next_sample += o.sample_every;
        progress.update(t, o.seconds, 1.0,
                        std::to_string(samples.back().kib / 1024) + " MiB RSS, " + std::to_string(frames) + " frames");
      }
      // SIGINT/SIGTERM: stop between frames and report the samples taken so far.
      if (t >= o.seconds || interrupted()) break;
      profiler.begin_frame();
      step(*scene, dt, profiler);
      // The camera follows the crowd, and the next step culls and levels against it, rendered or not: the soak
      // runs the frame every command runs.
      frame_crowd(*scene, camera, aspect, scratch);
      if (renderer) {
        render_frame(*scene, *renderer, camera, aspect, o.height, scratch);
        renderer->read_rgba(pixels);
      } else {
        set_crowd_camera(*scene, camera, aspect, o.height);
      }
      profiler.end_frame();
      ++frames;
      if (!o.unpaced) {
        next_frame += std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(dt));
        const auto now = clock::now();
        if (next_frame > now) std::this_thread::sleep_until(next_frame);
        else next_frame = now;  // behind schedule: do not try to catch up in a burst
      }
    }

    progress.finish();
    const bool stopped = interrupted();
    if (samples.empty() || samples.back().t < std::chrono::duration<double>(clock::now() - start).count() - 0.5)
      samples.push_back({std::chrono::duration<double>(clock::now() - start).count(), resident_kib()});
    // Flat means: no sample after the warm-up exceeds the first one after it by more than the tolerance. A run
    // interrupted before the warm-up ended has no verdict, only its samples.
    auto first_after = std::find_if(samples.begin(), samples.end(), [&](const Sample& s) { return s.t >= warmup; });
    if (first_after == samples.end() && !stopped) throw std::runtime_error("no memory sample after the warm-up");
    const bool judged = first_after != samples.end();
    if (!judged) first_after = samples.end() - 1;
    long peak = first_after->kib, low = first_after->kib;
    for (auto it = first_after; it != samples.end(); ++it) {
      peak = std::max(peak, it->kib);
      low = std::min(low, it->kib);
    }
    const long baseline = first_after->kib;
    const double growth_pct = 100.0 * static_cast<double>(peak - baseline) / static_cast<double>(baseline);
    const bool flat = !judged || growth_pct <= o.tolerance_pct;
    const double wall = std::chrono::duration<double>(clock::now() - start).count();

    nlohmann::json j;
    j["command"] = "soak";
    j["interrupted"] = stopped;
    j["seconds_requested"] = o.seconds;
    j["inputs"] = scene_inputs_json(o.scene);
    j["walkers"] = scene->walker_count();
    j["level"] = scene->skin.level.json_code();
    j["render"] = o.render;
    j["threads"] = threads;
    j["paced_fps"] = o.unpaced ? nlohmann::json(nullptr) : nlohmann::json(o.fps);
    j["wall_s"] = wall;
    j["warmup_s"] = warmup;
    j["frames"] = frames;
    j["rss_kib_start"] = samples.front().kib;
    j["rss_kib_after_warmup"] = baseline;
    j["rss_kib_min_after_warmup"] = low;
    j["rss_kib_max_after_warmup"] = peak;
    j["rss_kib_end"] = samples.back().kib;
    j["growth_pct"] = growth_pct;
    j["tolerance_pct"] = o.tolerance_pct;
    j["flat"] = judged ? nlohmann::json(flat) : nlohmann::json(nullptr);  // null: stopped before the warm-up ended
    nlohmann::json series = nlohmann::json::array();
    for (const Sample& s : samples) series.push_back({s.t, s.kib});
    j["samples_s_kib"] = series;
    if (!o.json.empty()) write_json_file(o.json, j);

    std::printf("strata soak: %zu walkers, %zu frames in %.0f s; RSS %ld KiB at start, %ld after %.0f s warm-up, "
                "max %ld, end %ld: %+.2f %% (limit %.2f %%)\n",
                scene->walker_count(), frames, wall, samples.front().kib, baseline, warmup, peak, samples.back().kib,
                growth_pct, o.tolerance_pct);
    if (stopped) {
      print_error("soak", "interrupted after " + std::to_string(static_cast<long>(wall)) + " of " +
                              std::to_string(static_cast<long>(o.seconds)) + " s; " +
                              std::to_string(samples.size()) + " samples kept" + (o.json.empty() ? "" : " in " + o.json));
      return interrupted_exit_code();
    }
    if (!flat) {
      std::cerr << "strata soak: resident memory grew " << growth_pct << " % after the warm-up (limit "
                << o.tolerance_pct << " %)\n";
      return 1;
    }
  } catch (const std::exception& e) {
    print_error("soak", error_text(e));
    return 1;
  }
  return 0;
}

}  // namespace

void add_soak_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<SoakOptions>();
  auto* cmd = app.add_subcommand("soak", "Run a crowd for a wall time, asserting resident memory stays flat");
  add_scene_options(*cmd, o->scene);
  cmd->add_option("--seconds,-s", o->seconds, "Wall time to run")->capture_default_str()->check(positive_up_to(1e7));
  cmd->add_option("--warmup", o->warmup, "Seconds before the baseline sample (default: a quarter, 10-300 s)")
      ->check(finite_in(0, 1e7));
  cmd->add_option("--fps", o->fps, "Simulation steps per second, also the real-time pace")->capture_default_str()
      ->check(positive_up_to(1000));
  cmd->add_flag("--unpaced", o->unpaced, "Run frames back to back instead of at --fps");
  cmd->add_flag("--render", o->render, "Also render every frame headless (EGL) and read it back");
  cmd->add_option("--width", o->width, "Render width")->capture_default_str()->check(whole_in(1, 16384));
  cmd->add_option("--height", o->height, "Render height")->capture_default_str()->check(whole_in(1, 16384));
  cmd->add_option("--tolerance-pct", o->tolerance_pct, "Allowed growth after the warm-up, percent")
      ->capture_default_str()->check(finite_in(0, 1000));
  cmd->add_option("--sample-every", o->sample_every, "Seconds between memory samples (0.01 to 3600)")->capture_default_str()
      ->check(finite_in(0.01, 3600));
  cmd->add_option("--json", o->json, "Write the report (with every sample) here");
  cmd->add_flag("!--no-progress", o->progress, "Hide the progress line (shown only when stderr is a terminal)");
  cmd->callback([o, &exit_code] { exit_code = run_soak(*o); });
}

}  // namespace strata::cli
