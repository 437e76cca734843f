#include "render/impostor_pass.h"

#include <glm/common.hpp>

#include <epoxy/gl.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>

#include "render/appearance.h"

namespace strata {

namespace {

// impostor.frag has no #version line: each program puts its own header in front (see the shader's comment).
GlObject link_impostor_program(bool shaded) {
  const std::string header = shaded ? std::string(shader_source("render/shaders/shading.glsl")) + "\n#define SHADED 1\n"
                                    : std::string("#version 450 core\n");
  return link_program("render/shaders/impostor.vert", shader_source("render/shaders/impostor.vert"),
                      "render/shaders/impostor.frag",
                      header + "#line 1\n" + std::string(shader_source("render/shaders/impostor.frag")));
}

}  // namespace

void grow_by_impostors(const ImpostorBatch& b, glm::vec3& lo, glm::vec3& hi) {
  if (!b.atlas || b.walker_count == 0) return;
  const float radius = 0.5f * std::hypot(b.atlas->cell_width_m, b.atlas->cell_height_m);
  for (std::size_t w = 0; w < b.walker_count; ++w) {
    const float s = b.scale[w];
    const glm::vec3 centre(b.x[w], b.y[w] + b.atlas->center_height_m * s, b.z[w]);
    if (!std::isfinite(centre.x + centre.y + centre.z + s)) continue;
    lo = glm::min(lo, centre - glm::vec3(radius * s)), hi = glm::max(hi, centre + glm::vec3(radius * s));
  }
}

ImpostorPass::ImpostorPass()
    : program_(link_impostor_program(false)),
      vao_(GlKind::kVertexArray),
      instances_(GlKind::kBuffer) {
  const GLuint vao = vao_.id();
  for (GLuint a = 0; a < 6; ++a) {
    glEnableVertexArrayAttrib(vao, a);
    glVertexArrayAttribFormat(vao, a, 1, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao, a, a);
    glVertexArrayBindingDivisor(vao, a, 1);
  }
}

void ImpostorPass::check(const ImpostorBatch& b) {
  if (b.walker_count == 0) return;
  if (!b.atlas || !b.atlas->complete())
    throw std::invalid_argument("crowd renderer: impostor batch of " + std::to_string(b.walker_count) +
                                " walkers without a complete atlas");
  if (!b.x || !b.y || !b.z || !b.heading || !b.scale || !b.phase)
    throw std::invalid_argument("crowd renderer: impostor batch misses a per-walker array");
}

void ImpostorPass::upload(const ImpostorAtlas& atlas) {
  const ImpostorAtlasLayout& l = atlas.layout;
  // Mip levels down to cells of 8 pixels across: far impostors minify, and level 3 still keeps the cells apart
  // (their empty borders are a few texels wide there).
  const int levels = std::max(1, std::min(4, 1 + static_cast<int>(std::log2(std::max(1, l.cell_width / 8)))));
  for (GlObject* texture : {&color_, &normal_}) {
    *texture = GlObject(GlKind::kTexture2DArray);  // storage is immutable: a new atlas needs a new texture
    const GLuint t = texture->id();
    glTextureStorage3D(t, levels, GL_RGBA8, l.layer_width(), l.layer_height(), l.phases);
    const std::uint8_t* pixels = texture == &color_ ? atlas.color.data() : atlas.normal_depth.data();
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage3D(t, 0, 0, 0, 0, l.layer_width(), l.layer_height(), l.phases, GL_RGBA, GL_UNSIGNED_BYTE,
                        pixels);
    // Nearest mip level, bilinear within it: trilinear filtering doubled the texel fetches, the impostor's main
    // cost on a software rasteriser, for a blur far walkers do not need.
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glGenerateTextureMipmap(t);
  }
  // Each cell's covered rectangle, one texel of margin for the bilinear filter; an empty cell keeps a
  // degenerate rectangle (its quad draws nothing).
  const int cw = l.cell_width, ch = l.cell_height, W = l.layer_width();
  std::vector<float> bounds(static_cast<std::size_t>(l.phases * l.elevations * l.azimuths) * 4);
  for (int k = 0; k < l.phases; ++k)
    for (int e = 0; e < l.elevations; ++e)
      for (int a = 0; a < l.azimuths; ++a) {
        int x0 = cw, y0 = ch, x1 = -1, y1 = -1;
        const std::uint8_t* layer = atlas.color.data() + static_cast<std::size_t>(k) * l.layer_bytes();
        for (int y = 0; y < ch; ++y)
          for (int x = 0; x < cw; ++x)
            if (layer[(static_cast<std::size_t>(e * ch + y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(a * cw + x)) * 4 + 3] > 0) {
              x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
            }
        float* b = bounds.data() + (static_cast<std::size_t>((k * l.elevations + e) * l.azimuths + a)) * 4;
        if (x1 < 0) {
          b[0] = b[1] = b[2] = b[3] = 0.5f;
          continue;
        }
        b[0] = static_cast<float>(std::max(x0 - 1, 0)) / static_cast<float>(cw);
        b[1] = static_cast<float>(std::max(y0 - 1, 0)) / static_cast<float>(ch);
        b[2] = static_cast<float>(std::min(x1 + 2, cw)) / static_cast<float>(cw);
        b[3] = static_cast<float>(std::min(y1 + 2, ch)) / static_cast<float>(ch);
      }
  cell_bounds_ = GlObject(GlKind::kBuffer);
  glNamedBufferStorage(cell_bounds_.id(), static_cast<GLsizeiptr>(bounds.size() * sizeof(float)), bounds.data(), 0);
  uploaded_ = &atlas;
  uploaded_key_ = atlas.key;
}

void ImpostorPass::stream(const ImpostorBatch& b) {
  const ImpostorAtlas& atlas = *b.atlas;
  if (uploaded_ != &atlas || uploaded_key_ != atlas.key) upload(atlas);
  const GLuint vao = vao_.id();
  const GLsizeiptr bytes = static_cast<GLsizeiptr>(b.walker_count * sizeof(float));
  glNamedBufferData(instances_.id(), 6 * bytes, nullptr, GL_STREAM_DRAW);
  const float* arrays[6] = {b.x, b.y, b.z, b.heading, b.scale, b.phase};
  for (GLuint a = 0; a < 6; ++a) {
    glNamedBufferSubData(instances_.id(), a * bytes, bytes, arrays[a]);
    glVertexArrayVertexBuffer(vao, a, instances_.id(), a * bytes, sizeof(float));
  }
}

void ImpostorPass::bind_atlas(GLuint p, const ImpostorAtlas& atlas, const glm::mat4& view, const glm::mat4& projection,
                              const glm::vec3& eye) const {
  const ImpostorAtlasLayout& l = atlas.layout;
  glUseProgram(p);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
  glProgramUniform3fv(p, glGetUniformLocation(p, "u_eye"), 1, glm::value_ptr(eye));
  glProgramUniform4i(p, glGetUniformLocation(p, "u_grid"), l.phases, l.azimuths, l.elevations, 0);
  glProgramUniform1f(p, glGetUniformLocation(p, "u_max_elevation"), glm::radians(l.max_elevation_deg));
  glProgramUniform3f(p, glGetUniformLocation(p, "u_cell"), atlas.cell_width_m, atlas.cell_height_m,
                     atlas.center_height_m);
  glProgramUniform1f(p, glGetUniformLocation(p, "u_depth_range"), atlas.depth_range_m);
  glProgramUniform1i(p, glGetUniformLocation(p, "u_color_atlas"), 0);
  glProgramUniform1i(p, glGetUniformLocation(p, "u_normal_atlas"), 1);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, cell_bounds_.id());
  glBindTextureUnit(0, color_.id());
  glBindTextureUnit(1, normal_.id());
  glBindVertexArray(vao_.id());
}

void ImpostorPass::draw(const ImpostorBatch& b, const glm::mat4& view, const glm::mat4& projection,
                        const glm::vec3& skin_color, const ShadedFrame* shading) {
  if (b.walker_count == 0) return;
  stream(b);
  if (shading && !shaded_program_) shaded_program_ = link_impostor_program(true);
  const GLuint p = shading ? shaded_program_.id() : program_.id();
  const glm::mat4 inverse_view = glm::inverse(view);
  if (shading) {
    // Each walker's palette by its key, as the body pass does (render/appearance.h).
    fill_palettes(b.walker_keys, b.walker_count, plain_palette(skin_color), palette_scratch_);
    glNamedBufferData(palettes_.id(), static_cast<GLsizeiptr>(palette_scratch_.size() * sizeof(glm::vec4)),
                      palette_scratch_.data(), GL_STREAM_DRAW);
    glTextureBuffer(palettes_texture_.id(), GL_RGBA32F, palettes_.id());
    glBindTextureUnit(2, palettes_texture_.id());
    glProgramUniform1i(p, glGetUniformLocation(p, "u_palettes"), 2);
    glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view_inverse"), 1, GL_FALSE, glm::value_ptr(inverse_view));
    shading->apply(p);
  } else {
    glProgramUniform3fv(p, glGetUniformLocation(p, "u_skin_color"), 1, glm::value_ptr(skin_color));
  }
  bind_atlas(p, *b.atlas, view, projection, glm::vec3(inverse_view[3]));
  // Coverage from alpha; the alpha itself is kept out of the target (which stays opaque): written, it left
  // the edges' pixels translucent, and a PNG writer that un-premultiplies brightened them to white.
  glEnable(GL_SAMPLE_ALPHA_TO_COVERAGE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_FALSE);
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(b.walker_count));
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDisable(GL_SAMPLE_ALPHA_TO_COVERAGE);
  glBindTextureUnit(0, 0);
  glBindTextureUnit(1, 0);
  glBindTextureUnit(2, 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
  drawn_ += b.walker_count;
}

void ImpostorPass::draw_shadow(const ImpostorBatch& b, const ShadowPass& shadow) {
  if (b.walker_count == 0) return;
  stream(b);
  if (!shadow_program_)
    shadow_program_ = link_program("render/shaders/impostor.vert", shader_source("render/shaders/impostor.vert"),
                                   "render/shaders/impostor_shadow.frag",
                                   shader_source("render/shaders/impostor_shadow.frag"));
  // The sun as the eye: far enough out that every walker sees it along the sun's rays (within 0.3 degrees for a
  // crowd 500 m across), so each quad faces the sun as the orthographic map looks at it.
  bind_atlas(shadow_program_.id(), *b.atlas, shadow.light_view(), shadow.light_projection(), shadow.far_sun_point());
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(b.walker_count));
  glBindTextureUnit(0, 0);
  glBindTextureUnit(1, 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
}

}  // namespace strata
