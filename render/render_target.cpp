#include "render/render_target.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>

#include <glm/gtc/type_ptr.hpp>

namespace strata {

namespace {

void check_size(int width, int height) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("crowd renderer: size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
}

}  // namespace

RenderTarget::RenderTarget(int width, int height) : width_(width), height_(height) {
  check_size(width, height);
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  // 4x is enough to keep thin bones from breaking up; below 2 there is no MSAA and samples = 0 makes the
  // "multisample" target an ordinary one, leaving the resolve blit a plain copy.
  samples_ = max_samples >= 2 ? std::min<GLint>(4, max_samples) : 0;
  buffers_ = create(width, height, samples_);
}

void RenderTarget::resize(int width, int height) {
  check_size(width, height);
  if (width == width_ && height == height_) return;
  buffers_ = create(width, height, samples_);
  width_ = width;
  height_ = height;
}

RenderTarget::Buffers RenderTarget::create(int width, int height, int samples) {
  // The multisampled depth is a texture so that read_depth() can take each pixel's nearest sample (a renderbuffer
  // cannot be sampled); without multisampling, a renderbuffer as the colour.
  Buffers b{GlObject(GlKind::kFramebuffer), GlObject(GlKind::kRenderbuffer),
            GlObject(samples > 0 ? GlKind::kTexture2DMultisample : GlKind::kRenderbuffer),
            GlObject(GlKind::kFramebuffer), GlObject(GlKind::kRenderbuffer), GlObject(GlKind::kRenderbuffer)};
  glNamedRenderbufferStorageMultisample(b.msaa_color.id(), samples, GL_RGBA8, width, height);
  if (samples > 0) glTextureStorage2DMultisample(b.msaa_depth.id(), samples, GL_DEPTH_COMPONENT24, width, height, GL_TRUE);
  else glNamedRenderbufferStorage(b.msaa_depth.id(), GL_DEPTH_COMPONENT24, width, height);
  glNamedRenderbufferStorage(b.resolve_color.id(), GL_RGBA8, width, height);
  glNamedFramebufferRenderbuffer(b.msaa_fbo.id(), GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, b.msaa_color.id());
  if (samples > 0) glNamedFramebufferTexture(b.msaa_fbo.id(), GL_DEPTH_ATTACHMENT, b.msaa_depth.id(), 0);
  else glNamedFramebufferRenderbuffer(b.msaa_fbo.id(), GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, b.msaa_depth.id());
  // A depth buffer beside the resolved colour only for read_depth(): blitting depth needs equal formats.
  glNamedRenderbufferStorage(b.resolve_depth.id(), GL_DEPTH_COMPONENT24, width, height);
  glNamedFramebufferRenderbuffer(b.resolve_fbo.id(), GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, b.resolve_color.id());
  glNamedFramebufferRenderbuffer(b.resolve_fbo.id(), GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, b.resolve_depth.id());
  glNamedFramebufferReadBuffer(b.resolve_fbo.id(), GL_COLOR_ATTACHMENT0);
  for (const GlObject* fbo : {&b.msaa_fbo, &b.resolve_fbo}) {
    const GLenum status = glCheckNamedFramebufferStatus(fbo->id(), GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      char buf[128];
      std::snprintf(buf, sizeof buf, "crowd renderer: %dx%d framebuffer incomplete (status 0x%04X)", width, height,
                    static_cast<unsigned>(status));
      throw std::runtime_error(buf);
    }
  }
  return b;
}

void RenderTarget::begin_frame(const glm::vec4& clear_color) {
  const GLuint fbo = buffers_.msaa_fbo.id();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, width_, height_);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_BLEND);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_TRUE);  // clears honour the write mask
  glClearNamedFramebufferfv(fbo, GL_COLOR, 0, glm::value_ptr(clear_color));
  const GLfloat far_depth = 1.0f;
  glClearNamedFramebufferfv(fbo, GL_DEPTH, 0, &far_depth);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
}

void RenderTarget::resolve() const {
  glBlitNamedFramebuffer(buffers_.msaa_fbo.id(), buffers_.resolve_fbo.id(), 0, 0, width_, height_, 0, 0, width_,
                         height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

void RenderTarget::read_rgba(std::vector<std::uint8_t>& out) const {
  const std::size_t row_bytes = static_cast<std::size_t>(width_) * 4;
  out.resize(row_bytes * static_cast<std::size_t>(height_));
  glBindFramebuffer(GL_READ_FRAMEBUFFER, buffers_.resolve_fbo.id());
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glReadnPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, static_cast<GLsizei>(out.size()), out.data());
  // GL's origin is bottom-left; images are stored top row first.
  for (int y = 0; y < height_ / 2; ++y) {
    std::uint8_t* top = out.data() + static_cast<std::size_t>(y) * row_bytes;
    std::uint8_t* bottom = out.data() + static_cast<std::size_t>(height_ - 1 - y) * row_bytes;
    std::swap_ranges(top, top + row_bytes, bottom);
  }
}

void RenderTarget::read_depth(std::vector<float>& out) const {
  if (samples_ > 0) {
    if (!depth_program_) {
      depth_program_ = link_program("render/shaders/fullscreen.vert", "render/shaders/depth_nearest.frag");
      depth_vao_ = GlObject(GlKind::kVertexArray);
    }
    // Every pixel's nearest sample written as the resolved depth: depth test on (writes need it) but always
    // passing, colour untouched.
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, buffers_.resolve_fbo.id());
    glViewport(0, 0, width_, height_);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glDepthMask(GL_TRUE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_ALWAYS);
    glUseProgram(depth_program_.id());
    glBindTextureUnit(0, buffers_.msaa_depth.id());
    glUniform1i(glGetUniformLocation(depth_program_.id(), "u_depth"), 0);
    glUniform1i(glGetUniformLocation(depth_program_.id(), "u_samples"), samples_);
    glBindVertexArray(depth_vao_.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthFunc(GL_LESS);
  } else {
    glBlitNamedFramebuffer(buffers_.msaa_fbo.id(), buffers_.resolve_fbo.id(), 0, 0, width_, height_, 0, 0, width_,
                           height_, GL_DEPTH_BUFFER_BIT, GL_NEAREST);
  }
  const std::size_t row = static_cast<std::size_t>(width_);
  out.resize(row * static_cast<std::size_t>(height_));
  glBindFramebuffer(GL_READ_FRAMEBUFFER, buffers_.resolve_fbo.id());
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glReadnPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(out.size() * sizeof(float)),
                out.data());
  for (int y = 0; y < height_ / 2; ++y) {
    float* top = out.data() + static_cast<std::size_t>(y) * row;
    float* bottom = out.data() + static_cast<std::size_t>(height_ - 1 - y) * row;
    std::swap_ranges(top, top + row, bottom);
  }
}

void RenderTarget::blit_to_default_framebuffer(int width, int height) const {
  const bool same_size = width == width_ && height == height_;
  glDisable(GL_SCISSOR_TEST);  // blits honour the scissor box
  glBlitNamedFramebuffer(buffers_.resolve_fbo.id(), 0, 0, 0, width_, height_, 0, 0, width, height,
                         GL_COLOR_BUFFER_BIT, same_size ? GL_NEAREST : GL_LINEAR);
}

}  // namespace strata
