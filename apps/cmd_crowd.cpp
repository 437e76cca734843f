// strata crowd: simulate N walkers on a ground grid and render them headless (EGL), writing frames, a Chrome
// trace, a CSV profile and a JSON summary. The main job.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/json_output.h"
#include "apps/scene_options.h"
#include "render/scene_draw.h"
#include "apps/crowd_distributed.h"
#include "apps/crowd_outputs.h"
#include "io/image_writer.h"
#include "profiling/profiler.h"
#include "render/camera.h"
#include "systems/animation_sample.h"
#include "render/gl_context.h"
#include "render/crowd_renderer.h"
#include "scene/crowd.h"
#include "systems/pose_gather.h"
#include "scene/state_hash.h"
#include "scene/step.h"

namespace strata::cli {
namespace {

// The clip the first walker plays (a clip index, kAllClips or kRestPose): what summary.json reports as "clip".
int first_walker_clip(const Crowd& crowd) {
  const std::vector<Entity> walkers = crowd.world.entities();
  if (walkers.empty()) return kRestPose;
  const EntityLocation at = crowd.world.location(walkers.front());
  return crowd.world.table(at.table).i32(kWalkerClip)[at.block];
}

struct CrowdOptions {
  SceneOptions scene;
  std::size_t frames = 60;
  std::string out = "out/crowd";
  RenderQuality quality = RenderQuality::High;
  RenderBackend renderer = RenderBackend::Gl;
  int width = 1280;
  int height = 720;
  float fps = 30.0f;
  double skip_seconds = 0.0;  // simulated before the first frame is drawn
  std::size_t png_every = 1;
  bool no_png = false;
  bool progress = true;
  float camera_yaw = 0.6f;
  float camera_pitch = 0.25f;
  bool follow = false;
  bool skeleton_overlay = false;
  bool mp4 = false;                // --mp4: ask for the video (a note, not an error, when ffmpeg is absent)
  bool no_mp4 = false;             // --no-mp4; neither flag: a video whenever ffmpeg is on PATH
  std::size_t table1_frames = 5;   // frames timed at each body level not drawn, for summary.json's table1
  double rebalance_seconds = 2.0;  // under mpirun: simulated seconds between recutting the ranks' slabs
  double mpi_timeout_seconds = 600.0;  // under mpirun: a rank without progress this long stops the job
};

// summary.json: written at the start (the directory's manifest while the run goes on, "running": true, so a
// killed run's directory is still recognised as a crowd output) and at the end with the files written.
void write_summary(const std::filesystem::path& dir, nlohmann::json summary, const std::vector<std::string>& files) {
  nlohmann::json list = files;
  list.push_back("summary.json");
  summary["files"] = list;
  write_json_file(dir / "summary.json", summary);
}

int run_crowd(const CrowdOptions& o) {
  namespace fs = std::filesystem;
  const fs::path out(o.out);
  // Under mpirun one crowd runs over every process (apps/crowd_distributed.h); joined first, so that a refusal
  // below is agreed by every rank and printed once.
  bool join_failed = false;
  const std::unique_ptr<CrowdDistribution> dist =
      join_if_launched("crowd", o.rebalance_seconds, o.mpi_timeout_seconds, join_failed);
  if (join_failed) return kExitFailure;
  const bool root = !dist || dist->root();
  // Everything that can be refused is refused before any work: the output directory, the memory the crowd
  // needs, the inputs, then (once a context exists) the image size. Each check runs only while none failed.
  Refusal refusal;
  if (root) refusal.refuse_if(kExitFailure, check_output_dir("--out", out));
  refusal.refuse_if(kExitUsage, check_renderer_level(o.renderer, o.scene.level, o.skeleton_overlay));
  if (dist && o.renderer != RenderBackend::Gl)
    refusal.refuse_if(kExitUsage, kDistributedRendererRefusal);
  if (refusal.none()) refusal.refuse_if(kExitFailure, check_crowd_memory(o.scene));
  const int threads = thread_count(o.scene);
  tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  std::unique_ptr<Crowd> built;
  std::unique_ptr<GlContext> context;
  if (refusal.none()) {
    try {
      check_scene_inputs(o.scene);
      built = build_scene(o.scene);
      context = create_headless_gl_context();
    } catch (const std::exception& e) {
      refusal.refuse_if(kExitFailure, error_text(e));
    }
  }
  if (refusal.none()) refusal.refuse_if(kExitFailure, check_render_size(context->limits(), o.width, o.height));
  // The render targets are made now, before the output directory: a driver may refuse a size inside the limits
  // it reports (llvmpipe caps one resource's bytes, which 4x MSAA at 12000x12000 exceeds), and that must fail
  // here with the flags named, not at the first frame with a bare GL status.
  std::unique_ptr<CrowdRenderer> renderer_owner;
  if (refusal.none()) {
    try {
      renderer_owner = std::make_unique<CrowdRenderer>(o.width, o.height);
    } catch (const std::exception& e) {
      refusal.refuse_if(kExitFailure, render_target_error(o.width, o.height, context->limits(), e));
    }
  }
  // The output directory is rank 0's alone (the other ranks may be other machines).
  if (refusal.none() && root) {
    refusal.refuse_if(kExitUsage, claim_crowd_output_dir(out).refused);
    std::error_code ec;
    if (refusal.none()) fs::create_directories(out, ec);
    if (ec) refusal.refuse_if(kExitFailure, "--out: cannot create " + out.string() + ": " + ec.message());
  }
  if (refusal.stop("crowd", dist.get())) return refusal.exit_code();
  CrowdRenderer& renderer = *renderer_owner;
  renderer.options().quality = o.quality;
  renderer.options().backend = o.renderer;
  Crowd& scene = *built;

  nlohmann::json summary;
  summary["command"] = "crowd";
  summary["running"] = true;
  summary["inputs"] = scene_inputs_json(o.scene);
  std::vector<std::string> files;  // written so far, relative to --out
  if (dist) summary["mpi_ranks"] = dist->ranks();
  try {
    if (root) write_summary(out, summary, files);
    const bool bodies = !scene.skin.level.is_none();
    RenderScratch scratch;
    RenderFrameOptions draw;
    draw.skeleton_overlay = o.skeleton_overlay;
    if (dist) draw.share_bounds = [&](glm::vec3& lo, glm::vec3& hi) { dist->share_bounds(lo, hi); };
    // Under mpirun every rank's profiler starts at a common barrier, so the merged trace's clocks line up.
    if (dist) dist->all_ok(true);
    Profiler profiler(120, true);
    // The render passes under the "render" scope, each finished before its scope closes (render/crowd_renderer.h).
    renderer.set_profiler(&profiler);
    OrbitCamera camera;
    camera.yaw = o.camera_yaw;
    camera.pitch = o.camera_pitch;
    std::vector<std::uint8_t> pixels;
    ProgressLine bar("frames", o.progress && root);
    const float dt = 1.0f / o.fps;
    const float aspect = static_cast<float>(o.width) / static_cast<float>(o.height);
    std::size_t written = 0;
    std::unique_ptr<Mp4Writer> mp4;
    if (!o.no_mp4 && root) {
      const fs::path ffmpeg = find_on_path("ffmpeg");
      if (ffmpeg.empty())
        std::cerr << "strata crowd: ffmpeg is not on PATH; no crowd.mp4 (install ffmpeg for a video)\n";
      else
        mp4 = std::make_unique<Mp4Writer>(ffmpeg, out / "crowd.mp4", o.width, o.height, o.fps);
    }
    double simulate_render_s = 0.0;  // simulate + render + read-back, without writing outputs: Table 1's fps
    const auto wall_start = std::chrono::steady_clock::now();

    // The camera frames the whole crowd: under mpirun every rank's bounds of its own walkers, shared.
    const auto frame_camera = [&]() {
      glm::vec3 lo, hi;
      bool any = crowd_frame_bounds(scene, scratch, lo, hi);
      if (dist) any = dist->share_box(any, lo, hi);
      if (any) camera.frame_box_tight(lo, hi, aspect);
      return any;
    };
    std::size_t steps_taken = 0;
    const auto step_crowd = [&](Profiler& p) {
      if (dist) dist->assign_walkers(scene, static_cast<double>(steps_taken) * dt);
      step(scene, dt, p);
      ++steps_taken;
    };
    // SIGINT/SIGTERM: stop between frames. Under mpirun every rank stops at the same frame (they agree on it).
    const auto stop_now = [&]() { return dist ? !dist->all_ok(!interrupted()) : interrupted(); };
    // A walking crowd under --level auto starts as impostors (scene/body_settings.h spawn_slot): framed from their
    // feet before the first step, so that step already gives the near walkers their meshes.
    if (scene.table(DetailSlot::Impostor).size() > 0 && frame_camera())
      set_crowd_camera(scene, camera, aspect, o.height);
    // --skip: the crowd runs that long unseen before the first drawn frame (a scenario's crowd in mid-crossing).
    // Without a camera yet, walkers keep the tables they were spawned in (scene/step.h), so a crowd spawned as
    // impostors only advances its clocks and agents: cheap, and the first drawn frame restarts the near walks.
    const auto skipped = static_cast<std::size_t>(o.skip_seconds * o.fps + 0.5);
    for (std::size_t f = 0; f < skipped && !stop_now(); ++f) step_crowd(profiler);
    std::size_t frames_done = 0;
    for (std::size_t f = 0; f < o.frames; ++f) {
      // SIGINT/SIGTERM: stop between frames, then write what the frames done show.
      if (stop_now()) break;
      profiler.begin_frame();
      {
        STRATA_PROFILE_SCOPE(profiler, "frame");
        const auto frame_start = std::chrono::steady_clock::now();
        step_crowd(profiler);
        {
          STRATA_PROFILE_SCOPE(profiler, "render");
          if (f == 0) {
            // Frame the crowd once from its first pose; a camera that re-fits every frame would pump. Bodies
            // reach past the joints (the skull above skullbase, the soles below the ankles).
            frame_camera();
          } else if (o.follow) {
            // Joints gathered here only when followed: render_frame gathers its own for the skeleton pass.
            gather_crowd_joints(scene, scratch.joints);
            glm::vec3 lo, hi;
            bool any = joint_bounds(scratch.joints, lo, hi);
            if (dist) any = dist->share_box(any, lo, hi);
            if (any) camera.target = 0.5f * (lo + hi);
          }
          // From the next frame on, walkers outside this camera are culled and --level auto picks by size.
          render_frame(scene, renderer, camera, aspect, o.height, scratch, draw);
          renderer.read_rgba(pixels);
        }
        if (dist) {
          dist->frame_done(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_start).count());
          STRATA_PROFILE_SCOPE(profiler, "composite");
          dist->composite(renderer, pixels, o.width, o.height);
        }
        simulate_render_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - frame_start).count();
        if (mp4) {
          STRATA_PROFILE_SCOPE(profiler, "write_mp4");
          mp4->write(pixels);
        }
        if (root && !o.no_png && f % o.png_every == 0) {
          STRATA_PROFILE_SCOPE(profiler, "write_png");
          char name[32];
          std::snprintf(name, sizeof name, "frame_%04zu.png", f);
          write_image(out / name, o.width, o.height, 4, pixels);
          files.push_back(name);
          ++written;
        }
      }
      profiler.end_frame();
      frames_done = f + 1;
      double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      bar.update(static_cast<double>(f + 1), static_cast<double>(o.frames),
                 elapsed > 0 ? static_cast<double>(f + 1) / elapsed : 0.0);
    }
    bar.finish();
    const bool stopped = dist ? frames_done < o.frames : interrupted();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    std::size_t mp4_frames = 0;
    if (mp4) {
      // No frame: an empty video is no video.
      if (frames_done > 0) {
        mp4_frames = mp4->finish();
        files.push_back("crowd.mp4");
      }
      else mp4.reset();
    }

    // Under mpirun: one trace with a process per rank; the CSV and the systems table are rank 0's own.
    if (dist) dist->write_merged_trace(profiler, out / "profile.json");
    else profiler.write_chrome_trace(out / "profile.json");
    files.push_back("profile.json");
    if (root) profiler.write_csv(out / "profile.csv");
    files.push_back("profile.csv");

    summary.erase("running");
    summary["interrupted"] = stopped;
    summary["walkers"] = scene.walker_count();
    summary["frames"] = frames_done;
    summary["frames_requested"] = o.frames;
    summary["frames_written"] = written;
    summary["width"] = o.width;
    summary["height"] = o.height;
    summary["threads"] = threads;
    summary["seed"] = o.scene.seed;
    summary["dt_s"] = dt;
    summary["skeleton"] = {{"name", scene.rig().skeleton.name},
                           {"source", scene.rig().skeleton.source},
                           {"joints", scene.rig().skeleton.joint_count()},
                           {"segments", scene.rig().skeleton.segments.size()},
                           {"sites", scene.rig().skeleton.sites.size()}};
    const int clip = first_walker_clip(scene);
    summary["body_level"] = scene.skin.level.json_code();
    summary["body_level_name"] = scene.skin.level.name();
    // Vertices per walker of the finest level drawn in the last frame (under --level auto, levels vary by walker).
    const std::vector<BodyDrawInput> draws = body_draw_inputs(scene);
    summary["body_vertices"] = bodies && !draws.empty() ? draws.front().vertex_count : 0;
    const auto lod = scene.lod.counts;
    // Walkers skinned and drawn at each level in the last frame, and walkers the camera did not see.
    summary["lod_last_frame"] = {{"level0", lod[0]}, {"level1", lod[1]}, {"level2", lod[2]}, {"culled", lod[3]},
                                 {"impostor", scene.lod.impostors}, {"over_mesh_budget", scene.lod.over_budget}};
    summary["mesh_budget"] = scene.lod.policy.mesh_budget;
    summary["impostors_drawn_last_frame"] = renderer.impostors_drawn();
    if (scene.impostor_atlas)
      summary["impostor_atlas"] = {{"bake_seconds", scene.impostor_atlas->bake_seconds},
                                   {"from_cache", scene.impostor_atlas->from_cache},
                                   {"bytes", scene.impostor_atlas->bytes()}};
    summary["triangles_drawn_last_frame"] = renderer.triangles_drawn();
    summary["clip"] = clip >= 0 ? nlohmann::json(scene.rig().clips[clip].name)
                      : clip == kAllClips ? nlohmann::json("all") : nlohmann::json(nullptr);
    summary["gl_renderer"] = context->renderer();
    summary["quality"] = quality_name(o.quality);
    summary["renderer"] = renderer_name(o.renderer);
    summary["gl_version"] = context->version();
    summary["wall_s"] = wall;
    summary["fps"] = wall > 0 ? static_cast<double>(frames_done) / wall : 0.0;
    summary["state_hash"] = dist ? dist->state_hash(scene) : state_hash(scene);
    if (dist) summary["mpi"] = dist->summary(frames_done);
    nlohmann::json systems = nlohmann::json::array();
    for (const SystemStats& s : profiler.stats())
      systems.push_back({{"name", s.name}, {"samples", s.samples}, {"min_ms", s.min_ms}, {"mean_ms", s.mean_ms},
                         {"p95_ms", s.p95_ms}, {"max_ms", s.max_ms}});
    summary["systems"] = systems;
    summary["mp4"] = mp4 ? nlohmann::json("crowd.mp4") : nlohmann::json(nullptr);
    // The paper's Table 1, one row per body level. Measured after everything above (state_hash included), since
    // timing the other levels walks the crowd on. Not after an interruption: the user asked to stop.
    // A profiler of its own, so the extra frames stay out of the timings reported above.
    Profiler table1_profiler(1, false);
    // Not under mpirun: Table 1 times one process drawing the whole crowd.
    const std::vector<Table1Row> table1 =
        frames_done == 0 || dist ? std::vector<Table1Row>{}
                         : measure_table1(scene, static_cast<double>(frames_done) / simulate_render_s, frames_done,
                                          stopped ? 0 : o.table1_frames, [&] {
                                            step(scene, dt, table1_profiler);
                                            render_frame(scene, renderer, camera, aspect, o.height, scratch, draw);
                                            renderer.read_rgba(pixels);
                                          });
    summary["table1"] = table1_json(table1);
    if (!root) return stopped ? interrupted_exit_code() : kExitOk;
    write_summary(out, summary, files);

    std::cout << "strata crowd: " << scene.walker_count() << " walkers x " << frames_done << " frames, "
              << scene.rig().skeleton.joint_count() << " joints each, " << o.width << "x" << o.height << " on "
              << context->renderer() << ", " << threads << " threads, " << wall << " s wall\n";
    profiler.print_table(std::cout);
    if (!table1.empty()) {
      std::cout << "Table 1 (fps: simulate + render + read-back, " << scene.walker_count()
                << (scene.walker_count() == 1 ? " walker)\n" : " walkers)\n")
                << "level  vertices  triangles  one joint  two joints     fps  measured over\n";
      for (const Table1Row& r : table1) {
        char fps[32] = "-", line[160];
        if (r.fps) std::snprintf(fps, sizeof fps, "%.1f", *r.fps);
        std::snprintf(line, sizeof line, "%5d  %8zu  %9zu  %9zu  %10zu  %6s  %s\n", r.level, r.vertices, r.triangles,
                      r.one_joint, r.two_joints, fps,
                      r.fps ? (std::to_string(r.fps_frames) + " frames, " + r.fps_source).c_str() : "not measured");
        std::cout << line;
      }
    }
    if (mp4) std::cout << "wrote crowd.mp4 (" << mp4_frames << " frames)\n";
    std::cout << "wrote " << written << " frames, profile.json, profile.csv, summary.json to " << o.out << "\n";
    if (stopped) {
      print_error("crowd", "interrupted after " + std::to_string(frames_done) + " of " + std::to_string(o.frames) +
                               " frames; the outputs cover the frames done");
      return interrupted_exit_code();
    }
  } catch (const std::exception& e) {
    if (dist) {
      // One rank's failure mid-run: the others would wait for it in the next collective, so every rank stops.
      // Printed by the failing rank itself (print_error speaks for rank 0 only).
      std::cerr << "strata crowd: rank " << dist->rank() << ": " << error_text(e) << "; stopping every rank\n";
      std::cerr.flush();
      dist->abort(kExitFailure);
    }
    print_error("crowd", error_text(e));
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void add_crowd_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<CrowdOptions>();
  auto* cmd = app.add_subcommand("crowd", "Simulate a crowd of walkers and render it headless (EGL) with a profile");
  add_scene_options(*cmd, o->scene);
  cmd->add_option("--frames,-f", o->frames, "Frames to simulate and render")->capture_default_str()
      ->check(whole_in(1, 100'000'000, true));
  cmd->add_option("--out,-o", o->out, "Output directory")->capture_default_str();
  add_quality_option(*cmd, o->quality);
  add_renderer_option(*cmd, o->renderer);
  cmd->add_option("--width", o->width, "Image width")->capture_default_str()->check(whole_in(1, 16384));
  cmd->add_option("--height", o->height, "Image height")->capture_default_str()->check(whole_in(1, 16384));
  cmd->add_option("--skip", o->skip_seconds,
                  "Simulate this many seconds before the first drawn frame (e.g. a scenario's crowd mid-way)")
      ->capture_default_str()->check(finite_in(0, 86400));
  cmd->add_option("--fps", o->fps, "Simulation frames per second (dt = 1/fps)")->capture_default_str()
      ->check(positive_up_to(1000));
  cmd->add_option("--camera-yaw", o->camera_yaw, "Camera angle about +Y in radians (0 = from the front, +Z)")
      ->capture_default_str()->check(finite_in(-100, 100));
  // The camera keeps pitch within (-1.5, 1.5) (render/camera.cpp); a value outside is refused rather than clamped.
  cmd->add_option("--camera-pitch", o->camera_pitch, "Camera angle above the ground in radians (-1.5 to 1.5)")
      ->capture_default_str()->check(finite_in(-1.5, 1.5));
  cmd->add_flag("--follow", o->follow, "Keep the camera centred on the crowd as it moves");
  cmd->add_flag("--skeleton-overlay", o->skeleton_overlay, "Draw the skeletons too when bodies are drawn");
  cmd->add_option("--png-every", o->png_every, "Write every K-th frame as PNG")->capture_default_str()
      ->check(whole_in(1, 1'000'000, true));
  cmd->add_flag("--no-png", o->no_png, "Render but write no frames");
  cmd->add_flag("!--no-progress", o->progress, "Hide the progress bar");
  cmd->add_flag("--mp4", o->mp4, "Write crowd.mp4 through ffmpeg (the default whenever ffmpeg is on PATH)");
  cmd->add_flag("--no-mp4", o->no_mp4, "Write no video even when ffmpeg is on PATH")->excludes("--mp4");
  add_mpi_options(*cmd, o->rebalance_seconds, o->mpi_timeout_seconds);
  cmd->add_option("--table1-frames", o->table1_frames,
                  "Frames timed at each body level not drawn, for the fps column of summary.json's table1 (0: none)")
      ->capture_default_str()->check(whole_in(0, 100'000, true));
  cmd->callback([o, &exit_code] { exit_code = run_crowd(*o); });
}

}  // namespace strata::cli
