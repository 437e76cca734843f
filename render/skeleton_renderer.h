#pragma once
// Draws walkers as skeletons: each bone (parent joint -> child joint) as a lit tapered prism and each joint as
// a small lit sphere, instanced (one draw for all bones of all walkers, one for all joints), over a ground plane.
// Renders into its own FBO (multisampled colour + depth, resolved on read); the caller owns the GL context.
// Later issues replace bones with skinned bodies; this stays as a debug overlay.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "components/skeleton.h"

namespace strata {

struct SkeletonDrawInput {
  const Skeleton* skeleton = nullptr;
  // World-space joint positions, walker-major: joint j of walker w at [w * joint_count + j].
  std::span<const glm::vec3> joint_positions;
  std::size_t walker_count = 0;
};

struct SkeletonRenderOptions {
  bool draw_ground = true;
  float bone_radius = 0.025f;          // metres at the parent end of a bone
  float joint_radius = 0.03f;          // metres
  glm::vec4 clear_color{0.62f, 0.70f, 0.80f, 1.0f};
  glm::vec3 bone_color{0.92f, 0.86f, 0.74f};
  glm::vec3 joint_color{0.80f, 0.25f, 0.20f};
};

class SkeletonRenderer {
 public:
  // Needs a current GL 4.5 core context. Throws std::runtime_error on shader/FBO failure.
  SkeletonRenderer(int width, int height, SkeletonRenderOptions options = {});
  ~SkeletonRenderer();
  SkeletonRenderer(const SkeletonRenderer&) = delete;
  SkeletonRenderer& operator=(const SkeletonRenderer&) = delete;

  int width() const;
  int height() const;
  void resize(int width, int height);
  SkeletonRenderOptions& options();

  // Draws one frame into the FBO. Waits for nothing; read_rgba() or blit_to_default_framebuffer() finish it.
  void render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection);
  // RGBA8 pixels, rows top to bottom (image order), width*height*4 bytes.
  void read_rgba(std::vector<std::uint8_t>& out) const;
  // Copies the FBO to framebuffer 0 (a window), scaled to the given size.
  void blit_to_default_framebuffer(int width, int height) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace strata
