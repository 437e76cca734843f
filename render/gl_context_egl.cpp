// Headless GL 4.5 core context through EGL, with no window system at all.
//
// Route order: the surfaceless Mesa platform first (llvmpipe or a Mesa GPU driver, works with DISPLAY unset),
// then the EGL device platform, which is how NVIDIA's EGL exposes a GPU without X. eglGetDisplay(DEFAULT) was
// rejected as a route: with DISPLAY unset it needs EGL_PLATFORM=surfaceless in the environment, and with
// DISPLAY set it ties a "headless" context to the X server.
#include <epoxy/egl.h>
#include <epoxy/gl.h>
#if defined(STRATA_ASAN)
#include <dlfcn.h>
#include <link.h>
#endif

#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/gl_context.h"

namespace strata {

std::string GlContext::renderer() const {
  const GLubyte* s = glGetString(GL_RENDERER);
  return s ? reinterpret_cast<const char*>(s) : std::string{};
}

GlContext::Limits GlContext::limits() const {
  Limits l;
  GLint viewport[2] = {0, 0};
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &l.max_renderbuffer_size);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, viewport);
  glGetIntegerv(GL_MAX_SAMPLES, &l.max_samples);
  l.max_viewport_width = viewport[0];
  l.max_viewport_height = viewport[1];
  return l;
}

std::string GlContext::version() const {
  const GLubyte* s = glGetString(GL_VERSION);
  return s ? reinterpret_cast<const char*>(s) : std::string{};
}

namespace {

std::string egl_error_text(const char* call) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s failed (EGL error 0x%04X)", call, static_cast<unsigned>(eglGetError()));
  return buf;
}

// EGL displays are per-process singletons per (platform, native display): a second context on the same display
// gets the same EGLDisplay, and eglTerminate from one owner would pull it from under the other. Reference
// counting the initialisations keeps two live contexts independent.
class DisplayRegistry {
 public:
  void acquire(EGLDisplay dpy) {
    std::lock_guard lock(mutex_);
    ++counts_[dpy];
  }
  void release(EGLDisplay dpy) {
    std::lock_guard lock(mutex_);
    auto it = counts_.find(dpy);
    if (it == counts_.end()) return;
    if (--it->second == 0) {
      counts_.erase(it);
      eglTerminate(dpy);
    }
  }

 private:
  std::mutex mutex_;
  std::map<EGLDisplay, int> counts_;
};

DisplayRegistry& display_registry() {
  static DisplayRegistry registry;
  return registry;
}

#if defined(STRATA_ASAN)
// AddressSanitizer builds only (scripts/strata.sh sanitize): Mesa keeps a few driver allocations for the life of
// the process, and eglTerminate/exit dlclose the driver before LeakSanitizer runs, so its report shows
// "<unknown module>" frames that no suppression can name. Marking the already-loaded driver objects
// RTLD_NODELETE keeps them mapped, so the leaks are attributed to swrast_dri.so & co. and scripts/lsan.supp can
// suppress them by library. Release builds never do this.
}  // namespace
void pin_gl_driver_libraries() {
  std::vector<std::string> names;
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* out) {
        const char* n = info->dlpi_name;
        if (n && (std::strstr(n, "/dri/") || std::strstr(n, "mesa") || std::strstr(n, "gallium") ||
                  std::strstr(n, "LLVM") || std::strstr(n, "glapi")))
          static_cast<std::vector<std::string>*>(out)->emplace_back(n);
        return 0;
      },
      &names);
  for (const std::string& n : names) dlopen(n.c_str(), RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);
}
namespace {
#else
}  // namespace
void pin_gl_driver_libraries() {}
namespace {
#endif

// Returns an initialised display or EGL_NO_DISPLAY; `why` collects the reason of each route that failed.
EGLDisplay open_surfaceless_display(std::string& why) {
  if (!epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless")) {
    why += "EGL_MESA_platform_surfaceless not offered; ";
    return EGL_NO_DISPLAY;
  }
  EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (dpy == EGL_NO_DISPLAY) {
    why += egl_error_text("eglGetPlatformDisplayEXT(surfaceless)") + "; ";
    return EGL_NO_DISPLAY;
  }
  EGLint major = 0, minor = 0;
  if (!eglInitialize(dpy, &major, &minor)) {
    why += egl_error_text("eglInitialize(surfaceless)") + "; ";
    return EGL_NO_DISPLAY;
  }
  pin_gl_driver_libraries();
  return dpy;
}

EGLDisplay open_device_display(std::string& why) {
  if (!epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_device_enumeration") ||
      !epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_device")) {
    why += "EGL device platform not offered; ";
    return EGL_NO_DISPLAY;
  }
  EGLint count = 0;
  if (!eglQueryDevicesEXT(0, nullptr, &count) || count <= 0) {
    why += egl_error_text("eglQueryDevicesEXT") + "; ";
    return EGL_NO_DISPLAY;
  }
  std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
  eglQueryDevicesEXT(count, devices.data(), &count);
  // First device that initialises wins: on a GPU machine the hardware device is listed before Mesa's
  // software device, which is the order we want.
  for (EGLint i = 0; i < count; ++i) {
    EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[static_cast<std::size_t>(i)],
                                              nullptr);
    if (dpy == EGL_NO_DISPLAY) continue;
    EGLint major = 0, minor = 0;
    if (eglInitialize(dpy, &major, &minor)) {
      pin_gl_driver_libraries();
      return dpy;
    }
  }
  why += egl_error_text("eglInitialize(device)") + "; ";
  return EGL_NO_DISPLAY;
}

class EglContext final : public GlContext {
 public:
  EglContext() {
    std::string why;
    dpy_ = open_surfaceless_display(why);
    if (dpy_ == EGL_NO_DISPLAY) dpy_ = open_device_display(why);
    if (dpy_ == EGL_NO_DISPLAY) throw std::runtime_error("headless GL: no usable EGL display: " + why);
    display_registry().acquire(dpy_);
    try {
      create_context();
    } catch (...) {
      release();
      throw;
    }
  }

  ~EglContext() override { release(); }

  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  void make_current() override {
    if (!eglMakeCurrent(dpy_, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx_))
      throw std::runtime_error("headless GL: " + egl_error_text("eglMakeCurrent"));
  }

 private:
  void create_context() {
    if (!eglBindAPI(EGL_OPENGL_API)) throw std::runtime_error("headless GL: " + egl_error_text("eglBindAPI"));
    if (!epoxy_has_egl_extension(dpy_, "EGL_KHR_surfaceless_context"))
      throw std::runtime_error("headless GL: display lacks EGL_KHR_surfaceless_context");

    // The default surface type (window) yields zero configs on the surfaceless platform, hence PBUFFER_BIT.
    // We never create the pbuffer: the renderer draws into its own FBO.
    const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                     EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_NONE};
    EGLConfig config = EGL_NO_CONFIG_KHR;
    EGLint config_count = 0;
    if (!eglChooseConfig(dpy_, config_attribs, &config, 1, &config_count) || config_count < 1) {
      if (!epoxy_has_egl_extension(dpy_, "EGL_KHR_no_config_context"))
        throw std::runtime_error("headless GL: " + egl_error_text("eglChooseConfig") +
                                 " and no EGL_KHR_no_config_context");
      config = EGL_NO_CONFIG_KHR;
    }

    const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                      EGL_NONE};
    ctx_ = eglCreateContext(dpy_, config, EGL_NO_CONTEXT, context_attribs);
    if (ctx_ == EGL_NO_CONTEXT)
      throw std::runtime_error("headless GL: " + egl_error_text("eglCreateContext(4.5 core)"));
    make_current();
    // A driver may hand out a context that fails the request silently; the renderer relies on 4.5 (DSA).
    if (epoxy_gl_version() < 45)
      throw std::runtime_error("headless GL: context reports GL " + version() + ", need 4.5 core");
  }

  void release() {
    if (dpy_ == EGL_NO_DISPLAY) return;
    if (ctx_ != EGL_NO_CONTEXT) {
      if (eglGetCurrentContext() == ctx_) eglMakeCurrent(dpy_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      eglDestroyContext(dpy_, ctx_);
      ctx_ = EGL_NO_CONTEXT;
    }
    display_registry().release(dpy_);
    dpy_ = EGL_NO_DISPLAY;
  }

  EGLDisplay dpy_ = EGL_NO_DISPLAY;
  EGLContext ctx_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<GlContext> create_headless_gl_context() { return std::make_unique<EglContext>(); }

}  // namespace strata
