// strata bench: the full simulation (locomotion, IK, FK, muscle, skinning; no rendering) of N walkers for F frames,
// with per-system timings, total frame time and walkers per second. With --render, also the crowd render pass
// against raw instanced drawing of the same triangles, in the same run.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <cstdio>
#include <iostream>
#include <memory>

#include "apps/cli_support.h"
#include "apps/crowd_distributed.h"
#include "apps/commands.h"
#include "apps/json_output.h"
#include "apps/scene_options.h"
#include "render/scene_draw.h"
#include "render/camera.h"
#include "render/gl_context.h"
#include "render/crowd_renderer.h"
#include "scene/step.h"

namespace strata::cli {
namespace {

struct BenchOptions {
  SceneOptions scene;
  std::size_t frames = 120;
  float fps = 60.0f;
  std::string json;
  bool render = false;
  int width = 1280, height = 720;
  RenderQuality quality = RenderQuality::Low;
  RenderBackend renderer = RenderBackend::Gl;
  double rebalance_seconds = 2.0;      // under mpirun (apps/crowd_distributed.h)
  double mpi_timeout_seconds = 600.0;
};

// The crowd render pass (skinned bodies streamed every frame, one multi-draw per level) against the fastest way
// to draw the same triangles: each level's mesh uploaded once and drawn with glDrawElementsInstanced, one copy per
// walker at its position. Same target, material and camera; ground and skeletons off; each timed to glFinish.
// Under mpirun (`dist`) every rank does this for its own walkers, over the shared ground and shadow frustum as
// `strata crowd` draws them, and each frame is then composited onto rank 0 (timed apart); `step_crowd` steps
// the crowd as the timed frames did (walkers changing owner included). Collective: every rank calls it.
nlohmann::json render_bench(Crowd& scene, const BenchOptions& o, GlContext& context, CrowdRenderer& renderer,
                            CrowdDistribution* dist, const std::function<void(Profiler&)>& step_crowd) {
  renderer.options().quality = o.quality;
  renderer.options().backend = o.renderer;
  // High quality keeps the ground, and so does the ray tracer, whose lighting is always high quality.
  renderer.options().draw_ground = o.quality == RenderQuality::High || o.renderer == RenderBackend::RayTraced;
  renderer.options().draw_skeleton = false;
  const float aspect = static_cast<float>(o.width) / static_cast<float>(o.height);
  OrbitCamera camera;
  RenderScratch scratch;
  Profiler unused(1, false);
  step_crowd(unused);
  // Under mpirun a rank may hold no body at all (an empty slab): the check is the crowd's, over every rank.
  const bool has_body = !scene.skin.level.is_none() &&
                        (!body_draw_inputs(scene).empty() || scene.table(DetailSlot::Impostor).size() > 0);
  const bool any_body = dist ? !dist->all_ok(!has_body) : has_body;
  if (!any_body)
    throw std::runtime_error("--render needs a body (--level 0, 1, 2, auto, impostor or S1..S3)");
  frame_whole_crowd(scene, camera, aspect, scratch, dist);  // every rank's bounds, shared
  set_crowd_camera(scene, camera, aspect, o.height);
  RenderFrameOptions draw;
  if (dist) draw.share_bounds = [&](glm::vec3& lo, glm::vec3& hi) { dist->share_bounds(lo, hi); };
  std::vector<std::uint8_t> pixels;
  double composite_s = 0.0;
  double crowd_s = 0.0, raw_s = 0.0;
  std::size_t crowd_triangles = 0, raw_triangles = 0, impostors = 0;
  std::vector<glm::vec3> offsets;
  for (std::size_t f = 0; f < std::min<std::size_t>(o.frames, 30); ++f) {
    step_crowd(unused);
    renderer.finish();
    auto t0 = std::chrono::steady_clock::now();
    render_frame(scene, renderer, camera, aspect, o.height, scratch, draw);
    renderer.finish();
    auto t1 = std::chrono::steady_clock::now();
    if (f > 0) {
      crowd_s += std::chrono::duration<double>(t1 - t0).count();
      crowd_triangles += renderer.triangles_drawn();
      impostors += renderer.impostors_drawn();
    }
    if (dist) {
      // The frame's read-back and compositing (depth read, the wait for the slowest rank, the exchange).
      t0 = std::chrono::steady_clock::now();
      renderer.read_rgba(pixels);
      dist->composite(renderer, pixels, o.width, o.height);
      if (f > 0) composite_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    // The reference: per level, that level's mesh (the first skinned walker's, placed at the origin) instanced
    // at every walker of the level, which moves it as far as the walker went.
    const std::vector<BodyDrawInput> inputs = body_draw_inputs(scene);
    for (const BodyDrawInput& input : inputs) {
      offsets.clear();
      const glm::vec3 first(input.px[0], input.py[0], input.pz[0]);
      for (std::size_t w = 0; w < input.walker_count; ++w) {
        const std::size_t i = w * input.stride;
        offsets.push_back(glm::vec3(input.px[i], input.py[i], input.pz[i]) - first);
      }
      renderer.finish();
      t0 = std::chrono::steady_clock::now();
      renderer.render_instanced_reference(input, offsets, camera.view(), camera.projection(aspect));
      renderer.finish();
      t1 = std::chrono::steady_clock::now();
      if (f > 0) raw_s += std::chrono::duration<double>(t1 - t0).count(), raw_triangles += renderer.triangles_drawn();
    }
  }
  // Then each pass on its own: a few more frames with the renderer's pass timer (which waits for the GL after each
  // pass, so these frames are not part of the rates above).
  Profiler passes(10, false);
  renderer.set_profiler(&passes);
  for (int f = 0; f < 10; ++f) {
    step_crowd(unused);
    passes.begin_frame();
    render_frame(scene, renderer, camera, aspect, o.height, scratch, draw);
    passes.end_frame();
  }
  renderer.set_profiler(nullptr);
  nlohmann::json pass_ms = nlohmann::json::object();
  for (const SystemStats& s : passes.stats()) pass_ms[s.name] = s.mean_ms;
  const double crowd_rate = crowd_s > 0 ? double(crowd_triangles) / crowd_s : 0.0;
  const double raw_rate = raw_s > 0 ? double(raw_triangles) / raw_s : 0.0;
  nlohmann::json j;
  j["gl_renderer"] = context.renderer();
  j["width"] = o.width;
  j["height"] = o.height;
  j["quality"] = quality_name(o.quality);
  j["renderer"] = renderer_name(o.renderer);
  j["pass_ms"] = pass_ms;
  j["crowd_triangles_per_second"] = crowd_rate;
  j["raw_instanced_triangles_per_second"] = raw_rate;
  j["ratio"] = raw_rate > 0 ? crowd_rate / raw_rate : 0.0;
  j["crowd_ms_per_frame"] = 1000.0 * crowd_s / double(std::max<std::size_t>(std::min<std::size_t>(o.frames, 30) - 1, 1));
  j["raw_ms_per_frame"] = 1000.0 * raw_s / double(std::max<std::size_t>(std::min<std::size_t>(o.frames, 30) - 1, 1));
  // Walkers drawn as impostors per frame (not part of the triangle rates: a quad each, from the atlas).
  j["impostors_per_frame"] = double(impostors) / double(std::max<std::size_t>(std::min<std::size_t>(o.frames, 30) - 1, 1));
  if (dist) {
    // This rank's figures above; every rank's here. A distributed frame costs its slowest rank's render pass and
    // then the compositing.
    const double timed = double(std::max<std::size_t>(std::min<std::size_t>(o.frames, 30) - 1, 1));
    const std::vector<double> render_ms = dist->all_gather(j["crowd_ms_per_frame"].get<double>());
    const std::vector<double> composite_ms = dist->all_gather(1000.0 * composite_s / timed);
    const std::vector<double> triangles = dist->all_gather(double(crowd_triangles) / timed);
    j["mpi"] = {{"render_ms_per_frame_per_rank", render_ms},
                {"composite_ms_per_frame_per_rank", composite_ms},
                {"triangles_per_frame_per_rank", triangles},
                {"frame_ms", *std::max_element(render_ms.begin(), render_ms.end()) +
                                 *std::max_element(composite_ms.begin(), composite_ms.end())}};
  }
  return j;
}

int run_bench(const BenchOptions& o) {
  // Under mpirun the simulation is timed with the crowd spread over the ranks as `strata crowd` spreads it
  // (apps/crowd_distributed.h): each rank steps the walkers of its slab; rank 0 reports every rank's times.
  bool join_failed = false;
  const std::unique_ptr<CrowdDistribution> dist =
      join_if_launched("bench", o.rebalance_seconds, o.mpi_timeout_seconds, join_failed);
  if (join_failed) return kExitFailure;
  const bool root = !dist || dist->root();
  // The first refusal with its exit code; under mpirun agreed between the ranks before anyone stops.
  Refusal refusal;
  if (root && !o.json.empty()) refusal.refuse_if(kExitFailure, check_output_file("--json", o.json));
  refusal.refuse_if(kExitFailure, check_crowd_memory(o.scene));
  if (o.render) refusal.refuse_if(kExitUsage, check_renderer_level(o.renderer, o.scene.level, false));
  if (o.render && dist && o.renderer != RenderBackend::Gl)
    refusal.refuse_if(kExitUsage, kDistributedRendererRefusal);
  const int threads = thread_count(o.scene);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  std::unique_ptr<Crowd> built;
  if (refusal.none()) {
    try {
      check_scene_inputs(o.scene);
      built = build_scene(o.scene);
    } catch (const std::exception& e) {
      refusal.refuse_if(kExitFailure, error_text(e));
    }
  }
  if (refusal.stop("bench", dist.get())) return refusal.exit_code();
  try {
    std::unique_ptr<Crowd> scene = std::move(built);
    // --render: the context and render target first, so a size the driver refuses fails before the timed frames.
    std::unique_ptr<GlContext> context;
    std::unique_ptr<CrowdRenderer> renderer;
    if (o.render) {
      context = create_headless_gl_context();
      std::string why;
      renderer = make_checked_renderer(*context, o.width, o.height, why);
      if (!renderer) {
        print_error("bench", why);
        return kExitFailure;
      }
    }
    // Warm-up frames settle caches and the thread pool; they are not measured. After the first, a camera framing
    // the crowd (as strata crowd's) is handed to the level-of-detail stage, so the timed frames are the frame every
    // command runs, culling and --level auto included.
    Profiler warmup(8, false);
    std::size_t steps_taken = 0;
    const auto step_crowd = [&](Profiler& p) {
      if (dist) dist->assign_walkers(*scene, static_cast<double>(steps_taken) / o.fps);
      step(*scene, 1.0f / o.fps, p);
      ++steps_taken;
    };
    {
      OrbitCamera camera;
      RenderScratch scratch;
      const float aspect = static_cast<float>(o.width) / static_cast<float>(o.height);
      // A walking crowd under --level auto starts as impostors: framed from their feet before the first step.
      const bool framed_first = scene->table(DetailSlot::Impostor).size() > 0;
      // Under mpirun the camera frames the whole crowd: every rank's bounds, shared.
      if (framed_first && frame_whole_crowd(*scene, camera, aspect, scratch, dist.get()))
        set_crowd_camera(*scene, camera, aspect, o.height);
      step_crowd(warmup);
      frame_whole_crowd(*scene, camera, aspect, scratch, dist.get());
      set_crowd_camera(*scene, camera, aspect, o.height);
    }
    for (int f = 1; f < 3; ++f) step_crowd(warmup);
    Profiler profiler(o.frames, false);
    const auto start = std::chrono::steady_clock::now();
    std::size_t frames = 0;  // measured; fewer than --frames when SIGINT/SIGTERM stopped the run
    // SIGINT/SIGTERM: stop between frames; under mpirun every rank at the same frame.
    const auto stop_now = [&]() { return dist ? !dist->all_ok(!interrupted()) : interrupted(); };
    for (std::size_t f = 0; f < o.frames && !stop_now(); ++f, ++frames) {
      profiler.begin_frame();
      const auto frame_start = std::chrono::steady_clock::now();
      {
        STRATA_PROFILE_SCOPE(profiler, "frame");
        step_crowd(profiler);
      }
      if (dist)
        dist->frame_done(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_start).count());
      profiler.end_frame();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const bool stopped = dist ? frames < o.frames : interrupted();
    const double frame_ms = frames ? 1000.0 * seconds / static_cast<double>(frames) : 0.0;
    // Vertices per walker of the (finest) level drawn; under --level auto with no camera every walker is at 0.
    const std::vector<BodyDrawInput> draws = body_draw_inputs(*scene);
    const std::size_t vertices = draws.empty() ? 0 : draws.front().vertex_count;
    nlohmann::json j;
    j["walkers"] = scene->walker_count();
    j["frames"] = frames;
    j["interrupted"] = stopped;
    j["inputs"] = scene_inputs_json(o.scene);
    j["threads"] = threads;
    j["level"] = scene->skin.level.json_code();
    j["level_name"] = scene->skin.level.name();
    j["vertices_per_walker"] = vertices;
    j["frame_ms"] = frame_ms;
    j["walkers_per_second"] = frame_ms > 0 ? static_cast<double>(scene->walker_count()) * 1000.0 / frame_ms : 0.0;
    // Under mpirun: frame_ms and systems are rank 0's; every rank's in "mpi" (the crowd's frame is its slowest
    // rank's: compute_ms_mean_per_rank).
    if (dist) j["mpi"] = dist->summary(frames);
    // The render benchmark before the ranks part: under mpirun every rank renders its own walkers.
    nlohmann::json render;
    if (o.render && !stopped) render = render_bench(*scene, o, *context, *renderer, dist.get(), step_crowd);
    if (!root) return stopped ? interrupted_exit_code() : kExitOk;
    nlohmann::json systems = nlohmann::json::array();
    for (const SystemStats& s : profiler.stats())
      systems.push_back({{"name", s.name}, {"mean_ms", s.mean_ms}, {"p95_ms", s.p95_ms}, {"min_ms", s.min_ms},
                         {"max_ms", s.max_ms}});
    j["systems"] = systems;
    if (o.render && !stopped) {
      const nlohmann::json& r = render;
      j["render"] = r;
      std::printf("render pass (%s, %dx%d): crowd %.3g triangles/s (%.1f ms/frame), raw instanced %.3g triangles/s "
                  "(%.1f ms/frame), ratio %.2f\n",
                  r["gl_renderer"].get<std::string>().c_str(), o.width, o.height,
                  r["crowd_triangles_per_second"].get<double>(), r["crowd_ms_per_frame"].get<double>(),
                  r["raw_instanced_triangles_per_second"].get<double>(), r["raw_ms_per_frame"].get<double>(),
                  r["ratio"].get<double>());
    }
    if (!o.json.empty()) write_json_file(o.json, j);
    std::printf("strata bench: %zu walkers x %zu frames, level %s (%zu vertices each), %d threads: %.2f ms/frame, "
                "%.0f walker-frames/s\n",
                scene->walker_count(), frames, scene->skin.level.name().c_str(), vertices, threads, frame_ms,
                frame_ms > 0 ? static_cast<double>(scene->walker_count()) * 1000.0 / frame_ms : 0.0);
    profiler.print_table(std::cout);
    if (stopped) {
      print_error("bench", "interrupted after " + std::to_string(frames) + " of " + std::to_string(o.frames) + " frames");
      return interrupted_exit_code();
    }
  } catch (const std::exception& e) {
    if (dist) {
      std::cerr << "strata bench: rank " << dist->rank() << ": " << error_text(e) << "; stopping every rank\n";
      std::cerr.flush();
      dist->abort(kExitFailure);
    }
    print_error("bench", error_text(e));
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
      ->check(whole_in(1, 1'000'000, true));
  cmd->add_option("--fps", o->fps, "Simulation steps per second")->capture_default_str()->check(positive_up_to(1000));
  cmd->add_option("--json", o->json, "Write the results here");
  cmd->add_flag("--render", o->render,
                "Also time the crowd render pass (headless EGL) against raw instanced drawing of the same triangles");
  add_quality_option(*cmd, o->quality);
  add_renderer_option(*cmd, o->renderer);
  add_mpi_options(*cmd, o->rebalance_seconds, o->mpi_timeout_seconds);
  cmd->add_option("--width", o->width, "Render width for --render")->capture_default_str()->check(whole_in(1, 16384));
  cmd->add_option("--height", o->height, "Render height for --render")->capture_default_str()->check(whole_in(1, 16384));
  cmd->callback([o, &exit_code] { exit_code = run_bench(*o); });
}

}  // namespace strata::cli
