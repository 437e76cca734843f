#pragma once
// The control panel of `strata view` (Dear ImGui, immediate mode): crowd size, level policy, gait, muscle
// gains, a live per-system timing chart, pause/step, screenshot. Changes that the scene can take at run time
// (level, level-of-detail policy, gait style, muscle gains) go straight into the Crowd; those that need the
// app (a new crowd, a screenshot, stepping, the camera) are requests in ViewPanelState, which the app clears once
// handled.
#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

#include "components/detail_level.h"

namespace strata {

struct Crowd;
class Profiler;

// The last `capacity` frames of every profiled system's time (ms), for the chart. Fed once per frame after
// Profiler::end_frame from its rolling statistics' last sample.
class TimingHistory {
 public:
  explicit TimingHistory(std::size_t capacity = 240);
  void push(const Profiler& profiler);
  struct Series {
    std::string name;
    std::vector<float> ms;  // oldest first, at most capacity
    double mean_ms = 0.0, p95_ms = 0.0;
  };
  const std::vector<Series>& series() const { return series_; }
  std::size_t capacity() const { return capacity_; }

 private:
  std::size_t capacity_;
  std::vector<Series> series_;
};

// Where the panel's named widgets were drawn in the last frame (window coordinates), for scripted input: tests
// click "Pause" by its rectangle instead of by a hard-coded pixel that a font or style change would move.
struct UiProbe {
  std::map<std::string, std::array<glm::vec2, 2>> rects;  // label -> {min, max}
  glm::vec2 centre(const std::string& label) const;       // throws std::out_of_range for an unknown label
};

// The binding editor's controls (the panel's "Binding" tab); ViewSession acts on the requests and fills in the
// counts.
struct BindingEditState {
  enum class Tool : std::uint8_t { Click, Box, Brush };
  bool active = false;            // edit mode: left-drag selects (Alt+left-drag orbits), weights shown
  bool activate_requested = false, deactivate_requested = false;
  Tool tool = Tool::Click;
  float brush_radius_px = 24.0f;
  bool select_through = false;    // box and brush also take vertices hidden behind the surface
  bool rest_pose = false;         // edit on walkers standing in the rest pose instead of walking
  int joint = -1;                 // joint to bind to, and whose weights are shown; -1 until chosen
  bool show_weights = true;
  bool bind_requested = false, undo_requested = false, clear_requested = false, save_requested = false;
  std::string save_path = "binding_overrides.json";
  // Filled in by ViewSession.
  int level = -1;                 // mesh level being edited
  std::size_t selected = 0, edits = 0;
  // The drag in progress (framebuffer pixels), for the panel to draw the box or brush outline; pixels_per_unit
  // converts to the window units ImGui draws in (they differ on HiDPI screens).
  bool dragging = false;
  glm::vec2 drag_from{0.0f}, cursor{0.0f};
  glm::vec2 pixels_per_unit{1.0f};
};

struct ViewPanelState {
  // Playback.
  bool paused = false;
  int step_requests = 0;          // single steps asked for while paused
  float time_scale = 1.0f;        // simulation seconds per real second
  bool screenshot_requested = false;
  bool frame_camera_requested = false;
  bool show_skeleton = false;
  bool high_quality = true;       // RenderQuality::High (sun, shadows, clothes); off: the low-quality headlight
  // Crowd: a new crowd of `walkers` with `seed` when rebuild_requested.
  int walkers = 25;
  int seed = 1;
  bool rebuild_requested = false;
  // What the app reports back for display.
  std::size_t triangles_drawn = 0;
  float fps = 0.0f;
  std::string last_message;       // e.g. "saved out/view/screenshot_000.png"
  TimingHistory timings;
  BindingEditState binding;
  std::string select_tab;         // a tab to bring to the front on the next frame ("Crowd", "Binding", ...)
};

// Draws the panel for this frame (between ImGuiLayer::begin_frame and render). `probe`, when given, records
// the widgets' rectangles.
void draw_view_panel(Crowd& scene, ViewPanelState& state, UiProbe* probe = nullptr);

// The body levels a scene can show, in the order the panel and the L key cycle them: its meshes, auto, and
// S1..S3 when the body has a subdivision cage. Empty without a body.
std::vector<DetailLevel> selectable_body_levels(const Crowd& scene);

}  // namespace strata
