#include "render/reference_pass.h"

#include <epoxy/gl.h>

#include <stdexcept>

#include <glm/gtc/type_ptr.hpp>

namespace strata {

ReferencePass::ReferencePass()
    : program_(link_program("render/shaders/body.vert", "render/shaders/lit.frag")),
      vao_(GlKind::kVertexArray),
      mesh_(GlKind::kBuffer),
      offsets_(GlKind::kBuffer) {
  const GLuint vao = vao_.id();
  for (GLuint a = 0; a < 6; ++a) {
    glEnableVertexArrayAttrib(vao, a);
    glVertexArrayAttribFormat(vao, a, 1, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao, a, a);
  }
  glEnableVertexArrayAttrib(vao, 6);
  glVertexArrayAttribFormat(vao, 6, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(vao, 6, 6);
  glVertexArrayBindingDivisor(vao, 6, 1);
  glVertexArrayElementBuffer(vao, topology_.id());
}

void ReferencePass::upload(const BodyDrawInput& mesh, std::span<const glm::vec3> offsets) {
  if (!mesh.px || mesh.vertex_count == 0 || mesh.triangles.size() % 3 != 0)
    throw std::invalid_argument("render_instanced_reference: no mesh");
  // The mesh (walker 0 of `mesh`) and its indices go up once, like any static instanced model.
  if (!topology_.holds(mesh.triangles, mesh.vertex_count)) {
    for (std::uint32_t index : mesh.triangles)
      if (index >= mesh.vertex_count) throw std::invalid_argument("render_instanced_reference: index out of range");
    topology_.upload(mesh.triangles, mesh.vertex_count, optimized_);
    const GLsizeiptr bytes = static_cast<GLsizeiptr>(mesh.vertex_count * sizeof(float));
    glNamedBufferData(mesh_.id(), 6 * bytes, nullptr, GL_STATIC_DRAW);
    const float* arrays[6] = {mesh.px, mesh.py, mesh.pz, mesh.nx, mesh.ny, mesh.nz};
    for (GLuint a = 0; a < 6; ++a) {
      glNamedBufferSubData(mesh_.id(), a * bytes, bytes, arrays[a]);
      glVertexArrayVertexBuffer(vao_.id(), a, mesh_.id(), a * bytes, sizeof(float));
    }
  }
  glNamedBufferData(offsets_.id(), static_cast<GLsizeiptr>(offsets.size() * sizeof(glm::vec3)), offsets.data(),
                    GL_STREAM_DRAW);
  glVertexArrayVertexBuffer(vao_.id(), 6, offsets_.id(), 0, sizeof(glm::vec3));
  index_count_ = mesh.triangles.size();
  instance_count_ = offsets.size();
}

std::size_t ReferencePass::draw(const glm::mat4& view, const glm::mat4& projection, const glm::vec3& skin_color) {
  const GLuint p = program_.id();
  glUseProgram(p);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_color"), 1, glm::value_ptr(skin_color));
  glVertexAttrib4f(7, 0.0f, 0.0f, 0.0f, 0.0f);  // no per-vertex tint (attribute 7 is never enabled here)
  glBindVertexArray(vao_.id());
  glDrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(index_count_), GL_UNSIGNED_INT, nullptr,
                          static_cast<GLsizei>(instance_count_));
  return instance_count_ * (index_count_ / 3);
}

}  // namespace strata
