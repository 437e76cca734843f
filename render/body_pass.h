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
#include "render/impostor_pass.h"
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
  // Draws every batch of `bodies` (checked) into the bound framebuffer.
  void draw(const BodySource& bodies, const glm::mat4& view, const glm::mat4& projection,
            const glm::vec3& skin_color);
  // Body triangles submitted by the last draw (walkers x triangles, summed over batches).
  std::size_t triangles_drawn() const { return triangles_drawn_; }
  // Walkers drawn as impostors by the last draw.
  std::size_t impostors_drawn() const { return impostors_ ? impostors_->impostors_drawn() : 0; }

 private:
  void check_batch(const BodyDrawInput& b, const TopologyBuffer& slot) const;
  // Reads batch_cache_ (the source's batches, fetched once per call).
  std::vector<std::optional<std::size_t>> assign_slots(const BodySource& bodies) const;
  void draw_batch(const BodyDrawInput& b, TopologyBuffer& slot, const glm::mat4& view, const glm::mat4& projection,
                  const glm::vec3& skin_color);

  GlObject program_;  // body.vert + lit.frag
  // The six component arrays are re-specified per draw in one buffer (orphaning, as for the skeleton's instances),
  // the optional colours in another.
  GlObject vao_, components_, colors_;
  std::array<TopologyBuffer, kMaxBatches> slots_;  // batch k of a frame uses slot k
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
