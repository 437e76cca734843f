#include "render/shadow_pass.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace strata {

GlObject link_shaded_program(std::string_view vertex_path, std::string_view fragment_path) {
  const std::string fragment = std::string(shader_source("render/shaders/shading.glsl")) + "\n#line 1\n" +
                               std::string(shader_source(fragment_path));
  return link_program(vertex_path, shader_source(vertex_path), fragment_path, fragment);
}

ShadowPass::ShadowPass(int size)
    : size_(size),
      depth_(GlKind::kTexture2D),
      framebuffer_(GlKind::kFramebuffer),
      body_program_(link_program("render/shaders/shadow.vert", "render/shaders/shadow.frag")) {
  const GLuint depth = depth_.id();
  glTextureStorage2D(depth, 1, GL_DEPTH_COMPONENT24, size_, size_);
  // Hardware comparison with linear filtering: each of the shader's 16 taps is itself a 2x2 bilinear PCF.
  glTextureParameteri(depth, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(depth, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(depth, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(depth, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTextureParameteri(depth, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glTextureParameteri(depth, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  const GLuint fbo = framebuffer_.id();
  glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth, 0);
  glNamedFramebufferDrawBuffer(fbo, GL_NONE);
  glNamedFramebufferReadBuffer(fbo, GL_NONE);
  if (glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("shadow map: depth framebuffer of " + std::to_string(size_) + " x " +
                             std::to_string(size_) + " is incomplete");
}

bool ShadowPass::begin(const glm::vec3& to_sun, std::span<const glm::vec3> casters, float reach) {
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
  for (const glm::vec3& p : casters) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  if (lo.x > hi.x) return false;
  lo -= glm::vec3(reach);
  hi += glm::vec3(reach);
  lo.y = std::min(lo.y, 0.0f);  // the ground the shadows fall on
  // The light looks along -to_sun at the box's centre; the box's eight corners in light space bound the
  // orthographic frustum. A shadow falls where the sun's ray through its caster meets the ground, and that point
  // is inside the box's light-space footprint already, since the box reaches the ground.
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float radius = 0.5f * glm::length(hi - lo) + 1.0f;
  const glm::vec3 up = std::abs(to_sun.y) > 0.99f ? glm::vec3(0.0f, 0.0f, 1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
  const glm::mat4 view = glm::lookAt(centre + to_sun * radius, centre, up);
  glm::vec3 llo(std::numeric_limits<float>::max()), lhi(std::numeric_limits<float>::lowest());
  for (int k = 0; k < 8; ++k) {
    const glm::vec3 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
    const glm::vec3 l = glm::vec3(view * glm::vec4(corner, 1.0f));
    llo = glm::min(llo, l);
    lhi = glm::max(lhi, l);
  }
  // Light space looks down -z: near and far are the negated z extremes.
  const glm::mat4 projection = glm::ortho(llo.x, lhi.x, llo.y, lhi.y, -lhi.z - 0.1f, -llo.z + 0.1f);
  view_projection_ = projection * view;
  view_ = view, projection_ = projection;
  far_sun_ = centre + to_sun * 1.0e5f;
  texel_world_ = std::max(lhi.x - llo.x, lhi.y - llo.y) / static_cast<float>(size_);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glViewport(0, 0, size_, size_);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);  // thin parts (fingers, ears) must cast from both sides
  // A slope-scaled offset so a surface does not shadow itself; the normal offset in the lookup does the rest.
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.5f, 2.0f);
  const float one = 1.0f;
  glClearNamedFramebufferfv(framebuffer_.id(), GL_DEPTH, 0, &one);
  return true;
}

void ShadowPass::end() const { glDisable(GL_POLYGON_OFFSET_FILL); }

void ShadowPass::apply(unsigned program, const Sunlight& sun, const glm::vec3& eye, bool shadows, int unit) const {
  const GLuint p = program;
  // Map clip space [-1, 1] to texture space [0, 1] for the lookup.
  const glm::mat4 bias = glm::translate(glm::mat4(1.0f), glm::vec3(0.5f)) * glm::scale(glm::mat4(1.0f), glm::vec3(0.5f));
  const glm::mat4 light = bias * view_projection_;
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_sun_dir"), 1, glm::value_ptr(sun.to_sun));
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_sun_color"), 1, glm::value_ptr(sun.sun_color));
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_sky_color"), 1, glm::value_ptr(sun.sky_color));
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_bounce_color"), 1, glm::value_ptr(sun.bounce_color));
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_eye"), 1, glm::value_ptr(eye));
  glProgramUniform1f(p, glGetUniformLocation(p, "u_exposure"), sun.exposure);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_light_matrix"), 1, GL_FALSE, glm::value_ptr(light));
  glProgramUniform1i(p, glGetUniformLocation(p, "u_shadow_map"), unit);
  glProgramUniform1f(p, glGetUniformLocation(p, "u_shadow_texel"), 1.0f / static_cast<float>(size_));
  glProgramUniform1f(p, glGetUniformLocation(p, "u_shadow_world"), texel_world_);
  glProgramUniform1i(p, glGetUniformLocation(p, "u_shadows"), shadows ? 1 : 0);
  glBindTextureUnit(static_cast<GLuint>(unit), depth_.id());
}

void ShadedFrame::apply(unsigned program) const { shadow->apply(program, *sun, eye, shadows); }

}  // namespace strata
