#pragma once
// The body pass: the skinned bodies of a frame, read from a BodySource (render/body_source.h), lit in the skin
// colour. CPU-skinned batches stream their six component arrays every frame and draw in one multi-draw each: the
// batch's shared index list once per walker, offset by the walker's first vertex.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "render/body_source.h"
#include "render/gl_program.h"
#include "render/appearance.h"
#include "render/impostor_pass.h"
#include "render/shadow_pass.h"
#include "render/topology_buffer.h"

namespace strata {

class BodyPass {
 public:
  // Batches per frame: each keeps its own cached index buffer, so several body levels (--level auto uses 3)
  // draw every frame without re-uploading topology.
  static constexpr std::size_t kMaxBatches = 4;

  // Needs a current GL 4.5 core context (as do check, draw and the destructor). Throws std::runtime_error on a
  // shader failure.
  BodyPass();

  // Throws std::invalid_argument when `bodies` has more than kMaxBatches CPU-skinned batches or a batch's arrays, sizes or
  // triangles do not agree. Called before a frame starts, so a bad input leaves the target untouched. Indices
  // are range-checked only when a batch's topology differs from the one cached for its slot (when it would be
  // uploaded), not every frame.
  void check(const BodySource& bodies) const;
  // Draws the CPU-skinned batches of `bodies` (checked) into the bound shadow map (ShadowPass::begin). Their
  // vertices stay in the pass's buffers for the draw() of the same frame, which must follow with the same bodies.
  void draw_shadow(const BodySource& bodies, const ShadowPass& shadow);
  // Draws every batch of `bodies` (checked) into the bound framebuffer; ends the frame. `shading`: the
  // RenderQuality::High material (null: the low-quality one).
  void draw(const BodySource& bodies, const glm::mat4& view, const glm::mat4& projection,
            const glm::vec3& skin_color, const ShadedFrame* shading = nullptr);
  // Body triangles submitted by the last draw (walkers x triangles, summed over batches).
  std::size_t triangles_drawn() const { return triangles_drawn_; }
  // Walkers drawn as impostors by the last draw.
  std::size_t impostors_drawn() const { return impostors_ ? impostors_->impostors_drawn() : 0; }

 private:
  void check_batch(const BodyDrawInput& b, const TopologyBuffer& slot) const;
  // Reads batch_cache_ (the source's batches, fetched once per call).
  std::vector<std::optional<std::size_t>> assign_slots(const BodySource& bodies) const;
  // Per topology slot: the vertices streamed this frame, and the shaded material's per-vertex lists (uploaded
  // when they change, like the topology).
  struct SlotData {
    GlObject components{GlKind::kBuffer};
    std::uint64_t streamed_frame = 0;  // frame_ when `components` last received a batch
    const float* streamed_from = nullptr;
    GlObject materials{GlKind::kBuffer}, materials_texture{GlKind::kTextureBuffer};
    GlObject occlusion{GlKind::kBuffer}, occlusion_texture{GlKind::kTextureBuffer};
    const void* materials_key = nullptr;
    const void* occlusion_key = nullptr;
    std::size_t lists_stride = 0;  // the stride the two lists were padded to (0: none uploaded)
  };
  // Makes the slot's buffers hold batch `b`'s vertices (once per frame) and binds them to the VAO; uploads the
  // topology when it changed.
  void stream(const BodyDrawInput& b, TopologyBuffer& slot, SlotData& data);
  void prepare_shaded(const BodyDrawInput& b, SlotData& data);
  void bind_draw(const BodyDrawInput& b);
  void draw_batch(const BodyDrawInput& b, TopologyBuffer& slot, SlotData& data, const glm::mat4& view,
                  const glm::mat4& projection, const glm::vec3& skin_color, const ShadedFrame* shading);

  GlObject program_;         // body.vert + lit.frag
  GlObject shaded_program_;  // body_shaded.vert + shading.glsl + shaded.frag, made on the first shaded frame
  // Each slot's six component arrays are re-specified per frame in its buffer (orphaning, as for the skeleton's
  // instances), the optional colours in one more buffer, the walkers' palettes in another.
  GlObject vao_, colors_;
  GlObject palettes_{GlKind::kBuffer}, palettes_texture_{GlKind::kTextureBuffer};
  std::array<TopologyBuffer, kMaxBatches> slots_;  // batch k of a frame uses slot k
  std::array<SlotData, kMaxBatches> slot_data_;
  std::uint64_t frame_ = 1;  // counts draw() calls: a frame is an optional draw_shadow, then draw
  std::vector<glm::vec4> palette_scratch_;
  WalkerPalette plain_{};  // the palette of walkers without a key (the skin colour everywhere)
  std::vector<std::uint8_t> materials_scratch_;
  std::vector<float> occlusion_scratch_;
  std::unique_ptr<ImpostorPass> impostors_;         // made on the first impostor batch
  std::size_t triangles_drawn_ = 0;
  // Kept between frames so steady-state rendering does not allocate.
  std::vector<std::uint32_t> optimized_;
  std::vector<int> counts_;
  std::vector<const void*> offsets_;
  std::vector<int> base_vertices_;
  mutable std::vector<BodyBatch> batch_cache_;  // this call's batches (check and draw each fetch them once)
};

}  // namespace strata
