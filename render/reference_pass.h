#pragma once
// The render benchmark's reference (`strata bench --render`): one walker's body uploaded once as a static mesh
// and drawn once per offset in a single glDrawElementsInstanced, each copy moved by its offset, with the body
// pass's shaders and material. It is raw instancing of the same triangles with nothing streamed: the fastest way
// to draw them, which the crowd's body pass is measured against.
//
// A pass of its own rather than a mode of BodyPass: it shares the shaders but none of the per-frame state (its
// mesh is static, its vertex array has an instanced attribute), and it is built only when the benchmark first
// asks for it, so nothing else pays for it. It links its own copy of the body program instead of borrowing the
// body pass's, so neither pass's lifetime depends on the other; the one extra link happens once, in the
// benchmark's untimed first frame.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "render/body_source.h"
#include "render/gl_program.h"
#include "render/topology_buffer.h"

namespace strata {

class ReferencePass {
 public:
  // Needs a current GL 4.5 core context (as do upload, draw and the destructor). Throws std::runtime_error on a
  // shader failure.
  ReferencePass();

  // Walker 0 of `mesh` (uploaded when its topology differs from the last one's) and the per-copy offsets (every
  // call). Throws std::invalid_argument for a mesh without vertices, a triangle list whose length is not a
  // multiple of 3, or an index out of range.
  void upload(const BodyDrawInput& mesh, std::span<const glm::vec3> offsets);
  // Draws the uploaded mesh once per offset into the bound framebuffer; returns the triangles submitted.
  std::size_t draw(const glm::mat4& view, const glm::mat4& projection, const glm::vec3& skin_color);

 private:
  GlObject program_;  // body.vert + lit.frag, as the body pass
  GlObject vao_, mesh_, offsets_;
  TopologyBuffer topology_;
  std::vector<std::uint32_t> optimized_;
  std::size_t index_count_ = 0, instance_count_ = 0;
};

}  // namespace strata
