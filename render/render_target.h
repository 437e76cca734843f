#pragma once
// The render target every pass draws into: a 4x multisampled colour + depth framebuffer, resolved into a
// single-sample colour framebuffer at the end of a frame, which is what is read back or shown in a window.
#include <cstdint>
#include <vector>

#include <glm/vec4.hpp>

#include "render/gl_program.h"

namespace strata {

class RenderTarget {
 public:
  // Needs a current GL 4.5 core context (as does every call and the destructor). Throws std::invalid_argument
  // for a non-positive size, std::runtime_error when the framebuffers are incomplete.
  RenderTarget(int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }
  // New storage at the new size (nothing when the size is unchanged). It is made before the old is freed, briefly
  // holding both, so a failed resize leaves the old target working; freeing first would leave none.
  void resize(int width, int height);

  // Binds the multisampled framebuffer, sets every piece of state a frame depends on (the caller, or a GUI, may
  // have changed any of it: viewport, scissor, blending, masks, depth test, culling) and clears colour and depth.
  void begin_frame(const glm::vec4& clear_color);
  // Resolves the multisampled framebuffer into the single-sample one.
  void resolve() const;

  // The single-sample framebuffer resolve() writes and read_rgba() reads.
  unsigned output_framebuffer() const { return buffers_.resolve_fbo.id(); }
  // RGBA8 pixels, rows top to bottom (image order), width*height*4 bytes.
  void read_rgba(std::vector<std::uint8_t>& out) const;
  // The depth of each pixel (window depth, 0 near to 1 far; the cleared background is 1), rows top to bottom as
  // read_rgba's, width*height floats: the nearest of the pixel's samples (render/shaders/depth_nearest.frag), so
  // a pixel a surface only partly covers has that surface's depth. What sort-last compositing compares
  // (dist/composite.h): the process that drew an edge wins its antialiased pixel. Rejected: a depth blit, which
  // gives one sample of the GL's choosing, often the ground's beside an edge, and lost those pixels.
  void read_depth(std::vector<float>& out) const;
  // Copies the resolved image to framebuffer 0 (a window), scaled to the given size.
  void blit_to_default_framebuffer(int width, int height) const;

 private:
  struct Buffers {
    GlObject msaa_fbo, msaa_color, msaa_depth;
    GlObject resolve_fbo, resolve_color, resolve_depth;
  };
  static Buffers create(int width, int height, int samples);

  int width_ = 0, height_ = 0;
  int samples_ = 0;
  Buffers buffers_;
  mutable GlObject depth_program_, depth_vao_;  // read_depth's pass, made at its first call
};

}  // namespace strata
