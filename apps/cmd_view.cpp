// strata view: the crowd scene in a GLFW window with an orbit camera and a Dear ImGui control panel
// (ui/view_panel.h: crowd size, level policy, gait, muscle gains, live per-system timing chart, pause/step,
// screenshot). Left-drag orbits, right/middle-drag pans, the wheel zooms; Space pauses, N single-steps, S saves a
// screenshot, L cycles the body level (0, 1, 2, auto, S1, S2, S3), Esc/Q quits. The live per-system timings also
// go to stderr; the full table prints on exit.
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <span>
#include <sstream>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/scene_options.h"
#include "render/scene_draw.h"
#include "ui/view_session.h"
#include "io/image_writer.h"
#include "profiling/profiler.h"
#include "render/camera.h"
#include "render/gl_context.h"
#include "render/gl_context_glfw.h"
#include "render/crowd_renderer.h"
#include "scene/crowd.h"
#include "systems/pose_gather.h"
#include "ui/imgui_layer.h"
#include "ui/view_panel.h"
#include "scene/body_settings.h"
#include "scene/step.h"

namespace strata::cli {
namespace {

struct ViewOptions {
  SceneOptions scene;
  RenderQuality quality = RenderQuality::High;
  int width = 1280;
  int height = 720;
  std::size_t frames = 0;  // 0 = until the window closes
  bool hidden = false;
  std::string screenshot_dir = "out/view";
  bool skeleton_overlay = false;
  bool no_panel = false;
  std::string headless_png;  // render without a window (EGL) and save the last frame, panel included
  std::string tab;           // panel tab to open first
  std::string edit_joint;    // start the binding editor showing this joint's weights
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

// Draws the session's scene from `camera` (bodies in the binding editor's colours while it runs) and hands the
// camera to culling and --level auto for the next frame (render_frame, the render half of every command's frame).
void render_scene(ViewSession& session, CrowdRenderer& renderer, const OrbitCamera& camera, float aspect,
                  int viewport_height, RenderScratch& scratch) {
  ViewPanelState& panel = session.panel();
  RenderFrameOptions options;
  options.skeleton_overlay = panel.show_skeleton;
  renderer.options().quality = panel.high_quality ? RenderQuality::High : RenderQuality::Low;
  options.recolour = [&session](std::vector<BodyDrawInput>& bodies) { session.colour_draws(bodies); };
  panel.triangles_drawn = render_frame(session.scene(), renderer, camera, aspect, viewport_height, scratch, options);
}

// Frames per second from the profiler's rolling mean frame time; 0 before the first frame.
float mean_fps(const Profiler& profiler) {
  for (const SystemStats& s : profiler.stats())
    if (s.name == "frame" && s.mean_ms > 0) return static_cast<float>(1000.0 / s.mean_ms);
  return 0.0f;
}

// Applies --tab and --edit-binding to a new session.
void apply_start_options(const ViewOptions& o, ViewSession& session) {
  ViewPanelState& panel = session.panel();
  panel.select_tab = o.tab;
  panel.show_skeleton = o.skeleton_overlay;
  panel.high_quality = o.quality == RenderQuality::High;
  if (o.edit_joint.empty()) return;
  const int joint = session.scene().rig().skeleton.find_joint(o.edit_joint);
  if (joint < 0) throw std::invalid_argument("--edit-binding: no joint '" + o.edit_joint + "' in the skeleton");
  panel.binding.activate_requested = true;
  session.apply_binding_requests();
  panel.binding.joint = joint;
  if (o.tab.empty()) panel.select_tab = "Binding";
}

// The viewer without a window: the same session, scene and panel drawn through EGL into the renderer's output,
// for pictures of the tool (docs/commands.md) and for checking the panel on machines without a display.
int run_view_headless(const ViewOptions& o) {
  if (!check_outputs("view", {{"--headless-png", o.headless_png}})) return kExitFailure;
  try {
    check_scene_inputs(o.scene);
    ViewSession session(o.scene);
    apply_start_options(o, session);
    std::unique_ptr<GlContext> context = create_headless_gl_context();
    CrowdRenderer renderer(o.width, o.height);  // its quality follows the panel (render_scene)
    std::optional<ImGuiLayer> ui;
    if (!o.no_panel) ui.emplace();
    Profiler profiler(120, false);
    OrbitCamera camera;
    const float aspect = static_cast<float>(o.width) / static_cast<float>(o.height);
    RenderScratch scratch;
    std::vector<glm::vec3>& joints = scratch.joints;
    const std::size_t frames = o.frames ? o.frames : 30;
    ViewPanelState& panel = session.panel();
    for (std::size_t f = 0; f < frames; ++f) {
      session.apply_binding_requests();
      Crowd& scene = session.scene();
      profiler.begin_frame();
      {
        STRATA_PROFILE_SCOPE(profiler, "frame");
        session.advance(1.0f / 30.0f, profiler);
        STRATA_PROFILE_SCOPE(profiler, "render");
        gather_crowd_joints(scene, joints);
        glm::vec3 lo, hi;
        if (f == 0 && (body_bounds(scene, lo, hi) || joint_bounds(joints, lo, hi))) camera.frame_box(lo, hi, aspect);
        render_scene(session, renderer, camera, aspect, o.height, scratch);
        if (ui) {
          STRATA_PROFILE_SCOPE(profiler, "ui");
          UiFrameInput in;
          in.display_size = {static_cast<float>(o.width), static_cast<float>(o.height)};
          ui->begin_frame(in);
          draw_view_panel(scene, panel);
          ui->render({o.width, o.height}, renderer.output_framebuffer());
        }
      }
      profiler.end_frame();
      panel.timings.push(profiler);
      panel.fps = mean_fps(profiler);
    }
    std::vector<std::uint8_t> pixels;
    renderer.read_rgba(pixels);
    write_image(o.headless_png, renderer.width(), renderer.height(), 4, pixels);
    std::cout << "strata view: " << frames << " frames, " << session.scene().walker_count() << " walkers, saved "
              << o.headless_png << "\n";
  } catch (const std::exception& e) {
    print_error("view", error_text(e));
    return 1;
  }
  return 0;
}

int run_view(const ViewOptions& o) {
  if (!check_outputs("view", {{"--screenshot-dir", o.screenshot_dir, true}})) return kExitFailure;
  const int threads = thread_count(o.scene);
  tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  try {
    check_scene_inputs(o.scene);
    ViewSession session(o.scene);
    apply_start_options(o, session);
    ViewPanelState& panel = session.panel();

    WindowOptions wo;
    wo.width = o.width;
    wo.height = o.height;
    wo.visible = !o.hidden;
    GlfwWindow window(wo);
    glm::ivec2 fb = window.framebuffer_size();
    CrowdRenderer renderer(fb.x, fb.y);  // its quality follows the panel (render_scene)
    // The panel attaches to the window's callbacks; --no-panel leaves the scene alone on screen.
    std::optional<ImGuiLayer> ui;
    if (!o.no_panel) ui.emplace(window.native_handle());
    Profiler profiler(120, false);
    OrbitCamera camera;
    RenderScratch scratch;
    std::vector<glm::vec3>& joints = scratch.joints;
    std::vector<std::uint8_t> pixels;
    bool framed = false;
    std::size_t frame = 0, screenshots = 0;
    auto last = std::chrono::steady_clock::now();
    auto title_time = last;
    const bool live_status = stderr_is_terminal();

    while (!window.should_close() && (o.frames == 0 || frame < o.frames)) {
      WindowInput input = window.poll_events();
      if (input.quit) break;
      // The keys and the panel's buttons drive the same state.
      if (input.toggle_pause) panel.paused = !panel.paused;
      panel.step_requests += input.single_steps;
      panel.screenshot_requested |= input.screenshot;
      if (session.apply_crowd_request()) framed = false;
      session.apply_binding_requests();
      const bool editing = panel.binding.active;
      // Editing: the left button selects; Alt+left still orbits.
      if (editing && !input.alt) input.orbit_drag = glm::vec2(0.0f);
      Crowd& scene = session.scene();
      if (input.level_steps > 0 && !scene.skin.level.is_none()) {
        const std::vector<DetailLevel> levels = selectable_body_levels(scene);
        if (!levels.empty()) {
          const auto at = std::find(levels.begin(), levels.end(), scene.skin.level);
          const std::size_t from = at == levels.end() ? 0 : static_cast<std::size_t>(at - levels.begin());
          set_detail_level(scene, levels[(from + static_cast<std::size_t>(input.level_steps)) % levels.size()]);
          step(scene, 0.0f, profiler);  // fill the new level's output before it is drawn
          std::cout << "strata view: body level " << scene.skin.level.name() << "\n";
        }
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
        const DetailLevel level_before = scene.skin.level;
        session.advance(dt, profiler);
        STRATA_PROFILE_SCOPE(profiler, "render");
        gather_crowd_joints(scene, joints, /*include_culled=*/true);  // framing reaches walkers out of view
        if (!framed || panel.frame_camera_requested) {
          glm::vec3 lo, hi;
          if (joint_bounds(joints, lo, hi)) camera.frame_box(lo, hi, aspect);
          framed = true;
          panel.frame_camera_requested = false;
        }
        if (editing) {
          // The mouse in framebuffer pixels (they differ from window units on HiDPI screens).
          const glm::ivec2 ws = window.window_size();
          const glm::vec2 scale{ws.x > 0 ? static_cast<float>(fb.x) / static_cast<float>(ws.x) : 1.0f,
                                ws.y > 0 ? static_cast<float>(fb.y) / static_cast<float>(ws.y) : 1.0f};
          EditorMouse mouse;
          mouse.cursor = input.cursor * scale;
          mouse.pressed = input.left_pressed && !input.alt;
          mouse.released = input.left_released;
          mouse.down = input.left_down;
          mouse.shift = input.shift;
          mouse.ctrl = input.ctrl;
          session.binding_mouse(mouse, camera.projection(aspect) * camera.view(), fb);
          panel.binding.pixels_per_unit = scale;  // the outline is drawn in window units
        }
        render_scene(session, renderer, camera, aspect, fb.y, scratch);
        if (panel.screenshot_requested) {
          panel.screenshot_requested = false;
          // The scene without the panel: a screenshot is for showing the crowd, not the tool.
          renderer.read_rgba(pixels);
          std::filesystem::create_directories(o.screenshot_dir);
          char name[40];
          std::snprintf(name, sizeof name, "screenshot_%03zu.png", screenshots++);
          auto path = std::filesystem::path(o.screenshot_dir) / name;
          write_image(path, renderer.width(), renderer.height(), 4, pixels);
          panel.last_message = "saved " + path.string();
          std::cout << "strata view: " << panel.last_message << "\n";
        }
        renderer.blit_to_default_framebuffer(fb.x, fb.y);
        if (ui) {
          STRATA_PROFILE_SCOPE(profiler, "ui");
          ui->begin_frame();
          draw_view_panel(scene, panel);
          ui->render(fb);
          window.set_ui_capture(ui->wants_mouse(), ui->wants_keyboard());
        }
        // A level picked in the panel is skinned on the next frame; fill it now so nothing blinks.
        if (scene.skin.level != level_before) step(scene, 0.0f, profiler);
        window.swap_buffers();
      }
      profiler.end_frame();
      panel.timings.push(profiler);
      ++frame;
      if (now - title_time > std::chrono::milliseconds(500)) {
        panel.fps = mean_fps(profiler);
        // A line that rewrites itself only on a terminal; in a log the '\r' lines would pile up, and the table
        // printed on exit has the same numbers.
        if (live_status) std::fprintf(stderr, "\r%s   ", timing_title(profiler, panel.fps).c_str());
        title_time = now;
      }
    }
    if (live_status) std::fputc('\n', stderr);
    std::cout << "strata view: " << frame << " frames, " << session.scene().walker_count() << " walkers\n";
    profiler.print_table(std::cout);
  } catch (const std::exception& e) {
    print_error("view", error_text(e));
    return 1;
  }
  return 0;
}

}  // namespace

void add_view_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ViewOptions>();
  auto* cmd = app.add_subcommand("view", "Open the crowd in a window with an orbit camera (needs a display)");
  add_scene_options(*cmd, o->scene);
  add_quality_option(*cmd, o->quality);
  cmd->add_option("--width", o->width, "Window width")->capture_default_str()->check(whole_in(1, 16384));
  cmd->add_option("--height", o->height, "Window height")->capture_default_str()->check(whole_in(1, 16384));
  cmd->add_option("--frames", o->frames, "Quit after F frames (0 = run until closed)")->capture_default_str()
      ->check(whole_in(0, 1e9, true));
  cmd->add_flag("--hidden", o->hidden, "Create the window hidden (smoke tests under Xvfb)");
  cmd->add_flag("--no-panel", o->no_panel, "Hide the control panel (crowd, levels, gait, muscles, timings)");
  cmd->add_flag("--skeleton-overlay", o->skeleton_overlay, "Draw the skeletons too when bodies are drawn");
  cmd->add_option("--screenshot-dir", o->screenshot_dir, "Where S saves PNG screenshots")->capture_default_str();
  cmd->add_option("--headless-png", o->headless_png,
                  "No window: render --frames frames (default 30) through EGL and save the last, panel included");
  cmd->add_option("--tab", o->tab, "Panel tab to open first: Crowd, Gait, Muscles, Timings or Binding")
      ->check(CLI::IsMember({"Crowd", "Gait", "Muscles", "Timings", "Binding"}));
  cmd->add_option("--edit-binding", o->edit_joint, "Start the binding editor showing this joint's weights");
  cmd->callback([o, &exit_code] {
    if (!o->headless_png.empty()) {
      const int threads = thread_count(o->scene);
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
      exit_code = run_view_headless(*o);
    } else {
      exit_code = run_view(*o);
    }
  });
}

}  // namespace strata::cli
