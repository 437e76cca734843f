#pragma once
// Draws walkers as skeletons: each bone (parent joint -> child joint) as a lit tapered prism and each joint as
// a small lit sphere, instanced (one draw for all bones of all walkers, one for all joints), over a ground plane.
// Renders into its own FBO (4x multisampled colour + depth, resolved into a single-sample FBO at the end of
// render()); the caller owns the GL context, which must be current for every call including the destructor.
// Later issues replace bones with skinned bodies; this stays as a debug overlay.
#include <cstdint>
#include <memory>
#include <optional>
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

// Skinned bodies: per-walker deformed vertices already in world space, as six component arrays (SoA, the skin
// system's output), sharing one triangle list (every walker of a draw uses the same mesh level). Walker w's
// vertex v is element w * stride + v of each array. Drawn lit in the skin colour.
struct BodyDrawInput {
  std::span<const std::uint32_t> triangles;
  const float *px = nullptr, *py = nullptr, *pz = nullptr, *nx = nullptr, *ny = nullptr, *nz = nullptr;
  std::size_t stride = 0;        // >= vertex_count
  std::size_t vertex_count = 0;
  std::size_t walker_count = 0;
  // Optional per-vertex colours, indexed like the positions (walker_count * stride entries), each bytes R, G, B,
  // A in memory; A blends the colour over the skin colour (0 = plain skin). The binding editor shows weights so.
  const std::uint32_t* rgba = nullptr;
};

struct SkeletonRenderOptions {
  bool draw_ground = true;
  bool draw_skeleton = true;           // bones and joints (drawn inside bodies when both are on)
  float bone_radius = 0.025f;          // metres at the parent end of a bone
  float joint_radius = 0.03f;          // metres
  glm::vec4 clear_color{0.62f, 0.70f, 0.80f, 1.0f};
  glm::vec3 bone_color{0.92f, 0.86f, 0.74f};
  glm::vec3 joint_color{0.80f, 0.25f, 0.20f};
  glm::vec3 skin_color{0.80f, 0.62f, 0.52f};
  glm::vec3 ground_color{0.50f, 0.52f, 0.49f};
};

// The per-instance transform of one bone: maps the unit bone mesh (radius 1 about the segment (0,0,0)-(0,1,0))
// onto the segment a -> b with the given radius. Columns 0 and 2 are orthogonal to b - a with length `radius`,
// column 1 is b - a, column 3 is a; the determinant is positive so winding (and back-face culling) survives.
// nullopt for a zero-length or non-finite bone, which the renderer skips (its joint sphere still shows).
std::optional<glm::mat4> bone_transform(const glm::vec3& a, const glm::vec3& b, float radius);

class SkeletonRenderer {
 public:
  // Needs a current GL 4.5 core context. Throws std::runtime_error on shader/FBO failure, std::invalid_argument
  // for a non-positive size (as do resize and, for too few joint positions, render).
  SkeletonRenderer(int width, int height, SkeletonRenderOptions options = {});
  ~SkeletonRenderer();
  SkeletonRenderer(const SkeletonRenderer&) = delete;
  SkeletonRenderer& operator=(const SkeletonRenderer&) = delete;

  int width() const;
  int height() const;
  void resize(int width, int height);
  SkeletonRenderOptions& options();

  // Draws one frame into the FBO: ground, skeletons (when options().draw_skeleton) and, when given, bodies.
  // Waits for nothing; read_rgba() or blit_to_default_framebuffer() finish it. Throws std::invalid_argument when
  // the inputs' sizes disagree.
  void render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
              const BodyDrawInput* bodies = nullptr);
  // The same with bodies at several levels (up to 4 draws, one per level; each keeps its own index buffer).
  void render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
              std::span<const BodyDrawInput> body_levels);
  // Body triangles submitted by the last render() (walkers x triangles per level).
  std::size_t triangles_drawn() const;
  // The render benchmark's reference (`strata bench --render`): walker 0 of `mesh` uploaded once as a static
  // mesh and drawn offsets.size() times in one glDrawElementsInstanced, each copy moved by its offset, into the
  // same target with the same material: raw instancing of the same triangles, with nothing streamed.
  void render_instanced_reference(const BodyDrawInput& mesh, std::span<const glm::vec3> offsets, const glm::mat4& view,
                                  const glm::mat4& projection);
  // Waits until the GL has finished every command (for timing).
  void finish() const;
  // RGBA8 pixels, rows top to bottom (image order), width*height*4 bytes.
  void read_rgba(std::vector<std::uint8_t>& out) const;
  // The single-sample framebuffer render() resolves into and read_rgba() reads: an overlay (the viewer's panel)
  // drawn into it after render() shows up in read_rgba().
  unsigned output_framebuffer() const;
  // Copies the FBO to framebuffer 0 (a window), scaled to the given size.
  void blit_to_default_framebuffer(int width, int height) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace strata
