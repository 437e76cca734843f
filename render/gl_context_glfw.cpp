#include "render/gl_context_glfw.h"

// epoxy must come before GLFW so GLFW does not pull in the system GL header.
#include <epoxy/gl.h>
#include <GLFW/glfw3.h>

#include <mutex>
#include <stdexcept>
#include <string>

#include "render/camera.h"
#include "render/gl_context.h"

namespace strata {

namespace {

// glfwInit/glfwTerminate are process-wide; windows share one initialisation. The last GLFW error is kept so
// a failed call can be reported with GLFW's own words instead of a bare "failed".
std::mutex g_glfw_mutex;
int g_glfw_users = 0;
std::string g_last_glfw_error;

void on_glfw_error(int code, const char* description) {
  g_last_glfw_error = "GLFW error " + std::to_string(code) + ": " + (description ? description : "");
}

void acquire_glfw() {
  std::lock_guard lock(g_glfw_mutex);
  if (g_glfw_users == 0) {
    glfwSetErrorCallback(on_glfw_error);
    g_last_glfw_error.clear();
    if (!glfwInit())
      throw std::runtime_error("window: glfwInit failed (" +
                               (g_last_glfw_error.empty() ? std::string("no display?") : g_last_glfw_error) +
                               "); on a headless machine run under xvfb-run -a");
  }
  ++g_glfw_users;
}

void release_glfw() {
  std::lock_guard lock(g_glfw_mutex);
  if (--g_glfw_users == 0) glfwTerminate();
}

}  // namespace

struct GlfwWindow::Impl {
  GLFWwindow* window = nullptr;
  WindowInput pending;
  glm::dvec2 last_cursor{0.0};
  bool have_cursor = false;
  bool ui_mouse = false, ui_keyboard = false;  // set_ui_capture

  static Impl& of(GLFWwindow* w) { return *static_cast<Impl*>(glfwGetWindowUserPointer(w)); }

  static void on_cursor(GLFWwindow* w, double x, double y) {
    Impl& self = of(w);
    const glm::dvec2 pos{x, y};
    // The first event after creation has no predecessor; a jump from (0,0) would spin the camera.
    if (self.have_cursor && !self.ui_mouse) {
      const glm::vec2 delta{pos - self.last_cursor};
      if (glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS)
        self.pending.orbit_drag += delta;
      else if (glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
               glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS)
        self.pending.pan_drag += delta;
    }
    self.last_cursor = pos;
    self.have_cursor = true;
  }

  static void on_scroll(GLFWwindow* w, double, double y) {
    if (!of(w).ui_mouse) of(w).pending.scroll += static_cast<float>(y);
  }

  static void on_mouse_button(GLFWwindow* w, int button, int action, int) {
    Impl& self = of(w);
    if (button != GLFW_MOUSE_BUTTON_LEFT) return;
    // A release always counts (a drag that started in the scene ends even over the panel); a press only when
    // the UI does not want it.
    if (action == GLFW_RELEASE) self.pending.left_released = true;
    else if (!self.ui_mouse) self.pending.left_pressed = true;
  }

  static void on_key(GLFWwindow* w, int key, int, int action, int) {
    if (action == GLFW_RELEASE) return;
    Impl& self = of(w);
    if (self.ui_keyboard) return;
    const bool press = action == GLFW_PRESS;  // repeats only step
    switch (key) {
      case GLFW_KEY_SPACE:
        if (press) self.pending.toggle_pause = !self.pending.toggle_pause;
        break;
      case GLFW_KEY_N:
        ++self.pending.single_steps;
        break;
      case GLFW_KEY_S:
        if (press) self.pending.screenshot = true;
        break;
      case GLFW_KEY_L:
        if (press) ++self.pending.level_steps;
        break;
      case GLFW_KEY_ESCAPE:
      case GLFW_KEY_Q:
        if (press) {
          self.pending.quit = true;
          glfwSetWindowShouldClose(w, GLFW_TRUE);
        }
        break;
      default:
        break;
    }
  }

  static void on_framebuffer_size(GLFWwindow* w, int, int) { of(w).pending.resized = true; }
};

GlfwWindow::GlfwWindow(const WindowOptions& options) : impl_(std::make_unique<Impl>()) {
  acquire_glfw();
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
  // The renderer draws into its own multisampled FBO and blits; the window needs neither samples nor depth.
  glfwWindowHint(GLFW_SAMPLES, 0);
  glfwWindowHint(GLFW_DEPTH_BITS, 0);
  glfwWindowHint(GLFW_STENCIL_BITS, 0);
  GLFWwindow* window = glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
  if (!window) {
    const std::string reason = g_last_glfw_error;
    release_glfw();
    throw std::runtime_error("window: cannot create a " + std::to_string(options.width) + "x" +
                             std::to_string(options.height) + " GL 4.5 core window (" + reason + ")");
  }
  impl_->window = window;
  pin_gl_driver_libraries();
  glfwSetWindowUserPointer(window, impl_.get());
  glfwSetCursorPosCallback(window, Impl::on_cursor);
  glfwSetScrollCallback(window, Impl::on_scroll);
  glfwSetMouseButtonCallback(window, Impl::on_mouse_button);
  glfwSetKeyCallback(window, Impl::on_key);
  glfwSetFramebufferSizeCallback(window, Impl::on_framebuffer_size);
  make_current();
  glfwSwapInterval(options.vsync ? 1 : 0);
}

GlfwWindow::~GlfwWindow() {
  if (impl_ && impl_->window) {
    glfwDestroyWindow(impl_->window);
    release_glfw();
  }
}

void GlfwWindow::make_current() { glfwMakeContextCurrent(impl_->window); }
void GlfwWindow::swap_buffers() { glfwSwapBuffers(impl_->window); }

WindowInput GlfwWindow::poll_events() {
  glfwPollEvents();
  WindowInput out = impl_->pending;
  impl_->pending = {};
  GLFWwindow* w = impl_->window;
  if (glfwWindowShouldClose(w)) out.quit = true;
  double x = 0.0, y = 0.0;
  glfwGetCursorPos(w, &x, &y);
  out.cursor = {static_cast<float>(x), static_cast<float>(y)};
  out.left_down = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  out.shift = glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS || glfwGetKey(w, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
  out.ctrl = glfwGetKey(w, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS || glfwGetKey(w, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS;
  out.alt = glfwGetKey(w, GLFW_KEY_LEFT_ALT) == GLFW_PRESS || glfwGetKey(w, GLFW_KEY_RIGHT_ALT) == GLFW_PRESS;
  return out;
}

void GlfwWindow::set_ui_capture(bool mouse, bool keyboard) {
  impl_->ui_mouse = mouse;
  impl_->ui_keyboard = keyboard;
}

void* GlfwWindow::native_handle() const { return impl_->window; }

bool GlfwWindow::should_close() const { return glfwWindowShouldClose(impl_->window) == GLFW_TRUE; }
void GlfwWindow::request_close() { glfwSetWindowShouldClose(impl_->window, GLFW_TRUE); }

glm::ivec2 GlfwWindow::framebuffer_size() const {
  glm::ivec2 size{0};
  glfwGetFramebufferSize(impl_->window, &size.x, &size.y);
  return size;
}

glm::ivec2 GlfwWindow::window_size() const {
  glm::ivec2 size{0};
  glfwGetWindowSize(impl_->window, &size.x, &size.y);
  return size;
}

void apply_camera_input(const WindowInput& input, float window_height, OrbitCamera& camera) {
  if (input.orbit_drag.x != 0.0f || input.orbit_drag.y != 0.0f)
    camera.orbit(input.orbit_drag.x, input.orbit_drag.y, window_height);
  if (input.pan_drag.x != 0.0f || input.pan_drag.y != 0.0f)
    camera.pan(input.pan_drag.x, input.pan_drag.y, window_height);
  if (input.scroll != 0.0f) camera.zoom(input.scroll);
}

}  // namespace strata
