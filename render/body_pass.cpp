#include "render/body_pass.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>

#include <glm/gtc/type_ptr.hpp>

#include "render/appearance.h"

namespace strata {

namespace {

// std::visit over a BodyBatch with one lambda per kind. No catch-all (auto) overload: a new kind must be handled.
template <class... F>
struct Overloads : F... {
  using F::operator()...;
};
template <class... F>
Overloads(F...) -> Overloads<F...>;

}  // namespace

BodyPass::BodyPass()
    : program_(link_program("render/shaders/body.vert", "render/shaders/lit.frag")),
      vao_(GlKind::kVertexArray),
      colors_(GlKind::kBuffer) {
  const GLuint vao = vao_.id();
  for (GLuint a = 0; a < 6; ++a) {
    glEnableVertexArrayAttrib(vao, a);
    glVertexArrayAttribFormat(vao, a, 1, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao, a, a);
  }
  // Attribute 6 (the reference's per-instance offset) stays disabled: GL supplies (0, 0, 0). Attribute 7, the
  // colours, is enabled only for batches that have them.
  glVertexArrayAttribFormat(vao, 7, 4, GL_UNSIGNED_BYTE, GL_TRUE, 0);
  glVertexArrayAttribBinding(vao, 7, 7);
}

// The topology slot each CPU-skinned batch of a frame draws from: the slot already holding its triangles when one
// does, else a slot holding none of this frame's. A level keeps its slot while the set of levels drawn changes
// (under --level auto, levels come and go as walkers cross thresholds), where numbering the batches in order made
// level 2 take level 1's slot whenever level 1 was empty, re-uploading and re-optimising both lists every such
// frame. Impostor batches take no slot (std::nullopt below).
std::vector<std::optional<std::size_t>> BodyPass::assign_slots(const BodySource& bodies) const {
  const std::size_t n = bodies.batch_count();
  std::vector<std::optional<std::size_t>> slot(n);
  std::array<bool, kMaxBatches> taken{};
  std::vector<const BodyDrawInput*> skinned(n, nullptr);
  std::size_t count = 0;
  for (std::size_t k = 0; k < n; ++k)
    if (const BodyDrawInput* b = std::get_if<BodyDrawInput>(&batch_cache_[k])) skinned[k] = b, ++count;
  if (count > kMaxBatches)
    throw std::invalid_argument("crowd renderer: at most " + std::to_string(kMaxBatches) + " body levels per frame");
  for (std::size_t k = 0; k < n; ++k) {
    if (!skinned[k]) continue;
    for (std::size_t s = 0; s < kMaxBatches; ++s)
      if (!taken[s] && slots_[s].holds(skinned[k]->triangles, skinned[k]->vertex_count)) {
        slot[k] = s, taken[s] = true;
        break;
      }
  }
  for (std::size_t k = 0; k < n; ++k) {
    if (!skinned[k] || slot[k]) continue;
    for (std::size_t s = 0; s < kMaxBatches; ++s)
      if (!taken[s]) {
        slot[k] = s, taken[s] = true;
        break;
      }
  }
  return slot;
}

void BodyPass::check(const BodySource& bodies) const {
  const std::size_t n = bodies.batch_count();
  batch_cache_.clear();
  for (std::size_t k = 0; k < n; ++k) batch_cache_.push_back(bodies.batch(k));
  const std::vector<std::optional<std::size_t>> slot = assign_slots(bodies);
  for (std::size_t k = 0; k < n; ++k)
    std::visit(Overloads{[&](const BodyDrawInput& b) { check_batch(b, slots_[*slot[k]]); },
                         [&](const ImpostorBatch& b) { ImpostorPass::check(b); }},
               batch_cache_[k]);
}

void BodyPass::check_batch(const BodyDrawInput& b, const TopologyBuffer& slot) const {
  if (b.walker_count == 0) return;
  if (!b.px || !b.py || !b.pz || !b.nx || !b.ny || !b.nz || b.stride < b.vertex_count || b.triangles.size() % 3 != 0)
    throw std::invalid_argument("crowd renderer: body arrays/triangles do not describe " +
                                std::to_string(b.walker_count) + " walkers of " + std::to_string(b.vertex_count) +
                                " vertices");
  if (!slot.holds(b.triangles, b.vertex_count))
    for (std::uint32_t index : b.triangles)
      if (index >= b.vertex_count)
        throw std::invalid_argument("crowd renderer: body triangle index " + std::to_string(index) + " out of range");
}

void BodyPass::draw_shadow(const BodySource& bodies, const ShadowPass& shadow) {
  const std::size_t n = bodies.batch_count();
  batch_cache_.clear();
  for (std::size_t k = 0; k < n; ++k) batch_cache_.push_back(bodies.batch(k));
  const std::vector<std::optional<std::size_t>> slot = assign_slots(bodies);
  const GLuint p = shadow.body_program();
  glUseProgram(p);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view_projection"), 1, GL_FALSE,
                            glm::value_ptr(shadow.light_view_projection()));
  for (std::size_t k = 0; k < n; ++k) {
    // Impostors as the atlas shows them from the sun (render/impostor_pass.h): a card facing the camera would cast
    // a card's shadow, not the walker's.
    if (const ImpostorBatch* imp = std::get_if<ImpostorBatch>(&batch_cache_[k]); imp && imp->walker_count > 0) {
      if (!impostors_) impostors_ = std::make_unique<ImpostorPass>();
      impostors_->draw_shadow(*imp, shadow);
      continue;
    }
    if (const BodyDrawInput* b = std::get_if<BodyDrawInput>(&batch_cache_[k]);
        b && b->walker_count > 0 && !b->triangles.empty()) {
      stream(*b, slots_[*slot[k]], slot_data_[*slot[k]]);
      // Positions only: the normals' arrays stay unfetched.
      for (GLuint a = 3; a < 6; ++a) glDisableVertexArrayAttrib(vao_.id(), a);
      glDisableVertexArrayAttrib(vao_.id(), 7);
      glUseProgram(p);
      bind_draw(*b);
      for (GLuint a = 3; a < 6; ++a) glEnableVertexArrayAttrib(vao_.id(), a);
    }
  }
}

void BodyPass::draw(const BodySource& bodies, const glm::mat4& view, const glm::mat4& projection,
                    const glm::vec3& skin_color, const ShadedFrame* shading) {
  triangles_drawn_ = 0;
  if (impostors_) impostors_->reset_count();
  const std::size_t n = bodies.batch_count();
  batch_cache_.clear();
  for (std::size_t k = 0; k < n; ++k) batch_cache_.push_back(bodies.batch(k));
  const std::vector<std::optional<std::size_t>> slot = assign_slots(bodies);
  for (std::size_t k = 0; k < n; ++k)
    std::visit(Overloads{[&](const BodyDrawInput& b) {
                           draw_batch(b, slots_[*slot[k]], slot_data_[*slot[k]], view, projection, skin_color,
                                      shading);
                         },
                         [&](const ImpostorBatch& b) {
                           if (b.walker_count == 0) return;
                           if (!impostors_) impostors_ = std::make_unique<ImpostorPass>();
                           impostors_->draw(b, view, projection, skin_color, shading);
                         }},
               batch_cache_[k]);
  ++frame_;
}

void BodyPass::stream(const BodyDrawInput& b, TopologyBuffer& slot, SlotData& data) {
  if (!slot.holds(b.triangles, b.vertex_count)) slot.upload(b.triangles, b.vertex_count, optimized_);
  const GLuint vao = vao_.id();
  glVertexArrayElementBuffer(vao, slot.id());
  const std::size_t floats = b.walker_count * b.stride;
  const GLsizeiptr bytes = static_cast<GLsizeiptr>(floats * sizeof(float));
  const bool fresh = data.streamed_frame != frame_ || data.streamed_from != b.px;
  if (fresh) glNamedBufferData(data.components.id(), 6 * bytes, nullptr, GL_STREAM_DRAW);
  const float* arrays[6] = {b.px, b.py, b.pz, b.nx, b.ny, b.nz};
  for (GLuint a = 0; a < 6; ++a) {
    if (fresh) glNamedBufferSubData(data.components.id(), a * bytes, bytes, arrays[a]);
    glVertexArrayVertexBuffer(vao, a, data.components.id(), a * bytes, sizeof(float));
  }
  data.streamed_frame = frame_;
  data.streamed_from = b.px;
}

void BodyPass::bind_draw(const BodyDrawInput& b) {
  // One multi-draw: the shared index list once per walker, offset by its first vertex.
  counts_.assign(b.walker_count, static_cast<GLsizei>(b.triangles.size()));
  offsets_.assign(b.walker_count, nullptr);
  base_vertices_.resize(b.walker_count);
  for (std::size_t w = 0; w < b.walker_count; ++w) base_vertices_[w] = static_cast<GLint>(w * b.stride);
  glBindVertexArray(vao_.id());
  glMultiDrawElementsBaseVertex(GL_TRIANGLES, counts_.data(), GL_UNSIGNED_INT, offsets_.data(),
                                static_cast<GLsizei>(b.walker_count), base_vertices_.data());
}

// The shaded material's inputs: the surface classes and occlusion of the body's vertices (per slot, uploaded
// when the batch's lists change) and this frame's palettes, one per walker.
void BodyPass::prepare_shaded(const BodyDrawInput& b, SlotData& data) {
  const void* materials_key = b.materials.empty() ? nullptr : b.materials.data();
  const void* occlusion_key = b.ambient_occlusion.empty() ? nullptr : b.ambient_occlusion.data();
  if (data.lists_stride != b.stride || data.materials_key != materials_key || data.occlusion_key != occlusion_key) {
    // Padded to the stride: the shader fetches by the vertex's place in its walker's block, padding included.
    // Classes (R8UI: two per byte), then per vertex its cut distance and occlusion (RG32F).
    const bool cut = b.material_cut.size() >= b.vertex_count && b.materials.size() >= b.vertex_count;
    materials_scratch_.assign(b.stride, 0);
    occlusion_scratch_.assign(2 * b.stride, 1.0f);
    for (std::size_t v = 0; v < b.vertex_count && v < b.materials.size(); ++v)
      materials_scratch_[v] = b.materials[v];
    for (std::size_t v = 0; v < b.vertex_count; ++v) {
      if (cut) occlusion_scratch_[2 * v] = b.material_cut[v];
      if (v < b.ambient_occlusion.size()) occlusion_scratch_[2 * v + 1] = b.ambient_occlusion[v];
    }
    glNamedBufferData(data.materials.id(), static_cast<GLsizeiptr>(b.stride), materials_scratch_.data(),
                      GL_STATIC_DRAW);
    glTextureBuffer(data.materials_texture.id(), GL_R8UI, data.materials.id());
    glNamedBufferData(data.occlusion.id(), static_cast<GLsizeiptr>(2 * b.stride * sizeof(float)),
                      occlusion_scratch_.data(), GL_STATIC_DRAW);
    glTextureBuffer(data.occlusion_texture.id(), GL_RG32F, data.occlusion.id());
    data.lists_stride = b.stride;
    data.materials_key = materials_key;
    data.occlusion_key = occlusion_key;
  }
  fill_palettes(b.walker_keys, b.walker_count, plain_, palette_scratch_);
  glNamedBufferData(palettes_.id(), static_cast<GLsizeiptr>(palette_scratch_.size() * sizeof(glm::vec4)),
                    palette_scratch_.data(), GL_STREAM_DRAW);
  glTextureBuffer(palettes_texture_.id(), GL_RGBA32F, palettes_.id());
  glBindTextureUnit(0, data.materials_texture.id());
  glBindTextureUnit(1, data.occlusion_texture.id());
  glBindTextureUnit(2, palettes_texture_.id());
}

void BodyPass::draw_batch(const BodyDrawInput& b, TopologyBuffer& slot, SlotData& data, const glm::mat4& view,
                          const glm::mat4& projection, const glm::vec3& skin_color, const ShadedFrame* shading) {
  if (b.walker_count == 0 || b.triangles.empty()) return;
  stream(b, slot, data);
  const GLuint vao = vao_.id();
  const std::size_t floats = b.walker_count * b.stride;
  if (b.rgba) {
    glNamedBufferData(colors_.id(), static_cast<GLsizeiptr>(floats * sizeof(std::uint32_t)), b.rgba, GL_STREAM_DRAW);
    glVertexArrayVertexBuffer(vao, 7, colors_.id(), 0, sizeof(std::uint32_t));
    glEnableVertexArrayAttrib(vao, 7);
  } else {
    // The generic value is context state, not the VAO's: set it every time, or the last tint would stick.
    glDisableVertexArrayAttrib(vao, 7);
    glVertexAttrib4f(7, 0.0f, 0.0f, 0.0f, 0.0f);
  }
  if (shading) {
    if (!shaded_program_) shaded_program_ = link_shaded_program("render/shaders/body_shaded.vert", "render/shaders/shaded.frag");
    const GLuint p = shaded_program_.id();
    plain_ = plain_palette(skin_color);
    prepare_shaded(b, data);
    const glm::mat4 view_projection = projection * view;
    glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view_projection"), 1, GL_FALSE,
                              glm::value_ptr(view_projection));
    glProgramUniform1i(p, glGetUniformLocation(p, "u_stride"), static_cast<GLint>(b.stride));
    glProgramUniform1i(p, glGetUniformLocation(p, "u_materials"), 0);
    glProgramUniform1i(p, glGetUniformLocation(p, "u_surface"), 1);
    glProgramUniform1i(p, glGetUniformLocation(p, "u_palettes"), 2);
    shading->apply(p);
    glUseProgram(p);
  } else {
    const GLuint p = program_.id();
    glUseProgram(p);
    glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
    glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
    glProgramUniform3fv(p, glGetUniformLocation(p, "u_color"), 1, glm::value_ptr(skin_color));
  }
  bind_draw(b);
  triangles_drawn_ += b.walker_count * (b.triangles.size() / 3);
}

}  // namespace strata
