#pragma once
// Dear ImGui over the renderer: one ImGui context drawn with the library's OpenGL 3 backend into whatever
// framebuffer is bound (the window's, after the scene was blitted there, so screenshots of the scene stay free of
// the panel). Input comes either from a GLFW window (ImGui's GLFW backend, chained to the window's own callbacks)
// or, headless, from UiFrameInput, which is how the tests drive the panel with a scripted mouse.
//
// Why a separate static library (strata_ui) rather than part of libstrata: only the viewer and its tests need a
// GUI, and programs using Strata as a library should not inherit Dear ImGui and its GLFW backend.
#include <memory>

#include <glm/vec2.hpp>

namespace strata {

// A scripted frame of input for a layer without a window (tests): window coordinates, y down.
struct UiFrameInput {
  glm::vec2 display_size{1280.0f, 720.0f};
  glm::vec2 mouse{-1.0f, -1.0f};  // negative: no mouse
  bool left_down = false;
  float wheel = 0.0f;
  float dt = 1.0f / 60.0f;
};

class ImGuiLayer {
 public:
  // Needs a current GL 3.2+ core context. `glfw_window` (a GLFWwindow*, GlfwWindow::native_handle()) or
  // nullptr for scripted input. Writes no imgui.ini: the panel's layout is the code's, not a file beside the
  // user's working directory. Throws std::runtime_error when the GL backend cannot start. One layer at a time.
  explicit ImGuiLayer(void* glfw_window = nullptr);
  ~ImGuiLayer();
  ImGuiLayer(const ImGuiLayer&) = delete;
  ImGuiLayer& operator=(const ImGuiLayer&) = delete;

  // Starts a UI frame: from the window's state, or from `input` when the layer has no window.
  void begin_frame(const UiFrameInput& input = {});
  // Ends the frame and draws it into `framebuffer` (0: the window's) of `framebuffer_size` pixels, over what is
  // there.
  void render(glm::ivec2 framebuffer_size, unsigned framebuffer = 0);
  // What the UI claimed in the last frame: the window should not turn those events into camera moves.
  bool wants_mouse() const;
  bool wants_keyboard() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace strata
