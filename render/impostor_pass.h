#pragma once
// The impostor pass: ImpostorBatch (render/body_source.h), far walkers drawn as one camera-facing quad each from
// their rig's atlas (components/impostor_atlas.h) with impostor.vert/.frag. The atlas is uploaded once into two
// mipmapped array textures (one layer per gait phase) and kept while batches point at the same atlas; per frame
// only the six per-walker floats are streamed and drawn in one instanced call. Under the sun (RenderQuality::High)
// they cast shadows too: the same quads drawn into the shadow map facing the sun, each showing the cell nearest
// the sun's direction (impostor_shadow.frag), so a walker keeps its shadow when it becomes an impostor. Owned by
// the BodyPass, which dispatches batches by kind.
#include <cstdint>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <glm/vec3.hpp>

#include "render/body_source.h"
#include "render/gl_program.h"
#include "render/shadow_pass.h"

namespace strata {

// Grows [lo, hi] to hold every quad of `batch` (a sphere about each quad's centre holds it, whichever way it turns
// to face the eye or the sun). Walkers with a non-finite placement or scale are skipped.
void grow_by_impostors(const ImpostorBatch& batch, glm::vec3& lo, glm::vec3& hi);

class ImpostorPass {
 public:
  // Needs a current GL 4.5 core context (as do draw and the destructor). Throws std::runtime_error on a shader
  // failure.
  ImpostorPass();
  // Throws std::invalid_argument when a batch with walkers has no complete atlas or misses an array.
  static void check(const ImpostorBatch& batch);
  // `shading`: dressed in each walker's palette and lit as RenderQuality::High lights meshes; null: the skin
  // colour under the low-quality headlight.
  void draw(const ImpostorBatch& batch, const glm::mat4& view, const glm::mat4& projection, const glm::vec3& skin_color,
            const ShadedFrame* shading = nullptr);
  // Into the sun's shadow map (between ShadowPass::begin and end): each walker as the atlas shows it from the sun.
  void draw_shadow(const ImpostorBatch& batch, const ShadowPass& shadow);
  std::size_t impostors_drawn() const { return drawn_; }
  void reset_count() { drawn_ = 0; }

 private:
  void upload(const ImpostorAtlas& atlas);
  // The batch's six per-walker arrays into the instance buffer (the atlas uploaded first when it changed).
  void stream(const ImpostorBatch& batch);
  // Program `p`'s camera, grid and atlas uniforms, the atlas textures and cell bounds, and the VAO.
  void bind_atlas(unsigned p, const ImpostorAtlas& atlas, const glm::mat4& view, const glm::mat4& projection,
                  const glm::vec3& eye) const;

  GlObject program_, vao_, instances_;
  GlObject shaded_program_;  // made on the first shaded frame
  GlObject shadow_program_;  // made on the first frame with a shadow map
  GlObject palettes_{GlKind::kBuffer}, palettes_texture_{GlKind::kTextureBuffer};
  std::vector<glm::vec4> palette_scratch_;
  // Per cell (phase-major, then elevation, then azimuth), the part of the cell the walker covers, as texture
  // coordinates within the cell (x0, y0, x1, y1): quads are shrunk to it, which halves the fragments shaded.
  GlObject cell_bounds_{GlKind::kBuffer};
  GlObject color_{GlKind::kTexture2DArray}, normal_{GlKind::kTexture2DArray};
  const ImpostorAtlas* uploaded_ = nullptr;  // the atlas the textures hold (address and key)
  std::uint64_t uploaded_key_ = 0;
  std::size_t drawn_ = 0;
};

}  // namespace strata
