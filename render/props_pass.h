#pragma once
// The props pass: a scenario's static scenery — obstacles as solid blocks standing on the ground, and goal
// markers (discs at goal points and waypoints, flat slabs over goal regions) in each spawn group's colour — built
// once per scenario and drawn with the bodies' light (lit.frag). Agents are drawn by the body, impostor and
// skeleton passes as any walker.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "components/scenario.h"
#include "render/gl_program.h"
#include "render/shadow_pass.h"

namespace strata {

struct PropVertex {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec4 color;  // rgb, alpha 1 (the tint replaces the pass colour)
};

// The triangles (three vertices each) of `scenario`'s props: each obstacle polygon extruded to `obstacle_height`
// metres (walls and sides lit by their outward normals, a flat top), and a marker per goal. Pure geometry, no GL:
// tested without a context.
std::vector<PropVertex> scenario_props(const Scenario& scenario, float obstacle_height = 1.1f);

// The colour of spawn group `group` (its agents' goal markers).
glm::vec4 group_color(std::size_t group);

class PropsPass {
 public:
  // Needs a current GL 4.5 core context (as do upload, draw and the destructor).
  PropsPass();
  // Replaces the props with `triangles` (a multiple of three vertices) unless `key` is the one uploaded last.
  // Throws std::invalid_argument for a count that is not a multiple of three.
  void upload(std::uint64_t key, std::span<const PropVertex> triangles);
  void clear();
  bool empty() const { return count_ == 0; }
  std::uint64_t key() const { return key_; }
  // `shading`: lit by the sun (RenderQuality::High); null: the low-quality look.
  void draw(const glm::mat4& view, const glm::mat4& projection, const ShadedFrame* shading = nullptr);
  // Draws the props' depth into the bound shadow map (ShadowPass::begin).
  void draw_shadow(const ShadowPass& shadow);

 private:
  GlObject program_, vao_, buffer_;
  GlObject shaded_program_, depth_program_;  // made on the first shaded frame
  std::size_t count_ = 0;
  std::uint64_t key_ = 0;
};

}  // namespace strata
