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

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/json_output.h"
#include "apps/scene_options.h"
#include "render/scene_draw.h"
#include "apps/crowd_outputs.h"
#include "io/image_writer.h"
#include "profiling/profiler.h"
#include "render/camera.h"
#include "systems/animation_sample.h"
#include "render/gl_context.h"
#include "render/skeleton_renderer.h"
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
  return static_cast<int>(crowd.world.table(at.table).f32(kWalkerClock, 2)[at.block]);
}

struct CrowdOptions {
  SceneOptions scene;
  std::size_t frames = 60;
  std::string out = "out/crowd";
  int width = 1280;
  int height = 720;
  float fps = 30.0f;
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
};

// One line that rewrites itself; only when stderr is a terminal, so logs and CI output stay clean.
class ProgressBar {
 public:
  ProgressBar(std::size_t total, bool enabled) : total_(total), enabled_(enabled && isatty(fileno(stderr))) {}
  void update(std::size_t done, double fps) {
    if (!enabled_) return;
    constexpr int kWidth = 30;
    int filled = total_ ? static_cast<int>(kWidth * done / total_) : kWidth;
    std::fprintf(stderr, "\r[%.*s%*s] %zu/%zu frames  %.1f fps ", filled, "##############################",
                 kWidth - filled, "", done, total_, fps);
    if (done == total_) std::fputc('\n', stderr);
    std::fflush(stderr);
  }

 private:
  std::size_t total_;
  bool enabled_;
};

int run_crowd(const CrowdOptions& o) {
  namespace fs = std::filesystem;
  if (o.frames == 0 || o.width <= 0 || o.height <= 0 || !(o.fps > 0.0f)) {
    std::cerr << "strata crowd: --frames, --width, --height and --fps must be positive\n";
    return 2;
  }
  const int threads = thread_count(o.scene);
  tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  std::unique_ptr<Crowd> built;
  try {
    check_scene_inputs(o.scene);
    built = build_scene(o.scene);
  } catch (const std::exception& e) {
    print_error("crowd", error_text(e));
    return 1;
  }
  Crowd& scene = *built;
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec) {
    std::cerr << "strata crowd: cannot create output directory " << o.out << ": " << ec.message() << "\n";
    return 1;
  }

  try {
    auto context = create_headless_gl_context();
    SkeletonRenderer renderer(o.width, o.height);
    const bool bodies = !scene.skin.level.is_none();
    RenderScratch scratch;
    RenderFrameOptions draw;
    draw.skeleton_overlay = o.skeleton_overlay;
    Profiler profiler(120, true);
    OrbitCamera camera;
    camera.yaw = o.camera_yaw;
    camera.pitch = o.camera_pitch;
    std::vector<glm::vec3> joints;
    std::vector<std::uint8_t> pixels;
    ProgressBar bar(o.frames, o.progress);
    const float dt = 1.0f / o.fps;
    const float aspect = static_cast<float>(o.width) / static_cast<float>(o.height);
    std::size_t written = 0;
    std::unique_ptr<Mp4Writer> mp4;
    if (!o.no_mp4) {
      const fs::path ffmpeg = find_on_path("ffmpeg");
      if (ffmpeg.empty())
        std::cerr << "strata crowd: ffmpeg is not on PATH; no crowd.mp4 (install ffmpeg for a video)\n";
      else
        mp4 = std::make_unique<Mp4Writer>(ffmpeg, fs::path(o.out) / "crowd.mp4", o.width, o.height, o.fps);
    }
    double simulate_render_s = 0.0;  // simulate + render + read-back, without writing outputs: Table 1's fps
    const auto wall_start = std::chrono::steady_clock::now();

    for (std::size_t f = 0; f < o.frames; ++f) {
      profiler.begin_frame();
      {
        STRATA_PROFILE_SCOPE(profiler, "frame");
        const auto frame_start = std::chrono::steady_clock::now();
        step(scene, dt, profiler);
        {
          STRATA_PROFILE_SCOPE(profiler, "render");
          gather_crowd_joints(scene, joints);
          if (f == 0) {
            // Frame the crowd once from its first pose; a camera that re-fits every frame would pump. Bodies
            // reach past the joints (the skull above skullbase, the soles below the ankles).
            glm::vec3 lo, hi;
            const bool any = bodies ? body_bounds(scene, lo, hi) : joint_bounds(joints, lo, hi);
            if (any) camera.frame_box_tight(lo, hi, aspect);
          } else if (o.follow) {
            glm::vec3 lo, hi;
            if (joint_bounds(joints, lo, hi)) camera.target = 0.5f * (lo + hi);
          }
          // From the next frame on, walkers outside this camera are culled and --level auto picks by size.
          render_frame(scene, renderer, camera, aspect, o.height, scratch, draw);
          renderer.read_rgba(pixels);
        }
        simulate_render_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - frame_start).count();
        if (mp4) {
          STRATA_PROFILE_SCOPE(profiler, "write_mp4");
          mp4->write(pixels);
        }
        if (!o.no_png && f % o.png_every == 0) {
          STRATA_PROFILE_SCOPE(profiler, "write_png");
          char name[32];
          std::snprintf(name, sizeof name, "frame_%04zu.png", f);
          write_image(fs::path(o.out) / name, o.width, o.height, 4, pixels);
          ++written;
        }
      }
      profiler.end_frame();
      double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      bar.update(f + 1, elapsed > 0 ? static_cast<double>(f + 1) / elapsed : 0.0);
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    const std::size_t mp4_frames = mp4 ? mp4->finish() : 0;

    profiler.write_chrome_trace(fs::path(o.out) / "profile.json");
    profiler.write_csv(fs::path(o.out) / "profile.csv");

    nlohmann::json summary;
    summary["command"] = "crowd";
    summary["walkers"] = scene.walker_count();
    summary["frames"] = o.frames;
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
    summary["lod_last_frame"] = {{"level0", lod[0]}, {"level1", lod[1]}, {"level2", lod[2]}, {"culled", lod[3]}};
    summary["triangles_drawn_last_frame"] = renderer.triangles_drawn();
    summary["clip"] = clip >= 0 ? nlohmann::json(scene.rig().clips[clip].name)
                      : clip == kAllClips ? nlohmann::json("all") : nlohmann::json(nullptr);
    summary["gl_renderer"] = context->renderer();
    summary["gl_version"] = context->version();
    summary["wall_s"] = wall;
    summary["fps"] = static_cast<double>(o.frames) / wall;
    summary["state_hash"] = state_hash(scene);
    nlohmann::json systems = nlohmann::json::array();
    for (const SystemStats& s : profiler.stats())
      systems.push_back({{"name", s.name}, {"samples", s.samples}, {"min_ms", s.min_ms}, {"mean_ms", s.mean_ms},
                         {"p95_ms", s.p95_ms}, {"max_ms", s.max_ms}});
    summary["systems"] = systems;
    summary["mp4"] = mp4 ? nlohmann::json("crowd.mp4") : nlohmann::json(nullptr);
    // The paper's Table 1, one row per body level. Measured after everything above (state_hash included), since
    // timing the other levels walks the crowd on.
    // A profiler of its own, so the extra frames stay out of the timings reported above.
    Profiler table1_profiler(1, false);
    const std::vector<Table1Row> table1 = measure_table1(
        scene, static_cast<double>(o.frames) / simulate_render_s, o.frames, o.table1_frames, [&] {
          step(scene, dt, table1_profiler);
          render_frame(scene, renderer, camera, aspect, o.height, scratch, draw);
          renderer.read_rgba(pixels);
        });
    summary["table1"] = table1_json(table1);
    write_json_file(fs::path(o.out) / "summary.json", summary);

    std::cout << "strata crowd: " << scene.walker_count() << " walkers x " << o.frames << " frames, "
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
  } catch (const std::exception& e) {
    print_error("crowd", error_text(e));
    return 1;
  }
  return 0;
}

}  // namespace

void add_crowd_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<CrowdOptions>();
  auto* cmd = app.add_subcommand("crowd", "Simulate a crowd of walkers and render it headless (EGL) with a profile");
  add_scene_options(*cmd, o->scene);
  cmd->add_option("--frames,-f", o->frames, "Frames to simulate and render")->capture_default_str()
      ->check(whole_in(1, 100'000'000, true));
  cmd->add_option("--out,-o", o->out, "Output directory")->capture_default_str();
  cmd->add_option("--width", o->width, "Image width")->capture_default_str()->check(whole_in(1, 16384));
  cmd->add_option("--height", o->height, "Image height")->capture_default_str()->check(whole_in(1, 16384));
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
  cmd->add_option("--table1-frames", o->table1_frames,
                  "Frames timed at each body level not drawn, for the fps column of summary.json's table1 (0: none)")
      ->capture_default_str()->check(whole_in(0, 100'000, true));
  cmd->callback([o, &exit_code] { exit_code = run_crowd(*o); });
}

}  // namespace strata::cli
