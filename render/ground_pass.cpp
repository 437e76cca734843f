#include "render/ground_pass.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/common.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace strata {

GroundExtent ground_extent(std::span<const glm::vec3> points) {
  glm::vec2 lo{std::numeric_limits<float>::max()}, hi{std::numeric_limits<float>::lowest()};
  for (const glm::vec3& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    lo = glm::min(lo, glm::vec2{p.x, p.z});
    hi = glm::max(hi, glm::vec2{p.x, p.z});
  }
  if (lo.x > hi.x) return {};
  GroundExtent e;
  e.center = 0.5f * (lo + hi);
  // The farthest point from the centre is a corner of the box.
  const float reach = 0.5f * glm::length(hi - lo);
  e.half_size = std::max({0.5f * std::max(hi.x - lo.x, hi.y - lo.y) + 15.0f, reach + std::max(15.0f, 0.4f * reach), 25.0f});
  e.fade_start = std::max(0.6f * e.half_size, reach + 2.0f);
  return e;
}

GroundPass::GroundPass()
    : program_(link_program("render/shaders/ground.vert", "render/shaders/ground.frag")),
      vao_(GlKind::kVertexArray) {}

void GroundPass::draw(std::span<const glm::vec3> joints, const glm::mat4& view, const glm::mat4& projection,
                      const glm::vec3& ground_color, const glm::vec4& clear_color, const ShadedFrame* shading) {
  const GroundExtent e = ground_extent(joints);
  if (shading && !shaded_program_)
    shaded_program_ = link_shaded_program("render/shaders/ground.vert", "render/shaders/ground_shaded.frag");
  const GLuint p = shading ? shaded_program_.id() : program_.id();
  if (shading) shading->apply(p);
  glUseProgram(p);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
  glProgramUniform2fv(p, glGetUniformLocation(p, "u_center"), 1, glm::value_ptr(e.center));
  glProgramUniform1f(p, glGetUniformLocation(p, "u_half_size"), e.half_size);
  glProgramUniform1f(p, glGetUniformLocation(p, "u_fade_start"), e.fade_start);
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_ground_color"), 1, glm::value_ptr(ground_color));
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_clear_color"), 1, glm::value_ptr(clear_color));
  glBindVertexArray(vao_.id());
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
}

}  // namespace strata
