#pragma once
// A GLFW window with a GL 4.5 core context, for `strata view`. GLFW stays out of this header (it is a private
// dependency of the library): the window reports what the user did since the last poll in a WindowInput, and
// the app applies it (apply_camera_input for the orbit camera, the flags for its own loop).
//
// GLFW 3.3 needs a display; on a headless machine run under `xvfb-run -a` (a hidden window works there too).
// GLFW allows window calls from the main thread only; so does this class.
#include <memory>
#include <string>

#include <glm/vec2.hpp>

#include "render/gl_context.h"

namespace strata {

struct OrbitCamera;

struct WindowOptions {
  int width = 1280;
  int height = 720;
  std::string title = "Strata";
  bool visible = true;
  bool vsync = true;
};

// Everything that happened since the previous poll_events(). Drag deltas are in window coordinates (y down).
struct WindowInput {
  glm::vec2 orbit_drag{0.0f};   // left button held
  glm::vec2 pan_drag{0.0f};     // right or middle button held
  float scroll = 0.0f;          // wheel steps, positive = away from the user (zoom in)
  bool toggle_pause = false;    // Space; an even number of presses cancels out
  int single_steps = 0;         // N presses (key repeat counts)
  bool screenshot = false;      // S
  int level_steps = 0;          // L presses: next body level (0, 1, 2, S1, S2, S3, back to 0)
  bool quit = false;            // Esc, Q or the window's close button
  bool resized = false;         // framebuffer size changed
  // The mouse as the binding editor needs it (window coordinates, y down). Presses and releases that the UI
  // captured are not reported.
  glm::vec2 cursor{0.0f};
  bool left_down = false;       // left button held now
  bool left_pressed = false;    // pressed since the previous poll
  bool left_released = false;   // released since the previous poll
  bool shift = false, ctrl = false, alt = false;  // modifiers held now
};

class GlfwWindow final : public GlContext {
 public:
  // Creates the window and makes its context current. Throws std::runtime_error with GLFW's reason (e.g. no
  // display).
  explicit GlfwWindow(const WindowOptions& options = {});
  ~GlfwWindow() override;
  GlfwWindow(const GlfwWindow&) = delete;
  GlfwWindow& operator=(const GlfwWindow&) = delete;

  void make_current() override;
  void swap_buffers();
  // Processes pending events and returns what they amounted to since the previous call.
  WindowInput poll_events();
  bool should_close() const;
  void request_close();
  glm::ivec2 framebuffer_size() const;  // pixels; differs from window_size on HiDPI screens
  glm::ivec2 window_size() const;       // screen coordinates, the unit of WindowInput's drags
  // While the UI drawn over the scene (the viewer's Dear ImGui panel) wants the mouse or the keyboard, the
  // window stops turning those events into camera drags and shortcuts; the app sets this once per frame from the
  // UI's own verdict. Filtering here rather than in the app keeps a drag that started on a slider from also
  // orbiting the camera.
  void set_ui_capture(bool mouse, bool keyboard);
  // The GLFWwindow*, for a UI backend that attaches its own callbacks (they chain to this window's).
  void* native_handle() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Applies the drags and scroll of `input` to `camera` (OrbitCamera::orbit / pan / zoom), scaled by the window
// height in screen coordinates.
void apply_camera_input(const WindowInput& input, float window_height, OrbitCamera& camera);

}  // namespace strata
