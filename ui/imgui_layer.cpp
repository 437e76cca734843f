#include "ui/imgui_layer.h"

#include <epoxy/gl.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <stdexcept>

namespace strata {

struct ImGuiLayer::Impl {
  ImGuiContext* context = nullptr;
  GLFWwindow* window = nullptr;
  bool glfw_backend = false, gl_backend = false;
};

ImGuiLayer::ImGuiLayer(void* glfw_window) : impl_(std::make_unique<Impl>()) {
  if (ImGui::GetCurrentContext() != nullptr) throw std::runtime_error("ui: an ImGui layer already exists");
  IMGUI_CHECKVERSION();
  impl_->context = ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;
  io.LogFilename = nullptr;
  ImGui::StyleColorsDark();
  ImGui::GetStyle().WindowRounding = 4.0f;
  impl_->window = static_cast<GLFWwindow*>(glfw_window);
  if (impl_->window) {
    impl_->glfw_backend = ImGui_ImplGlfw_InitForOpenGL(impl_->window, true);
    if (!impl_->glfw_backend) {
      ImGui::DestroyContext(impl_->context);
      throw std::runtime_error("ui: ImGui's GLFW backend did not start");
    }
  }
  // "#version 410 core": the backend's shaders need nothing newer, and the renderer's 4.5 context runs them.
  impl_->gl_backend = ImGui_ImplOpenGL3_Init("#version 410 core");
  if (!impl_->gl_backend) {
    if (impl_->glfw_backend) ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext(impl_->context);
    throw std::runtime_error("ui: ImGui's OpenGL 3 backend did not start (no libGL.so.1 to load GL from?)");
  }
}

ImGuiLayer::~ImGuiLayer() {
  ImGui_ImplOpenGL3_Shutdown();
  if (impl_->glfw_backend) ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext(impl_->context);
}

void ImGuiLayer::begin_frame(const UiFrameInput& input) {
  ImGui_ImplOpenGL3_NewFrame();
  if (impl_->glfw_backend) {
    ImGui_ImplGlfw_NewFrame();
  } else {
    // ImGui 1.86 (Debian 12) reads the mouse from these fields; the event queue API came in 1.87.
    ImGuiIO& io = ImGui::GetIO();
    io.DisplaySize = ImVec2(input.display_size.x, input.display_size.y);
    io.DisplayFramebufferScale = ImVec2(1.0f, 1.0f);
    io.DeltaTime = input.dt > 0.0f ? input.dt : 1.0f / 60.0f;
    io.MousePos = input.mouse.x < 0.0f ? ImVec2(-FLT_MAX, -FLT_MAX) : ImVec2(input.mouse.x, input.mouse.y);
    io.MouseDown[0] = input.left_down;
    io.MouseWheel = input.wheel;
  }
  ImGui::NewFrame();
}

void ImGuiLayer::render(glm::ivec2 framebuffer_size, unsigned framebuffer) {
  ImGui::Render();
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  glViewport(0, 0, framebuffer_size.x, framebuffer_size.y);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

bool ImGuiLayer::wants_mouse() const { return ImGui::GetIO().WantCaptureMouse; }
bool ImGuiLayer::wants_keyboard() const { return ImGui::GetIO().WantCaptureKeyboard; }

}  // namespace strata
