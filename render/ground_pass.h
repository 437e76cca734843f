#pragma once
// The ground pass: a grid-lined quad on y = 0 under the walkers, fading into the clear colour towards its edge so
// the crowd seems to stand on an endless plane.
#include <span>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "render/gl_program.h"
#include "render/shadow_pass.h"

namespace strata {

// The square the ground covers: centred under the points (x, z), reaching at least 25 m from the centre and past
// the farthest point by 15 m or 40 % of its distance, whichever is more; the origin +-25 m when there is no finite
// point. The ground fades into the clear colour from `fade_start` (m from the centre) to its edge: no nearer than
// 2 m past the farthest point, so no walker stands on faded ground (the fade once began at 60 % of the half size,
// and a wide crowd's outer walkers stood on ground 80 % faded, as if floating in the sky).
struct GroundExtent {
  glm::vec2 center{0.0f};
  float half_size = 25.0f;
  float fade_start = 15.0f;
};
GroundExtent ground_extent(std::span<const glm::vec3> points);

class GroundPass {
 public:
  // Needs a current GL 4.5 core context (as do draw and the destructor). Throws std::runtime_error on a shader
  // failure.
  GroundPass();

  // Draws the ground under `joints` (every walker's world-space joints) into the bound framebuffer. `shading`:
  // lit by the sun with the walkers' shadows (RenderQuality::High); null: the low-quality look.
  void draw(std::span<const glm::vec3> joints, const glm::mat4& view, const glm::mat4& projection,
            const glm::vec3& ground_color, const glm::vec4& clear_color, const ShadedFrame* shading = nullptr);

 private:
  GlObject program_;
  GlObject shaded_program_;  // made on the first shaded frame
  GlObject vao_;  // empty: the quad comes from gl_VertexID, but the core profile draws only with a VAO bound
};

}  // namespace strata
