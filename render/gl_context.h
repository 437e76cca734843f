#pragma once
// OpenGL 4.5 core contexts. One renderer serves both kinds:
//  - headless: EGL on the surfaceless Mesa platform (llvmpipe on machines without a GPU, no X server needed),
//    falling back to the EGL device platform; rendering goes into the renderer's own FBO;
//  - windowed: GLFW (needs a display; Xvfb works), see render/gl_context_glfw.h.
// libepoxy resolves GL entry points for either.
#include <memory>
#include <string>

namespace strata {

class GlContext {
 public:
  virtual ~GlContext() = default;
  virtual void make_current() = 0;
  // GL_RENDERER / GL_VERSION strings of the live context, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
  std::string renderer() const;
  std::string version() const;
  // Limits of the live context that decide whether a render target can be made: the largest renderbuffer side
  // (GL_MAX_RENDERBUFFER_SIZE), the largest viewport (GL_MAX_VIEWPORT_DIMS) and the most MSAA samples
  // (GL_MAX_SAMPLES). Commands check a requested image size against them before a run, rather than meeting an
  // incomplete framebuffer at its first frame.
  struct Limits {
    int max_renderbuffer_size = 0;
    int max_viewport_width = 0, max_viewport_height = 0;
    int max_samples = 0;
  };
  Limits limits() const;
};

// AddressSanitizer builds: keeps the GL driver libraries loaded so that LeakSanitizer can name them (see
// render/gl_context_egl.cpp). A no-op in every other build.
void pin_gl_driver_libraries();

// Creates a headless GL 4.5 core context and makes it current on the calling thread.
// Throws std::runtime_error with a one-line reason (which EGL call failed, with its error code).
std::unique_ptr<GlContext> create_headless_gl_context();

}  // namespace strata
