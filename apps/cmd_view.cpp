// strata view: the crowd scene in a GLFW window with an orbit camera. Left-drag orbits, right/middle-drag pans,
// the wheel zooms; Space pauses, N single-steps, S saves a screenshot, L cycles the body level (0, 1, 2, auto, S1, S2,
// S3), Esc/Q quits. The window title carries
// the live per-system timings; the full table prints on exit.
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "apps/commands.h"
#include "apps/crowd_setup.h"
#include "io/image_writer.h"
#include "profiling/profiler.h"
#include "render/camera.h"
#include "render/gl_context_glfw.h"
#include "render/skeleton_renderer.h"
#include "systems/frame_script.h"
#include "systems/pose_gather.h"

namespace strata::cli {
namespace {

struct ViewOptions {
  SceneOptions scene;
  int width = 1280;
  int height = 720;
  std::size_t frames = 0;  // 0 = until the window closes
  bool hidden = false;
  std::string screenshot_dir = "out/view";
  bool skeleton_overlay = false;
};

std::string timing_title(const Profiler& profiler, double fps) {
  std::ostringstream title;
  title.setf(std::ios::fixed);
  title.precision(1);
  title << "Strata view - " << fps << " fps";
  title.precision(2);
  for (const SystemStats& s : profiler.stats())
    if (s.name != "frame") title << " | " << s.name << " " << s.mean_ms << " ms";
  return title.str();
}

int run_view(const ViewOptions& o) {
  const int threads = thread_count(o.scene);
  tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  try {
    std::unique_ptr<CrowdScene> built = build_scene(o.scene);
    CrowdScene& scene = *built;

    WindowOptions wo;
    wo.width = o.width;
    wo.height = o.height;
    wo.visible = !o.hidden;
    GlfwWindow window(wo);
    glm::ivec2 fb = window.framebuffer_size();
    SkeletonRenderer renderer(fb.x, fb.y);
    Profiler profiler(120, false);
    OrbitCamera camera;
    std::vector<glm::vec3> joints;
    std::vector<std::uint8_t> pixels;
    bool paused = false;
    bool show_skeleton = o.skeleton_overlay;
    bool framed = false;
    std::size_t frame = 0, screenshots = 0;
    auto last = std::chrono::steady_clock::now();
    auto title_time = last;

    while (!window.should_close() && (o.frames == 0 || frame < o.frames)) {
      WindowInput input = window.poll_events();
      if (input.quit) break;
      if (input.toggle_pause) paused = !paused;
      if (input.level_steps > 0 && scene.body_level() >= 0) {
        // The levels this body has: its meshes, automatic, then S1..S3 when it has a cage.
        std::vector<int> levels;
        for (std::size_t l = 0; l < scene.rig().body->levels.size(); ++l) levels.push_back(static_cast<int>(l));
        levels.push_back(kAutoBodyLevel);
        if (scene.rig().body->cage)
          for (int d = 1; d <= kMaxSubdivDepth; ++d) levels.push_back(subdiv_level(d));
        const auto at = std::find(levels.begin(), levels.end(), scene.body_level());
        const std::size_t from = at == levels.end() ? 0 : static_cast<std::size_t>(at - levels.begin());
        scene.set_body_level(levels[(from + static_cast<std::size_t>(input.level_steps)) % levels.size()]);
        scene.simulate(0.0f, profiler);  // fill the new level's output before it is drawn
        std::cout << "strata view: body level " << body_level_name(scene.body_level()) << "\n";
      }
      if (input.resized) {
        fb = window.framebuffer_size();
        if (fb.x > 0 && fb.y > 0) renderer.resize(fb.x, fb.y);
      }
      apply_camera_input(input, static_cast<float>(window.window_size().y), camera);
      auto now = std::chrono::steady_clock::now();
      // Real time, capped so a stall (a drag, a debugger) does not fling the clock forward.
      const float dt = std::min(std::chrono::duration<float>(now - last).count(), 0.1f);
      last = now;
      const float aspect = fb.y > 0 ? static_cast<float>(fb.x) / static_cast<float>(fb.y) : 1.0f;

      profiler.begin_frame();
      {
        STRATA_PROFILE_SCOPE(profiler, "frame");
        if (!paused || input.single_steps > 0 || !framed) {
          const int steps = paused ? std::max(input.single_steps, framed ? 0 : 1) : 1;
          for (int s = 0; s < steps; ++s) scene.simulate(paused ? 1.0f / 30.0f : dt, profiler);
        }
        STRATA_PROFILE_SCOPE(profiler, "render");
        gather_joint_positions(scene.lanes(), joints);
        if (!framed) {
          glm::vec3 lo, hi;
          if (joint_bounds(joints, lo, hi)) camera.frame_box(lo, hi, aspect);
          framed = true;
        }
        SkeletonDrawInput draw{&scene.rig().skeleton, joints, scene.walker_count()};
        const std::vector<BodyDrawInput> bodies = body_draw_inputs(scene);
        renderer.options().draw_skeleton = bodies.empty() || show_skeleton;
        renderer.render(draw, camera.view(), camera.projection(aspect), bodies);
        scene.set_view(lod_view(camera, aspect, fb.y));  // culling and --level auto follow the orbit camera
        if (input.screenshot) {
          renderer.read_rgba(pixels);
          std::filesystem::create_directories(o.screenshot_dir);
          char name[40];
          std::snprintf(name, sizeof name, "screenshot_%03zu.png", screenshots++);
          auto path = std::filesystem::path(o.screenshot_dir) / name;
          write_image(path, renderer.width(), renderer.height(), 4, pixels);
          std::cout << "strata view: saved " << path.string() << "\n";
        }
        renderer.blit_to_default_framebuffer(fb.x, fb.y);
        window.swap_buffers();
      }
      profiler.end_frame();
      ++frame;
      if (now - title_time > std::chrono::milliseconds(500)) {
        auto stats = profiler.stats();
        double frame_ms = 0;
        for (const auto& s : stats)
          if (s.name == "frame") frame_ms = s.mean_ms;
        std::fprintf(stderr, "\r%s   ", timing_title(profiler, frame_ms > 0 ? 1000.0 / frame_ms : 0.0).c_str());
        title_time = now;
      }
    }
    std::fputc('\n', stderr);
    std::cout << "strata view: " << frame << " frames, " << scene.walker_count() << " walkers\n";
    profiler.print_table(std::cout);
  } catch (const std::exception& e) {
    std::cerr << "strata view: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

void add_view_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ViewOptions>();
  auto* cmd = app.add_subcommand("view", "Open the crowd in a window with an orbit camera (needs a display)");
  add_scene_options(*cmd, o->scene);
  cmd->add_option("--width", o->width, "Window width")->capture_default_str();
  cmd->add_option("--height", o->height, "Window height")->capture_default_str();
  cmd->add_option("--frames", o->frames, "Quit after F frames (0 = run until closed)")->capture_default_str();
  cmd->add_flag("--hidden", o->hidden, "Create the window hidden (smoke tests under Xvfb)");
  cmd->add_flag("--skeleton-overlay", o->skeleton_overlay, "Draw the skeletons too when bodies are drawn");
  cmd->add_option("--screenshot-dir", o->screenshot_dir, "Where S saves PNG screenshots")->capture_default_str();
  cmd->callback([o, &exit_code] { exit_code = run_view(*o); });
}

}  // namespace strata::cli
