#include "render/gl_program.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>

#include "data/embedded.h"

namespace strata {

GlObject::GlObject(GlKind kind) : kind_(kind) {
  switch (kind) {
    case GlKind::kBuffer: glCreateBuffers(1, &name_); break;
    case GlKind::kVertexArray: glCreateVertexArrays(1, &name_); break;
    case GlKind::kFramebuffer: glCreateFramebuffers(1, &name_); break;
    case GlKind::kRenderbuffer: glCreateRenderbuffers(1, &name_); break;
    case GlKind::kProgram: name_ = glCreateProgram(); break;
    case GlKind::kTexture2D: glCreateTextures(GL_TEXTURE_2D, 1, &name_); break;
    case GlKind::kTexture2DArray: glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &name_); break;
    case GlKind::kTextureBuffer: glCreateTextures(GL_TEXTURE_BUFFER, 1, &name_); break;
    case GlKind::kTexture2DMultisample: glCreateTextures(GL_TEXTURE_2D_MULTISAMPLE, 1, &name_); break;
  }
}

GlObject& GlObject::operator=(GlObject&& other) noexcept {
  if (this != &other) {
    reset();
    kind_ = other.kind_;
    name_ = other.release();
  }
  return *this;
}

void GlObject::reset() {
  if (name_ == 0) return;
  switch (kind_) {
    case GlKind::kBuffer: glDeleteBuffers(1, &name_); break;
    case GlKind::kVertexArray: glDeleteVertexArrays(1, &name_); break;
    case GlKind::kFramebuffer: glDeleteFramebuffers(1, &name_); break;
    case GlKind::kRenderbuffer: glDeleteRenderbuffers(1, &name_); break;
    case GlKind::kProgram: glDeleteProgram(name_); break;
    case GlKind::kTexture2D:
    case GlKind::kTexture2DArray:
    case GlKind::kTextureBuffer:
    case GlKind::kTexture2DMultisample: glDeleteTextures(1, &name_); break;
  }
  name_ = 0;
}

std::string_view shader_source(std::string_view path) {
  const std::optional<std::string_view> text = embedded::find(path);
  if (!text)
    throw std::runtime_error(std::string(path) + ": shader not embedded in this build (add it to "
                             "STRATA_EMBEDDED_FILES in CMakeLists.txt)");
  return *text;
}

namespace {

// A shader object lives only until its program is linked, so it gets no GlKind: the caller deletes it.
GLuint compile_shader(GLenum stage, std::string_view name, std::string_view source) {
  const GLuint shader = glCreateShader(stage);
  const GLchar* text = source.data();
  const GLint length = static_cast<GLint>(source.size());
  glShaderSource(shader, 1, &text, &length);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint log_length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &log_length);
    std::string log(static_cast<std::size_t>(std::max(log_length, 1)), '\0');
    glGetShaderInfoLog(shader, log_length, nullptr, log.data());
    glDeleteShader(shader);
    throw std::runtime_error(std::string(name) + ": failed to compile: " + log.c_str());
  }
  return shader;
}

}  // namespace

GlObject link_program(std::string_view vertex_name, std::string_view vertex_source, std::string_view fragment_name,
                      std::string_view fragment_source) {
  const GLuint vs = compile_shader(GL_VERTEX_SHADER, vertex_name, vertex_source);
  GLuint fs = 0;
  try {
    fs = compile_shader(GL_FRAGMENT_SHADER, fragment_name, fragment_source);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  GlObject program(GlKind::kProgram);
  glAttachShader(program.id(), vs);
  glAttachShader(program.id(), fs);
  glLinkProgram(program.id());
  glDeleteShader(vs);  // flagged; freed with the program
  glDeleteShader(fs);
  GLint ok = GL_FALSE;
  glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint log_length = 0;
    glGetProgramiv(program.id(), GL_INFO_LOG_LENGTH, &log_length);
    std::string log(static_cast<std::size_t>(std::max(log_length, 1)), '\0');
    glGetProgramInfoLog(program.id(), log_length, nullptr, log.data());
    throw std::runtime_error(std::string(vertex_name) + " + " + std::string(fragment_name) +
                             ": failed to link: " + log.c_str());
  }
  return program;
}

GlObject link_program(std::string_view vertex_path, std::string_view fragment_path) {
  return link_program(vertex_path, shader_source(vertex_path), fragment_path, shader_source(fragment_path));
}

}  // namespace strata
