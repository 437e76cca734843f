#pragma once
// The sun of --quality high (RenderQuality::High): its direction and colours, and its shadow map. Each frame the
// map is fitted to what casts and receives shadows (the walkers' joints, grown by a body's reach, and the
// ground beneath them): an orthographic depth map seen from the sun, which the shaded programs
// (render/shaders/shading.glsl) sample with a percentage-closer filter.
//
// Shadow maps, because they serve every command and the viewer through the one GL renderer, reusing the vertices
// the colour pass streams anyway. For large headless crowds the ray tracer (render/ray_tracer.h, --renderer
// embree) is faster: 100 level-0 walkers with sun shadows in 209 ms where this path takes 1,042 ms on llvmpipe
// (docs/rendering.md).
#include <span>
#include <string_view>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "render/gl_program.h"

namespace strata {

class ShadowPass;

struct Sunlight {
  glm::vec3 to_sun{0.0f, 1.0f, 0.0f};  // unit, world
  glm::vec3 sun_color{0.0f};           // linear
  glm::vec3 sky_color{0.0f}, bounce_color{0.0f};
  float exposure = 1.0f;
};

class ShadowPass {
 public:
  // Needs a current GL 4.5 core context (as do every call and the destructor). Throws std::runtime_error when the
  // depth framebuffer is incomplete. `size`: the map's width and height in texels.
  explicit ShadowPass(int size = 2048);

  // Fits the light's orthographic frustum around `casters` (world points, non-finite ones skipped) grown by
  // `reach` metres, and down to the ground plane y = 0 below them, then binds the depth framebuffer cleared and
  // ready for depth-only draws (viewport, polygon offset, front faces culled off). Returns false, binding
  // nothing, when there is no finite point.
  bool begin(const glm::vec3& to_sun, std::span<const glm::vec3> casters, float reach);
  // The light's world -> clip matrix of this frame (what the depth draws use).
  const glm::mat4& light_view_projection() const { return view_projection_; }
  // Its two halves (the light's view, looking down -z at the frustum's centre, and its orthographic projection),
  // and a point far out towards the sun (1e5 m) from which every caster is seen along the sun's rays.
  const glm::mat4& light_view() const { return view_; }
  const glm::mat4& light_projection() const { return projection_; }
  const glm::vec3& far_sun_point() const { return far_sun_; }
  // One texel of this frame's map in metres: how far the filtered lookup spreads a shadow's edge.
  float texel_world() const { return texel_world_; }
  // The program that draws the bodies' three position arrays into the map (render/shaders/shadow.vert).
  unsigned body_program() const { return body_program_.id(); }
  // Restores the state begin() changed. The map is then ready to sample.
  void end() const;
  // Sets shading.glsl's uniforms on `program`: the sun and sky, the eye, and this frame's shadow map on texture
  // unit `unit` (or no shadows when `shadows` is false, as when begin() found nothing).
  void apply(unsigned program, const Sunlight& sun, const glm::vec3& eye, bool shadows, int unit = 3) const;

 private:
  int size_ = 0;
  GlObject depth_, framebuffer_, body_program_;
  glm::mat4 view_projection_{1.0f};
  float texel_world_ = 0.01f;
  glm::mat4 view_{1.0f}, projection_{1.0f};
  glm::vec3 far_sun_{0.0f};
};

// What a RenderQuality::High frame shades with, handed to every pass that draws lit surfaces.
struct ShadedFrame {
  const ShadowPass* shadow = nullptr;
  const Sunlight* sun = nullptr;
  glm::vec3 eye{0.0f};
  bool shadows = false;  // whether the shadow map holds this frame
  void apply(unsigned program) const;
};

// Links a program whose fragment shader uses shading.glsl (put in front of it). Throws as link_program.
GlObject link_shaded_program(std::string_view vertex_path, std::string_view fragment_path);

}  // namespace strata
